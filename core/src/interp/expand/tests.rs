use super::*;
use crate::arena::{Arena, ArenaLayout};
use crate::guides::CvLayout;
use crate::guides::Guides;
use crate::interp::bind::StrandBinding;
use crate::interp::bind::{bind, BindParams};
use crate::interp::groom::GroomMaps;
use crate::interp::groom::StrandGroom;
use crate::interp::strand::EndPoints;
use crate::testmesh::{bumpy_plane, graded_plane, roots, straight_guides, TestMesh};
use crate::Strided;
use crate::{Mesh, Root};
use glam::Vec3;
use proptest::prelude::*;

const CVS: usize = 8;

struct Scene {
    m: TestMesh,
    guide_roots: Vec<Root>,
    guide_points: Vec<[f32; 3]>,
    strands: Vec<Root>,
}

impl Scene {
    fn plane(guides: u32, strands: u32) -> Scene {
        Scene::on(graded_plane(16, 1.0), guides, strands)
    }

    fn on(m: TestMesh, guides: u32, strands: u32) -> Scene {
        let guide_roots = roots(m.mesh(), guides, 5);
        let guide_points = straight_guides(&m.mesh(), &guide_roots, CVS, 0.1);
        let strands = roots(m.mesh(), strands, 9);
        Scene {
            m,
            guide_roots,
            guide_points,
            strands,
        }
    }

    fn guides(&self) -> Guides<'_> {
        Guides {
            roots: &self.guide_roots,
            points: Strided::from_slice(&self.guide_points),
            layout: CvLayout::Fixed(CVS),
        }
    }

    fn bind(&self, params: &BindParams) -> Vec<StrandBinding> {
        let mut buf =
            vec![
                0u8;
                crate::interp::bind::required_bytes(&self.m.mesh(), self.guide_roots.len())
                    .unwrap()
            ];
        let mut out = vec![StrandBinding::default(); self.strands.len()];
        bind(
            &self.m.mesh(),
            &self.guides(),
            &self.strands,
            params,
            &mut Arena::new(&mut buf),
            &mut out,
        )
        .unwrap();
        out
    }

    /// Runs `f` with this scene's guides prepared for `n` points.
    fn prepared<R>(&self, n: usize, f: impl FnOnce(&PosedFrame) -> R) -> R {
        let mesh = self.m.mesh();
        let mut layout = ArenaLayout::new();
        PosedFrame::layout(&mut layout, self.m.p.len(), self.guide_roots.len(), n);
        let mut buf = vec![0u8; layout.bytes()];
        let mut arena = Arena::new(&mut buf);
        let prepared = PosedFrame::with_guides(mesh, &self.guides(), n, &mut arena).unwrap();
        f(&prepared)
    }

    fn expand(
        &self,
        bindings: &[StrandBinding],
        grooms: &[StrandGroom],
        params: &ExpandParams,
        chunks: usize,
    ) -> Vec<[f32; 4]> {
        self.prepared(params.points_per_strand, |prepared| {
            let per = params.output_points();
            let n = self.strands.len();
            let mut out = vec![[0.0f32; 4]; n * per];
            for c in 0..chunks {
                let r = c * n / chunks..(c + 1) * n / chunks;
                let bytes: &mut [u8] =
                    bytemuck::cast_slice_mut(&mut out[r.start * per..r.end * per]);
                let all = Strands {
                    roots: &self.strands,
                    bindings,
                    grooms,
                };
                expand(prepared, &all.range(r), params, bytes, 16).unwrap();
            }
            out
        })
    }
}

fn plain_grooms(n: usize) -> Vec<StrandGroom> {
    vec![
        StrandGroom {
            length: 1.0,
            root_radius: 0.001,
            tip_radius: 0.0005,
            ..StrandGroom::default()
        };
        n
    ]
}

/// Strand `i`'s groom with every shaping value set (no clump): bend,
/// a kink whose phase turns with `i`, and a sideways lift.
fn styled(i: usize) -> StrandGroom {
    StrandGroom {
        length: 0.9,
        root_radius: 0.002,
        tip_radius: 0.0005,
        bend: 0.2,
        kink_amplitude: 0.05,
        kink_frequency: 3.0,
        kink_phase: [libm::cosf(i as f32), libm::sinf(i as f32)],
        lift: [0.1 * libm::sinf(i as f32), 0.0],
        ..StrandGroom::default()
    }
}

