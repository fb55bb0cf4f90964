//! What a corpus mesh is made of, measured from its arrays alone: shells,
//! boundary loops, non-manifold edges, creases, degenerate faces, slivers,
//! rim planarity and parts that cut through each other.
//!
//! Vertices with bit-identical positions are one vertex here (UV seams
//! split vertices, not the surface), and a face that repeats a vertex once
//! welded (a zero-area face whose corners coincide) joins no edge.

use std::collections::HashMap;
use std::ops::Range;

use glam::DVec3;

use crate::creature::CreatureMesh;

fn point(m: &CreatureMesh, i: u32) -> DVec3 {
    DVec3::from(m.positions[i as usize].map(f64::from))
}

/// For each vertex, the first vertex with its bit-identical position.
pub fn welded(m: &CreatureMesh) -> Vec<u32> {
    let mut ids = HashMap::new();
    m.positions
        .iter()
        .enumerate()
        .map(|(i, p)| *ids.entry(p.map(f32::to_bits)).or_insert(i as u32))
        .collect()
}

/// The faces of each undirected welded edge (smaller vertex first), from
/// the faces that do not repeat a welded vertex.
pub fn edge_faces(m: &CreatureMesh) -> HashMap<(u32, u32), Vec<u32>> {
    let weld = welded(m);
    let mut edges: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for (f, t) in m.triangles.iter().enumerate() {
        let v = t.map(|i| weld[i as usize]);
        if v[0] == v[1] || v[1] == v[2] || v[2] == v[0] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            edges
                .entry((a.min(b), a.max(b)))
                .or_default()
                .push(f as u32);
        }
    }
    edges
}

/// The boundary (the edges with exactly one face), split into connected
/// pieces.
#[derive(Clone, Debug, Default)]
pub struct Boundary {
    /// Pieces that are simple closed loops (every vertex on two boundary
    /// edges), as their welded vertices in order around the loop.
    pub loops: Vec<Vec<u32>>,
    /// Pieces that are open chains (two ends on one boundary edge each).
    pub chains: usize,
    /// Pieces with a vertex on more than two boundary edges (loops that
    /// touch, or a chain that branches).
    pub pinched: usize,
}

/// The boundary of `m`.
pub fn boundary(m: &CreatureMesh) -> Boundary {
    let mut next: HashMap<u32, Vec<u32>> = HashMap::new();
    for (&(a, b), faces) in &edge_faces(m) {
        if faces.len() == 1 {
            next.entry(a).or_default().push(b);
            next.entry(b).or_default().push(a);
        }
    }
    let mut keys: Vec<u32> = next.keys().copied().collect();
    keys.sort_unstable();
    let mut seen = HashMap::new();
    let mut out = Boundary::default();
    for start in keys {
        if seen.contains_key(&start) {
            continue;
        }
        // the piece's vertices, by a walk over the boundary graph
        let mut piece = vec![start];
        seen.insert(start, ());
        let mut k = 0;
        while k < piece.len() {
            for &w in &next[&piece[k]] {
                if seen.insert(w, ()).is_none() {
                    piece.push(w);
                }
            }
            k += 1;
        }
        let degrees: Vec<usize> = piece.iter().map(|v| next[v].len()).collect();
        if degrees.iter().any(|&d| d > 2) {
            out.pinched += 1;
        } else if degrees.contains(&1) {
            out.chains += 1;
        } else {
            // in order around the loop
            let mut order = vec![start];
            let (mut prev, mut v) = (start, next[&start][0]);
            while v != start {
                order.push(v);
                let n = &next[&v];
                let w = if n[0] == prev { n[1] } else { n[0] };
                (prev, v) = (v, w);
            }
            out.loops.push(order);
        }
    }
    out.loops.sort_by_key(|l| std::cmp::Reverse(l.len()));
    out
}

