//! Small meshes for unit tests.

use crate::{Mesh, Strided};

#[derive(Clone)]
pub struct TestMesh {
    pub p: Vec<[f32; 3]>,
    pub t: Vec<[u32; 3]>,
    pub uv: Vec<[f32; 2]>,
    /// Per-vertex normals, or empty for face normals.
    pub n: Vec<[f32; 3]>,
}

impl TestMesh {
    pub fn mesh(&self) -> Mesh<'_> {
        let mut m = Mesh::new(Strided::from_slice(&self.p), Strided::from_slice(&self.t));
        m.uvs = Some(Strided::from_slice(&self.uv));
        if !self.n.is_empty() {
            m.normals = Some(Strided::from_slice(&self.n));
        }
        m
    }
}

/// A grid over [0,1]^2 (z = 0) whose column and row widths grow
/// geometrically by `ratio` overall, so triangle areas vary by ratio^2.
pub fn graded_plane(n: usize, ratio: f32) -> TestMesh {
    let g = libm::powf(ratio, 1.0 / (n as f32 - 1.0));
    let mut xs = vec![0.0f32];
    let mut w = 1.0f32;
    for _ in 0..n {
        let last = *xs.last().unwrap();
        xs.push(last + w);
        w *= g;
    }
    let total = *xs.last().unwrap();
    let xs: Vec<f32> = xs.iter().map(|x| x / total).collect();
    let mut p = vec![];
    let mut uv = vec![];
    for &y in &xs {
        for &x in &xs {
            p.push([x, y, 0.0]);
            uv.push([x, y]);
        }
    }
    TestMesh {
        p,
        t: grid_triangles(n, n, |_| true),
        uv,
        n: vec![],
    }
}

/// The triangles of a grid of `n` x `m` cells whose `(n + 1) x (m + 1)`
/// vertices are stored row by row: two per cell, split from the cell's
/// first corner to the opposite one when `first_diagonal(cell)` holds
/// (cells counted row by row), along the other diagonal otherwise.
pub fn grid_triangles(n: usize, m: usize, first_diagonal: impl Fn(usize) -> bool) -> Vec<[u32; 3]> {
    let mut t = vec![];
    let s = (n + 1) as u32;
    for j in 0..m as u32 {
        for i in 0..n as u32 {
            let a = j * s + i;
            if first_diagonal((j * n as u32 + i) as usize) {
                t.extend([[a, a + 1, a + s + 1], [a, a + s + 1, a + s]]);
            } else {
                t.extend([[a, a + 1, a + s], [a + 1, a + s + 1, a + s]]);
            }
        }
    }
    t
}

/// [`graded_plane`] (even spacing) lifted to the height field
/// z = 0.15 sin(2 pi x) cos(2 pi y), with its exact normals: a curved skin
/// whose triangles all turn against each other.
pub fn bumpy_plane(n: usize) -> TestMesh {
    use core::f32::consts::TAU;
    let mut m = graded_plane(n, 1.0);
    m.n =
        m.p.iter_mut()
            .map(|q| {
                let (x, y) = (q[0], q[1]);
                q[2] = 0.15 * libm::sinf(TAU * x) * libm::cosf(TAU * y);
                let dx = 0.15 * TAU * libm::cosf(TAU * x) * libm::cosf(TAU * y);
                let dy = -0.15 * TAU * libm::sinf(TAU * x) * libm::sinf(TAU * y);
                glam::Vec3::new(-dx, -dy, 1.0).normalize().into()
            })
            .collect();
    m
}

