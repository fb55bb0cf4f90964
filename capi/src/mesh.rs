//! The host's triangle mesh.

use crate::buffers::strided;
use crate::status::Failure;
use pelage_core::Mesh;
use std::ffi::c_void;

/// A triangle mesh in host memory, borrowed for one call (like an Embree
/// shared buffer: pointer, byte stride, count).
///
/// `positions`: float3 per vertex. `indices`: uint32 x3 per triangle.
/// `uvs` (float2) and `normals` (float3) are optional per-vertex attributes:
/// NULL when absent. UVs are needed by texture maps; without normals, face
/// normals are used.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageMeshDesc {
    /// float3 vertex positions.
    pub positions: *const c_void,
    /// Bytes between consecutive positions (>= 12).
    pub position_stride: usize,
    /// Number of vertices.
    pub vertex_count: usize,
    /// uint32 triangle indices, three per triangle.
    pub indices: *const c_void,
    /// Bytes between consecutive triangles (>= 12).
    pub index_stride: usize,
    /// Number of triangles.
    pub triangle_count: usize,
    /// Optional float2 per-vertex UVs, or NULL.
    pub uvs: *const c_void,
    /// Bytes between consecutive UVs (>= 8).
    pub uv_stride: usize,
    /// Optional float3 per-vertex normals, or NULL.
    pub normals: *const c_void,
    /// Bytes between consecutive normals (>= 12).
    pub normal_stride: usize,
}

impl PelageMeshDesc {
    /// Checks the buffers and wraps them as a core mesh (not yet validated).
    pub(crate) fn view(&self) -> Result<Mesh<'_>, Failure> {
        let nv = self.vertex_count;
        let mut mesh = Mesh::new(
            strided(self.positions, self.position_stride, nv, "mesh positions")?,
            strided(
                self.indices,
                self.index_stride,
                self.triangle_count,
                "mesh indices",
            )?,
        );
        if !self.uvs.is_null() {
            mesh.uvs = Some(strided(self.uvs, self.uv_stride, nv, "mesh uvs")?);
        }
        if !self.normals.is_null() {
            mesh.normals = Some(strided(
                self.normals,
                self.normal_stride,
                nv,
                "mesh normals",
            )?);
        }
        Ok(mesh)
    }
}
