//! The pipeline's stages on the representative corpus meshes (open rims,
//! separate intersecting shells, creases, no UVs, far from the origin):
//! what each stage promises on the project's creature must hold there too.

use glam::{DQuat, DVec3, Vec3};
use pelage::{
    pelage_sim_params_defaults, pelage_sim_step, pelage_step_params_defaults, PelageSimParams,
    PelageStatus, PelageStepParams,
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

/// The mesh's centre: the middle of its box.
fn centre(mesh: &CreatureMesh) -> DVec3 {
    let (mut lo, mut hi) = (DVec3::MAX, DVec3::MIN);
    for p in &mesh.positions {
        let p = DVec3::from(p.map(f64::from));
        (lo, hi) = (lo.min(p), hi.max(p));
    }
    (lo + hi) / 2.0
}

/// Frame `k` of a shot that turns the mesh about its centre (0.08 rad a
/// frame about y) and moves it sideways (1% of its size a frame).
fn shot_frame(e: &CorpusMesh, k: usize) -> CreatureMesh {
    let c = centre(&e.mesh);
    let turn = DQuat::from_rotation_y(0.08 * k as f64);
    let shift = DVec3::X * (0.01 * size(e) as f64 * k as f64);
    corpus::placed(&e.mesh, c - turn * c + shift, turn)
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
