//! The open boundary of a mesh: the edges that lack a partner running the
//! other way, gathered into closed loops (eye sockets, a mouth, a neck).
//!
//! Vertices at the same position are one vertex here (they are welded):
//! meshes split their vertices along UV seams and normal creases, and a
//! seam is not a hole.
//!
//! The boundary depends on the triangle indices, on which vertices share a
//! position (welding) and on which triangles are degenerate (skipped, as
//! the body skips them, so a sliver becomes a capped hole rather than a
//! slit): find it again when the positions may change those
//! ([`Rim::refresh`] checks whether they did, in one pass over the mesh,
//! and finds it again only then: the simulation refreshes it every step).
//! An edge listed `a -> b` by `m` triangles and `b -> a` by `n` is a
//! boundary edge `m - n` times (in the direction of the surplus); a closed mesh, however many
//! shells it has, has none. The surplus edges meet every vertex as often
//! going in as going out (each triangle does), so they always split into
//! closed loops.

use crate::arena::{Arena, ArenaLayout};
use crate::{Error, Mesh};
use glam::{Vec3, Vec3A};

/// The boundary loops of a mesh, in caller-provided memory.
#[derive(Clone, Copy, Debug)]
pub struct Rim<'a> {
    /// Each vertex's welded index: the lowest index at its position.
    weld: &'a [u32],
    /// Boundary edges as their triangles list them (`[a, b]` for `a -> b`,
    /// welded indices), loop after loop, each loop in order around it.
    edges: &'a [[u32; 2]],
    /// Loop `k` is `edges[starts[k]..starts[k + 1]]`.
    starts: &'a [u32],
    /// 1 for each triangle that is not degenerate (the rim's and the
    /// body's triangles), 0 for the others.
    solid: &'a [u8],
    /// Vertices and triangles of the mesh it was found on.
    vertices: usize,
    triangles: usize,
    /// The bounds of the solid triangles' corners, and their number.
    solid_bounds: SolidBounds,
}

/// The bounds of a mesh's solid triangles (their corners), and how many
/// there are: found with the solid triangles, as a body's grid is placed
/// by them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SolidBounds {
    pub(crate) lo: Vec3A,
    pub(crate) hi: Vec3A,
    pub(crate) count: usize,
}

impl SolidBounds {
    /// No triangle yet.
    pub(crate) const EMPTY: SolidBounds = SolidBounds {
        lo: Vec3A::INFINITY,
        hi: Vec3A::NEG_INFINITY,
        count: 0,
    };

    /// Takes in a solid triangle's `corners`.
    #[inline]
    pub(crate) fn add(&mut self, corners: [Vec3; 3]) {
        for c in corners.map(Vec3A::from) {
            (self.lo, self.hi) = (self.lo.min(c), self.hi.max(c));
        }
        self.count += 1;
    }
}

/// `keys` (`[low end, high end, direction, 0]`, ends below `vertices`)
/// in increasing order, copied into `arena`: a counting sort by the low end,
/// then each end's few edges sorted in place. A mesh's edges number three
/// per triangle and a vertex has a handful, so this is linear where a
/// comparison sort of every edge is not.
fn sort_by_first_end<'a>(
    keys: &[[u32; 4]],
    vertices: usize,
    arena: &mut Arena<'a>,
) -> Result<&'a mut [[u32; 4]], Error> {
    let sorted = arena.alloc::<[u32; 4]>(keys.len())?;
    let start = arena.alloc::<u32>(vertices + 1)?;
    start.fill(0);
    for k in keys {
        start[k[0] as usize + 1] += 1;
    }
    for v in 0..vertices {
        start[v + 1] += start[v];
    }
    for k in keys {
        let at = &mut start[k[0] as usize];
        sorted[*at as usize] = *k;
        *at += 1;
    }
    // each vertex's edges now end where the next vertex's begin
    let mut begin = 0;
    for &end in start[..vertices].iter() {
        sorted[begin..end as usize].sort_unstable();
        begin = end as usize;
    }
    Ok(sorted)
}

