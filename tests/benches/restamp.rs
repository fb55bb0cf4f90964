//! What re-stamping a mesh already analysed could save (issue 48, ask 8):
//! for each corpus mesh at 20,000 and 200,000 roots, the median of a whole
//! stamp, of the stamp's set-up before its first pass (faces, charts,
//! shells, the body, the burial of the skin, the first radius), and of
//! the part of that set-up a density edit leaves as it was (the hole rims
//! and the body). A stamp that kept those in a prepared mesh would take at
//! best the whole stamp less that part; the table gives that share of a
//! first stamp (the target: at most 0.40), then the worst row. Charts,
//! burial and the radius depend on the density (a chart ends at a density
//! step, the reach and lift scale with the local radius), and the passes
//! (placement, edge pass, fill, ranks) on every root.
//!
//! `PELAGE_CORPUS=representative` for the 4 coarse meshes only.

use pelage_core::arena::Arena;
use pelage_core::stamp::{self, Stamper};
use pelage_core::surface::body::{Body, BodyPlan, Rim};
use pelage_core::StampParams;
use pelage_tests::corpus::{self, report::median};
use std::hint::black_box;
use std::time::{Duration, Instant};

/// Runs timed per figure.
const RUNS: usize = 5;

fn timed(mut run: impl FnMut()) -> Duration {
    median(
        (0..RUNS)
            .map(|_| {
                let t = Instant::now();
                run();
                t.elapsed()
            })
            .collect(),
    )
}

fn main() {
    let list = match std::env::var("PELAGE_CORPUS").as_deref() {
        Ok("representative") => corpus::representative(),
        _ => corpus::corpus(),
    };
    println!("## What a prepared mesh could save of a re-stamp (1 thread)\n");
    println!("| mesh | tris | roots | stamp ms | set-up ms | rims + body ms | re-stamp at best / stamp |");
    println!("|---|---|---|---|---|---|---|");
    let mut worst = 0.0f64;
    for e in &list {
        let mesh = e.view();
        for target in [20_000u32, 200_000] {
            let params = StampParams {
                target_count: target,
                seed: 3,
                ..StampParams::default()
            };
            let mut memory = vec![0u8; stamp::required_bytes(&mesh, &params).expect("size")];
            let mut roots = vec![
                pelage_core::Root::default();
                stamp::max_roots(&mesh, &params).expect("max roots")
            ];
            let whole = timed(|| {
                let arena = &mut Arena::new(&mut memory);
                black_box(stamp::stamp(mesh, &params, arena, &mut roots).expect("stamp"));
            });
            let setup = timed(|| {
                let arena = &mut Arena::new(&mut memory);
                black_box(
                    Stamper::new(mesh, &params, arena)
                        .expect("set-up")
                        .is_some(),
                );
            });
            let kept = timed(|| {
                let arena = &mut Arena::new(&mut memory);
                let rim = Rim::new(&mesh, arena).expect("rims");
                let plan = BodyPlan::of(&mesh, &rim).expect("plan");
                black_box(
                    Body::build(&plan, &mesh, &rim, arena)
                        .expect("body")
                        .contains(glam::Vec3::ZERO),
                );
            });
            let ms = |d: Duration| d.as_secs_f64() * 1e3;
            let best = (ms(whole) - ms(kept)) / ms(whole);
            worst = worst.max(best);
            println!(
                "| {} | {} | {target} | {:.1} | {:.1} | {:.1} | {best:.2} |",
                e.name,
                mesh.triangle_count(),
                ms(whole),
                ms(setup),
                ms(kept)
            );
        }
    }
    println!("| worst | | | | | | {worst:.2} |");
}
