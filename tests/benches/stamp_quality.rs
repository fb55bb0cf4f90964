//! Stamp quality benchmark (issue 30): the test creature and the head
//! (open eye sockets, eyeballs, horn and ears as intersecting shells), at
//! 10K, 100K and 1M roots, constant density 1. Each stamp is shown next to
//! two references of the same count measured in the same run: `darts`, a
//! dart-throwing Poisson set (`quality::dart_throwing`, whose 25% and 50%
//! rank prefixes are dart sets of their own size), and `random`, uniform
//! random roots by area (ranked at random).
//!
//! Every distance is in units of r_hex = sqrt(2A / (sqrt(3) N)), same-side
//! pairs only (see `pelage_tests::quality`); A and the empty space leave out
//! buried skin (inside the body with its holes capped), where pelage grows
//! no hair:
//! - r/rhex: the set's promised spacing (the stamp's `StampReport::radius`,
//!   the darts' last spacing; random sets promise nothing and are checked
//!   against the stamp's);
//! - empty: distance from the skin to its nearest root over 32 samples per
//!   root, 99th and 99.9th percentiles and the largest;
//! - NN: nearest-neighbour distance per root, min, mean and CV;
//! - close (x): pairs closer than r/rhex, and how many of them join two
//!   shells;
//! - P50, P25: NN CV and min of the roots ranked in the first 50% and 25%,
//!   in units of their own r_hex;
//! - ms: making the set (the stamp's median over runs with its memory
//!   sized once, as a host does); meas s: the measures of the row;
//! - worst hole: the shell and point of the largest empty distance.

use pelage_core::stamp::{self, StampParams};
use pelage_core::surface::body::Body;
use pelage_core::{Arena, Root};
use pelage_tests::creature::{default_creature, CreatureMesh};
use pelage_tests::head::head_with_parts;
use pelage_tests::measure::{mesh_view, uniform_roots};
use pelage_tests::quality::{dart_throwing, empty_space, neighbours, prefix, Skin};
use std::time::Instant;

/// Surface samples per root of the empty-space measure.
const SAMPLES_PER_ROOT: usize = 32;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Prints one table row: the measures of `roots` checked at `radius`.
fn row(skin: &Skin, shells: &[u32], set: &str, roots: &[Root], radius: f32, ms: f64) {
    let t = Instant::now();
    let rh = skin.r_hex(roots.len());
    let e = empty_space(skin, roots, SAMPLES_PER_ROOT, 7);
    let n = neighbours(skin, roots, radius);
    let [p50, p25] = [0.5, 0.25].map(|f| prefix(skin, roots, f));
    let (face, at) = e.worst;
    println!(
        "{:>7} {:>8} {:>6.3} | {:>5.3} {:>5.3} {:>5.3} | {:>5.3} {:>5.3} {:>5.3} | {:>7} ({:>5}) | {:>5.3} {:>5.3} | {:>5.3} {:>5.3} | {:>8.1} {:>6.1} | {} ({:.2}, {:.2}, {:.2})",
        set,
        roots.len(),
        radius / rh,
        e.p99,
        e.p999,
        e.max,
        n.min,
        n.mean,
        n.cv,
        n.close_pairs,
        n.close_across_shells,
        p50.cv,
        p50.min,
        p25.cv,
        p25.min,
        ms,
        t.elapsed().as_secs_f64(),
        shells[face],
        at.x,
        at.y,
        at.z,
    );
}

fn bench(name: &str, legend: &str, m: &CreatureMesh, shells: &[u32]) {
    let mesh = mesh_view(m);
    // constant density 1: every face grows fur, except where it is buried
    // in the body (pelage's rule)
    let mut body_memory = vec![0u8; Body::required_bytes(&mesh).unwrap()];
    let body = Body::new(&mesh, &mut Arena::new(&mut body_memory)).unwrap();
    let skin = Skin::unburied(mesh, shells, |_| true, &body);
    let count = shells.iter().max().map_or(0, |s| s + 1);
    println!(
        "\n{name}: {} triangles, {count} shells, area {:.3}{legend}",
        mesh.triangle_count(),
        skin.area()
    );
    println!(
        "{:>7} {:>8} {:>6} | {:>17} | {:>17} | {:>15} | {:>11} | {:>11} | {:>8} {:>6}",
        "set",
        "count",
        "r/rhex",
        "empty 99 99.9 max",
        "NN min mean CV",
        "close (x)",
        "P50 CV min",
        "P25 CV min",
        "ms",
        "meas s"
    );
    for target in [10_000u32, 100_000, 1_000_000] {
        println!("target {target}");
        let params = StampParams {
            target_count: target,
            seed: 1,
            ..StampParams::default()
        };
        let runs = if target >= 1_000_000 { 3 } else { 5 };
        let mut arena = vec![0u8; stamp::required_bytes(&mesh, &params).unwrap()];
        let mut out = vec![Root::default(); stamp::max_roots(&mesh, &params).unwrap()];
        let mut times = vec![];
        let mut result = None;
        for _ in 0..runs {
            let t = Instant::now();
            result =
                Some(stamp::stamp(mesh, &params, &mut Arena::new(&mut arena), &mut out).unwrap());
            times.push(t.elapsed().as_secs_f64());
        }
        let (n, report) = result.unwrap();
        let roots = &out[..n];
        row(
            &skin,
            shells,
            "stamp",
            roots,
            report.radius,
            median(times) * 1e3,
        );

        let t = Instant::now();
        let darts = dart_throwing(&skin, n, 1);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        row(&skin, shells, "darts", &darts.roots, darts.radius, ms);

        let t = Instant::now();
        let random = uniform_roots(&mesh, n, 1);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        row(&skin, shells, "random", &random, report.radius, ms);
    }
}

fn main() {
    let creature = default_creature();
    bench(
        "creature",
        "",
        &creature,
        &vec![0; creature.triangle_count()],
    );
    let (head, parts) = head_with_parts();
    let legend = " (shells: 0 head, 1-2 eyes, 3 horn, 4-5 ears)";
    bench("head", legend, &head, &parts.shells());
}
