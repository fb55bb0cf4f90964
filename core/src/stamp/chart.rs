//! Charts: neighbouring triangles unfolded into one flat piece, so that they
//! take one continuous window of the Poisson stamp.
//!
//! The paper places every triangle in the stamp on its own, at random, so the
//! Poisson spacing breaks along every edge and a later pass has to check every
//! point near an edge in 3D. Two triangles that share an edge, bend against
//! each other by less than [`MAX_BEND_DEGREES`] and have the same density
//! scale can instead be laid flat side by side: the points on both sides of
//! that edge then come from one piece of the stamp and are spaced by it. Only
//! points near the edges a chart leaves cut, or whose disk reaches past a
//! linked neighbour, still need the 3D check.
//!
//! A chart grows from its lowest-numbered free triangle, always across the
//! longest edge on its border (Prim's algorithm on edge length), so the edges
//! left cut are the short ones, and stops at a given reach from its first
//! corner (the stamp uses half its periodic tile, so one chart never takes the
//! same tile point twice). Edges are matched by vertex index: two triangles
//! link only across an edge that both use, in opposite directions, and that no
//! third triangle uses.

use crate::arena::{Arena, ArenaLayout};
use crate::{Error, Mesh};
use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

/// Largest bend between two linked triangles. Points on both sides of a
/// linked edge are spaced by the stamp in the unfolded plane; folded by an
/// angle `a`, their 3D distance can shrink by at most `cos(a / 2)`
/// (0.99905 at this bound).
pub const MAX_BEND_DEGREES: f32 = 5.0;
/// `cos(MAX_BEND_DEGREES)`.
const MIN_NORMAL_DOT: f32 = 0.996_194_7;

/// No half-edge.
const NONE: u32 = u32::MAX;

/// Where one triangle lies in its chart's plane.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Unfolded {
    /// Its corners, in world units times the triangle's density scale,
    /// counter-clockwise.
    pub corners: [[f32; 2]; 3],
    /// For each linked edge `i` (corner `i` to corner `i + 1`), the third
    /// corner of the neighbour laid across it; zero for a cut edge.
    pub across: [[f32; 2]; 3],
    /// The chart: the index of its first triangle.
    pub chart: u32,
    /// Bit `i`: edge `i` is linked. Bit `3 + i`: edge `i` is shared with
    /// exactly one other stamped triangle (linked or not).
    pub edges: u32,
}

impl Unfolded {
    /// Whether edge `i` is linked to the neighbour across it.
    #[inline]
    pub fn linked(&self, i: usize) -> bool {
        self.edges & (1 << i) != 0
    }

    /// Whether edge `i` is shared with one other stamped triangle.
    #[inline]
    pub fn shared(&self, i: usize) -> bool {
        self.edges & (8 << i) != 0
    }
}

/// Adds the scratch bytes [`unfold`] takes from the arena to `layout`.
pub fn layout(layout: &mut ArenaLayout, mesh: &Mesh) {
    let half_edges = 3 * mesh.triangle_count();
    layout
        .add::<u32>(mesh.positions.len() + 1)
        .add::<u64>(half_edges)
        .add::<u32>(half_edges)
        .add::<u64>(half_edges);
}

