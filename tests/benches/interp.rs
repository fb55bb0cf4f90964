//! Interpolation benchmark at the paper's gorilla scale (Figure 1): the
//! ~65K-triangle creature, 13,030 guides x 16 points, 979,526 render hairs x
//! 16 points (18 with pinned ends). Reports bind time, and expand time per
//! frame at 1 and 2 threads through the C API (`pelage_expand`, which checks
//! every strand record each call, and `pelage_groom_expand` on a groom whose
//! records were checked once), next to the time to simply
//! write the same number of output bytes with the same threads (the
//! memory-bandwidth floor), measured in the same run.

use pelage::*;
use pelage_core::guides::{CvLayout, Guides};
use pelage_core::interp::bind::{self, BindParams, StrandBinding};
use pelage_core::interp::expand::{self, EndPoints, ExpandParams, PreparedGuides, Strands};
use pelage_core::interp::groom::{GroomMaps, StrandGroom};
use pelage_core::{Arena, ArenaLayout, Mesh, Root, ScalarMap, Strided};
use pelage_tests::creature::default_creature;
use pelage_tests::measure::{
    combed_guides, guides_desc, mesh_desc, mesh_view, stamp_roots, ExpandCall,
};
use std::hint::black_box;
use std::time::Instant;

const GUIDES: u32 = 13_030;
const HAIRS: u32 = 979_526;
const CVS: usize = 16;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn time(runs: usize, mut f: impl FnMut()) -> f64 {
    median(
        (0..runs)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64()
            })
            .collect(),
    )
}

/// Writes `out` with a cheap per-element pattern over `threads` threads.
fn write_floor(out: &mut [[f32; 4]], threads: usize) {
    let chunk = out.len().div_ceil(threads);
    std::thread::scope(|s| {
        for (t, part) in out.chunks_mut(chunk).enumerate() {
            s.spawn(move || {
                for (i, p) in part.iter_mut().enumerate() {
                    let x = (t * chunk + i) as f32;
                    *p = [x, x, x, 0.001];
                }
            });
        }
    });
}

