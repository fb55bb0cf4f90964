//! End-to-end interpolation on the creature through the C API: thread
//! independence, thin parts, the three-level hierarchy, bad input.

use glam::Vec3;
use pelage::*;
use pelage_core::Root;
use pelage_tests::creature::{default_creature, CreatureMesh};
use pelage_tests::measure::{
    groomed, guides_desc, mesh_desc as desc, mesh_view, stamp_roots, ExpandCall, Groomed,
};
use std::ptr::{null, null_mut};

const CVS: usize = 12;

fn as_c(roots: &[Root]) -> &[PelageRoot] {
    bytemuck::cast_slice(roots)
}

fn groom(m: &CreatureMesh, guides: u32, strands: u32, maps: &PelageGroomMaps) -> Groomed {
    groomed(m, (guides, CVS, 0.08), strands, maps, 1)
}

fn expand(m: &CreatureMesh, g: &Groomed, params: &PelageExpandParams) -> Vec<[f32; 4]> {
    let guides = guides_desc(&g.guide_roots, &g.guide_points);
    expand_from(m, &guides, g, params).unwrap()
}

/// The control points per curve `params` write.
fn points_per_curve(params: &PelageExpandParams) -> usize {
    let mut per = 0usize;
    assert_eq!(pelage_expand_size(params, &mut per), PelageStatus::Ok);
    per
}

/// `g`'s strands expanded from `guides` (g's guides, possibly stored
/// otherwise), or the failing status with the output left untouched.
fn expand_from(
    m: &CreatureMesh,
    guides: &PelageGuidesDesc,
    g: &Groomed,
    params: &PelageExpandParams,
) -> Result<Vec<[f32; 4]>, PelageStatus> {
    let per = points_per_curve(params);
    let mut out = vec![[0.0f32; 4]; g.strands.len() * per];
    let mut counts = vec![0u32; g.strands.len()];
    let call = ExpandCall {
        mesh: &desc(m),
        guides,
        strands: &g.strands,
        bindings: &g.bindings,
        grooms: &g.grooms,
        params,
    };
    let canary = [-7.0f32; 4];
    out.fill(canary);
    match call.run(&mut out, Some(&mut counts)) {
        PelageStatus::Ok => {
            assert!(counts.iter().all(|&c| c as usize == per));
            Ok(out)
        }
        status => {
            assert!(out.iter().all(|p| *p == canary) && counts.iter().all(|&c| c == 0));
            Err(status)
        }
    }
}

