//! Root frames: the local coordinate system a strand grows in.

use crate::sqrt;
use crate::{Mesh, Root};
use glam::{Vec2, Vec3};

/// An orthonormal frame at a root: `n` is the surface normal, `t` the
/// mesh's vertex tangent field (see [`vertex_tangents`]) made orthogonal to
/// `n`, `b = n x t`.
///
/// Because the tangent comes from the mesh's own geometry, the frame
/// follows the deforming mesh without swimming or flipping; because it is
/// interpolated from the vertices like the normal, it does not jump where a
/// strand's root crosses from one triangle to the next.
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

/// The tangent direction of one triangle: its UV u-direction when the mesh
/// has UVs that span it, else its first edge. Not normalized: the UV
/// direction comes scaled by twice the triangle's area times its texel
/// density (no division or square root), which is the weight
/// [`vertex_tangents`] gives it.
fn face_tangent(mesh: &Mesh, face: usize, corners: [Vec3; 3]) -> Vec3 {
    let [p0, p1, p2] = corners;
    let (e1, e2) = (p1 - p0, p2 - p0);
    if let Some(uvs) = mesh.uvs {
        let idx = mesh.triangles.get(face);
        let t0 = Vec2::from(uvs.get(idx[0] as usize));
        let d1 = Vec2::from(uvs.get(idx[1] as usize)) - t0;
        let d2 = Vec2::from(uvs.get(idx[2] as usize)) - t0;
        let det = d1.perp_dot(d2);
        // the gradient of u is (e1 d2.y - e2 d1.y) / det: only det's sign
        // matters for the direction (mirrored UV islands)
        if det.abs() > 1e-12 {
            let t = e1 * d2.y - e2 * d1.y;
            return if det > 0.0 { t } else { -t };
        }
    }
    e1
}

/// Writes a unit tangent per vertex of a checked `mesh` to `out` (its
/// first `positions.len()` entries): the weighted mean direction of the
/// face tangents around the vertex (weighted by area where the UVs have an
/// even texel density), zero where they cancel.
///
/// Frames interpolate these over each triangle, so a tangent field that is
/// continuous across triangle edges (within a UV island) gives strands that
/// do not turn where their roots change triangle. Computed once per frame
/// on the deformed mesh; it costs one pass over the triangles.
pub fn vertex_tangents(mesh: &Mesh, out: &mut [[f32; 3]]) {
    let nv = mesh.positions.len().min(out.len());
    let out = &mut out[..nv];
    out.fill([0.0; 3]);
    for (f, idx) in mesh.triangles.iter().enumerate() {
        let t = face_tangent(mesh, f, mesh.corners(f));
        for i in idx {
            if let Some(o) = out.get_mut(i as usize) {
                *o = (Vec3::from(*o) + t).into();
            }
        }
    }
    for o in out.iter_mut() {
        *o = Vec3::from(*o).normalize_or_zero().into();
    }
}

/// `t` made orthogonal to the unit normal `n` and unit length, or zero.
#[inline]
fn orthogonal(t: Vec3, n: Vec3) -> Vec3 {
    sqrt::normalize_or_zero(t - n * n.dot(t))
}

/// The tangent where the interpolated vertex tangent is lost (zero, or along
/// the normal): the triangle's own tangent, else any direction.
fn fallback_tangent(n: Vec3, face_tangent: Vec3) -> Vec3 {
    let t = orthogonal(face_tangent, n);
    if t == Vec3::ZERO {
        n.any_orthonormal_vector()
    } else {
        t
    }
}

/// What every frame on one triangle shares: its corners, corner normals,
/// corner tangents and own tangent. Strands come in face order, so
/// expansion computes this once per triangle instead of once per strand.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceBasis {
    corners: [Vec3; 3],
    normals: Option<[Vec3; 3]>,
    face_normal: Vec3,
    tangents: [Vec3; 3],
    tangent: Vec3,
}

