//! pelage-core: the allocation-free heart of the pelage fur pipeline.
//!
//! Every stage is a pure function over borrowed inputs that writes into memory
//! the caller provides (an [`arena::Arena`] over a `&mut [u8]`), so the crate
//! runs unchanged inside a DCC plugin, a render procedural or a `no_std` target.
//! Randomness is counter-based ([`rng`]), so results never depend on call order,
//! chunking or thread count.
//!
//! # Public surface
//! Modules are grouped by the paper's stages, and data flows downward:
//! - [`surface`]: the mesh and what is read off it (maps, parting regions,
//!   root frames, the body's inside test, point grids).
//! - [`stamp`]: Poisson stamping of roots (paper 2.3); `stamp::tile` and
//!   `stamp::chart` are public for inspection and tests.
//! - [`interp`]: bind, groom values, settle, and per frame the posed frame
//!   ([`interp::posed::PosedFrame`]), the strand kernel
//!   ([`interp::strand`]), strand records and their checks
//!   ([`interp::strands`]) and the expansion driver ([`interp::expand`]).
//! - [`trim`]: trimming at a cloth (paper 3.3): per-frame records, the
//!   shot pass, the cut.
//! - [`dynamics`]: guide simulation (paper 3): tip spring, CCD IK,
//!   Catmull-Rom output, tip links, colliders and push-out, the state.
//! - Shared data and memory: [`arena`], [`error`], [`guides`], [`root`],
//!   [`rng`], [`strided`].
//!
//! Hosts need [`stamp::stamp`], [`interp::bind::bind`],
//! [`interp::groom::GroomMaps`], [`interp::settle::settle`],
//! [`interp::posed::PosedFrame`] and [`interp::expand::ExpandJob`] (or
//! [`interp::expand::expand`]); the lower-level items (the hash grid, the
//! counter-based RNG, tile and chart queries, the strand checks) are public
//! because the C API, the end-to-end tests and the benchmarks use them.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod arena;
pub mod cache;
pub mod collide;
pub mod curve;
pub mod dynamics;
pub mod error;
pub mod guides;
pub mod interp;
pub mod rng;
pub mod root;
mod sqrt;
pub mod stamp;
pub mod strided;
pub mod surface;
#[cfg(test)]
mod testmesh;
pub mod trim;

pub use arena::{Arena, ArenaLayout};
pub use error::Error;
pub use root::Root;
pub use stamp::{StampParams, StampReport};
pub use strided::Strided;
pub use surface::map::ScalarMap;
pub use surface::mesh::Mesh;
pub use surface::region::RegionMap;
