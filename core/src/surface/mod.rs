//! The character's surface: the mesh and what is read off it (maps, parting
//! regions, root frames), and the spatial structures over it (point grids,
//! the body as a solid for inside tests).

pub mod body;
pub mod frame;
pub mod grid;
pub mod map;
pub mod mesh;
pub mod nearest;
pub mod region;
pub mod rim;
