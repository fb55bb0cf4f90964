//! The LOD order of a small stamp by weighted sample elimination (Yuksel,
//! "Sample Elimination for Generating Poisson Disk Sample Sets", 2015).
//!
//! Below some tens of thousands of roots a chart of the tile is narrow next
//! to the spacing of the coarse LOD steps, so those steps are mostly made
//! across triangles, where a root can only move to a finer step: the 50%
//! and 25% rank prefixes come out less even than a Poisson set of their own
//! size. Up to [`ELIMINATION_LIMIT`] roots the ranks are therefore made
//! from the finished candidates instead, over the whole mesh: halve the set by
//! removing, one at a time, the root whose neighbours crowd it most (each
//! same-side neighbour `j` closer than `2 r` weighs `(1 - d / 2r)^8`, `r`
//! the spacing a Poisson set of the halved count would have there, by the
//! local density), then halve what is left, and so on; the roots removed
//! from a set of `m` take the ranks below `m`, the first removed the
//! highest. A pass that lands above the count leaves its surplus the same
//! way first, down to the count (the spacing of the count's set). Every prefix is then a set thinned evenly from the one above
//! it. Sequential and exact in its order (ties go to the higher index), so
//! the same stamp gives the same ranks on any machine.

use super::{same_air, Candidate, Scratch, Stamper};
use crate::surface::grid::HashGrid;
use crate::Error;
use glam::Vec3;

/// Largest stamp whose ranks are made by elimination; larger stamps keep
/// the tile's order, whose prefixes are even there (a chart holds many
/// coarse points) and whose cost does not grow with a heap.
pub(super) const ELIMINATION_LIMIT: usize = 1 << 16;
/// Candidates the elimination takes at most: the limit and its surplus (a
/// pass lands a few percent above the count; a stamp accepted with more
/// after the last radius correction keeps the tile's order).
pub(super) const ELIMINATION_ROOM: usize = 2 * ELIMINATION_LIMIT;
/// The heap place of a root that has left.
const GONE: u32 = u32::MAX;
/// Grid buckets per root in the elimination.
pub(super) const BUCKETS_PER_ROOT: usize = 8;