/// Lays every triangle with a nonzero `scale` into a chart, writing
/// `out[f]` for each (the others are left as they are). `normal` gives each
/// triangle's unit normal. `reach` bounds the distance of any corner from
/// its chart's first corner, in the units of [`Unfolded::corners`]. The
/// mesh must be validated.
pub fn unfold(
    mesh: &Mesh,
    scale: impl Fn(usize) -> f32,
    normal: impl Fn(usize) -> Vec3,
    reach: f32,
    arena: &mut Arena,
    out: &mut [Unfolded],
) -> Result<(), Error> {
    let faces = mesh.triangle_count();
    let start = arena.alloc::<u32>(mesh.positions.len() + 1)?;
    let entries = arena.alloc::<u64>(3 * faces)?;
    let twin = arena.alloc::<u32>(3 * faces)?;
    let heap = arena.alloc::<u64>(3 * faces)?;
    let stamped = |f: usize| scale(f) != 0.0;
    match_edges(mesh, &stamped, start, entries, twin);
    // the chart of each face, where the growth looks it up: a small array
    // stays in cache where the laid-out faces would not (the edge entries
    // are done with, and have room)
    let (chart_of, rest) = bytemuck::cast_slice_mut::<u64, u32>(entries).split_at_mut(faces);
    // the half-edges' lengths, in one pass in face order: the growth reads
    // them in its own order, where the corners would be scattered reads
    let length = bytemuck::cast_slice_mut::<u32, f32>(&mut rest[..3 * faces]);
    for (f, (u, c)) in out.iter_mut().zip(chart_of.iter_mut()).enumerate() {
        *c = f as u32;
        if stamped(f) {
            (u.chart, *c) = (NONE, NONE);
            u.edges = (0..3).fold(0, |e, i| e | ((twin[3 * f + i] != NONE) as u32) << (3 + i));
            let corners = mesh.corners(f);
            for i in 0..3 {
                length[3 * f + i] = (corners[(i + 1) % 3] - corners[i]).length();
            }
        }
    }
    let length = &*length;
    let mut heap = Heap { keys: heap, len: 0 };
    for seed in 0..faces {
        if chart_of[seed] != NONE {
            continue;
        }
        out[seed].corners = seed_corners(mesh, seed, scale(seed));
        out[seed].across = [[0.0; 2]; 3];
        out[seed].chart = seed as u32;
        chart_of[seed] = seed as u32;
        for i in 0..3 {
            heap.push_edge(length, twin, 3 * seed + i);
        }
        while let Some(h) = heap.pop() {
            let (f, i) = (h / 3, h % 3);
            let t = twin[h] as usize;
            let (g, j) = (t / 3, t % 3);
            if chart_of[g] != NONE || scale(g) != scale(f) {
                continue;
            }
            if normal(f).dot(normal(g)) < MIN_NORMAL_DOT {
                continue;
            }
            let w = unfold_across(mesh, &out[f], f, i, length[h], g, j, scale(f));
            if w.length() > reach {
                continue;
            }
            let near = out[f].corners;
            let mut corners = [[0.0; 2]; 3];
            corners[j] = near[(i + 1) % 3];
            corners[(j + 1) % 3] = near[i];
            corners[(j + 2) % 3] = w.into();
            let mut across = [[0.0; 2]; 3];
            across[j] = near[(i + 2) % 3];
            out[g].corners = corners;
            out[g].across = across;
            out[g].chart = seed as u32;
            chart_of[g] = seed as u32;
            out[g].edges |= 1 << j;
            out[f].across[i] = w.into();
            out[f].edges |= 1 << i;
            for k in [(j + 1) % 3, (j + 2) % 3] {
                let o = twin[3 * g + k];
                if o != NONE && chart_of[o as usize / 3] == NONE {
                    heap.push_edge(length, twin, 3 * g + k);
                }
            }
        }
    }
    Ok(())
}

/// Finds the twin of every half-edge of the stamped triangles: the one
/// other half-edge over the same two vertices, running the other way, when
/// there is exactly one; `NONE` otherwise (a border, a non-manifold edge or
/// flipped winding).
fn match_edges(
    mesh: &Mesh,
    stamped: &impl Fn(usize) -> bool,
    start: &mut [u32],
    entries: &mut [u64],
    twin: &mut [u32],
) {
    let ends = |h: usize| {
        let t = mesh.triangles.get(h / 3);
        (t[h % 3], t[(h + 1) % 3])
    };
    let half_edges = || (0..twin.len()).filter(|&h| stamped(h / 3));
    // bucket the half-edges by their lower vertex (a counting sort) ...
    start.fill(0);
    for h in half_edges() {
        let (a, b) = ends(h);
        start[a.min(b) as usize + 1] += 1;
    }
    for v in 1..start.len() {
        start[v] += start[v - 1];
    }
    for h in half_edges() {
        let (a, b) = ends(h);
        let lo = a.min(b) as usize;
        entries[start[lo] as usize] = (a.max(b) as u64) << 32 | h as u64;
        start[lo] += 1;
    }
    // ... then order each bucket by upper vertex, so the half-edges over one
    // edge sit together (after the fill, start[v] is where bucket v ends)
    twin.fill(NONE);
    let mut begin = 0;
    for &end in &start[..start.len() - 1] {
        let bucket = &mut entries[begin..end as usize];
        bucket.sort_unstable();
        let mut k = 0;
        while k < bucket.len() {
            let upper = bucket[k] >> 32;
            let run = bucket[k..]
                .iter()
                .take_while(|&&e| e >> 32 == upper)
                .count();
            if run == 2 {
                let (h, o) = (bucket[k] as u32, bucket[k + 1] as u32);
                let ((a, b), (c, d)) = (ends(h as usize), ends(o as usize));
                if (a, b) == (d, c) {
                    (twin[h as usize], twin[o as usize]) = (o, h);
                }
            }
            k += run;
        }
        begin = end as usize;
    }
}

