//! Where each posed guide first meets the cloth or a collider.

use crate::collide::{field_inside, Colliders, Entry, Near, FIELD_BATCH, MAX_POINTS};
use crate::interp::posed::PosedFrame;
use crate::surface::body::Body;
use crate::Error;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Where one guide first meets the cloth or a collider in one frame.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TrimRecord {
    /// The guide.
    pub guide: u32,
    /// The first control point past the meet (1 ..= points per guide - 1).
    pub cv: u32,
    /// The guide's curve parameter at the meet, in `[0, 1]`:
    /// `(cv - 1 + t) / (points - 1)` for the meet at `t` of the segment
    /// ending at `cv`.
    pub length: f32,
}

impl TrimRecord {
    /// Checks a record against a frame of `guides` guides of `points`
    /// points each; `index` names it in the error.
    pub fn check(&self, index: usize, guides: usize, points: usize) -> Result<(), Error> {
        if self.guide as usize >= guides {
            return Err(Error::OutOfRange {
                what: "trim records.guide",
                index,
                value: self.guide as usize,
                bound: guides,
            });
        }
        // the point past the meet: 0, the root, lies past none
        if !(1..points).contains(&(self.cv as usize)) {
            return Err(Error::NotBetween {
                what: "trim records.cv",
                index,
                value: self.cv as usize,
                first: 1,
                last: points.saturating_sub(1),
            });
        }
        if !self.length.is_finite() {
            return Err(Error::NonFinite {
                what: "trim records' length",
                index,
            });
        }
        if !(0.0..=1.0).contains(&self.length) {
            return Err(Error::OutOfDomain {
                what: "trim records' length (0..=1)",
                index,
            });
        }
        Ok(())
    }
}

/// Where guide `g` of `frame` first meets `cloth` (its triangles: the
/// body's inside test plays no part) or enters one of `colliders`, walking
/// from the root: the record, or `None` when it meets nothing. A collider
/// is entered at a segment whose end point is inside (a collider thinner
/// than a segment can be passed through); the entry is placed on the
/// segment by bisection, at the last tried parameter still outside.
pub fn meet(
    frame: &PosedFrame,
    g: usize,
    cloth: Option<&Body>,
    colliders: &Colliders,
) -> Option<TrimRecord> {
    let n = frame.points();
    let (cv, length) = first_meet(n, |j| frame.world_point(g, j), cloth, colliders)?;
    Some(TrimRecord {
        guide: g as u32,
        cv: cv as u32,
        length,
    })
}

/// [`meet`] for each guide of `guides`, in guide order, to `found`: the
/// same records, with a host field asked about [`FIELD_BATCH`] guides at
/// once (every point past their roots in one call, then one call per
/// bisection step for all their entries) rather than point by point.
pub fn meet_guides(
    frame: &PosedFrame,
    guides: core::ops::Range<usize>,
    cloth: Option<&Body>,
    colliders: &Colliders,
    mut found: impl FnMut(TrimRecord),
) {
    let first = guides.start;
    first_meets(
        guides.len(),
        frame.points(),
        |i, j| frame.world_point(first + i, j),
        cloth,
        colliders,
        |i, (cv, length)| {
            found(TrimRecord {
                guide: (first + i) as u32,
                cv: cv as u32,
                length,
            })
        },
    );
}

/// [`first_meet`] for `count` polylines of `n` points (at most
/// [`MAX_POINTS`]), polyline `i`'s point `j` at `at(i, j)`: `found(i,
/// meet)` for each that meets something, in order, with the same results,
/// a host field asked as [`meet_guides`] says.
pub(crate) fn first_meets(
    count: usize,
    n: usize,
    at: impl Fn(usize, usize) -> Vec3,
    cloth: Option<&Body>,
    colliders: &Colliders,
    mut found: impl FnMut(usize, (usize, f32)),
) {
    let mut start = 0;
    while start < count {
        let k = (count - start).min(FIELD_BATCH);
        let batch = |i: usize, j: usize| at(start + i, j);
        first_meets_batch(k, n, batch, cloth, colliders, |i, m| found(start + i, m));
        start += k;
    }
}