impl Stamper<'_, '_> {
    /// Ranks the `n` candidates `cands` (at most [`ELIMINATION_ROOM`]) by
    /// weighted sample elimination into `scratch.elimination.rank`: the
    /// surplus over `target` leaves first, where the candidates crowd each
    /// other most, and takes the ranks from `target` on; the `target` left
    /// are then halved as the module docs say. Calls `done` with the share
    /// of the work done after each step; an error from it ends the call.
    pub(super) fn rank_by_elimination(
        &self,
        cands: &[Candidate],
        target: usize,
        scratch: &mut Scratch,
        done: &mut dyn FnMut(f32) -> Result<(), Error>,
    ) -> Result<(), Error> {
        let n = cands.len();
        if n == 0 {
            return Ok(());
        }
        let Scratch {
            next,
            elimination: e,
            ..
        } = scratch;
        let (weight, heap, slot, mark) = (
            &mut e.weight[..n],
            &mut e.heap[..n],
            &mut e.slot[..n],
            &mut e.mark[..n],
        );
        let (at, ranks) = (&mut e.at[..n], &mut e.rank[..n]);
        for (i, c) in cands.iter().enumerate() {
            let f = c.face as usize;
            let (p, normal) = (self.mesh.point(f, c.uv[0], c.uv[1]), self.faces[f].normal);
            let scale = self.faces[f].scale;
            at[i] = [p.x, p.y, p.z, scale, normal[0], normal[1], normal[2], 0.0];
        }
        let at = &*at;
        // a root's place in the heap, or GONE once it has left
        slot.fill(0);
        mark.fill(u32::MAX);
        // the skin the roots grow on, in units of the spacing at scale 1
        let area = self.area * self.unburied;
        let smallest = at.iter().fold(f32::INFINITY, |m, a| m.min(a[3]));
        // a table much larger than the roots: a query's cells share their
        // buckets with few roots from elsewhere on the mesh
        let buckets = (BUCKETS_PER_ROOT * n)
            .next_power_of_two()
            .min(e.heads.len());
        let mut grid = HashGrid::new(&mut e.heads[..buckets], next, 1.0).in_blocks();
        let (mut m, mut kept, mut query) = (n, target.min(n), 0u32);
        let mut spent = 0;
        loop {
            if kept == m {
                if m <= 1 {
                    break;
                }
                kept = m / 2;
            }
            // Yuksel's r_max: the spacing of `kept` points in hexagons
            let reach = 2.0 * libm::sqrt(area / (2.0 * libm::sqrt(3.0) * kept as f64)) as f32;
            grid.reset_buckets(
                2.0 * reach / smallest,
                (BUCKETS_PER_ROOT * m).next_power_of_two(),
            );
            for (i, &place) in slot.iter().enumerate() {
                grid.insert_if(place != GONE, i as u32, point(at, i));
            }
            // the farthest a neighbour of root i can weigh from
            let around = |i: usize| reach * 2.0 / (at[i][3] + smallest);
            let crowding = |i: usize, j: usize| -> f64 {
                let (a, b) = (&at[i], &at[j]);
                // d >= r with r = 2 reach / (s_a + s_b), without a division
                let (scale, far) = (a[3] + b[3], 2.0 * reach);
                let d2 = point(at, i).distance_squared(point(at, j));
                let normal = |x: &[f32; 8]| Vec3::new(x[4], x[5], x[6]);
                let same_side = same_air(point(at, i), normal(a), point(at, j), normal(b));
                if !same_side || d2 * scale * scale >= far * far {
                    return 0.0;
                }
                // Yuksel's exponent, 8
                let x = 1.0 - (libm::sqrtf(d2) * scale / far) as f64;
                let x2 = x * x;
                let x4 = x2 * x2;
                x4 * x4
            };
            // each root's weight; a bucket shared by two cells of a query
            // yields its roots twice, the mark counts each once
            let mut len = 0;
            for i in 0..n {
                if slot[i] == GONE {
                    continue;
                }
                query += 1;
                let mut w = 0.0;
                grid.any_within(point(at, i), around(i), |j| {
                    let j = j as usize;
                    if j != i && mark[j] != query {
                        mark[j] = query;
                        w += crowding(i, j);
                    }
                    false
                });
                weight[i] = w;
                heap[len] = i as u32;
                slot[i] = len as u32;
                len += 1;
            }
            let mut h = Heap {
                heap: &mut heap[..len],
                slot,
                weight,
            };
            h.build();
            for rank in (kept..m).rev() {
                let i = h.pop();
                ranks[i] = rank as u32;
                h.slot[i] = GONE;
                query += 1;
                grid.any_within(point(at, i), around(i), |j| {
                    let j = j as usize;
                    if h.slot[j] != GONE && mark[j] != query {
                        mark[j] = query;
                        let c = crowding(i, j);
                        if c > 0.0 {
                            h.lower(j, c);
                        }
                    }
                    false
                });
            }
            // a step's work goes with the roots it starts from: all of
            // them, then the target, its half and so on
            spent += m;
            done(spent as f32 / (n + 2 * target) as f32)?;
            m = kept;
        }
        if let Some(last) = slot.iter().position(|&s| s != GONE) {
            ranks[last] = 0;
        }
        Ok(())
    }
}

/// The position of root `i` in the elimination's records.
#[inline]
fn point(at: &[[f32; 8]], i: usize) -> Vec3 {
    Vec3::new(at[i][0], at[i][1], at[i][2])
}

/// A max-heap of roots by weight (ties: the higher index first), with each
/// root's place in it, so a weight can drop in place.
struct Heap<'h> {
    heap: &'h mut [u32],
    slot: &'h mut [u32],
    weight: &'h mut [f64],
}

