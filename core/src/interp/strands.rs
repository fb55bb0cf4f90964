//! Strand records (root, binding, groom values) and their checks: what
//! expansion, settling and the groom handle read per strand, checked once
//! so that the kernel never meets a value it cannot turn into finite points.

use crate::interp::bind::{StrandBinding, MAX_NEIGHBOURS, NO_GUIDE, WEIGHT_SUM_TOLERANCE};
use crate::interp::groom::StrandGroom;
use crate::root::{check_root, BARYCENTRIC_SLACK};
use crate::{Error, Root};
use glam::Vec2;

/// Largest magnitude of a groom value (length multiplier, radii, bend,
/// kink, clump, phase): with coordinates within
/// [`crate::surface::mesh::MAX_COORDINATE`], every expanded point stays
/// finite.
pub const MAX_GROOM_VALUE: f32 = 1e6;

/// The per-strand inputs of expansion: parallel arrays, index for index.
#[derive(Clone, Copy, Debug)]
pub struct Strands<'a> {
    /// Where each strand grows (its `id` seeds nothing here; grooms hold
    /// the per-strand randomness).
    pub roots: &'a [Root],
    /// Guides and weights of each strand.
    pub bindings: &'a [StrandBinding],
    /// Groom values of each strand.
    pub grooms: &'a [StrandGroom],
}

impl<'a> Strands<'a> {
    /// Number of strands.
    pub fn len(&self) -> usize {
        self.roots.len()
    }

    /// True when there is no strand.
    pub fn is_empty(&self) -> bool {
        self.roots.is_empty()
    }

    /// The strands in `range` (of the roots; bindings and grooms are cut alike).
    pub fn range(&self, range: core::ops::Range<usize>) -> Strands<'a> {
        Strands {
            roots: &self.roots[range.clone()],
            bindings: &self.bindings[range.clone()],
            grooms: &self.grooms[range],
        }
    }
}

/// The smallest mesh and guide set that strand records checked by
/// [`StrandBounds::new`] fit: all that is left to check per frame.
///
/// A host that keeps a groom's strands across frames checks the records
/// once, then each frame checks only these two counts (O(1)) instead of
/// reading every record again.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StrandBounds {
    /// Largest root face + 1 (0 without strands), and a strand on it.
    faces: (usize, usize),
    /// Largest guide index a binding's guides use + 1 (0 when none), and a
    /// strand using it.
    guides: (usize, usize),
    /// The same for the clump guides.
    clumps: (usize, usize),
}

impl StrandBounds {
    /// Checks everything about `strands` that does not depend on the mesh
    /// or the guides (faces and guide indices are checked against the
    /// counts by [`StrandBounds::fits`]), and finds the counts they need.
    /// The first faulty strand is reported.
    pub fn new(strands: &Strands) -> Result<Self, Error> {
        let Strands {
            roots,
            bindings,
            grooms,
        } = *strands;
        if bindings.len() < roots.len() || grooms.len() < roots.len() {
            return Err(Error::InvalidArgument(
                "bindings and grooms must cover every strand",
            ));
        }
        // every index a u32 holds is some mesh's face; NO_GUIDE is no guide
        let (faces, guides) = (u32::MAX as usize, NO_GUIDE as usize);
        let mut bounds = StrandBounds::default();
        // this may run every frame over every strand: a branch-free screen
        // passes the valid ones, and the detailed checks run only on a
        // strand it rejects, to name the fault
        for (i, ((r, b), g)) in roots.iter().zip(bindings).zip(grooms).enumerate() {
            let (valid, used, clump) = strand_is_valid(faces, guides, r, b, g);
            if !valid {
                check_strand(faces, guides, r, b, g).map_err(|e| e.shifted(i))?;
            }
            if r.face as usize >= bounds.faces.0 {
                bounds.faces = (r.face as usize + 1, i);
            }
            if used > bounds.guides.0 {
                bounds.guides = (used, i);
            }
            if clump > bounds.clumps.0 {
                bounds.clumps = (clump, i);
            }
        }
        Ok(bounds)
    }

