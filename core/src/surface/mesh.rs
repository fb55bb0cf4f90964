//! A borrowed triangle mesh and barycentric evaluation on it.

use crate::{Error, Strided};
use glam::{Vec2, Vec3};

/// Largest magnitude of a mesh coordinate, normal component, uv or guide
/// point coordinate: with it, every product a stage forms stays finite.
/// Production scenes span well under 1e6 units.
pub const MAX_COORDINATE: f32 = 1e9;

/// A triangle mesh borrowed from the host: positions, triangle indices and
/// optional per-vertex UVs and normals.
///
/// Roots are stored as (face, u, v), with `p = (1 - u - v) p0 + u p1 + v p2`,
/// so the same roots follow any deformation of a mesh with the same topology.
#[derive(Clone, Copy, Debug)]
pub struct Mesh<'a> {
    /// Vertex positions.
    pub positions: Strided<'a, [f32; 3]>,
    /// Vertex indices, three per triangle.
    pub triangles: Strided<'a, [u32; 3]>,
    /// Optional per-vertex texture coordinates (needed by texture maps).
    pub uvs: Option<Strided<'a, [f32; 2]>>,
    /// Optional per-vertex normals; face normals are used without them.
    pub normals: Option<Strided<'a, [f32; 3]>>,
}

/// One read of a face's corners (see [`Mesh::shape`]).
#[derive(Clone, Copy, Debug)]
pub struct FaceShape {
    /// The corners.
    pub corners: [Vec3; 3],
    /// Corner 0 to 1, corner 0 to 2, corner 1 to 2.
    pub edges: [Vec3; 3],
    /// The cross product of the first two edges: along the normal, twice
    /// the area long.
    pub cross: Vec3,
    /// The face repeats a vertex or its area is negligible next to its
    /// edge lengths.
    pub degenerate: bool,
}

impl FaceShape {
    /// The face's area: the same bits as [`Mesh::area`].
    #[inline]
    pub fn area(&self) -> f32 {
        0.5 * self.cross.length()
    }

    /// The face's perimeter, edges in corner order (0 to 1, 1 to 2, 2 to 0).
    #[inline]
    pub fn perimeter(&self) -> f32 {
        let [e01, e02, e12] = self.edges;
        e01.length() + e12.length() + e02.length()
    }
}

/// What [`Mesh::validate`] found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MeshReport {
    /// Triangles with (near-)zero area or repeated vertices; stages skip them.
    pub degenerate_triangles: usize,
    /// Sum of the areas of the non-degenerate triangles.
    pub area: f64,
}

impl<'a> Mesh<'a> {
    /// A mesh from positions and triangles, without UVs or normals.
    pub fn new(positions: Strided<'a, [f32; 3]>, triangles: Strided<'a, [u32; 3]>) -> Self {
        Mesh {
            positions,
            triangles,
            uvs: None,
            normals: None,
        }
    }

    /// Number of triangles.
    #[inline]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Checks every index and every number once; call before any stage.
    ///
    /// Out-of-range indices and non-finite values are errors; degenerate
    /// triangles are counted and later skipped.
    pub fn validate(&self) -> Result<MeshReport, Error> {
        self.check()?;
        let mut report = MeshReport::default();
        for f in 0..self.triangle_count() {
            if self.is_degenerate(f) {
                report.degenerate_triangles += 1;
            } else {
                report.area += self.area(f) as f64;
            }
        }
        Ok(report)
    }

    /// The checks of [`Mesh::validate`] without its report: what a stage
    /// that runs every frame on a deformed mesh needs.
    pub fn check(&self) -> Result<(), Error> {
        // a branch-free screen over every value; the detailed checks run
        // only when it fails, to name the fault
        fn finite<const N: usize>(s: Strided<[f32; N]>) -> bool
        where
            [f32; N]: bytemuck::Pod,
        {
            s.iter().fold(true, |ok, p| {
                p.iter().fold(ok, |ok, c| ok & (c.abs() <= MAX_COORDINATE))
            })
        }
        let nv = self.positions.len();
        let counts =
            self.uvs.is_none_or(|t| t.len() == nv) & self.normals.is_none_or(|n| n.len() == nv);
        let values =
            finite(self.positions) & self.uvs.is_none_or(finite) & self.normals.is_none_or(finite);
        let top = self
            .triangles
            .iter()
            .fold(0, |top, t| top.max(t[0]).max(t[1]).max(t[2]));
        if counts & values & ((top as usize) < nv || self.triangles.is_empty()) {
            return Ok(());
        }
        self.check_detailed()
    }

