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
//! slit): find it again when the positions may change those (the
//! simulation finds it every step; see
//! [`BodyPlan::of`](crate::surface::body::BodyPlan::of)). An edge listed
//! `a -> b` by `m` triangles and `b -> a` by `n` is a boundary edge `m - n`
//! times (in the direction of the surplus); a closed mesh, however many
//! shells it has, has none. The surplus edges meet every vertex as often
//! going in as going out (each triangle does), so they always split into
//! closed loops.

use crate::arena::{Arena, ArenaLayout};
use crate::{Error, Mesh};
use glam::Vec3;

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

impl<'a> Rim<'a> {
    /// Arena bytes [`Rim::new`] takes for `mesh` (an upper bound: every edge
    /// could be a boundary edge).
    pub fn required_bytes(mesh: &Mesh) -> usize {
        let edges = 3 * mesh.triangle_count();
        let vertices = mesh.positions.len();
        let mut layout = ArenaLayout::new();
        layout
            .add::<u32>(vertices)
            .add::<[u32; 4]>(edges.max(vertices))
            .add::<[u32; 4]>(edges)
            .add::<u32>(vertices + 1)
            .add::<[u32; 2]>(edges)
            .add::<u32>(edges / 3 + 2)
            .add::<u8>(mesh.triangle_count());
        layout.bytes()
    }

    /// Finds the boundary loops of `mesh` (checks its indices).
    pub fn new(mesh: &Mesh, arena: &mut Arena<'a>) -> Result<Self, Error> {
        mesh.check()?;
        let needed = Self::required_bytes(mesh);
        if arena.remaining() < needed {
            return Err(Error::CapacityExceeded {
                needed: arena.capacity() - arena.remaining() + needed,
                available: arena.capacity(),
            });
        }
        let vertices = mesh.positions.len();
        let weld = arena.alloc::<u32>(vertices)?;
        let keys = arena.alloc::<[u32; 4]>((3 * mesh.triangle_count()).max(vertices))?;
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
        let solid = arena.alloc::<u8>(mesh.triangle_count())?;
        for (f, t) in mesh.triangles.iter().enumerate() {
            solid[f] = !mesh.is_degenerate(f) as u8;
            if solid[f] == 0 {
                continue;
            }
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
        let edges = arena.alloc::<[u32; 2]>(e)?;
        let starts = arena.alloc::<u32>(e / 3 + 2)?;
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
        Ok(Rim {
            weld,
            edges: &edges[..written],
            starts: &starts[..=loops],
            solid,
            vertices: mesh.positions.len(),
            triangles: mesh.triangle_count(),
        })
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
        let tris: Vec<[u32; 3]> =
            m.t.iter()
                .enumerate()
                .filter(|&(i, _)| i != 40 && i != 150)
                .map(|(_, &t)| t)
                .collect();
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
