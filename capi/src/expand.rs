//! Expanding render curves from a frame: parameters, the strand and curve
//! descriptors, and the one-call `pelage_expand`.

use crate::buffers::{bytes_mut, req, req_mut, slice, slice_mut};
use crate::handles::object;
use crate::status::Failure;
use crate::threads::{pelage_run_defaults, split_over_threads, split_with_progress, PelageRun};
use crate::{PelageFrame, PelageRoot, PelageStatus, PelageStrandBinding, PelageStrandGroom};
use pelage_core::collide::Colliders;
use pelage_core::interp::expand::ExpandJob;
use pelage_core::interp::posed::PosedFrame;
use pelage_core::interp::strand::{EndPoints, ExpandParams};
use pelage_core::interp::strands::{StrandBounds, Strands};
use std::ffi::c_void;
use std::ops::Range;

/// End-point convention of the output curves.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PelageEndPoints {
    /// Points as computed: a Catmull-Rom consumer (Embree, RenderMan) draws
    /// from the second to the second-last point.
    Raw = 0,
    /// First and last points repeated ("pinned" in USD): the curve runs from
    /// root to tip. Adds 2 points per curve.
    Pinned = 1,
}

/// Expansion parameters; start from pelage_expand_params_defaults().
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageExpandParams {
    /// Control points per strand before end handling (2..64); guides are
    /// resampled. Must match the frame's `points_per_strand`.
    pub points_per_strand: u32,
    /// End-point convention: a PelageEndPoints value.
    pub end_points: u32,
    /// Length of orphan strands, 0..1e9 (use PelageBindInfo.mean_guide_length).
    pub orphan_length: f32,
    /// Factor on every strand's radii, in (0, 1e6] (default 1). A shadow or
    /// distance LOD that expands the first k of n strands by rank (a
    /// cutoff in every patch: `pelage_groom_lod_counts`) passes n / k, so
    /// the fur covers as much: coverage `1 - exp(-n w l / A)` of n strands
    /// of width w and length l over an area A depends on n w alone.
    pub width_scale: f32,
    /// Threads and progress (the share of strands done). Defaults: 1
    /// thread (a renderer expands its patches on threads of its own), no
    /// callback.
    pub run: PelageRun,
}

/// Defaults: 16 points per strand, pinned ends, orphan_length 0.1,
/// width_scale 1, 1 thread,
/// no progress callback.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_expand_params_defaults() -> PelageExpandParams {
    PelageExpandParams {
        points_per_strand: 16,
        end_points: PelageEndPoints::Pinned as u32,
        orphan_length: 0.1,
        width_scale: 1.0,
        run: PelageRun {
            thread_count: 1,
            ..pelage_run_defaults()
        },
    }
}

pub(crate) fn core_params(p: &PelageExpandParams) -> Result<ExpandParams, Failure> {
    const RAW: u32 = PelageEndPoints::Raw as u32;
    const PINNED: u32 = PelageEndPoints::Pinned as u32;
    let end_points = match p.end_points {
        RAW => EndPoints::Raw,
        PINNED => EndPoints::Pinned,
        other => {
            return Err(Failure::new(
                PelageStatus::InvalidArgument,
                format!("unknown end_points value {other}"),
            ))
        }
    };
    let params = ExpandParams {
        points_per_strand: p.points_per_strand as usize,
        end_points,
        orphan_length: p.orphan_length,
        width_scale: p.width_scale,
    };
    params.check()?;
    Ok(params)
}

/// The per-strand records of a groom: `count` roots, bindings (from
/// `pelage_bind`) and groom values (from `pelage_groom_evaluate`, settled
/// by `pelage_settle`), index for index, borrowed for the call.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageStrands {
    /// Where each strand grows.
    pub roots: *const PelageRoot,
    /// Guides and weights of each strand.
    pub bindings: *const PelageStrandBinding,
    /// Groom values of each strand.
    pub grooms: *const PelageStrandGroom,
    /// Number of strands.
    pub count: usize,
}

