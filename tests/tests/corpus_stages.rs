//! The pipeline's stages on the representative corpus meshes (open rims,
//! separate intersecting shells, creases, no UVs, far from the origin):
//! what each stage promises on the project's creature must hold there too.

use glam::{DQuat, DVec3, Vec3};
use pelage::{
    pelage_sim_params_defaults, pelage_sim_step, pelage_step_params_defaults, pelage_trim_find,
    PelageSimParams, PelageStatus, PelageStepParams, PelageTrimRecord,
};
use pelage_tests::animated::colliders;
use pelage_tests::corpus::{self, CorpusMesh};
use pelage_tests::creature::CreatureMesh;
use pelage_tests::measure::{combed_guides, frame, guides_desc, on_threads, SimHandle};
use pelage_tests::quality::winding_number;

/// Points per guide.
const POINTS: usize = 16;

/// The mesh's size: the diagonal of its box.
fn size(e: &CorpusMesh) -> f32 {
    let (mut lo, mut hi) = (Vec3::MAX, Vec3::MIN);
    for p in &e.mesh.positions {
        (lo, hi) = (lo.min(Vec3::from(*p)), hi.max(Vec3::from(*p)));
    }
    (hi - lo).length()
}

/// Trim records against the body agree with the inside rule (the
/// generalized winding number above 1/2): a record's first point past the
/// meet is inside, and a record at the root is one whose first segment
/// enters at once. A root lies on the skin by construction, so it is
/// never a meet itself. Far from the origin too: the body works relative
/// to its grid's corner (at 1e3 a record stood on a point the winding
/// number calls out when it worked in world coordinates).
#[test]
fn trim_records_against_the_body_agree_with_the_inside_rule() {
    for e in &corpus::representative() {
        let (roots, _, _) = e.stamp(1500, 7);
        let mesh = e.view();
        let length = 0.08 * size(e);
        let points = combed_guides(&mesh, &roots, POINTS, length);
        let guides = guides_desc(&roots, &points);
        let handle = frame(&e.desc(), &guides, POINTS as u32, 2).expect("frame");
        let body = colliders(&[], true);
        let mut records = vec![PelageTrimRecord::default(); roots.len()];
        let mut count = 0;
        let s = pelage_trim_find(
            handle.0,
            std::ptr::null(),
            &body,
            on_threads(2),
            records.as_mut_ptr(),
            records.len(),
            &mut count,
        );
        assert_eq!(s, PelageStatus::Ok, "{}", e.name);
        records.truncate(count);
        let point = |g: usize, k: usize| Vec3::from(points[g * POINTS + k]);
        let (mut outside, mut at_root) = (vec![], vec![]);
        for r in &records {
            let (g, cv) = (r.guide as usize, r.cv as usize);
            let past = winding_number(&mesh, point(g, cv));
            if past <= 0.5 {
                outside.push((g, cv, past));
            }
            if r.length == 0.0 {
                // a hair's breadth along the first segment
                let (a, b) = (point(g, 0), point(g, 1));
                let w = winding_number(&mesh, a.lerp(b, 1.0 / 4096.0));
                if w <= 0.5 {
                    at_root.push((g, w));
                }
            }
        }
        println!(
            "{}: {} of {} guides meet the body; {} records past an outside point, {} at a root outside",
            e.name,
            records.len(),
            roots.len(),
            outside.len(),
            at_root.len()
        );
        assert!(
            outside.is_empty(),
            "{}: records whose point past the meet is outside (guide, cv, winding): {outside:?}",
            e.name
        );
        assert!(
            at_root.is_empty(),
            "{}: records at a root whose first segment starts outside (guide, winding): {at_root:?}",
            e.name
        );
    }
}

/// Frame `k` of a shot that turns the mesh about its centre (0.08 rad a
/// frame about y) and moves it sideways (1% of its size a frame).
fn shot_frame(e: &CorpusMesh, k: usize) -> CreatureMesh {
    let turn = DQuat::from_rotation_y(0.08 * k as f64);
    let shift = DVec3::X * (0.01 * size(e) as f64 * k as f64);
    corpus::turned_about_centre(&e.mesh, turn, shift)
}

