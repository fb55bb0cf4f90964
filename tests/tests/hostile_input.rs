//! The C API under hostile input (issue 47), called as a new host would:
//! counts read from small files, empty and non-finite values, records that
//! break a documented rule. Each call must refuse with its documented
//! status and a message that names the field and the real need, or succeed
//! with finite outputs, and never do work out of proportion to its input.
//!
//! Every allocation above 1 GiB fails in this binary (the system's memory
//! is not the limit being tested): a call that sizes memory by a count it
//! read from a file reports OUT_OF_MEMORY instead of touching gigabytes.

use pelage::*;
use pelage_tests::creature::{creature, CreatureMesh};
use pelage_tests::measure::{
    curves_desc, frame, groom_handle, groomed, guides_desc, mesh_desc, on_threads, strands_desc,
    Frame, Groomed,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::ffi::CStr;
use std::ptr::{null, null_mut};

/// The system's allocator, refusing any one allocation above 1 GiB.
struct Capped;

const CAP: usize = 1 << 30;

// SAFETY: every call is forwarded to the system allocator unchanged, or
// refused with NULL, which the GlobalAlloc contract allows.
unsafe impl GlobalAlloc for Capped {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        match layout.size() > CAP {
            true => std::ptr::null_mut(),
            // SAFETY: the caller's layout, as it gave it.
            false => unsafe { System.alloc(layout) },
        }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        match layout.size() > CAP {
            true => std::ptr::null_mut(),
            // SAFETY: the caller's layout, as it gave it.
            false => unsafe { System.alloc_zeroed(layout) },
        }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        match new_size > CAP {
            true => std::ptr::null_mut(),
            // SAFETY: the caller's block and sizes, as it gave them.
            false => unsafe { System.realloc(ptr, layout, new_size) },
        }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the block came from `System` through this allocator.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Capped = Capped;

const CVS: usize = 8;

fn last_error() -> String {
    // SAFETY: pelage_last_error returns a NUL-terminated string owned by
    // the library, valid until the next failing call on this thread.
    unsafe { CStr::from_ptr(pelage_last_error()) }
        .to_string_lossy()
        .into_owned()
}

/// `status` is `want`, and the message of a failure holds every one of
/// `words`.
fn expect(status: PelageStatus, want: PelageStatus, words: &[&str]) {
    let message = last_error();
    assert_eq!(status, want, "{message}");
    if want != PelageStatus::Ok {
        for w in words {
            assert!(message.contains(w), "{message:?} lacks {w:?}");
        }
    }
}

/// A small creature, groomed through the C API: 120 guides of 8 points,
/// 1,500 strands.
fn fixture() -> (CreatureMesh, Groomed) {
    let m = creature(24, 48);
    let g = groomed(
        &m,
        (120, CVS, 0.08),
        1_500,
        &pelage_groom_maps_defaults(),
        1,
    );
    (m, g)
}

/// A groom handle, freed on drop.
struct Groom(PelageGroom);

impl Drop for Groom {
    fn drop(&mut self) {
        pelage_groom_free(self.0);
    }
}

impl Groom {
    fn of(g: &Groomed) -> Groom {
        Groom(groom_handle(&g.strands, &g.bindings, &g.grooms))
    }
}

/// The largest guide index `g`'s strands use (clump included) + 1.
fn used_guides(g: &Groomed) -> usize {
    g.bindings
        .iter()
        .flat_map(|b| {
            let clump = (b.clump != u32::MAX).then_some(b.clump);
            b.guides[..b.count as usize].iter().copied().chain(clump)
        })
        .max()
        .map_or(0, |i| i as usize + 1)
}

#[test]
fn the_shot_pass_sizes_its_memory_by_the_groom_not_by_a_file() {
    let (_, g) = fixture();
    let groom = Groom::of(&g);
    let n = g.strands.len();
    // a records file of no records whose header claims 2^31 guides
    let mut size = 0usize;
    expect(
        pelage_trim_records_size(0, &mut size),
        PelageStatus::Ok,
        &[],
    );
    let mut file = vec![0u8; size];
    let mut written = 0usize;
    expect(
        pelage_trim_records_write(
            null(),
            0,
            1 << 31,
            CVS as u32,
            file.as_mut_ptr().cast(),
            size,
            &mut written,
        ),
        PelageStatus::Ok,
        &[],
    );
    let mut info = PelageTrimRecordsInfo::default();
    expect(
        pelage_trim_records_info(file.as_ptr().cast(), written, &mut info),
        PelageStatus::Ok,
        &[],
    );
    assert_eq!(info.guide_count, 1 << 31);
    let mut lengths = vec![PELAGE_TRIM_WHOLE; n];
    let shortest = |records: &[PelageTrimRecord], guides: usize, lengths: &mut [u16]| {
        pelage_trim_shortest(
            groom.0,
            records.as_ptr(),
            records.len(),
            guides,
            CVS as u32,
            lengths.as_mut_ptr(),
            lengths.len(),
        )
    };
    expect(
        shortest(&[], info.guide_count, &mut lengths),
        PelageStatus::Ok,
        &[],
    );
    // 2^32 - 1 guides can all be named (u32::MAX names none): the
    // documented limit, inclusive
    expect(
        shortest(&[], u32::MAX as usize, &mut lengths),
        PelageStatus::Ok,
        &[],
    );
    expect(
        shortest(&[], u32::MAX as usize + 1, &mut lengths),
        PelageStatus::InvalidArgument,
        &["guide_count", "2^32 - 1"],
    );
    assert!(lengths.iter().all(|&l| l == PELAGE_TRIM_WHOLE));
    // a frame with fewer guides than the groom's strands use: refused,
    // naming the count
    let used = used_guides(&g);
    expect(
        shortest(&[], used - 1, &mut lengths),
        PelageStatus::OutOfRange,
        &["guide_count", "groom"],
    );
    // a record of a guide past those the strands use, on a frame that has
    // it: checked, and cuts nothing
    let far = PelageTrimRecord {
        guide: (used + 5) as u32,
        cv: 1,
        length: 0.0,
    };
    expect(
        shortest(&[far], used + 6, &mut lengths),
        PelageStatus::Ok,
        &[],
    );
    assert!(lengths.iter().all(|&l| l == PELAGE_TRIM_WHOLE));
    expect(
        shortest(&[far], used + 5, &mut lengths),
        PelageStatus::OutOfRange,
        &["guide"],
    );
    // and a record of a guide the strands use still cuts them
    let near = PelageTrimRecord {
        guide: g.bindings[0].guides[0],
        cv: 1,
        length: 0.0,
    };
    expect(
        shortest(&[near], info.guide_count, &mut lengths),
        PelageStatus::Ok,
        &[],
    );
    assert!(lengths[0] < PELAGE_TRIM_WHOLE);
}

#[test]
fn an_empty_patch_gets_a_finite_empty_box() {
    let (m, g) = fixture();
    let params = pelage_expand_params_defaults();
    let frame = frame(&mesh_desc(&m), &g.guides(), params.points_per_strand, 1).unwrap();
    let strands = strands_desc(&g.strands, &g.bindings, &g.grooms);
    let n = g.strands.len() as u32;
    let patches = [
        PelagePatch { first: 0, count: 0 },
        PelagePatch { first: 0, count: n },
        PelagePatch { first: n, count: 0 },
    ];
    let mut boxes = [0.0f32; 18];
    expect(
        pelage_patch_boxes(
            frame.0,
            &strands,
            &params,
            patches.as_ptr(),
            patches.len(),
            boxes.as_mut_ptr(),
        ),
        PelageStatus::Ok,
        &[],
    );
    assert!(boxes.iter().all(|v| v.is_finite()), "{boxes:?}");
    let empty = [
        f32::MAX,
        f32::MAX,
        f32::MAX,
        -f32::MAX,
        -f32::MAX,
        -f32::MAX,
    ];
    assert_eq!(boxes[..6], empty);
    assert_eq!(boxes[12..], empty);
    assert!((0..3).all(|a| boxes[6 + a] < boxes[9 + a]));
}

/// Writes `g`'s strands with `bindings` as a groom file (rest frame of
/// `m`), or the failing status.
fn groom_file(
    m: &CreatureMesh,
    g: &Groomed,
    bindings: &[PelageStrandBinding],
) -> Result<Vec<u8>, PelageStatus> {
    let rest = frame(&mesh_desc(m), &g.guides(), CVS as u32, 1).unwrap();
    let desc = PelageGroomFileDesc {
        rest_frame: rest.0,
        guide_roots: bytemuck::cast_slice::<_, PelageRoot>(&g.guide_roots).as_ptr(),
        strands: strands_desc(&g.strands, bindings, &g.grooms),
        patches: null(),
        patch_count: 0,
    };
    let mut size = 0usize;
    let s = pelage_groom_file_write(&desc, null_mut(), 0, &mut size);
    if s != PelageStatus::CapacityExceeded {
        return Err(s);
    }
    let mut bytes = vec![0u8; size];
    match pelage_groom_file_write(&desc, bytes.as_mut_ptr().cast(), size, &mut size) {
        PelageStatus::Ok => Ok(bytes),
        s => Err(s),
    }
}

/// The guides of a groom file of `g`'s counts (roots, rest points in
/// their root frames), or the failing status.
fn read_groom_file(g: &Groomed, bytes: &[u8]) -> Result<(Vec<PelageRoot>, Vec<f32>), PelageStatus> {
    let (guides, n) = (g.guide_roots.len(), g.strands.len());
    let mut guide_roots = vec![PelageRoot::default(); guides];
    let mut guide_points = vec![0.0f32; guides * CVS * 3];
    let mut roots = vec![PelageRoot::default(); n];
    let mut bindings = vec![PelageStrandBinding::default(); n];
    let mut grooms = vec![PelageStrandGroom::default(); n];
    let buffers = PelageGroomFileBuffers {
        guide_roots: guide_roots.as_mut_ptr(),
        guide_points: guide_points.as_mut_ptr(),
        guide_capacity: guides,
        roots: roots.as_mut_ptr(),
        bindings: bindings.as_mut_ptr(),
        grooms: grooms.as_mut_ptr(),
        strand_capacity: n,
        patches: null_mut(),
        patch_capacity: 0,
    };
    match pelage_groom_file_read(bytes.as_ptr().cast(), bytes.len(), &buffers) {
        PelageStatus::Ok => Ok((guide_roots, guide_points)),
        s => Err(s),
    }
}

#[test]
fn bound_weights_must_sum_to_one() {
    let (m, g) = fixture();
    let params = pelage_expand_params_defaults();
    let posed = frame(&mesh_desc(&m), &g.guides(), params.points_per_strand, 1).unwrap();
    let rest = frame(&mesh_desc(&m), &g.guides(), CVS as u32, 1).unwrap();
    let n = g.strands.len();
    let per = {
        let mut per = 0usize;
        expect(pelage_expand_size(&params, &mut per), PelageStatus::Ok, &[]);
        per
    };
    let mut out = vec![[0.0f32; 4]; n * per];
    let mut arena_bytes = 0usize;
    let d = mesh_desc(&m);
    expect(
        pelage_settle_size(&d, g.guide_roots.len(), &params, &mut arena_bytes),
        PelageStatus::Ok,
        &[],
    );
    let mut arena = vec![0u8; arena_bytes];
    // every call that takes bindings from the host, with `bindings`
    let mut calls = |bindings: &[PelageStrandBinding], out: &mut [[f32; 4]]| {
        let strands = strands_desc(&g.strands, bindings, &g.grooms);
        let mut groom = null_mut();
        let new = pelage_groom_new(&strands, &mut groom);
        pelage_groom_free(groom);
        let expand = pelage_expand(posed.0, &strands, &params, &curves_desc(out, None));
        let mut boxes = [0.0f32; 6];
        let patch = PelagePatch {
            first: 0,
            count: n as u32,
        };
        let boxes = pelage_patch_boxes(posed.0, &strands, &params, &patch, 1, boxes.as_mut_ptr());
        let mut grooms = g.grooms.clone();
        let settle = pelage_settle(
            &PelageRestPose {
                mesh: &d,
                guides: &g.guides(),
            },
            bytemuck::cast_slice::<_, PelageRoot>(&g.strands).as_ptr(),
            bindings.as_ptr(),
            grooms.as_mut_ptr(),
            n,
            &params,
            PelageArena {
                memory: arena.as_mut_ptr().cast(),
                bytes: arena_bytes,
            },
            null_mut(),
        );
        let file = groom_file(&m, &g, bindings)
            .err()
            .unwrap_or(PelageStatus::Ok);
        [new, expand, boxes, settle, file]
    };
    let all_ok = [PelageStatus::Ok; 5];
    assert_eq!(calls(&g.bindings, &mut out), all_ok, "{}", last_error());
    // eight weights of 1: a strand 8 times as long as its guides
    let mut bad = g.bindings.clone();
    bad[7] = PelageStrandBinding {
        guides: [0, 1, 2, 3, 4, 5, 6, 7],
        weights: [1.0; 8],
        count: 8,
        clump: 0,
    };
    for status in calls(&bad, &mut out) {
        expect(
            status,
            PelageStatus::InvalidArgument,
            &["bindings[7].weights sum to 8 (must be 1 within 1e-4)"],
        );
    }
    // within the tolerance, and just past it
    let pair = |a: f32, b: f32| PelageStrandBinding {
        guides: [0, 1, 0, 0, 0, 0, 0, 0],
        weights: [a, b, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        count: 2,
        clump: 0,
    };
    bad[7] = pair(0.5, 0.50005);
    assert_eq!(calls(&bad, &mut out), all_ok, "{}", last_error());
    bad[7] = pair(0.5, 0.4998);
    for status in calls(&bad, &mut out) {
        expect(
            status,
            PelageStatus::InvalidArgument,
            &[
                "bindings[7].weights sum to 0.999",
                "(must be 1 within 1e-4)",
            ],
        );
    }
    // an orphan has no weight: its sum is 0, and it is fine
    bad[7] = PelageStrandBinding {
        clump: u32::MAX,
        ..PelageStrandBinding::default()
    };
    assert_eq!(calls(&bad, &mut out), all_ok, "{}", last_error());
    drop(rest);
}

#[test]
fn the_library_s_own_bindings_pass_and_its_groom_files_read() {
    // pelage_bind at every neighbour count, and the groom file it goes into
    let (m, mut g) = fixture();
    let d = mesh_desc(&m);
    let mut bytes = 0usize;
    expect(
        pelage_bind_size(&d, g.guide_roots.len(), &mut bytes),
        PelageStatus::Ok,
        &[],
    );
    let mut arena = vec![0u8; bytes];
    let mut worst = 0.0f64;
    for (min, max) in [(1, 1), (1, 8), (8, 8), (3, 6)] {
        let params = PelageBindParams {
            min_neighbours: min,
            max_neighbours: max,
            seed: u64::from(min * 10 + max),
            ..pelage_bind_params_defaults()
        };
        let n = g.strands.len();
        expect(
            pelage_bind(
                &PelageRestPose {
                    mesh: &d,
                    guides: &g.guides(),
                },
                bytemuck::cast_slice::<_, PelageRoot>(&g.strands).as_ptr(),
                n,
                &params,
                PelageArena {
                    memory: arena.as_mut_ptr().cast(),
                    bytes,
                },
                g.bindings.as_mut_ptr(),
                n,
                null_mut(),
            ),
            PelageStatus::Ok,
            &[],
        );
        for b in g.bindings.iter().filter(|b| b.count > 0) {
            let sum: f32 = b.weights[..b.count as usize].iter().sum();
            worst = worst.max((f64::from(sum) - 1.0).abs());
        }
        let file = groom_file(&m, &g, &g.bindings).unwrap();
        if let Err(s) = read_groom_file(&g, &file) {
            expect(s, PelageStatus::Ok, &[]);
        }
    }
    // far inside the tolerance
    assert!(worst < 1e-6, "{worst}");
}

/// CRC-32 (IEEE) of `bytes`, as the files' framing takes it.
fn crc32(bytes: impl Iterator<Item = u8>) -> u32 {
    !bytes.fold(!0u32, |crc, b| {
        (0..8).fold(crc ^ u32::from(b), |c, _| {
            (c >> 1) ^ (0xEDB8_8320 & (c & 1).wrapping_neg())
        })
    })
}

/// A guide cache relabelled as format `version`, its CRC made valid again.
fn relabelled(cache: &[u8], version: u32) -> Vec<u8> {
    // the CRC sits 8 bytes before the payload of the cache's 6 header fields
    let crc_at = 32 + 8 * 6 - 8;
    let mut bytes = cache.to_vec();
    bytes[8..12].copy_from_slice(&version.to_le_bytes());
    let crc = crc32(bytes[..crc_at].iter().chain(&bytes[crc_at + 8..]).copied());
    bytes[crc_at..crc_at + 4].copy_from_slice(&crc.to_le_bytes());
    bytes
}

/// `p` moved as a smooth, non-rigid pose moves it.
fn warp(p: [f32; 3]) -> [f32; 3] {
    [
        p[0] + 0.05 * (2.0 * p[1]).sin(),
        p[1] * 1.02,
        p[2] + 0.03 * (3.0 * p[0]).cos(),
    ]
}

#[test]
fn guide_cache_flags_and_versions_take_only_what_is_documented() {
    let (m, g) = fixture();
    let (guides, pts) = (g.guide_roots.len(), CVS as u32);
    let mut size = 0usize;
    // sizes: only counts a cache can hold, only the two modes
    expect(
        pelage_guide_cache_size(guides, pts, 1, 0, &mut size),
        PelageStatus::Ok,
        &[],
    );
    let bad = [
        (guides, pts, 0, 0, "shutter samples"),
        (guides, pts, 256, 0, "shutter samples"),
        (guides, 0, 1, 0, "points"),
        (guides, 65, 1, 0, "points"),
        (0, pts, 1, 0, "guide"),
        (guides, pts, 1, 7, "exact is 7"),
        (guides, pts, 1, 2, "exact is 2"),
        (1 << 28, pts, 2, 1, "4 GB"),
        (usize::MAX, pts, 255, 0, "4 GB"),
    ];
    for (g, p, s, exact, what) in bad {
        let mut out = 12345usize;
        expect(
            pelage_guide_cache_size(g, p, s, exact, &mut out),
            PelageStatus::InvalidArgument,
            &[what],
        );
        assert_eq!(out, 12345);
    }
    // the groom file's guides, a warped frame of them, and its cache
    let file = groom_file(&m, &g, &g.bindings).unwrap();
    let (guide_roots, guide_points) = read_groom_file(&g, &file).unwrap();
    let mut info = PelageGroomFileInfo::default();
    expect(
        pelage_groom_file_info(file.as_ptr().cast(), file.len(), &mut info),
        PelageStatus::Ok,
        &[],
    );
    let set = PelageGuideSet {
        guide_roots: guide_roots.as_ptr(),
        guide_points: guide_points.as_ptr(),
        guide_count: guides,
        points_per_guide: pts,
        groom_id: info.id,
    };
    let posed_mesh = CreatureMesh {
        positions: m.positions.iter().map(|&p| warp(p)).collect(),
        ..m.clone()
    };
    let posed_points: Vec<[f32; 3]> = g.guide_points.iter().map(|&p| warp(p)).collect();
    let d = mesh_desc(&posed_mesh);
    let posed = frame(&d, &guides_desc(&g.guide_roots, &posed_points), pts, 1).unwrap();
    let rest = frame(&mesh_desc(&m), &g.guides(), pts, 1).unwrap();
    let mut cache = vec![0u8; size];
    let write = |sample: &Frame, exact: u32, cache: &mut [u8]| {
        let mut written = 0usize;
        let s = pelage_guide_cache_write(
            &set,
            &sample.0,
            1,
            exact,
            on_threads(1),
            cache.as_mut_ptr().cast(),
            cache.len(),
            &mut written,
        );
        (s, written)
    };
    for exact in [2, 3, 7] {
        let (s, _) = write(&posed, exact, &mut cache);
        expect(s, PelageStatus::InvalidArgument, &["exact"]);
    }
    // a quantized cache of the warped frame codes guides from their
    // neighbours, which version 1 cannot: relabelled, it is corrupt
    let (s, written) = write(&posed, 0, &mut cache);
    expect(s, PelageStatus::Ok, &[]);
    let decoded = frame(&d, &guides_desc(&g.guide_roots, &g.guide_points), pts, 1).unwrap();
    let read = |bytes: &[u8]| {
        pelage_guide_cache_read(
            bytes.as_ptr().cast(),
            bytes.len(),
            &set,
            0,
            decoded.0,
            on_threads(1),
        )
    };
    expect(read(&cache[..written]), PelageStatus::Ok, &[]);
    let v1 = relabelled(&cache[..written], 1);
    let mut cinfo = PelageGuideCacheInfo::default();
    expect(
        pelage_guide_cache_info(v1.as_ptr().cast(), v1.len(), &mut cinfo),
        PelageStatus::Ok,
        &[],
    );
    expect(
        read(&v1),
        PelageStatus::CorruptData,
        &["version 1", "the one before it"],
    );
    // while a cache at the neutral pose has no such code: as version 1 it
    // still reads (what version 1 files hold)
    let (s, written) = write(&rest, 0, &mut cache);
    expect(s, PelageStatus::Ok, &[]);
    let rest_decoded = frame(&mesh_desc(&m), &g.guides(), pts, 1).unwrap();
    let v1 = relabelled(&cache[..written], 1);
    expect(
        pelage_guide_cache_read(
            v1.as_ptr().cast(),
            v1.len(),
            &set,
            0,
            rest_decoded.0,
            on_threads(1),
        ),
        PelageStatus::Ok,
        &[],
    );
}

/// `status` is NON_FINITE, its message naming `what`.
fn non_finite(status: PelageStatus, what: &str) {
    expect(status, PelageStatus::NonFinite, &[what]);
}

#[test]
fn any_non_finite_input_is_non_finite_in_every_object() {
    let (m, g) = fixture();
    let d = mesh_desc(&m);
    let n = g.strands.len();
    let c_strands = bytemuck::cast_slice::<_, PelageRoot>(&g.strands);
    let bad_values = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY];

    // stamp: parameters and maps
    for x in bad_values {
        let (mut arena, mut roots) = (0usize, 0usize);
        let defaults = pelage_stamp_params_defaults();
        for (what, params) in [
            (
                "radius",
                PelageStampParams {
                    radius: x,
                    ..defaults
                },
            ),
            (
                "black_scale",
                PelageStampParams {
                    black_scale: x,
                    ..defaults
                },
            ),
            (
                "bald_below",
                PelageStampParams {
                    bald_below: x,
                    ..defaults
                },
            ),
            (
                "density",
                PelageStampParams {
                    density: PelageMap {
                        constant: x,
                        ..defaults.density
                    },
                    ..defaults
                },
            ),
        ] {
            non_finite(pelage_stamp_size(&d, &params, &mut arena, &mut roots), what);
        }
    }
    let finite = PelageStampParams {
        black_scale: 2.0,
        ..pelage_stamp_params_defaults()
    };
    let (mut arena, mut roots) = (0usize, 0usize);
    expect(
        pelage_stamp_size(&d, &finite, &mut arena, &mut roots),
        PelageStatus::InvalidArgument,
        &["black_scale"],
    );

    // bind: every float parameter; a finite one out of range stays
    // INVALID_ARGUMENT
    let mut bytes = 0usize;
    expect(
        pelage_bind_size(&d, g.guide_roots.len(), &mut bytes),
        PelageStatus::Ok,
        &[],
    );
    let mut arena = vec![0u8; bytes];
    let mut bindings = vec![PelageStrandBinding::default(); n];
    let mut bind = |params: &PelageBindParams| {
        pelage_bind(
            &PelageRestPose {
                mesh: &d,
                guides: &g.guides(),
            },
            c_strands.as_ptr(),
            n,
            params,
            PelageArena {
                memory: arena.as_mut_ptr().cast(),
                bytes,
            },
            bindings.as_mut_ptr(),
            n,
            null_mut(),
        )
    };
    let defaults = pelage_bind_params_defaults();
    for x in bad_values {
        for (what, params) in [
            (
                "min_normal_dot",
                PelageBindParams {
                    min_normal_dot: x,
                    ..defaults
                },
            ),
            (
                "search_factor",
                PelageBindParams {
                    search_factor: x,
                    ..defaults
                },
            ),
            (
                "max_wrap_slope",
                PelageBindParams {
                    max_wrap_slope: x,
                    ..defaults
                },
            ),
        ] {
            non_finite(bind(&params), what);
        }
    }
    expect(
        bind(&PelageBindParams {
            search_factor: -1.0,
            ..defaults
        }),
        PelageStatus::InvalidArgument,
        &["search_factor"],
    );
    let mut nan_points = g.guide_points.clone();
    nan_points[17][2] = f32::NAN;
    non_finite(
        pelage_bind(
            &PelageRestPose {
                mesh: &d,
                guides: &guides_desc(&g.guide_roots, &nan_points),
            },
            c_strands.as_ptr(),
            n,
            &defaults,
            PelageArena {
                memory: arena.as_mut_ptr().cast(),
                bytes,
            },
            bindings.as_mut_ptr(),
            n,
            null_mut(),
        ),
        "guide points",
    );

    // groom: maps and groom values
    let mut grooms = vec![PelageStrandGroom::default(); n];
    for x in bad_values {
        let mut maps = pelage_groom_maps_defaults();
        maps.length.constant = x;
        non_finite(
            pelage_groom_evaluate(&d, &maps, c_strands.as_ptr(), n, grooms.as_mut_ptr(), n),
            "length map",
        );
        let mut values = g.grooms.clone();
        values[3].bend = x;
        let mut groom = null_mut();
        non_finite(
            pelage_groom_new(&strands_desc(&g.strands, &g.bindings, &values), &mut groom),
            "grooms",
        );
    }

    // expand and settle: their parameters
    let params = pelage_expand_params_defaults();
    let posed = frame(&d, &g.guides(), params.points_per_strand, 1).unwrap();
    let strands = strands_desc(&g.strands, &g.bindings, &g.grooms);
    let mut out = vec![[0.0f32; 4]; n * 18];
    let mut settle_bytes = 0usize;
    for x in bad_values {
        for (what, p) in [
            (
                "orphan_length",
                PelageExpandParams {
                    orphan_length: x,
                    ..params
                },
            ),
            (
                "width_scale",
                PelageExpandParams {
                    width_scale: x,
                    ..params
                },
            ),
        ] {
            let mut per = 0usize;
            non_finite(pelage_expand_size(&p, &mut per), what);
            non_finite(
                pelage_expand(posed.0, &strands, &p, &curves_desc(&mut out, None)),
                what,
            );
            non_finite(
                pelage_settle_size(&d, g.guide_roots.len(), &p, &mut settle_bytes),
                what,
            );
            // patch boxes take the expansion's parameters
            let patch = PelagePatch {
                first: 0,
                count: n as u32,
            };
            let mut boxes = [0.0f32; 6];
            non_finite(
                pelage_patch_boxes(posed.0, &strands, &p, &patch, 1, boxes.as_mut_ptr()),
                what,
            );
        }
    }
    let zero_width = PelageExpandParams {
        width_scale: 0.0,
        ..params
    };
    let mut per = 0usize;
    expect(
        pelage_expand_size(&zero_width, &mut per),
        PelageStatus::InvalidArgument,
        &["width_scale"],
    );

    // patch plan: a root's barycentric coordinate
    let mut roots_nan = c_strands.to_vec();
    roots_nan[9].u = f32::NAN;
    let mut order = vec![0u32; n];
    let mut patches = vec![PelagePatch::default(); n];
    let mut patch_count = 0usize;
    non_finite(
        pelage_patch_plan(
            &d,
            roots_nan.as_ptr(),
            n,
            64,
            order.as_mut_ptr(),
            patches.as_mut_ptr(),
            n,
            &mut patch_count,
        ),
        "strand roots",
    );

    // guide cache: the guide set's rest points, written and read
    let file = groom_file(&m, &g, &g.bindings).unwrap();
    let (guide_roots, mut guide_points) = read_groom_file(&g, &file).unwrap();
    let mut info = PelageGroomFileInfo::default();
    expect(
        pelage_groom_file_info(file.as_ptr().cast(), file.len(), &mut info),
        PelageStatus::Ok,
        &[],
    );
    let pts = CVS as u32;
    let rest = frame(&d, &g.guides(), pts, 1).unwrap();
    let mut size = 0usize;
    expect(
        pelage_guide_cache_size(g.guide_roots.len(), pts, 1, 0, &mut size),
        PelageStatus::Ok,
        &[],
    );
    let mut cache = vec![0u8; size];
    let mut written = 0usize;
    let set = |points: &[f32]| PelageGuideSet {
        guide_roots: guide_roots.as_ptr(),
        guide_points: points.as_ptr(),
        guide_count: g.guide_roots.len(),
        points_per_guide: pts,
        groom_id: info.id,
    };
    expect(
        pelage_guide_cache_write(
            &set(&guide_points),
            &rest.0,
            1,
            0,
            on_threads(1),
            cache.as_mut_ptr().cast(),
            size,
            &mut written,
        ),
        PelageStatus::Ok,
        &[],
    );
    for (x, want) in [
        (f32::NAN, PelageStatus::NonFinite),
        (f32::INFINITY, PelageStatus::NonFinite),
        (2e9, PelageStatus::InvalidArgument),
    ] {
        let kept = guide_points[40];
        guide_points[40] = x;
        let mut unused = 0usize;
        expect(
            pelage_guide_cache_write(
                &set(&guide_points),
                &rest.0,
                1,
                0,
                on_threads(1),
                cache.as_mut_ptr().cast(),
                size,
                &mut unused,
            ),
            want,
            &["guide rest points"],
        );
        expect(
            pelage_guide_cache_read(
                cache.as_ptr().cast(),
                written,
                &set(&guide_points),
                0,
                rest.0,
                on_threads(1),
            ),
            want,
            &["guide rest points"],
        );
        guide_points[40] = kept;
    }

    // trim: a record's length, the cloth, the shot pass on the hairs
    let groom = Groom::of(&g);
    let record = PelageTrimRecord {
        guide: 0,
        cv: 1,
        length: f32::NAN,
    };
    let mut trim_file = vec![0u8; 1024];
    non_finite(
        pelage_trim_records_write(
            &record,
            1,
            g.guide_roots.len(),
            pts,
            trim_file.as_mut_ptr().cast(),
            trim_file.len(),
            &mut written,
        ),
        "trim records",
    );
    let mut lengths = vec![PELAGE_TRIM_WHOLE; n];
    non_finite(
        pelage_trim_shortest(
            groom.0,
            &record,
            1,
            g.guide_roots.len(),
            pts,
            lengths.as_mut_ptr(),
            n,
        ),
        "trim records",
    );
    let mut cloth = m.clone();
    cloth.positions[5][1] = f32::INFINITY;
    let mut records = vec![PelageTrimRecord::default(); g.guide_roots.len()];
    let mut count = 0usize;
    non_finite(
        pelage_trim_find(
            posed.0,
            &mesh_desc(&cloth),
            null(),
            on_threads(1),
            records.as_mut_ptr(),
            records.len(),
            &mut count,
        ),
        "positions",
    );
    let nan_params = PelageExpandParams {
        orphan_length: f32::NAN,
        ..params
    };
    non_finite(
        pelage_trim_shortest_hairs(
            groom.0,
            posed.0,
            null(),
            null(),
            &nan_params,
            lengths.as_mut_ptr(),
            n,
        ),
        "orphan_length",
    );

    // the frame's guides, the groom file's roots, roots and masks
    let frame_nan = frame(&d, &guides_desc(&g.guide_roots, &nan_points), pts, 1);
    assert_eq!(
        frame_nan.err(),
        Some(PelageStatus::NonFinite),
        "{}",
        last_error()
    );
    let mut root_nan = Groomed {
        guide_roots: g.guide_roots.clone(),
        guide_points: g.guide_points.clone(),
        strands: g.strands.clone(),
        bindings: g.bindings.clone(),
        grooms: g.grooms.clone(),
        info: g.info,
    };
    root_nan.strands[11].v = f32::INFINITY;
    non_finite(
        groom_file(&m, &root_nan, &g.bindings).unwrap_err(),
        "strand roots",
    );
    let mut positions = vec![[0.0f32; 3]; n];
    non_finite(
        pelage_roots_evaluate(
            &d,
            roots_nan.as_ptr(),
            n,
            positions.as_mut_ptr().cast(),
            12,
            null_mut(),
            0,
        ),
        "roots",
    );
    let mut mask = vec![0u8; n];
    let map = pelage_groom_maps_defaults().length;
    non_finite(
        pelage_map_mask(&d, &map, c_strands.as_ptr(), n, f32::NAN, mask.as_mut_ptr()),
        "threshold",
    );
}

#[test]
fn messages_name_the_field_and_the_real_need() {
    let (m, g) = fixture();
    let d = mesh_desc(&m);
    let n = g.strands.len();
    let guides = g.guide_roots.len();
    let pts = CVS as u32;

    // a trim record's cv is 1 to points - 1: 0 is the root
    let groom = Groom::of(&g);
    let mut lengths = vec![PELAGE_TRIM_WHOLE; n];
    let mut file = vec![0u8; 1024];
    let mut written = 0usize;
    for cv in [0, pts] {
        let record = PelageTrimRecord {
            guide: 3,
            cv,
            length: 0.5,
        };
        let want = format!("trim records[0].cv = {cv} is out of range (must be from 1 to 7)");
        expect(
            pelage_trim_shortest(groom.0, &record, 1, guides, pts, lengths.as_mut_ptr(), n),
            PelageStatus::OutOfRange,
            &[&want],
        );
        expect(
            pelage_trim_records_write(
                &record,
                1,
                guides,
                pts,
                file.as_mut_ptr().cast(),
                file.len(),
                &mut written,
            ),
            PelageStatus::OutOfRange,
            &[&want],
        );
    }
    let past = PelageTrimRecord {
        guide: guides as u32,
        cv: 1,
        length: 0.5,
    };
    expect(
        pelage_trim_shortest(groom.0, &past, 1, guides, pts, lengths.as_mut_ptr(), n),
        PelageStatus::OutOfRange,
        &[&format!(
            "trim records[0].guide = {guides} is out of range (must be below {guides})"
        )],
    );

    // a short patch table: the patches needed, not the strands
    let c_strands = bytemuck::cast_slice::<_, PelageRoot>(&g.strands);
    let mut order = vec![0u32; n];
    let mut patches = vec![PelagePatch::default(); 4];
    let mut patch_count = 0usize;
    let needed = n.div_ceil(64);
    expect(
        pelage_patch_plan(
            &d,
            c_strands.as_ptr(),
            n,
            64,
            order.as_mut_ptr(),
            patches.as_mut_ptr(),
            patches.len(),
            &mut patch_count,
        ),
        PelageStatus::CapacityExceeded,
        &[
            &format!("patches: {needed} needed for {n} strands in patches of 64"),
            "patch_capacity is 4",
        ],
    );
    assert_eq!(patch_count, needed);

    // bindings: the field that is out of range
    let params = pelage_expand_params_defaults();
    let posed = frame(&d, &g.guides(), params.points_per_strand, 1).unwrap();
    let mut out = vec![[0.0f32; 4]; n * 18];
    let bound = (0..n).find(|&i| g.bindings[i].count >= 2).unwrap();
    for field in ["guides", "clump", "count"] {
        let mut bindings = g.bindings.clone();
        let b = &mut bindings[bound];
        // the value written, and the bound it had to respect
        let (value, below) = match field {
            "guides" => {
                b.guides[1] = guides as u32;
                (guides, guides)
            }
            "clump" => {
                b.clump = guides as u32;
                (guides, guides)
            }
            _ => {
                b.count = 9;
                (9, 9)
            }
        };
        let strands = strands_desc(&g.strands, &bindings, &g.grooms);
        let want =
            format!("bindings[{bound}].{field} = {value} is out of range (must be below {below})");
        expect(
            pelage_expand(posed.0, &strands, &params, &curves_desc(&mut out, None)),
            PelageStatus::OutOfRange,
            &[&want],
        );
    }

    // a groom file read into short arrays: which capacity
    let bytes = groom_file(&m, &g, &g.bindings).unwrap();
    let mut guide_roots = vec![PelageRoot::default(); guides];
    let mut guide_points = vec![0.0f32; guides * CVS * 3];
    let (mut roots, mut bindings, mut grooms) = (
        vec![PelageRoot::default(); n],
        vec![PelageStrandBinding::default(); n],
        vec![PelageStrandGroom::default(); n],
    );
    let buffers = PelageGroomFileBuffers {
        guide_roots: guide_roots.as_mut_ptr(),
        guide_points: guide_points.as_mut_ptr(),
        guide_capacity: guides - 1,
        roots: roots.as_mut_ptr(),
        bindings: bindings.as_mut_ptr(),
        grooms: grooms.as_mut_ptr(),
        strand_capacity: n,
        patches: null_mut(),
        patch_capacity: 0,
    };
    expect(
        pelage_groom_file_read(bytes.as_ptr().cast(), bytes.len(), &buffers),
        PelageStatus::CapacityExceeded,
        &[&format!(
            "buffers.guide_capacity is {}: the file holds {guides}",
            guides - 1
        )],
    );
}
