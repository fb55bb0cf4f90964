//! Interpolation benchmark at the paper's gorilla scale (Figure 1): the
//! ~65K-triangle creature, 13,030 guides x 16 points, 979,526 render hairs x
//! 16 points (18 with pinned ends). Reports bind time, and the time per
//! frame at 1 and 2 threads through the C API (the frame made, then
//! `pelage_expand`, which checks every strand record each call, or
//! `pelage_groom_expand` on a groom whose records were checked once, in one
//! call or as 500 patches spread over the host's threads), next to the time
//! to simply write the same number of output bytes with the same threads
//! (the memory-bandwidth floor), measured in the same run.

use pelage::*;
use pelage_core::guides::{CvLayout, Guides};
use pelage_core::interp::bind::{self, BindParams, StrandBinding};
use pelage_core::interp::expand::ExpandJob;
use pelage_core::interp::groom::{GroomMaps, StrandGroom};
use pelage_core::interp::posed::PosedFrame;
use pelage_core::interp::strand::{EndPoints, ExpandParams};
use pelage_core::interp::strands::{StrandBounds, Strands};
use pelage_core::{Arena, ArenaLayout, Mesh, Root, ScalarMap, Strided};
use pelage_tests::creature::default_creature;
use pelage_tests::measure::{
    combed_guides, curves_desc, frame, groom_handle, guides_desc, mesh_desc, mesh_view, on_threads,
    stamp_roots, ExpandCall, Frame,
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
    let mut per = 0;
    assert_eq!(pelage_expand_size(&ep, &mut per), PelageStatus::Ok);
    let mut out = vec![[0.0f32; 4]; hairs.len() * per];
    let mb = (out.len() * 16) as f64 / 1e6;
    println!("bind: {:.1} ms ({:.2e} hairs/s); groom maps: {:.1} ms; output {mb:.0} MB per frame ({per} points per hair)", t_bind * 1e3, hairs.len() as f64 / t_bind, t_groom * 1e3);
    println!("every row is one frame: the frame (mesh copied and checked, tangents, posed guides) made, then the hairs expanded");
    println!(
        "{:>28} {:>7} | {:>9} {:>8} {:>11} | {:>13} {:>9} | {:>8}",
        "call", "threads", "frame ms", "frames/s", "hairs/s", "write-floor ms", "GB/s", "ratio"
    );
    let (binds, groom_records) = (
        bytemuck::cast_slice(&bindings),
        bytemuck::cast_slice(&grooms),
    );
    let handle = groom_handle(&hairs, binds, groom_records);
    for threads in [1u32, 2] {
        ep.run.thread_count = threads;
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
            assert_eq!(call.run(&mut out, None), PelageStatus::Ok);
            black_box(&out);
        });
        // a groom kept across frames: its records were checked once
        let t_groom = time(7, || {
            let f = frame(&desc, &gdesc, CVS as u32, threads).unwrap();
            let curves = curves_desc(&mut out, None);
            let s = pelage_groom_expand(handle, f.0, 0, hairs.len(), &ep, &curves);
            assert_eq!(s, PelageStatus::Ok);
            black_box(&out);
        });
        // a renderer: the frame made once, then 500 patches expanded with
        // thread_count 1 each, the host's threads taking patches as they
        // free up
        let t_patches = time(7, || {
            let f = frame(&desc, &gdesc, CVS as u32, threads).unwrap();
            patches(handle, &f, &mut out, per, threads as usize);
            black_box(&out);
        });
        for (name, t) in [
            ("pelage_expand", t_expand),
            ("pelage_groom_expand", t_groom),
            ("500 patches (groom_expand)", t_patches),
        ] {
            println!(
                "{name:>28} {:>7} | {:>9.1} {:>8.1} {:>11.3e} | {:>13.1} {:>9.2} | {:>7.2}x",
                threads,
                t * 1e3,
                1.0 / t,
                hairs.len() as f64 / t,
                t_floor * 1e3,
                mb / 1e3 / t_floor,
                t / t_floor
            );
        }
        println!(
            "{:>28} {:>7} | 500 patches / one call: {:.3}",
            "",
            threads,
            t_patches / t_groom
        );
    }
    edits(handle, &m, &guide_roots, &gdesc, &hairs, &ep, &mut out);
    pelage_groom_free(handle);
    println!("ratio = frame time / time to write the same bytes with the same threads (the bandwidth floor)");
    stages(&mesh, &guides, &hairs, &bindings, &grooms, &ep, &mut out);
    println!("paper: 2 frames/s with full interpolation (979,526 hairs)");
}

