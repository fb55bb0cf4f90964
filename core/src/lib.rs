//! pelage-core: the allocation-free heart of the pelage fur pipeline.
//!
//! Every stage is a pure function over borrowed inputs that writes into memory
//! the caller provides (an [`arena::Arena`] over a `&mut [u8]`), so the crate
//! runs unchanged inside a DCC plugin, a render procedural or a `no_std` target.
//! Randomness is counter-based ([`rng`]), so results never depend on call order,
//! chunking or thread count.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod arena;
pub mod error;
pub mod guides;
pub mod interp;
pub mod rng;
pub mod root;
pub mod stamp;
pub mod strided;
pub mod surface;
#[cfg(test)]
mod testmesh;

pub use arena::{Arena, ArenaLayout};
pub use error::Error;
pub use root::Root;
pub use stamp::{StampParams, StampReport};
pub use strided::Strided;
pub use surface::map::ScalarMap;
pub use surface::mesh::Mesh;
pub use surface::region::RegionMap;