/// The simulation on every representative mesh, with its body as a
/// collider, over a shot that turns and moves the head: every posed guide
/// is finite, keeps its root on the skin and its segments' lengths, no
/// point past a root on open skin is inside the body (the winding number,
/// on a sample of the guides), and 1 and 2 threads give the same bits.
#[test]
fn the_simulation_runs_on_every_representative_mesh() {
    for e in &corpus::representative() {
        let (roots, _, _) = e.stamp(1000, 11);
        let length = 0.08 * size(e);
        let points = combed_guides(&e.view(), &roots, POINTS, length);
        let guides = guides_desc(&roots, &points);
        let params = PelageSimParams {
            joints: POINTS as u32,
            points_per_guide: POINTS as u32,
            ..pelage_sim_params_defaults()
        };
        let sims = [1, 2].map(|_| SimHandle::new(&e.desc(), &guides, &params));
        let segment = length / (POINTS - 1) as f32;
        let mut inside = 0;
        for k in 0..12 {
            let mesh = shot_frame(e, k);
            let desc = corpus::mesh_desc(&mesh);
            let handle = frame(&desc, &guides, POINTS as u32, 2).expect("frame");
            let mut posed = vec![];
            for (threads, sim) in [1, 2].into_iter().zip(&sims) {
                let step = PelageStepParams {
                    colliders: &colliders(&[], true),
                    run: on_threads(threads),
                    ..pelage_step_params_defaults()
                };
                let s = pelage_sim_step(sim.sim, handle.0, &step, std::ptr::null_mut());
                assert_eq!(s, PelageStatus::Ok, "{} frame {k}", e.name);
                posed.push(sim.read(roots.len(), POINTS));
            }
            assert!(
                posed[0] == posed[1],
                "{} frame {k}: 1 and 2 threads differ",
                e.name
            );
            let view = corpus::mesh_view(&mesh);
            for (g, r) in roots.iter().enumerate() {
                let p: Vec<Vec3> = posed[0][g * POINTS..(g + 1) * POINTS]
                    .iter()
                    .map(|&q| Vec3::from(q))
                    .collect();
                assert!(
                    p.iter().all(|q| q.is_finite()),
                    "{} frame {k} guide {g}",
                    e.name
                );
                let root = view.point(r.face as usize, r.u, r.v);
                let slack = 1e-4 * segment + 8.0 * f32::EPSILON * root.abs().max_element();
                assert!(
                    p[0].distance(root) <= slack,
                    "{} frame {k} guide {g}: root",
                    e.name
                );
                for w in p.windows(2) {
                    let stretch = (w[0].distance(w[1]) - segment).abs();
                    assert!(
                        stretch <= 0.02 * segment + slack,
                        "{} frame {k} guide {g}: a segment of {} for {segment}",
                        e.name,
                        w[0].distance(w[1])
                    );
                }
                // a root whose skin is itself inside (a tooth in the mouth,
                // which the stamp's flat caps call open) has no way out
                let lifted = root + view.normal(r.face as usize, r.u, r.v) * (1e-3 * length);
                if k == 11 && g % 10 == 0 && winding_number(&view, lifted) <= 0.5 {
                    inside += p[1..]
                        .iter()
                        .filter(|&&q| winding_number(&view, q) > 0.5)
                        .count();
                }
            }
        }
        println!("{}: {inside} sampled points inside the body", e.name);
        assert_eq!(inside, 0, "{}: points inside the body", e.name);
    }
}