fn raw(n: usize) -> ExpandParams {
    ExpandParams {
        points_per_strand: n,
        end_points: EndPoints::Raw,
        orphan_length: 0.1,
        width_scale: 1.0,
    }
}

#[test]
fn identical_bits_for_any_chunking() {
    let s = Scene::plane(200, 3000);
    let b = s.bind(&BindParams::default());
    let mut grooms = plain_grooms(s.strands.len());
    let maps = GroomMaps {
        kink_amplitude: crate::ScalarMap::Constant(0.1),
        clump: crate::ScalarMap::Constant(0.5),
        bend: crate::ScalarMap::Constant(0.2),
        ..GroomMaps::default()
    };
    maps.evaluate(&s.m.mesh(), &s.strands, 3, &mut grooms)
        .unwrap();
    let one = s.expand(&b, &grooms, &raw(CVS), 1);
    for chunks in [2, 7] {
        let other = s.expand(&b, &grooms, &raw(CVS), chunks);
        assert!(bytemuck::cast_slice::<_, u8>(&one) == bytemuck::cast_slice::<_, u8>(&other));
    }
    assert!(one
        .iter()
        .all(|p| p.iter().all(|c| c.is_finite()) && p[3] >= 0.0));
}

#[test]
fn a_lift_too_small_to_square_turns_nothing() {
    let s = Scene::plane(100, 400);
    let b = s.bind(&BindParams::default());
    let plain = plain_grooms(s.strands.len());
    let tiny: Vec<StrandGroom> = plain
        .iter()
        .map(|g| StrandGroom {
            lift: [1e-25, -1e-30],
            ..*g
        })
        .collect();
    assert_eq!(
        s.expand(&b, &plain, &raw(CVS), 1),
        s.expand(&b, &tiny, &raw(CVS), 1)
    );
}

#[test]
fn roots_sit_on_the_surface_and_pinned_ends_repeat() {
    let s = Scene::plane(150, 500);
    let b = s.bind(&BindParams::default());
    let params = ExpandParams {
        end_points: EndPoints::Pinned,
        ..raw(CVS)
    };
    let out = s.expand(&b, &plain_grooms(s.strands.len()), &params, 1);
    let per = params.output_points();
    for (i, r) in s.strands.iter().enumerate() {
        let root = s.m.mesh().point(r.face as usize, r.u, r.v);
        let c = &out[i * per..(i + 1) * per];
        assert!(Vec3::new(c[1][0], c[1][1], c[1][2]).distance(root) < 1e-5);
        assert_eq!(c[0], c[1]);
        assert_eq!(c[per - 1], c[per - 2]);
        assert!(c[per - 1][2] > 0.0, "tip above the plane");
    }
}

#[test]
fn curves_follow_a_moving_body_without_swimming() {
    // the character walks and turns: the mesh and the posed guides move
    // rigidly; every curve must move with them, shape, kink, clump and
    // lift included (frames come from the triangles, not from world axes)
    let s = Scene::plane(60, 400);
    let b = s.bind(&BindParams::default());
    let grooms: Vec<StrandGroom> = (0..s.strands.len())
        .map(|i| StrandGroom {
            length: 0.8 + 0.001 * i as f32,
            clump: 0.3,
            ..styled(i)
        })
        .collect();
    let params = ExpandParams {
        end_points: EndPoints::Pinned,
        ..raw(CVS)
    };
    let rest = s.expand(&b, &grooms, &params, 1);
    let turn = glam::Quat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 2.3);
    let walk = Vec3::new(3.0, -1.0, 0.5);
    let moved = |p: &[f32; 3]| (turn * Vec3::from(*p) + walk).into();
    let posed = Scene {
        m: TestMesh {
            p: s.m.p.iter().map(moved).collect(),
            ..s.m.clone()
        },
        guide_roots: s.guide_roots.clone(),
        guide_points: s.guide_points.iter().map(moved).collect(),
        strands: s.strands.clone(),
    };
    let out = posed.expand(&b, &grooms, &params, 1);
    let mut worst = 0.0f32;
    for (a, o) in rest.iter().zip(&out) {
        let expect = turn * Vec3::new(a[0], a[1], a[2]) + walk;
        worst = worst.max(expect.distance(Vec3::new(o[0], o[1], o[2])));
        assert_eq!(a[3], o[3], "radius");
    }
    // float rounding at coordinates of a few units, not a swim
    assert!(worst < 2e-5, "curves moved {worst} away from the body");
}