#[test]
fn groom_maps_through_the_c_api_give_each_strand_its_value() {
    // a per-vertex map with interleaved values (stride 8), an 8-bit texture
    // with padded rows and a float texture: every strand gets the map's
    // value at its root (the core's lookups, here from the host's buffers)
    use pelage_core::surface::map::{Texels, Texture};
    let m = default_creature();
    let mesh = mesh_view(&m);
    let strands = stamp_roots(mesh, 5000, 3);
    let interleaved: Vec<[f32; 2]> = m
        .positions
        .iter()
        .map(|p| [1.0 + 0.5 * p[1], -1.0])
        .collect();
    let (w, h, row) = (37usize, 23usize, 40usize);
    let bytes: Vec<u8> = (0..row * h)
        .map(|i| ((i % row) * 7 + (i / row) * 11) as u8)
        .collect();
    let floats: Vec<f32> = (0..w * h)
        .map(|i| 0.001 * (i % w) as f32 + 0.002 * (i / w) as f32)
        .collect();
    let map =
        |kind: PelageMapKind, data: *const std::ffi::c_void, width, height, stride| PelageMap {
            kind: kind as u32,
            constant: 0.0,
            data,
            width,
            height,
            stride,
        };
    let mut maps = pelage_groom_maps_defaults();
    maps.length = map(
        PelageMapKind::PerVertex,
        interleaved.as_ptr().cast(),
        0,
        0,
        8,
    );
    maps.clump = map(PelageMapKind::TextureU8, bytes.as_ptr().cast(), w, h, row);
    maps.root_width = map(
        PelageMapKind::TextureF32,
        floats.as_ptr().cast(),
        w,
        h,
        4 * w,
    );
    let mut grooms = vec![PelageStrandGroom::default(); strands.len()];
    let s = pelage_groom_evaluate(
        &desc(&m),
        &maps,
        as_c(&strands).as_ptr(),
        strands.len(),
        grooms.as_mut_ptr(),
        grooms.len(),
    );
    assert_eq!(s, PelageStatus::Ok);
    let texture = |texels, row_stride| Texture {
        texels,
        width: w,
        height: h,
        row_stride,
    };
    let u8_texture = texture(Texels::U8(&bytes), row);
    let f32_texture = texture(Texels::F32(bytemuck::cast_slice(&floats)), 4 * w);
    for (r, g) in strands.iter().zip(&grooms) {
        let (f, u, v) = (r.face as usize, r.u, r.v);
        let [a, b, c] = m.triangles[f].map(|i| interleaved[i as usize][0]);
        let length = a * (1.0 - u - v) + b * u + c * v;
        assert!(
            (g.length - length).abs() < 1e-5,
            "length {} vs {length}",
            g.length
        );
        let uv = mesh.uv(f, u, v).unwrap();
        let clump = u8_texture.sample(uv.x, uv.y);
        assert!(
            (g.clump - clump).abs() < 1e-6,
            "clump {} vs {clump}",
            g.clump
        );
        let width = f32_texture.sample(uv.x, uv.y);
        assert!((2.0 * g.root_radius - width).abs() < 1e-7, "width");
        assert_eq!((g.tip_radius, g.bend), (0.00025, 0.0), "defaults elsewhere");
    }
    // values must vary over the body, or the test would prove little
    let spread = |f: fn(&PelageStrandGroom) -> f32| {
        let (lo, hi) = grooms
            .iter()
            .map(f)
            .fold((f32::MAX, f32::MIN), |(l, h), x| (l.min(x), h.max(x)));
        hi - lo
    };
    assert!(
        spread(|g| g.length) > 0.5 && spread(|g| g.clump) > 0.5 && spread(|g| g.root_radius) > 0.01
    );
}

#[test]
fn guides_with_their_own_point_counts_through_offsets() {
    // each guide's segments split into 1, 2 or 3 equal parts: the same
    // polylines stored with 12, 23 or 34 points through `offsets`.
    // Resampling is uniform in point index, so they resample to the same
    // points and every curve must match the fixed-count one
    let m = default_creature();
    let g = groom(&m, 600, 20_000, &styled());
    let mut params = pelage_expand_params_defaults();
    params.points_per_strand = CVS as u32;
    params.run.thread_count = 2;
    let fixed = expand(&m, &g, &params);
    let mut points = vec![];
    let mut offsets = vec![0u32];
    for (i, guide) in g.guide_points.chunks(CVS).enumerate() {
        let parts = 1 + i % 3;
        points.push(guide[0]);
        for w in guide.windows(2) {
            let (a, b) = (Vec3::from(w[0]), Vec3::from(w[1]));
            points.extend((1..=parts).map(|k| a.lerp(b, k as f32 / parts as f32).to_array()));
        }
        offsets.push(points.len() as u32);
    }
    let mut guides = guides_desc(&g.guide_roots, &points);
    guides.offsets = offsets.as_ptr();
    guides.points_per_guide = 0;
    let varied = expand_from(&m, &guides, &g, &params).unwrap();
    let worst = fixed
        .iter()
        .zip(&varied)
        .map(|(a, b)| Vec3::from_slice(&a[..3]).distance(Vec3::from_slice(&b[..3])))
        .fold(0.0f32, f32::max);
    assert!(worst < 2e-5, "curves from offsets differ by {worst}");
    // broken offsets are refused before anything is written
    let last = offsets.len() - 1;
    let bad = |edit: &dyn Fn(&mut Vec<u32>)| {
        let mut o = offsets.clone();
        edit(&mut o);
        let mut d = guides;
        d.offsets = o.as_ptr();
        expand_from(&m, &d, &g, &params).unwrap_err()
    };
    assert_eq!(bad(&|o| o[0] = 1), PelageStatus::InvalidArgument);
    assert_eq!(bad(&|o| o[5] = o[4] + 1), PelageStatus::InvalidArgument);
    assert_eq!(bad(&|o| o[last] -= 1), PelageStatus::InvalidArgument);
    assert_eq!(bad(&|o| o.swap(3, 4)), PelageStatus::InvalidArgument);
}

