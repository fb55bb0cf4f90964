//! The distance from a point to a mesh's surface, for the signed depth of
//! host points: a bounding volume hierarchy over the triangles, searched
//! branch and bound, nearer child first.
//!
//! The tree is built by median splits along the longest axis of the
//! triangles' centroids, down to four triangles, ties broken by the
//! triangles' indices, so the same mesh gives the same tree. Its triangles
//! are copied in leaf order, relative to the corner of the mesh's box: far
//! from the origin the distances keep the precision of the mesh's own size
//! rather than of its position (as the body does).

use crate::arena::{Arena, ArenaLayout};
use crate::{Error, Mesh};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Most triangles a leaf holds.
const LEAF: usize = 4;
/// Nodes a search holds at once: two per level of a tree of median
/// splits, far more than 2^32 triangles need.
const STACK: usize = 96;

/// A node: its box and, for a leaf, its triangles `first .. first + count`
/// in leaf order; for an inner node (`count` 0), its children are the next
/// node and node `first`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct Node {
    lo: [f32; 3],
    hi: [f32; 3],
    first: u32,
    count: u32,
}

/// A triangle while the tree is built: its index and centroid.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct Item {
    face: u32,
    centroid: [f32; 3],
}

/// The triangles of a mesh in a tree, for nearest-point queries.
pub struct Nearest<'a> {
    /// Subtracted from every point: the corner of the mesh's box.
    base: Vec3,
    nodes: &'a [Node],
    /// The corners of the triangles with area, in leaf order, relative to
    /// `base`.
    triangles: &'a [[[f32; 3]; 3]],
}

/// Nodes of a tree over `n` triangles: a median split of more than
/// [`LEAF`] leaves at least half of `LEAF` (rounded up) a side, so a leaf holds at
/// least that many (but for a tree of fewer), and a binary tree has fewer
/// than twice as many nodes as leaves.
fn node_bound(n: usize) -> usize {
    (2 * n.div_ceil(LEAF.div_ceil(2))).max(1)
}

impl<'a> Nearest<'a> {
    /// Adds the arena bytes [`Nearest::new`] takes for `mesh` (validated).
    pub fn layout(layout: &mut ArenaLayout, mesh: &Mesh) {
        let n = mesh.triangle_count();
        layout
            .add::<Node>(node_bound(n))
            .add::<[[f32; 3]; 3]>(n)
            .add::<Item>(n);
    }

    /// Builds the tree over the triangles of a checked `mesh` that have an
    /// area (a degenerate triangle's edges are its neighbours'); a mesh
    /// without one has no surface, and every distance is infinite.
    pub fn new(mesh: &Mesh, arena: &mut Arena<'a>) -> Result<Self, Error> {
        let (mut lo, mut hi) = (Vec3::MAX, Vec3::MIN);
        for p in mesh.positions.iter() {
            (lo, hi) = (lo.min(Vec3::from(p)), hi.max(Vec3::from(p)));
        }
        let base = if lo.cmple(hi).all() { lo } else { Vec3::ZERO };
        let corners = |f: u32| mesh.corners(f as usize).map(|p| p - base);
        let n = (0..mesh.triangle_count())
            .filter(|&f| !mesh.is_degenerate(f))
            .count();
        let nodes = arena.alloc::<Node>(node_bound(n))?;
        let triangles = arena.alloc::<[[f32; 3]; 3]>(n)?;
        let items = arena.alloc::<Item>(n)?;
        let kept = (0..mesh.triangle_count()).filter(|&f| !mesh.is_degenerate(f));
        for (item, f) in items.iter_mut().zip(kept) {
            let [a, b, c] = corners(f as u32);
            *item = Item {
                face: f as u32,
                centroid: ((a + b + c) / 3.0).to_array(),
            };
        }
        let mut used = 0;
        if n > 0 {
            split(nodes, &mut used, items, 0, &corners);
        }
        for (t, item) in triangles.iter_mut().zip(items.iter()) {
            *t = corners(item.face).map(|p| p.to_array());
        }
        Ok(Nearest {
            base,
            nodes: &nodes[..used],
            triangles,
        })
    }

    /// True when the mesh has no triangle with area: every distance is
    /// infinite.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The distance from `p` to the nearest point of the mesh's triangles
    /// with area (infinite without one).
    pub fn distance(&self, p: Vec3) -> f32 {
        let p = p - self.base;
        let mut best = f32::INFINITY;
        if self.nodes.is_empty() {
            return best;
        }
        let mut stack = [0u32; STACK];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if box_distance_squared(&node, p) >= best {
                continue;
            }
            if node.count > 0 {
                let first = node.first as usize;
                for t in &self.triangles[first..first + node.count as usize] {
                    best = best.min(triangle_distance_squared(p, t.map(Vec3::from)));
                }
                continue;
            }
            let (near, far) = (stack[top] + 1, node.first);
            let (dn, df) = (
                box_distance_squared(&self.nodes[near as usize], p),
                box_distance_squared(&self.nodes[far as usize], p),
            );
            // the nearer child is searched first: pushed last
            let (first, second) = if dn <= df { (far, near) } else { (near, far) };
            for child in [first, second] {
                stack[top] = child;
                top += 1;
            }
        }
        libm::sqrtf(best)
    }
}