#[test]
fn each_groom_value_shapes_the_curve_as_documented() {
    // on a curved skin, every groom value against the plain curve:
    // length scales the root-relative shape, bend moves point j by
    // bend L t^2 along the root tangent, kink by kink L t in the tangent
    // plane turning kink_frequency waves over the strand from the
    // strand's phase, clump pulls point j toward the clump guide by
    // clump t, widths run linearly from root to tip
    let s = Scene::on(bumpy_plane(16), 60, 300);
    let b = s.bind(&BindParams::default());
    let n = s.strands.len();
    let phase = |i: usize| 0.7 * i as f32;
    let plain = StrandGroom {
        length: 1.0,
        root_radius: 0.002,
        tip_radius: 0.0005,
        kink_frequency: 2.5,
        ..StrandGroom::default()
    };
    let with = |f: &dyn Fn(&mut StrandGroom)| {
        let grooms: Vec<StrandGroom> = (0..n)
            .map(|i| {
                let (sin, cos) = libm::sincosf(phase(i));
                let mut g = StrandGroom {
                    kink_phase: [cos, sin],
                    ..plain
                };
                f(&mut g);
                g
            })
            .collect();
        s.expand(&b, &grooms, &raw(CVS), 1)
    };
    let base = with(&|_| {});
    let long = with(&|g| g.length = 1.5);
    let bent = with(&|g| g.bend = 0.3);
    let kinked = with(&|g| g.kink_amplitude = 0.05);
    let clumped = with(&|g| g.clump = 0.6);
    let at = |c: &[[f32; 4]], i: usize, j: usize| Vec3::from_slice(&c[i * CVS + j][..3]);
    let delta = core::f32::consts::TAU * 2.5 / (CVS - 1) as f32;
    let close = |a: Vec3, e: Vec3, what: &str, i: usize, j: usize| {
        assert!(
            a.distance(e) < 2e-5,
            "{what}: strand {i} point {j}: {a} vs {e}"
        );
    };
    // an orphan (no guide passes the gates, here on a steep bump) has no
    // clump centre; the clump check needs nearly every strand bound
    let orphans = b
        .iter()
        .filter(|x| x.clump == crate::interp::bind::NO_GUIDE)
        .count();
    assert!(orphans * 100 <= n, "{orphans} orphans of {n}");
    s.prepared(CVS, |prepared| {
        for (i, r) in s.strands.iter().enumerate() {
            let f = prepared.root_frame(r.face as usize, r.u, r.v);
            let root = at(&base, i, 0);
            let len = at(&base, i, CVS - 1).distance(root);
            assert!(len > 0.05, "strand {i} has length {len}");
            for j in 0..CVS {
                let t = j as f32 / (CVS - 1) as f32;
                let p = at(&base, i, j);
                let radius = base[i * CVS + j][3];
                assert!(
                    (radius - (0.002 - 0.0015 * t)).abs() < 1e-7,
                    "radius {radius}"
                );
                close(at(&long, i, j) - root, (p - root) * 1.5, "length", i, j);
                close(at(&bent, i, j), p + f.t * (0.3 * len * t * t), "bend", i, j);
                let (sin, cos) = libm::sincosf(phase(i) + j as f32 * delta);
                let wave = (f.t * sin + f.b * cos) * (0.05 * len * t);
                close(at(&kinked, i, j), p + wave, "kink", i, j);
                if b[i].clump == crate::interp::bind::NO_GUIDE {
                    continue;
                }
                let c = prepared.world(b[i].clump as usize);
                let centre = Vec3::new(c[j], c[CVS + j], c[2 * CVS + j]);
                close(
                    at(&clumped, i, j),
                    p + (centre - p) * (0.6 * t),
                    "clump",
                    i,
                    j,
                );
            }
        }
    });
}

