//! The per-frame guide cache in C: written per frame from the frame's
//! shutter samples, read by a renderer straight into a frame.

use crate::buffers::{bytes, bytes_mut, handles, req, req_mut, slice};
use crate::handles::{object, object_mut};
use crate::status::Failure;
use crate::threads::PelageRun;
use crate::{PelageFrame, PelageRoot, PelageStatus};
use pelage_core::cache::groom_file::Groom;
use pelage_core::cache::guide_cache::{self, GuideCache, Mode};
use pelage_core::interp::posed::PosedFrame;

/// The guides of a groom file, as `pelage_groom_file_read` gives them:
/// what a guide cache is coded against.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageGuideSet {
    /// guide_count roots.
    pub guide_roots: *const PelageRoot,
    /// guide_count x points_per_guide rest points in their root frames, 3
    /// floats each.
    pub guide_points: *const f32,
    /// Guides.
    pub guide_count: usize,
    /// Points per guide.
    pub points_per_guide: u32,
    /// The groom file's id (`PelageGroomFileInfo::id`).
    pub groom_id: u32,
}

/// The counts in a guide cache's checked header.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PelageGuideCacheInfo {
    /// Guides.
    pub guide_count: usize,
    /// Points per guide.
    pub points_per_guide: u32,
    /// Shutter samples.
    pub sample_count: u32,
    /// 1 for exact float32 points, 0 for quantized ones.
    pub exact: u32,
    /// The id of the groom file it was coded for.
    pub groom_id: u32,
}

impl PelageGuideSet {
    fn view(&self) -> Result<Groom<'_>, Failure> {
        let n = self.points_per_guide as usize;
        let count = self.guide_count.checked_mul(3 * n).ok_or(Failure::new(
            PelageStatus::InvalidArgument,
            "guide_count overflows",
        ))?;
        Ok(Groom::of_guides(
            bytemuck::cast_slice(slice(self.guide_roots, self.guide_count, "guide_roots")?),
            bytemuck::cast_slice(slice(self.guide_points, count, "guide_points")?),
            n,
        ))
    }
}

/// The mode an `exact` flag names; only the documented values are taken,
/// so a host's stray flag bits never pick a mode.
fn mode(exact: u32) -> Result<Mode, Failure> {
    match exact {
        0 => Ok(Mode::Quantized),
        1 => Ok(Mode::Exact),
        other => Err(Failure::new(
            PelageStatus::InvalidArgument,
            format!("exact is {other}: it must be 0 (quantized) or 1 (exact float32)"),
        )),
    }
}

/// The most bytes `pelage_guide_cache_write` writes for `sample_count`
/// shutter samples (1..255) of `guide_count` guides (at least 1) of
/// `points_per_guide` points (2..64), quantized (`exact` 0) or exact
/// (`exact` 1). A quantized frame typically takes a tenth of it.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (a count outside its
/// range, `exact` other than 0 or 1, or a cache past 4 GB, counts whose
/// product overflows included), PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_guide_cache_size(
    guide_count: usize,
    points_per_guide: u32,
    sample_count: u32,
    exact: u32,
    bytes: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let out = req_mut(bytes, "bytes")?;
        *out = guide_cache::max_encoded_bytes(guide_count, points_per_guide as usize, sample_count as usize, mode(exact)?)?;
        Ok(())
    }
}

