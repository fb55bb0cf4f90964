//! The groom file in C: written once per asset from the rest frame and the
//! strand records, read by a renderer (`docs/FORMAT.md`).

use crate::buffers::{bytes, bytes_mut, collected, req, req_mut, slice, slice_mut};
use crate::expand::PelageStrands;
use crate::handles::object;
use crate::status::Failure;
use crate::{PelageFrame, PelageRoot, PelageStatus, PelageStrandBinding, PelageStrandGroom};
use bytemuck::{Pod, Zeroable};
use pelage_core::cache::groom_file::{self, Groom, GroomBuffers};
use pelage_core::interp::patch::Patch;

/// A patch: strands `first` .. `first + count` (see `pelage_patch_plan`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PelagePatch {
    /// First strand.
    pub first: u32,
    /// Strands in it.
    pub count: u32,
}

same_layout!(PelagePatch, Patch, first, count);

/// What a groom file is written from.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageGroomFileDesc {
    /// The rest mesh's frame posed with the guides (`pelage_frame_new`,
    /// `pelage_frame_set_guides`): their rest shapes in their root frames,
    /// at its point count, are the neutral pose the guide caches code
    /// against.
    pub rest_frame: PelageFrame,
    /// The guides' roots, as many as the frame's guides.
    pub guide_roots: *const PelageRoot,
    /// The render strands (in patch order when there are patches).
    pub strands: PelageStrands,
    /// The strands' patches, or NULL with `patch_count` 0.
    pub patches: *const PelagePatch,
    /// Patches.
    pub patch_count: usize,
}

/// The counts and id in a groom file's checked header.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PelageGroomFileInfo {
    /// Guides.
    pub guide_count: usize,
    /// Points per guide.
    pub points_per_guide: u32,
    /// Render strands.
    pub strand_count: usize,
    /// Patches.
    pub patch_count: usize,
    /// The file's id (its CRC-32): a guide cache names its groom file by it.
    pub id: u32,
}

/// Where `pelage_groom_file_read` writes a groom file's contents; each
/// array at least as long as `pelage_groom_file_info` says.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageGroomFileBuffers {
    /// guide_count roots.
    pub guide_roots: *mut PelageRoot,
    /// guide_count x points_per_guide rest points, 3 floats each.
    pub guide_points: *mut f32,
    /// Guides the two arrays above hold.
    pub guide_capacity: usize,
    /// strand_count roots.
    pub roots: *mut PelageRoot,
    /// strand_count bindings.
    pub bindings: *mut PelageStrandBinding,
    /// strand_count groom records.
    pub grooms: *mut PelageStrandGroom,
    /// Strands the three arrays above hold.
    pub strand_capacity: usize,
    /// patch_count patches.
    pub patches: *mut PelagePatch,
    /// Patches it holds.
    pub patch_capacity: usize,
}

/// Writes a groom file into `out` (`capacity` bytes) and its length to
/// `*written`. With `out` NULL and `capacity` 0, only the length needed is
/// written (CAPACITY_EXCEEDED, as for a buffer too small). Every record is
/// checked first (finite, in range, guide indices below the guide count,
/// weights summing to 1 within PELAGE_WEIGHT_SUM_TOLERANCE, patches
/// contiguous and covering the strands); on failure `out` is untouched.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (counts, a frame with no
/// guides, patches that leave strands out, weights), NON_FINITE, OUT_OF_RANGE,
/// CAPACITY_EXCEEDED (`*written` holds the bytes needed), MISALIGNED, OUT_OF_MEMORY, PANIC.
///
/// Thread safety: reads `desc->rest_frame`.
#[no_mangle]
pub extern "C" fn pelage_groom_file_write(
    desc: *const PelageGroomFileDesc,
    out: *mut std::ffi::c_void,
    capacity: usize,
    written: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let written = req_mut(written, "written")?;
        let desc = req(desc, "desc")?;
        let frame = object(desc.rest_frame)?.posed();
        if !frame.is_posed() {
            return Err(Failure::new(PelageStatus::InvalidArgument, "the rest frame has no guides"));
        }
        let points = collected(frame.local_points(), frame.guide_count() * frame.points(), "the guide points")?;
        let groom = Groom {
            guide_roots: bytemuck::cast_slice(slice(desc.guide_roots, frame.guide_count(), "guide_roots")?),
            guide_points: &points,
            points: frame.points(),
            strands: desc.strands.view()?,
            patches: bytemuck::cast_slice(slice(desc.patches, desc.patch_count, "patches")?),
        };
        groom.check()?;
        let needed = groom.encoded_bytes()?;
        if capacity < needed {
            *written = needed;
            return Err(Failure::new(
                PelageStatus::CapacityExceeded,
                format!("the groom file needs {needed} bytes, the buffer holds {capacity}"),
            ));
        }
        *written = groom_file::encode(&groom, bytes_mut(out, capacity, "out")?)?;
        Ok(())
    }
}