#[test]
fn curves_keep_their_shape_on_a_bending_body() {
    // the skin rolls around a cylinder (a bend, not a rigid motion) and
    // each posed guide rides on its root, keeping its shape in its root
    // frame: every strand must keep its shape in its own root frame,
    // bend, kink and lift included (clump is left out: it pulls toward
    // the guides' world points, which the bend moves apart)
    let mut flat = graded_plane(16, 1.0);
    flat.n = vec![[0.0, 0.0, 1.0]; flat.p.len()];
    let s = Scene::on(flat, 60, 400);
    let b = s.bind(&BindParams::default());
    let grooms: Vec<StrandGroom> = (0..s.strands.len())
        .map(|i| StrandGroom {
            lift: [0.1 * libm::sinf(i as f32), 0.05],
            ..styled(i)
        })
        .collect();
    let params = raw(CVS);
    let rest = s.expand(&b, &grooms, &params, 1);
    let radius = 0.4;
    let rolled = |p: &[f32; 3]| {
        let (sin, cos) = libm::sincosf(p[0] / radius);
        [(radius + p[2]) * sin, p[1], (radius + p[2]) * cos - radius]
    };
    let bent = TestMesh {
        p: s.m.p.iter().map(rolled).collect(),
        n: s.m
            .p
            .iter()
            .map(|p| {
                let (sin, cos) = libm::sincosf(p[0] / radius);
                [sin, 0.0, cos]
            })
            .collect(),
        ..s.m.clone()
    };
    let frames = |scene: &Scene, roots: &[Root]| {
        scene.prepared(CVS, |prepared| {
            roots
                .iter()
                .map(|r| prepared.root_frame(r.face as usize, r.u, r.v))
                .collect::<Vec<_>>()
        })
    };
    let mut posed = Scene {
        m: bent,
        guide_roots: s.guide_roots.clone(),
        guide_points: s.guide_points.clone(),
        strands: s.strands.clone(),
    };
    let (rest_guides, bent_guides) = (frames(&s, &s.guide_roots), frames(&posed, &s.guide_roots));
    for (g, points) in posed.guide_points.chunks_mut(CVS).enumerate() {
        for p in points {
            *p = bent_guides[g]
                .to_world(rest_guides[g].to_local(Vec3::from(*p)))
                .into();
        }
    }
    let out = posed.expand(&b, &grooms, &params, 1);
    let (rest_frames, bent_frames) = (frames(&s, &s.strands), frames(&posed, &s.strands));
    let mut worst = 0.0f32;
    for (i, (a, o)) in rest.chunks(CVS).zip(out.chunks(CVS)).enumerate() {
        for (p, q) in a.iter().zip(o) {
            let before = rest_frames[i].to_local(Vec3::from_slice(&p[..3]));
            let after = bent_frames[i].to_local(Vec3::from_slice(&q[..3]));
            worst = worst.max(before.distance(after));
            assert_eq!(p[3], q[3], "radius");
        }
    }
    assert!(
        worst < 2e-5,
        "strands changed shape by {worst} in their frames"
    );
    // and the skin did bend under them: the frames turned by up to 2.5 rad
    let turn = rest_frames
        .iter()
        .zip(&bent_frames)
        .map(|(a, b)| a.n.angle_between(b.n));
    assert!(turn.fold(0.0f32, f32::max) > 2.0);
}

/// Roots along the segment y = 0.37 + 0.1 x, x in [0.1, 0.9], on the plane.
fn path(mesh: &Mesh, steps: u32) -> Vec<Root> {
    (0..steps)
        .map(|i| {
            let x = 0.1 + 0.8 * i as f32 / steps as f32;
            let p = Vec3::new(x, 0.37 + 0.1 * x, 0.0);
            let bary = |f: usize| {
                let [a, b, c] = mesh.corners(f);
                let (e1, e2, d) = (b - a, c - a, p - a);
                let det = e1.x * e2.y - e1.y * e2.x;
                (
                    (d.x * e2.y - d.y * e2.x) / det,
                    (e1.x * d.y - e1.y * d.x) / det,
                )
            };
            let face = (0..mesh.triangle_count())
                .find(|&f| {
                    let (u, v) = bary(f);
                    u >= -1e-6 && v >= -1e-6 && u + v <= 1.0 + 1e-6
                })
                .unwrap();
            let (u, v) = bary(face);
            Root {
                face: face as u32,
                u,
                v,
                id: i,
                rank: i,
            }
        })
        .collect()
}