fn styled() -> PelageGroomMaps {
    let mut maps = pelage_groom_maps_defaults();
    maps.kink_amplitude.constant = 0.05;
    maps.clump.constant = 0.3;
    maps.bend.constant = 0.1;
    maps
}

#[test]
fn bindings_are_the_same_on_any_thread_count() {
    let m = default_creature();
    let one = groom(&m, 2000, 30_000, &styled());
    for threads in [2, 7, 0] {
        let other = groomed(&m, (2000, CVS, 0.08), 30_000, &styled(), threads);
        assert!(other.bindings == one.bindings, "{threads} threads");
        assert_eq!(other.info.orphans, one.info.orphans);
    }
    let orphans = one.bindings.iter().filter(|b| b.count == 0).count();
    assert_eq!(
        orphans, one.info.orphans as usize,
        "orphans summed over the ranges"
    );
}

#[test]
fn identical_bits_for_1_2_and_7_threads_and_chunks() {
    let m = default_creature();
    let g = groom(&m, 2000, 30_000, &styled());
    let mut params = pelage_expand_params_defaults();
    params.run.thread_count = 1;
    let one = expand(&m, &g, &params);
    for threads in [2, 7] {
        params.run.thread_count = threads;
        assert!(expand(&m, &g, &params) == one, "{threads} threads");
    }
    assert!(one
        .iter()
        .all(|p| p.iter().all(|c| c.is_finite()) && p[3] >= 0.0));
}

/// The AVX2 build of the expansion kernel (what the C API runs where the CPU
/// has it) gives the same bits as the baseline build, for every branch of
/// the kernel: fixed and generic point counts, both end conventions, packed
/// and strided output, orphans, and strands with and without lift, kink and
/// clump.
#[cfg(target_arch = "x86_64")]
#[test]
fn avx2_kernel_gives_the_baseline_bits() {
    use pelage_core::guides::{CvLayout, Guides};
    use pelage_core::interp::bind::StrandBinding;
    use pelage_core::interp::expand::ExpandJob;
    use pelage_core::interp::groom::StrandGroom;
    use pelage_core::interp::posed::PosedFrame;
    use pelage_core::interp::strand::{EndPoints, ExpandParams};
    use pelage_core::interp::strands::{StrandBounds, Strands};
    use pelage_core::{Arena, ArenaLayout, Strided};
    if !std::is_x86_feature_detected!("avx2") {
        eprintln!("no AVX2 on this CPU: nothing to compare");
        return;
    }
    let m = default_creature();
    let g = groom(&m, 1500, 20_000, &styled());
    let mesh = mesh_view(&m);
    let mut bindings: Vec<StrandBinding> = bytemuck::cast_slice(&g.bindings).to_vec();
    let mut grooms: Vec<StrandGroom> = bytemuck::cast_slice(&g.grooms).to_vec();
    // every seventh strand an orphan, and the others a mix of looks
    for (i, (b, gr)) in bindings.iter_mut().zip(&mut grooms).enumerate() {
        match i % 7 {
            0 => gr.lift = [0.3, -0.2],
            1 => gr.kink_amplitude = 0.0,
            2 => gr.clump = 0.0,
            3 => (gr.kink_amplitude, gr.clump) = (0.0, 0.0),
            4 => {
                *b = StrandBinding {
                    clump: pelage_core::interp::bind::NO_GUIDE,
                    ..StrandBinding::default()
                }
            }
            _ => {}
        }
    }
    let guides = Guides {
        roots: &g.guide_roots,
        points: Strided::from_slice(&g.guide_points),
        layout: CvLayout::Fixed(CVS),
    };
    let strands = Strands {
        roots: &g.strands,
        bindings: &bindings,
        grooms: &grooms,
    };
    for points in [16, 8, 32, 11] {
        let mut layout = ArenaLayout::new();
        PosedFrame::layout(&mut layout, mesh.positions.len(), guides.len(), points);
        let mut arena = vec![0u8; layout.bytes()];
        let frame =
            PosedFrame::with_guides(mesh, &guides, points, &mut Arena::new(&mut arena)).unwrap();
        let bounds = StrandBounds::new(&strands).unwrap();
        for end_points in [EndPoints::Raw, EndPoints::Pinned] {
            let params = ExpandParams {
                points_per_strand: points,
                end_points,
                orphan_length: 0.05,
                width_scale: 1.0,
            };
            for stride in [16, 20] {
                let bytes = strands.len() * params.output_points() * stride;
                let (mut base, mut wide) = (vec![0u8; bytes], vec![1u8; bytes]);
                let job = ExpandJob::new(&frame, strands, &bounds, &params, bytes, stride).unwrap();
                job.run(0..job.len(), &mut base);
                // SAFETY: the CPU has AVX2 (checked above).
                unsafe { job.run_avx2(0..job.len(), &mut wide) };
                let pad = |v: &[u8]| -> Vec<u8> {
                    v.chunks(stride).flat_map(|p| p[..16].to_vec()).collect()
                };
                assert!(
                    pad(&base) == pad(&wide),
                    "{points} points, {end_points:?}, stride {stride}"
                );
            }
        }
    }
}