/// The per-frame cost of the strand edits (paper 3.3) at 2 threads: every
/// hair cut (trimming), and a mask over the body's lowest tenth of the
/// hairs pushed out
/// of the body and 16 capsules, against the plain expansion.
fn edits(
    handle: PelageGroom,
    m: &pelage_tests::creature::CreatureMesh,
    guide_roots: &[Root],
    gdesc: &PelageGuidesDesc,
    hairs: &[Root],
    ep: &PelageExpandParams,
    out: &mut [[f32; 4]],
) {
    use pelage_tests::animated::{capsules, colliders};
    let ep = PelageExpandParams {
        run: on_threads(2),
        ..*ep
    };
    let desc = mesh_desc(m);
    // the lowest tenth of the hairs, as a map over the body
    let skin = mesh_view(m);
    let mut ys: Vec<f32> = hairs
        .iter()
        .map(|r| skin.point(r.face as usize, r.u, r.v).y)
        .collect();
    ys.sort_by(f32::total_cmp);
    let low = ys[ys.len() / 10];
    let values: Vec<f32> = m
        .positions
        .iter()
        .map(|p| (p[1] < low) as u32 as f32)
        .collect();
    let map = PelageMap {
        kind: PelageMapKind::PerVertex as u32,
        constant: 0.0,
        data: values.as_ptr().cast(),
        width: 0,
        height: 0,
        stride: 4,
    };
    let mut mask = vec![0u8; hairs.len()];
    let roots: &[PelageRoot] = bytemuck::cast_slice(hairs);
    let s = pelage_map_mask(
        &desc,
        &map,
        roots.as_ptr(),
        hairs.len(),
        0.5,
        mask.as_mut_ptr(),
    );
    assert_eq!(s, PelageStatus::Ok);
    let masked = mask.iter().filter(|&&v| v != 0).count();
    let lengths = vec![(PELAGE_TRIM_WHOLE / 5) * 3; hairs.len()];
    let caps = capsules(m, guide_roots, 0);
    let col = colliders(&caps, true);
    let run = |edits: Option<PelageStrandEdits>, set: bool, out: &mut [[f32; 4]]| {
        let f = frame(&desc, gdesc, CVS as u32, 2).unwrap();
        if set {
            assert_eq!(
                pelage_frame_set_colliders(f.0, &col, on_threads(1)),
                PelageStatus::Ok
            );
        }
        let curves = curves_desc(out, None);
        let e = edits.as_ref().map_or(std::ptr::null(), |e| e as *const _);
        let s = pelage_groom_expand_edited(handle, f.0, 0, hairs.len(), e, &ep, &curves);
        assert_eq!(s, PelageStatus::Ok);
        black_box(&*out);
    };
    let plain = time(7, || run(None, false, out));
    let colliders_only = time(7, || run(None, true, out));
    let cut = PelageStrandEdits {
        lengths: lengths.as_ptr(),
        push_mask: std::ptr::null(),
    };
    let t_cut = time(7, || run(Some(cut), false, out));
    let push = PelageStrandEdits {
        lengths: std::ptr::null(),
        push_mask: mask.as_ptr(),
    };
    let t_push = time(7, || run(Some(push), true, out));
    println!(
        "strand edits, 2 threads, one frame each (frame made, expanded); {masked} hairs ({:.1}%) masked",
        100.0 * masked as f64 / hairs.len() as f64
    );
    println!("{:>44} | {:>9} | {:>12}", "", "frame ms", "over plain");
    for (name, t) in [
        ("plain pelage_groom_expand_edited", plain),
        (
            "+ pelage_frame_set_colliders (body, 16 caps)",
            colliders_only,
        ),
        ("every hair cut (trim lengths)", t_cut),
        ("colliders set, masked hairs pushed out", t_push),
    ] {
        println!("{name:>44} | {:>9.1} | {:>11.2}x", t * 1e3, t / plain);
    }
}