impl FaceBasis {
    /// The basis of `face`, with the vertex `tangents` of [`vertex_tangents`]
    /// (a vertex missing from the slice counts as zero, so an empty slice
    /// gives every frame its triangle's own tangent).
    pub fn new(mesh: &Mesh, tangents: &[[f32; 3]], face: usize) -> Self {
        let corners = mesh.corners(face);
        let [p0, p1, p2] = corners;
        let idx = mesh.triangles.get(face);
        let vertex_tangent =
            |i: u32| Vec3::from(tangents.get(i as usize).copied().unwrap_or_default());
        FaceBasis {
            corners,
            normals: mesh
                .normals
                .map(|n| idx.map(|i| Vec3::from(n.get(i as usize)))),
            face_normal: sqrt::normalize_or_zero((p1 - p0).cross(p2 - p0)),
            tangents: idx.map(vertex_tangent),
            tangent: face_tangent(mesh, face, corners),
        }
    }

    /// The normal sum and tangent sum at barycentric (u, v), before either
    /// is normalized.
    #[inline]
    fn sums(&self, u: f32, v: f32) -> (Vec3, Vec3) {
        let w = 1.0 - u - v;
        let [ta, tb, tc] = self.tangents;
        let n = match self.normals {
            Some([na, nb, nc]) => na * w + nb * u + nc * v,
            None => Vec3::ZERO,
        };
        (n, ta * w + tb * u + tc * v)
    }

