//! Binds the gorilla-scale groom once and expands it repeatedly on one
//! thread (for profiling the per-frame path).
use pelage_core::arena::ArenaLayout;
use pelage_core::bind::{self, BindParams, StrandBinding};
use pelage_core::expand::{expand, EndPoints, ExpandParams, PreparedGuides};
use pelage_core::groom::{GroomMaps, StrandGroom};
use pelage_core::guides::{CvLayout, Guides};
use pelage_core::stamp::StampParams;
use pelage_core::{Arena, ScalarMap, Strided};
use pelage_tests::creature::default_creature;
use pelage_tests::measure::{combed_guides, mesh_view, stamp_vec};

fn main() {
    let m = default_creature();
    let mesh = mesh_view(&m);
    let stamp = |n, seed| {
        stamp_vec(
            mesh,
            &StampParams {
                target_count: n,
                seed,
                ..StampParams::default()
            },
        )
        .0
    };
    let groots = stamp(13_030, 1);
    let gpts = combed_guides(&mesh, &groots, 16, 0.06);
    let hairs = stamp(979_526, 2);
    let guides = Guides {
        roots: &groots,
        points: Strided::from_slice(&gpts),
        layout: CvLayout::Fixed(16),
    };
    let mut arena = vec![0u8; bind::required_bytes(groots.len())];
    let mut b = vec![StrandBinding::default(); hairs.len()];
    bind::bind(
        &mesh,
        &guides,
        &hairs,
        &BindParams::default(),
        &mut Arena::new(&mut arena),
        &mut b,
    )
    .unwrap();
    let mut g = vec![StrandGroom::default(); hairs.len()];
    let maps = GroomMaps {
        kink_amplitude: ScalarMap::Constant(0.03),
        clump: ScalarMap::Constant(0.2),
        ..GroomMaps::default()
    };
    maps.evaluate(&mesh, &hairs, 0, &mut g).unwrap();
    let params = ExpandParams {
        points_per_strand: 16,
        end_points: EndPoints::Pinned,
        orphan_length: 0.05,
    };
    let mut layout = ArenaLayout::new();
    PreparedGuides::layout(&mut layout, groots.len(), 16);
    let mut earena = vec![0u8; layout.bytes()];
    let mut out = vec![[0.0f32; 4]; hairs.len() * params.output_points()];
    let frames: usize = std::env::args().nth(1).map_or(10, |s| s.parse().unwrap());
    let t = std::time::Instant::now();
    for _ in 0..frames {
        let prepared =
            PreparedGuides::new(&mesh, &guides, 16, &mut Arena::new(&mut earena)).unwrap();
        expand(
            &mesh,
            &hairs,
            &b,
            &g,
            &prepared,
            &params,
            bytemuck::cast_slice_mut(&mut out),
            16,
        )
        .unwrap();
    }
    println!(
        "{:.1} ms per frame",
        t.elapsed().as_secs_f64() * 1e3 / frames as f64
    );
}