impl PelageStrands {
    /// Checks the pointers and wraps the records (contents checked by the core).
    pub(crate) fn view(&self) -> Result<Strands<'_>, Failure> {
        let n = self.count;
        Ok(Strands {
            roots: bytemuck::cast_slice(slice(self.roots, n, "strands.roots")?),
            bindings: bytemuck::cast_slice(slice(self.bindings, n, "strands.bindings")?),
            grooms: bytemuck::cast_slice(slice(self.grooms, n, "strands.grooms")?),
        })
    }
}

/// Where expanded curves go, in host memory: points_per_curve float4
/// (x, y, z, radius) per strand into `points`, `point_stride` bytes apart
/// (16 = Embree's RTC_FORMAT_FLOAT4 layout, >= 16, a multiple of 4),
/// capacity `point_capacity` points; optionally the point count of each
/// curve (`curve_counts`) and each strand's id (`curve_ids`), NULL to skip.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageCurves {
    /// float4 control points.
    pub points: *mut c_void,
    /// Bytes between consecutive points.
    pub point_stride: usize,
    /// Points the buffer holds.
    pub point_capacity: usize,
    /// Optional uint32 per curve: its point count; or NULL.
    pub curve_counts: *mut u32,
    /// Optional uint32 per curve: its strand's id; or NULL.
    pub curve_ids: *mut u32,
}

/// The control points written per curve for `params` (points_per_strand,
/// + 2 when pinned).
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_expand_size(
    params: *const PelageExpandParams,
    points_per_curve: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let p = req(params, "params")?;
        let per = req_mut(points_per_curve, "points_per_curve")?;
        *per = core_params(p)?.output_points();
        Ok(())
    }
}

/// Expands render curves for one frame: every strand of `strands`, whose
/// records are checked on every call (a host that keeps a groom across
/// frames makes a `PelageGroom` once and calls `pelage_groom_expand`).
/// Work is split over `params->run.thread_count` threads; the bits do not
/// depend on it. Everything is validated before anything is written.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (parameters, a frame
/// without guides or posed for another point count, stride, a groom value
/// beyond 1e6, a weight outside 0..1 or a strand's weights that do not sum
/// to 1 within PELAGE_WEIGHT_SUM_TOLERANCE), NON_FINITE, OUT_OF_RANGE (a face or
/// guide index), CAPACITY_EXCEEDED (`point_capacity`), MISALIGNED,
/// CANCELLED (the curves already written are unspecified), PANIC.
///
/// Thread safety: reads `frame`.
#[no_mangle]
pub extern "C" fn pelage_expand(
    frame: PelageFrame,
    strands: *const PelageStrands,
    params: *const PelageExpandParams,
    curves: *const PelageCurves,
) -> PelageStatus {
    ffi_boundary! {
        let frame = object(frame)?;
        let all = req(strands, "strands")?.view()?;
        let p = req(params, "params")?;
        // every record is checked before any range writes
        let parts = split_over_threads(all.len(), p.run.thread_count, &mut [0u8; 0], 0, |range, _| {
            StrandBounds::new(&all.range(range.clone())).map_err(|e| e.shifted(range.start)).map(|b| (range.start, b))
        })?;
        let mut bounds = StrandBounds::default();
        for part in parts {
            let (start, b) = part?;
            bounds = bounds.merge(b, start);
        }
        run(frame.posed(), all, &bounds, Edits::default(), p, req(curves, "curves")?)
    }
}

/// Per-strand edits of one expansion (see `PelageStrandEdits`), over its strands.
#[derive(Clone, Copy, Default)]
pub(crate) struct Edits<'a> {
    pub(crate) lengths: Option<&'a [u16]>,
    pub(crate) push: Option<(&'a [u8], &'a Colliders<'a>)>,
}

