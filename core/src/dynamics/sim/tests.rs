use super::*;
use crate::cache::container::header_bytes;
use crate::collide::{Capsule, Plane, SignedDistance, Sphere, FIELD_BATCH};
use crate::dynamics::links::LinkParams;
use crate::guides::CvLayout;
use crate::surface::body::Body;
use crate::testmesh::{roots, sphere, straight_guides, TestMesh};
use crate::Strided;
use glam::Quat;

const JOINTS: usize = 8;

/// A unit sphere with straight guides of length 0.3 along the normals.
struct Scene {
    rest: TestMesh,
    guide_roots: Vec<Root>,
    guide_points: Vec<[f32; 3]>,
}

impl Scene {
    fn new(guides: u32) -> Scene {
        let rest = sphere(16, 32);
        let guide_roots = roots(rest.mesh(), guides, 3);
        let guide_points = straight_guides(&rest.mesh(), &guide_roots, JOINTS, 0.3);
        Scene {
            rest,
            guide_roots,
            guide_points,
        }
    }

    fn guides(&self) -> Guides<'_> {
        Guides {
            roots: &self.guide_roots,
            points: Strided::from_slice(&self.guide_points),
            layout: CvLayout::Fixed(JOINTS),
        }
    }

    fn sim<'a>(&'a self, params: &SimParams, buf: &'a mut Vec<u8>) -> Sim<'a> {
        let mut layout = ArenaLayout::new();
        Sim::layout(
            &mut layout,
            self.rest.p.len(),
            self.guide_roots.len(),
            params,
        );
        *buf = vec![0u8; layout.bytes()];
        Sim::new(
            self.rest.mesh(),
            &self.guides(),
            params,
            &mut Arena::new(buf),
        )
        .unwrap()
    }
}

/// The rest sphere moved rigidly.
fn moved(rest: &TestMesh, turn: Quat, shift: Vec3) -> TestMesh {
    TestMesh {
        p: rest
            .p
            .iter()
            .map(|&p| (turn * Vec3::from(p) + shift).into())
            .collect(),
        n: rest
            .n
            .iter()
            .map(|&n| (turn * Vec3::from(n)).into())
            .collect(),
        ..rest.clone()
    }
}

/// Steps `sim` on `mesh` with `colliders` and `dt`.
fn step(sim: &mut Sim, mesh: &TestMesh, colliders: &Colliders, dt: f32) {
    let mut layout = ArenaLayout::new();
    PosedFrame::layout(&mut layout, mesh.p.len(), 1, 2);
    let mut buf = vec![0u8; layout.bytes()];
    let frame = PosedFrame::new(mesh.mesh(), 1, 2, &mut Arena::new(&mut buf)).unwrap();
    sim.step(&frame, colliders, dt).unwrap();
}

fn posed(sim: &Sim) -> Vec<Vec3> {
    (0..sim.len())
        .flat_map(|g| (0..sim.points()).map(move |k| (g, k)))
        .map(|(g, k)| sim.posed(g, k))
        .collect()
}

/// Every point finite, every segment at its rest length (within 1e-5
/// of the guide's length), every tip within reach of its root.
fn assert_sound(sim: &Sim, what: &str) {
    let j = JOINTS;
    for g in 0..sim.len() {
        let reach = sim.constants[g].reach;
        let p: Vec<Vec3> = (0..j).map(|k| sim.posed_local(g, k)).collect();
        assert!(
            p.iter().all(|q| q.is_finite()),
            "{what}: guide {g} not finite"
        );
        for k in 0..j - 1 {
            let (len, rest) = (p[k].distance(p[k + 1]), sim.lengths[g * (j - 1) + k]);
            assert!(
                (len - rest).abs() <= 1e-5 * reach.max(1.0),
                "{what}: guide {g} segment {k}: {len} vs {rest}"
            );
        }
        assert!(
            p[j - 1].distance(p[0]) <= reach * (1.0 + 1e-5),
            "{what}: guide {g} tip beyond reach"
        );
    }
}

fn neutral_distance(sim: &Sim, scene_mesh: &TestMesh) -> f32 {
    // distance of every tip from its neutral tip on `scene_mesh`
    let mut layout = ArenaLayout::new();
    PosedFrame::layout(&mut layout, scene_mesh.p.len(), 1, 2);
    let mut buf = vec![0u8; layout.bytes()];
    let frame = PosedFrame::new(scene_mesh.mesh(), 1, 2, &mut Arena::new(&mut buf)).unwrap();
    let j = JOINTS;
    (0..sim.len())
        .map(|g| {
            let r = &sim.roots[g];
            let f = frame.root_frame(r.face as usize, r.u, r.v);
            let l = &sim.rest[(g * j + j - 1) * 3..(g * j + j) * 3];
            f.to_world(Vec3::new(l[0], l[1], l[2]))
                .distance(sim.posed(g, j - 1))
        })
        .fold(0.0, f32::max)
}

fn params() -> SimParams<'static> {
    SimParams {
        joints: JOINTS,
        points: JOINTS,
        ..SimParams::default()
    }
}

#[test]
fn a_still_character_stays_bitwise_still() {
    let s = Scene::new(60);
    let mut buf = vec![];
    let mut sim = s.sim(&params(), &mut buf);
    step(&mut sim, &s.rest, &Colliders::default(), 1.0 / 24.0);
    let first = posed(&sim);
    for _ in 0..10 {
        step(&mut sim, &s.rest, &Colliders::default(), 1.0 / 24.0);
        assert!(posed(&sim) == first);
    }
    assert_sound(&sim, "still");
    assert!(neutral_distance(&sim, &s.rest) < 1e-5);
}

