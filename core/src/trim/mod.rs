//! Trimming (paper 3.3): hairs sandwiched between the body and a cloth
//! layer are cut where their guides meet the cloth.
//!
//! - [`meet`]: per frame, where each posed guide first meets the cloth
//!   (a triangle mesh) or the colliders of the dynamics, as
//!   [`TrimRecord`]s.
//! - [`length`]: a render hair's length under a frame's records (its
//!   guides' weighted), the shot pass that keeps each hair's shortest
//!   length over a whole shot, and the cut that expansion applies.
//!
//! A length is a fraction of the strand's curve parameter, stored in 16
//! bits ([`WHOLE`] is the whole strand): the points of a posed guide and of
//! an expanded strand are evenly spaced along their arc, so the parameter
//! is the fraction of the arc length.

pub mod length;
pub mod meet;

pub use crate::curve::WHOLE;
pub use meet::TrimRecord;
