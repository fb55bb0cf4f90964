//! The simulation state's restore on damaged and arbitrary bytes: never a
//! panic; on failure the simulation keeps its state (it saves the same
//! bytes again), on success its next step poses every point finite.
#![no_main]

mod scene;

use libfuzzer_sys::fuzz_target;
use pelage_core::collide::Colliders;
use pelage_core::dynamics::sim::{Sim, SimParams};
use pelage_core::guides::{CvLayout, Guides};
use pelage_core::{Arena, ArenaLayout, Mesh, Strided};
use std::cell::RefCell;

struct Fixture {
    sim: Sim<'static>,
    roots: Vec<pelage_core::Root>,
    /// The state after a few steps of a swinging plane.
    good: Vec<u8>,
}

fn fixture() -> Fixture {
    let (p, tri) = scene::grid(0.0);
    let mesh = Mesh::new(Strided::from_slice(&p), Strided::from_slice(&tri));
    let roots = scene::guide_roots();
    let points = scene::guides(&mesh, &roots, 0.0);
    let guides = Guides {
        roots: &roots,
        points: Strided::from_slice(&points),
        layout: CvLayout::Fixed(scene::POINTS),
    };
    let params = SimParams {
        joints: scene::POINTS,
        points: scene::POINTS,
        ..SimParams::default()
    };
    let mut layout = ArenaLayout::new();
    Sim::layout(&mut layout, p.len(), roots.len(), &params);
    // the simulation lives as long as the fuzzer: its memory is never freed
    let memory: &'static mut [u8] = vec![0u8; layout.bytes()].leak();
    let mut sim = Sim::new(mesh, &guides, &params, &mut Arena::new(memory)).unwrap();
    for f in 1..6 {
        step(&mut sim, &roots, f as f32 * 0.2);
    }
    let good = save(&sim);
    Fixture { sim, roots, good }
}

fn step(sim: &mut Sim, roots: &[pelage_core::Root], t: f32) {
    scene::with_frame(t, roots, |frame| {
        sim.step(frame, &Colliders::default(), 1.0 / 24.0).unwrap()
    });
}

fn save(sim: &Sim) -> Vec<u8> {
    let mut out = vec![0u8; sim.state_bytes()];
    sim.save(&mut out).unwrap();
    out
}

thread_local! {
    static FIXTURE: RefCell<Fixture> = RefCell::new(fixture());
}

fuzz_target!(|data: &[u8]| {
    FIXTURE.with_borrow_mut(|f| {
        let Some((&flags, edits)) = data.split_first() else {
            return;
        };
        let bytes = if flags & 1 == 1 {
            edits.to_vec()
        } else {
            // the good state with bytes overwritten at offsets the input
            // names, its checksum made anew when the input says so, so
            // that the checks past the checksum are reached
            let mut b = f.good.clone();
            for pair in edits.chunks_exact(3) {
                let at = u16::from_le_bytes([pair[0], pair[1]]) as usize % b.len();
                b[at] = pair[2];
            }
            if flags & 2 == 2 {
                let body = b.len() - 4;
                let crc = crc32fast::hash(&b[..body]).to_le_bytes();
                b[body..].copy_from_slice(&crc);
            }
            b
        };
        let before = save(&f.sim);
        match f.sim.restore(&bytes) {
            Ok(()) => {
                step(&mut f.sim, &f.roots, 1.3);
                for g in 0..f.sim.len() {
                    for k in 0..f.sim.points() {
                        let q = f.sim.posed(g, k);
                        assert!(q.is_finite(), "guide {g} point {k}: {q}");
                    }
                }
                f.sim.restore(&f.good).unwrap();
            }
            Err(_) => assert!(
                save(&f.sim) == before,
                "a refused state changed the simulation"
            ),
        }
    });
});