#[test]
fn violent_motion_stays_finite_bounded_and_settles() {
    let s = Scene::new(80);
    for spring in [
        TipSpring::default(),
        TipSpring {
            frequency: 0.0,
            amplitude: 1.0,
            decay: 0.0,
        },
        TipSpring {
            frequency: 1000.0,
            amplitude: 1.0,
            decay: 0.0,
        },
        TipSpring {
            frequency: 2.0,
            amplitude: 1.0,
            decay: 10000.0,
        },
    ] {
        let p = SimParams {
            frequency: ScalarMap::Constant(spring.frequency),
            amplitude: ScalarMap::Constant(spring.amplitude),
            decay: ScalarMap::Constant(spring.decay),
            ..params()
        };
        let mut buf = vec![];
        let mut sim = s.sim(&p, &mut buf);
        let mut t = 0.0f32;
        let mut last = s.rest.clone();
        for frame in 0..120 {
            // dt jumps between 1/240 and 1/12; a walk, a spin of half a
            // turn in one frame, a teleport of 100 m, a dead stop
            let dt = if frame % 3 == 0 {
                1.0 / 12.0
            } else {
                1.0 / 240.0
            };
            t += dt;
            let (turn, shift) = match frame {
                0..=29 => (Quat::IDENTITY, Vec3::new(2.0 * t, 0.0, 0.0)),
                30..=39 => (
                    Quat::from_rotation_y(core::f32::consts::PI),
                    Vec3::new(2.0 * t, 0.0, 0.0),
                ),
                40..=59 => (
                    Quat::from_rotation_y(core::f32::consts::PI),
                    Vec3::new(100.0, 0.0, 0.0),
                ),
                _ => (Quat::from_rotation_z(1.0), Vec3::new(100.0, 5.0, 0.0)),
            };
            last = moved(&s.rest, turn, shift);
            step(&mut sim, &last, &Colliders::default(), dt);
            assert_sound(&sim, motion_name(frame));
        }
        // standing still from frame 60 on, long enough to settle
        for _ in 0..240 {
            step(&mut sim, &last, &Colliders::default(), 1.0 / 24.0);
        }
        assert_sound(&sim, "after the stop");
        let off = neutral_distance(&sim, &last);
        if spring.frequency > 0.0 && spring.decay > 0.0 {
            assert!(off < 1e-3, "{spring:?} still {off} from neutral");
        } else {
            assert!(off <= 2.0 * 0.3 + 1e-4, "{spring:?}: {off}");
        }
    }
}

fn motion_name(frame: usize) -> &'static str {
    match frame {
        0..=29 => "walk",
        30..=39 => "spin",
        40..=59 => "teleport",
        _ => "stop",
    }
}

#[test]
fn a_teleport_carries_the_tip_without_a_whip() {
    let s = Scene::new(40);
    let mut buf = vec![];
    let mut sim = s.sim(&params(), &mut buf);
    step(&mut sim, &s.rest, &Colliders::default(), 1.0 / 24.0);
    let far = moved(
        &s.rest,
        Quat::from_rotation_x(0.7),
        Vec3::new(0.0, 100.0, 0.0),
    );
    step(&mut sim, &far, &Colliders::default(), 1.0 / 24.0);
    // the guides were at rest: they arrive at rest, in the new place
    assert!(neutral_distance(&sim, &far) < 1e-4);
}

/// A swinging shot that teleports (turned and moved far) ends as the
/// same shot played whole in the far place: the swing rides along
/// (neither dropped nor whipped). The shot moves at a constant speed,
/// which the teleported step carries on.
#[test]
fn a_teleport_carries_the_swing_as_the_shot_played_in_the_far_place() {
    let s = Scene::new(40);
    let pose = |k: usize| {
        moved(
            &s.rest,
            Quat::IDENTITY,
            Vec3::new(0.06, 0.0, 0.0) * k as f32,
        )
    };
    let far = |m: &TestMesh| moved(m, Quat::from_rotation_x(0.7), Vec3::new(0.0, 100.0, 0.0));
    let (dt, none) = (1.0 / 24.0, Colliders::default());
    let (mut buf_a, mut buf_b) = (vec![], vec![]);
    let mut here = s.sim(&params(), &mut buf_a);
    let mut there = s.sim(&params(), &mut buf_b);
    for k in 0..4 {
        step(&mut here, &pose(k), &none, dt);
        step(&mut there, &far(&pose(k)), &none, dt);
    }
    let swing = neutral_distance(&here, &pose(3));
    assert!(swing > 0.01, "the tips must swing: {swing}");
    step(&mut here, &far(&pose(4)), &none, dt);
    step(&mut there, &far(&pose(4)), &none, dt);
    let apart = (0..here.len())
        .flat_map(|g| (0..JOINTS).map(move |k| (g, k)))
        .map(|(g, k)| here.posed_local(g, k).distance(there.posed_local(g, k)))
        .fold(0.0f32, f32::max);
    assert!(apart < 1e-3 * swing, "{apart} apart, swing {swing}");
}

#[test]
fn bits_do_not_depend_on_ranges_or_on_a_save_and_restore() {
    let s = Scene::new(90);
    let p = SimParams {
        links: LinkParams {
            radius: 0.5,
            ..LinkParams::default()
        },
        ..params()
    };
    let poses: Vec<TestMesh> = (0..12)
        .map(|k| {
            moved(
                &s.rest,
                Quat::from_rotation_y(0.2 * k as f32),
                Vec3::new(0.1 * (k * k) as f32, 0.0, 0.0),
            )
        })
        .collect();
    let dt = 1.0 / 24.0;
    let mut buf = vec![];
    let mut whole = s.sim(&p, &mut buf);
    let mut saved = vec![];
    let mut reference = vec![];
    for (k, m) in poses.iter().enumerate() {
        step(&mut whole, m, &Colliders::default(), dt);
        reference.push(posed(&whole));
        if k == 5 {
            saved = vec![0u8; whole.state_bytes()];
            whole.save(&mut saved).unwrap();
        }
    }
    // the same steps run in three uneven ranges per phase
    let mut buf2 = vec![];
    let mut split = s.sim(&p, &mut buf2);
    for (k, m) in poses.iter().enumerate() {
        let mut layout = ArenaLayout::new();
        PosedFrame::layout(&mut layout, m.p.len(), 1, 2);
        let mut fbuf = vec![0u8; layout.bytes()];
        let frame = PosedFrame::new(m.mesh(), 1, 2, &mut Arena::new(&mut fbuf)).unwrap();
        let colliders = Colliders::default();
        let Step {
            context: ctx,
            blocks,
            snapshot,
        } = split.begin(&frame, &colliders, None, dt).unwrap();
        let per = ctx.block_floats();
        let cuts = [0, 7, 50, 90];
        for w in cuts.windows(2) {
            ctx.advance(w[0], &mut blocks[w[0] * per..w[1] * per]);
        }
        for _ in 0..ctx.link_iterations() {
            ctx.snapshot(blocks, snapshot);
            for w in cuts.windows(2) {
                ctx.relax(w[0], &mut blocks[w[0] * per..w[1] * per], snapshot);
            }
        }
        for w in cuts.windows(2) {
            ctx.finish(w[0], &mut blocks[w[0] * per..w[1] * per]);
        }
        assert!(posed(&split) == reference[k], "step {k}");
    }
    // a fresh simulation restored from step 5 gives steps 6.. bit for bit
    let mut buf3 = vec![];
    let mut resumed = s.sim(&p, &mut buf3);
    resumed.restore(&saved).unwrap();
    for (k, m) in poses.iter().enumerate().skip(6) {
        step(&mut resumed, m, &Colliders::default(), dt);
        assert!(posed(&resumed) == reference[k], "resumed step {k}");
    }
}

