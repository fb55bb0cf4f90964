//! The groom handle: a groom's render strands, checked once and kept for
//! expanding every frame.

use crate::buffers::{collected, req, req_mut, slice, slice_mut};
use crate::colliders::HostField;
use crate::expand::{run, Edits};
use crate::handles::{free, into_handle, object, Handle};
use crate::status::Failure;
use crate::{
    PelageCurves, PelageExpandParams, PelageFrame, PelagePatch, PelageStatus, PelageStrands,
};
use pelage_core::interp::bind::StrandBinding;
use pelage_core::interp::groom::StrandGroom;
use pelage_core::interp::patch::{self, Patch};
use pelage_core::interp::strands::{StrandBounds, Strands};
use pelage_core::Root;

/// The opaque object a `PelageGroom` points to.
// not repr(C): cbindgen declares it in C without a definition
pub struct PelageGroomTy {
    _private: [u8; 0],
}

/// A groom: render strands (roots, bindings, groom values) copied and
/// checked once by `pelage_groom_new`, so that `pelage_groom_expand` checks
/// per frame only the mesh, the posed guides and the outputs. Created by
/// `pelage_groom_new`, released by `pelage_groom_free`; immutable between.
pub type PelageGroom = *mut PelageGroomTy;

impl Handle for PelageGroomTy {
    type Object = Groom;
    const NAME: &'static str = "groom";
}

/// What a [`PelageGroom`] points to.
pub(crate) struct Groom {
    roots: Vec<Root>,
    bindings: Vec<StrandBinding>,
    grooms: Vec<StrandGroom>,
    pub(crate) bounds: StrandBounds,
}

impl Groom {
    pub(crate) fn strands(&self) -> Strands<'_> {
        Strands {
            roots: &self.roots,
            bindings: &self.bindings,
            grooms: &self.grooms,
        }
    }
}

/// Creates a groom from render strands (roots, bindings from `pelage_bind`,
/// groom values from `pelage_groom_evaluate` or the host). The records are
/// checked (faces, barycentrics, guide indices, weights in 0..1 summing to
/// 1 within PELAGE_WEIGHT_SUM_TOLERANCE, finite groom values within 1e6)
/// and copied: the host may free or change its arrays afterwards. On
/// success `*out_groom` is the new groom; on failure it is left untouched.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT, NON_FINITE, OUT_OF_RANGE,
/// MISALIGNED (a record pointer), OUT_OF_MEMORY, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_groom_new(
    strands: *const PelageStrands,
    out_groom: *mut PelageGroom,
) -> PelageStatus {
    ffi_boundary! {
        let out = req_mut(out_groom, "out_groom")?;
        let strands = req(strands, "strands")?.view()?;
        let bounds = StrandBounds::new(&strands)?;
        let groom = Box::new(Groom {
            roots: collected(strands.roots.iter().copied(), strands.roots.len(), "the strand roots")?,
            bindings: collected(strands.bindings.iter().copied(), strands.bindings.len(), "the bindings")?,
            grooms: collected(strands.grooms.iter().copied(), strands.grooms.len(), "the groom values")?,
            bounds,
        });
        *out = into_handle(groom);
        Ok(())
    }
}

/// Releases a groom. NULL is accepted and does nothing.
///
/// Thread safety: frees `groom`.
#[no_mangle]
pub extern "C" fn pelage_groom_free(groom: PelageGroom) {
    free(groom);
}

/// Writes the number of strands in `groom` to `*strand_count`.
///
/// Returns OK, NULL_PARAMETER, PANIC.
///
/// Thread safety: reads `groom`.
#[no_mangle]
pub extern "C" fn pelage_groom_strand_count(
    groom: PelageGroom,
    strand_count: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let groom = object(groom)?;
        *req_mut(strand_count, "strand_count")? = groom.roots.len();
        Ok(())
    }
}

/// Expands the strands `first .. first + count` of `groom` on `frame`:
/// the same outputs and bits as `pelage_expand` with those records, without
/// reading every record again to check it (`pelage_groom_new` did; only
/// that they fit the frame's mesh and guides is checked, in O(1)). The
/// frame's preparation is shared by every call, so a render procedural
/// expands patch by patch (one range per patch, from any threads) at the
/// cost of one whole call.
///
/// Returns OK, NULL_PARAMETER, OUT_OF_RANGE (the range, or the groom's
/// faces or guides beyond the frame's), INVALID_ARGUMENT (parameters, a
/// frame without guides or posed for another point count, stride),
/// CAPACITY_EXCEEDED (`point_capacity`), MISALIGNED, CANCELLED (the curves
/// already written are unspecified), PANIC.
///
/// Thread safety: reads `groom` and `frame`.
#[no_mangle]
pub extern "C" fn pelage_groom_expand(
    groom: PelageGroom,
    frame: PelageFrame,
    first: usize,
    count: usize,
    params: *const PelageExpandParams,
    curves: *const PelageCurves,
) -> PelageStatus {
    ffi_boundary! {
        expand_range(groom, frame, first, count, std::ptr::null(), params, curves)
    }
}

