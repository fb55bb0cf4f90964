//! The body collider's cost on the corpus (issue 48, ask 3): for each
//! corpus mesh and its closed reference (a closed single shell as large,
//! with about as many triangles, placed alike), ~13,000 guides of 16
//! points, 0.05 to 0.15 of the head's size long, stepped through the C API
//! on 2 threads while the mesh sways rigidly. Medians over several runs
//! of: the step without the body, with the body the step builds, and with
//! the frame's body (`pelage_frame_set_colliders`, whose own time is
//! reported apart). The table gives each mesh's extra step cost with the
//! body, the closed reference's in the same run, their ratio (the target:
//! at most 1.5), and the extra cost with the frame's body (the target: less
//! than with the step's), then the worst row.
//!
//! `PELAGE_BENCH_QUICK=1` runs the representative subset instead of the
//! whole corpus.

use glam::{DQuat, DVec3, Vec3};
use pelage::*;
use pelage_core::rng::{self, Purpose};
use pelage_core::Root;
use pelage_tests::animated::colliders;
use pelage_tests::corpus::{corpus, mesh_desc, representative, turned_about_centre, CorpusMesh};
use pelage_tests::creature::CreatureMesh;
use pelage_tests::measure::{frame, guides_desc, on_threads, stamp_roots, Frame, SimHandle};
use std::hint::black_box;
use std::time::Instant;

const GUIDES: u32 = 13_030;
const JOINTS: usize = 16;
const THREADS: u32 = 2;
/// Frames of the sway a run steps through.
const FRAMES: usize = 8;
/// Runs of each variant (each over every frame), interleaved with the
/// closed reference's.
const RUNS: usize = 5;
/// The head's size at scale 1 (the corpus head is about one unit across).
const UNIT: f64 = 1.0;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// What one mesh measured (medians, seconds).
#[derive(Clone, Copy, Debug)]
struct Costs {
    bare: f64,
    body: f64,
    frame_body: f64,
    set_colliders: f64,
    groomed: usize,
}

impl Costs {
    fn extra(&self) -> f64 {
        self.body - self.bare
    }

    fn frame_extra(&self) -> f64 {
        self.frame_body - self.bare
    }
}

/// Guides of `JOINTS` points on `roots`: leaving along the normal, combed
/// toward -y, each `size` times 0.05 to 0.15 long (by its root's id).
fn guides(mesh: &pelage_core::Mesh, roots: &[Root], size: f32) -> Vec<[f32; 3]> {
    let mut pts = Vec::with_capacity(roots.len() * JOINTS);
    for r in roots {
        let share = rng::to_unit(rng::hash(7, r.id as u64, Purpose::Uniform, 0));
        let length = size * (0.05 + 0.10 * share);
        let (f, u, v) = (r.face as usize, r.u, r.v);
        let (p, n) = (mesh.point(f, u, v), mesh.normal(f, u, v));
        let comb = (Vec3::NEG_Y - n * n.dot(Vec3::NEG_Y)).normalize_or_zero();
        let seg = length / (JOINTS - 1) as f32;
        let mut q = p;
        pts.push(q.into());
        for j in 1..JOINTS {
            let t = j as f32 / (JOINTS - 1) as f32;
            q += (n * (1.0 - 0.6 * t) + comb * (0.6 * t)).normalize() * seg;
            pts.push(q.into());
        }
    }
    pts
}

/// Frame `f` of the sway: the mesh turned about the vertical through its
/// bounds' centre and moved sideways, rigidly (in f64, rounded once).
fn swayed(m: &CreatureMesh, f: usize, size: f64) -> CreatureMesh {
    let phase = std::f64::consts::TAU * f as f64 / FRAMES as f64;
    let turn = DQuat::from_rotation_y(0.25 * phase.sin());
    let shift = DVec3::new(0.04 * size * phase.sin(), 0.02 * size * phase.cos(), 0.0);
    turned_about_centre(m, turn, shift)
}

/// A mesh's simulation, ready to step, and the frames of the sway.
struct Rig {
    sim: SimHandle,
    frames: Vec<Frame>,
    guides: usize,
    /// Samples of each variant: no body, the step's body, the frame's.
    times: [Vec<f64>; 3],
    set_colliders: Vec<f64>,
    groomed: usize,
}

