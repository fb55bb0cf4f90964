//! Parting regions for binding.

use crate::buffers::strided;
use crate::map::texture_bytes;
use crate::status::Failure;
use crate::PelageStatus;
use pelage_core::surface::map::{Texels, Texture};
use pelage_core::RegionMap;
use std::ffi::c_void;

/// How a [`PelageRegionMap`] stores its ids.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PelageRegionKind {
    /// No partings: every strand may use every guide; `data` is ignored.
    None = 0,
    /// One uint32 id per mesh vertex, `stride` bytes apart (4-byte aligned);
    /// a root takes the id of its nearest corner.
    PerVertex = 1,
    /// An 8-bit id texture over UV, `width` x `height`, `stride` bytes per
    /// row, row 0 at v = 0; a root takes the texel it falls in, unfiltered.
    /// Needs mesh UVs.
    TextureU8 = 2,
}

/// Parting regions: a strand only uses guides of its own region id.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageRegionMap {
    /// Storage kind: a PelageRegionKind value.
    pub kind: u32,
    /// Ids; borrowed for the call.
    pub data: *const c_void,
    /// Texture width in texels.
    pub width: usize,
    /// Texture height in texels.
    pub height: usize,
    /// Bytes per texture row, or between per-vertex ids.
    pub stride: usize,
}

impl PelageRegionMap {
    /// No partings.
    pub(crate) fn none() -> Self {
        PelageRegionMap {
            kind: PelageRegionKind::None as u32,
            data: std::ptr::null(),
            width: 0,
            height: 0,
            stride: 0,
        }
    }

    /// Wraps the host's storage; `vertex_count` sizes per-vertex ids.
    pub(crate) fn view(&self, vertex_count: usize) -> Result<Option<RegionMap<'_>>, Failure> {
        const NONE: u32 = PelageRegionKind::None as u32;
        const PER_VERTEX: u32 = PelageRegionKind::PerVertex as u32;
        const TEXTURE_U8: u32 = PelageRegionKind::TextureU8 as u32;
        let name = "regions";
        Ok(match self.kind {
            NONE => None,
            PER_VERTEX => Some(RegionMap::PerVertex(strided(
                self.data,
                self.stride,
                vertex_count,
                name,
            )?)),
            TEXTURE_U8 => Some(RegionMap::Texture(Texture {
                texels: Texels::U8(texture_bytes(
                    self.data,
                    self.width,
                    self.height,
                    self.stride,
                    1,
                    name,
                )?),
                width: self.width,
                height: self.height,
                row_stride: self.stride,
            })),
            other => {
                return Err(Failure::new(
                    PelageStatus::InvalidArgument,
                    format!("{name}: unknown region kind {other}"),
                ))
            }
        })
    }
}
