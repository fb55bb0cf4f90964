//! Patches (paper 2.2, 4): strands grouped by place, so a renderer expands
//! only the patches its rays reach, and each patch's box on a frame,
//! bounded without expanding it.
//!
//! A patch is a contiguous range of strands (one expansion range): the
//! strands are put in Morton order of their rest roots and cut into runs of
//! the patch size, and within each patch sorted by LOD rank, so the first k
//! of a patch are its share of an even subset (a shadow or distance LOD is
//! a cutoff inside every patch).
//!
//! The box of a patch on a posed frame holds, around each strand's root, a
//! ball its expanded points (with their radii), and the Catmull-Rom curves
//! through them, cannot leave: the blended guide points are within the
//! weighted sum of the bound guides' reaches, scaled by the strand's
//! length, bent by at most `bend` of its length, pulled toward the clump
//! guide's points, and kinked by at most `kink_amplitude` of its length
//! (times the phase's length). A rotation about the
//! root (lift, push-out) or a cut (trimming) keeps every point in the ball,
//! so the box covers them too; the union over shutter samples covers the
//! motion.

use crate::interp::bind::NO_GUIDE;
use crate::interp::posed::PosedFrame;
use crate::interp::strand::ExpandParams;
use crate::interp::strands::Strands;
use crate::{Error, Mesh, Root};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// How far a uniform Catmull-Rom curve can reach beyond its control
/// points' ball around the root (the sum of the basis' absolute weights).
const CURVE_OVERSHOOT: f32 = 1.25;

/// A patch: strands `first .. first + count`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct Patch {
    /// First strand.
    pub first: u32,
    /// Strands in it.
    pub count: u32,
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchBox {
    /// Low corner.
    pub lo: Vec3,
    /// High corner.
    pub hi: Vec3,
}

impl PatchBox {
    /// The empty box (the identity of [`PatchBox::merge`]): low corner
    /// `f32::MAX`, high corner `-f32::MAX`, so it holds no point. Finite,
    /// so a host that checks its boxes for NaN and infinity (as Embree's
    /// users must) never meets one, and merging still leaves any box as
    /// it is.
    pub const EMPTY: PatchBox = PatchBox {
        lo: Vec3::splat(f32::MAX),
        hi: Vec3::splat(-f32::MAX),
    };

    /// The box holding both (shutter samples, patches).
    pub fn merge(self, other: PatchBox) -> PatchBox {
        PatchBox {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
        }
    }

    /// True when `p` is inside (bounds included).
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.lo).all() && p.cmple(self.hi).all()
    }
}

/// Patches for `strands` strands of about `size` each.
pub fn patch_count(strands: usize, size: usize) -> usize {
    strands.div_ceil(size.max(1))
}

