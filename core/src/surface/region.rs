//! Parting regions: an integer id over the mesh surface.
//!
//! A strand only takes guides of its own region (Blender's group id, XGen and
//! Ornatrix partings). Ids are labels, never blended: a root takes the id of
//! its nearest corner or of the texel it falls in.

use crate::surface::map::{Texels, Texture};
use crate::{Error, Mesh, Root, ScalarMap, Strided};

/// Where the parting region of a root comes from.
#[derive(Clone, Copy, Debug)]
pub enum RegionMap<'a> {
    /// One id per mesh vertex; a root takes the id of its nearest corner.
    PerVertex(Strided<'a, u32>),
    /// An 8-bit id texture over UV (an id map painted with hard edges): a
    /// root takes the texel it falls in, unfiltered. The mesh needs UVs.
    Texture(Texture<'a>),
}

impl RegionMap<'_> {
    /// Checks sizes against `mesh`; every lookup is then in bounds.
    pub fn validate(&self, mesh: &Mesh) -> Result<(), Error> {
        match *self {
            RegionMap::PerVertex(ids) if ids.len() != mesh.positions.len() => Err(
                Error::InvalidArgument("region map size differs from vertex count"),
            ),
            RegionMap::PerVertex(_) => Ok(()),
            RegionMap::Texture(t) => {
                if let Texels::F32(_) = t.texels {
                    return Err(Error::InvalidArgument(
                        "a region texture holds 8-bit ids, not floats",
                    ));
                }
                ScalarMap::Texture(t).validate(mesh, "region texture")
            }
        }
    }

    /// The region of `root`. Call [`validate`](Self::validate) first.
    #[inline]
    pub fn region(&self, mesh: &Mesh, root: &Root) -> u32 {
        match *self {
            RegionMap::PerVertex(ids) => {
                let tri = mesh.triangles.get(root.face as usize);
                let w = [1.0 - root.u - root.v, root.u, root.v];
                let corner = if w[0] >= w[1] && w[0] >= w[2] {
                    0
                } else if w[1] >= w[2] {
                    1
                } else {
                    2
                };
                ids.get(tri[corner] as usize)
            }
            RegionMap::Texture(t) => match mesh.uv(root.face as usize, root.u, root.v) {
                Some(uv) => t.nearest_byte(uv.x, uv.y) as u32,
                None => 0,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testmesh::graded_plane;

    #[test]
    fn texture_ids_are_not_blended() {
        let m = graded_plane(4, 1.0);
        let mesh = m.mesh();
        // left half id 3, right half id 200
        let texels = [3u8, 3, 200, 200, 3, 3, 200, 200];
        let map = RegionMap::Texture(Texture {
            texels: Texels::U8(&texels),
            width: 4,
            height: 2,
            row_stride: 4,
        });
        map.validate(&mesh).unwrap();
        for face in 0..mesh.triangle_count() {
            for (u, v) in [(0.2, 0.2), (0.6, 0.3), (0.1, 0.7)] {
                let root = Root {
                    face: face as u32,
                    u,
                    v,
                    id: 0,
                    rank: 0,
                };
                let uv = mesh.uv(face, u, v).unwrap();
                let id = map.region(&mesh, &root);
                assert_eq!(id, if uv.x < 0.5 { 3 } else { 200 }, "at {uv}");
            }
        }
        let floats = [0u8; 32];
        let bad = RegionMap::Texture(Texture {
            texels: Texels::F32(&floats),
            width: 4,
            height: 2,
            row_stride: 16,
        });
        assert!(matches!(
            bad.validate(&mesh),
            Err(Error::InvalidArgument(_))
        ));
    }
}
