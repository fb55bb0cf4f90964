//! A strand's expansion parameters: its point count, how its ends are
//! written, its widths. Read by the posed frame (which resamples guides to
//! the count) and by the strand kernel, so they sit below both.

use crate::surface::mesh::MAX_COORDINATE;
use crate::Error;

/// Most control points per strand.
pub const MAX_STRAND_POINTS: usize = 64;

/// Largest [`ExpandParams::width_scale`]: with groom radii within
/// [`crate::interp::strands::MAX_GROOM_VALUE`], radii stay finite.
pub const MAX_WIDTH_SCALE: f32 = 1e6;

/// How curve ends are written for a Catmull-Rom consumer.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EndPoints {
    /// The points as they are; a Catmull-Rom curve (Embree, RenderMan) spans
    /// the second to the second-last point.
    Raw = 0,
    /// First and last points repeated ("pinned" in USD), so the curve runs
    /// from the root to the tip.
    Pinned = 1,
}

/// Expansion parameters.
#[derive(Clone, Copy, Debug)]
pub struct ExpandParams {
    /// Control points per strand before end handling (2..=64); guides are
    /// resampled to it. Catmull-Rom consumers need 4 points per curve, so
    /// with `Raw` ends use at least 4.
    pub points_per_strand: usize,
    /// End-point convention of the output.
    pub end_points: EndPoints,
    /// Length of orphan strands (no eligible guide), grown along the normal.
    pub orphan_length: f32,
    /// Factor on every strand's radii (1: as groomed). A shadow or
    /// distance LOD that keeps k of n strands passes n / k
    /// ([`lod_width_scale`]), so the fur covers as much.
    pub width_scale: f32,
}

/// The width factor that keeps the fur's projected coverage when only
/// `kept` of `total` strands are drawn (a rank prefix, an even subset).
///
/// Strands of width `w` and length `l` scattered evenly over an area `A`
/// cover, seen from any direction, the fraction `1 - exp(-n w l / A)` of it
/// (a Boolean model of independent strands): the coverage depends on `n w`
/// alone, so `kept` strands at width `w total / kept` cover as much as all
/// of them. Overlaps are part of the model, so the factor holds for dense
/// fur too, where the sum of projected areas would not.
pub fn lod_width_scale(kept: usize, total: usize) -> f32 {
    if kept == 0 {
        return 1.0;
    }
    (total as f64 / kept as f64) as f32
}

impl ExpandParams {
    /// Control points written per strand.
    pub fn output_points(&self) -> usize {
        self.points_per_strand + 2 * (self.end_points == EndPoints::Pinned) as usize
    }

    /// Checks the point count, the orphan length and the width scale (a
    /// NaN or infinite one is [`Error::NonFinite`], a finite one out of its
    /// range [`Error::InvalidArgument`]).
    pub fn check(&self) -> Result<(), Error> {
        if !(2..=MAX_STRAND_POINTS).contains(&self.points_per_strand) {
            return Err(Error::InvalidArgument(
                "points_per_strand must be in 2..=64",
            ));
        }
        for (what, value) in [
            ("orphan_length", self.orphan_length),
            ("width_scale", self.width_scale),
        ] {
            if !value.is_finite() {
                return Err(Error::NonFinite { what, index: 0 });
            }
        }
        if !(self.orphan_length >= 0.0 && self.orphan_length <= MAX_COORDINATE) {
            return Err(Error::InvalidArgument("orphan_length must be in 0..=1e9"));
        }
        if !(self.width_scale > 0.0 && self.width_scale <= MAX_WIDTH_SCALE) {
            return Err(Error::InvalidArgument("width_scale must be in (0, 1e6]"));
        }
        Ok(())
    }
}