/// One triangle, its right angle at `corner`, its legs `size` along x
/// and y.
fn triangle(corner: [f32; 3], size: f32) -> TestMesh {
    let [x, y, z] = corner;
    TestMesh {
        p: vec![corner, [x + size, y, z], [x, y + size, z]],
        t: vec![[0, 1, 2]],
        uv: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        n: vec![],
    }
}

/// The simulation, in `buf`, of one guide of three joints (`points`)
/// rooted at `uv` on `rest`'s first triangle, with `p` (its joint and
/// point counts set to 3).
fn one_guide<'b>(
    rest: &TestMesh,
    [u, v]: [f32; 2],
    points: &[[f32; 3]; 3],
    p: SimParams,
    buf: &'b mut Vec<u8>,
) -> Sim<'b> {
    let roots = [Root {
        face: 0,
        u,
        v,
        id: 0,
        rank: 0,
    }];
    let guides = Guides {
        roots: &roots,
        points: Strided::from_slice(points),
        layout: CvLayout::Fixed(3),
    };
    let p = SimParams {
        joints: 3,
        points: 3,
        ..p
    };
    let mut layout = ArenaLayout::new();
    Sim::layout(&mut layout, 3, 1, &p);
    buf.resize(layout.bytes(), 0);
    Sim::new(rest.mesh(), &guides, &p, &mut Arena::new(buf)).unwrap()
}

/// Poses `frame` from `sim` on the calling thread, checked.
fn pose_from(sim: &Sim, frame: &mut PosedFrame) -> Result<(), Error> {
    let posing = sim.posing(frame)?;
    posing.filler.fill(0, posing.data);
    posing.finish_checked(sim.posed_faults(0..sim.len()))
}

/// Whether posing a frame from `sim` on `mesh` succeeds or fails as
/// validating the world points it reads (with its roots) does.
fn posing_agrees_with_its_points(sim: &Sim, mesh: &crate::testmesh::TestMesh) {
    let points: Vec<[f32; 3]> = (0..sim.len())
        .flat_map(|g| (0..sim.points()).map(move |k| (g, k)))
        .map(|(g, k)| sim.posed(g, k).to_array())
        .collect();
    let guides = Guides {
        roots: sim.roots(),
        points: Strided::from_slice(&points),
        layout: CvLayout::Fixed(sim.points()),
    };
    let want = guides.validate(&mesh.mesh());
    let mut layout = ArenaLayout::new();
    PosedFrame::layout(&mut layout, mesh.p.len(), sim.len(), sim.points());
    let mut buf = vec![0u8; layout.bytes()];
    let mut frame = PosedFrame::new(
        mesh.mesh(),
        sim.len(),
        sim.points(),
        &mut Arena::new(&mut buf),
    )
    .unwrap();
    let got = pose_from(sim, &mut frame);
    assert_eq!(format!("{got:?}"), format!("{want:?}"));
}

/// A guide as long as the coordinate limit allows, on a triangle that
/// jumps across it: the IK's products overflow, and the guide takes
/// its groomed shape; the state the step saves restores.
#[test]
fn guides_at_the_coordinate_limit_stay_finite_and_restore() {
    let triangle = |off: f32| triangle([off; 3], 1000.0);
    let points = [[0.1f32, 0.1, 0.0], [1e9, 1e9, 1e9], [-1e9, -1e9, -1e9]];
    let p = SimParams {
        frequency: ScalarMap::Constant(0.0),
        decay: ScalarMap::Constant(0.0),
        ..SimParams::default()
    };
    let mut buf = vec![];
    let mut sim = one_guide(&triangle(0.0), [0.1, 0.1], &points, p, &mut buf);
    for off in [-9e8f32, 9e8, 0.0] {
        step(&mut sim, &triangle(off), &Colliders::default(), 1.0 / 24.0);
        posing_agrees_with_its_points(&sim, &triangle(off));
        for k in 0..3 {
            assert!(
                sim.posed(0, k).is_finite(),
                "point {k}: {}",
                sim.posed(0, k)
            );
        }
    }
    let mut state = vec![0u8; sim.state_bytes()];
    sim.save(&mut state).unwrap();
    sim.restore(&state).unwrap();
}