fn main() {
    let m = default_creature();
    let mesh = mesh_view(&m);
    let guide_roots = stamp_roots(mesh, GUIDES, 1);
    let guide_points = combed_guides(&mesh, &guide_roots, CVS, 0.06);
    let hairs: Vec<Root> = {
        let mut h = stamp_roots(mesh, HAIRS + HAIRS / 50, 2);
        h.retain(|r| r.rank < HAIRS);
        h
    };
    println!(
        "creature: {} triangles; {} guides x {CVS} points; {} hairs",
        m.triangles.len(),
        guide_roots.len(),
        hairs.len()
    );

    let guides = Guides {
        roots: &guide_roots,
        points: Strided::from_slice(&guide_points),
        layout: CvLayout::Fixed(CVS),
    };
    let params = BindParams::default();
    let mut arena = vec![0u8; bind::required_bytes(&mesh, guide_roots.len()).unwrap()];
    let mut bindings = vec![StrandBinding::default(); hairs.len()];
    let t_bind = time(3, || {
        bind::bind(
            &mesh,
            &guides,
            &hairs,
            &params,
            &mut Arena::new(&mut arena),
            &mut bindings,
        )
        .unwrap();
    });
    let mut grooms = vec![StrandGroom::default(); hairs.len()];
    let maps = GroomMaps {
        kink_amplitude: ScalarMap::Constant(0.03),
        clump: ScalarMap::Constant(0.2),
        ..GroomMaps::default()
    };
    let t_groom = time(3, || maps.evaluate(&mesh, &hairs, 0, &mut grooms).unwrap());

    let desc = mesh_desc(&m);
    let gdesc = guides_desc(&guide_roots, &guide_points);
    let mut ep = pelage_expand_params_defaults();
    ep.points_per_strand = CVS as u32;
    let (mut bytes, mut per) = (0, 0);
    assert_eq!(
        pelage_expand_query(
            guide_roots.len(),
            m.positions.len(),
            &ep,
            &mut bytes,
            &mut per
        ),
        PelageStatus::Ok
    );
    let mut earena = vec![0u8; bytes];
    let mut out = vec![[0.0f32; 4]; hairs.len() * per];
    let mb = (out.len() * 16) as f64 / 1e6;
    println!("bind: {:.1} ms ({:.2e} hairs/s); groom maps: {:.1} ms; output {mb:.0} MB per frame ({per} points per hair)", t_bind * 1e3, hairs.len() as f64 / t_bind, t_groom * 1e3);
    println!(
        "{:>21} {:>7} | {:>9} {:>8} {:>11} | {:>13} {:>9} | {:>8}",
        "call", "threads", "expand ms", "frames/s", "hairs/s", "write-floor ms", "GB/s", "ratio"
    );
    let (binds, groom_records) = (
        bytemuck::cast_slice(&bindings),
        bytemuck::cast_slice(&grooms),
    );
    let mut handle: PelageGroom = std::ptr::null_mut();
    assert_eq!(
        pelage_groom_new(
            bytemuck::cast_slice(&hairs).as_ptr(),
            binds.as_ptr(),
            groom_records.as_ptr(),
            hairs.len(),
            &mut handle,
        ),
        PelageStatus::Ok
    );
    for threads in [1u32, 2] {
        ep.thread_count = threads;
        let t_floor = time(7, || {
            write_floor(&mut out, threads as usize);
            black_box(&out);
        });
        let call = ExpandCall {
            mesh: &desc,
            guides: &gdesc,
            strands: &hairs,
            bindings: binds,
            grooms: groom_records,
            params: &ep,
        };
        let t_expand = time(7, || {
            let s = call.run(&mut earena, &mut out, None);
            assert_eq!(s, PelageStatus::Ok);
            black_box(&out);
        });
        // a groom kept across frames: its records were checked once
        let t_groom = time(7, || {
            let s = pelage_groom_expand(
                handle,
                &desc,
                &gdesc,
                0,
                hairs.len(),
                &ep,
                earena.as_mut_ptr().cast(),
                earena.len(),
                out.as_mut_ptr().cast(),
                16,
                out.len(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            );
            assert_eq!(s, PelageStatus::Ok);
            black_box(&out);
        });
        for (name, t) in [
            ("pelage_expand", t_expand),
            ("pelage_groom_expand", t_groom),
        ] {
            println!(
                "{name:>21} {:>7} | {:>9.1} {:>8.1} {:>11.3e} | {:>13.1} {:>9.2} | {:>7.2}x",
                threads,
                t * 1e3,
                1.0 / t,
                hairs.len() as f64 / t,
                t_floor * 1e3,
                mb / 1e3 / t_floor,
                t / t_floor
            );
        }
    }
    pelage_groom_free(handle);
    println!("ratio = expand time / time to write the same bytes with the same threads (the bandwidth floor)");
    stages(&mesh, &guides, &hairs, &bindings, &grooms, &ep, &mut out);
    println!("paper: 2 frames/s with full interpolation (979,526 hairs)");
}

/// Where one thread's frame goes, through the core: preparing the posed
/// guides, validating the strands (every frame, so that nothing is written
/// on bad input), and the expansion kernel itself.
fn stages(
    mesh: &Mesh,
    guides: &Guides,
    hairs: &[Root],
    bindings: &[StrandBinding],
    grooms: &[StrandGroom],
    ep: &PelageExpandParams,
    out: &mut [[f32; 4]],
) {
    // the same work as the C API rows above
    assert_eq!(ep.end_points, PelageEndPoints::Pinned as u32);
    let params = ExpandParams {
        points_per_strand: ep.points_per_strand as usize,
        end_points: EndPoints::Pinned,
        orphan_length: ep.orphan_length,
    };
    let mut layout = ArenaLayout::new();
    PreparedGuides::layout(&mut layout, mesh.positions.len(), guides.len(), CVS);
    let mut arena = vec![0u8; layout.bytes()];
    let t_prepare = time(7, || {
        black_box(PreparedGuides::new(mesh, guides, CVS, &mut Arena::new(&mut arena)).unwrap());
    });
    let prepared = PreparedGuides::new(mesh, guides, CVS, &mut Arena::new(&mut arena)).unwrap();
    let strands = Strands {
        roots: hairs,
        bindings,
        grooms,
    };
    let t_check = time(7, || {
        expand::check_strands(mesh, &strands, &prepared).unwrap();
    });
    let bytes: &mut [u8] = bytemuck::cast_slice_mut(out);
    let t_kernel = time(7, || {
        kernel(mesh, &strands, &prepared, &params, bytes);
        black_box(&bytes);
    });
    println!(
        "1 thread, core stages: prepare guides {:.1} ms, check strands {:.1} ms, expand kernel{} {:.1} ms ({:.0} ns per hair)",
        t_prepare * 1e3,
        t_check * 1e3,
        if avx2() { " (AVX2)" } else { "" },
        t_kernel * 1e3,
        t_kernel * 1e9 / hairs.len() as f64
    );
}

fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    return std::is_x86_feature_detected!("avx2");
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// The expansion kernel the C API runs: its AVX2 build where the CPU has it.
fn kernel(
    mesh: &Mesh,
    strands: &Strands,
    prepared: &PreparedGuides,
    params: &ExpandParams,
    out: &mut [u8],
) {
    #[cfg(target_arch = "x86_64")]
    if avx2() {
        // SAFETY: the CPU has AVX2.
        unsafe { expand::expand_checked_avx2(mesh, strands, prepared, params, out, 16) };
        return;
    }
    expand::expand_checked(mesh, strands, prepared, params, out, 16);
}
