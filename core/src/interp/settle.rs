//! Settling strands out of the body at rest (once per groom).
//!
//! Interpolated strands can enter the body even when every guide stays
//! outside: a strand's own root frame turns its guides' shapes, and on a thin
//! part (between fingers, along an ear) the turned shape reaches the next
//! surface. Settling expands each strand at the rest pose, and where a point
//! lies inside the [`Body`], pushes the strand out by rotating it about its
//! root toward the normal (the paper's collision response), in steps, storing
//! the angle as the groom's `lift`. Since `lift` is applied in the strand's
//! own frame, the fix follows the body at every frame at no cost to strands
//! that need none. Strands that a full lift does not free lose their clump
//! pull, are turned about other axes of the tangent plane (past the normal,
//! for creases where the interpolated normal grazes the surface), and last
//! are shortened; any left inside are counted, never hidden.

use crate::collide::lift::{first_clear, none_inside, toward_normal, LIFT_STEP, LIFT_STEPS};
use crate::interp::bind::StrandBinding;
use crate::interp::groom::StrandGroom;
use crate::interp::posed::PosedFrame;
use crate::interp::strand::{strand, EndPoints, ExpandParams, Lanes, MAX_STRAND_POINTS};
use crate::interp::strands::{check_strands, Strands};
use crate::surface::body::Body;
use crate::{Error, Root};
use glam::{Vec2, Vec3};

/// Rotation axes tried around the tangent plane when lifting toward the
/// normal is not enough.
const AXES: u32 = 8;
/// Times a strand that a full lift leaves inside is shortened.
const SHORTEN_STEPS: u32 = 6;
/// Length kept at each shortening.
const SHORTEN: f32 = 0.7;

/// What settling changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SettleReport {
    /// Strands rotated toward their normal.
    pub lifted: u32,
    /// Strands a lift alone did not free (their clump pull was dropped).
    pub unclumped: u32,
    /// Strands that were also turned about another axis, past the normal.
    pub turned: u32,
    /// Strands that also had to be shortened.
    pub shortened: u32,
    /// Strands still partly inside after every step (left fully lifted,
    /// unclumped and at the shortest length tried).
    pub unresolved: u32,
}

impl SettleReport {
    /// Adds the counts of another range.
    pub fn merge(&mut self, other: SettleReport) {
        self.lifted += other.lifted;
        self.unclumped += other.unclumped;
        self.turned += other.turned;
        self.shortened += other.shortened;
        self.unresolved += other.unresolved;
    }
}

/// Settles the strands at `roots`, bound by `bindings`, updating `grooms`
/// (all three parallel) on the rest pose `guides` (a [`PosedFrame`] of the
/// rest mesh and rest guides) with the rest mesh's `body`. Validates
/// first: nothing changes on error. Pure per strand, so disjoint ranges may
/// run on different threads.
pub fn settle(
    body: &Body,
    roots: &[Root],
    bindings: &[StrandBinding],
    grooms: &mut [StrandGroom],
    guides: &PosedFrame,
    params: &ExpandParams,
) -> Result<SettleReport, Error> {
    check_settle(roots, bindings, grooms, guides, params)?;
    Ok(settle_checked(
        body, roots, bindings, grooms, guides, params,
    ))
}

/// Everything [`settle`] checks: the parameters against the frame, and the
/// strand records against its mesh and guides. A threaded host checks all
/// strands (or each range, before any range runs) and then runs
/// [`settle_checked`] on ranges.
pub fn check_settle(
    roots: &[Root],
    bindings: &[StrandBinding],
    grooms: &[StrandGroom],
    guides: &PosedFrame,
    params: &ExpandParams,
) -> Result<(), Error> {
    guides.check_params(params)?;
    let strands = Strands {
        roots,
        bindings,
        grooms,
    };
    let faces = guides.mesh().triangle_count();
    check_strands(&strands, faces, guides.guide_count())
}

