//! Trimming in C (paper 3.3): a frame's trim records, the shot pass over a
//! groom's strands, and the two small files.

use crate::body::BodyMemory;
use crate::buffers::{bytes, bytes_mut, collected, filled, grow, req, req_mut, slice, slice_mut};
use crate::colliders::HostColliders;
use crate::expand::{core_params, PelageExpandParams};
use crate::handles::object;
use crate::status::Failure;
use crate::threads::{split_with_progress, PelageRun, Progress};
use crate::{PelageColliders, PelageFrame, PelageGroom, PelageMeshDesc, PelageStatus};
use pelage_core::cache::trim_file::{self, RecordsInfo};
use pelage_core::interp::expand::ExpandJob;
use pelage_core::surface::body::{Body, CELLS_PER_TRIANGLE};
use pelage_core::trim::length::{guide_lengths, shortest, shortest_own};
use pelage_core::trim::meet::meet_guides;
use pelage_core::trim::TrimRecord;
use pelage_core::{Arena, Mesh};

/// Where one guide first meets the cloth or a collider in one frame.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PelageTrimRecord {
    /// The guide.
    pub guide: u32,
    /// The first control point past the meet (1 .. points per guide - 1).
    pub cv: u32,
    /// The guide's curve parameter at the meet, 0..1: (cv - 1 + t) /
    /// (points - 1) for the meet at t of the segment ending at cv. A
    /// guide's points are evenly spaced along it, so this is the fraction
    /// of its length.
    pub length: f32,
}

same_layout!(PelageTrimRecord, TrimRecord, guide, cv, length);

/// The memory of what guides and hairs meet: the cloth's grid, and the
/// body's.
#[derive(Default)]
struct ObstacleMemory {
    cloth: Vec<u8>,
    body: BodyMemory,
}

impl ObstacleMemory {
    /// The cloth (NULL: none) as a grid of its triangles, the host's
    /// colliders, and the body of `mesh` when they ask for it (its grid
    /// built over `threads` threads, its stages reported to `progress`).
    fn build<'a>(
        &'a mut self,
        mesh: &Mesh,
        cloth: *const PelageMeshDesc,
        colliders: *const PelageColliders,
        threads: u32,
        progress: Progress,
    ) -> Result<(Option<Body<'a>>, HostColliders<'a>, Option<Body<'a>>), Failure> {
        let cloth = match cloth.is_null() {
            true => None,
            false => {
                let mesh = req(cloth, "cloth")?.view()?;
                grow(
                    &mut self.cloth,
                    Body::required_bytes(&mesh)?,
                    0,
                    "the cloth's body",
                )?;
                Some(Body::new(&mesh, &mut Arena::new(&mut self.cloth))?)
            }
        };
        let host = HostColliders::read(colliders)?;
        let body = match host.body {
            true => Some(
                self.body
                    .body(mesh, CELLS_PER_TRIANGLE, threads, progress)?,
            ),
            false => None,
        };
        Ok((cloth, host, body))
    }
}

/// The counts of a trim records file.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PelageTrimRecordsInfo {
    /// Guides of the frame the records were found on.
    pub guide_count: usize,
    /// Points per guide of that frame.
    pub points_per_guide: u32,
    /// Records in the file.
    pub record_count: usize,
}

/// The stored length of an untrimmed strand (lengths are fractions of a
/// strand's length in 1/65535).
pub const PELAGE_TRIM_WHOLE: u16 = 65535;
const _: () = assert!(PELAGE_TRIM_WHOLE == pelage_core::trim::WHOLE);

