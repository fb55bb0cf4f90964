//! Sizing a stamp from its faces: per-face setup, the scaled area, and the
//! candidate and memory bounds a host sizes its buffers with.

use super::{
    min_radius_factor, validate, Candidate, Face, Scratch, StampParams, Stamper, MAX_TARGET,
};
use crate::arena::ArenaLayout;
use crate::stamp::tile::TILE;
use crate::{Error, Mesh};

/// Steps the density takes between black and white when it scales faces.
/// Only faces of one scale are laid out together (see [`chart`](crate::stamp::chart)), so a
/// smooth gradient is stamped as bands of equal scale: a step is 0.8% of
/// the face size at the paper's `black_scale` of 0.5 (1.6% of the root
/// density in white regions, 3.1% in black ones).
pub const DENSITY_STEPS: f32 = 64.0;

/// What the setup needs of one face, from one read of its corners.
pub(super) struct FaceSetup {
    pub(super) face: Face,
    pub(super) area: f32,
    perimeter: f32,
    pub(super) degenerate: bool,
}

impl FaceSetup {
    /// The area, normal and degeneracy [`Mesh::shape`] gives, the
    /// perimeter, and the scale of the density (0 = no roots: bald or
    /// degenerate).
    pub(super) fn new(mesh: &Mesh, params: &StampParams, f: usize) -> Self {
        let shape = mesh.shape(f);
        let scale = if shape.degenerate {
            0.0
        } else {
            density_scale(params, params.density.sample(mesh, f, 1.0 / 3.0, 1.0 / 3.0))
        };
        FaceSetup {
            face: Face {
                normal: shape.cross.normalize_or_zero().into(),
                scale,
            },
            area: shape.area(),
            perimeter: shape.perimeter(),
            degenerate: shape.degenerate,
        }
    }
}

/// Scale of a face of density `d` (0 = no roots).
pub(super) fn density_scale(params: &StampParams, d: f32) -> f32 {
    if d < params.bald_below {
        return 0.0;
    }
    let step = libm::roundf(d.clamp(0.0, 1.0) * DENSITY_STEPS) / DENSITY_STEPS;
    params.black_scale + (1.0 - params.black_scale) * step
}

/// Sums over the faces that size a stamp.
#[derive(Default)]
pub(super) struct FaceSums {
    /// Area weighted by the squared density scale.
    pub(super) area: f64,
    /// Perimeter of the stamped faces, weighted by the density scale.
    perimeter: f64,
    stamped: usize,
    pub(super) degenerate: u32,
}

impl FaceSums {
    /// Sets up every face of `mesh` (validated), handing each to `keep`.
    pub(super) fn of(mesh: &Mesh, params: &StampParams, mut keep: impl FnMut(usize, Face)) -> Self {
        let mut sums = FaceSums::default();
        for f in 0..mesh.triangle_count() {
            let setup = FaceSetup::new(mesh, params, f);
            let s = setup.face.scale as f64;
            if s != 0.0 {
                sums.area += setup.area as f64 * s * s;
                sums.perimeter += setup.perimeter as f64 * s;
                sums.stamped += 1;
            }
            sums.degenerate += setup.degenerate as u32;
            keep(f, setup.face);
        }
        sums
    }

    /// Upper bound on the candidates of any pass, for every radius the count
    /// correction can reach.
    ///
    /// The per-face bounds of [`face_bound`] are affine in a face's area and
    /// perimeter before rounding down, so one walk over the faces gives both
    /// the scaled area (hence the smallest radius) and their sum.
    pub(super) fn bound(&self, mesh: &Mesh, params: &StampParams) -> Result<usize, Error> {
        let r_min = if params.radius > 0.0 {
            params.radius
        } else {
            let Some(r) = first_radius(self.area, params.target_count, TILE.density()) else {
                return Ok(0);
            };
            r * min_radius_factor(params.target_count, mesh.triangle_count())
        } as f64;
        let bound = oler(
            self.area / (r_min * r_min),
            self.perimeter / r_min,
            self.stamped,
        ) + 1.0;
        // ids, ranks and sort keys are 32-bit
        if bound.is_nan() || bound > 4.0 * MAX_TARGET as f64 {
            return Err(Error::InvalidArgument(
                "radius too small for this mesh (over 2^30 candidates)",
            ));
        }
        Ok(bound as usize)
    }
}