/// Makes node `*used` of `items` (whose first slot is slot `offset` of the
/// whole) and its subtree, splitting at the median of the centroids along
/// their longest axis.
fn split(
    nodes: &mut [Node],
    used: &mut usize,
    items: &mut [Item],
    offset: usize,
    corners: &dyn Fn(u32) -> [Vec3; 3],
) {
    let at = *used;
    *used += 1;
    let (mut lo, mut hi) = (Vec3::MAX, Vec3::MIN);
    let (mut clo, mut chi) = (Vec3::MAX, Vec3::MIN);
    for item in items.iter() {
        for p in corners(item.face) {
            (lo, hi) = (lo.min(p), hi.max(p));
        }
        let c = Vec3::from(item.centroid);
        (clo, chi) = (clo.min(c), chi.max(c));
    }
    nodes[at] = Node {
        lo: lo.to_array(),
        hi: hi.to_array(),
        first: offset as u32,
        count: items.len() as u32,
    };
    if items.len() <= LEAF {
        return;
    }
    let extent = chi - clo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| {
        a.centroid[axis]
            .total_cmp(&b.centroid[axis])
            .then(a.face.cmp(&b.face))
    });
    let (left, right) = items.split_at_mut(mid);
    split(nodes, used, left, offset, corners);
    let second = *used;
    split(nodes, used, right, offset + mid, corners);
    nodes[at].first = second as u32;
    nodes[at].count = 0;
}

/// The squared distance from `p` to the node's box (0 inside it).
#[inline]
fn box_distance_squared(node: &Node, p: Vec3) -> f32 {
    let d = (Vec3::from(node.lo) - p)
        .max(p - Vec3::from(node.hi))
        .max(Vec3::ZERO);
    d.length_squared()
}

/// The squared distance from `p` to the triangle `[a, b, c]` (with area),
/// by the region of the triangle's plane the point projects into (Ericson,
/// Real-Time Collision Detection, 5.1.5).
fn triangle_distance_squared(p: Vec3, [a, b, c]: [Vec3; 3]) -> f32 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.length_squared();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.length_squared();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (ap - ab * v).length_squared();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.length_squared();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (ap - ac * w).length_squared();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (bp - (c - b) * w).length_squared();
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (ap - ab * v - ac * w).length_squared()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testmesh::sphere;

    /// The distance by trying every triangle.
    fn brute(mesh: &Mesh, p: Vec3) -> f32 {
        (0..mesh.triangle_count())
            .filter(|&f| !mesh.is_degenerate(f))
            .map(|f| triangle_distance_squared(p, mesh.corners(f)))
            .fold(f32::INFINITY, f32::min)
            .sqrt()
    }

    #[test]
    fn the_tree_finds_the_nearest_triangle_as_trying_them_all_does() {
        let m = sphere(12, 24);
        let mesh = m.mesh();
        let mut layout = ArenaLayout::new();
        Nearest::layout(&mut layout, &mesh);
        let mut buf = vec![0u8; layout.bytes()];
        let near = Nearest::new(&mesh, &mut Arena::new(&mut buf)).unwrap();
        use crate::rng::{unit, Purpose};
        for i in 0..2000u64 {
            let r = |k| unit(5, i, Purpose::Uniform, k);
            let p = Vec3::new(r(0), r(1), r(2)) * 6.0 - 3.0;
            let (got, want) = (near.distance(p), brute(&mesh, p));
            assert!(
                (got - want).abs() <= 1e-5 * want.max(1.0),
                "{p}: {got} vs {want}"
            );
        }
        // a point on the skin is at distance 0 (up to rounding)
        let on = mesh.point(7, 0.2, 0.3);
        assert!(near.distance(on) < 1e-6);
    }

    #[test]
    fn far_from_the_origin_the_distance_keeps_the_mesh_precision() {
        let mut m = sphere(12, 24);
        let far = Vec3::splat(1e4);
        for p in m.p.iter_mut() {
            *p = (Vec3::from(*p) + far).to_array();
        }
        let mesh = m.mesh();
        let mut layout = ArenaLayout::new();
        Nearest::layout(&mut layout, &mesh);
        let mut buf = vec![0u8; layout.bytes()];
        let near = Nearest::new(&mesh, &mut Arena::new(&mut buf)).unwrap();
        // a vertex, found again at 0 rather than at the rounding of 1e4
        let v = Vec3::from(m.p[40]);
        assert_eq!(near.distance(v), 0.0);
    }

    #[test]
    fn a_mesh_without_area_has_no_surface() {
        let m = crate::testmesh::TestMesh {
            p: vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            t: vec![[0, 1, 2]],
            uv: vec![],
            n: vec![],
        };
        let mesh = m.mesh();
        let mut layout = ArenaLayout::new();
        Nearest::layout(&mut layout, &mesh);
        let mut buf = vec![0u8; layout.bytes()];
        let near = Nearest::new(&mesh, &mut Arena::new(&mut buf)).unwrap();
        assert_eq!(near.distance(Vec3::ONE), f32::INFINITY);
    }
}