/// What a rim keeps at the front of its arena, for [`Rim::refresh`] to
/// find again: a header, then the rim's arrays and a copy of the indices
/// it was found for.
struct Kept<'a> {
    /// [`MAGIC`], the header's address, vertices, triangles, boundary
    /// edges, loops; all zero until a rim is complete.
    header: &'a mut [u64; HEADER],
    weld: &'a mut [u32],
    indices: &'a mut [[u32; 3]],
    edges: &'a mut [[u32; 2]],
    starts: &'a mut [u32],
    solid: &'a mut [u8],
}

/// The first word of a complete rim's header.
const MAGIC: u64 = u64::from_le_bytes(*b"pelarim1");
/// Words of a rim's header.
const HEADER: usize = 6;

impl<'a> Kept<'a> {
    fn layout(layout: &mut ArenaLayout, vertices: usize, triangles: usize) {
        layout
            .add::<[u64; HEADER]>(1)
            .add::<u32>(vertices)
            .add::<[u32; 3]>(triangles)
            .add::<[u32; 2]>(3 * triangles)
            .add::<u32>(triangles + 2)
            .add::<u8>(triangles);
    }

    fn alloc(mesh: &Mesh, arena: &mut Arena<'a>) -> Result<Self, Error> {
        let (vertices, triangles) = (mesh.positions.len(), mesh.triangle_count());
        Ok(Kept {
            header: &mut arena.alloc::<[u64; HEADER]>(1)?[0],
            weld: arena.alloc::<u32>(vertices)?,
            indices: arena.alloc::<[u32; 3]>(triangles)?,
            edges: arena.alloc::<[u32; 2]>(3 * triangles)?,
            starts: arena.alloc::<u32>(triangles + 2)?,
            solid: arena.alloc::<u8>(triangles)?,
        })
    }

    /// The header a rim of `edges` boundary edges in `loops` loops on
    /// `mesh` has here.
    fn header(&self, mesh: &Mesh, edges: usize, loops: usize) -> [u64; HEADER] {
        [
            MAGIC,
            self.header.as_ptr() as u64,
            mesh.positions.len() as u64,
            mesh.triangle_count() as u64,
            edges as u64,
            loops as u64,
        ]
    }

    fn rim(self, mesh: &Mesh, edges: usize, loops: usize, solid_bounds: SolidBounds) -> Rim<'a> {
        Rim {
            weld: self.weld,
            edges: &self.edges[..edges],
            starts: &self.starts[..=loops],
            solid: self.solid,
            vertices: mesh.positions.len(),
            triangles: mesh.triangle_count(),
            solid_bounds,
        }
    }

    /// Whether the rim kept here is `mesh`'s: found for the same indices,
    /// the same triangles degenerate, and the same vertices welded (each
    /// at its welded vertex's position, and no two welded vertices at one
    /// position), which is all a rim depends on; and if so, the bounds of
    /// its solid triangles. `table` is scratch.
    fn still_fits(&self, mesh: &Mesh, table: &mut [u32]) -> Option<SolidBounds> {
        let [magic, _, _, _, edges, loops] = *self.header;
        let fits = magic == MAGIC
            && self.header[..4] == self.header(mesh, 0, 0)[..4]
            && edges <= self.edges.len() as u64
            && loops < self.starts.len() as u64;
        if !fits {
            return None;
        }
        if (0..mesh.triangle_count()).any(|f| self.indices[f] != mesh.triangles.get(f)) {
            return None;
        }
        let mut bounds = SolidBounds::EMPTY;
        for f in 0..mesh.triangle_count() {
            let shape = mesh.shape(f);
            if self.solid[f] != !shape.degenerate as u8 {
                return None;
            }
            if !shape.degenerate {
                bounds.add(shape.corners);
            }
        }
        let key = |v: u32| mesh.positions.get(v as usize).map(|c| (c + 0.0).to_bits());
        // a vertex is welded to itself or a lower index
        let weld_ok = (0..mesh.positions.len() as u32).all(|v| {
            let w = self.weld[v as usize];
            w <= v && key(v) == key(w)
        });
        if !weld_ok {
            return None;
        }
        // the welded vertices at distinct positions: an open-addressed set
        table.fill(u32::MAX);
        let mask = table.len() - 1;
        for v in (0..mesh.positions.len() as u32).filter(|&v| self.weld[v as usize] == v) {
            let [x, y, z] = key(v);
            let mut h = (x.wrapping_mul(0x9E37_79B1)
                ^ y.wrapping_mul(0x85EB_CA77)
                ^ z.wrapping_mul(0xC2B2_AE3D)) as usize;
            loop {
                h &= mask;
                match table[h] {
                    u32::MAX => {
                        table[h] = v;
                        break;
                    }
                    u if key(u) == key(v) => return None,
                    _ => h += 1,
                }
            }
        }
        Some(bounds)
    }
}

