//! Expanding render curves from posed guides.

use crate::buffers::{bytes_mut, req, req_mut, slice, slice_mut};
use crate::status::Failure;
use crate::threads::{check_over_threads, split_over_threads};
use crate::{
    PelageGuidesDesc, PelageMeshDesc, PelageRoot, PelageStatus, PelageStrandBinding,
    PelageStrandGroom,
};
use pelage_core::arena::ArenaLayout;
use pelage_core::interp::bind::StrandBinding;
use pelage_core::interp::expand::{
    self, EndPoints, ExpandParams, GuideSlots, PreparedGuides, StrandBounds, Strands,
};
use pelage_core::interp::groom::StrandGroom;
use pelage_core::{Arena, Mesh, Root};

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
    /// Control points per strand before end handling (2..64); guides are resampled.
    pub points_per_strand: u32,
    /// End-point convention: a PelageEndPoints value.
    pub end_points: u32,
    /// Length of orphan strands (use PelageBindInfo.mean_guide_length).
    pub orphan_length: f32,
    /// Threads pelage_expand splits the strands over: 0 = all cores, 1 = the
    /// calling thread only; at most max(cores, 64). The output is bitwise
    /// identical for any value.
    pub thread_count: u32,
}

/// Defaults: 16 points per strand, pinned ends, orphan_length 0.1, 1 thread.
///
/// Thread safety: may be called from any thread at any time.
#[no_mangle]
pub extern "C" fn pelage_expand_params_defaults() -> PelageExpandParams {
    PelageExpandParams {
        points_per_strand: 16,
        end_points: PelageEndPoints::Pinned as u32,
        orphan_length: 0.1,
        thread_count: 1,
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
    };
    params.check()?;
    Ok(params)
}

/// Sizes an expansion: arena bytes for `guide_count` guides on a mesh of
/// `vertex_count` vertices (the frame's vertex tangents live in the arena),
/// and the control points written per curve (points_per_strand, + 2 when
/// pinned).
///
/// Thread safety: may be called from any thread at any time.
#[no_mangle]
pub extern "C" fn pelage_expand_query(
    guide_count: usize,
    vertex_count: usize,
    params: *const PelageExpandParams,
    arena_bytes: *mut usize,
    points_per_curve: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let p = req(params, "params")?;
        let bytes = req_mut(arena_bytes, "arena_bytes")?;
        let per = req_mut(points_per_curve, "points_per_curve")?;
        let core = core_params(p)?;
        let mut layout = ArenaLayout::new();
        PreparedGuides::layout(&mut layout, vertex_count, guide_count, core.points_per_strand);
        *bytes = layout.bytes();
        *per = core.output_points();
        Ok(())
    }
}

/// Expands `strand_count` render curves for one frame from posed guides on
/// the deformed mesh. `strands`, `bindings` and `grooms` are parallel arrays
/// (pass pointers offset by `first` to expand a range). Writes
/// points_per_curve float4 (x, y, z, radius) per strand into `points`,
/// `point_stride` bytes apart (16 = Embree's RTC_FORMAT_FLOAT4 layout),
/// capacity `point_capacity` points; optionally the point count of each curve
/// (`curve_counts`) and each strand's id (`curve_ids`), NULL to skip.
/// Work is split over `params->thread_count` threads; the bits do not depend
/// on it. Everything is validated before anything is written.
///
/// Thread safety: reentrant; concurrent calls need distinct arenas and outputs.
#[no_mangle]
pub extern "C" fn pelage_expand(
    mesh: *const PelageMeshDesc,
    guides: *const PelageGuidesDesc,
    strands: *const PelageRoot,
    bindings: *const PelageStrandBinding,
    grooms: *const PelageStrandGroom,
    strand_count: usize,
    params: *const PelageExpandParams,
    arena: *mut std::ffi::c_void,
    arena_bytes: usize,
    points: *mut std::ffi::c_void,
    point_stride: usize,
    point_capacity: usize,
    curve_counts: *mut u32,
    curve_ids: *mut u32,
) -> PelageStatus {
    ffi_boundary! {
        let strands: &[Root] = bytemuck::cast_slice(slice(strands, strand_count, "strands")?);
        let bindings: &[StrandBinding] = bytemuck::cast_slice(slice(bindings, strand_count, "bindings")?);
        let grooms: &[StrandGroom] = bytemuck::cast_slice(slice(grooms, strand_count, "grooms")?);
        let all = Strands { roots: strands, bindings, grooms };
        let out = Curves { points, point_stride, point_capacity, curve_counts, curve_ids };
        run(mesh, guides, all, None, params, arena, arena_bytes, out)
    }
}

/// Where [`run`] writes curves (see `pelage_expand`).
pub(crate) struct Curves {
    pub points: *mut std::ffi::c_void,
    pub point_stride: usize,
    pub point_capacity: usize,
    pub curve_counts: *mut u32,
    pub curve_ids: *mut u32,
}

/// Expands `all` into `out`, checking every input first: all the strand
/// records, or, with the `bounds` of records checked before, only that
/// they fit the mesh and guides.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run(
    mesh: *const PelageMeshDesc,
    guides: *const PelageGuidesDesc,
    all: Strands,
    bounds: Option<&StrandBounds>,
    params: *const PelageExpandParams,
    arena: *mut std::ffi::c_void,
    arena_bytes: usize,
    out: Curves,
) -> Result<(), Failure> {
    let mesh = req(mesh, "mesh")?.view()?;
    let guides = req(guides, "guides")?.view()?;
    let p = req(params, "params")?;
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
    let arena = bytes_mut(arena, arena_bytes, "arena")?;
    let mut arena = Arena::new(arena);
    let slots = GuideSlots::new(&mesh, &guides, core.points_per_strand, &mut arena)?;
    let filler = slots.filler;
    split_over_threads(
        guides.len(),
        p.thread_count,
        &mut *slots.data,
        filler.floats_per_guide(),
        |range, part| filler.fill(range.start, part),
    )?;
    let prepared = slots.finish();
    expand::check_frame(&prepared, &core)?;
    expand::check_output(strand_count, &core, points.len(), point_stride)?;
    match bounds {
        Some(bounds) => bounds.check(&mesh, &prepared)?,
        None => check_over_threads(strand_count, p.thread_count, |range| {
            expand::check_strands(&mesh, &all.range(range), &prepared)
        })?,
    }
    split_over_threads(
        strand_count,
        p.thread_count,
        points,
        per * point_stride,
        |range, bytes| {
            expand_range(
                &mesh,
                &all.range(range),
                &prepared,
                &core,
                bytes,
                point_stride,
            );
        },
    )?;
    counts.fill(per as u32);
    for (id, s) in ids.iter_mut().zip(all.roots) {
        *id = s.id;
    }
    Ok(())
}

/// `expand_checked` in its AVX2 build where the CPU has AVX2: the same bits
/// either way (see `expand_checked_avx2`), the AVX2 build faster.
fn expand_range(
    mesh: &Mesh,
    strands: &Strands,
    guides: &PreparedGuides,
    params: &ExpandParams,
    out: &mut [u8],
    stride: usize,
) {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, the one requirement of the AVX2 build.
        unsafe { expand::expand_checked_avx2(mesh, strands, guides, params, out, stride) };
        return;
    }
    expand::expand_checked(mesh, strands, guides, params, out, stride);
}

fn float4_out<'a>(
    ptr: *mut std::ffi::c_void,
    stride: usize,
    count: usize,
) -> Result<&'a mut [u8], Failure> {
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
/// Thread safety: may be called from any thread at any time.
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
