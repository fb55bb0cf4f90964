//! Root frames: the local coordinate system a strand grows in.

use crate::Mesh;
use glam::{Vec2, Vec3};

/// An orthonormal frame at a root: `n` is the surface normal, `t` a tangent
/// tied to the triangle (its UV u-direction when the mesh has UVs, else its
/// first edge), `b = n x t`.
///
/// Because the tangent comes from the triangle's own geometry, the frame
/// follows the deforming mesh without swimming or flipping.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Frame {
    /// Root position.
    pub origin: Vec3,
    /// Tangent.
    pub t: Vec3,
    /// Bitangent.
    pub b: Vec3,
    /// Normal.
    pub n: Vec3,
}

/// What every frame on one triangle shares: its corners, corner normals and
/// tangent direction. Strands come in face order, so expansion computes this
/// once per triangle instead of once per strand.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceBasis {
    corners: [Vec3; 3],
    normals: Option<[Vec3; 3]>,
    face_normal: Vec3,
    tangent: Vec3,
}

impl FaceBasis {
    /// The basis of `face`.
    pub fn new(mesh: &Mesh, face: usize) -> Self {
        let corners = mesh.corners(face);
        let [p0, p1, p2] = corners;
        let (e1, e2) = (p1 - p0, p2 - p0);
        let idx = mesh.triangles.get(face);
        let mut tangent = e1;
        if let Some(uvs) = mesh.uvs {
            let t0 = Vec2::from(uvs.get(idx[0] as usize));
            let d1 = Vec2::from(uvs.get(idx[1] as usize)) - t0;
            let d2 = Vec2::from(uvs.get(idx[2] as usize)) - t0;
            let det = d1.perp_dot(d2);
            if det.abs() > 1e-12 {
                tangent = (e1 * d2.y - e2 * d1.y) / det;
            }
        }
        FaceBasis {
            corners,
            normals: mesh
                .normals
                .map(|n| idx.map(|i| Vec3::from(n.get(i as usize)))),
            face_normal: e1.cross(e2).normalize_or_zero(),
            tangent,
        }
    }

    /// The frame at barycentric (u, v); the same numbers as
    /// [`Mesh::point`] and [`Mesh::normal`] give.
    #[inline]
    pub fn frame(&self, u: f32, v: f32) -> Frame {
        let [a, b, c] = self.corners;
        let w = 1.0 - u - v;
        let n = match self.normals {
            Some([na, nb, nc]) => {
                let s = (na * w + nb * u + nc * v).normalize_or_zero();
                if s == Vec3::ZERO {
                    self.face_normal
                } else {
                    s
                }
            }
            None => self.face_normal,
        };
        let mut t = (self.tangent - n * n.dot(self.tangent)).normalize_or_zero();
        if t == Vec3::ZERO {
            t = n.any_orthonormal_vector();
        }
        Frame {
            origin: a * w + b * u + c * v,
            t,
            b: n.cross(t),
            n,
        }
    }
}

impl Frame {
    /// The frame at barycentric (u, v) on `face`.
    pub fn at(mesh: &Mesh, face: usize, u: f32, v: f32) -> Frame {
        FaceBasis::new(mesh, face).frame(u, v)
    }

    /// World point to frame coordinates.
    #[inline]
    pub fn to_local(&self, p: Vec3) -> Vec3 {
        let d = p - self.origin;
        Vec3::new(d.dot(self.t), d.dot(self.b), d.dot(self.n))
    }

    /// Frame coordinates to a world point.
    #[inline]
    pub fn to_world(&self, l: Vec3) -> Vec3 {
        self.origin + self.t * l.x + self.b * l.y + self.n * l.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testmesh::sphere;

    #[test]
    fn frames_are_orthonormal_and_match_mesh_evaluation() {
        let m = sphere(8, 16);
        let mesh = m.mesh();
        for f in 0..mesh.triangle_count() {
            let fr = Frame::at(&mesh, f, 0.2, 0.3);
            assert_eq!(fr.origin, mesh.point(f, 0.2, 0.3));
            assert_eq!(fr.n, mesh.normal(f, 0.2, 0.3));
            for (a, b) in [(fr.t, fr.b), (fr.b, fr.n), (fr.n, fr.t)] {
                assert!(a.dot(b).abs() < 1e-5);
            }
            let p = Vec3::new(0.3, -0.2, 0.9);
            assert!(fr.to_world(fr.to_local(p)).distance(p) < 1e-5);
        }
    }
}
