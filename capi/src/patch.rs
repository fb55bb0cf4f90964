//! Patches in C: the strand order a groom is stored in, and each patch's
//! box on a frame (a renderer's bounds, before anything is expanded).

use crate::buffers::{filled, req, req_mut, slice, slice_mut};
use crate::expand::{core_params, PelageExpandParams, PelageStrands};
use crate::groom_file::PelagePatch;
use crate::handles::object;
use crate::status::Failure;
use crate::threads::split_over_threads;
use crate::{PelageMeshDesc, PelageRoot, PelageStatus};
use pelage_core::interp::patch::{self, Patch};

/// Orders `root_count` strands rooted at `roots` on the rest `mesh` into
/// patches of `patch_size` strands: `order` (root_count entries) receives
/// the strand to place k-th (reorder roots, bindings and grooms by it),
/// `patches` (capacity `patch_capacity`, at least
/// ceil(root_count / patch_size)) the patches, and `*patch_count` their
/// count. Patches are runs of the strands in Morton order of their roots,
/// sorted by LOD rank inside each (an LOD is a cutoff in every patch).
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (patch size 0), NON_FINITE,
/// OUT_OF_RANGE (a root's face), CAPACITY_EXCEEDED (`patch_capacity` below
/// ceil(root_count / patch_size): `*patch_count` gets that count),
/// MISALIGNED, OUT_OF_MEMORY, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_patch_plan(
    mesh: *const PelageMeshDesc,
    roots: *const PelageRoot,
    root_count: usize,
    patch_size: u32,
    order: *mut u32,
    patches: *mut PelagePatch,
    patch_capacity: usize,
    patch_count: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let count = req_mut(patch_count, "patch_count")?;
        let mesh = req(mesh, "mesh")?.view()?;
        let roots: &[pelage_core::Root] = bytemuck::cast_slice(slice(roots, root_count, "roots")?);
        let order = slice_mut(order, root_count, "order")?;
        let patches: &mut [Patch] = bytemuck::cast_slice_mut(slice_mut(patches, patch_capacity, "patches")?);
        let mut keys = filled(root_count, 0u64, "the patch keys")?;
        match patch::plan(&mesh, roots, patch_size as usize, &mut keys, order, patches) {
            Ok(n) => *count = n,
            // the keys and `order` hold every strand: only the patches can be short
            Err(pelage_core::Error::OutputTooSmall { needed, available }) => {
                *count = needed;
                return Err(Failure::new(PelageStatus::CapacityExceeded, format!(
                    "patches: {needed} needed for {root_count} strands in patches of {patch_size}, patch_capacity is {available}"
                )));
            }
            Err(e) => return Err(e.into()),
        }
        Ok(())
    }
}

/// Writes the box of each of `patches` (`patch_count`) on `frame`: 6
/// floats per patch into `boxes` (low x, y, z, then high x, y, z) holding
/// every point `pelage_groom_expand` writes for its strands, radius
/// included, and any rotation of them about their roots. Computed from the
/// frame's guides and the strand records without expanding; merge the boxes
/// of a frame's shutter samples for motion blur. The boxes also hold the
/// Catmull-Rom curves through the points (which reach up to 1.25 times
/// farther from the root). `params` are the expansion's. Every float
/// written is finite: an empty patch (count 0) gets the empty box, low
/// corner FLT_MAX and high corner -FLT_MAX on every axis (low above high,
/// so it holds no point, and merging boxes by min and max leaves any box
/// as it is).
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (a frame without guides,
/// or of another point count, strand records as `pelage_expand` refuses
/// them), NON_FINITE, OUT_OF_RANGE (a strand's face
/// or guide, a patch past the strands), MISALIGNED, OUT_OF_MEMORY, PANIC.
///
/// Thread safety: reads `frame`.
#[no_mangle]
pub extern "C" fn pelage_patch_boxes(
    frame: crate::PelageFrame,
    strands: *const PelageStrands,
    params: *const PelageExpandParams,
    patches: *const PelagePatch,
    patch_count: usize,
    boxes: *mut f32,
) -> PelageStatus {
    ffi_boundary! {
        let frame = object(frame)?.posed();
        let strands = req(strands, "strands")?.view()?;
        let host = req(params, "params")?;
        let params = core_params(host)?;
        // a posed frame, at the parameters' point count
        frame.check_params(&params)?;
        let patches: &[Patch] = bytemuck::cast_slice(slice(patches, patch_count, "patches")?);
        let floats = patch_count
            .checked_mul(6)
            .ok_or(Failure::new(PelageStatus::InvalidArgument, "patch_count overflows"))?;
        let boxes = slice_mut(boxes, floats, "boxes")?;
        patch::check(frame, &strands, patches)?;
        let mut reach = filled(frame.guide_count(), 0.0f32, "the guides' reach")?;
        patch::guide_reach(frame, &mut reach);
        split_over_threads(patch_count, host.run.thread_count, boxes, 6, |range, part| {
            for (p, out) in patches[range].iter().zip(part.chunks_exact_mut(6)) {
                let b = patch::patch_box(frame, &reach, &strands, &params, *p);
                out.copy_from_slice(&[b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z]);
            }
        })?;
        Ok(())
    }
}