/// The shell (connected component through shared welded vertices) of
/// every face, numbered in order of first face, and the shell count.
pub fn shells(m: &CreatureMesh) -> (Vec<u32>, usize) {
    let weld = welded(m);
    let mut parent: Vec<u32> = (0..m.positions.len() as u32).collect();
    fn find(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    for t in &m.triangles {
        let r = find(&mut parent, weld[t[0] as usize]);
        for &i in &t[1..] {
            let s = find(&mut parent, weld[i as usize]);
            parent[s as usize] = r;
        }
    }
    let mut ids = HashMap::new();
    let shells = m
        .triangles
        .iter()
        .map(|t| {
            let r = find(&mut parent, weld[t[0] as usize]);
            let n = ids.len() as u32;
            *ids.entry(r).or_insert(n)
        })
        .collect();
    (shells, ids.len())
}

/// Edges with three faces or more.
pub fn non_manifold_edges(m: &CreatureMesh) -> Vec<(u32, u32)> {
    let mut out: Vec<(u32, u32)> = edge_faces(m)
        .into_iter()
        .filter(|(_, f)| f.len() > 2)
        .map(|(e, _)| e)
        .collect();
    out.sort_unstable();
    out
}

/// Unit normal of face `f` in f64 (zero for a zero-area face).
pub fn face_normal(m: &CreatureMesh, f: usize) -> DVec3 {
    let [a, b, c] = m.triangles[f].map(|i| point(m, i));
    (b - a).cross(c - a).normalize_or_zero()
}

/// Manifold edges (two faces, neither degenerate by pelage's rule) whose
/// faces' normals have a dot product at most `max_dot`: `(face, face,
/// dot)`, sharpest first.
pub fn creases(m: &CreatureMesh, max_dot: f64) -> Vec<(u32, u32, f64)> {
    let degenerate = degenerate_faces(m);
    let mut out: Vec<(u32, u32, f64)> = edge_faces(m)
        .into_values()
        .filter(|f| f.len() == 2)
        .filter(|f| {
            f.iter()
                .all(|&f| degenerate.binary_search(&(f as usize)).is_err())
        })
        .map(|f| {
            let d = face_normal(m, f[0] as usize).dot(face_normal(m, f[1] as usize));
            (f[0].min(f[1]), f[0].max(f[1]), d)
        })
        .filter(|&(_, _, d)| d <= max_dot)
        .collect();
    out.sort_by(|a, b| a.2.total_cmp(&b.2).then((a.0, a.1).cmp(&(b.0, b.1))));
    out
}

/// The faces pelage calls degenerate (a repeated vertex, or twice the area
/// at most 1e-6 of the longest edge squared), in order.
pub fn degenerate_faces(m: &CreatureMesh) -> Vec<usize> {
    let mesh = pelage_core::Mesh::new(
        pelage_core::Strided::from_slice(&m.positions),
        pelage_core::Strided::from_slice(&m.triangles),
    );
    (0..m.triangles.len())
        .filter(|&f| mesh.is_degenerate(f))
        .collect()
}

/// Faces whose corners are exactly collinear or coincident in f64 from
/// the f32 positions: zero area, not merely small.
pub fn zero_area_faces(m: &CreatureMesh) -> Vec<usize> {
    (0..m.triangles.len())
        .filter(|&f| {
            let [a, b, c] = m.triangles[f].map(|i| point(m, i));
            (b - a).cross(c - a) == DVec3::ZERO
        })
        .collect()
}

/// Aspect ratio of face `f`: its longest edge over the height onto it
/// (1.15 for an equilateral triangle; infinite for a zero-area one).
pub fn aspect(m: &CreatureMesh, f: usize) -> f64 {
    let [a, b, c] = m.triangles[f].map(|i| point(m, i));
    let twice_area = (b - a).cross(c - a).length();
    let longest = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    longest / twice_area
}

/// The least-squares plane of `points`: their centroid and the unit
/// normal of least variance.
pub fn plane_fit(points: &[DVec3]) -> (DVec3, DVec3) {
    let c = points.iter().sum::<DVec3>() / points.len() as f64;
    let mut cov = glam::DMat3::ZERO;
    for p in points {
        let d = *p - c;
        cov += glam::DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    // the smallest eigenvector, by inverse iteration (shifted a hair so a
    // planar set's singular matrix still inverts)
    let scale = cov.x_axis.length() + cov.y_axis.length() + cov.z_axis.length();
    let inv = (cov + glam::DMat3::IDENTITY * (1e-12 * scale)).inverse();
    let mut v = DVec3::new(0.3, 0.5, 0.8).normalize();
    for _ in 0..64 {
        v = (inv * v).normalize();
    }
    (c, v)
}

/// The extent of `points` across their least-squares plane: the thickness
/// of a flat part.
pub fn thickness(points: &[DVec3]) -> f64 {
    let (c, n) = plane_fit(points);
    let (lo, hi) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            let d = (*p - c).dot(n);
            (lo.min(d), hi.max(d))
        });
    hi - lo
}