/// Finds where each posed guide of `frame` first meets `cloth` (a triangle
/// mesh such as a shirt, deformed to this frame; NULL: none) or enters one
/// of `colliders` (NULL: none; the body, when set, is the frame's mesh),
/// walking from the root. A collider's surface is placed to 1/4096 of a
/// segment, on the outside. Writes one record per guide that meets
/// something, in guide order, to `records` (capacity `capacity`; the
/// frame's guide count always suffices) and their number to
/// `*record_count`. Runs as `run` says (progress: the body's build, when
/// the colliders have it, as the first fifth, then the share of guides
/// walked). On failure nothing else is written.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (a frame without guides, a
/// collider, the cloth), NON_FINITE, OUT_OF_RANGE (cloth indices),
/// CAPACITY_EXCEEDED (`capacity`; `*record_count` gets the count
/// needed), MISALIGNED, CANCELLED, OUT_OF_MEMORY, PANIC.
///
/// Thread safety: reads `frame`.
#[no_mangle]
pub extern "C" fn pelage_trim_find(
    frame: PelageFrame,
    cloth: *const PelageMeshDesc,
    colliders: *const PelageColliders,
    run: PelageRun,
    records: *mut PelageTrimRecord,
    capacity: usize,
    record_count: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let count = req_mut(record_count, "record_count")?;
        let frame = object(frame)?.posed();
        if !frame.is_posed() {
            return Err(Failure::new(PelageStatus::InvalidArgument, "the frame has no guides (pelage_frame_set_guides)"));
        }
        let mut memory = ObstacleMemory::default();
        let progress = run.progress();
        let (cloth_body, host, body) = memory.build(frame.mesh(), cloth, colliders, run.thread_count, progress.within(0.0, 0.2))?;
        let colliders = host.colliders(body.as_ref());
        colliders.check()?;
        let guides = frame.guide_count();
        let found = split_with_progress(guides, run.thread_count, &mut [0u8; 0], 0, progress.within(0.2, 1.0), |range, _| {
            let mut found = Vec::new();
            meet_guides(frame, range, cloth_body.as_ref(), &colliders, |r| found.push(r));
            found
        })?;
        host.check_field()?;
        let total: usize = found.iter().map(Vec::len).sum();
        let out: &mut [TrimRecord] = bytemuck::cast_slice_mut(slice_mut(records, capacity, "records")?);
        if total > out.len() {
            *count = total;
            return Err(Failure::new(PelageStatus::CapacityExceeded, format!("records: {total} found, capacity {}", out.len())));
        }
        for (slot, record) in out.iter_mut().zip(found.into_iter().flatten()) {
            *slot = record;
        }
        *count = total;
        Ok(())
    }
}

/// The shot pass, one frame at a time: each of `groom`'s strands' stored
/// lengths in `lengths` (`length_count` = the groom's strand count) becomes
/// the shorter of itself and the strand's length under `records` (found on
/// a frame of `guide_count` guides of `points_per_guide` points). A strand
/// reaches the cloth where its guides, weighted, do (a weighted harmonic
/// mean of their meets; a guide that meets nothing counts as meeting at
/// its tip, so a strand of untrimmed guides stays whole). Start a shot with
/// every length PELAGE_TRIM_WHOLE; frames may come in any order. On
/// failure `lengths` is unchanged.
///
/// `guide_count` (from `pelage_trim_records_info` when the records come
/// from a file) must be at least the guides the groom's strands use, and
/// at most 2^32 - 1; the records are checked against it. Memory and work
/// follow the records and the guides the groom uses, never `guide_count`
/// itself: records of guides no strand uses are checked and left out.
///
/// Returns OK, NULL_PARAMETER, OUT_OF_RANGE (a record's guide or cv, the
/// groom's guides past `guide_count`), NON_FINITE, INVALID_ARGUMENT (a
/// length outside 0..1, `length_count`, `guide_count` above 2^32 - 1,
/// `points_per_guide` outside 2..64), MISALIGNED, OUT_OF_MEMORY, PANIC.
///
/// Thread safety: reads `groom`.
#[no_mangle]
pub extern "C" fn pelage_trim_shortest(
    groom: PelageGroom,
    records: *const PelageTrimRecord,
    record_count: usize,
    guide_count: usize,
    points_per_guide: u32,
    lengths: *mut u16,
    length_count: usize,
) -> PelageStatus {
    ffi_boundary! {
        let groom = object(groom)?;
        let records: &[TrimRecord] = bytemuck::cast_slice(slice(records, record_count, "records")?);
        let strands = groom.strands();
        if length_count != strands.len() {
            return Err(Failure::new(PelageStatus::InvalidArgument, format!("length_count {length_count} differs from the groom's {} strands", strands.len())));
        }
        // guides are named by u32 below u32::MAX (which names none)
        if guide_count > u32::MAX as usize {
            return Err(Failure::new(PelageStatus::InvalidArgument, format!("guide_count {guide_count} is above 2^32 - 1")));
        }
        groom.bounds.fits(usize::MAX, guide_count).map_err(|e| {
            Failure::new(PelageStatus::OutOfRange, format!("guide_count {guide_count} (the records' frame) is below the guides the groom's strands use: {e}"))
        })?;
        let lengths = slice_mut(lengths, length_count, "lengths")?;
        // a count read from a file sizes nothing: the groom's guides do
        let mut per_guide = filled(groom.bounds.guides(), 0.0f32, "the guide lengths")?;
        guide_lengths(records, guide_count, points_per_guide as usize, &mut per_guide)?;
        shortest(&strands, &per_guide, lengths);
        Ok(())
    }
}