/// `pelage_frame_inside` answers by the one inside rule, the generalized
/// winding number above 1/2, on open meshes of several shells too: points
/// a little off the skin on both sides, across the holes, and scattered in
/// the mesh's box (points within 1e-3 of the threshold left out), far
/// from the origin too (a point at 1e3 read the other way when the body
/// worked in world coordinates). Placed
/// far from the origin, 2 of 1,200 may disagree (see below).
#[test]
fn the_inside_query_is_the_winding_number_on_open_meshes() {
    for e in &corpus::representative() {
        let mesh = e.view();
        let (lo, hi) = e
            .mesh
            .positions
            .iter()
            .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| {
                (lo.min(Vec3::from(*p)), hi.max(Vec3::from(*p)))
            });
        let off = 0.01 * size(e);
        let mut points = vec![];
        let faces = mesh.triangle_count();
        for k in 0..400usize {
            let f = (k * 7919) % faces;
            let (u, v) = (0.2 + 0.001 * (k % 300) as f32, 0.3);
            let (p, n) = (mesh.point(f, u, v), mesh.face_normal(f));
            points.push(p + n * off);
            points.push(p - n * off);
            let t = Vec3::new(
                (k as f32 * 0.618_034).fract(),
                (k as f32 * 0.414_214).fract(),
                (k as f32 * 0.732_051).fract(),
            );
            points.push(lo + (hi - lo) * t);
        }
        let (roots, _, _) = e.stamp(200, 3);
        let guides = combed_guides(&mesh, &roots, POINTS, 0.05 * size(e));
        let handle =
            frame(&e.desc(), &guides_desc(&roots, &guides), POINTS as u32, 2).expect("frame");
        let mut inside = vec![0u8; points.len()];
        let s = pelage::pelage_frame_inside(
            handle.0,
            points.as_ptr().cast(),
            12,
            points.len(),
            on_threads(2),
            inside.as_mut_ptr(),
        );
        assert_eq!(s, PelageStatus::Ok, "{}", e.name);
        let (mut checked, mut wrong) = (0, vec![]);
        for (p, &answer) in points.iter().zip(&inside) {
            let w = winding_number(&mesh, *p);
            if (w - 0.5).abs() < 1e-3 {
                continue;
            }
            checked += 1;
            if (w > 0.5) != (answer == 1) {
                wrong.push((*p, w));
            }
        }
        println!(
            "{}: {checked} points checked, {} wrong",
            e.name,
            wrong.len()
        );
        assert!(wrong.is_empty(), "{}: {wrong:?}", e.name);
        // the signed distance: its sign is the inside rule's answer, its
        // size the distance to the nearest triangle (every one tried, in
        // f64), within 1e-5 of the mesh's size and the points' rounding
        let mut distances = vec![f32::NAN; points.len()];
        let s = pelage::pelage_frame_signed_distance(
            handle.0,
            points.as_ptr().cast(),
            12,
            points.len(),
            on_threads(2),
            distances.as_mut_ptr(),
        );
        assert_eq!(s, PelageStatus::Ok, "{}", e.name);
        let mut worst = 0.0f64;
        for ((p, &answer), &d) in points.iter().zip(&inside).zip(&distances) {
            assert_eq!(d < 0.0, answer == 1, "{}: {p} at {d}", e.name);
            let want = nearest_by_every_triangle(&mesh, *p);
            let slack =
                1e-5 * size(e) as f64 + 4.0 * f32::EPSILON as f64 * p.abs().max_element() as f64;
            assert!(
                (d.abs() as f64 - want).abs() <= slack,
                "{}: {p}: {d} for {want}",
                e.name
            );
            worst = worst.max((d.abs() as f64 - want).abs() / size(e) as f64);
        }
        println!(
            "{}: signed distances within {worst:.1e} of the size",
            e.name
        );
    }
}

/// The distance from `p` to the nearest triangle with area of `mesh`, in
/// f64, by trying every one (the closest point by the region of the
/// triangle's plane `p` projects into, as a textbook has it).
fn nearest_by_every_triangle(mesh: &pelage_core::Mesh, p: Vec3) -> f64 {
    let p = p.as_dvec3();
    (0..mesh.triangle_count())
        .filter(|&f| !mesh.is_degenerate(f))
        .map(|f| {
            let [a, b, c] = mesh.corners(f).map(|q| q.as_dvec3());
            let (ab, ac) = (b - a, c - a);
            let n = ab.cross(ac);
            // inside the triangle's prism: the distance to its plane
            let inside = [(a, b), (b, c), (c, a)]
                .iter()
                .all(|&(s, t)| (t - s).cross(p - s).dot(n) >= 0.0);
            if inside {
                return ((p - a).dot(n) / n.length()).abs();
            }
            [(a, b), (b, c), (c, a)]
                .iter()
                .map(|&(s, t)| {
                    let e = t - s;
                    let x = ((p - s).dot(e) / e.length_squared()).clamp(0.0, 1.0);
                    (p - (s + e * x)).length()
                })
                .fold(f64::INFINITY, f64::min)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Where a mesh is taken far from the origin to: its own placement, or
/// 1e4 away for a mesh at the origin.
fn far_offset(e: &CorpusMesh) -> DVec3 {
    if e.recipe.offset != DVec3::ZERO {
        e.recipe.offset
    } else {
        DVec3::new(1e4, -3e3, 5e3)
    }
}

/// The largest distance between `a` and `b` shifted by `by`, in f64.
fn worst_apart(a: &[[f32; 3]], b: &[[f32; 3]], by: DVec3) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            let (p, q) = (DVec3::from(p.map(f64::from)), DVec3::from(q.map(f64::from)));
            (p - (q + by)).abs().max_element()
        })
        .fold(0.0, f64::max)
}