/// How far the points are from being planar: the largest distance to
/// their least-squares plane over the diagonal of their bounding box.
pub fn non_planarity(points: &[DVec3]) -> f64 {
    let (c, n) = plane_fit(points);
    let dev = points
        .iter()
        .map(|p| (*p - c).dot(n).abs())
        .fold(0.0, f64::max);
    let (lo, hi) = points
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    dev / (hi - lo).length()
}

/// The welded vertices of a boundary loop as points.
pub fn loop_points(m: &CreatureMesh, l: &[u32]) -> Vec<DVec3> {
    l.iter().map(|&v| point(m, v)).collect()
}

/// Whether some triangle of `a` crosses some triangle of `b` (an edge of
/// one passes through the other), in f64.
pub fn parts_intersect(m: &CreatureMesh, a: Range<usize>, b: Range<usize>) -> bool {
    let tri = |f: usize| m.triangles[f].map(|i| point(m, i));
    let bounds = |faces: Range<usize>| {
        faces
            .flat_map(tri)
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p), hi.max(p))
            })
    };
    let (lo, hi) = bounds(a.clone());
    let near: Vec<[DVec3; 3]> = b
        .map(tri)
        .filter(|t| {
            let (tlo, thi) = t
                .iter()
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), p| {
                    (l.min(*p), h.max(*p))
                });
            tlo.cmple(hi).all() && thi.cmpge(lo).all()
        })
        .collect();
    a.map(tri).any(|s| {
        near.iter()
            .any(|t| edges_cross(&s, t) || edges_cross(t, &s))
    })
}

/// Whether an edge of `s` passes through the interior of triangle `t`.
fn edges_cross(s: &[DVec3; 3], t: &[DVec3; 3]) -> bool {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    if n == DVec3::ZERO {
        return false;
    }
    (0..3).any(|k| {
        let (p, q) = (s[k], s[(k + 1) % 3]);
        let (dp, dq) = ((p - t[0]).dot(n), (q - t[0]).dot(n));
        if dp * dq >= 0.0 {
            return false;
        }
        let x = p + (q - p) * (dp / (dp - dq));
        // inside the triangle: the same side of each edge as the normal
        (0..3).all(|e| (t[(e + 1) % 3] - t[e]).cross(x - t[e]).dot(n) > 0.0)
    })
}

/// The vertices of the faces `faces`, each once, as points.
pub fn part_points(m: &CreatureMesh, faces: Range<usize>) -> Vec<DVec3> {
    let mut ids: Vec<u32> = m.triangles[faces].iter().flatten().copied().collect();
    ids.sort_unstable();
    ids.dedup();
    ids.into_iter().map(|i| point(m, i)).collect()
}

/// The area of the faces that are not degenerate by pelage's rule, in f64.
pub fn area(m: &CreatureMesh) -> f64 {
    let degenerate = degenerate_faces(m);
    (0..m.triangles.len())
        .filter(|f| degenerate.binary_search(f).is_err())
        .map(|f| m.triangle_area(f))
        .sum()
}
