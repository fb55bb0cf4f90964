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
use pelage_tests::measure::{frame, groom_handle, groomed, mesh_desc, strands_desc, Groomed};
use std::alloc::{GlobalAlloc, Layout, System};
use std::ffi::CStr;
use std::ptr::null;

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
