//! Guide dynamics at the paper's gorilla scale: 13,030 simulation guides x
//! 16 joints on the animated creature (walk, turn, jump, sway), through the
//! C API at 1 and 2 threads. Reports the time per step with tip links and
//! 16 capsules, the extra cost of colliding with the deforming body, a
//! floor measured in the same run (reading every guide's neutral pose and
//! writing it as the posed guide, split over the same threads), and the
//! full frame: simulate, then expand 979,526 render hairs from the
//! simulated guides. The paper: 7 frames/s for the simulation alone.

use pelage::*;
use pelage_core::collide::COLLISION_CELLS_PER_TRIANGLE;
use pelage_core::interp::groom::{GroomMaps, StrandGroom};
use pelage_core::interp::posed::PosedFrame;
use pelage_core::surface::body::{Body, BodyPlan, Rim};
use pelage_core::{Arena, ArenaLayout, Root, ScalarMap};
use pelage_tests::animated::{capsules, colliders, pose, ShotSim, FRAMES};
use pelage_tests::creature::default_creature;
use pelage_tests::measure::{
    bind_vec, combed_guides, curves_desc, frame, groom_handle, guides_desc, mesh_desc, mesh_view,
    on_threads, stamp_roots,
};
use std::hint::black_box;
use std::time::Instant;