/// Orders the strands rooted at `roots` (on `mesh`, at rest) into patches
/// of `size` strands (the last may be smaller): writes `order` (the strand
/// placed k-th, to reorder roots, bindings and grooms by) and `patches`
/// ([`patch_count`] of them). `keys` is scratch, as long as `roots`.
pub fn plan(
    mesh: &Mesh,
    roots: &[Root],
    size: usize,
    keys: &mut [u64],
    order: &mut [u32],
    patches: &mut [Patch],
) -> Result<usize, Error> {
    let (s, count) = (roots.len(), patch_count(roots.len(), size));
    if size == 0 || size > u32::MAX as usize || s >= u32::MAX as usize {
        return Err(Error::InvalidArgument(
            "patch size must be 1..2^32 and strands fewer than 2^32",
        ));
    }
    // each buffer reported in its own count: strands, or patches
    if keys.len() < s || order.len() < s {
        return Err(Error::OutputTooSmall {
            needed: s,
            available: keys.len().min(order.len()),
        });
    }
    if patches.len() < count {
        return Err(Error::OutputTooSmall {
            needed: count,
            available: patches.len(),
        });
    }
    mesh.check()?;
    for (i, r) in roots.iter().enumerate() {
        crate::root::check_root(mesh.triangle_count(), r, "strand roots")
            .map_err(|e| e.shifted(i))?;
    }
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for r in roots {
        let p = mesh.point(r.face as usize, r.u, r.v);
        (lo, hi) = (lo.min(p), hi.max(p));
    }
    let scale = 1023.0 / (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
    for (i, (k, r)) in keys.iter_mut().zip(roots).enumerate() {
        let q = ((mesh.point(r.face as usize, r.u, r.v) - lo) * scale)
            .clamp(Vec3::ZERO, Vec3::splat(1023.0));
        *k = morton(q.x as u32, q.y as u32, q.z as u32) << 32 | i as u64;
    }
    keys[..s].sort_unstable();
    for (o, k) in order.iter_mut().zip(&keys[..s]) {
        *o = *k as u32;
    }
    for (k, (patch, run)) in patches
        .iter_mut()
        .zip(order[..s].chunks_mut(size))
        .enumerate()
    {
        run.sort_unstable_by_key(|&i| (roots[i as usize].rank, i));
        *patch = Patch {
            first: (k * size) as u32,
            count: run.len() as u32,
        };
    }
    Ok(count)
}

/// Spreads the low 10 bits of x, y and z into a 30-bit Morton code.
fn morton(x: u32, y: u32, z: u32) -> u64 {
    fn spread(v: u32) -> u64 {
        let mut v = u64::from(v & 0x3ff);
        v = (v | v << 16) & 0x0300_00ff;
        v = (v | v << 8) & 0x0300_f00f;
        v = (v | v << 4) & 0x030c_30c3;
        (v | v << 2) & 0x0924_9249
    }
    spread(x) | spread(y) << 1 | spread(z) << 2
}

/// Checks `strands` (as expansion does) against `frame`'s mesh and guides,
/// and that each of `patches` lies within them, so [`patch_box`] may run on
/// any of them.
pub fn check(frame: &PosedFrame, strands: &Strands, patches: &[Patch]) -> Result<(), Error> {
    crate::interp::strands::check_strands(
        strands,
        frame.mesh().triangle_count(),
        frame.guide_count(),
    )?;
    for (i, p) in patches.iter().enumerate() {
        if u64::from(p.first) + u64::from(p.count) > strands.len() as u64 {
            return Err(Error::OutOfRange {
                what: "patches",
                index: i,
                value: (u64::from(p.first) + u64::from(p.count)) as usize,
                bound: strands.len(),
            });
        }
    }
    Ok(())
}

/// Writes, for every guide of `frame`, its reach: the largest distance of
/// its points from its root frame's origin.
pub fn guide_reach(frame: &PosedFrame, reach: &mut [f32]) {
    let n = frame.points();
    for (g, r) in reach.iter_mut().enumerate().take(frame.guide_count()) {
        *r = (0..n)
            .map(|j| frame.local_point(g, j).length())
            .fold(0.0, f32::max);
    }
}

/// How many of `patch`'s strands are in the LOD that keeps the strands of
/// rank below `cutoff`: its first ones, since [`plan`] sorts each patch by
/// rank (`roots` in the plan's order). Expanding that many of every patch,
/// with [`lod_width_scale`](crate::interp::strand::lod_width_scale), draws
/// an even subset of the fur that covers as much.
///
/// # Panics
/// When `patch` is not within `roots`.
pub fn lod_count(roots: &[Root], patch: Patch, cutoff: u32) -> u32 {
    let range = patch.first as usize..patch.first as usize + patch.count as usize;
    roots[range].partition_point(|r| r.rank < cutoff) as u32
}

/// The box of strands `first .. first + count` of `strands` (checked by
/// [`check`]) on `frame`, with `reach` from [`guide_reach`] on the same
/// frame: every point [`expand`](crate::interp::expand) writes for them,
/// radius included, lies inside. [`PatchBox::EMPTY`] for no strand.
pub fn patch_box(
    frame: &PosedFrame,
    reach: &[f32],
    strands: &Strands,
    params: &ExpandParams,
    patch: Patch,
) -> PatchBox {
    let mesh = frame.mesh();
    let range = patch.first as usize..(patch.first + patch.count) as usize;
    let mut out = PatchBox::EMPTY;
    for i in range {
        let (r, b, g) = (&strands.roots[i], &strands.bindings[i], &strands.grooms[i]);
        let o = mesh.point(r.face as usize, r.u, r.v);
        let count = b.count as usize;
        // the weights sum to 1 only within a tolerance: the blend is within
        // the weighted sum of the reaches
        let far = if count == 0 {
            params.orphan_length.abs()
        } else {
            (0..count)
                .map(|k| b.weights[k] * reach[b.guides[k] as usize])
                .sum::<f32>()
        };
        let scale = g.length.abs();
        // scaled, bent; then kinked (the phase need not be a unit vector)
        let shaped = far * scale * (1.0 + g.bend.abs());
        let phase = libm::hypotf(g.kink_phase[0], g.kink_phase[1]);
        let kink = g.kink_amplitude.abs() * far * scale * phase;
        // pulled toward the clump guide's points by up to `clump`
        let pulled = if b.clump == NO_GUIDE || g.clump == 0.0 {
            shaped
        } else {
            let c = b.clump as usize;
            // the clump guide's points are within twice its reach of its
            // first point
            let centre = (frame.world_point(c, 0) - o).length() + 2.0 * reach[c];
            shaped.max((1.0 - g.clump).abs() * shaped + g.clump.abs() * centre)
        };
        let radius = g.root_radius.abs().max(g.tip_radius.abs()) * params.width_scale;
        // a Catmull-Rom curve through the points (and its radius) reaches
        // at most 1.25 times as far (the basis' absolute weights sum to at
        // most 1.25); rounding in the kernel stays far below the slack
        let ball = (pulled + kink + radius) * CURVE_OVERSHOOT * (1.0 + 1e-4)
            + 1e-6 * o.abs().max_element();
        out = out.merge(PatchBox {
            lo: o - Vec3::splat(ball),
            hi: o + Vec3::splat(ball),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::fixture::{Scene, POINTS};
    use crate::interp::expand::expand;
    use crate::interp::strand::EndPoints;

    #[test]
    fn patches_are_places_ranked_inside() {
        let scene = Scene::new(100);
        let mesh = scene.rest.mesh();
        let s = scene.roots.len();
        let (mut keys, mut order) = (vec![0u64; s], vec![0u32; s]);
        let mut patches = vec![Patch::default(); patch_count(s, 32)];
        assert_eq!(
            plan(&mesh, &scene.roots, 32, &mut keys, &mut order, &mut patches),
            Ok(7)
        );
        // a permutation, cut into contiguous runs, ranked inside each
        let mut seen = vec![false; s];
        for &i in &order {
            assert!(!core::mem::replace(&mut seen[i as usize], true));
        }
        let mut next = 0;
        for p in &patches {
            assert_eq!(p.first, next);
            next += p.count;
            let run = &order[p.first as usize..(p.first + p.count) as usize];
            assert!(run
                .windows(2)
                .all(|w| scene.roots[w[0] as usize].rank < scene.roots[w[1] as usize].rank));
        }
        assert_eq!(next as usize, s);
        // a patch is a place: on average smaller than the whole (a random
        // seventh of the roots spans nearly all of it; Morton runs on a
        // curved surface are not round)
        let spread = |run: &[u32]| {
            let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
            for &i in run {
                let r = &scene.roots[i as usize];
                let p = mesh.point(r.face as usize, r.u, r.v);
                (lo, hi) = (lo.min(p), hi.max(p));
            }
            (hi - lo).length()
        };
        let runs = patches
            .iter()
            .map(|p| spread(&order[p.first as usize..(p.first + p.count) as usize]));
        let mean = runs.sum::<f32>() / patches.len() as f32;
        assert!(mean < 0.75 * spread(&order), "{mean} vs {}", spread(&order));
    }

    #[test]
    fn an_empty_patch_has_the_finite_empty_box() {
        let scene = Scene::new(100);
        let strands = Strands {
            roots: &scene.roots,
            bindings: &scene.bindings,
            grooms: &scene.grooms,
        };
        let params = ExpandParams {
            points_per_strand: POINTS,
            end_points: EndPoints::Pinned,
            orphan_length: 0.2,
            width_scale: 1.0,
        };
        scene.with_frame(&scene.rest, &scene.guide_world, |frame| {
            let mut reach = vec![0.0; frame.guide_count()];
            guide_reach(frame, &mut reach);
            let empty = Patch { first: 3, count: 0 };
            let b = patch_box(frame, &reach, &strands, &params, empty);
            assert_eq!(b, PatchBox::EMPTY);
            assert!(b.lo.is_finite() && b.hi.is_finite());
            assert!(b.lo.cmpgt(b.hi).all() && !b.contains(Vec3::ZERO));
            let one = patch_box(
                frame,
                &reach,
                &strands,
                &params,
                Patch { first: 3, count: 1 },
            );
            assert_eq!(one.merge(b), one);
        });
    }

    #[test]
    fn every_expanded_point_is_inside_its_patch_box() {
        let scene = Scene::new(100);
        let strands = Strands {
            roots: &scene.roots,
            bindings: &scene.bindings,
            grooms: &scene.grooms,
        };
        let params = ExpandParams {
            points_per_strand: POINTS,
            end_points: EndPoints::Pinned,
            orphan_length: 0.2,
            width_scale: 1.0,
        };
        let patches: Vec<Patch> = (0..scene.roots.len() as u32)
            .step_by(16)
            .map(|first| Patch {
                first,
                count: 16.min(scene.roots.len() as u32 - first),
            })
            .collect();
        for t in [0.0, 0.5, 1.0] {
            let (mesh, world) = scene.posed(t);
            scene.with_frame(&mesh, &world, |frame| {
                let mut reach = vec![0.0; frame.guide_count()];
                guide_reach(frame, &mut reach);
                let mut out = vec![[0.0f32; 4]; scene.roots.len() * params.output_points()];
                let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut out);
                expand(frame, &strands, &params, bytes, 16).unwrap();
                let per = params.output_points();
                for p in &patches {
                    let b = patch_box(frame, &reach, &strands, &params, *p);
                    assert!(b.lo.is_finite() && b.hi.is_finite());
                    for i in p.first as usize..(p.first + p.count) as usize {
                        for q in &out[i * per..(i + 1) * per] {
                            let (c, r) = (Vec3::new(q[0], q[1], q[2]), q[3]);
                            assert!(
                                b.contains(c + Vec3::splat(r)) && b.contains(c - Vec3::splat(r)),
                                "strand {i} at t {t}"
                            );
                        }
                    }
                }
            });
        }
    }
}