    /// The frame at barycentric (u, v); the same numbers as
    /// [`Mesh::point`] and [`Mesh::normal`] give. Where there is no normal
    /// (a collapsed triangle without vertex normals) every axis is zero:
    /// what the frame carries collapses onto its origin, rather than onto
    /// a line in some arbitrary direction.
    #[inline]
    pub fn frame(&self, u: f32, v: f32) -> Frame {
        let [a, b, c] = self.corners;
        let w = 1.0 - u - v;
        let (n, t) = self.sums(u, v);
        // a zero normal sum falls back to the face normal, as in
        // `Mesh::normal`; without vertex normals that is every root
        let n = match sqrt::normalize_or_zero(n) {
            Vec3::ZERO => self.face_normal,
            n => n,
        };
        let t = match orthogonal(t, n) {
            _ if n == Vec3::ZERO => Vec3::ZERO,
            Vec3::ZERO => fallback_tangent(n, self.tangent),
            t => t,
        };
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
/// order). Inlined whole, so that the AVX2 expansion compiles it for AVX2.
#[inline(always)]
pub(crate) fn frames(
    mesh: &Mesh,
    tangents: &[[f32; 3]],
    roots: &[Root],
    basis: &mut Option<(u32, FaceBasis)>,
    out: &mut [Frame],
) {
    let len = roots.len().min(out.len()).min(FRAME_LANES);
    let lanes = &mut FrameLanes::default();
    for (i, root) in roots[..len].iter().enumerate() {
        let face = match basis {
            Some((f, b)) if *f == root.face => b,
            _ => {
                let b = FaceBasis::new(mesh, tangents, root.face as usize);
                &basis.insert((root.face, b)).1
            }
        };
        let (u, v) = (root.u, root.v);
        let w = 1.0 - u - v;
        let [a, b, c] = face.corners;
        out[i].origin = a * w + b * u + c * v;
        let (n, t) = face.sums(u, v);
        lanes.set(i, n, face.face_normal, t);
    }
    let FrameLanes { n, face_n, t } = lanes;
    normalize_or_zero(n);
    // component by component, so that each loop runs over whole lanes
    let mut zero = [false; FRAME_LANES];
    for (i, z) in zero.iter_mut().enumerate() {
        *z = n[0][i] == 0.0 && n[1][i] == 0.0 && n[2][i] == 0.0;
    }
    for (c, f) in n.iter_mut().zip(face_n.iter()) {
        for i in 0..FRAME_LANES {
            c[i] = if zero[i] { f[i] } else { c[i] };
        }
    }
    let mut d = [0.0f32; FRAME_LANES];
    for (i, d) in d.iter_mut().enumerate() {
        *d = n[0][i] * t[0][i] + n[1][i] * t[1][i] + n[2][i] * t[2][i];
    }
    for (c, nc) in t.iter_mut().zip(n.iter()) {
        for i in 0..FRAME_LANES {
            c[i] -= nc[i] * d[i];
        }
    }
    normalize_or_zero(t);
    for (i, frame) in out[..len].iter_mut().enumerate() {
        let nv = Vec3::new(n[0][i], n[1][i], n[2][i]);
        let mut tv = Vec3::new(t[0][i], t[1][i], t[2][i]);
        if nv == Vec3::ZERO {
            tv = Vec3::ZERO;
        } else if tv == Vec3::ZERO {
            // rare (the vertex tangents cancel or run along the normal): the
            // triangle's own tangent is computed again only here
            let face = roots[i].face as usize;
            tv = fallback_tangent(nv, face_tangent(mesh, face, mesh.corners(face)));
        }
        (frame.n, frame.t, frame.b) = (nv, tv, nv.cross(tv));
    }
}

/// Roots per [`frames`] call.
pub(crate) const FRAME_LANES: usize = 32;

/// x, y and z lanes of one vector per root.
type Lanes3 = [[f32; FRAME_LANES]; 3];

/// [`frames`]' working lanes: the normal (first unnormalized), the face
/// normal, and the tangent (first the interpolated sum, then made
/// orthogonal).
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
    sqrt::sqrt_lanes(&mut rcp);
    for r in rcp.iter_mut() {
        *r = 1.0 / *r;
    }
    for c in v.iter_mut() {
        for (x, &r) in c.iter_mut().zip(&rcp) {
            *x = if r.is_finite() && r > 0.0 {
                *x * r
            } else {
                0.0
            };
        }
    }
}

impl Frame {
    /// The frame at barycentric (u, v) on `face`, with the vertex
    /// `tangents` of [`vertex_tangents`] (see [`FaceBasis::new`]).
    pub fn at(mesh: &Mesh, tangents: &[[f32; 3]], face: usize, u: f32, v: f32) -> Frame {
        FaceBasis::new(mesh, tangents, face).frame(u, v)
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
    use crate::testmesh::{bumpy_plane, roots, sphere};
    use crate::Strided;

    fn tangents(mesh: &Mesh) -> Vec<[f32; 3]> {
        let mut t = vec![[0.0; 3]; mesh.positions.len()];
        vertex_tangents(mesh, &mut t);
        t
    }

    #[test]
    fn frames_are_orthonormal_and_match_mesh_evaluation() {
        let m = sphere(8, 16);
        let mesh = m.mesh();
        let tangents = tangents(&mesh);
        for f in 0..mesh.triangle_count() {
            let fr = Frame::at(&mesh, &tangents, f, 0.2, 0.3);
            assert_eq!(fr.origin, mesh.point(f, 0.2, 0.3));
            assert_eq!(fr.n, mesh.normal(f, 0.2, 0.3));
            for (a, b) in [(fr.t, fr.b), (fr.b, fr.n), (fr.n, fr.t)] {
                assert!(a.dot(b).abs() < 1e-5);
            }
            let p = Vec3::new(0.3, -0.2, 0.9);
            assert!(fr.to_world(fr.to_local(p)).distance(p) < 1e-5);
        }
    }

    /// The barycentric (u, v) of corner `k` of a triangle.
    fn corner_uv(k: usize) -> Vec2 {
        [Vec2::ZERO, Vec2::X, Vec2::Y][k]
    }

    #[test]
    fn frames_agree_across_triangle_edges() {
        // where two triangles share an edge, a root on it gets the same
        // frame from either: the strand does not turn as its root crosses
        // (the sphere's UV seam and poles included: its seam vertices are
        // shared, so its face tangents there disagree)
        let mut ball = sphere(10, 20);
        ball.n = ball.p.clone();
        for m in [bumpy_plane(12), ball] {
            let mesh = m.mesh();
            let tangents = tangents(&mesh);
            let mut edges = std::collections::HashMap::new();
            let mut shared = 0;
            for f in 0..mesh.triangle_count() {
                let idx = mesh.triangles.get(f);
                for k in 0..3 {
                    let (a, b) = (idx[k], idx[(k + 1) % 3]);
                    // a point 30% along the edge from its lower vertex
                    let (lo, hi) = if a < b {
                        (k, (k + 1) % 3)
                    } else {
                        ((k + 1) % 3, k)
                    };
                    let at = corner_uv(lo).lerp(corner_uv(hi), 0.3);
                    let frame = Frame::at(&mesh, &tangents, f, at.x, at.y);
                    if let Some(other) = edges.insert((a.min(b), a.max(b)), frame) {
                        shared += 1;
                        assert!(frame.origin.distance(other.origin) < 1e-6);
                        let turn = frame.t.distance(other.t);
                        assert!(turn < 1e-5, "face {f}: tangents {turn} apart");
                        assert!(frame.n.distance(other.n) < 1e-5);
                    }
                }
            }
            assert!(shared > mesh.triangle_count());
        }
    }

    /// Every root's frame from `frames`, block by block, against `FaceBasis::frame`.
    fn assert_blocks_match(mesh: &Mesh, tangents: &[[f32; 3]], roots: &[Root]) {
        let mut basis = None;
        let mut out = [Frame::default(); FRAME_LANES];
        for (b, block) in roots.chunks(FRAME_LANES).enumerate() {
            frames(mesh, tangents, block, &mut basis, &mut out);
            for (i, (r, f)) in block.iter().zip(&out).enumerate() {
                let want = FaceBasis::new(mesh, tangents, r.face as usize).frame(r.u, r.v);
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
        assert_blocks_match(&mesh, &tangents(&mesh), &rs);
        // three triangles with UVs = xy, so every tangent is exactly x: on
        // the first the corner normals at (0.5, 0.5) cancel (face normal
        // fallback); on the second they all point along x, the tangent
        // (any-orthonormal fallback); the third has no vertex tangents
        // (its triangle's tangent)
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let p: Vec<[f32; 3]> = p.iter().cycle().take(9).copied().collect();
        let uv: Vec<[f32; 2]> = p.iter().map(|q| [q[0], q[1]]).collect();
        let (x, z) = ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
        let normals = [z, x, [-1.0, 0.0, 0.0], x, x, x, z, z, z];
        let t = [[0, 1, 2], [3, 4, 5], [6, 7, 8]];
        let mut mesh = Mesh::new(Strided::from_slice(&p), Strided::from_slice(&t));
        mesh.uvs = Some(Strided::from_slice(&uv));
        mesh.normals = Some(Strided::from_slice(&normals));
        let tangents = &tangents(&mesh)[..6];
        let at = |face| Root {
            face,
            u: 0.5,
            v: 0.5,
            ..Root::default()
        };
        let basis = |f| FaceBasis::new(&mesh, tangents, f);
        let (cancel, along, bare) = (basis(0), basis(1), basis(2));
        assert_eq!(cancel.frame(0.5, 0.5).n, cancel.face_normal);
        assert_eq!(cancel.frame(0.5, 0.5).t, Vec3::X);
        let f = along.frame(0.5, 0.5);
        assert_eq!(f.t, f.n.any_orthonormal_vector());
        assert_eq!(bare.frame(0.5, 0.5).t, Vec3::X);
        let mut blocks = vec![at(0); 5];
        blocks.extend([at(1); 40]);
        blocks.extend([at(2); 30]);
        assert_blocks_match(&mesh, tangents, &blocks);
    }

    #[test]
    fn a_collapsed_triangle_has_a_zero_frame_on_both_paths() {
        // triangle 1 collapsed to a point; triangle 0 shares a vertex, so
        // the vertex tangents there are not zero
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [2.0, 2.0, 0.0],
        ];
        let t = [[0u32, 1, 2], [3, 3, 3]];
        let uv = [[0.0f32, 0.0], [1.0, 0.0], [0.0, 1.0], [0.5, 0.5]];
        let mut mesh = Mesh::new(Strided::from_slice(&p), Strided::from_slice(&t));
        mesh.uvs = Some(Strided::from_slice(&uv));
        let tangents = tangents(&mesh);
        let f = FaceBasis::new(&mesh, &tangents, 1).frame(0.3, 0.3);
        assert_eq!((f.t, f.b, f.n), (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO));
        assert_eq!(
            f.to_world(Vec3::new(0.1, 0.2, 0.3)),
            Vec3::new(2.0, 2.0, 0.0)
        );
        let root = |face| Root {
            face,
            u: 0.3,
            v: 0.3,
            ..Root::default()
        };
        assert_blocks_match(&mesh, &tangents, &[root(0), root(1), root(0), root(1)]);
    }
}