#[test]
fn a_collapsed_root_triangle_collapses_its_guide_and_it_comes_back() {
    // away from the world's origin, so that "at the root" is not "at 0"
    let o = [3.0f32, -2.0, 5.0];
    let rest = triangle(o, 1.0);
    // leaning along both tangents: a frame left with a tangent would
    // lay it along a line
    let lean = |k: f32| [o[0] + 0.05 * k, o[1] + 0.03 * k, o[2] + 0.08 * k];
    let points = [lean(0.0), lean(1.0), lean(2.0)];
    let mut buf = vec![];
    let mut sim = one_guide(&rest, [0.0, 0.0], &points, SimParams::default(), &mut buf);
    step(&mut sim, &rest, &Colliders::default(), 1.0 / 24.0);
    // the triangle scaled to nothing (a rig hiding a part): no frame
    step(
        &mut sim,
        &triangle(o, 0.0),
        &Colliders::default(),
        1.0 / 24.0,
    );
    for k in 0..3 {
        let q = sim.posed(0, k);
        let off = q.distance(Vec3::from(o));
        assert!(
            q.is_finite() && off < 1e-6,
            "point {k}: {q}, {off} from the root"
        );
    }
    // a frame posed from it refuses the collapsed guide, as posing it
    // from the points it reads does
    let pose_on = |mesh: &crate::testmesh::TestMesh, sim: &Sim| {
        let mut layout = ArenaLayout::new();
        PosedFrame::layout(&mut layout, mesh.p.len(), 1, sim.points());
        let mut buf = vec![0u8; layout.bytes()];
        let mut frame =
            PosedFrame::new(mesh.mesh(), 1, sim.points(), &mut Arena::new(&mut buf)).unwrap();
        pose_from(sim, &mut frame)
    };
    assert!(matches!(
        pose_on(&triangle(o, 0.0), &sim),
        Err(Error::InvalidArgument("a guide has zero length"))
    ));
    posing_agrees_with_its_points(&sim, &triangle(o, 0.0));
    // a posing finished with faults of no guide is refused
    let mut layout = ArenaLayout::new();
    PosedFrame::layout(&mut layout, rest.p.len(), 1, sim.points());
    let mut frame_buf = vec![0u8; layout.bytes()];
    let mut frame = PosedFrame::new(
        rest.mesh(),
        1,
        sim.points(),
        &mut Arena::new(&mut frame_buf),
    )
    .unwrap();
    let posing = sim.posing(&mut frame).unwrap();
    assert!(matches!(
        posing.finish_checked(PosedFaults::default()),
        Err(Error::InvalidArgument(_))
    ));
    assert!(!frame.is_posed());
    // back: the guide stands again, its segments their rest length
    for _ in 0..48 {
        step(&mut sim, &rest, &Colliders::default(), 1.0 / 24.0);
    }
    let rest_segment = Vec3::from(lean(1.0)).distance(Vec3::from(lean(0.0)));
    for k in 1..3 {
        let segment = sim.posed(0, k).distance(sim.posed(0, k - 1));
        assert!(
            (segment - rest_segment).abs() < 1e-5,
            "segment {k}: {segment}"
        );
    }
    let tip = sim.posed(0, 2);
    assert!(tip.distance(Vec3::from(lean(2.0))) < 0.01, "tip {tip}");
    assert!(pose_on(&rest, &sim).is_ok());
}

#[test]
fn a_damaged_state_is_refused_and_changes_nothing() {
    let s = Scene::new(20);
    let mut buf = vec![];
    let mut sim = s.sim(&params(), &mut buf);
    let moved_mesh = moved(&s.rest, Quat::IDENTITY, Vec3::new(0.2, 0.0, 0.0));
    step(&mut sim, &moved_mesh, &Colliders::default(), 0.05);
    let mut good = vec![0u8; sim.state_bytes()];
    sim.save(&mut good).unwrap();
    let before = posed(&sim);
    let mut flipped = good.clone();
    flipped[40] ^= 1;
    assert!(matches!(sim.restore(&flipped), Err(Error::Corrupt { .. })));
    assert!(matches!(
        sim.restore(&good[..good.len() - 1]),
        Err(Error::Corrupt { .. })
    ));
    assert!(matches!(
        sim.restore(&good[..10]),
        Err(Error::Corrupt { .. })
    ));
    let mut magic = good.clone();
    magic[0] = b'X';
    assert!(matches!(
        sim.restore(&magic),
        Err(Error::VersionMismatch { found: 0, .. })
    ));
    let mut version = good.clone();
    version[8] = 9;
    assert!(matches!(
        sim.restore(&version),
        Err(Error::VersionMismatch { found: 9, .. })
    ));
    let mut short = vec![0u8; 10];
    assert!(matches!(
        sim.save(&mut short),
        Err(Error::OutputTooSmall { .. })
    ));
    // a sound state with a value no step makes (checksum made anew)
    let mut huge = good.clone();
    let at = header_bytes(8);
    huge[at..at + 4].copy_from_slice(&1e30f32.to_le_bytes());
    reseal(&mut huge);
    assert!(matches!(sim.restore(&huge), Err(Error::Corrupt { .. })));
    // the stepped field neither 0 nor 1, the checksum made anew
    let mut stepped = good.clone();
    stepped[48..56].copy_from_slice(&2u64.to_le_bytes());
    reseal(&mut stepped);
    assert!(matches!(
        sim.restore(&stepped),
        Err(Error::Corrupt { what }) if what.contains("stepped")
    ));
    // an origin that is not finite, the checksum made anew
    let mut origin = good.clone();
    origin[56..64].copy_from_slice(&f64::NAN.to_bits().to_le_bytes());
    reseal(&mut origin);
    assert!(matches!(
        sim.restore(&origin),
        Err(Error::Corrupt { what }) if what.contains("origin")
    ));
    // 0.11's unframed state: "PLGS", then its version 1
    let mut old = good.clone();
    old[4..8].copy_from_slice(&1u32.to_le_bytes());
    assert!(matches!(
        sim.restore(&old),
        Err(Error::VersionMismatch { .. })
    ));
    // a sound state of other guides
    let other_scene = Scene::new(21);
    let mut other_buf = vec![];
    let other_sim = other_scene.sim(&params(), &mut other_buf);
    let mut theirs = vec![0u8; other_sim.state_bytes()];
    other_sim.save(&mut theirs).unwrap();
    assert!(matches!(
        sim.restore(&theirs),
        Err(Error::InvalidArgument(_))
    ));
    // too short a step to divide by, and steps out of range
    let mut layout = ArenaLayout::new();
    PosedFrame::layout(&mut layout, moved_mesh.p.len(), 1, 2);
    let mut fbuf = vec![0u8; layout.bytes()];
    let frame = PosedFrame::new(moved_mesh.mesh(), 1, 2, &mut Arena::new(&mut fbuf)).unwrap();
    for dt in [1e-30, 0.0, -1.0, 2.0] {
        let refused = sim.step(&frame, &Colliders::default(), dt);
        assert!(matches!(refused, Err(Error::InvalidArgument(_))), "dt {dt}");
    }
    let refused = sim.step(&frame, &Colliders::default(), f32::NAN);
    assert!(matches!(refused, Err(Error::NonFinite { what: "dt", .. })));
    // nothing changed: the next step is the one the good state gives
    step(&mut sim, &moved_mesh, &Colliders::default(), 0.05);
    let mut buf2 = vec![];
    let mut other = s.sim(&params(), &mut buf2);
    other.restore(&good).unwrap();
    step(&mut other, &moved_mesh, &Colliders::default(), 0.05);
    assert!(posed(&sim) == posed(&other));
    assert!(before.iter().all(|p| p.is_finite()));
}