/// A character far from the origin, given relative to an origin that
/// follows it (`pelage_frame_set_origin`, every frame's different), gives
/// the simulated guides, their render hairs and the trim records of the
/// same character at the world's origin: within 1e-4 of the hair length,
/// with the body as a collider, on every representative mesh.
#[test]
fn an_origin_that_follows_the_character_gives_the_answers_at_the_origin() {
    use pelage::*;
    for e in &corpus::representative() {
        let home = CorpusMesh::new(e.name.clone(), e.about, e.recipe.at_origin());
        let far = far_offset(e);
        let length = 0.08 * size(&home);
        let maps = pelage_groom_maps_defaults();
        let g = pelage_tests::measure::groomed(&home.mesh, (300, POINTS, length), 3000, &maps, 2);
        let guides = g.guides();
        let params = PelageSimParams {
            joints: POINTS as u32,
            points_per_guide: POINTS as u32,
            ..pelage_sim_params_defaults()
        };
        let sims = [0, 1].map(|_| SimHandle::new(&home.desc(), &guides, &params));
        let (mut worst_guides, mut worst_hairs) = (0.0f64, 0.0f64);
        let mut records: [Vec<PelageTrimRecord>; 2] = Default::default();
        for k in 0..10 {
            let turn = DQuat::from_rotation_y(0.08 * k as f64);
            let shift = DVec3::X * (0.01 * size(&home) as f64 * k as f64);
            // at the origin, moving; far away, the same frame relative to
            // an origin that moves with it
            let meshes = [
                corpus::turned_about_centre(&home.mesh, turn, shift),
                corpus::turned_about_centre(&home.mesh, turn, DVec3::ZERO),
            ];
            let origins = [DVec3::ZERO, far + shift];
            let mut posed: Vec<Vec<[f32; 3]>> = vec![];
            let mut hairs: Vec<Vec<[f32; 4]>> = vec![];
            for side in 0..2 {
                let desc = corpus::mesh_desc(&meshes[side]);
                let handle = frame(&desc, &guides, POINTS as u32, 2).expect("frame");
                let origin = origins[side].to_array();
                assert_eq!(
                    pelage_frame_set_origin(handle.0, origin.as_ptr()),
                    PelageStatus::Ok
                );
                let body = colliders(&[], true);
                let step = PelageStepParams {
                    colliders: &body,
                    run: on_threads(2),
                    ..pelage_step_params_defaults()
                };
                let s = pelage_sim_step(sims[side].sim, handle.0, &step, std::ptr::null_mut());
                assert_eq!(s, PelageStatus::Ok, "{} frame {k}", e.name);
                let mut at = [f64::NAN; 3];
                assert_eq!(
                    pelage_sim_origin(sims[side].sim, at.as_mut_ptr()),
                    PelageStatus::Ok
                );
                assert_eq!(at, origin);
                posed.push(sims[side].read(g.guide_roots.len(), POINTS));
                if k == 9 {
                    let s = pelage_frame_set_sim_guides(handle.0, sims[side].sim, on_threads(2));
                    assert_eq!(s, PelageStatus::Ok);
                    let expand = PelageExpandParams {
                        points_per_strand: POINTS as u32,
                        run: on_threads(2),
                        ..pelage_expand_params_defaults()
                    };
                    let strands =
                        pelage_tests::measure::strands_desc(&g.strands, &g.bindings, &g.grooms);
                    let mut per = 0;
                    assert_eq!(pelage_expand_size(&expand, &mut per), PelageStatus::Ok);
                    let mut out = vec![[0.0f32; 4]; per * g.strands.len()];
                    let s = pelage_expand(
                        handle.0,
                        &strands,
                        &expand,
                        &pelage_tests::measure::curves_desc(&mut out, None),
                    );
                    assert_eq!(s, PelageStatus::Ok);
                    hairs.push(out);
                    let mut found = vec![PelageTrimRecord::default(); g.guide_roots.len()];
                    let mut count = 0;
                    let s = pelage_trim_find(
                        handle.0,
                        std::ptr::null(),
                        &body,
                        on_threads(2),
                        found.as_mut_ptr(),
                        found.len(),
                        &mut count,
                    );
                    assert_eq!(s, PelageStatus::Ok);
                    found.truncate(count);
                    records[side] = found;
                }
            }
            worst_guides = worst_guides.max(worst_apart(&posed[0], &posed[1], shift));
            if k == 9 {
                let xyz = |h: &[[f32; 4]]| h.iter().map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>();
                worst_hairs = worst_hairs.max(worst_apart(&xyz(&hairs[0]), &xyz(&hairs[1]), shift));
            }
        }
        let (a, b) = (&records[0], &records[1]);
        let same_guides = a.len() == b.len()
            && a.iter()
                .zip(b)
                .all(|(x, y)| (x.guide, x.cv) == (y.guide, y.cv));
        let worst_record = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x.length - y.length).abs())
            .fold(0.0f32, f32::max);
        let l = length as f64;
        println!(
            "{}: at {far:?} by a following origin, guides {:.2e} L, hairs {:.2e} L, {} trim records, worst {:.2e} L",
            e.name,
            worst_guides / l,
            worst_hairs / l,
            a.len(),
            worst_record
        );
        assert!(
            worst_guides <= 1e-4 * l,
            "{}: guides {worst_guides}",
            e.name
        );
        assert!(worst_hairs <= 1e-4 * l, "{}: hairs {worst_hairs}", e.name);
        assert!(
            same_guides,
            "{}: trim records of other guides ({} vs {})",
            e.name,
            a.len(),
            b.len()
        );
        assert!(
            worst_record <= 1e-4,
            "{}: a trim record {worst_record} L apart",
            e.name
        );
    }
}