/// Largest change of root-relative shape between consecutive path roots.
fn largest_step_change(s: &Scene, steps: u32) -> f32 {
    let strands = path(&s.m.mesh(), steps);
    let scene = Scene {
        m: s.m.clone(),
        guide_roots: s.guide_roots.clone(),
        guide_points: s.guide_points.clone(),
        strands,
    };
    let fixed = BindParams {
        min_neighbours: 4,
        max_neighbours: 4,
        ..BindParams::default()
    };
    let b = scene.bind(&fixed);
    let out = scene.expand(&b, &plain_grooms(steps as usize), &raw(CVS), 1);
    let rel = |c: &[[f32; 4]], j: usize| {
        Vec3::new(c[j][0] - c[0][0], c[j][1] - c[0][1], c[j][2] - c[0][2])
    };
    let mut worst = 0.0f32;
    for i in 1..steps as usize {
        let (p, q) = (&out[(i - 1) * CVS..i * CVS], &out[i * CVS..(i + 1) * CVS]);
        for j in 0..CVS {
            worst = worst.max(rel(p, j).distance(rel(q, j)));
        }
    }
    worst
}

/// Refining the path 8x must shrink the largest change between
/// neighbouring strands about 8x, to within a constant times the step
/// (0.8 / steps): a jump (a seam) stays the same size at every
/// resolution.
fn assert_shapes_change_continuously(s: &Scene) {
    let coarse = largest_step_change(s, 1000);
    let fine = largest_step_change(s, 8000);
    assert!(
        fine < 0.3 * coarse,
        "largest change {coarse} at 1000 steps, {fine} at 8000 steps"
    );
    assert!(fine < 20.0 * 0.8 / 8000.0, "change {fine} per step");
}

#[test]
fn shapes_change_continuously_along_a_path() {
    // continuous weights: a hard k cutoff would leave a jump
    assert_shapes_change_continuously(&Scene::plane(120, 10));
}

#[test]
fn shapes_change_continuously_on_a_curved_skin() {
    // on a bumpy skin every triangle turns against its neighbours: the
    // root frame's tangent must not jump at triangle edges (a
    // per-triangle tangent turns leaning strands by a fixed angle there)
    assert_shapes_change_continuously(&Scene::on(bumpy_plane(16), 120, 10));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn strand_stays_in_its_guides_envelope(seed in 0u64..1000, kmin in 1u32..5, extra in 0u32..4) {
        let s = Scene::plane(80, 300);
        let params = BindParams { min_neighbours: kmin, max_neighbours: kmin + extra, seed, ..BindParams::default() };
        let b = s.bind(&params);
        let out = s.expand(&b, &plain_grooms(s.strands.len()), &raw(CVS), 1);
        s.prepared(CVS, |prepared| {
        for (i, r) in s.strands.iter().enumerate() {
            let frame = prepared.root_frame(r.face as usize, r.u, r.v);
            for j in 0..CVS {
                let p = out[i * CVS + j];
                let local = frame.to_local(Vec3::new(p[0], p[1], p[2]));
                let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
                for k in 0..b[i].count as usize {
                    let l = prepared.local_point(b[i].guides[k] as usize, j);
                    lo = lo.min(l);
                    hi = hi.max(l);
                }
                prop_assert!(local.cmpge(lo - 1e-5).all() && local.cmple(hi + 1e-5).all(),
                    "strand {} point {}: {:?} outside {:?}..{:?}", i, j, local, lo, hi);
            }
        }
        Ok(())
        })?;
    }
}

#[test]
fn variable_cv_counts_resample() {
    let s = Scene::plane(60, 200);
    let b = s.bind(&BindParams::default());
    // the same guides stored with offsets give the same curves
    let offsets: Vec<u32> = (0..=s.guide_roots.len() as u32)
        .map(|g| g * CVS as u32)
        .collect();
    let mesh = s.m.mesh();
    let guides = Guides {
        roots: &s.guide_roots,
        points: Strided::from_slice(&s.guide_points),
        layout: CvLayout::Offsets(&offsets),
    };
    let mut buf = vec![0u8; 1 << 20];
    let prepared = PosedFrame::with_guides(mesh, &guides, 15, &mut Arena::new(&mut buf)).unwrap();
    let mut out = vec![[0.0f32; 4]; s.strands.len() * 15];
    let grooms = plain_grooms(s.strands.len());
    let strands = Strands {
        roots: &s.strands,
        bindings: &b,
        grooms: &grooms,
    };
    expand(
        &prepared,
        &strands,
        &raw(15),
        bytemuck::cast_slice_mut(&mut out),
        16,
    )
    .unwrap();
    let straight = s.expand(&b, &plain_grooms(s.strands.len()), &raw(CVS), 1);
    for i in 0..s.strands.len() {
        let tip_a = out[i * 15 + 14];
        let tip_b = straight[i * CVS + CVS - 1];
        assert!((0..3).all(|c| (tip_a[c] - tip_b[c]).abs() < 1e-5));
    }
}

