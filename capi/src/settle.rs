//! Settling strands out of the body at rest.

use crate::buffers::{opt_mut, req, req_mut, slice, slice_mut};
use crate::expand::core_params;
use crate::threads::{check_over_threads, split_over_threads, split_with_progress};
use crate::{
    PelageArena, PelageExpandParams, PelageMeshDesc, PelageRestPose, PelageRoot, PelageStatus,
    PelageStrandBinding, PelageStrandGroom,
};
use pelage_core::arena::ArenaLayout;
use pelage_core::interp::bind::StrandBinding;
use pelage_core::interp::groom::StrandGroom;
use pelage_core::interp::posed::PosedFrame;
use pelage_core::interp::settle::{check_settle, settle_checked, SettleReport};
use pelage_core::surface::body::Body;
use pelage_core::{Arena, Root};

/// What pelage_settle changed.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PelageSettleInfo {
    /// Strands rotated toward their root normal (lift set).
    pub lifted: u32,
    /// Strands a lift alone did not free (their clump pull was dropped).
    pub unclumped: u32,
    /// Strands that were also turned about another axis, past the normal (a
    /// crease where the root normal grazes the surface).
    pub turned: u32,
    /// Strands that also had to be shortened.
    pub shortened: u32,
    /// Strands still partly inside after every step.
    pub unresolved: u32,
}

/// Arena bytes pelage_settle needs for `rest_mesh` (validated) and
/// `guide_count` guides at `params->points_per_strand` points.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT, MISALIGNED, NON_FINITE,
/// OUT_OF_RANGE, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_settle_size(
    rest_mesh: *const PelageMeshDesc,
    guide_count: usize,
    params: *const PelageExpandParams,
    arena_bytes: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let mesh = req(rest_mesh, "rest_mesh")?.view()?;
        let core = core_params(req(params, "params")?)?;
        let out = req_mut(arena_bytes, "arena_bytes")?;
        let mut layout = ArenaLayout::new();
        PosedFrame::layout(&mut layout, mesh.positions.len(), guide_count, core.points_per_strand);
        *out = layout.bytes().saturating_add(Body::required_bytes(&mesh)?);
        Ok(())
    }
}

/// Settles strands out of the body at the rest pose, once per groom, after
/// pelage_groom_evaluate: each strand is expanded on the rest mesh from the
/// rest guides, and where a control point after the root lies inside the
/// body (its generalized winding number over the whole mesh is above 0.5,
/// so open meshes and intersecting shells work), the strand is rotated about its root toward the normal and
/// the angle stored in its groom's `lift`; strands a full lift does not free
/// lose their clump pull, are turned about other axes, then shortened. pelage_expand applies `lift` in the
/// strand's own frame at every frame. `grooms` is updated in place; it is
/// validated with everything else first and left untouched on failure.
/// Work is split over `params->run.thread_count` threads; the result does not
/// depend on it. `params->run.progress`, when set, hears the share of strands
/// done on the calling thread and may cancel.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (also values beyond 1e9,
/// groom values beyond 1e6, or a strand's weights that do not sum to 1
/// within PELAGE_WEIGHT_SUM_TOLERANCE), NON_FINITE, OUT_OF_RANGE, CAPACITY_EXCEEDED
/// (the arena), MISALIGNED, CANCELLED (the grooms of the strands not yet
/// reached are unchanged, the others settled: which ones is unspecified;
/// `info` is not written), PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_settle(
    rest: *const PelageRestPose,
    strands: *const PelageRoot,
    bindings: *const PelageStrandBinding,
    grooms: *mut PelageStrandGroom,
    strand_count: usize,
    params: *const PelageExpandParams,
    arena: PelageArena,
    info: *mut PelageSettleInfo,
) -> PelageStatus {
    ffi_boundary! {
        let (mesh, guides) = req(rest, "rest")?.view()?;
        let p = req(params, "params")?;
        let core = core_params(p)?;
        let roots: &[Root] = bytemuck::cast_slice(slice(strands, strand_count, "strands")?);
        let bindings: &[StrandBinding] = bytemuck::cast_slice(slice(bindings, strand_count, "bindings")?);
        let grooms: &mut [StrandGroom] = bytemuck::cast_slice_mut(slice_mut(grooms, strand_count, "grooms")?);
        let arena = arena.view("arena")?;
        let mut arena = Arena::new(arena);
        let body = Body::new(&mesh, &mut arena)?;
        let mut rest = PosedFrame::new(mesh, guides.len(), core.points_per_strand, &mut arena)?;
        let posing = rest.posing(&guides)?;
        let filler = posing.filler;
        split_over_threads(guides.len(), p.run.thread_count, &mut *posing.data, filler.floats_per_guide(), |range, part| {
            filler.fill(range.start, part)
        })?;
        posing.finish();
        check_over_threads(strand_count, p.run.thread_count, |range| {
            check_settle(&roots[range.clone()], &bindings[range.clone()], &grooms[range], &rest, &core)
        })?;
        let progress = p.run.progress();
        let reports = split_with_progress(strand_count, p.run.thread_count, grooms, 1, progress, |range, part| {
            settle_checked(&body, &roots[range.clone()], &bindings[range], part, &rest, &core)
        })?;
        let mut total = SettleReport::default();
        for r in reports {
            total.merge(r);
        }
        if let Some(info) = opt_mut(info) {
            *info = PelageSettleInfo {
                lifted: total.lifted,
                unclumped: total.unclumped,
                turned: total.turned,
                shortened: total.shortened,
                unresolved: total.unresolved,
            };
        }
        Ok(())
    }
}