/// A UV sphere with single-vertex poles.
pub fn sphere(rows: usize, cols: usize) -> TestMesh {
    let mut p = vec![[0.0, 1.0, 0.0]];
    let mut uv = vec![[0.5, 0.0]];
    for r in 1..rows {
        let th = core::f32::consts::PI * r as f32 / rows as f32;
        for c in 0..cols {
            let ph = core::f32::consts::TAU * c as f32 / cols as f32;
            p.push([
                libm::sinf(th) * libm::cosf(ph),
                libm::cosf(th),
                libm::sinf(th) * libm::sinf(ph),
            ]);
            uv.push([c as f32 / cols as f32, r as f32 / rows as f32]);
        }
    }
    p.push([0.0, -1.0, 0.0]);
    uv.push([0.5, 1.0]);
    let last = (p.len() - 1) as u32;
    let at = |r: usize, c: usize| (1 + (r - 1) * cols + c % cols) as u32;
    let mut t = vec![];
    for c in 0..cols {
        t.push([0, at(1, c + 1), at(1, c)]);
        t.push([last, at(rows - 1, c), at(rows - 1, c + 1)]);
    }
    for r in 1..rows - 1 {
        for c in 0..cols {
            t.push([at(r, c), at(r, c + 1), at(r + 1, c + 1)]);
            t.push([at(r, c), at(r + 1, c + 1), at(r + 1, c)]);
        }
    }
    TestMesh {
        p,
        t,
        uv,
        n: vec![],
    }
}

/// The C contract test's UV sphere: a duplicated seam column, and pole rows
/// of repeated points (so the pole bands hold `2 * cols` zero-area
/// triangles), with vertex normals; positions computed in f64 as there.
pub fn seamed_sphere(rows: u32, cols: u32) -> TestMesh {
    let mut m = TestMesh {
        p: vec![],
        t: vec![],
        uv: vec![],
        n: vec![],
    };
    for r in 0..=rows {
        let th = core::f64::consts::PI * r as f64 / rows as f64;
        let (st, y) = match r {
            0 => (0.0, 1.0),
            _ if r == rows => (0.0, -1.0),
            _ => (libm::sin(th), libm::cos(th)),
        };
        for c in 0..=cols {
            let ph = core::f64::consts::TAU * (c % cols) as f64 / cols as f64;
            let p = [st * libm::cos(ph), y, -st * libm::sin(ph)].map(|x| x as f32);
            m.p.push(p);
            m.n.push(p);
            m.uv.push([c as f32 / cols as f32, r as f32 / rows as f32]);
        }
    }
    for r in 0..rows {
        for c in 0..cols {
            let a = r * (cols + 1) + c;
            let (b, d) = (a + 1, a + cols + 1);
            m.t.push([a, d, d + 1]);
            m.t.push([a, d + 1, b]);
        }
    }
    m
}

/// Stamps `n` roots with `seed` (heap-backed, for tests).
pub fn roots(mesh: Mesh, n: u32, seed: u64) -> Vec<crate::Root> {
    let params = crate::StampParams {
        target_count: n,
        seed,
        ..crate::StampParams::default()
    };
    let mut buf = vec![0u8; crate::stamp::required_bytes(&mesh, &params).unwrap()];
    let mut out = vec![crate::Root::default(); crate::stamp::max_roots(&mesh, &params).unwrap()];
    let (k, _) =
        crate::stamp::stamp(mesh, &params, &mut crate::Arena::new(&mut buf), &mut out).unwrap();
    out.truncate(k);
    out
}

/// Guides of `cvs` points on `roots`: straight lines leaving each root along
/// its normal tilted by a smooth function of the root position.
pub fn straight_guides(
    mesh: &Mesh,
    roots: &[crate::Root],
    cvs: usize,
    length: f32,
) -> Vec<[f32; 3]> {
    let mut pts = vec![];
    for r in roots {
        let p = mesh.point(r.face as usize, r.u, r.v);
        let n = mesh.normal(r.face as usize, r.u, r.v);
        let tilt = glam::Vec3::new(libm::sinf(3.0 * p.x), libm::cosf(2.0 * p.y), 0.0) * 0.5;
        let d = (n + tilt - n * n.dot(tilt)).normalize();
        for j in 0..cvs {
            pts.push((p + d * (length * j as f32 / (cvs - 1) as f32)).into());
        }
    }
    pts
}
