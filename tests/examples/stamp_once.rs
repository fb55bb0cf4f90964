//! Stamps the creature once at a given count (for profiling).
use pelage_core::stamp::StampParams;
use pelage_tests::creature::default_creature;
use pelage_tests::measure::{mesh_view, stamp_vec};
fn main() {
    let n: u32 = std::env::args()
        .nth(1)
        .map_or(1_000_000, |s| s.parse().unwrap());
    let creature = default_creature();
    let mesh = mesh_view(&creature);
    let t = std::time::Instant::now();
    let (roots, report) = stamp_vec(
        mesh,
        &StampParams {
            target_count: n,
            seed: 1,
            ..StampParams::default()
        },
    );
    println!("{} roots in {:?} {:?}", roots.len(), t.elapsed(), report);
}