struct Ball;

impl SignedDistance for Ball {
    fn distances(&self, points: &[[f32; 3]], out: &mut [f32]) {
        for (p, d) in points.iter().zip(out) {
            *d = Vec3::from(*p).distance(Vec3::new(0.0, 1.38, 0.0)) - 0.3;
        }
    }
}

#[test]
fn no_posed_point_ends_inside_a_collider() {
    let s = Scene::new(400);
    let mut buf = vec![];
    let mut sim = s.sim(&params(), &mut buf);
    // every collider clear of the skin (no root inside) but in the
    // guides' way (they are 0.3 long)
    let spheres = [Sphere {
        centre: [1.35, 0.0, 0.0],
        radius: 0.3,
    }];
    let capsules = [Capsule {
        a: [0.0, 0.0, 1.25],
        b: [0.0, 0.5, 1.25],
        radius: 0.12,
    }];
    let planes = [Plane {
        normal: [0.0, 1.0, 0.0],
        offset: -1.1,
    }];
    let ball = Ball;
    // the body: a second, small shell (an ear, a horn) beside the skin
    let ear = TestMesh {
        p: s.rest
            .p
            .iter()
            .map(|&p| (Vec3::from(p) * 0.3 + Vec3::new(-0.955, 0.0, 0.955)).into())
            .collect(),
        ..s.rest.clone()
    };
    let ear_mesh = ear.mesh();
    let mut body_buf = vec![0u8; Body::required_bytes(&ear_mesh).unwrap()];
    let body = Body::new(&ear_mesh, &mut Arena::new(&mut body_buf)).unwrap();
    // each collider by itself: the sphere, the capsule, the plane, the
    // body and the field
    let in_one = |c: usize, p: Vec3| match c {
        0 => p.distance(Vec3::from(spheres[0].centre)) < 0.3,
        1 => Vec3::new(p.x, p.y - p.y.clamp(0.0, 0.5), p.z - 1.25).length() < 0.12,
        2 => p.y < -1.1,
        3 => body.contains(p),
        _ => p.distance(Vec3::new(0.0, 1.38, 0.0)) < 0.3,
    };
    let inside = |p: Vec3| (0..5).any(|c| in_one(c, p));
    let colliders = Colliders {
        spheres: &spheres,
        capsules: &capsules,
        planes: &planes,
        body: Some(&body),
        field: Some(&ball),
    };
    step(&mut sim, &s.rest, &Colliders::default(), 1.0 / 24.0);
    let crossing = |sim: &Sim| {
        (0..sim.len())
            .filter(|&g| (1..JOINTS).any(|k| inside(sim.posed(g, k))))
            .count()
    };
    // every collider must hold guides (here 6, 4, 26, 5 and 4), or a
    // push-out that ignored one would pass
    let held: Vec<usize> = (0..5)
        .map(|c| {
            (0..sim.len())
                .filter(|&g| (1..JOINTS).any(|k| in_one(c, sim.posed(g, k))))
                .count()
        })
        .collect();
    assert!(
        held.iter().all(|&n| n >= 3),
        "the scene must put guides in every collider: {held:?}"
    );
    step(&mut sim, &s.rest, &colliders, 1.0 / 24.0);
    assert_sound(&sim, "collided");
    assert_eq!(crossing(&sim), 0);

    // the same steps with their guides shaped while a body is "built"
    // (begun without it), each taken back once (the first, before
    // the simulation ever stepped, too), then run again and collided
    // with every collider: the bits of the steps above
    let mut buf2 = vec![];
    let mut apart = s.sim(&params(), &mut buf2);
    let saved = |sim: &Sim| {
        let mut bytes = vec![0u8; sim.state_bytes()];
        sim.save(&mut bytes).unwrap();
        (bytes, posed(sim), sim.has_stepped(), sim.target(3))
    };
    let mut layout = ArenaLayout::new();
    PosedFrame::layout(&mut layout, s.rest.p.len(), 1, 2);
    let mut fbuf = vec![0u8; layout.bytes()];
    let frame = PosedFrame::new(s.rest.mesh(), 1, 2, &mut Arena::new(&mut fbuf)).unwrap();
    let shapes = Colliders {
        body: None,
        ..colliders
    };
    let m = apart.points();
    let mut kept = vec![0.0f32; apart.len() * KEPT_FLOATS];
    let mut shaped = vec![0.0f32; apart.len() * 3 * m];
    let mut before = saved(&apart);
    for (undone, with) in [
        (true, &Colliders::default()),
        (false, &Colliders::default()),
        (true, &shapes),
        (false, &shapes),
    ] {
        if undone {
            before = saved(&apart);
        }
        let mark = apart.mark();
        let Step {
            context: ctx,
            blocks,
            snapshot,
        } = apart.begin(&frame, with, None, 1.0 / 24.0).unwrap();
        let per = ctx.block_floats();
        ctx.keep(blocks, &mut kept);
        ctx.advance(0, blocks);
        for _ in 0..ctx.link_iterations() {
            ctx.snapshot(blocks, snapshot);
            ctx.relax(0, blocks, snapshot);
        }
        // in two uneven ranges, as threads would
        let cut = 7 * per;
        ctx.shape(0, &mut blocks[..cut], &mut shaped[..7 * 3 * m]);
        ctx.shape(7, &mut blocks[cut..], &mut shaped[7 * 3 * m..]);
        if undone {
            apart.undo(&kept, mark);
            assert!(saved(&apart) == before, "the step taken back");
            continue;
        }
        let body = (!with.spheres.is_empty()).then_some(&body);
        ctx.collide(0, &mut blocks[..cut], &shaped[..7 * 3 * m], body);
        ctx.collide(7, &mut blocks[cut..], &shaped[7 * 3 * m..], body);
    }
    assert!(saved(&apart) == saved(&sim), "shaped apart, then collided");
}

