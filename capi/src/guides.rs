//! Guide curves from the host.

use crate::buffers::{req, slice, strided};
use crate::status::Failure;
use crate::{PelageMeshDesc, PelageRoot, PelageStatus};
use pelage_core::guides::{CvLayout, Guides};
use pelage_core::{Mesh, Root};
use std::ffi::c_void;

/// Guide curves in host memory (rest or posed), borrowed for one call.
///
/// Guide g is rooted at `roots[g]` (face, u, v; id and rank unused). Its
/// control points are float3 `point_stride` bytes apart: with `offsets` NULL
/// every guide has `points_per_guide` points (the fast path); otherwise guide g
/// owns points `offsets[g] .. offsets[g + 1]` (guide_count + 1 entries).
/// `point_count` is the total number of points.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageGuidesDesc {
    /// Guide roots, `guide_count` entries.
    pub roots: *const PelageRoot,
    /// Number of guides.
    pub guide_count: usize,
    /// float3 control points of all guides.
    pub points: *const c_void,
    /// Bytes between consecutive points (>= 12; 16 reads float4 buffers).
    pub point_stride: usize,
    /// Total number of points.
    pub point_count: usize,
    /// Points per guide when `offsets` is NULL.
    pub points_per_guide: u32,
    /// Optional per-guide offsets (guide_count + 1 entries), or NULL.
    pub offsets: *const u32,
}

impl PelageGuidesDesc {
    /// Checks the buffers and wraps them (contents validated by the core).
    pub(crate) fn view(&self) -> Result<Guides<'_>, Failure> {
        let roots: &[Root] =
            bytemuck::cast_slice(slice(self.roots, self.guide_count, "guide roots")?);
        let points = strided(
            self.points,
            self.point_stride,
            self.point_count,
            "guide points",
        )?;
        let layout = if self.offsets.is_null() {
            CvLayout::Fixed(self.points_per_guide as usize)
        } else {
            let count = self.guide_count.checked_add(1).ok_or_else(|| {
                Failure::new(PelageStatus::InvalidArgument, "guide_count overflows")
            })?;
            CvLayout::Offsets(slice(self.offsets, count, "guide offsets")?)
        };
        Ok(Guides {
            roots,
            points,
            layout,
        })
    }
}

/// The rest pose a groom is made on, read by pelage_bind, pelage_settle and
/// pelage_sim_new: the rest mesh and the rest guides on it.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageRestPose {
    /// The rest mesh.
    pub mesh: *const PelageMeshDesc,
    /// The rest guides, rooted on `mesh`.
    pub guides: *const PelageGuidesDesc,
}

impl PelageRestPose {
    /// The mesh and the guides, checked as views.
    pub(crate) fn view(&self) -> Result<(Mesh<'_>, Guides<'_>), Failure> {
        let mesh = req(self.mesh, "rest.mesh")?.view()?;
        let guides = req(self.guides, "rest.guides")?.view()?;
        Ok((mesh, guides))
    }
}