/// Expands `all` into `out` with records whose `bounds` were found by
/// `StrandBounds::new`, with `edits`: checks that they fit the frame, the
/// parameters and the output, then writes every range over threads.
pub(crate) fn run(
    frame: &PosedFrame,
    all: Strands,
    bounds: &StrandBounds,
    edits: Edits,
    p: &PelageExpandParams,
    out: &PelageCurves,
) -> Result<(), Failure> {
    let core = core_params(p)?;
    let strand_count = all.len();
    let per = core.output_points();
    let needed = strand_count
        .checked_mul(per)
        .ok_or_else(|| Failure::new(PelageStatus::InvalidArgument, "strand_count overflows"))?;
    if out.point_capacity < needed {
        return Err(Failure::new(
            PelageStatus::CapacityExceeded,
            format!("points: {needed} needed, {} available", out.point_capacity),
        ));
    }
    let point_stride = out.point_stride;
    if point_stride < 16 {
        return Err(Failure::new(
            PelageStatus::InvalidArgument,
            format!("point_stride {point_stride} is below 16"),
        ));
    }
    let points = float4_out(out.points, point_stride, needed)?;
    let optional = |p: *mut u32| if p.is_null() { 0 } else { strand_count };
    let counts = slice_mut(out.curve_counts, optional(out.curve_counts), "curve_counts")?;
    let ids = slice_mut(out.curve_ids, optional(out.curve_ids), "curve_ids")?;
    let mut job = ExpandJob::new(frame, all, bounds, &core, points.len(), point_stride)?;
    if let Some(lengths) = edits.lengths {
        job = job.trimmed(lengths)?;
    }
    if let Some((mask, colliders)) = edits.push {
        job = job.pushed(mask, colliders)?;
    }
    split_with_progress(
        strand_count,
        p.run.thread_count,
        points,
        job.bytes_per_strand(),
        p.run.progress(),
        |range, bytes| run_range(&job, range, bytes),
    )?;
    counts.fill(per as u32);
    for (id, s) in ids.iter_mut().zip(all.roots) {
        *id = s.id;
    }
    Ok(())
}

/// `ExpandJob::run` in its AVX2 build where the CPU has AVX2: the same bits
/// either way (see `ExpandJob::run_avx2`), the AVX2 build faster.
fn run_range(job: &ExpandJob, range: Range<usize>, out: &mut [u8]) {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, the one requirement of the AVX2 build.
        unsafe { job.run_avx2(range, out) };
        return;
    }
    job.run(range, out);
}

fn float4_out<'a>(ptr: *mut c_void, stride: usize, count: usize) -> Result<&'a mut [u8], Failure> {
    if count == 0 {
        return Ok(&mut []);
    }
    if ptr as usize % 4 != 0 || stride % 4 != 0 {
        return Err(Failure::new(
            PelageStatus::Misaligned,
            "points: pointer and stride must be multiples of 4",
        ));
    }
    let len = stride
        .checked_mul(count - 1)
        .and_then(|b| b.checked_add(16))
        .ok_or_else(|| Failure::new(PelageStatus::InvalidArgument, "points: size overflows"))?;
    bytes_mut(ptr, len, "points")
}

/// Writes Embree's index buffer for `curve_count` curves of
/// `points_per_curve` points stored back to back: one uint32 per Catmull-Rom
/// segment, the index of its first control point (points_per_curve - 3
/// segments per curve). `capacity` is in entries.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (fewer than 4 points, more
/// points than a uint32 addresses), CAPACITY_EXCEEDED, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_curves_segment_indices(
    curve_count: usize,
    points_per_curve: usize,
    indices: *mut u32,
    capacity: usize,
) -> PelageStatus {
    ffi_boundary! {
        if points_per_curve < 4 {
            return Err(Failure::new(PelageStatus::InvalidArgument, "a Catmull-Rom curve needs at least 4 points"));
        }
        let segments = points_per_curve - 3;
        let needed = curve_count.checked_mul(segments).filter(|_| curve_count.saturating_mul(points_per_curve) <= u32::MAX as usize)
            .ok_or_else(|| Failure::new(PelageStatus::InvalidArgument, "more points than a uint32 index can address"))?;
        if capacity < needed {
            return Err(Failure::new(PelageStatus::CapacityExceeded, format!("indices: {needed} needed, {capacity} available")));
        }
        let out = slice_mut(indices, needed, "indices")?;
        for (c, seg) in out.chunks_exact_mut(segments).enumerate() {
            for (i, s) in seg.iter_mut().enumerate() {
                *s = (c * points_per_curve + i) as u32;
            }
        }
        Ok(())
    }
}