/// A segment whose end is inside a collider, being bisected.
struct Entering<'c, 'r> {
    polyline: usize,
    /// The segment's end point's index.
    j: usize,
    near: Near<'c, 'r>,
    /// Where the cloth meets the segment, if it does.
    cloth: Option<f32>,
    entry: Entry,
}

/// [`first_meets`] for at most [`FIELD_BATCH`] polylines.
fn first_meets_batch(
    k: usize,
    n: usize,
    at: impl Fn(usize, usize) -> Vec3,
    cloth: Option<&Body>,
    colliders: &Colliders,
    mut found: impl FnMut(usize, (usize, f32)),
) {
    let n = n.min(MAX_POINTS);
    let per = n.saturating_sub(1);
    let mut xyz = [[0.0f32; 3]; FIELD_BATCH * MAX_POINTS];
    let mut d = [0.0f32; FIELD_BATCH * MAX_POINTS];
    let mut in_field = [false; FIELD_BATCH * MAX_POINTS];
    if colliders.field.is_some() {
        for i in 0..k {
            for j in 1..n {
                xyz[i * per + j - 1] = at(i, j).to_array();
            }
        }
        field_inside(colliders, &xyz[..k * per], &mut d, &mut in_field);
    }
    let mut meets: [Option<(usize, f32)>; FIELD_BATCH] = [None; FIELD_BATCH];
    let mut entering: [Option<Entering>; FIELD_BATCH] = [const { None }; FIELD_BATCH];
    let mut pending = 0;
    for i in 0..k {
        let reach: f32 = (1..n).map(|j| at(i, j).distance(at(i, j - 1))).sum();
        let near = Near::new(colliders, at(i, 0), reach);
        let colliding = !near.is_empty();
        for j in 1..n {
            let (a, b) = (at(i, j - 1), at(i, j));
            let t = cloth.and_then(|c| c.first_meet(a, b));
            if colliding && (in_field[i * per + j - 1] || near.in_shape(b)) {
                entering[pending] = Some(Entering {
                    polyline: i,
                    j,
                    near,
                    cloth: t,
                    entry: Entry::new(),
                });
                pending += 1;
                break;
            }
            if let Some(t) = t {
                meets[i] = Some((j, t));
                break;
            }
        }
    }
    let entering = &mut entering[..pending];
    for _ in 0..Entry::BISECTIONS {
        let tried = |e: &Entering| e.entry.next(at(e.polyline, e.j - 1), at(e.polyline, e.j));
        if colliders.field.is_some() {
            for (x, e) in xyz.iter_mut().zip(entering.iter().flatten()) {
                *x = tried(e).to_array();
            }
            in_field[..pending].fill(false);
            field_inside(colliders, &xyz[..pending], &mut d, &mut in_field);
        }
        for (e, &field) in entering.iter_mut().flatten().zip(&in_field) {
            let inside = field || e.near.in_shape(tried(e));
            e.entry.narrow(inside);
        }
    }
    for e in entering.iter().flatten() {
        let entry = e.entry.out;
        meets[e.polyline] = Some((e.j, e.cloth.map_or(entry, |t| t.min(entry))));
    }
    for (i, m) in meets.iter().enumerate().take(k) {
        if let Some((j, t)) = *m {
            found(i, (j, ((j - 1) as f32 + t) / (n - 1) as f32));
        }
    }
}