/// Nearest intersection of the ray origin + t dir (t in 0..max_t) with the
/// mesh: (t, face).
fn first_hit(m: &CreatureMesh, origin: Vec3, dir: Vec3, max_t: f32) -> Option<(f32, usize)> {
    let mut best: Option<(f32, usize)> = None;
    for (f, tri) in m.triangles.iter().enumerate() {
        let [p0, p1, p2] = tri.map(|i| Vec3::from(m.positions[i as usize]));
        let (e1, e2) = (p1 - p0, p2 - p0);
        let h = dir.cross(e2);
        let det = e1.dot(h);
        if det.abs() < 1e-12 {
            continue;
        }
        let s = origin - p0;
        let u = s.dot(h) / det;
        let q = s.cross(e1);
        let v = dir.dot(q) / det;
        let t = e2.dot(q) / det;
        if u >= 0.0
            && v >= 0.0
            && u + v <= 1.0
            && t > 0.0
            && t < max_t
            && best.is_none_or(|b| t < b.0)
        {
            best = Some((t, f));
        }
    }
    best
}

/// A strand root is on a face of a thin part when the ray into the body
/// leaves it again within `thickness` through a face pointing the other way.
fn on_thin_face(
    m: &CreatureMesh,
    mesh: &pelage_core::Mesh,
    p: Vec3,
    n: Vec3,
    thickness: f32,
) -> bool {
    first_hit(m, p - n * 1e-4, -n, thickness)
        .is_some_and(|(_, f)| mesh.face_normal(f).dot(n) < -0.8)
}