    /// [`Mesh::check`], naming the first fault.
    fn check_detailed(&self) -> Result<(), Error> {
        let nv = self.positions.len();
        for (i, p) in self.positions.iter().enumerate() {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(Error::NonFinite {
                    what: "positions",
                    index: i,
                });
            }
        }
        if let Some(uvs) = self.uvs {
            if uvs.len() != nv {
                return Err(Error::InvalidArgument("uv count differs from vertex count"));
            }
            if let Some(i) = uvs.iter().position(|t| !t.iter().all(|c| c.is_finite())) {
                return Err(Error::NonFinite {
                    what: "uvs",
                    index: i,
                });
            }
        }
        if let Some(normals) = self.normals {
            if normals.len() != nv {
                return Err(Error::InvalidArgument(
                    "normal count differs from vertex count",
                ));
            }
            if let Some(i) = normals
                .iter()
                .position(|t| !t.iter().all(|c| c.is_finite()))
            {
                return Err(Error::NonFinite {
                    what: "normals",
                    index: i,
                });
            }
        }
        let large = |s: Strided<[f32; 3]>| {
            s.iter()
                .position(|p| p.iter().any(|c| c.abs() > MAX_COORDINATE))
        };
        for (what, values) in [
            ("positions (within 1e9)", Some(self.positions)),
            ("normals (within 1e9)", self.normals),
        ] {
            if let Some(index) = values.and_then(large) {
                return Err(Error::OutOfDomain { what, index });
            }
        }
        if let Some(index) = self.uvs.and_then(|t| {
            t.iter()
                .position(|p| p.iter().any(|c| c.abs() > MAX_COORDINATE))
        }) {
            return Err(Error::OutOfDomain {
                what: "uvs (within 1e9)",
                index,
            });
        }
        for (f, tri) in self.triangles.iter().enumerate() {
            for &k in &tri {
                if k as usize >= nv {
                    return Err(Error::OutOfRange {
                        what: "triangles",
                        index: f,
                        value: k as usize,
                        bound: nv,
                    });
                }
            }
        }
        Ok(())
    }

    /// The three corner positions of `face`.
    #[inline]
    pub fn corners(&self, face: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles.get(face);
        [
            Vec3::from(self.positions.get(a as usize)),
            Vec3::from(self.positions.get(b as usize)),
            Vec3::from(self.positions.get(c as usize)),
        ]
    }

    /// Area of `face`.
    #[inline]
    pub fn area(&self, face: usize) -> f32 {
        let [a, b, c] = self.corners(face);
        0.5 * (b - a).cross(c - a).length()
    }

    /// True when `face` repeats a vertex or its area is negligible next to
    /// its edge lengths (relative test, so it does not depend on the units).
    pub fn is_degenerate(&self, face: usize) -> bool {
        self.shape(face).degenerate
    }

    /// The edges of `face`, their cross product and whether the face is
    /// degenerate, from one read of its corners: [`area`](Self::area),
    /// [`face_normal`](Self::face_normal) and
    /// [`is_degenerate`](Self::is_degenerate) derive from these, bit for bit.
    #[inline]
    pub fn shape(&self, face: usize) -> FaceShape {
        let [i, j, k] = self.triangles.get(face);
        let [a, b, c] = [i, j, k].map(|v| Vec3::from(self.positions.get(v as usize)));
        let edges = [b - a, c - a, c - b];
        let cross = edges[0].cross(edges[1]);
        let twice_area = cross.length();
        let size = edges[0]
            .length_squared()
            .max(edges[1].length_squared())
            .max(edges[2].length_squared());
        let degenerate =
            i == j || j == k || i == k || twice_area.is_nan() || twice_area <= 1e-6 * size;
        FaceShape {
            corners: [a, b, c],
            edges,
            cross,
            degenerate,
        }
    }

    /// Unit geometric normal of `face` (zero for a degenerate face).
    #[inline]
    pub fn face_normal(&self, face: usize) -> Vec3 {
        let [a, b, c] = self.corners(face);
        (b - a).cross(c - a).normalize_or_zero()
    }

    /// Position at barycentric (u, v) on `face`.
    #[inline]
    pub fn point(&self, face: usize, u: f32, v: f32) -> Vec3 {
        let [a, b, c] = self.corners(face);
        a * (1.0 - u - v) + b * u + c * v
    }

    /// Unit normal at (u, v): interpolated vertex normals when the mesh has
    /// them, the face normal otherwise.
    pub fn normal(&self, face: usize, u: f32, v: f32) -> Vec3 {
        match self.normals {
            Some(n) => {
                let [i, j, k] = self.triangles.get(face);
                let a = Vec3::from(n.get(i as usize));
                let b = Vec3::from(n.get(j as usize));
                let c = Vec3::from(n.get(k as usize));
                let s = a * (1.0 - u - v) + b * u + c * v;
                let s = s.normalize_or_zero();
                if s == Vec3::ZERO {
                    self.face_normal(face)
                } else {
                    s
                }
            }
            None => self.face_normal(face),
        }
    }

    /// Texture coordinates at (u, v), when the mesh has UVs.
    pub fn uv(&self, face: usize, u: f32, v: f32) -> Option<Vec2> {
        let uvs = self.uvs?;
        let [i, j, k] = self.triangles.get(face);
        let a = Vec2::from(uvs.get(i as usize));
        let b = Vec2::from(uvs.get(j as usize));
        let c = Vec2::from(uvs.get(k as usize));
        Some(a * (1.0 - u - v) + b * u + c * v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const P: [[f32; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [2.0, 0.0, 0.0],
    ];

    #[test]
    fn validates_indices_finiteness_and_degeneracy() {
        let tris = [[0u32, 1, 2], [0, 1, 3], [0, 0, 2]];
        let mesh = Mesh::new(Strided::from_slice(&P), Strided::from_slice(&tris));
        let r = mesh.validate().unwrap();
        assert_eq!(r.degenerate_triangles, 2);
        assert!((r.area - 0.5).abs() < 1e-9);
        let bad = [[0u32, 1, 4]];
        let mesh = Mesh::new(Strided::from_slice(&P), Strided::from_slice(&bad));
        assert!(matches!(
            mesh.validate(),
            Err(Error::OutOfRange {
                value: 4,
                bound: 4,
                ..
            })
        ));
        let nan = [[0.0, f32::NAN, 0.0]];
        let mesh = Mesh::new(Strided::from_slice(&nan), Strided::from_slice(&[]));
        assert!(matches!(
            mesh.validate(),
            Err(Error::NonFinite { index: 0, .. })
        ));
    }

    #[test]
    fn the_quick_check_names_each_fault_as_validate_does() {
        let tris = [[0u32, 1, 2], [1, 3, 2]];
        let inf_uv = [[0.0, 0.0], [1.0, 0.0], [0.0, f32::INFINITY], [1.0, 1.0]];
        let mut nan_normal = [[0.0f32, 0.0, 1.0]; 4];
        nan_normal[3] = [f32::NAN; 3];
        let few_uvs = [[0.0f32, 0.0]; 3];
        let far = [[0u32, 1, 2], [1, 9, 2]];
        let base = Mesh::new(Strided::from_slice(&P), Strided::from_slice(&tris));
        let cases = [
            base,
            Mesh {
                uvs: Some(Strided::from_slice(&inf_uv)),
                ..base
            },
            Mesh {
                normals: Some(Strided::from_slice(&nan_normal)),
                ..base
            },
            Mesh {
                uvs: Some(Strided::from_slice(&few_uvs)),
                ..base
            },
            Mesh {
                triangles: Strided::from_slice(&far),
                ..base
            },
            Mesh::new(Strided::from_slice(&[]), Strided::from_slice(&[])),
        ];
        for (i, mesh) in cases.iter().enumerate() {
            assert_eq!(mesh.check(), mesh.validate().map(|_| ()), "case {i}");
            assert_eq!(mesh.check().is_ok(), i == 0 || i == 5, "case {i}");
        }
    }

    #[test]
    fn barycentric_evaluation() {
        let tris = [[0u32, 1, 2]];
        let mesh = Mesh::new(Strided::from_slice(&P), Strided::from_slice(&tris));
        assert_eq!(mesh.point(0, 0.25, 0.5), Vec3::new(0.25, 0.5, 0.0));
        assert_eq!(mesh.normal(0, 0.2, 0.2), Vec3::Z);
    }
}