/// How far each guide's tip moves, in guide lengths, when the mesh is
/// turned by `turn` and stretched along x by `stretch`, from where the
/// rest frame's tip taken through the same motion lies: 0 for root frames
/// that follow the mesh exactly.
fn tip_moves(e: &CorpusMesh, turn: DQuat, stretch: f32) -> Vec<f32> {
    use pelage_core::arena::{Arena, ArenaLayout};
    use pelage_core::guides::{CvLayout, Guides};
    use pelage_core::interp::posed::PosedFrame;
    let mesh = e.view();
    let (roots, _, _) = e.stamp(3000, 5);
    let length = 0.05 * size(e);
    let points = combed_guides(&mesh, &roots, 8, length);
    let guides = Guides {
        roots: &roots,
        points: pelage_core::Strided::from_slice(&points),
        layout: CvLayout::Fixed(8),
    };
    let mut layout = ArenaLayout::new();
    PosedFrame::layout(&mut layout, mesh.positions.len(), roots.len(), 8);
    let mut rest_memory = vec![0u8; layout.bytes()];
    let rest = PosedFrame::with_guides(mesh, &guides, 8, &mut Arena::new(&mut rest_memory))
        .expect("rest frame");
    let mut moved = corpus::turned_about_centre(&e.mesh, turn, DVec3::ZERO);
    for p in moved.positions.iter_mut() {
        p[0] *= stretch;
    }
    let view = corpus::mesh_view(&moved);
    let mut memory = vec![0u8; layout.bytes()];
    let frame = PosedFrame::new(view, roots.len(), 8, &mut Arena::new(&mut memory)).expect("frame");
    let motion = |w: Vec3| {
        let w = turn.as_quat() * w;
        Vec3::new(w.x * stretch, w.y, w.z)
    };
    roots
        .iter()
        .enumerate()
        .map(|(g, r)| {
            let (now, then) = (
                frame.root_frame(r.face as usize, r.u, r.v),
                rest.root_frame(r.face as usize, r.u, r.v),
            );
            let tip = rest.local_point(g, 7);
            let want = motion(then.to_world(tip) - then.origin);
            ((now.to_world(tip) - now.origin) - want).length() / length
        })
        .collect()
}

/// Root frames follow the mesh without UVs as with them: under a rigid
/// turn no guide's tip moves by more than 1e-3 of its length from where
/// the turn takes it (every representative mesh, relative to an origin
/// near it, as a host far from the origin gives it), and under a 1%
/// stretch along x the frames without UVs move tips no more than those
/// with UVs (a stretch turns the skin itself, so the tips move either way).
#[test]
fn root_frames_without_uvs_follow_the_mesh() {
    let turn = DQuat::from_rotation_y(0.7) * DQuat::from_rotation_x(0.3);
    for e in &corpus::representative() {
        let home = CorpusMesh::new(e.name.clone(), e.about, e.recipe.at_origin());
        let worst = tip_moves(&home, turn, 1.0)
            .into_iter()
            .fold(0.0f32, f32::max);
        println!("{}: a turn moves a tip by at most {worst:.1e} L", e.name);
        assert!(worst <= 1e-3, "{}: {worst}", e.name);
    }
    let list = corpus::representative();
    let (with, without) = (&list[0], &list[1]);
    assert!(with.has_uvs() && !without.has_uvs());
    let worst = |e: &CorpusMesh| {
        tip_moves(e, DQuat::IDENTITY, 1.01)
            .into_iter()
            .fold(0.0f32, f32::max)
    };
    let (uv, no_uv) = (worst(with), worst(without));
    println!("a 1% stretch moves a tip by at most {uv:.1e} L with UVs, {no_uv:.1e} L without");
    assert!(no_uv <= uv + 1e-3, "{no_uv} without UVs, {uv} with");
}