/// [`settle`] for inputs [`check_settle`] passed.
pub fn settle_checked(
    body: &Body,
    roots: &[Root],
    bindings: &[StrandBinding],
    grooms: &mut [StrandGroom],
    guides: &PosedFrame,
    params: &ExpandParams,
) -> SettleReport {
    let n = params.points_per_strand;
    // settling looks at the strand's own points, not the repeated ends
    let params = &ExpandParams {
        end_points: EndPoints::Raw,
        ..*params
    };
    let mut lanes = Lanes::new(n);
    let mut points = [[0.0f32; 4]; MAX_STRAND_POINTS];
    let mut report = SettleReport::default();
    for ((root, bind), groom) in roots.iter().zip(bindings).zip(grooms) {
        let frame = guides.root_frame(root.face as usize, root.u, root.v);
        // the root itself lies on the surface; every later point must be
        // outside. Gives that, and the tip.
        let mut hint = 0;
        let mut evaluate = |g: &StrandGroom| {
            strand(
                &frame,
                bind,
                g,
                guides,
                params,
                &mut lanes,
                &mut points[..n],
            );
            let later = &points[1..n];
            let clear = none_inside(later.len(), &mut hint, |j| {
                body.contains(Vec3::new(later[j][0], later[j][1], later[j][2]))
            });
            (
                clear,
                Vec3::new(points[n - 1][0], points[n - 1][1], points[n - 1][2]),
            )
        };
        let (clear, tip) = evaluate(groom);
        if clear {
            continue;
        }
        let tip = frame.to_local(tip);
        let (settled, outcome) = settle_one(*groom, tip, &mut |g| evaluate(g).0);
        *groom = settled;
        let at_least = |o: Outcome| (outcome >= o) as u32;
        report.lifted += 1;
        report.unclumped += at_least(Outcome::Unclumped);
        report.turned += at_least(Outcome::Turned);
        report.shortened += at_least(Outcome::Shortened);
        report.unresolved += at_least(Outcome::Unresolved);
    }
    report
}

/// How far settling had to go for one strand, in order.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Outcome {
    Lifted,
    Unclumped,
    Turned,
    Shortened,
    Unresolved,
}

