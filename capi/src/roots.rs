//! Root records and their evaluation on a (deformed) mesh.

use crate::buffers::{req, slice, Float3Out};
use crate::status::Failure;
use crate::{PelageMeshDesc, PelageStatus};
use bytemuck::{Pod, Zeroable};

/// A hair root: barycentric position (u, v) on triangle `face`, so
/// p = (1 - u - v) p0 + u p1 + v p2; `id` is permanent, and the roots with
/// `rank` < k form an evenly spread subset of k roots.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PelageRoot {
    /// Triangle index.
    pub face: u32,
    /// Barycentric weight of the second vertex.
    pub u: f32,
    /// Barycentric weight of the third vertex.
    pub v: f32,
    /// Stable strand id.
    pub id: u32,
    /// LOD rank.
    pub rank: u32,
}

same_layout!(PelageRoot, pelage_core::Root, face, u, v, id, rank);
const _: () =
    assert!(std::mem::align_of::<PelageRoot>() == std::mem::align_of::<pelage_core::Root>());

/// Evaluates `root_count` roots on `mesh` (rest or deformed, same topology):
/// positions into `positions` (float3, `position_stride` bytes apart) and, if
/// `normals` is not NULL, unit normals (interpolated vertex normals when the
/// mesh has them, else face normals). Pass `roots + first` to evaluate a range.
/// Every root is checked (face in range, u, v inside the triangle within
/// 1e-4) before anything is written. The two outputs may interleave in one
/// buffer; neither may overlap the inputs.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (a root outside its
/// triangle, a stride), NON_FINITE, OUT_OF_RANGE (a face), MISALIGNED,
/// PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_roots_evaluate(
    mesh: *const PelageMeshDesc,
    roots: *const PelageRoot,
    root_count: usize,
    positions: *mut std::ffi::c_void,
    position_stride: usize,
    normals: *mut std::ffi::c_void,
    normal_stride: usize,
) -> PelageStatus {
    ffi_boundary! {
        let desc = req(mesh, "mesh")?;
        let mesh = desc.view()?;
        mesh.validate()?;
        let roots = slice(roots, root_count, "roots")?;
        if positions.is_null() && root_count > 0 {
            return Err(Failure::new(PelageStatus::NullParameter, "positions is NULL"));
        }
        let mut pos_out = Float3Out::new(positions, position_stride, root_count, "positions")?;
        let mut nrm_out = Float3Out::new(normals, normal_stride, root_count, "normals")?;
        pelage_core::root::check_roots(&mesh, bytemuck::cast_slice(roots), "roots")?;
        for (i, r) in roots.iter().enumerate() {
            let f = r.face as usize;
            if let Some(out) = pos_out.as_mut() {
                out.set(i, mesh.point(f, r.u, r.v).into());
            }
            if let Some(out) = nrm_out.as_mut() {
                out.set(i, mesh.normal(f, r.u, r.v).into());
            }
        }
        Ok(())
    }
}