/// Writes one frame's guide cache: `samples` are `sample_count` frames
/// (1..255), the frame's deformed mesh at each shutter sample posed with
/// its guides (`pelage_frame_set_guides`, at the guide set's point count).
/// Quantized (`exact` 0: every root-frame coordinate within 2^-15 of the
/// guide's length) or exact float32 (`exact` 1). `out` holds `capacity`
/// bytes (`pelage_guide_cache_size`); the bytes written go to
/// `*written`. On failure `out` is untouched, except on CANCELLED, when it
/// holds part of a cache. Codes on the calling thread (`run.thread_count`
/// is not read), reporting the share of guide blocks coded to
/// `run.progress`.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (counts that differ from
/// the guide set's, a frame with no guides, sample count, `exact` other
/// than 0 or 1), NON_FINITE,
/// OUT_OF_RANGE, CAPACITY_EXCEEDED, MISALIGNED, CANCELLED, PANIC.
///
/// Thread safety: reads the `samples` frames.
#[no_mangle]
pub extern "C" fn pelage_guide_cache_write(
    guides: *const PelageGuideSet,
    samples: *const PelageFrame,
    sample_count: u32,
    exact: u32,
    run: PelageRun,
    out: *mut std::ffi::c_void,
    capacity: usize,
    written: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let written = req_mut(written, "written")?;
        let mode = mode(exact)?;
        let set = req(guides, "guides")?;
        let groom = set.view()?;
        let handles = handles(samples, sample_count as usize, "samples")?;
        let frames = handles
            .iter()
            .map(|&h| object(h).map(|f| f.posed()))
            .collect::<Result<Vec<&PosedFrame>, Failure>>()?;
        let progress = run.progress();
        let mut report = |fraction: f32| progress.report(fraction as f64).is_ok();
        *written = guide_cache::encode_with_progress(&groom, set.groom_id, &frames, mode, bytes_mut(out, capacity, "out")?, &mut report)?;
        Ok(())
    }
}

/// Checks a guide cache's framing (magic, version, length, CRC), counts and
/// offset table, and writes its header to `*info`.
///
/// Returns OK, NULL_PARAMETER, CORRUPT_DATA, VERSION_MISMATCH, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_guide_cache_info(
    data: *const std::ffi::c_void,
    data_bytes: usize,
    info: *mut PelageGuideCacheInfo,
) -> PelageStatus {
    ffi_boundary! {
        let info = req_mut(info, "info")?;
        let i = GuideCache::parse(bytes(data, data_bytes, "data")?)?.info();
        *info = PelageGuideCacheInfo {
            guide_count: i.guides,
            points_per_guide: i.points as u32,
            sample_count: i.samples as u32,
            exact: (i.mode == Mode::Exact) as u32,
            groom_id: i.groom,
        };
        Ok(())
    }
}

/// Decodes shutter sample `sample` of a guide cache into `frame` (made on
/// that sample's deformed mesh for the guide set's counts): its posed
/// guides, ready for `pelage_groom_expand`. The cache must have been coded
/// for `guides` (the same groom id). The whole cache is checked before the
/// frame is written; on failure the frame keeps the guides it had, except
/// that a call cancelled (or a PANIC) while it poses the guides, in the
/// second half of its progress, leaves the frame without guides until the
/// next successful call.
///
/// Checks and decodes as `run` says (progress: the share of blocks
/// unpacked, then of guides posed).
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (another groom, counts,
/// sample index), OUT_OF_RANGE (a guide root past the mesh), CORRUPT_DATA
/// (also a coding its version does not have: a version 1 label on a guide
/// coded from the one before it), VERSION_MISMATCH, MISALIGNED,
/// CANCELLED, OUT_OF_MEMORY, PANIC (also when a worker thread cannot
/// start).
///
/// Thread safety: writes `frame`.
#[no_mangle]
pub extern "C" fn pelage_guide_cache_read(
    data: *const std::ffi::c_void,
    data_bytes: usize,
    guides: *const PelageGuideSet,
    sample: u32,
    frame: PelageFrame,
    run: PelageRun,
) -> PelageStatus {
    ffi_boundary! {
        let set = req(guides, "guides")?;
        let groom = set.view()?;
        let frame = object_mut(frame)?;
        let cache = GuideCache::parse(bytes(data, data_bytes, "data")?)?;
        frame.decode_guides(&cache, &groom, set.groom_id, sample as usize, &run)?;
        Ok(())
    }
}