#[test]
fn strands_never_use_guides_from_the_other_side_of_a_thin_part() {
    let m = default_creature();
    let g = groom(&m, 13_000, 200_000, &pelage_groom_maps_defaults());
    let mesh = mesh_view(&m);
    let (mut used, mut suspicious, mut thin) = (0, 0, 0);
    for (s, b) in g.strands.iter().zip(&g.bindings) {
        let n = mesh.normal(s.face as usize, s.u, s.v);
        let p = mesh.point(s.face as usize, s.u, s.v);
        for &gi in &b.guides[..b.count as usize] {
            let r = &g.guide_roots[gi as usize];
            let gn = mesh.normal(r.face as usize, r.u, r.v);
            let gp = mesh.point(r.face as usize, r.u, r.v);
            assert!(n.dot(gn) > 0.0, "strand {} uses a guide facing away", s.id);
            used += 1;
            // Where normals differ, a thin part may separate the roots: a
            // strand on the face of an ear or finger (not its rim) must not
            // reach a guide whose root is hidden behind that face, i.e. the
            // segment between the roots lifted off the surface crosses it.
            if n.dot(gn) < 0.8 {
                suspicious += 1;
                if !on_thin_face(&m, &mesh, p, n, 0.06) {
                    continue;
                }
                thin += 1;
                let lift = 0.25 * p.distance(gp);
                let (a, c) = (p + n * lift, gp + gn * lift);
                let crossing = first_hit(&m, a, c - a, 1.0).is_some();
                assert!(!crossing, "strand {} reaches through a thin part to guide {gi}: p {p} n {n} gp {gp} gn {gn}", s.id);
            }
        }
    }
    println!("{used} strand-guide pairs, {suspicious} with normals over 37 degrees apart, {thin} of them from strands on a thin face; orphans {} of {}", g.info.orphans, g.strands.len());
    assert!(used > 200_000 && thin > 0);
    assert!((g.info.orphans as usize) < g.strands.len() / 1000);
}

#[test]
fn three_level_hierarchy_groom_to_sim_to_render() {
    let m = default_creature();
    let d = desc(&m);
    // level 1 -> 2: simulation guides are stamped sparser and expanded from groom guides
    let sim = groom(&m, 1500, 6000, &pelage_groom_maps_defaults());
    let mut params = pelage_expand_params_defaults();
    params.end_points = PelageEndPoints::Raw as u32;
    params.points_per_strand = 10;
    params.orphan_length = 0.06;
    let sim_points = expand(&m, &sim, &params);
    // level 2 -> 3: the float4 output is read in place as float3 guides (stride 16)
    let sim_guides = PelageGuidesDesc {
        roots: as_c(&sim.strands).as_ptr(),
        guide_count: sim.strands.len(),
        points: sim_points.as_ptr().cast(),
        point_stride: 16,
        point_count: sim_points.len(),
        points_per_guide: 10,
        offsets: null(),
    };
    let mesh = mesh_view(&m);
    let render = stamp_roots(mesh, 50_000, 3);
    let mut bytes = 0;
    assert_eq!(
        pelage_bind_size(&d, sim.strands.len(), &mut bytes),
        PelageStatus::Ok
    );
    let mut arena = vec![0u8; bytes];
    let mut bindings = vec![PelageStrandBinding::default(); render.len()];
    let bp = pelage_bind_params_defaults();
    let s = pelage_bind(
        &PelageRestPose {
            mesh: &d,
            guides: &sim_guides,
        },
        as_c(&render).as_ptr(),
        render.len(),
        &bp,
        PelageArena {
            memory: arena.as_mut_ptr().cast(),
            bytes,
        },
        bindings.as_mut_ptr(),
        bindings.len(),
        null_mut(),
    );
    // SAFETY: pelage_last_error returns a valid NUL-terminated string that
    // lives until the next failing call on this thread.
    assert_eq!(s, PelageStatus::Ok, "{:?}", unsafe {
        std::ffi::CStr::from_ptr(pelage_last_error())
    });
    let grooms = vec![
        PelageStrandGroom {
            length: 1.0,
            root_radius: 0.001,
            tip_radius: 0.0002,
            ..Default::default()
        };
        render.len()
    ];
    params.points_per_strand = 16;
    params.end_points = PelageEndPoints::Pinned as u32;
    params.orphan_length = 0.05;
    let per = points_per_curve(&params);
    let mut out = vec![[0.0f32; 4]; render.len() * per];
    let call = ExpandCall {
        mesh: &d,
        guides: &sim_guides,
        strands: &render,
        bindings: &bindings,
        grooms: &grooms,
        params: &params,
    };
    let s = call.run(&mut out, None);
    assert_eq!(s, PelageStatus::Ok);
    // every render hair starts on the surface and ends outside, about a guide length away
    for (i, r) in render.iter().enumerate() {
        let root = mesh.point(r.face as usize, r.u, r.v);
        let c = &out[i * per..(i + 1) * per];
        assert!(Vec3::new(c[0][0], c[0][1], c[0][2]).distance(root) < 1e-4);
        let tip = Vec3::new(c[per - 1][0], c[per - 1][1], c[per - 1][2]);
        let len = tip.distance(root);
        assert!(len > 0.03 && len < 0.1, "hair {i} chord {len}");
    }
}