/// The shot pass on the hairs themselves, one frame at a time: each of
/// `groom`'s strands is expanded on `frame` with `params` (its
/// `run.thread_count` splits the strands; the lengths do not depend on it),
/// and its stored length in `lengths` (`length_count` = the groom's strand
/// count) becomes the shorter of itself and where the strand's own curve
/// first meets `cloth` (NULL: none) or enters one of `colliders` (NULL:
/// none; the body is the frame's mesh). Exact where
/// `pelage_trim_shortest` estimates from the guides' records, at the cost
/// of an expansion and a walk of every segment through the cloth per
/// frame. A cut is checked on the frame that makes it and the ones after
/// it, so go over the shot's frames again until no length changes (one
/// more pass that changes some, then one that changes none, on the test
/// shot): then no cut hair crosses the cloth on any frame. Store the
/// result with `pelage_trim_lengths_write` as the shot's (or one frame's,
/// to reduce later) lengths. `params->run.progress`, when set, hears the
/// body's build (when the colliders have it) as the first fifth, then the
/// share of strands done, and may cancel. On failure
/// `lengths` is unchanged.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (parameters, a frame
/// without guides or posed for another point count, a collider, the
/// cloth, `length_count`), OUT_OF_RANGE, NON_FINITE, CANCELLED,
/// MISALIGNED, OUT_OF_MEMORY, PANIC.
///
/// Thread safety: reads `groom` and `frame`.
#[no_mangle]
pub extern "C" fn pelage_trim_shortest_hairs(
    groom: PelageGroom,
    frame: PelageFrame,
    cloth: *const PelageMeshDesc,
    colliders: *const PelageColliders,
    params: *const PelageExpandParams,
    lengths: *mut u16,
    length_count: usize,
) -> PelageStatus {
    ffi_boundary! {
        let groom = object(groom)?;
        let frame = object(frame)?.posed();
        let p = req(params, "params")?;
        let core = core_params(p)?;
        let strands = groom.strands();
        let n = strands.len();
        if length_count != n {
            return Err(Failure::new(PelageStatus::InvalidArgument, format!("length_count {length_count} differs from the groom's {n} strands")));
        }
        let bytes = n.checked_mul(core.output_points() * 16).ok_or_else(|| Failure::new(PelageStatus::InvalidArgument, "strand count overflows"))?;
        let job = ExpandJob::new(frame, strands, &groom.bounds, &core, bytes, 16)?;
        let mut memory = ObstacleMemory::default();
        let progress = p.run.progress();
        let (cloth_body, host, body) = memory.build(frame.mesh(), cloth, colliders, p.run.thread_count, progress.within(0.0, 0.2))?;
        let colliders = host.colliders(body.as_ref());
        colliders.check()?;
        let lengths = slice_mut(lengths, length_count, "lengths")?;
        let mut own = collected(lengths.iter().copied(), lengths.len(), "the lengths")?;
        split_with_progress(n, p.run.thread_count, &mut own, 1, progress.within(0.2, 1.0), |range, part| {
            shortest_own(&job, range, cloth_body.as_ref(), &colliders, part)
        })?;
        host.check_field()?;
        lengths.copy_from_slice(&own);
        Ok(())
    }
}

/// The size in bytes of a trim records file of `record_count` records.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (overflow), PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_trim_records_size(record_count: usize, bytes: *mut usize) -> PelageStatus {
    ffi_boundary! {
        *req_mut(bytes, "bytes")? = trim_file::records_bytes(record_count)
            .ok_or_else(|| Failure::new(PelageStatus::InvalidArgument, "record_count overflows"))?;
        Ok(())
    }
}

/// Writes a frame's trim records (found on a frame of `guide_count` guides
/// of `points_per_guide` points) as a trim records file into `out`
/// (`capacity` bytes; `pelage_trim_records_size`); the bytes written go to
/// `*written`. On failure `out` is untouched.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (`guide_count` 0 or above
/// 2^32 - 1, `points_per_guide` outside 2..64), OUT_OF_RANGE, NON_FINITE,
/// CAPACITY_EXCEEDED, MISALIGNED, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_trim_records_write(
    records: *const PelageTrimRecord,
    record_count: usize,
    guide_count: usize,
    points_per_guide: u32,
    out: *mut std::ffi::c_void,
    capacity: usize,
    written: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let written = req_mut(written, "written")?;
        let records: &[TrimRecord] = bytemuck::cast_slice(slice(records, record_count, "records")?);
        let info = RecordsInfo { guides: guide_count, points: points_per_guide as usize, records: record_count };
        *written = trim_file::encode_records(records, info, bytes_mut(out, capacity, "out")?)?;
        Ok(())
    }
}