    /// The bounds of two ranges of one strand list, `other` starting at
    /// strand `offset` (its strands are reported at their index in the list).
    pub fn merge(self, other: StrandBounds, offset: usize) -> StrandBounds {
        let pick = |a: (usize, usize), b: (usize, usize)| {
            if b.0 > a.0 {
                (b.0, b.1 + offset)
            } else {
                a
            }
        };
        StrandBounds {
            faces: pick(self.faces, other.faces),
            guides: pick(self.guides, other.guides),
            clumps: pick(self.clumps, other.clumps),
        }
    }

    /// The fewest guides a frame needs for these strands: the largest
    /// guide index a binding uses (clump included) + 1, 0 when none.
    pub fn guides(&self) -> usize {
        self.guides.0.max(self.clumps.0)
    }

    /// Checks that the strands fit a mesh of `faces` triangles and a frame
    /// of `guides` guides.
    pub fn fits(&self, faces: usize, guides: usize) -> Result<(), Error> {
        let (needed, face_strand) = self.faces;
        if needed > faces {
            return Err(Error::OutOfRange {
                what: "strand roots",
                index: face_strand,
                value: needed - 1,
                bound: faces,
            });
        }
        for (what, (used, strand)) in [
            ("bindings.guides", self.guides),
            ("bindings.clump", self.clumps),
        ] {
            if used > guides {
                return Err(Error::OutOfRange {
                    what,
                    index: strand,
                    value: used - 1,
                    bound: guides,
                });
            }
        }
        Ok(())
    }
}

/// Validates `strands` against a mesh of `faces` triangles and `guides`
/// guides: [`StrandBounds::new`] and [`StrandBounds::fits`].
pub fn check_strands(strands: &Strands, faces: usize, guides: usize) -> Result<(), Error> {
    StrandBounds::new(strands)?.fits(faces, guides)
}

/// Exactly the conditions [`check_strand`] tests, without a branch; and
/// the strand's largest guide + 1 and its clump guide + 1 (each 0 without
/// one), read in the same pass.
#[inline]
fn strand_is_valid(
    faces: usize,
    guides: usize,
    r: &Root,
    b: &StrandBinding,
    g: &StrandGroom,
) -> (bool, usize, usize) {
    // comparisons are false for NaN, and an infinite coordinate fails the sum
    let e = BARYCENTRIC_SLACK;
    let root = ((r.face as usize) < faces) & (r.u >= -e) & (r.v >= -e) & (r.u + r.v <= 1.0 + e);
    let count = b.count as usize;
    let mut binding = count <= MAX_NEIGHBOURS;
    let clump = if b.clump == NO_GUIDE {
        0
    } else {
        b.clump as usize + 1
    };
    let mut used = 0;
    // summed in slot order, as `weight_sum` does
    let mut sum = 0.0f32;
    for k in 0..MAX_NEIGHBOURS {
        let guide = b.guides[k] as usize;
        let fine = (guide < guides) & (b.weights[k] >= 0.0) & (b.weights[k] <= 1.0);
        binding &= (k >= count) | fine;
        used = used.max(if k < count { guide + 1 } else { 0 });
        sum += if k < count { b.weights[k] } else { 0.0 };
    }
    binding &= (count == 0) | ((sum - 1.0).abs() <= WEIGHT_SUM_TOLERANCE);
    binding &= (b.clump == NO_GUIDE) | ((b.clump as usize) < guides);
    let values: &[f32] = bytemuck::cast_slice(core::slice::from_ref(g));
    let bounded = values
        .iter()
        .fold(true, |all, v| all & (v.abs() <= MAX_GROOM_VALUE));
    let pi2 = core::f32::consts::PI * core::f32::consts::PI;
    let groom = bounded
        & (g.root_radius >= 0.0)
        & (g.tip_radius >= 0.0)
        & (g.length >= 0.0)
        & (Vec2::from(g.lift).length_squared() <= pi2);
    (root & binding & groom, used, clump)
}

/// The float32 sum of `weights` in order: the one both checks compare.
fn weight_sum(weights: &[f32]) -> f32 {
    weights.iter().fold(0.0, |s, w| s + w)
}

