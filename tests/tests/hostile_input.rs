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
    curves_desc, frame, groom_handle, groomed, mesh_desc, strands_desc, Groomed,
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

/// Reads a groom file of `g`'s counts.
fn read_groom_file(g: &Groomed, bytes: &[u8]) -> PelageStatus {
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
    pelage_groom_file_read(bytes.as_ptr().cast(), bytes.len(), &buffers)
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
        expect(
            pelage_expand_query(&params, &mut per),
            PelageStatus::Ok,
            &[],
        );
        per
    };
    let mut out = vec![[0.0f32; 4]; n * per];
    let mut arena_bytes = 0usize;
    let d = mesh_desc(&m);
    expect(
        pelage_settle_query(&d, g.guide_roots.len(), &params, &mut arena_bytes),
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
            &d,
            &g.guides(),
            bytemuck::cast_slice::<_, PelageRoot>(&g.strands).as_ptr(),
            bindings.as_ptr(),
            grooms.as_mut_ptr(),
            n,
            &params,
            arena.as_mut_ptr().cast(),
            arena_bytes,
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
        pelage_bind_query(&d, g.guide_roots.len(), &mut bytes),
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
                &d,
                &g.guides(),
                bytemuck::cast_slice::<_, PelageRoot>(&g.strands).as_ptr(),
                n,
                &params,
                arena.as_mut_ptr().cast(),
                bytes,
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
        expect(read_groom_file(&g, &file), PelageStatus::Ok, &[]);
    }
    // far inside the tolerance
    assert!(worst < 1e-6, "{worst}");
}
