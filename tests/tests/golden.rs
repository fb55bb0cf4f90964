//! Same bits as before: hashes of every stage's output on the test creature
//! (stamp, bind, groom maps, settle, expand at rest and on a warped pose),
//! recorded before the per-frame object and the split of `expand` (version
//! 0.5.0) and kept through every change since, until issue 30 changed the
//! stamp (the fill pass and the LOD steps move every root, and every stage
//! after it; the body's new inside test alone had kept every hash), and
//! again when the tile was grown coarse to fine with an order in each step
//! (0.8.0), and when the first radius was refitted so that stamps of 3K to
//! 10K roots land in one pass and the surplus of a stamp of up to 65,536
//! roots left by sample elimination (0.10.0), and when roots facing the
//! same air across a concave crease were spaced (0.12.0, issue 48). A
//! change that moves one bit of any output fails here; one that means to
//! must say so and record new hashes.

use pelage::*;
use pelage_core::Root;
use pelage_tests::creature::{default_creature, CreatureMesh};
use pelage_tests::measure::{groomed, guides_desc, mesh_desc, on_threads, ExpandCall, Groomed};

const CVS: usize = 12;

/// FNV-1a over the bytes of `data`.
fn hash<T: bytemuck::NoUninit>(data: &[T]) -> u64 {
    bytemuck::cast_slice::<T, u8>(data)
        .iter()
        .fold(0xcbf2_9ce4_8422_2325, |h, &b| {
            (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
        })
}

/// A smooth, non-rigid pose: the body sways and swells.
fn warp(p: [f32; 3]) -> [f32; 3] {
    [
        p[0] + 0.05 * libm::sinf(2.0 * p[1]),
        p[1] * 1.02,
        p[2] + 0.03 * libm::cosf(3.0 * p[0]),
    ]
}

fn expand(
    m: &CreatureMesh,
    guides: &PelageGuidesDesc,
    strands: &[Root],
    bindings: &[PelageStrandBinding],
    grooms: &[PelageStrandGroom],
) -> Vec<[f32; 4]> {
    let params = PelageExpandParams {
        run: on_threads(2),
        ..pelage_expand_params_defaults()
    };
    let mut per = 0usize;
    assert_eq!(pelage_expand_size(&params, &mut per), PelageStatus::Ok);
    let mut out = vec![[0.0f32; 4]; strands.len() * per];
    let call = ExpandCall {
        mesh: &mesh_desc(m),
        guides,
        strands,
        bindings,
        grooms,
        params: &params,
    };
    assert_eq!(call.run(&mut out, None), PelageStatus::Ok);
    out
}

#[test]
fn every_stage_gives_the_recorded_bits() {
    let m = default_creature();
    let mut maps = pelage_groom_maps_defaults();
    maps.kink_amplitude.constant = 0.05;
    maps.clump.constant = 0.3;
    maps.bend.constant = 0.1;
    maps.seed = 7;
    let mut g = groomed(&m, (13_030, CVS, 0.08), 100_000, &maps, 2);
    let groom_hash = hash(&g.grooms);
    let params = PelageExpandParams {
        run: on_threads(2),
        ..pelage_expand_params_defaults()
    };
    let settle = g.settle(&m, &params);
    // the settle hash means something only where settle changed grooms
    assert!(settle.lifted > 0, "{settle:?}");
    let Groomed {
        guide_roots,
        guide_points,
        strands,
        bindings,
        grooms,
        ..
    } = &g;
    let guides = g.guides();

    let rest = expand(&m, &guides, strands, bindings, grooms);
    let posed_mesh = CreatureMesh {
        positions: m.positions.iter().map(|&p| warp(p)).collect(),
        ..m.clone()
    };
    let posed_points: Vec<[f32; 3]> = guide_points.iter().map(|&p| warp(p)).collect();
    let posed = expand(
        &posed_mesh,
        &guides_desc(guide_roots, &posed_points),
        strands,
        bindings,
        grooms,
    );

    let got = [
        ("guide roots", hash(guide_roots)),
        ("strand roots", hash(strands)),
        ("bindings", hash(bindings)),
        ("groom maps", groom_hash),
        ("settled grooms", hash(grooms)),
        (
            "settle counts",
            hash(&[
                settle.lifted,
                settle.unclumped,
                settle.turned,
                settle.shortened,
            ]),
        ),
        ("rest curves", hash(&rest)),
        ("posed curves", hash(&posed)),
    ];
    for (what, h) in got {
        println!("(\"{what}\", {h:#018x}),");
    }
    let recorded = [
        ("guide roots", 0x2f1a20d649f3ffe3),
        ("strand roots", 0x61098483893e5aa4),
        ("bindings", 0x31031ea931c22829),
        ("groom maps", 0x7a58bbab91b418ec),
        ("settled grooms", 0x1abdaf92bc3e9fe5),
        ("settle counts", 0x0fd574c4e9835132),
        ("rest curves", 0x0189792a74148fba),
        ("posed curves", 0x5c66f693f46969a2),
    ];
    assert_eq!(got, recorded);
}