impl Heap<'_> {
    /// Whether root `a` leaves before root `b`.
    #[inline]
    fn before(&self, a: u32, b: u32) -> bool {
        let (wa, wb) = (self.weight[a as usize], self.weight[b as usize]);
        wa > wb || (wa == wb && a > b)
    }

    fn build(&mut self) {
        for k in (0..self.heap.len() / 2).rev() {
            self.sink(k);
        }
    }

    /// Takes the root that leaves next.
    fn pop(&mut self) -> usize {
        let top = self.heap[0];
        let last = self.heap.len() - 1;
        self.heap.swap(0, last);
        self.slot[self.heap[0] as usize] = 0;
        let heap = core::mem::take(&mut self.heap);
        self.heap = &mut heap[..last];
        if last > 0 {
            self.sink(0);
        }
        top as usize
    }

    /// Lowers the weight of root `i` (in the heap) by `by`.
    fn lower(&mut self, i: usize, by: f64) {
        self.weight[i] -= by;
        self.sink(self.slot[i] as usize);
    }

    fn sink(&mut self, mut k: usize) {
        let len = self.heap.len();
        loop {
            let (l, r) = (2 * k + 1, 2 * k + 2);
            let mut top = k;
            if l < len && self.before(self.heap[l], self.heap[top]) {
                top = l;
            }
            if r < len && self.before(self.heap[r], self.heap[top]) {
                top = r;
            }
            if top == k {
                return;
            }
            self.heap.swap(k, top);
            self.slot[self.heap[k] as usize] = k as u32;
            self.slot[self.heap[top] as usize] = top as u32;
            k = top;
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::stamp::{self, StampParams};
    use crate::testmesh::sphere;
    use crate::{Arena, Root};
    use glam::Vec3;

    /// Nearest-neighbour distances of the roots of rank below `k`, over
    /// r_hex of `k` roots on a skin of area `area`: their smallest and their
    /// coefficient of variation.
    fn prefix(points: &[(Vec3, u32)], k: u32, area: f32) -> (f32, f32) {
        let kept: Vec<Vec3> = points.iter().filter(|p| p.1 < k).map(|p| p.0).collect();
        let r_hex = (2.0 * area / (3f32.sqrt() * k as f32)).sqrt();
        let nearest: Vec<f32> = kept
            .iter()
            .enumerate()
            .map(|(i, a)| {
                let others = kept.iter().enumerate().filter(|&(j, _)| j != i);
                others
                    .map(|(_, b)| a.distance(*b))
                    .fold(f32::INFINITY, f32::min)
                    / r_hex
            })
            .collect();
        let mean = nearest.iter().sum::<f32>() / nearest.len() as f32;
        let var =
            nearest.iter().map(|d| (d - mean) * (d - mean)).sum::<f32>() / nearest.len() as f32;
        let min = nearest.iter().fold(f32::INFINITY, |m, &d| m.min(d));
        (min, var.sqrt() / mean)
    }

    #[test]
    fn halved_prefixes_are_as_even_as_a_poisson_set() {
        let m = sphere(24, 48);
        let mesh = m.mesh();
        let params = StampParams {
            target_count: 4000,
            seed: 3,
            ..StampParams::default()
        };
        let mut arena = vec![0u8; stamp::required_bytes(&mesh, &params).unwrap()];
        let mut out = vec![Root::default(); stamp::max_roots(&mesh, &params).unwrap()];
        let (n, _) = stamp::stamp(mesh, &params, &mut Arena::new(&mut arena), &mut out).unwrap();
        let roots = &out[..n];
        let mut ranks: Vec<u32> = roots.iter().map(|r| r.rank).collect();
        ranks.sort_unstable();
        assert!(ranks.iter().enumerate().all(|(i, &r)| r == i as u32));
        let area: f32 = (0..mesh.triangle_count()).map(|f| mesh.area(f)).sum();
        let points: Vec<(Vec3, u32)> = roots
            .iter()
            .map(|r| (mesh.point(r.face as usize, r.u, r.v), r.rank))
            .collect();
        // a dart-throwing set of its own size has a CV of 0.08-0.10 and no
        // pair nearer than 0.7 of its r_hex
        for share in [2, 4, 8] {
            let (min, cv) = prefix(&points, (n / share) as u32, area);
            assert!(cv <= 0.12 && min >= 0.55, "1/{share}: CV {cv}, min {min}");
        }
        // the same stamp again: the same ranks
        let first: Vec<u32> = roots.iter().map(|r| r.rank).collect();
        let (again, _) =
            stamp::stamp(mesh, &params, &mut Arena::new(&mut arena), &mut out).unwrap();
        assert_eq!(again, n);
        assert!(out[..n].iter().map(|r| r.rank).eq(first));
    }
}