#[test]
fn bad_input_gets_a_status_and_leaves_outputs_alone() {
    let m = default_creature();
    let g = groom(&m, 300, 1000, &pelage_groom_maps_defaults());
    let d = desc(&m);
    let params = pelage_bind_params_defaults();
    let mut arena = vec![0u8; 1 << 20];
    let canary = PelageStrandBinding {
        count: 0xCDCD_CDCD,
        ..Default::default()
    };
    let mut out = vec![canary; g.strands.len()];
    let mut bind = |guides: &PelageGuidesDesc, p: &PelageBindParams, arena_len: usize| {
        pelage_bind(
            &PelageRestPose { mesh: &d, guides },
            as_c(&g.strands).as_ptr(),
            g.strands.len(),
            p,
            PelageArena {
                memory: arena.as_mut_ptr().cast(),
                bytes: arena_len,
            },
            out.as_mut_ptr(),
            g.strands.len(),
            null_mut(),
        )
    };
    let good = guides_desc(&g.guide_roots, &g.guide_points);
    let mut nan = g.guide_points.clone();
    nan[7][2] = f32::NAN;
    assert_eq!(
        bind(&guides_desc(&g.guide_roots, &nan), &params, 1 << 20),
        PelageStatus::NonFinite
    );
    let mut zero = g.guide_points.clone();
    let first = zero[CVS];
    zero[CVS..2 * CVS].fill(first);
    assert_eq!(
        bind(&guides_desc(&g.guide_roots, &zero), &params, 1 << 20),
        PelageStatus::InvalidArgument
    );
    assert_eq!(
        bind(&guides_desc(&[], &[]), &params, 1 << 20),
        PelageStatus::InvalidArgument
    );
    let mut far = g.guide_roots.clone();
    far[2].face = 1 << 30;
    assert_eq!(
        bind(&guides_desc(&far, &g.guide_points), &params, 1 << 20),
        PelageStatus::OutOfRange
    );
    let k0 = PelageBindParams {
        min_neighbours: 0,
        ..params
    };
    assert_eq!(bind(&good, &k0, 1 << 20), PelageStatus::InvalidArgument);
    let swapped = PelageBindParams {
        min_neighbours: 6,
        max_neighbours: 2,
        ..params
    };
    assert_eq!(
        bind(&good, &swapped, 1 << 20),
        PelageStatus::InvalidArgument
    );
    assert_eq!(bind(&good, &params, 64), PelageStatus::CapacityExceeded);
    let mut bad_stride = good;
    bad_stride.point_stride = 8;
    assert_eq!(
        bind(&bad_stride, &params, 1 << 20),
        PelageStatus::InvalidArgument
    );
    bad_stride.point_stride = 14;
    assert_eq!(
        bind(&bad_stride, &params, 1 << 20),
        PelageStatus::Misaligned
    );
    let null_guides = PelageGuidesDesc {
        points: null(),
        ..good
    };
    assert_eq!(
        bind(&null_guides, &params, 1 << 20),
        PelageStatus::NullParameter
    );
    assert!(
        out.iter().all(|b| *b == canary),
        "a failed bind wrote output"
    );

    // zero-size groom map
    let mut maps = pelage_groom_maps_defaults();
    maps.length = PelageMap {
        kind: PelageMapKind::TextureU8 as u32,
        constant: 0.0,
        data: [0u8; 4].as_ptr().cast(),
        width: 0,
        height: 2,
        stride: 2,
    };
    let mut grooms = vec![
        PelageStrandGroom {
            length: 7.0,
            ..Default::default()
        };
        g.strands.len()
    ];
    let s = pelage_groom_evaluate(
        &d,
        &maps,
        as_c(&g.strands).as_ptr(),
        g.strands.len(),
        grooms.as_mut_ptr(),
        grooms.len(),
    );
    assert_eq!(s, PelageStatus::InvalidArgument);
    assert!(grooms.iter().all(|x| x.length == 7.0));

    // a binding that points past the guides
    let mut broken = g.bindings.clone();
    broken[5].guides[0] = 1 << 20;
    let params = pelage_expand_params_defaults();
    let per = points_per_curve(&params);
    let mut pts = vec![[-1.0f32; 4]; g.strands.len() * per];
    let mut call = ExpandCall {
        mesh: &d,
        guides: &good,
        strands: &g.strands,
        bindings: &broken,
        grooms: &g.grooms,
        params: &params,
    };
    let s = call.run(&mut pts, None);
    assert_eq!(s, PelageStatus::OutOfRange);
    assert!(pts.iter().all(|p| *p == [-1.0; 4]));
    call.bindings = &g.bindings;
    let short = pts.len() - 1;
    let s = call.run(&mut pts[..short], None);
    assert_eq!(s, PelageStatus::CapacityExceeded);
    assert!(pts.iter().all(|p| *p == [-1.0; 4]));
}

