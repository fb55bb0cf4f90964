//! Root frames: the local coordinate system a strand grows in.

use crate::Mesh;
use glam::{Vec2, Vec3};

/// An orthonormal frame at a root: `n` is the surface normal, `t` a tangent
/// tied to the triangle (its UV u-direction when the mesh has UVs, else its
/// first edge), `b = n x t`.
///
/// Because the tangent comes from the triangle's own geometry, the frame
/// follows the deforming mesh without swimming or flipping.
#[derive(Clone, Copy, Debug, PartialEq)]
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

impl Frame {
    /// The frame at barycentric (u, v) on `face`.
    pub fn at(mesh: &Mesh, face: usize, u: f32, v: f32) -> Frame {
        let [p0, p1, p2] = mesh.corners(face);
        let n = mesh.normal(face, u, v);
        let (e1, e2) = (p1 - p0, p2 - p0);
        let mut dir = e1;
        if let Some(uvs) = mesh.uvs {
            let [i, j, k] = mesh.triangles.get(face);
            let t0 = Vec2::from(uvs.get(i as usize));
            let (d1, d2) = (
                Vec2::from(uvs.get(j as usize)) - t0,
                Vec2::from(uvs.get(k as usize)) - t0,
            );
            let det = d1.perp_dot(d2);
            if det.abs() > 1e-12 {
                dir = (e1 * d2.y - e2 * d1.y) / det;
            }
        }
        let mut t = (dir - n * n.dot(dir)).normalize_or_zero();
        if t == Vec3::ZERO {
            t = n.any_orthonormal_vector();
        }
        Frame {
            origin: mesh.point(face, u, v),
            t,
            b: n.cross(t),
            n,
        }
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
