//! Stamping benchmark: 10K, 100K and 1M roots on the ~65K-triangle creature,
//! next to uniform random area-weighted sampling measured in the same run.
//!
//! Spacing quality is the minimum and mean nearest-neighbour distance divided
//! by r_hex = sqrt(2A / (sqrt(3) N)), the spacing of a perfect hexagonal
//! lattice with the same count (1.0 is the unreachable ideal).
//!
//! Stamp times are of `stamp::stamp` with its arena and root buffer sized
//! once up front and reused, as a host does.

use pelage_core::stamp::{self, StampParams};
use pelage_core::{Arena, Root};
use pelage_tests::creature::default_creature;
use pelage_tests::measure::{mesh_view, r_hex, root_points, spacing, uniform_roots};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let creature = default_creature();
    let mesh = mesh_view(&creature);
    let area = mesh.validate().unwrap().area;
    println!(
        "creature: {} triangles, area {:.3}",
        mesh.triangle_count(),
        area
    );
    println!(
        "{:>9} | {:>10} {:>11} {:>8} {:>6} {:>9} {:>9} | {:>10} {:>9} {:>9} | {:>6}",
        "target",
        "stamp ms",
        "roots/s",
        "count",
        "passes",
        "min/rhex",
        "mean/rhex",
        "uniform ms",
        "min/rhex",
        "mean/rhex",
        "speed"
    );
    for target in [10_000u32, 100_000, 1_000_000] {
        let params = StampParams {
            target_count: target,
            seed: 1,
            ..StampParams::default()
        };
        let runs = if target >= 1_000_000 { 9 } else { 11 };
        // a host sizes the memory once and reuses it every call
        let mut arena = vec![0u8; stamp::required_bytes(&mesh, &params).unwrap()];
        let mut out = vec![Root::default(); stamp::max_roots(&mesh, &params).unwrap()];
        // each run times both, one after the other, so that a slow spell of
        // the machine slows both and the ratio of a run stays fair
        let (mut stamp_times, mut uniform_times, mut ratios) = (vec![], vec![], vec![]);
        let (mut result, mut uniform) = (None, vec![]);
        for _ in 0..runs {
            let t = Instant::now();
            let r = stamp::stamp(mesh, &params, &mut Arena::new(&mut arena), &mut out).unwrap();
            let t_stamp = t.elapsed().as_secs_f64();
            let t = Instant::now();
            uniform = uniform_roots(&mesh, r.0, 1);
            let t_uniform = t.elapsed().as_secs_f64();
            stamp_times.push(t_stamp);
            uniform_times.push(t_uniform);
            ratios.push(t_stamp / t_uniform);
            result = Some(r);
        }
        let (n, report) = result.unwrap();
        let roots = &out[..n];
        let (t_stamp, t_uniform) = (median(stamp_times), median(uniform_times));
        let rh = r_hex(area, roots.len());
        let s = spacing(&root_points(&mesh, roots), 4.0 * rh);
        let u = spacing(&root_points(&mesh, &uniform), 4.0 * rh);
        println!(
            "{:>9} | {:>10.2} {:>11.3e} {:>+7.2}% {:>6} {:>9.3} {:>9.3} | {:>10.2} {:>9.3} {:>9.3} | {:>5.1}x",
            target,
            t_stamp * 1e3,
            roots.len() as f64 / t_stamp,
            100.0 * (roots.len() as f64 - target as f64) / target as f64,
            report.passes,
            s.min / rh,
            s.mean / rh,
            t_uniform * 1e3,
            u.min / rh,
            u.mean / rh,
            median(ratios),
        );
    }
    println!("times are medians; speed = median over runs of stamp time / uniform random time (same count, timed back to back)");
}