const GUIDES: u32 = 13_030;
const HAIRS: u32 = 979_526;
const JOINTS: usize = 16;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let rest = default_creature();
    let mesh = mesh_view(&rest);
    let roots = stamp_roots(mesh, GUIDES, 1);
    let points = combed_guides(&mesh, &roots, JOINTS, 0.06);
    let guides = guides_desc(&roots, &points);
    let t = Instant::now();
    let shot_sim = ShotSim::new(&rest, &roots, &points, JOINTS);
    let t_new = t.elapsed().as_secs_f64();
    let (sim, bytes) = (shot_sim.sim, shot_sim.bytes());
    // the shot's meshes and frames, made before timing (a host has them)
    let meshes: Vec<_> = (0..FRAMES).map(|f| pose(&rest, f)).collect();
    let descs: Vec<_> = meshes.iter().map(mesh_desc).collect();
    let frames: Vec<_> = descs
        .iter()
        .map(|d| frame(d, &guides, JOINTS as u32, 2).unwrap())
        .collect();
    let props: Vec<_> = (0..FRAMES).map(|f| capsules(&rest, &roots, f)).collect();
    println!(
        "creature: {} triangles; {} guides x {JOINTS} joints; sim memory {:.1} MB, made in {:.0} ms",
        rest.triangles.len(),
        roots.len(),
        bytes as f64 / 1e6,
        t_new * 1e3
    );
    // the body's build stage by stage, on one thread
    let mut stages = vec![vec![]; 6];
    // the memory kept from frame to frame, as the step keeps it
    let mut rim_memory = vec![0u8; Rim::required_bytes(&mesh)];
    let most = meshes
        .iter()
        .map(|m| Body::required_bytes(&mesh_view(m)).unwrap());
    let mut memory = vec![0u8; most.max().unwrap()];
    let mut refs_memory = vec![];
    for m in &meshes {
        let view = mesh_view(m);
        let mut lap = {
            let mut t = Instant::now();
            move |k: usize, stages: &mut Vec<Vec<f64>>| {
                stages[k].push(t.elapsed().as_secs_f64());
                t = Instant::now();
            }
        };
        let rim = Rim::refresh(&view, &mut Arena::new(&mut rim_memory)).unwrap();
        lap(0, &mut stages);
        let plan = BodyPlan::with_density(&view, &rim, COLLISION_CELLS_PER_TRIANGLE).unwrap();
        lap(1, &mut stages);
        let mut parts = Body::parts(&plan, &view, &rim, &mut Arena::new(&mut memory)).unwrap();
        lap(2, &mut stages);
        let layers = 0..parts.layers();
        let (grid, start, _, _) = parts.split();
        let cells = start.len() - 1;
        let total = grid.count(layers.clone(), &mut start[..cells]);
        refs_memory.resize(refs_memory.len().max(4 * total as usize), 0);
        parts
            .set_total(total, &mut Arena::new(&mut refs_memory))
            .unwrap();
        lap(3, &mut stages);
        let (grid, start, refs, class) = parts.split();
        grid.fill(layers.clone(), 0, &mut start[..cells], refs);
        lap(4, &mut stages);
        grid.classify(layers, start, class);
        black_box(parts.finish());
        lap(5, &mut stages);
    }
    let stages: Vec<f64> = stages.into_iter().map(median).collect();
    println!(
        "the body, built per step for the body collider: {:.1} ms (one thread): rim (refreshed) {:.1}, placement {:.1}, triangles copied {:.1}, grid counted {:.1}, listed {:.1}, classified {:.1}",
        stages.iter().sum::<f64>() * 1e3,
        stages[0] * 1e3,
        stages[1] * 1e3,
        stages[2] * 1e3,
        stages[3] * 1e3,
        stages[4] * 1e3,
        stages[5] * 1e3
    );
    println!(
        "{:>34} {:>7} | {:>9} {:>9} | {:>8}",
        "step (median over the shot)", "threads", "ms", "frames/s", "x floor"
    );
    let mut posed = vec![[0.0f32; 3]; roots.len() * JOINTS];
    for threads in [1u32, 2] {
        let floor = median(
            (0..FRAMES as usize)
                .map(|f| {
                    let t = Instant::now();
                    neutral_floor(&meshes[f], &roots, &points, &mut posed, threads as usize);
                    black_box(&posed);
                    t.elapsed().as_secs_f64()
                })
                .collect(),
        );
        // body: 0 none, 1 built by the step, 2 the frame's (built before
        // the step, untimed there, as a host that also pushes render
        // strands out has it)
        let mut frame_body = vec![];
        let mut run = |body: u32| {
            assert_eq!(pelage_sim_reset(sim), PelageStatus::Ok);
            median(
                (0..FRAMES as usize)
                    .map(|f| {
                        let caps = &props[f];
                        let colliders = colliders(caps, body != 0);
                        if body == 2 {
                            let t = Instant::now();
                            let s = pelage_frame_set_colliders(
                                frames[f].0,
                                &colliders,
                                on_threads(threads),
                            );
                            frame_body.push(t.elapsed().as_secs_f64());
                            assert_eq!(s, PelageStatus::Ok);
                        }
                        let t = Instant::now();
                        let s = pelage_sim_step(
                            sim,
                            frames[f].0,
                            &PelageStepParams {
                                dt: 1.0 / 24.0,
                                run: on_threads(threads),
                                colliders: &colliders,
                                ..pelage_step_params_defaults()
                            },
                            std::ptr::null_mut(),
                        );
                        let e = t.elapsed().as_secs_f64();
                        assert_eq!(s, PelageStatus::Ok);
                        if body == 2 {
                            // the frame's body freed (96 would not fit)
                            pelage_frame_set_colliders(
                                frames[f].0,
                                std::ptr::null(),
                                on_threads(threads),
                            );
                        }
                        e
                    })
                    .collect(),
            )
        };
        let with_capsules = run(0);
        let with_body = run(1);
        let with_frame_body = run(2);
        for (name, t) in [
            ("links + 16 capsules", with_capsules),
            ("links + 16 capsules + body", with_body),
            ("... + the frame's body", with_frame_body),
            ("floor: neutral read, posed written", floor),
        ] {
            println!(
                "{name:>34} {threads:>7} | {:>9.2} {:>9.0} | {:>7.2}x",
                t * 1e3,
                1.0 / t,
                t / floor
            );
        }
        println!(
            "{:>34} {threads:>7} | {:>9.2} ms more for the body; {:.2} ms with the frame's, which pelage_frame_set_colliders built in {:.2} ms (as many threads)",
            "",
            (with_body - with_capsules) * 1e3,
            (with_frame_body - with_capsules) * 1e3,
            median(frame_body) * 1e3
        );
    }
    full_frame(sim, &rest, &roots, &points, &frames, &props);
    println!("paper: 7 frames/s for the guide simulation, 2 frames/s with interpolation");
}

/// The floor: every guide's neutral pose (its rest shape carried by its
/// root frame on the posed mesh) written as a posed guide, over `threads`.
fn neutral_floor(
    mesh: &pelage_tests::creature::CreatureMesh,
    roots: &[Root],
    points: &[[f32; 3]],
    out: &mut [[f32; 3]],
    threads: usize,
) {
    let m = mesh_view(mesh);
    let mut layout = ArenaLayout::new();
    PosedFrame::layout(&mut layout, mesh.positions.len(), 1, 2);
    let mut buf = vec![0u8; layout.bytes()];
    let frame = PosedFrame::new(m, 1, 2, &mut Arena::new(&mut buf)).unwrap();
    let chunk = roots.len().div_ceil(threads);
    std::thread::scope(|s| {
        for (c, part) in out.chunks_mut(chunk * JOINTS).enumerate() {
            let frame = &frame;
            s.spawn(move || {
                for (i, guide) in part.chunks_mut(JOINTS).enumerate() {
                    let g = c * chunk + i;
                    let r = &roots[g];
                    let f = frame.root_frame(r.face as usize, r.u, r.v);
                    for (k, o) in guide.iter_mut().enumerate() {
                        *o = f
                            .to_world(glam::Vec3::from(points[g * JOINTS + k]))
                            .to_array();
                    }
                }
            });
        }
    });
}