/// For a strand found inside: the first groom `clear` accepts, trying in order: lifts toward the
/// normal (in the vertical plane of the local `tip`, up to the normal), the
/// same without clump pull, rotations about 8 axes of the tangent plane up
/// to a right angle (past the normal: in a crease the interpolated normal can
/// graze the surface), and shortening at the full lift. Returns how far it took.
fn settle_one(
    groom: StrandGroom,
    tip: Vec3,
    clear: &mut impl FnMut(&StrandGroom) -> bool,
) -> (StrandGroom, Outcome) {
    let (toward, to_normal) = toward_normal(tip);
    let with = |axis: Vec2, angle: f32, clump: f32| StrandGroom {
        lift: (Vec2::from(groom.lift) + axis * angle).into(),
        clump,
        ..groom
    };
    // the first clear angle of `axis` (up to `limit`), with a margin
    let mut sweep = |axis: Vec2, limit: f32, clump: f32, from: u32| {
        first_clear(limit, from, |a| clear(&with(axis, a, clump))).map(|a| with(axis, a, clump))
    };
    if let Some(g) = sweep(toward, to_normal, groom.clump, 1) {
        return (g, Outcome::Lifted);
    }
    if groom.clump != 0.0 {
        if let Some(g) = sweep(toward, to_normal, 0.0, 0) {
            return (g, Outcome::Unclumped);
        }
    }
    let axes: [Vec2; AXES as usize] = core::array::from_fn(|m| {
        let (s, c) = libm::sincosf(m as f32 * core::f32::consts::TAU / AXES as f32);
        Vec2::new(toward.x * c - toward.y * s, toward.x * s + toward.y * c)
    });
    let with = &with;
    let turned = (1..=LIFT_STEPS)
        .flat_map(|k| {
            axes.iter()
                .map(move |&axis| with(axis, k as f32 * LIFT_STEP, 0.0))
        })
        .find(|g| clear(g));
    if let Some(g) = turned {
        return (g, Outcome::Turned);
    }
    let mut trial = with(toward, to_normal, 0.0);
    for _ in 0..SHORTEN_STEPS {
        trial.length *= SHORTEN;
        if clear(&trial) {
            return (trial, Outcome::Shortened);
        }
    }
    (trial, Outcome::Unresolved)
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::arena::{Arena, ArenaLayout};
    use crate::guides::{CvLayout, Guides};
    use crate::interp::bind::{bind, BindParams, StrandBinding};
    use crate::interp::expand::expand;
    use crate::rng::{self, Purpose};
    use crate::testmesh::{roots, sphere};
    use crate::{Mesh, Strided};

    const CVS: usize = 8;

    /// Guides combed flat over a unit sphere in random directions, 1% above
    /// it: each guide is outside, but the average of two combed apart dips
    /// below its strand's root.
    fn hugging_guides(mesh: &Mesh, guides: &[Root]) -> Vec<[f32; 3]> {
        let mut out = vec![];
        for (g, r) in guides.iter().enumerate() {
            let p = mesh.point(r.face as usize, r.u, r.v).normalize();
            let a = rng::unit(3, g as u64, Purpose::Uniform, 0) * core::f32::consts::TAU;
            let t = p.any_orthonormal_vector();
            let d = t * libm::cosf(a) + p.cross(t) * libm::sinf(a);
            for j in 0..CVS {
                let s = 0.6 * j as f32 / (CVS - 1) as f32;
                out.push(((p * libm::cosf(s) + d * libm::sinf(s)) * 1.01).into());
            }
        }
        out
    }

    #[test]
    fn settled_strands_stay_outside_and_expand_honours_the_lift() {
        let m = sphere(24, 48);
        let mesh = m.mesh();
        let guide_roots = roots(mesh, 150, 1);
        let guide_points = hugging_guides(&mesh, &guide_roots);
        assert!(guide_points.iter().all(|p| Vec3::from(*p).length() > 1.0));
        let guides = Guides {
            roots: &guide_roots,
            points: Strided::from_slice(&guide_points),
            layout: CvLayout::Fixed(CVS),
        };
        let strands = roots(mesh, 3000, 2);
        let mut bindings = vec![StrandBinding::default(); strands.len()];
        let mut buf =
            vec![0u8; crate::interp::bind::required_bytes(&mesh, guide_roots.len()).unwrap()];
        let params = BindParams::default();
        bind(
            &mesh,
            &guides,
            &strands,
            &params,
            &mut Arena::new(&mut buf),
            &mut bindings,
        )
        .unwrap();
        let original = vec![
            StrandGroom {
                length: 1.0,
                clump: 0.3,
                root_radius: 0.001,
                ..StrandGroom::default()
            };
            strands.len()
        ];
        let expand_params = ExpandParams {
            points_per_strand: CVS,
            end_points: EndPoints::Pinned,
            orphan_length: 0.1,
            width_scale: 1.0,
        };
        let mut layout = ArenaLayout::new();
        PosedFrame::layout(&mut layout, m.p.len(), guide_roots.len(), CVS);
        let mut body_buf = vec![0u8; Body::required_bytes(&mesh).unwrap()];
        let body = Body::new(&mesh, &mut Arena::new(&mut body_buf)).unwrap();
        let mut guide_buf = vec![0u8; layout.bytes()];
        let prepared =
            PosedFrame::with_guides(mesh, &guides, CVS, &mut Arena::new(&mut guide_buf)).unwrap();
        let per = expand_params.output_points();
        let curves = |grooms: &[StrandGroom]| {
            let mut out = vec![[0.0f32; 4]; strands.len() * per];
            let all = Strands {
                roots: &strands,
                bindings: &bindings,
                grooms,
            };
            expand(
                &prepared,
                &all,
                &expand_params,
                bytemuck::cast_slice_mut(&mut out),
                16,
            )
            .unwrap();
            out
        };
        // points strictly inside the inscribed sphere of the polyhedron
        let deep = |out: &[[f32; 4]]| {
            out.chunks(per)
                .filter(|c| {
                    c[2..]
                        .iter()
                        .any(|p| Vec3::new(p[0], p[1], p[2]).length() < 0.99)
                })
                .count()
        };
        let before = deep(&curves(&original));
        assert!(
            before > 100,
            "the scene must produce strands inside ({before})"
        );

        let mut settled = original.clone();
        let report = settle(
            &body,
            &strands,
            &bindings,
            &mut settled,
            &prepared,
            &expand_params,
        )
        .unwrap();
        let out = curves(&settled);
        assert_eq!(deep(&out), 0, "{report:?}");
        assert_eq!(report.unresolved, 0);
        let inside = out
            .chunks(per)
            .filter(|c| {
                c[2..]
                    .iter()
                    .any(|p| body.contains(Vec3::new(p[0], p[1], p[2])))
            })
            .count();
        assert_eq!(inside, 0);
        let changed = original
            .iter()
            .zip(&settled)
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(changed as u32, report.lifted);
        assert!(report.lifted as usize >= before);
        assert!(settled.iter().all(|g| Vec2::from(g.lift).length() <= 1.7));

        // settling again changes nothing, and ranges settle independently
        let mut again = settled.clone();
        let report = settle(
            &body,
            &strands,
            &bindings,
            &mut again,
            &prepared,
            &expand_params,
        )
        .unwrap();
        assert_eq!((report, &again), (SettleReport::default(), &settled));
        let mut halves = original.clone();
        let mid = strands.len() / 3;
        let (a, b) = halves.split_at_mut(mid);
        let p = (&prepared, &expand_params);
        settle(&body, &strands[..mid], &bindings[..mid], a, p.0, p.1).unwrap();
        settle(&body, &strands[mid..], &bindings[mid..], b, p.0, p.1).unwrap();
        assert_eq!(halves, settled);

        // bad grooms are refused before anything changes
        let mut bad = original.clone();
        bad[7].lift = [f32::NAN, 0.0];
        assert!(matches!(
            settle(
                &body,
                &strands,
                &bindings,
                &mut bad,
                &prepared,
                &expand_params
            ),
            Err(Error::NonFinite {
                what: "grooms",
                index: 7
            })
        ));
        assert_eq!(bad[..7], original[..7]);
    }
}