impl Rig {
    /// The guides on `e`, `size` long at most 0.15 of it.
    fn new(e: &CorpusMesh, size: f64) -> Rig {
        let view = e.view();
        let roots = stamp_roots(view, GUIDES, 1);
        let points = guides(&view, &roots, size as f32);
        let rest = guides_desc(&roots, &points);
        let params = PelageSimParams {
            joints: JOINTS as u32,
            points_per_guide: JOINTS as u32,
            link_radius: (0.05 * size) as f32,
            ..pelage_sim_params_defaults()
        };
        let sim = SimHandle::new(&e.desc(), &rest, &params);
        // a frame copies its mesh: the swayed mesh is dropped once it has one
        let frames = (0..FRAMES)
            .map(|f| {
                let m = swayed(&e.mesh, f, size);
                frame(&mesh_desc(&m), &rest, JOINTS as u32, THREADS).unwrap()
            })
            .collect();
        Rig {
            sim,
            frames,
            guides: roots.len(),
            times: [vec![], vec![], vec![]],
            set_colliders: vec![],
            groomed: 0,
        }
    }

    /// Steps through the sway from rest with `variant`'s colliders: 0 no
    /// body, 1 the body the step builds, 2 the frame's body (set before
    /// each step, timed apart).
    fn run(&mut self, variant: usize) {
        assert_eq!(pelage_sim_reset(self.sim.sim), PelageStatus::Ok);
        let c = colliders(&[], variant != 0);
        for f in &self.frames {
            if variant == 2 {
                let t = Instant::now();
                let s = pelage_frame_set_colliders(f.0, &c, on_threads(THREADS));
                self.set_colliders.push(t.elapsed().as_secs_f64());
                assert_eq!(s, PelageStatus::Ok);
            }
            let mut info = PelageStepInfo { groomed_guides: 0 };
            let step = PelageStepParams {
                dt: 1.0 / 24.0,
                run: on_threads(THREADS),
                colliders: &c,
                ..pelage_step_params_defaults()
            };
            let t = Instant::now();
            let s = pelage_sim_step(self.sim.sim, f.0, &step, &mut info);
            self.times[variant].push(t.elapsed().as_secs_f64());
            assert_eq!(s, PelageStatus::Ok);
            if variant == 1 {
                self.groomed = self.groomed.max(info.groomed_guides);
            }
            if variant == 2 {
                pelage_frame_set_colliders(f.0, std::ptr::null(), on_threads(THREADS));
            }
        }
    }

    /// The medians.
    fn costs(&self) -> Costs {
        let [bare, body, frame_body] = self.times.clone().map(median);
        Costs {
            bare,
            body,
            frame_body,
            set_colliders: median(self.set_colliders.clone()),
            groomed: self.groomed,
        }
    }
}

/// Measures the step on `e` and on its closed reference, a run of each
/// variant on one then on the other, so both see the machine alike.
fn measure(e: &CorpusMesh, size: f64) -> (Costs, Costs, usize) {
    let closed = e.closed_reference();
    let mut rigs = [Rig::new(e, size), Rig::new(&closed, size)];
    for _ in 0..RUNS {
        for variant in 0..3 {
            for rig in &mut rigs {
                rig.run(variant);
            }
        }
    }
    black_box(&rigs[0].times);
    (rigs[0].costs(), rigs[1].costs(), rigs[0].guides)
}

fn main() {
    let quick = std::env::var_os("PELAGE_BENCH_QUICK").is_some();
    let meshes = if quick { representative() } else { corpus() };
    println!(
        "body collider cost on the corpus{}: ~{GUIDES} guides x {JOINTS} points, 0.05-0.15 of the head's size long, {THREADS} threads, a rigid sway of {FRAMES} frames; medians of {RUNS} runs",
        if quick { " (representative subset)" } else { "" }
    );
    println!();
    println!(
        "| mesh | tris | guides | step ms | + body ms | closed + body ms | ratio | + frame's body ms | frame's / step's | set_colliders ms | groomed |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let ms = |s: f64| s * 1e3;
    let (mut worst_ratio, mut worst_frame) = ((String::new(), 0.0f64), (String::new(), 0.0f64));
    for e in &meshes {
        let size = e.recipe.scale * UNIT;
        let (costs, closed, count) = measure(e, size);
        let ratio = costs.extra() / closed.extra();
        let frame_share = costs.frame_extra() / costs.extra();
        println!(
            "| {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.2} | {:.1} | {:.2} | {:.1} | {} |",
            e.name,
            e.mesh.triangle_count(),
            count,
            ms(costs.bare),
            ms(costs.extra()),
            ms(closed.extra()),
            ratio,
            ms(costs.frame_extra()),
            frame_share,
            ms(costs.set_colliders),
            costs.groomed,
        );
        if ratio > worst_ratio.1 {
            worst_ratio = (e.name.clone(), ratio);
        }
        if frame_share > worst_frame.1 {
            worst_frame = (e.name.clone(), frame_share);
        }
    }
    println!(
        "| **worst** | | | | | | {:.2} ({}) | | {:.2} ({}) | | |",
        worst_ratio.1, worst_ratio.0, worst_frame.1, worst_frame.0
    );
}