impl<'a> Rim<'a> {
    /// Arena bytes [`Rim::new`] and [`Rim::refresh`] take for `mesh` (an
    /// upper bound: every edge could be a boundary edge).
    pub fn required_bytes(mesh: &Mesh) -> usize {
        let edges = 3 * mesh.triangle_count();
        let vertices = mesh.positions.len();
        let mut layout = ArenaLayout::new();
        Kept::layout(&mut layout, vertices, mesh.triangle_count());
        layout
            .add::<[u32; 4]>(edges.max(vertices))
            .add::<[u32; 4]>(edges)
            .add::<u32>(vertices + 1);
        layout.bytes()
    }

    /// Finds the boundary loops of `mesh` (checks its indices).
    pub fn new(mesh: &Mesh, arena: &mut Arena<'a>) -> Result<Self, Error> {
        mesh.check()?;
        Self::check_room(mesh, arena)?;
        let kept = Kept::alloc(mesh, arena)?;
        let keys = arena.alloc::<[u32; 4]>(Self::key_count(mesh))?;
        Self::find(mesh, kept, keys, arena)
    }

    /// The boundary loops of `mesh`, found in `arena` as [`Rim::new`] finds
    /// them, unless `arena` (the same memory, at the same address) holds
    /// the rim of an earlier call that is still `mesh`'s: found for the
    /// same triangle indices, with the same triangles degenerate and the
    /// same vertices sharing a position. That rim is then taken as it is,
    /// after a check linear in the mesh, where finding it sorts. A host that
    /// builds the body of a deforming mesh every frame keeps one arena for
    /// its rim: the same rim, in less time.
    pub fn refresh(mesh: &Mesh, arena: &mut Arena<'a>) -> Result<Self, Error> {
        mesh.check()?;
        Self::check_room(mesh, arena)?;
        let kept = Kept::alloc(mesh, arena)?;
        let keys = arena.alloc::<[u32; 4]>(Self::key_count(mesh))?;
        // the check's set of positions takes at most 4 slots a vertex: it
        // fits in the keys' scratch
        let slots = (2 * mesh.positions.len()).max(2).next_power_of_two();
        let words = bytemuck::cast_slice_mut::<[u32; 4], u32>(keys);
        if slots <= words.len() {
            if let Some(bounds) = kept.still_fits(mesh, &mut words[..slots]) {
                let [.., edges, loops] = *kept.header;
                return Ok(kept.rim(mesh, edges as usize, loops as usize, bounds));
            }
        }
        Self::find(mesh, kept, keys, arena)
    }

    /// Scratch keys [`Rim::find`] takes: one per edge, and one per vertex
    /// to weld them.
    fn key_count(mesh: &Mesh) -> usize {
        (3 * mesh.triangle_count()).max(mesh.positions.len())
    }

    fn check_room(mesh: &Mesh, arena: &Arena) -> Result<(), Error> {
        let needed = Self::required_bytes(mesh);
        if arena.remaining() < needed {
            return Err(Error::CapacityExceeded {
                needed: arena.capacity() - arena.remaining() + needed,
                available: arena.capacity(),
            });
        }
        Ok(())
    }