/// Checks one strand, naming the first fault (element index 0).
fn check_strand(
    faces: usize,
    bound: usize,
    r: &Root,
    b: &StrandBinding,
    g: &StrandGroom,
) -> Result<(), Error> {
    check_root(faces, r, "strand roots")?;
    let count = b.count as usize;
    if count > MAX_NEIGHBOURS {
        return Err(Error::OutOfRange {
            what: "bindings.count",
            index: 0,
            value: count,
            bound: MAX_NEIGHBOURS + 1,
        });
    }
    let bad_guide = b.guides[..count].iter().find(|&&g| g as usize >= bound);
    let bad_clump = (b.clump != NO_GUIDE && b.clump as usize >= bound).then_some(&b.clump);
    let bad = bad_guide
        .map(|g| ("bindings.guides", g))
        .or(bad_clump.map(|c| ("bindings.clump", c)));
    if let Some((what, &value)) = bad {
        return Err(Error::OutOfRange {
            what,
            index: 0,
            value: value as usize,
            bound,
        });
    }
    if !b.weights[..count].iter().all(|w| w.is_finite()) {
        return Err(Error::NonFinite {
            what: "binding weights",
            index: 0,
        });
    }
    if !b.weights[..count].iter().all(|w| (0.0..=1.0).contains(w)) {
        return Err(Error::OutOfDomain {
            what: "binding weights (0..=1)",
            index: 0,
        });
    }
    // an orphan has no weight to sum; the weights are finite here
    let sum = weight_sum(&b.weights[..count]);
    if count > 0 && (sum - 1.0).abs() > WEIGHT_SUM_TOLERANCE {
        return Err(Error::WeightSum { index: 0, sum });
    }
    let values: &[f32] = bytemuck::cast_slice(core::slice::from_ref(g));
    if !values.iter().all(|v| v.is_finite()) {
        return Err(Error::NonFinite {
            what: "grooms",
            index: 0,
        });
    }
    if !values.iter().all(|v| v.abs() <= MAX_GROOM_VALUE) {
        return Err(Error::OutOfDomain {
            what: "grooms (within 1e6)",
            index: 0,
        });
    }
    if g.root_radius < 0.0 || g.tip_radius < 0.0 || g.length < 0.0 {
        return Err(Error::InvalidArgument(
            "a groom has a negative radius or length",
        ));
    }
    if Vec2::from(g.lift).length_squared() > core::f32::consts::PI * core::f32::consts::PI {
        return Err(Error::InvalidArgument(
            "a groom's lift turns by more than pi",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn special() -> impl Strategy<Value = f32> {
        prop::sample::select(vec![
            0.0,
            0.3,
            0.9,
            // with the base weights 0.3 and 0.5: a sum within 1e-4 of 1, and one past it
            0.20005,
            0.2002,
            -1e-3,
            -1e-5,
            1.0,
            4.0,
            2e6,
            -2e6,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ])
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]
        #[test]
        fn the_strand_screen_agrees_with_the_detailed_checks(
            changes in prop::collection::vec((0usize..32, special(), 0u32..12), 0..3),
        ) {
            let m = crate::testmesh::graded_plane(2, 1.0);
            let mesh = m.mesh();
            // a valid strand, then up to two fields changed
            let mut r = Root { face: 1, u: 0.2, v: 0.3, id: 0, rank: 0 };
            let mut b = StrandBinding { guides: [0, 1, 2, 0, 0, 0, 0, 0], weights: [0.2, 0.3, 0.5, 0.3, 0.3, 0.3, 0.3, 0.3], count: 3, clump: 0 };
            let mut g = StrandGroom { length: 1.0, root_radius: 0.01, tip_radius: 0.001, ..StrandGroom::default() };
            for &(field, x, i) in &changes {
                match field {
                    0 => r.face = i,
                    1 => r.u = x,
                    2 => r.v = x,
                    3 => b.count = i,
                    4..=11 => b.guides[field - 4] = i,
                    12..=19 => b.weights[field - 12] = x,
                    20 => b.clump = if i > 9 { NO_GUIDE } else { i },
                    _ => bytemuck::cast_slice_mut::<StrandGroom, f32>(core::slice::from_mut(&mut g))[field - 21] = x,
                }
            }
            let faces = mesh.triangle_count();
            let screen = strand_is_valid(faces, 6, &r, &b, &g).0;
            let detailed = check_strand(faces, 6, &r, &b, &g).is_ok();
            prop_assert_eq!(screen, detailed);
            // records checked once, then only the counts: the same verdict
            let strands = Strands { roots: &[r], bindings: &[b], grooms: &[g] };
            let split = StrandBounds::new(&strands).and_then(|bounds| bounds.fits(faces, 6));
            prop_assert_eq!(split.is_ok(), detailed);
        }
    }
}