/// A ball field over the graded plane, in the strands' way.
struct Ball;

impl crate::collide::SignedDistance for Ball {
    fn distances(&self, points: &[[f32; 3]], out: &mut [f32]) {
        for (p, d) in points.iter().zip(out) {
            *d = Vec3::from(*p).distance(Vec3::new(0.5, 0.5, 0.06)) - 0.1;
        }
    }
}

#[test]
fn strands_pushed_out_of_a_host_field_in_batches_keep_their_bits() {
    let s = Scene::plane(200, 3000);
    let b = s.bind(&BindParams::default());
    let g = plain_grooms(s.strands.len());
    let strands = Strands {
        roots: &s.strands,
        bindings: &b,
        grooms: &g,
    };
    let bounds = StrandBounds::new(&strands).unwrap();
    let mask: Vec<u8> = (0..s.strands.len()).map(|i| (i % 3 != 0) as u8).collect();
    let trim: Vec<u16> = (0..s.strands.len())
        .map(|i| if i % 5 == 0 { 40_000 } else { WHOLE })
        .collect();
    let ball = Ball;
    let colliders = Colliders {
        field: Some(&ball),
        ..Colliders::default()
    };
    for end_points in [EndPoints::Raw, EndPoints::Pinned] {
        let params = ExpandParams {
            end_points,
            ..raw(CVS)
        };
        let per = params.output_points();
        let n = s.strands.len();
        s.prepared(CVS, |frame| {
            // through the batches, packed and strided
            let mut packed = vec![[0.0f32; 4]; n * per];
            let job = ExpandJob::new(frame, strands, &bounds, &params, n * per * 16, 16)
                .unwrap()
                .pushed(&mask, &colliders)
                .unwrap()
                .trimmed(&trim)
                .unwrap();
            job.run(0..n, bytemuck::cast_slice_mut(&mut packed));
            let mut strided = vec![[0.0f32; 5]; n * per];
            let wide = ExpandJob::new(frame, strands, &bounds, &params, n * per * 20, 20)
                .unwrap()
                .pushed(&mask, &colliders)
                .unwrap()
                .trimmed(&trim)
                .unwrap();
            wide.run(0..n, bytemuck::cast_slice_mut(&mut strided));
            // strand by strand, each asking the field for itself
            let mut filler = Filler {
                strands: &strands,
                trim: Some(&trim),
                push: Some(Push {
                    mask: &mask,
                    colliders: &colliders,
                }),
                guides: frame,
                params: &params,
                lanes: Lanes::new(params.points_per_strand),
                basis: None,
                frames: [Frame::default(); FRAME_LANES],
            };
            let mut one = vec![[0.0f32; 4]; n * per];
            for (k, curve) in one.chunks_exact_mut(per).enumerate() {
                filler.fill::<0>(k, curve);
            }
            assert!(packed == one, "{end_points:?}: packed");
            let narrow: Vec<[f32; 4]> = strided.iter().map(|p| [p[0], p[1], p[2], p[3]]).collect();
            assert!(narrow == one, "{end_points:?}: strided");
            let moved = (0..n)
                .filter(|&k| mask[k] != 0 && trim[k] == WHOLE)
                .filter(|&k| {
                    let base = filler_free_expand(frame, &strands, &params, k, per);
                    base != one[k * per..(k + 1) * per]
                })
                .count();
            assert!(moved > 10, "{moved} strands pushed");
        });
    }
}

/// Strand `k` expanded with no trim and no push.
fn filler_free_expand(
    frame: &PosedFrame,
    strands: &Strands,
    params: &ExpandParams,
    k: usize,
    per: usize,
) -> Vec<[f32; 4]> {
    let mut out = vec![[0.0f32; 4]; per];
    let one = strands.range(k..k + 1);
    expand(frame, &one, params, bytemuck::cast_slice_mut(&mut out), 16).unwrap();
    out
}