    /// Finds the rim of `mesh` (its indices checked) into `kept`, with
    /// `keys` ([`key_count`](Self::key_count) of them) and `arena` for
    /// scratch.
    fn find(
        mesh: &Mesh,
        kept: Kept<'a>,
        keys: &mut [[u32; 4]],
        arena: &mut Arena<'_>,
    ) -> Result<Self, Error> {
        kept.header.fill(0);
        let vertices = mesh.positions.len();
        let weld = &mut *kept.weld;
        // vertices sorted by position (their bits, with -0 as 0): equal
        // positions are adjacent and take the first index among them
        for (v, key) in keys[..vertices].iter_mut().enumerate() {
            let p = mesh.positions.get(v).map(|c| (c + 0.0).to_bits());
            *key = [p[0], p[1], p[2], v as u32];
        }
        keys[..vertices].sort_unstable();
        let mut first = 0;
        for i in 0..vertices {
            if keys[i][..3] != keys[first][..3] {
                first = i;
            }
            weld[keys[i][3] as usize] = keys[first][3];
        }
        // each edge keyed by its ends in increasing order, with its
        // direction: after sorting, an edge's copies are adjacent
        let mut n = 0;
        let solid = &mut *kept.solid;
        let mut bounds = SolidBounds::EMPTY;
        for (f, t) in mesh.triangles.iter().enumerate() {
            kept.indices[f] = t;
            let shape = mesh.shape(f);
            solid[f] = !shape.degenerate as u8;
            if shape.degenerate {
                continue;
            }
            bounds.add(shape.corners);
            let [a, b, c] = t.map(|v| weld[v as usize]);
            for (from, to) in [(a, b), (b, c), (c, a)] {
                if from != to {
                    keys[n] = [from.min(to), from.max(to), (from > to) as u32, 0];
                    n += 1;
                }
            }
        }
        let keys = sort_by_first_end(&keys[..n], vertices, arena)?;
        // the surplus edges, compacted to the front as `[from, to, 0, 0]`
        let (mut i, mut e) = (0, 0);
        while i < n {
            let [lo, hi, ..] = keys[i];
            let mut net = 0i64;
            while i < n && keys[i][0] == lo && keys[i][1] == hi {
                net += if keys[i][2] == 0 { 1 } else { -1 };
                i += 1;
            }
            let edge = if net > 0 {
                [lo, hi, 0, 0]
            } else {
                [hi, lo, 0, 0]
            };
            for _ in 0..net.unsigned_abs() {
                keys[e] = edge;
                e += 1;
            }
        }
        let open = &mut keys[..e];
        open.sort_unstable();
        let (edges, starts) = (&mut *kept.edges, &mut *kept.starts);
        // walk each loop from an unused edge to the unused edge leaving its
        // end, until the walk is back where it began
        const USED: u32 = 1;
        let (mut written, mut loops) = (0, 0);
        for first in 0..e {
            if open[first][2] == USED {
                continue;
            }
            starts[loops] = written as u32;
            loops += 1;
            let begin = open[first][0];
            let mut at = first;
            loop {
                open[at][2] = USED;
                let [from, to, ..] = open[at];
                edges[written] = [from, to];
                written += 1;
                if to == begin {
                    break;
                }
                let leaving = open.partition_point(|k| k[0] < to);
                match open[leaving..]
                    .iter()
                    .take_while(|k| k[0] == to)
                    .position(|k| k[2] != USED)
                {
                    Some(j) => at = leaving + j,
                    None => break,
                }
            }
        }
        starts[loops] = written as u32;
        *kept.header = kept.header(mesh, written, loops);
        Ok(kept.rim(mesh, written, loops, bounds))
    }

    /// Number of boundary edges.
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// Number of boundary loops (holes).
    pub fn loop_count(&self) -> usize {
        self.starts.len() - 1
    }

