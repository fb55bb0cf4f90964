//! The paper's Figure 5 experiment: one disk radius, three grayscale density
//! maps (white, a gradient, a dark map with black areas), black = half size.
//! The paper got 11,175 / 3,992 / 2,909 roots in 0.05-0.07 s each.
//!
//! Prints counts and times; asserts that the counts follow the maps: each
//! triangle scaled by s keeps s^2 of its roots, so the count of a map is the
//! white count times the area-weighted mean of s^2.

use pelage_core::stamp::StampParams;
use pelage_core::surface::map::{Texels, Texture};
use pelage_core::ScalarMap;
use pelage_tests::creature::{default_creature, figure5_maps, sample_texture};
use pelage_tests::measure::{mesh_view, stamp_vec};
use std::time::Instant;

const WHITE_TARGET: u32 = 11_175;
const TEX: (u32, u32) = (512, 256);

#[test]
fn figure5_density_maps() {
    let m = default_creature();
    let mesh = mesh_view(&m);
    let paper = StampParams {
        target_count: WHITE_TARGET,
        seed: 5,
        black_scale: 0.5,
        bald_below: 0.0,
        ..StampParams::default()
    };
    let (_, white) = stamp_vec(mesh, &paper);
    let fixed = StampParams {
        radius: white.radius,
        target_count: 0,
        ..paper
    };
    let mut counts = vec![];
    println!(
        "radius {:.5} (from {WHITE_TARGET} roots on white)",
        white.radius
    );
    println!(
        "{:>9} | {:>7} {:>9} {:>9} | {:>8}",
        "map", "roots", "expected", "ms", "paper"
    );
    for ((name, f), paper_count) in figure5_maps().into_iter().zip([11_175, 3_992, 2_909]) {
        let texels = sample_texture(TEX.0, TEX.1, f);
        let map = Texture {
            texels: Texels::U8(&texels),
            width: TEX.0 as usize,
            height: TEX.1 as usize,
            row_stride: TEX.0 as usize,
        };
        let params = StampParams {
            density: ScalarMap::Texture(map),
            ..fixed
        };
        let t = Instant::now();
        let (roots, _) = stamp_vec(mesh, &params);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        // the expected count: white count times the area-weighted mean of s^2
        let (mut a, mut a_s2) = (0.0f64, 0.0f64);
        for face in 0..mesh.triangle_count() {
            let d = params
                .density
                .sample(&mesh, face, 1.0 / 3.0, 1.0 / 3.0)
                .clamp(0.0, 1.0) as f64;
            let s = 0.5 + 0.5 * d;
            a += mesh.area(face) as f64;
            a_s2 += mesh.area(face) as f64 * s * s;
        }
        let expected = counts.first().copied().unwrap_or(roots.len()) as f64 * a_s2 / a;
        println!(
            "{name:>9} | {:>7} {:>9.0} {ms:>9.1} | {paper_count:>8}",
            roots.len(),
            expected
        );
        // graded maps cut the mesh into narrow bands of one density step,
        // where the fill's darts (near-maximal) pack a little denser than
        // the tile: up to 7% over the white count's proportion
        let err = (roots.len() as f64 - expected) / expected;
        assert!(
            err.abs() < 0.08,
            "{name}: {} roots, expected about {expected:.0}",
            roots.len()
        );
        counts.push(roots.len());
    }
    assert!(counts[0] > counts[1] && counts[1] > counts[2], "{counts:?}");
    assert!((counts[0] as f64 / WHITE_TARGET as f64 - 1.0).abs() < 0.05);
}