/// Oler's bound on the points a distance 1 apart in `faces` convex sets of
/// total area `area` and perimeter `perimeter`: `2 / sqrt(3)` per unit of
/// area, one per two units of perimeter, and one per set. The stamp's
/// points are a distance 1 apart in the tile up to rounding, which the
/// margins cover (a thousandth of the area and perimeter terms, a hundredth
/// of a point per face).
fn oler(area: f64, perimeter: f64, faces: usize) -> f64 {
    (HEX_PACKING * area + 0.5 * perimeter) * 1.001 + 1.01 * faces as f64
}

/// Upper bound on the points a face can take at radius `r`: Oler's bound
/// for the face in the tile.
pub(super) fn face_bound(mesh: &Mesh, face: usize, scale: f32, r: f32) -> usize {
    if scale == 0.0 {
        return 0;
    }
    let shape = mesh.shape(face);
    let k = (scale / r) as f64;
    let bound = oler(shape.area() as f64 * k * k, shape.perimeter() as f64 * k, 1);
    // saturating: a radius tiny next to the face is reported by the caller
    bound.min(usize::MAX as f64 / 4.0) as usize
}

/// Points per unit area of the densest packing at unit spacing (2 / sqrt 3).
pub(super) const HEX_PACKING: f64 = 1.154_700_6;

/// Upper bound on the roots [`stamp`](super::stamp) writes: the target (surplus stamps
/// are trimmed by LOD rank), or 0 when every face is bald or degenerate;
/// with a fixed radius, a packing bound.
pub fn max_roots(mesh: &Mesh, params: &StampParams) -> Result<usize, Error> {
    if params.radius > 0.0 {
        return candidates_bound(mesh, params);
    }
    validate(mesh, params)?;
    Ok(if FaceSums::of(mesh, params, |_, _| {}).area > 0.0 {
        params.target_count as usize
    } else {
        0
    })
}

/// Upper bound on the candidates of any pass, for every radius the count
/// correction can reach.
pub(super) fn candidates_bound(mesh: &Mesh, params: &StampParams) -> Result<usize, Error> {
    validate(mesh, params)?;
    FaceSums::of(mesh, params, |_, _| {}).bound(mesh, params)
}

pub(super) fn first_radius(scaled_area: f64, target: u32, density: f32) -> Option<f32> {
    if target == 0 || scaled_area.is_nan() || scaled_area <= 0.0 {
        return None;
    }
    Some(libm::sqrt(density as f64 * scaled_area / target as f64) as f32)
}

/// Arena bytes [`stamp`](super::stamp) needs for `mesh` and `params`.
pub fn required_bytes(mesh: &Mesh, params: &StampParams) -> Result<usize, Error> {
    let bound = candidates_bound(mesh, params)?;
    Ok(bytes_for(mesh, bound))
}

pub(super) fn bytes_for(mesh: &Mesh, bound: usize) -> usize {
    let mut layout = ArenaLayout::new();
    Stamper::layout(&mut layout, mesh);
    layout.bytes() + passes_bytes(bound)
}

/// Arena bytes the passes take after the [`Stamper`], for `bound`
/// candidates (its own part costs a walk over the mesh to size).
pub(super) fn passes_bytes(bound: usize) -> usize {
    let mut layout = ArenaLayout::new();
    Scratch::layout(&mut layout, bound);
    layout.add::<Candidate>(bound);
    layout.bytes()
}