#[test]
fn regions_of_another_simulator_take_its_curves_and_keep_the_lengths() {
    let s = Scene::new(60);
    // the host's curves: every guide laid over along a fixed direction
    let host: Vec<[f32; 3]> = s
        .guide_points
        .chunks(JOINTS)
        .flat_map(|g| {
            let root = Vec3::from(g[0]);
            (0..JOINTS).map(move |k| (root + Vec3::new(0.03, 0.03, 0.0) * k as f32).to_array())
        })
        .collect();
    let run = |share: f32, with_host: bool| {
        let p = SimParams {
            external: ScalarMap::Constant(share),
            ..params()
        };
        let mut buf = vec![];
        let mut sim = s.sim(&p, &mut buf);
        let mut layout = ArenaLayout::new();
        PosedFrame::layout(&mut layout, s.rest.p.len(), 1, 2);
        let mut fbuf = vec![0u8; layout.bytes()];
        let frame = PosedFrame::new(s.rest.mesh(), 1, 2, &mut Arena::new(&mut fbuf)).unwrap();
        let colliders = Colliders::default();
        let external = with_host.then(|| Strided::from_slice(&host));
        let Step {
            context,
            blocks,
            snapshot,
        } = sim.begin(&frame, &colliders, external, 0.04).unwrap();
        context.advance(0, blocks);
        let _ = snapshot;
        context.finish(0, blocks);
        assert_sound(&sim, "external");
        posed(&sim)
    };
    let own = run(0.0, false);
    assert!(run(0.0, true) == own, "a zero share changes nothing");
    let taken = run(1.0, true);
    for (g, points) in taken.chunks(JOINTS).enumerate() {
        for k in 1..JOINTS {
            let d = (points[k] - points[k - 1]).normalize();
            let want = (Vec3::from(host[g * JOINTS + k]) - Vec3::from(host[g * JOINTS + k - 1]))
                .normalize();
            assert!(
                d.distance(want) < 1e-4,
                "guide {g} segment {k}: {d} vs {want}"
            );
        }
    }
    // half way: every segment between the two
    let half = run(0.5, true);
    for ((a, b), c) in own
        .chunks(JOINTS)
        .zip(taken.chunks(JOINTS))
        .zip(half.chunks(JOINTS))
    {
        let (da, db, dc) = (a[3] - a[2], b[3] - b[2], c[3] - c[2]);
        let (x, y) = (da.angle_between(dc), db.angle_between(dc));
        assert!((x - y).abs() < 1e-3, "{x} vs {y}");
    }
}

#[test]
fn links_reduce_strain_and_move_linked_tips_together() {
    let s = Scene::new(200);
    let p = SimParams {
        links: LinkParams {
            radius: 0.6,
            max_links: 4,
            iterations: 4,
            stiffness: 1.0,
        },
        ..params()
    };
    let mut buf = vec![];
    let mut sim = s.sim(&p, &mut buf);
    assert!(!sim.links().is_empty());
    // a jolt that throws the tips around
    step(&mut sim, &s.rest, &Colliders::default(), 1.0 / 24.0);
    posing_agrees_with_its_points(&sim, &s.rest);
    let jolted = moved(
        &s.rest,
        Quat::from_rotation_z(0.6),
        Vec3::new(0.5, -0.3, 0.0),
    );
    let mesh = jolted.mesh();
    let mut layout = ArenaLayout::new();
    PosedFrame::layout(&mut layout, jolted.p.len(), 1, 2);
    let mut fbuf = vec![0u8; layout.bytes()];
    let frame = PosedFrame::new(mesh, 1, 2, &mut Arena::new(&mut fbuf)).unwrap();
    let colliders = Colliders::default();
    let Step {
        context: ctx,
        blocks,
        snapshot,
    } = sim.begin(&frame, &colliders, None, 1.0 / 24.0).unwrap();
    ctx.advance(0, blocks);
    ctx.snapshot(blocks, snapshot);
    let before: Vec<[f32; 3]> = snapshot.to_vec();
    let mut strains = vec![];
    for _ in 0..4 {
        ctx.snapshot(blocks, snapshot);
        strains.push(ctx.links.strain(snapshot));
        ctx.relax(0, blocks, snapshot);
    }
    ctx.snapshot(blocks, snapshot);
    strains.push(ctx.links.strain(snapshot));
    assert!(strains.windows(2).all(|w| w[1] <= w[0]), "{strains:?}");
    // a sweep averages each tip's corrections over its links, so the
    // rate depends on the network: about a quarter off in four sweeps
    // on this network (0.76 measured)
    assert!(strains[4] < 0.8 * strains[0], "{strains:?}");
    // linked tips moved toward each other's motion: the spread of their
    // moves shrank
    let moves: Vec<Vec3> = before
        .iter()
        .zip(snapshot.iter())
        .map(|(a, b)| Vec3::from(*b) - Vec3::from(*a))
        .collect();
    assert!(moves.iter().any(|m| m.length() > 0.0));
}

/// Writes a state's CRC anew after a test changed its bytes.
fn reseal(state: &mut [u8]) {
    let at = header_bytes(8) - 8;
    let mut h = crc32fast::Hasher::new();
    h.update(&state[..at]);
    h.update(&state[at + 8..]);
    state[at..at + 4].copy_from_slice(&h.finalize().to_le_bytes());
}

#[test]
fn a_state_restores_only_into_the_same_guides_and_parameters() {
    let s = Scene::new(20);
    let mut buf = vec![];
    let mut sim = s.sim(&params(), &mut buf);
    let moved_mesh = moved(&s.rest, Quat::IDENTITY, Vec3::new(0.2, 0.0, 0.0));
    step(&mut sim, &moved_mesh, &Colliders::default(), 0.05);
    let mut state = vec![0u8; sim.state_bytes()];
    sim.save(&mut state).unwrap();
    // the same guides with another parameter
    let mut stiffer = params();
    stiffer.teleport *= 2.0;
    let mut other_buf = vec![];
    let mut other = s.sim(&stiffer, &mut other_buf);
    assert!(matches!(
        other.restore(&state),
        Err(Error::InvalidArgument(m)) if m.contains("parameters")
    ));
    // as many guides, of other shapes
    let mut bent = Scene::new(20);
    bent.guide_points[3 * JOINTS + 2][2] += 0.01;
    let mut bent_buf = vec![];
    let mut bent_sim = bent.sim(&params(), &mut bent_buf);
    assert!(matches!(
        bent_sim.restore(&state),
        Err(Error::InvalidArgument(m)) if m.contains("rest guides")
    ));
    assert!(!other.has_stepped() && !bent_sim.has_stepped());
}

