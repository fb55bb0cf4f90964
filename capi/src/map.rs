//! Grayscale maps (density and, later, groom parameters).

use crate::buffers::{bytes, req, slice, slice_mut, strided};
use crate::status::Failure;
use crate::{PelageMeshDesc, PelageRoot, PelageStatus};
use pelage_core::surface::map::{Texels, Texture};
use pelage_core::ScalarMap;
use std::ffi::c_void;

/// How a [`PelageMap`] stores its values.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PelageMapKind {
    /// `constant` everywhere; `data` is ignored.
    Constant = 0,
    /// 8-bit grayscale texture over UV (0..255 -> 0..1), `width` x `height`,
    /// `stride` bytes per row; row 0 is v = 0. Needs mesh UVs.
    TextureU8 = 1,
    /// 32-bit float texture over UV, as `TextureU8` otherwise.
    TextureF32 = 2,
    /// One float per mesh vertex, `stride` bytes apart (4-byte aligned),
    /// interpolated over triangles.
    PerVertex = 3,
}

/// A scalar value over the mesh surface: a constant, a texture, or per-vertex values.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageMap {
    /// Storage kind: a PelageMapKind value (a plain integer so that a bad
    /// value from the host is reported, not undefined behaviour).
    pub kind: u32,
    /// The value for PELAGE_MAP_KIND_CONSTANT.
    pub constant: f32,
    /// Texels or per-vertex values; borrowed for the call.
    pub data: *const c_void,
    /// Texture width in texels.
    pub width: usize,
    /// Texture height in texels.
    pub height: usize,
    /// Bytes per texture row, or between per-vertex values.
    pub stride: usize,
}

/// The bytes of a `width` x `height` texture of `size`-byte texels with rows
/// `stride` bytes apart.
pub(crate) fn texture_bytes<'a>(
    data: *const c_void,
    width: usize,
    height: usize,
    stride: usize,
    size: usize,
    name: &str,
) -> Result<&'a [u8], Failure> {
    if width == 0 || height == 0 {
        return Err(Failure::new(
            PelageStatus::InvalidArgument,
            format!("{name}: texture has zero size"),
        ));
    }
    let len = stride
        .checked_mul(height - 1)
        .and_then(|b| b.checked_add(width.checked_mul(size)?))
        .ok_or_else(|| {
            Failure::new(
                PelageStatus::InvalidArgument,
                format!("{name}: size overflows"),
            )
        })?;
    if stride < width * size {
        return Err(Failure::new(
            PelageStatus::InvalidArgument,
            format!("{name}: row stride too small"),
        ));
    }
    bytes(data, len, name)
}

impl PelageMap {
    /// A constant map.
    pub(crate) fn constant(value: f32) -> Self {
        PelageMap {
            kind: PelageMapKind::Constant as u32,
            constant: value,
            data: std::ptr::null(),
            width: 0,
            height: 0,
            stride: 0,
        }
    }

    fn texture<'a>(&self, texels: Texels<'a>) -> Texture<'a> {
        Texture {
            texels,
            width: self.width,
            height: self.height,
            row_stride: self.stride,
        }
    }

    /// Wraps the host's storage; `vertex_count` sizes per-vertex maps.
    pub(crate) fn view(
        &self,
        vertex_count: usize,
        name: &'static str,
    ) -> Result<ScalarMap<'_>, Failure> {
        let texels =
            |size| texture_bytes(self.data, self.width, self.height, self.stride, size, name);
        const CONSTANT: u32 = PelageMapKind::Constant as u32;
        const TEXTURE_U8: u32 = PelageMapKind::TextureU8 as u32;
        const TEXTURE_F32: u32 = PelageMapKind::TextureF32 as u32;
        const PER_VERTEX: u32 = PelageMapKind::PerVertex as u32;
        Ok(match self.kind {
            CONSTANT => ScalarMap::Constant(self.constant),
            TEXTURE_U8 => ScalarMap::Texture(self.texture(Texels::U8(texels(1)?))),
            TEXTURE_F32 => ScalarMap::Texture(self.texture(Texels::F32(texels(4)?))),
            PER_VERTEX => {
                ScalarMap::PerVertex(strided(self.data, self.stride, vertex_count, name)?)
            }
            other => {
                return Err(Failure::new(
                    PelageStatus::InvalidArgument,
                    format!("{name}: unknown map kind {other}"),
                ))
            }
        })
    }
}

/// A user mask over the body (paper 3.3: the regions where render hairs are
/// pushed out, or re-simulated elsewhere): evaluates `map` on `mesh` at
/// `root_count` roots and writes 1 to `mask[i]` where the value is at least
/// `threshold`, else 0 (for `PelageStrandEdits.push_mask`). Every root is
/// checked before anything is written.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (the map, a root outside
/// its triangle, a stride), NON_FINITE (also `threshold`), OUT_OF_RANGE (a
/// face), MISALIGNED, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_map_mask(
    mesh: *const PelageMeshDesc,
    map: *const PelageMap,
    roots: *const PelageRoot,
    root_count: usize,
    threshold: f32,
    mask: *mut u8,
) -> PelageStatus {
    ffi_boundary! {
        if !threshold.is_finite() {
            return Err(Failure::new(PelageStatus::NonFinite, "threshold is not finite"));
        }
        let mesh = req(mesh, "mesh")?.view()?;
        mesh.validate()?;
        let values = req(map, "map")?.view(mesh.positions.len(), "map")?;
        values.validate(&mesh, "map")?;
        let roots: &[pelage_core::Root] = bytemuck::cast_slice(slice(roots, root_count, "roots")?);
        pelage_core::root::check_roots(&mesh, roots, "roots")?;
        let mask = slice_mut(mask, root_count, "mask")?;
        for (m, r) in mask.iter_mut().zip(roots) {
            *m = (values.sample(&mesh, r.face as usize, r.u, r.v) >= threshold) as u8;
        }
        Ok(())
    }
}