/// Where the polyline of the `n` points `at(0)` (the root) .. `at(n - 1)`
/// first meets `cloth` or enters one of `colliders` (see [`meet`]): the
/// first point past the meet, and the curve parameter there.
pub(crate) fn first_meet(
    n: usize,
    at: impl Fn(usize) -> Vec3,
    cloth: Option<&Body>,
    colliders: &Colliders,
) -> Option<(usize, f32)> {
    let reach: f32 = (1..n).map(|j| at(j).distance(at(j - 1))).sum();
    let near = Near::new(colliders, at(0), reach);
    let colliding = !near.is_empty();
    for j in 1..n {
        let (a, b) = (at(j - 1), at(j));
        let mut t = cloth.and_then(|c| c.first_meet(a, b));
        if colliding && near.inside(b) {
            t = Some(t.map_or(near.entry(a, b), |t| t.min(near.entry(a, b))));
        }
        if let Some(t) = t {
            return Some((j, ((j - 1) as f32 + t) / (n - 1) as f32));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arena::{Arena, ArenaLayout};
    use crate::collide::{Plane, Sphere};
    use crate::guides::{CvLayout, Guides};
    use crate::interp::bind::{bind, BindParams, StrandBinding};
    use crate::interp::expand::ExpandJob;
    use crate::interp::groom::StrandGroom;
    use crate::interp::strand::{EndPoints, ExpandParams};
    use crate::interp::strands::{StrandBounds, Strands};
    use crate::testmesh::{graded_plane, roots, straight_guides, TestMesh};
    use crate::trim::length::{guide_lengths, shortest};
    use crate::trim::WHOLE;
    use crate::Strided;

    use crate::collide::{Entry, SignedDistance, FIELD_BATCH};
    use core::sync::atomic::{AtomicUsize, Ordering::Relaxed};

    const POINTS: usize = 8;

    /// A ball field (centre (0.5, 0.5, 0.2), radius 0.12) that counts its
    /// calls.
    #[derive(Default)]
    struct CountedBall {
        calls: AtomicUsize,
    }

    impl SignedDistance for CountedBall {
        fn distances(&self, points: &[[f32; 3]], out: &mut [f32]) {
            self.calls.fetch_add(1, Relaxed);
            for (p, d) in points.iter().zip(out) {
                *d = Vec3::from(*p).distance(Vec3::new(0.5, 0.5, 0.2)) - 0.12;
            }
        }
    }
    const CLOTH: f32 = 0.1;

    /// A flat cloth at height `CLOTH` over the unit square and beyond.
    fn cloth() -> TestMesh {
        TestMesh {
            p: vec![
                [-1.0, -1.0, CLOTH],
                [2.0, -1.0, CLOTH],
                [2.0, 2.0, CLOTH],
                [-1.0, 2.0, CLOTH],
            ],
            t: vec![[0, 1, 2], [0, 2, 3]],
            uv: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            n: vec![],
        }
    }

    #[test]
    fn guides_meet_a_cloth_and_colliders_where_they_cross_them() {
        let skin = graded_plane(8, 1.0);
        let guide_roots = roots(skin.mesh(), 40, 5);
        let points = straight_guides(&skin.mesh(), &guide_roots, POINTS, 0.3);
        let guides = Guides {
            roots: &guide_roots,
            points: Strided::from_slice(&points),
            layout: CvLayout::Fixed(POINTS),
        };
        let mut layout = ArenaLayout::new();
        PosedFrame::layout(&mut layout, skin.p.len(), guide_roots.len(), POINTS);
        let mut memory = vec![0u8; layout.bytes()];
        let frame =
            PosedFrame::with_guides(skin.mesh(), &guides, POINTS, &mut Arena::new(&mut memory))
                .unwrap();
        let cloth = cloth();
        let mut body_memory = vec![0u8; Body::required_bytes(&cloth.mesh()).unwrap()];
        let body = Body::new(&cloth.mesh(), &mut Arena::new(&mut body_memory)).unwrap();
        let g = guide_roots.len();
        let find = |cloth: Option<&Body>, colliders: &Colliders| -> Vec<TrimRecord> {
            (0..g)
                .filter_map(|i| meet(&frame, i, cloth, colliders))
                .collect()
        };

        // the cloth: every guide rises straight through it
        let none = Colliders::default();
        let records = find(Some(&body), &none);
        assert_eq!(records.len(), g);
        for r in &records {
            let tip = frame.world_point(r.guide as usize, POINTS - 1).z;
            assert!((r.length * tip - CLOTH).abs() < 1e-5, "{r:?} tip {tip}");
            let past = r.length * (POINTS - 1) as f32;
            assert_eq!(r.cv, libm::floorf(past) as u32 + 1, "{r:?}");
        }

        // the half-space above the cloth: the same meets, from outside
        let above = [Plane {
            normal: [0.0, 0.0, -1.0],
            offset: -CLOTH,
        }];
        let colliders = Colliders {
            planes: &above,
            ..Colliders::default()
        };
        let entered = find(None, &colliders);
        assert_eq!(entered.len(), g);
        for (a, b) in records.iter().zip(&entered) {
            let segment = 1.0 / (POINTS - 1) as f32;
            assert!(b.length <= a.length + 1e-6, "{a:?} {b:?}");
            assert!(a.length - b.length < segment / 2048.0, "{a:?} {b:?}");
        }

        // out of reach: nothing
        let far = [Sphere {
            centre: [0.5, 0.5, 5.0],
            radius: 1.0,
        }];
        let colliders = Colliders {
            spheres: &far,
            ..Colliders::default()
        };
        assert!(find(None, &colliders).is_empty());

        // a host field asked about whole batches gives the same records,
        // however the guides are split, in a call per batch and per step
        let ball = CountedBall::default();
        let spheres = [Sphere {
            centre: [0.2, 0.3, 0.25],
            radius: 0.1,
        }];
        let with_field = Colliders {
            spheres: &spheres,
            planes: &above,
            field: Some(&ball),
            ..Colliders::default()
        };
        for cloth in [None, Some(&body)] {
            let one_by_one = find(cloth, &with_field);
            ball.calls.store(0, Relaxed);
            let (mut batched, mut split) = (Vec::new(), Vec::new());
            meet_guides(&frame, 0..g, cloth, &with_field, |r| batched.push(r));
            let calls = ball.calls.load(Relaxed);
            meet_guides(&frame, 0..7, cloth, &with_field, |r| split.push(r));
            meet_guides(&frame, 7..g, cloth, &with_field, |r| split.push(r));
            assert_eq!(batched, one_by_one);
            assert_eq!(split, one_by_one);
            let batches = g.div_ceil(FIELD_BATCH);
            assert!(
                calls <= batches * (1 + Entry::BISECTIONS as usize),
                "{calls} calls"
            );
        }
        let ball_only = Colliders {
            field: Some(&ball),
            ..Colliders::default()
        };
        let entered = find(None, &ball_only);
        assert!(
            !entered.is_empty() && entered.len() < g,
            "{} of {g}",
            entered.len()
        );

        // render hairs cut by the shot pass end at the cloth, not before
        let hairs = roots(skin.mesh(), 600, 9);
        let mut bind_memory =
            vec![0u8; crate::interp::bind::required_bytes(&skin.mesh(), g).unwrap()];
        let mut bindings = vec![StrandBinding::default(); hairs.len()];
        bind(
            &skin.mesh(),
            &guides,
            &hairs,
            &BindParams::default(),
            &mut Arena::new(&mut bind_memory),
            &mut bindings,
        )
        .unwrap();
        let grooms = vec![
            StrandGroom {
                length: 1.0,
                root_radius: 0.001,
                tip_radius: 0.001,
                ..StrandGroom::default()
            };
            hairs.len()
        ];
        let strands = Strands {
            roots: &hairs,
            bindings: &bindings,
            grooms: &grooms,
        };
        let mut per_guide = vec![0.0f32; g];
        guide_lengths(&records, g, POINTS, &mut per_guide).unwrap();
        let mut lengths = vec![WHOLE; hairs.len()];
        shortest(&strands, &per_guide, &mut lengths);
        let params = ExpandParams {
            points_per_strand: POINTS,
            end_points: EndPoints::Pinned,
            orphan_length: 0.3,
            width_scale: 1.0,
        };
        let per = params.output_points();
        let mut curves = vec![[0.0f32; 4]; hairs.len() * per];
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut curves);
        let bounds = StrandBounds::new(&strands).unwrap();
        let job = ExpandJob::new(&frame, strands, &bounds, &params, bytes.len(), 16)
            .unwrap()
            .trimmed(&lengths)
            .unwrap();
        job.run(0..hairs.len(), bytes);
        for (i, curve) in curves.chunks(per).enumerate() {
            let top = curve.iter().map(|p| p[2]).fold(f32::MIN, f32::max);
            assert!(top <= CLOTH + 1e-5, "hair {i} reaches {top}");
            assert!(top >= CLOTH - 1e-3, "hair {i} stops at {top}");
            assert_eq!(curve[per - 1], curve[per - 2], "pinned tip");
        }
    }
}