#[test]
fn a_restored_simulation_reads_the_posed_guides_of_the_step_saved() {
    let s = Scene::new(20);
    let mut buf = vec![];
    let mut sim = s.sim(&params(), &mut buf);
    let mut fresh = vec![0u8; sim.state_bytes()];
    sim.save(&mut fresh).unwrap();
    let moved_mesh = moved(&s.rest, Quat::IDENTITY, Vec3::new(0.2, 0.0, 0.0));
    step(&mut sim, &moved_mesh, &Colliders::default(), 0.05);
    let mut state = vec![0u8; sim.state_bytes()];
    sim.save(&mut state).unwrap();
    let mut other_buf = vec![];
    let mut other = s.sim(&params(), &mut other_buf);
    other.restore(&state).unwrap();
    assert!(other.has_stepped());
    assert!(posed(&other) == posed(&sim));
    assert!(posed(&other).iter().any(|p| *p != Vec3::ZERO));
    // a state saved before any step has no posed guides to read
    other.restore(&fresh).unwrap();
    assert!(!other.has_stepped());
}

/// A ball field that counts its calls and the points asked.
struct CountedField {
    centre: Vec3,
    calls: core::sync::atomic::AtomicUsize,
    points: core::sync::atomic::AtomicUsize,
}

impl SignedDistance for CountedField {
    fn distances(&self, points: &[[f32; 3]], out: &mut [f32]) {
        use core::sync::atomic::Ordering::Relaxed;
        self.calls.fetch_add(1, Relaxed);
        self.points.fetch_add(points.len(), Relaxed);
        for (p, d) in points.iter().zip(out) {
            *d = Vec3::from(*p).distance(self.centre) - 0.3;
        }
    }
}

#[test]
fn a_host_field_is_asked_for_a_batch_of_guides_at_a_time() {
    use core::sync::atomic::Ordering::Relaxed;
    let s = Scene::new(400);
    let field_at = |centre: Vec3| CountedField {
        centre,
        calls: 0.into(),
        points: 0.into(),
    };
    // far from every guide: one call per batch, every point asked once
    let far = field_at(Vec3::new(0.0, 50.0, 0.0));
    let mut buf = vec![];
    let mut sim = s.sim(&params(), &mut buf);
    let colliders = Colliders {
        field: Some(&far),
        ..Colliders::default()
    };
    step(&mut sim, &s.rest, &colliders, 1.0 / 24.0);
    let n = sim.len();
    assert_eq!(far.calls.load(Relaxed), n.div_ceil(FIELD_BATCH));
    assert_eq!(far.points.load(Relaxed), n * (JOINTS - 1));
    // in the guides' way: the batches, then the rotations tried for the
    // few guides it holds; none ends inside
    let ball = field_at(Vec3::new(0.0, 1.38, 0.0));
    let mut buf2 = vec![];
    let mut sim = s.sim(&params(), &mut buf2);
    let colliders = Colliders {
        field: Some(&ball),
        ..Colliders::default()
    };
    step(&mut sim, &s.rest, &colliders, 1.0 / 24.0);
    let calls = ball.calls.load(Relaxed);
    let points = ball.points.load(Relaxed);
    assert!(calls < n / 4, "{calls} calls for {n} guides");
    assert!(points >= 256 * n.div_ceil(FIELD_BATCH) - 256, "{points}");
    let inside = (0..n)
        .filter(|&g| (1..JOINTS).any(|k| ball.centre.distance(sim.posed(g, k)) < 0.3))
        .count();
    assert_eq!(inside, 0);
}

/// After a shake, each tip settles as its spring target does: the tip
/// points where the target points, seen from the root, on every step down
/// to rest. The IK's sweeps stop within a tolerance of the length, and a
/// target that drifted under it used to leave the tip at rest at once (the
/// last 1% of the swing gone in one step).
#[test]
fn motion_fades_to_rest_without_a_snap() {
    let s = Scene::new(60);
    let mut buf = vec![];
    let mut sim = s.sim(&params(), &mut buf);
    let dt = 1.0 / 24.0;
    for k in 0..6 {
        let shift = Vec3::new(0.08 * (k % 2) as f32, 0.0, 0.0);
        step(
            &mut sim,
            &moved(&s.rest, Quat::IDENTITY, shift),
            &Colliders::default(),
            dt,
        );
    }
    let tip = JOINTS - 1;
    // the tip's and the target's angles from the rest tip, about the root
    let angles = |sim: &Sim, g: usize| -> (f32, f32) {
        let at = (g * JOINTS + tip) * 3;
        let rest = Vec3::new(sim.rest[at], sim.rest[at + 1], sim.rest[at + 2]);
        let root = sim.posed_local(g, 0);
        let target = sim.root_frame(g).to_local(sim.target(g));
        let angle = |p: Vec3| (p - root).angle_between(rest - root);
        (angle(sim.posed_local(g, tip)), angle(target))
    };
    let (mut worst, mut swing, mut end) = (0.0f32, 0.0f32, 0.0f32);
    for f in 0..144 {
        step(&mut sim, &s.rest, &Colliders::default(), dt);
        for g in 0..sim.len() {
            let (tip, target) = angles(&sim, g);
            worst = worst.max((tip - target).abs());
            swing = swing.max(target);
            if f == 143 {
                end = end.max(tip);
            }
        }
    }
    assert!(swing > 0.05, "the shake must swing the tips: {swing} rad");
    assert!(
        worst < 1e-3,
        "a tip strays {worst} rad from its target's bearing"
    );
    assert!(end < 1e-3, "still {end} rad from rest after 6 s");
}

/// A fast spin is motion, not a cut: at 10 turns a second on 24 frames a
/// second, every step is what it is with cuts never detected.
#[test]
fn a_fast_spin_is_never_a_cut() {
    let s = Scene::new(60);
    let never = SimParams {
        teleport: 1e9,
        ..params()
    };
    let (mut buf_a, mut buf_b) = (vec![], vec![]);
    let mut spun = s.sim(&params(), &mut buf_a);
    let mut reference = s.sim(&never, &mut buf_b);
    let turn = core::f32::consts::TAU * 10.0 / 24.0;
    for k in 0..24 {
        let pose = moved(&s.rest, Quat::from_rotation_y(turn * k as f32), Vec3::ZERO);
        step(&mut spun, &pose, &Colliders::default(), 1.0 / 24.0);
        step(&mut reference, &pose, &Colliders::default(), 1.0 / 24.0);
        assert!(
            posed(&spun) == posed(&reference),
            "step {k} taken for a cut"
        );
    }
}