/// Per-strand changes `pelage_groom_expand_edited` applies after expanding
/// a strand, each indexed over the whole groom (from strand 0); NULL: none.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageStrandEdits {
    /// Stored lengths (as `pelage_trim_shortest` or `pelage_trim_lengths_read`
    /// give them; PELAGE_TRIM_WHOLE for none): each strand is cut there,
    /// its points respread over the kept part, so the point count stays.
    pub lengths: *const u16,
    /// Nonzero for the strands to push out of the frame's colliders
    /// (`pelage_frame_set_colliders`), after the cut: each is rotated about
    /// its root, toward its normal, by the smallest tried angle that frees
    /// every point (paper 3.3: render hairs in user regions, which
    /// interpolation can leave inside a collider although every guide is
    /// clear). Build it from a map over the body (`pelage_map_mask`).
    pub push_mask: *const u8,
}

/// `pelage_groom_expand` with per-strand `edits` (NULL: none): the cut at
/// each strand's stored length, then the push-out of the strands a mask
/// selects. A cut or pushed strand stays inside its patch's box. Strands
/// without an edit are the same bits as `pelage_groom_expand`'s.
///
/// Returns the statuses of `pelage_groom_expand`; MISALIGNED also for
/// `edits.lengths` (2-byte aligned), INVALID_ARGUMENT for a push mask on a
/// frame without colliders, NON_FINITE when the frame's distance callback
/// gave a NaN (the curves are then unspecified).
///
/// Thread safety: reads `groom` and `frame`.
#[no_mangle]
pub extern "C" fn pelage_groom_expand_edited(
    groom: PelageGroom,
    frame: PelageFrame,
    first: usize,
    count: usize,
    edits: *const PelageStrandEdits,
    params: *const PelageExpandParams,
    curves: *const PelageCurves,
) -> PelageStatus {
    ffi_boundary! {
        expand_range(groom, frame, first, count, edits, params, curves)
    }
}

/// The strands `first .. first + count` of `groom` expanded on `frame`
/// with `edits` (NULL: none): the body of both groom expansions.
fn expand_range(
    groom: PelageGroom,
    frame: PelageFrame,
    first: usize,
    count: usize,
    edits: *const PelageStrandEdits,
    params: *const PelageExpandParams,
    curves: *const PelageCurves,
) -> Result<(), Failure> {
    let groom = object(groom)?;
    let frame = object(frame)?;
    let total = groom.roots.len();
    let range = first
        ..first
            .checked_add(count)
            .filter(|&end| end <= total)
            .ok_or_else(|| {
                Failure::new(
                    PelageStatus::OutOfRange,
                    format!("strands {first} + {count} exceed the groom's {total}"),
                )
            })?;
    let field = frame.push_field();
    let colliders = frame.push_colliders(field.as_ref());
    let mut edits_of = Edits::default();
    if !edits.is_null() {
        let e = req(edits, "edits")?;
        if !e.lengths.is_null() {
            edits_of.lengths = Some(&slice(e.lengths, total, "edits.lengths")?[range.clone()]);
        }
        if !e.push_mask.is_null() {
            let colliders = colliders.as_ref().ok_or_else(|| {
                Failure::new(
                    PelageStatus::InvalidArgument,
                    "a push mask on a frame without colliders (pelage_frame_set_colliders)",
                )
            })?;
            edits_of.push = Some((
                &slice(e.push_mask, total, "edits.push_mask")?[range.clone()],
                colliders,
            ));
        }
    }
    let p = req(params, "params")?;
    run(
        frame.posed(),
        groom.strands().range(range),
        &groom.bounds,
        edits_of,
        p,
        req(curves, "curves")?,
    )?;
    field.as_ref().map_or(Ok(()), HostField::check)
}

/// The shadow or distance LOD that keeps `groom`'s strands of rank below
/// `cutoff` (for example half the strand count): writes to `counts[i]` how
/// many of patch `i`'s strands it keeps, always its first ones, since
/// `pelage_patch_plan` sorts each patch by rank (the groom's strands must
/// be in that plan's order). Expand those with `width_scale` = strand
/// count / kept strands in PelageExpandParams so the fur covers as much.
///
/// Returns OK, NULL_PARAMETER, OUT_OF_RANGE (a patch past the groom's
/// strands), INVALID_ARGUMENT (a patch not sorted by rank), MISALIGNED,
/// PANIC.
///
/// Thread safety: reads `groom`.
#[no_mangle]
pub extern "C" fn pelage_groom_lod_counts(
    groom: PelageGroom,
    patches: *const PelagePatch,
    patch_count: usize,
    cutoff: u32,
    counts: *mut u32,
) -> PelageStatus {
    ffi_boundary! {
        let roots = object(groom)?.strands().roots;
        let patches: &[Patch] = bytemuck::cast_slice(slice(patches, patch_count, "patches")?);
        for (i, p) in patches.iter().enumerate() {
            if p.first as usize + p.count as usize > roots.len() {
                return Err(pelage_core::Error::OutOfRange { what: "patches", index: i, value: p.first as usize + p.count as usize, bound: roots.len() }.into());
            }
            let range = p.first as usize..p.first as usize + p.count as usize;
            if !roots[range].is_sorted_by_key(|r| r.rank) {
                return Err(Failure::new(PelageStatus::InvalidArgument, format!("patch {i} is not sorted by rank (strands not in pelage_patch_plan's order)")));
            }
        }
        let counts = slice_mut(counts, patch_count, "counts")?;
        for (c, &p) in counts.iter_mut().zip(patches) {
            *c = patch::lod_count(roots, p, cutoff);
        }
        Ok(())
    }
}