    /// True when the mesh has no boundary: every edge has a partner
    /// running the other way.
    pub fn is_closed(&self) -> bool {
        self.edges.is_empty()
    }

    /// The edges of loop `k`, in order around it, as `[from, to]`.
    pub fn loop_edges(&self, k: usize) -> &'a [[u32; 2]] {
        &self.edges[self.starts[k] as usize..self.starts[k + 1] as usize]
    }

    /// The ball around loop `k` on `mesh`: the mean of its corners, and the
    /// distance from there to the farthest. A cap, a fan from the mean,
    /// lies inside it.
    pub fn ball(&self, k: usize, mesh: &Mesh) -> (Vec3, f32) {
        let at = |v: u32| Vec3::from(mesh.positions.get(v as usize));
        let edges = self.loop_edges(k);
        let mean = edges.iter().map(|e| at(e[0])).sum::<Vec3>() / edges.len() as f32;
        let radius = edges
            .iter()
            .map(|e| at(e[0]).distance(mean))
            .fold(0.0f32, f32::max);
        (mean, radius)
    }

    /// True when triangle `f` of the rim's mesh is not degenerate (it was
    /// found so once, here).
    #[inline]
    pub(crate) fn is_solid(&self, f: usize) -> bool {
        self.solid[f] != 0
    }

    /// The welded index of vertex `v`: the lowest index at its position.
    pub fn welded(&self, v: u32) -> u32 {
        self.weld[v as usize]
    }

    /// The bounds of the solid triangles of the mesh the rim was found
    /// (or refreshed) on, and their number.
    pub(crate) fn solid_bounds(&self) -> SolidBounds {
        self.solid_bounds
    }

    /// Checks that `mesh` has the counts of the mesh the rim was found on.
    pub(crate) fn check_mesh(&self, mesh: &Mesh) -> Result<(), Error> {
        if mesh.positions.len() != self.vertices || mesh.triangle_count() != self.triangles {
            return Err(Error::InvalidArgument(
                "the rim was found on a mesh of another topology",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testmesh::{graded_plane, seamed_sphere, sphere};
    use crate::Strided;

    /// `triangles` without triangles 40 and 150: far apart on the test
    /// spheres, two triangular holes.
    fn two_holes(triangles: &[[u32; 3]]) -> Vec<[u32; 3]> {
        triangles
            .iter()
            .enumerate()
            .filter(|&(i, _)| i != 40 && i != 150)
            .map(|(_, &t)| t)
            .collect()
    }

    fn rim_of<'a>(mesh: &Mesh, buf: &'a mut Vec<u8>) -> Rim<'a> {
        *buf = vec![0u8; Rim::required_bytes(mesh)];
        Rim::new(mesh, &mut Arena::new(buf)).unwrap()
    }

    #[test]
    fn a_closed_mesh_has_no_rim_and_a_plane_has_one_loop() {
        let m = sphere(8, 16);
        let mut buf = vec![];
        assert!(rim_of(&m.mesh(), &mut buf).is_closed());
        let plane = graded_plane(6, 1.0);
        let rim = rim_of(&plane.mesh(), &mut buf);
        assert_eq!((rim.loop_count(), rim.edge_count()), (1, 24));
        let edges = rim.loop_edges(0);
        // in order: each edge starts where the last one ended, and back
        for w in edges.windows(2) {
            assert_eq!(w[0][1], w[1][0]);
        }
        assert_eq!(edges.last().unwrap()[1], edges[0][0]);
    }

    /// The rim `refresh` gives in `memory` (kept from call to call) is the
    /// one `new` finds in fresh memory, whatever changed in between.
    fn refreshes_as_found(mesh: &Mesh, memory: &mut [u8]) {
        let refreshed = Rim::refresh(mesh, &mut Arena::new(memory)).unwrap();
        let mut fresh_memory = vec![];
        let fresh = rim_of(mesh, &mut fresh_memory);
        assert_eq!(
            (refreshed.edge_count(), refreshed.loop_count()),
            (fresh.edge_count(), fresh.loop_count())
        );
        for k in 0..fresh.loop_count() {
            assert_eq!(refreshed.loop_edges(k), fresh.loop_edges(k));
        }
        for v in 0..mesh.positions.len() as u32 {
            assert_eq!(refreshed.welded(v), fresh.welded(v));
        }
        for f in 0..mesh.triangle_count() {
            assert_eq!(refreshed.is_solid(f), fresh.is_solid(f));
        }
    }

    #[test]
    fn a_refreshed_rim_is_the_rim_found_again() {
        // a seamed sphere with two holes: welds, loops and solid triangles
        let m = seamed_sphere(12, 24);
        let tris = two_holes(&m.t);
        let mut p = m.p.clone();
        let mut memory = vec![
            0u8;
            Rim::required_bytes(&Mesh::new(
                Strided::from_slice(&p),
                Strided::from_slice(&tris)
            ))
        ];
        let check = |p: &[[f32; 3]], t: &[[u32; 3]], memory: &mut [u8]| {
            refreshes_as_found(
                &Mesh::new(Strided::from_slice(p), Strided::from_slice(t)),
                memory,
            )
        };
        // fresh memory, then the same mesh again, then moved
        check(&p, &tris, &mut memory);
        check(&p, &tris, &mut memory);
        p.iter_mut()
            .for_each(|q| *q = [q[0] * 1.5 + 0.25, q[1], q[2] - 2.0]);
        check(&p, &tris, &mut memory);
        // a triangle collapsed (no longer solid: a third hole), then back
        let saved = p.clone();
        let [a, b, c] = tris[7];
        p[b as usize] = p[a as usize];
        p[c as usize] = p[a as usize];
        check(&p, &tris, &mut memory);
        p.clone_from(&saved);
        check(&p, &tris, &mut memory);
        // the seam's welded copies pulled apart (a slit opens), then back
        let copies: Vec<usize> = (0..p.len())
            .filter(|&v| (0..p.len()).any(|u| u != v && p[u] == p[v]))
            .collect();
        assert!(!copies.is_empty());
        p[copies[0]][0] += 1e-3;
        check(&p, &tris, &mut memory);
        p.clone_from(&saved);
        check(&p, &tris, &mut memory);
        // two vertices of a hole's rim moved onto one spot (welded anew)
        let [a, b, ..] = m.t[40];
        p[b as usize] = p[a as usize];
        check(&p, &tris, &mut memory);
        p.clone_from(&saved);
        // other indices, the same counts
        let mut turned = tris.clone();
        turned.iter_mut().for_each(|t| *t = [t[1], t[2], t[0]]);
        turned.swap(0, 1);
        check(&p, &turned, &mut memory);
        let mut other = tris.clone();
        other[3] = other[200];
        check(&p, &other, &mut memory);
        check(&p, &tris, &mut memory);
        // memory moved: found again, the same rim
        let mut moved = memory.clone();
        check(&p, &tris, &mut moved);
    }

    #[test]
    fn a_seam_of_split_vertices_is_not_a_hole() {
        let m = seamed_sphere(12, 24);
        let mut buf = vec![];
        assert!(rim_of(&m.mesh(), &mut buf).is_closed());
    }

    #[test]
    fn holes_give_one_loop_each_and_a_short_arena_is_refused() {
        // two triangles removed far apart on a sphere: two triangular holes
        let m = sphere(8, 16);
        let tris = two_holes(&m.t);
        let mesh = Mesh::new(Strided::from_slice(&m.p), Strided::from_slice(&tris));
        let mut buf = vec![];
        let rim = rim_of(&mesh, &mut buf);
        assert_eq!((rim.loop_count(), rim.edge_count()), (2, 6));
        let mut short = vec![0u8; Rim::required_bytes(&mesh) - 1];
        assert!(matches!(
            Rim::new(&mesh, &mut Arena::new(&mut short)),
            Err(Error::CapacityExceeded { .. })
        ));
    }
}