/// The full frame on 2 threads: step the simulation (links, capsules),
/// read the posed guides, pose a render frame with them and expand
/// 979,526 hairs bound to the simulation guides.
fn full_frame(
    sim: PelageSim,
    rest: &pelage_tests::creature::CreatureMesh,
    roots: &[Root],
    points: &[[f32; 3]],
    frames: &[pelage_tests::measure::Frame],
    props: &[Vec<PelageCapsule>],
) {
    let mesh = mesh_view(rest);
    let hairs: Vec<Root> = {
        let mut h = stamp_roots(mesh, HAIRS + HAIRS / 50, 2);
        h.retain(|r| r.rank < HAIRS);
        h
    };
    let bindings = bind_vec(&mesh, roots, points, JOINTS, &hairs);
    let mut grooms = vec![StrandGroom::default(); hairs.len()];
    let maps = GroomMaps {
        kink_amplitude: ScalarMap::Constant(0.03),
        clump: ScalarMap::Constant(0.2),
        ..GroomMaps::default()
    };
    maps.evaluate(&mesh, &hairs, 0, &mut grooms).unwrap();
    let groom = groom_handle(
        &hairs,
        bytemuck::cast_slice(&bindings),
        bytemuck::cast_slice(&grooms),
    );
    let ep = PelageExpandParams {
        points_per_strand: JOINTS as u32,
        run: on_threads(2),
        ..pelage_expand_params_defaults()
    };
    let mut per = 0;
    assert_eq!(pelage_expand_size(&ep, &mut per), PelageStatus::Ok);
    let mut out = vec![[0.0f32; 4]; hairs.len() * per];
    let mut posed = vec![[0.0f32; 3]; roots.len() * JOINTS];
    assert_eq!(pelage_sim_reset(sim), PelageStatus::Ok);
    let (mut times, mut stages, mut read_and_set) = (vec![], [vec![], vec![], vec![]], vec![]);
    for (f, handle) in frames.iter().enumerate() {
        let caps = &props[f];
        let colliders = colliders(caps, false);
        let t = Instant::now();
        assert_eq!(
            pelage_sim_step(
                sim,
                handle.0,
                &PelageStepParams {
                    dt: 1.0 / 24.0,
                    run: on_threads(2),
                    colliders: &colliders,
                    ..pelage_step_params_defaults()
                },
                std::ptr::null_mut()
            ),
            PelageStatus::Ok
        );
        let stepped = t.elapsed().as_secs_f64();
        assert_eq!(
            pelage_frame_set_sim_guides(handle.0, sim, on_threads(2)),
            PelageStatus::Ok
        );
        let posing = t.elapsed().as_secs_f64();
        let curves = curves_desc(&mut out, None);
        assert_eq!(
            pelage_groom_expand(groom, handle.0, 0, hairs.len(), &ep, &curves),
            PelageStatus::Ok
        );
        black_box(&out);
        let all = t.elapsed().as_secs_f64();
        times.push(all);
        // the same guides through a host buffer, as a host without
        // pelage_frame_set_sim_guides would pose them (the same bits)
        let t = Instant::now();
        assert_eq!(
            pelage_sim_read(sim, posed.as_mut_ptr().cast(), 12, posed.len()),
            PelageStatus::Ok
        );
        let simulated = guides_desc(roots, &posed);
        assert_eq!(
            pelage_frame_set_guides(handle.0, &simulated, on_threads(2)),
            PelageStatus::Ok
        );
        read_and_set.push(t.elapsed().as_secs_f64());
        for (v, d) in stages
            .iter_mut()
            .zip([stepped, posing - stepped, all - posing])
        {
            v.push(d);
        }
    }
    pelage_groom_free(groom);
    let t = median(times);
    let [step, pose, expand] = stages.map(median);
    println!(
        "full frame, 2 threads (step with links and capsules, pose, expand {} hairs): {:.1} ms, {:.1} frames/s (medians: step {:.1}, pose {:.1}, expand {:.1} ms; posing through pelage_sim_read and pelage_frame_set_guides instead: {:.1} ms)",
        hairs.len(),
        t * 1e3,
        1.0 / t,
        step * 1e3,
        pose * 1e3,
        expand * 1e3,
        median(read_and_set) * 1e3
    );
}