/// The corners of a chart's first triangle: corner 0 at the origin, edge
/// 0 along +x.
fn seed_corners(mesh: &Mesh, f: usize, scale: f32) -> [[f32; 2]; 3] {
    let [a, b, c] = mesh.corners(f);
    let (e1, e2) = (b - a, c - a);
    let x = e1.normalize();
    let y = x.cross(e2).cross(x).normalize();
    [
        [0.0, 0.0],
        [e1.length() * scale, 0.0],
        [e2.dot(x) * scale, e2.dot(y) * scale],
    ]
}

/// The third corner of `g`, laid flat across edge `i` of `f` (which is edge
/// `j` of `g`, run the other way, and `length` long), in `f`'s chart plane.
#[allow(clippy::too_many_arguments)]
fn unfold_across(
    mesh: &Mesh,
    laid: &Unfolded,
    f: usize,
    i: usize,
    length: f32,
    g: usize,
    j: usize,
    scale: f32,
) -> Vec2 {
    let corners = mesh.corners(f);
    let (a, b) = (corners[i], corners[(i + 1) % 3]);
    let w: Vec3 = mesh.corners(g)[(j + 2) % 3];
    // normalize() in the same operations, with the length already known
    let along = (b - a) * (1.0 / length);
    let d = w - a;
    let t = d.dot(along);
    let h = (d - along * t).length();
    let (a2, b2) = (
        Vec2::from(laid.corners[i]),
        Vec2::from(laid.corners[(i + 1) % 3]),
    );
    let x = (b2 - a2).normalize();
    // the neighbour lies right of edge i (the triangle is counter-clockwise)
    let right = Vec2::new(x.y, -x.x);
    a2 + (x * t + right * h) * scale
}

/// Children of a heap node: a 4-ary heap is half as deep as a binary one,
/// and a node's children share a cache line.
const ARITY: usize = 4;

/// A max-heap of border half-edges keyed by (edge length, index). Keys are
/// distinct, so any heap pops them in the same order.
struct Heap<'a> {
    keys: &'a mut [u64],
    len: usize,
}

