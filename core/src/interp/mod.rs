//! Interpolation (paper 2.2 and 3): binding strands to guides, groom values
//! per strand, settling strands out of the body at rest, and expanding
//! render strands from posed guides every frame.

pub mod bind;
pub mod expand;
pub mod groom;
pub mod params;
pub mod patch;
pub mod posed;
pub mod settle;
pub mod strand;
pub mod strands;