/// Patches of the render procedural: contiguous strand ranges.
const PATCHES: usize = 500;

/// Expands `handle`'s strands on `frame` as [`PATCHES`] ranges, each one
/// `pelage_groom_expand` call on one thread, spread over `threads` host
/// threads that take the next patch as they free up.
fn patches(handle: PelageGroom, frame: &Frame, out: &mut [[f32; 4]], per: usize, threads: usize) {
    let n = out.len() / per;
    let next = std::sync::atomic::AtomicUsize::new(0);
    // each patch's part of the output, handed out with the patch
    let mut parts: Vec<Option<&mut [[f32; 4]]>> = Vec::with_capacity(PATCHES);
    let mut rest = out;
    for p in 0..PATCHES {
        let len = ((p + 1) * n / PATCHES - p * n / PATCHES) * per;
        let (mine, tail) = std::mem::take(&mut rest).split_at_mut(len);
        parts.push(Some(mine));
        rest = tail;
    }
    let parts = std::sync::Mutex::new(parts);
    let (handle, frame) = (handle as usize, frame.0 as usize);
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| loop {
                let params = PelageExpandParams {
                    points_per_strand: CVS as u32,
                    ..pelage_expand_params_defaults()
                };
                let p = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if p >= PATCHES {
                    break;
                }
                let part = parts.lock().unwrap()[p].take().unwrap();
                let first = p * n / PATCHES;
                let curves = curves_desc(part, None);
                let count = curves.point_capacity / per;
                let s = pelage_groom_expand(
                    handle as PelageGroom,
                    frame as PelageFrame,
                    first,
                    count,
                    &params,
                    &curves,
                );
                assert_eq!(s, PelageStatus::Ok);
            });
        }
    });
}

/// Where one thread's frame goes, through the core: preparing the posed
/// frame, checking the strand records (what `pelage_expand` does every
/// call and `pelage_groom_new` once), and the expansion kernel itself.
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
        width_scale: 1.0,
    };
    let mut layout = ArenaLayout::new();
    PosedFrame::layout(&mut layout, mesh.positions.len(), guides.len(), CVS);
    let mut arena = vec![0u8; layout.bytes()];
    let t_prepare = time(7, || {
        black_box(
            PosedFrame::with_guides(*mesh, guides, CVS, &mut Arena::new(&mut arena)).unwrap(),
        );
    });
    let frame = PosedFrame::with_guides(*mesh, guides, CVS, &mut Arena::new(&mut arena)).unwrap();
    let strands = Strands {
        roots: hairs,
        bindings,
        grooms,
    };
    let t_check = time(7, || {
        black_box(StrandBounds::new(&strands).unwrap());
    });
    let bounds = StrandBounds::new(&strands).unwrap();
    let bytes: &mut [u8] = bytemuck::cast_slice_mut(out);
    let job = ExpandJob::new(&frame, strands, &bounds, &params, bytes.len(), 16).unwrap();
    let t_kernel = time(7, || {
        kernel(&job, bytes);
        black_box(&bytes);
    });
    println!(
        "1 thread, core stages: prepare frame {:.1} ms, check strand records {:.1} ms, expand kernel{} {:.1} ms ({:.0} ns per hair)",
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
fn kernel(job: &ExpandJob, out: &mut [u8]) {
    #[cfg(target_arch = "x86_64")]
    if avx2() {
        // SAFETY: the CPU has AVX2.
        unsafe { job.run_avx2(0..job.len(), out) };
        return;
    }
    job.run(0..job.len(), out);
}