impl Heap<'_> {
    /// Pushes half-edge `h` of `length` if it has a twin (a border edge
    /// can link to nothing).
    fn push_edge(&mut self, length: &[f32], twin: &[u32], h: usize) {
        if twin[h] == NONE {
            return;
        }
        // a positive float's bits order like the float
        let key = (length[h].to_bits() as u64) << 32 | h as u64;
        let mut k = self.len;
        self.len += 1;
        while k > 0 && self.keys[(k - 1) / ARITY] < key {
            self.keys[k] = self.keys[(k - 1) / ARITY];
            k = (k - 1) / ARITY;
        }
        self.keys[k] = key;
    }

    fn pop(&mut self) -> Option<usize> {
        if self.len == 0 {
            return None;
        }
        let top = self.keys[0];
        self.len -= 1;
        let key = self.keys[self.len];
        let mut k = 0;
        loop {
            let first = ARITY * k + 1;
            if first >= self.len {
                break;
            }
            let children = &self.keys[first..(first + ARITY).min(self.len)];
            let (mut m, mut largest) = (0, children[0]);
            for (c, &child) in children.iter().enumerate().skip(1) {
                if child > largest {
                    (m, largest) = (c, child);
                }
            }
            if largest <= key {
                break;
            }
            self.keys[k] = largest;
            k = first + m;
        }
        self.keys[k] = key;
        Some((top & 0xFFFF_FFFF) as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testmesh::{graded_plane, sphere, TestMesh};

    fn run(m: &TestMesh, scale: impl Fn(usize) -> f32, reach: f32) -> Vec<Unfolded> {
        let mesh = m.mesh();
        let mut layout_bytes = ArenaLayout::new();
        layout(&mut layout_bytes, &mesh);
        let mut buf = vec![0u8; layout_bytes.bytes()];
        let mut out = vec![Unfolded::default(); mesh.triangle_count()];
        let normal = |f: usize| mesh.face_normal(f);
        unfold(
            &mesh,
            scale,
            normal,
            reach,
            &mut Arena::new(&mut buf),
            &mut out,
        )
        .unwrap();
        out
    }

    /// Every face is laid isometrically (times its scale) and counter-clockwise,
    /// and faces linked across an edge hold the same two corners, bit for bit.
    fn check_layout(m: &TestMesh, laid: &[Unfolded], scale: impl Fn(usize) -> f32) -> usize {
        let mesh = m.mesh();
        let mut links = 0;
        for (f, u) in laid.iter().enumerate() {
            let c = u.corners.map(Vec2::from);
            let w = mesh.corners(f);
            for i in 0..3 {
                let (flat, real) = (
                    (c[(i + 1) % 3] - c[i]).length(),
                    (w[(i + 1) % 3] - w[i]).length(),
                );
                assert!(
                    (flat - real * scale(f)).abs() < 1e-5 * real,
                    "face {f} edge {i}"
                );
            }
            assert!(
                (c[1] - c[0]).perp_dot(c[2] - c[0]) > 0.0,
                "face {f} is flipped"
            );
            for i in (0..3).filter(|&i| u.linked(i)) {
                let [a, b] = [m.t[f][i], m.t[f][(i + 1) % 3]];
                let (g, other) = laid
                    .iter()
                    .enumerate()
                    .find(|&(g, _)| g != f && m.t[g].contains(&a) && m.t[g].contains(&b))
                    .unwrap();
                assert_eq!(other.chart, u.chart);
                let at = |t: [u32; 3], v: u32| t.iter().position(|&x| x == v).unwrap();
                assert_eq!(other.corners[at(m.t[g], a)], u.corners[i]);
                assert_eq!(other.corners[at(m.t[g], b)], u.corners[(i + 1) % 3]);
                let third = m.t[g].iter().position(|&x| x != a && x != b).unwrap();
                assert_eq!(u.across[i], other.corners[third]);
                let bend = mesh.face_normal(f).dot(mesh.face_normal(g));
                assert!(bend >= MIN_NORMAL_DOT, "faces {f} and {g} bend too much");
                links += 1;
            }
        }
        links / 2
    }

    #[test]
    fn a_flat_mesh_is_one_chart_spanned_by_its_longest_edges() {
        let m = graded_plane(8, 20.0);
        let laid = run(&m, |_| 0.5, f32::INFINITY);
        assert!(laid.iter().all(|u| u.chart == 0));
        // a spanning tree: every face but the first joins across one edge
        assert_eq!(check_layout(&m, &laid, |_| 0.5), laid.len() - 1);
        // each square's diagonal is its longest edge, and is always linked
        assert!(laid.iter().all(|u| u.linked(2) || u.linked(0)));
    }

    #[test]
    fn charts_stop_at_bends_scale_changes_and_their_reach() {
        let m = sphere(6, 12);
        let laid = run(&m, |_| 1.0, f32::INFINITY);
        check_layout(&m, &laid, |_| 1.0);
        // a coarse sphere bends by 30 degrees at every edge but the flat
        // diagonals of its quads
        for u in &laid {
            assert!(laid.iter().filter(|o| o.chart == u.chart).count() <= 2);
        }

        let m = graded_plane(8, 1.0);
        let scale = |f: usize| if f < 64 { 1.0 } else { 0.75 };
        let laid = run(&m, scale, f32::INFINITY);
        check_layout(&m, &laid, scale);
        assert!(laid
            .iter()
            .all(|u| (u.chart < 64) == (scale(u.chart as usize) == 1.0)));
        assert_eq!(laid.iter().map(|u| u.chart).max(), Some(64));

        let reach = 0.3;
        let laid = run(&m, |_| 1.0, reach);
        check_layout(&m, &laid, |_| 1.0);
        assert!(laid.iter().map(|u| u.chart).max() > Some(0));
        for u in &laid {
            assert!(u.corners.iter().all(|&c| Vec2::from(c).length() <= reach));
        }
    }

    #[test]
    fn flipped_non_manifold_and_skipped_faces_stay_apart() {
        let mut m = graded_plane(4, 1.0);
        m.t[5].swap(1, 2);
        // a third face on the edge between faces 8 and 9
        let [a, _, c] = m.t[8];
        m.p.push([0.5, 0.5, 0.3]);
        m.t.push([a, c, m.p.len() as u32 - 1]);
        let skipped = 12;
        let scale = |f: usize| if f == skipped { 0.0 } else { 1.0 };
        let laid = run(&m, scale, f32::INFINITY);
        for (f, u) in laid.iter().enumerate() {
            if f == 5 || f == skipped {
                assert_eq!(u.edges & 7, 0, "face {f}");
            }
        }
        let shared = |f: usize, i: usize| laid[f].shared(i);
        assert!(!shared(8, 2) && !shared(9, 0) && !shared(5, 0));
        assert_eq!(laid[skipped], Unfolded::default());
    }
}
