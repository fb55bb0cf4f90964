//! Root frames: the local coordinate system a strand grows in.

use crate::{Mesh, Root};
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

/// Computes the frames of up to [`FRAME_LANES`] roots together, with the
/// same numbers [`FaceBasis::frame`] gives for each.
///
/// A frame is a chain of two square roots and two divisions. Done root by
/// root, each chain stalls the next; done lane by lane over the block, the
/// chains of different roots overlap and the divisions vectorize.
/// `basis` caches the last face's basis across calls (roots come in face
/// order).
pub(crate) fn frames(
    mesh: &Mesh,
    roots: &[Root],
    basis: &mut Option<(u32, FaceBasis)>,
    out: &mut [Frame],
) {
    let len = roots.len().min(out.len()).min(FRAME_LANES);
    let lanes = &mut FrameLanes::default();
    for (i, root) in roots[..len].iter().enumerate() {
        let face = match *basis {
            Some((f, b)) if f == root.face => b,
            _ => {
                let b = FaceBasis::new(mesh, root.face as usize);
                *basis = Some((root.face, b));
                b
            }
        };
        let (u, v) = (root.u, root.v);
        let w = 1.0 - u - v;
        let [a, b, c] = face.corners;
        out[i].origin = a * w + b * u + c * v;
        // a zero normal sum falls back to the face normal, as in `frame`;
        // without vertex normals that is every root
        let s = match face.normals {
            Some([na, nb, nc]) => na * w + nb * u + nc * v,
            None => Vec3::ZERO,
        };
        lanes.set(i, s, face.face_normal, face.tangent);
    }
    let FrameLanes { n, face_n, t } = lanes;
    normalize_or_zero(n);
    for i in 0..FRAME_LANES {
        let zero = n[0][i] == 0.0 && n[1][i] == 0.0 && n[2][i] == 0.0;
        for (c, f) in n.iter_mut().zip(face_n.iter()) {
            c[i] = if zero { f[i] } else { c[i] };
        }
        let d = n[0][i] * t[0][i] + n[1][i] * t[1][i] + n[2][i] * t[2][i];
        for (c, nc) in t.iter_mut().zip(n.iter()) {
            c[i] -= nc[i] * d;
        }
    }
    normalize_or_zero(t);
    for (i, frame) in out[..len].iter_mut().enumerate() {
        let nv = Vec3::new(n[0][i], n[1][i], n[2][i]);
        let mut tv = Vec3::new(t[0][i], t[1][i], t[2][i]);
        if tv == Vec3::ZERO {
            tv = nv.any_orthonormal_vector();
        }
        (frame.n, frame.t, frame.b) = (nv, tv, nv.cross(tv));
    }
}

/// Roots per [`frames`] call.
pub(crate) const FRAME_LANES: usize = 32;

/// x, y and z lanes of one vector per root.
type Lanes3 = [[f32; FRAME_LANES]; 3];

/// [`frames`]' working lanes: the normal (first unnormalized), the face
/// normal, and the tangent (first the face's, then made orthogonal).
#[derive(Default)]
struct FrameLanes {
    n: Lanes3,
    face_n: Lanes3,
    t: Lanes3,
}

impl FrameLanes {
    fn set(&mut self, i: usize, n: Vec3, face_n: Vec3, t: Vec3) {
        for (lanes, v) in [
            (&mut self.n, n),
            (&mut self.face_n, face_n),
            (&mut self.t, t),
        ] {
            (lanes[0][i], lanes[1][i], lanes[2][i]) = (v.x, v.y, v.z);
        }
    }
}

/// `Vec3::normalize_or_zero` lane by lane, operation for operation (the
/// same bits).
fn normalize_or_zero(v: &mut Lanes3) {
    let mut rcp = [0.0f32; FRAME_LANES];
    for (i, r) in rcp.iter_mut().enumerate() {
        *r = v[0][i] * v[0][i] + v[1][i] * v[1][i] + v[2][i] * v[2][i];
    }
    for r in rcp.iter_mut() {
        *r = libm::sqrtf(*r);
    }
    for r in rcp.iter_mut() {
        *r = 1.0 / *r;
    }
    for (i, &r) in rcp.iter().enumerate() {
        let ok = r.is_finite() && r > 0.0;
        for c in v.iter_mut() {
            c[i] = if ok { c[i] * r } else { 0.0 };
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
    use crate::testmesh::{roots, sphere};
    use crate::Strided;

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

    /// Every root's frame from `frames`, block by block, against `FaceBasis::frame`.
    fn assert_blocks_match(mesh: &Mesh, roots: &[Root]) {
        let mut basis = None;
        let mut out = [Frame::default(); FRAME_LANES];
        for (b, block) in roots.chunks(FRAME_LANES).enumerate() {
            frames(mesh, block, &mut basis, &mut out);
            for (i, (r, f)) in block.iter().zip(&out).enumerate() {
                let want = FaceBasis::new(mesh, r.face as usize).frame(r.u, r.v);
                assert_eq!(*f, want, "root {}", b * FRAME_LANES + i);
            }
        }
    }

    #[test]
    fn block_frames_are_the_per_root_frames() {
        let m = sphere(12, 24);
        let mesh = m.mesh();
        let mut rs = roots(mesh, 700, 3);
        rs.sort_by_key(|r| r.face);
        assert_blocks_match(&mesh, &rs);
        // two triangles with UVs = xy, so the tangent is exactly x: on the
        // first the corner normals at (0.5, 0.5) cancel (face normal
        // fallback), on the second they all point along x, the tangent
        // (any-orthonormal fallback)
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let p: Vec<[f32; 3]> = p.iter().chain(&p).copied().collect();
        let uv: Vec<[f32; 2]> = p.iter().map(|q| [q[0], q[1]]).collect();
        let x = [1.0, 0.0, 0.0];
        let normals = [[0.0, 0.0, 1.0], x, [-1.0, 0.0, 0.0], x, x, x];
        let t = [[0, 1, 2], [3, 4, 5]];
        let mut mesh = Mesh::new(Strided::from_slice(&p), Strided::from_slice(&t));
        mesh.uvs = Some(Strided::from_slice(&uv));
        mesh.normals = Some(Strided::from_slice(&normals));
        let at = |face| Root {
            face,
            u: 0.5,
            v: 0.5,
            ..Root::default()
        };
        let (cancel, along) = (FaceBasis::new(&mesh, 0), FaceBasis::new(&mesh, 1));
        assert_eq!(cancel.frame(0.5, 0.5).n, cancel.face_normal);
        let f = along.frame(0.5, 0.5);
        assert_eq!(f.t, f.n.any_orthonormal_vector());
        let mut with_normals = vec![at(0); 5];
        with_normals.extend([at(1); 40]);
        assert_blocks_match(&mesh, &with_normals);
    }
}