#[test]
fn interleaved_outputs_and_host_records_are_checked() {
    let m = default_creature();
    let g = groom(&m, 300, 1000, &pelage_groom_maps_defaults());
    let d = desc(&m);
    // positions and normals interleaved in one vertex buffer
    let mut vertices = vec![[0.0f32; 6]; g.strands.len()];
    let base = vertices.as_mut_ptr().cast::<f32>();
    let s = pelage_roots_evaluate(
        &d,
        as_c(&g.strands).as_ptr(),
        g.strands.len(),
        base.cast(),
        24,
        base.wrapping_add(3).cast(),
        24,
    );
    assert_eq!(s, PelageStatus::Ok);
    let mesh = mesh_view(&m);
    for (v, r) in vertices.iter().zip(&g.strands) {
        assert_eq!(
            Vec3::new(v[0], v[1], v[2]),
            mesh.point(r.face as usize, r.u, r.v)
        );
        assert_eq!(
            Vec3::new(v[3], v[4], v[5]),
            mesh.normal(r.face as usize, r.u, r.v)
        );
    }
    // a root outside its triangle
    let mut off = g.strands.clone();
    off[4].u = 3.0;
    let s = pelage_roots_evaluate(
        &d,
        as_c(&off).as_ptr(),
        off.len(),
        base.cast(),
        24,
        null_mut(),
        0,
    );
    assert_eq!(s, PelageStatus::InvalidArgument);
    // groom and binding records read back from a file are checked too
    let params = pelage_expand_params_defaults();
    let per = points_per_curve(&params);
    let mut pts = vec![[-1.0f32; 4]; g.strands.len() * per];
    let good = guides_desc(&g.guide_roots, &g.guide_points);
    let mut run = |bindings: &[PelageStrandBinding], grooms: &[PelageStrandGroom]| {
        let call = ExpandCall {
            mesh: &d,
            guides: &good,
            strands: &g.strands,
            bindings,
            grooms,
            params: &params,
        };
        let s = call.run(&mut pts, None);
        (s, pts.iter().all(|p| *p == [-1.0; 4]))
    };
    let mut grooms = g.grooms.clone();
    grooms[9].tip_radius = f32::NAN;
    assert_eq!(run(&g.bindings, &grooms), (PelageStatus::NonFinite, true));
    grooms[9].tip_radius = -0.001;
    assert_eq!(
        run(&g.bindings, &grooms),
        (PelageStatus::InvalidArgument, true)
    );
    let mut bindings = g.bindings.clone();
    bindings[3].weights[0] = f32::INFINITY;
    assert_eq!(run(&bindings, &g.grooms), (PelageStatus::NonFinite, true));
    bindings[3] = g.bindings[3];
    bindings[3].count = 9;
    assert_eq!(run(&bindings, &g.grooms), (PelageStatus::OutOfRange, true));
}