/// Reads the header of a trim records file (`data_bytes` bytes at `data`) into `*info`,
/// checking its framing (magic, version, length, checksum).
///
/// Returns OK, NULL_PARAMETER, CORRUPT_DATA, VERSION_MISMATCH, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_trim_records_info(
    data: *const std::ffi::c_void,
    data_bytes: usize,
    info: *mut PelageTrimRecordsInfo,
) -> PelageStatus {
    ffi_boundary! {
        let info = req_mut(info, "info")?;
        *info = c_info(trim_file::records_info(bytes(data, data_bytes, "data")?)?);
        Ok(())
    }
}

/// Decodes a trim records file (`data_bytes` bytes at `data`) into `records` (capacity
/// `capacity`) and its counts into `*info`. Every record is checked first:
/// on failure nothing is written.
///
/// Returns OK, NULL_PARAMETER, CORRUPT_DATA, VERSION_MISMATCH,
/// CAPACITY_EXCEEDED, MISALIGNED, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_trim_records_read(
    data: *const std::ffi::c_void,
    data_bytes: usize,
    records: *mut PelageTrimRecord,
    capacity: usize,
    info: *mut PelageTrimRecordsInfo,
) -> PelageStatus {
    ffi_boundary! {
        let info = req_mut(info, "info")?;
        let out: &mut [TrimRecord] = bytemuck::cast_slice_mut(slice_mut(records, capacity, "records")?);
        *info = c_info(trim_file::decode_records(bytes(data, data_bytes, "data")?, out)?);
        Ok(())
    }
}

fn c_info(info: RecordsInfo) -> PelageTrimRecordsInfo {
    PelageTrimRecordsInfo {
        guide_count: info.guides,
        points_per_guide: info.points as u32,
        record_count: info.records,
    }
}

/// The size in bytes of a trim lengths file of `strand_count` strands (2
/// bytes per strand and a 40-byte header).
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (overflow), PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_trim_lengths_size(strand_count: usize, bytes: *mut usize) -> PelageStatus {
    ffi_boundary! {
        *req_mut(bytes, "bytes")? = trim_file::lengths_bytes(strand_count)
            .ok_or_else(|| Failure::new(PelageStatus::InvalidArgument, "strand_count overflows"))?;
        Ok(())
    }
}

/// Writes a shot's stored lengths (one per strand of the groom, from
/// `pelage_trim_shortest`) as a trim lengths file into `out` (`capacity`
/// bytes; `pelage_trim_lengths_size`); the bytes written go to `*written`.
/// On failure `out` is untouched.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT, CAPACITY_EXCEEDED,
/// MISALIGNED, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_trim_lengths_write(
    lengths: *const u16,
    strand_count: usize,
    out: *mut std::ffi::c_void,
    capacity: usize,
    written: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let written = req_mut(written, "written")?;
        let lengths = slice(lengths, strand_count, "lengths")?;
        *written = trim_file::encode_lengths(lengths, bytes_mut(out, capacity, "out")?)?;
        Ok(())
    }
}

/// Decodes a trim lengths file (`data_bytes` bytes at `data`) into `lengths` (capacity
/// `capacity`; NULL with 0 to learn the count) and its strand count into
/// `*strand_count`. On failure nothing is written to `lengths`; with too
/// small a capacity, `*strand_count` still gets the count.
///
/// Returns OK, NULL_PARAMETER, CORRUPT_DATA, VERSION_MISMATCH,
/// CAPACITY_EXCEEDED, MISALIGNED, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_trim_lengths_read(
    data: *const std::ffi::c_void,
    data_bytes: usize,
    lengths: *mut u16,
    capacity: usize,
    strand_count: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let count = req_mut(strand_count, "strand_count")?;
        let file = bytes(data, data_bytes, "data")?;
        *count = trim_file::lengths_count(file)?;
        trim_file::decode_lengths(file, slice_mut(lengths, capacity, "lengths")?)?;
        Ok(())
    }
}