/// A cut from a running shot to a still one starts the body from rest:
/// guides that ran long enough to settle arrive settled, with no whip
/// from the last shot's speed (the cut carried that speed into the still
/// shot, which then kicked every tip).
#[test]
fn a_cut_from_a_run_to_a_still_shot_adds_no_whip() {
    let s = Scene::new(60);
    let mut buf = vec![];
    let mut sim = s.sim(&params(), &mut buf);
    let dt = 1.0 / 24.0;
    let mut run = s.rest.clone();
    for k in 0..240 {
        run = moved(&s.rest, Quat::IDENTITY, Vec3::new(0.1 * k as f32, 0.0, 0.0));
        step(&mut sim, &run, &Colliders::default(), dt);
    }
    let settled = neutral_distance(&sim, &run);
    let far = moved(
        &s.rest,
        Quat::from_rotation_x(0.7),
        Vec3::new(0.0, 100.0, 0.0),
    );
    let mut most = 0.0f32;
    for _ in 0..12 {
        step(&mut sim, &far, &Colliders::default(), dt);
        most = most.max(neutral_distance(&sim, &far));
    }
    assert!(settled < 1e-4, "the run must settle first: {settled}");
    assert!(most < 1e-3, "{most} from rest after the cut");
}

/// The rest sphere turned by `turn` and placed at `place` in a world held
/// in double precision, given relative to `origin`.
fn placed_relative(rest: &TestMesh, turn: Quat, place: [f64; 3], origin: [f64; 3]) -> TestMesh {
    let local = |p: Vec3| -> [f32; 3] {
        let q = turn * p;
        core::array::from_fn(|i| (q[i] as f64 + place[i] - origin[i]) as f32)
    };
    TestMesh {
        p: rest.p.iter().map(|&p| local(Vec3::from(p))).collect(),
        n: rest
            .n
            .iter()
            .map(|&n| (turn * Vec3::from(n)).into())
            .collect(),
        ..rest.clone()
    }
}

#[test]
fn an_origin_that_follows_the_character_gives_the_answers_at_the_world_origin() {
    // a run with a turn, at the world's origin and 1e4 away; far away the
    // host gives the mesh relative to an origin that follows the character
    // (every frame's origin differs), or in float32 world space
    let s = Scene::new(60);
    let (far, dt) = (1e4f64, 1.0 / 24.0);
    let length = 0.3f64;
    let (mut b0, mut b1, mut b2) = (vec![], vec![], vec![]);
    let mut at_zero = s.sim(&params(), &mut b0);
    let mut followed = s.sim(&params(), &mut b1);
    let mut world = s.sim(&params(), &mut b2);
    let none = Colliders::default();
    let (mut worst_followed, mut worst_world) = (0.0f64, 0.0f64);
    let mut saved = vec![];
    for t in 0..36 {
        let tf = t as f64;
        let run = [
            0.9 * tf * dt as f64,
            0.2 * (3.0 * tf * dt as f64).sin(),
            0.0,
        ];
        let turn = Quat::from_rotation_z(0.4 * t as f32 * dt);
        let at = |o: f64| run.map(|c| c + o);
        let step_at = |sim: &mut Sim, place: [f64; 3], origin: [f64; 3]| {
            let mesh = placed_relative(&s.rest, turn, place, origin);
            let mut layout = ArenaLayout::new();
            PosedFrame::layout(&mut layout, mesh.p.len(), 1, 2);
            let mut buf = vec![0u8; layout.bytes()];
            let mut frame = PosedFrame::new(mesh.mesh(), 1, 2, &mut Arena::new(&mut buf)).unwrap();
            frame.set_origin(origin).unwrap();
            sim.step(&frame, &none, dt).unwrap();
        };
        step_at(&mut at_zero, at(0.0), [0.0; 3]);
        step_at(&mut followed, at(far), at(far));
        step_at(&mut world, at(far), [0.0; 3]);
        assert_eq!(followed.origin(), at(far));
        assert_sound(&followed, "followed");
        for (g, k) in (0..s.guide_roots.len()).flat_map(|g| (0..JOINTS).map(move |k| (g, k))) {
            let reference = at_zero.posed(g, k);
            let error = |p: Vec3, origin: [f64; 3]| -> f64 {
                (0..3)
                    .map(|i| (p[i] as f64 + origin[i] - far - reference[i] as f64).abs())
                    .fold(0.0, f64::max)
            };
            worst_followed = worst_followed.max(error(followed.posed(g, k), followed.origin()));
            worst_world = worst_world.max(error(world.posed(g, k), [0.0; 3]));
        }
        if t == 20 {
            saved = vec![0u8; followed.state_bytes()];
            followed.save(&mut saved).unwrap();
        }
    }
    assert!(
        worst_followed <= 1e-4 * length,
        "followed: {worst_followed} of a {length} guide"
    );
    // float32 world points at 1e4 cannot do it: the test can tell
    assert!(worst_world > 10.0 * 1e-4 * length, "world: {worst_world}");
    // the posed guides go only to a frame of the simulation's origin
    let mesh = placed_relative(&s.rest, Quat::IDENTITY, [0.0; 3], [0.0; 3]);
    let mut layout = ArenaLayout::new();
    PosedFrame::layout(&mut layout, mesh.p.len(), s.guide_roots.len(), JOINTS);
    let mut buf = vec![0u8; layout.bytes()];
    let mut frame = PosedFrame::new(
        mesh.mesh(),
        s.guide_roots.len(),
        JOINTS,
        &mut Arena::new(&mut buf),
    )
    .unwrap();
    assert!(matches!(
        followed.posing(&mut frame),
        Err(Error::InvalidArgument(what)) if what.contains("origin")
    ));
    frame.set_origin(followed.origin()).unwrap();
    assert!(followed.posing(&mut frame).is_ok());
    // the saved origin comes back with the state
    let mut b3 = vec![];
    let mut restored = s.sim(&params(), &mut b3);
    restored.restore(&saved).unwrap();
    let run20 = 0.9 * 20.0 * dt as f64;
    assert_eq!(restored.origin()[0], run20 + far);
}