/// Checks a groom file's framing (magic, version, length, CRC) and counts,
/// and writes them to `*info`.
///
/// Returns OK, NULL_PARAMETER, CORRUPT_DATA (truncated, checksum, counts),
/// VERSION_MISMATCH (another magic or version), PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_groom_file_info(
    data: *const std::ffi::c_void,
    data_bytes: usize,
    info: *mut PelageGroomFileInfo,
) -> PelageStatus {
    ffi_boundary! {
        let info = req_mut(info, "info")?;
        let c = groom_file::counts(bytes(data, data_bytes, "data")?)?;
        *info = PelageGroomFileInfo {
            guide_count: c.guides,
            points_per_guide: c.points as u32,
            strand_count: c.strands,
            patch_count: c.patches,
            id: c.id,
        };
        Ok(())
    }
}

/// Reads a groom file into `buffers`. The whole file is checked first
/// (framing, counts, every record as `pelage_groom_file_write` checks it:
/// a record that fails is CORRUPT_DATA); on failure nothing is written.
///
/// Returns OK, NULL_PARAMETER, CORRUPT_DATA, VERSION_MISMATCH,
/// CAPACITY_EXCEEDED (a capacity below the file's count; the message names
/// it, and `pelage_groom_file_info` gives every count),
/// MISALIGNED, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_groom_file_read(
    data: *const std::ffi::c_void,
    data_bytes: usize,
    buffers: *const PelageGroomFileBuffers,
) -> PelageStatus {
    ffi_boundary! {
        let b = req(buffers, "buffers")?;
        let data = bytes(data, data_bytes, "data")?;
        let counts = groom_file::counts(data)?;
        let points = counts.points;
        let out = GroomBuffers {
            guide_roots: bytemuck::cast_slice_mut(slice_mut(b.guide_roots, b.guide_capacity, "guide_roots")?),
            guide_points: bytemuck::cast_slice_mut(slice_mut(
                b.guide_points,
                b.guide_capacity.checked_mul(3 * points).ok_or(Failure::new(PelageStatus::InvalidArgument, "guide_capacity overflows"))?,
                "guide_points",
            )?),
            roots: bytemuck::cast_slice_mut(slice_mut(b.roots, b.strand_capacity, "roots")?),
            bindings: bytemuck::cast_slice_mut(slice_mut(b.bindings, b.strand_capacity, "bindings")?),
            grooms: bytemuck::cast_slice_mut(slice_mut(b.grooms, b.strand_capacity, "grooms")?),
            patches: bytemuck::cast_slice_mut(slice_mut(b.patches, b.patch_capacity, "patches")?),
        };
        // named here: the decoder's own report does not say which array
        for (what, capacity, needed) in [
            ("guide_capacity", b.guide_capacity, counts.guides),
            ("strand_capacity", b.strand_capacity, counts.strands),
            ("patch_capacity", b.patch_capacity, counts.patches),
        ] {
            if capacity < needed {
                return Err(Failure::new(PelageStatus::CapacityExceeded, format!("buffers.{what} is {capacity}: the file holds {needed}")));
            }
        }
        groom_file::decode(data, out)?;
        Ok(())
    }
}
