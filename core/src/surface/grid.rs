//! A hashed 3D uniform grid over points, built incrementally in an arena.

use glam::Vec3;

const EMPTY: u32 = u32::MAX;

/// `floor(x)` as an integer for |x| < 2^31: a truncation and a fix-up, where
/// libm's portable floor is a bit-twiddling routine several times slower.
#[inline]
pub fn floor_i32(x: f32) -> i32 {
    let i = x as i32;
    i - ((i as f32) > x) as i32
}

/// Hash of an integer cell for a power-of-two bucket table. x enters
/// linearly so the cells of one row of a query sit in neighbouring buckets
/// (one cache line instead of three).
#[inline]
fn cell_hash(c: [i32; 3]) -> u32 {
    (c[0] as u32)
        .wrapping_add((c[1] as u32).wrapping_mul(0x9E37_79B1))
        .wrapping_add((c[2] as u32).wrapping_mul(0x85EB_CA77))
}

/// [`cell_hash`] of the 2x2x2 block holding cell `c`, with the cell's place
/// in the block as the low three bits: a block's cells sit in 8
/// neighbouring buckets.
#[inline]
fn block_hash(c: [i32; 3]) -> u32 {
    let corner = cell_hash([c[0] >> 1, c[1] >> 1, c[2] >> 1]);
    corner << 3 | (c[0] & 1 | (c[1] & 1) << 1 | (c[2] & 1) << 2) as u32
}

/// The bucket of cell `c` in a table of `buckets` (a power of two).
#[inline]
fn bucket_of(c: [i32; 3], buckets: usize, in_blocks: bool) -> usize {
    let h = if in_blocks {
        block_hash(c)
    } else {
        cell_hash(c)
    };
    h as usize & (buckets - 1)
}

/// Buckets of point indices keyed by integer cell, as singly linked lists
/// threaded through a `next` array (one slot per point).
///
/// Collisions between cells only add candidates, never lose them, so a query
/// visits every point inserted into the cells it asks for, and may visit a
/// point more than once when two of those cells share a bucket.
pub struct HashGrid<'a> {
    heads: &'a mut [u32],
    next: &'a mut [u32],
    /// Buckets in use, a power of two: the front of `heads`.
    buckets: usize,
    inv_cell: f32,
    /// Whether cells go to buckets by 2x2x2 blocks (see [`HashGrid::in_blocks`]).
    in_blocks: bool,
}

impl<'a> HashGrid<'a> {
    /// Bucket count to allocate for `points` points (a power of two).
    pub fn buckets_for(points: usize) -> usize {
        (points / 2).max(16).next_power_of_two()
    }

    /// A grid with cells of side `cell`, over caller-provided storage:
    /// `heads.len()` must be a power of two, `next` one slot per point index.
    pub fn new(heads: &'a mut [u32], next: &'a mut [u32], cell: f32) -> Self {
        debug_assert!(heads.len().is_power_of_two());
        heads.fill(EMPTY);
        HashGrid {
            buckets: heads.len(),
            heads,
            next,
            inv_cell: 1.0 / cell,
            in_blocks: false,
        }
    }

    /// The grid with each 2x2x2 block of cells in 8 neighbouring buckets,
    /// for a table much larger than its points: a small query then reads one
    /// or two cache lines of the table where a read per row of cells would
    /// miss the cache each time. A table about the size of its points is
    /// better off with rows, which collide less.
    pub fn in_blocks(mut self) -> Self {
        self.in_blocks = true;
        self
    }

    /// Empties the grid, changes its cell size, and sizes its bucket table
    /// for `points` points (within the storage): a grid rebuilt for fewer
    /// points clears and walks a smaller table.
    pub fn reset(&mut self, cell: f32, points: usize) {
        self.buckets = Self::buckets_for(points).min(self.heads.len());
        self.heads[..self.buckets].fill(EMPTY);
        self.inv_cell = 1.0 / cell;
    }

    /// [`reset`](Self::reset) with `buckets` buckets (a power of two;
    /// within the storage).
    pub fn reset_buckets(&mut self, cell: f32, buckets: usize) {
        debug_assert!(buckets.is_power_of_two());
        self.buckets = buckets.min(self.heads.len());
        self.heads[..self.buckets].fill(EMPTY);
        self.inv_cell = 1.0 / cell;
    }

    /// Integer cell of `p`.
    #[inline]
    pub fn cell_of(&self, p: Vec3) -> [i32; 3] {
        let q = p * self.inv_cell;
        [floor_i32(q.x), floor_i32(q.y), floor_i32(q.z)]
    }

    #[inline]
    fn bucket(&self, c: [i32; 3]) -> usize {
        bucket_of(c, self.buckets, self.in_blocks)
    }

    /// Inserts point `index` at `p`.
    #[inline]
    pub fn insert(&mut self, index: u32, p: Vec3) {
        let b = self.bucket(self.cell_of(p));
        self.next[index as usize] = self.heads[b];
        self.heads[b] = index;
    }

    /// Inserts point `index` at `p` when `keep` holds, without a branch
    /// (for a condition close to random); otherwise leaves the grid as it
    /// was (`index` reaches no bucket).
    #[inline]
    pub fn insert_if(&mut self, keep: bool, index: u32, p: Vec3) {
        let b = self.bucket(self.cell_of(p));
        let head = self.heads[b];
        self.next[index as usize] = head;
        self.heads[b] = if keep { index } else { head };
    }

    /// Calls `f` for every point inserted in the cells that overlap the cube
    /// of half-side `radius` around `p` (so every point within `radius`),
    /// stopping early when `f` returns true; returns whether it did.
    #[inline]
    pub fn any_within(&self, p: Vec3, radius: f32, mut f: impl FnMut(u32) -> bool) -> bool {
        let lo = self.cell_of(p - Vec3::splat(radius));
        let hi = self.cell_of(p + Vec3::splat(radius));
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let mut i = self.heads[self.bucket([x, y, z])];
                    while i != EMPTY {
                        if f(i) {
                            return true;
                        }
                        i = self.next[i as usize];
                    }
                }
            }
        }
        false
    }

    /// The points inserted in the cells that overlap the box `[lo, hi]`
    /// (points outside the box included: the caller filters).
    pub fn in_box(&self, lo: Vec3, hi: Vec3) -> InBox<'_> {
        let (lo, hi) = (self.cell_of(lo), self.cell_of(hi));
        InBox {
            heads: &self.heads[..self.buckets],
            next: self.next,
            in_blocks: self.in_blocks,
            lo,
            hi,
            at: lo,
            node: EMPTY,
        }
    }
}

/// Iterator of [`HashGrid::in_box`].
pub struct InBox<'g> {
    heads: &'g [u32],
    next: &'g [u32],
    in_blocks: bool,
    lo: [i32; 3],
    hi: [i32; 3],
    /// The next cell to enter.
    at: [i32; 3],
    node: u32,
}

impl Iterator for InBox<'_> {
    type Item = u32;

    #[inline]
    fn next(&mut self) -> Option<u32> {
        loop {
            if self.node != EMPTY {
                let i = self.node;
                self.node = self.next[i as usize];
                return Some(i);
            }
            if self.at[2] > self.hi[2] {
                return None;
            }
            self.node = self.heads[bucket_of(self.at, self.heads.len(), self.in_blocks)];
            self.at[0] += 1;
            if self.at[0] > self.hi[0] {
                self.at[0] = self.lo[0];
                self.at[1] += 1;
                if self.at[1] > self.hi[1] {
                    self.at[1] = self.lo[1];
                    self.at[2] += 1;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn insert_if_adds_only_the_points_it_keeps() {
        let (mut heads, mut next) = ([0u32; 16], [0u32; 8]);
        let mut grid = HashGrid::new(&mut heads, &mut next, 1.0);
        let at = |i: u32| Vec3::new(0.25 * i as f32, 0.5, 0.5);
        for i in 0..8 {
            grid.insert_if(i % 3 != 1, i, at(i));
        }
        let mut found: Vec<u32> = grid.in_box(Vec3::ZERO, Vec3::splat(1.9)).collect();
        // cells of the box that share a bucket yield its points twice
        found.sort_unstable();
        found.dedup();
        assert_eq!(found, [0, 2, 3, 5, 6]);
    }

    #[test]
    fn a_block_of_cells_takes_eight_neighbouring_buckets() {
        for corner in [[0, 0, 0], [-2, 4, -6], [10, -8, 2]] {
            let mut hashes: Vec<u32> = (0..8)
                .map(|k| {
                    block_hash([
                        corner[0] + (k & 1),
                        corner[1] + (k >> 1 & 1),
                        corner[2] + (k >> 2),
                    ])
                })
                .collect();
            hashes.sort_unstable();
            let first = hashes[0];
            assert_eq!(first % 8, 0);
            assert_eq!(hashes, (first..first + 8).collect::<Vec<_>>());
        }
    }

    #[test]
    fn both_layouts_find_every_point_in_a_box() {
        // points on both sides of zero, in a table larger than the points
        let points: Vec<Vec3> = (0..500u32)
            .map(|i| {
                let h = |k: u32| crate::rng::unit(7, i as u64, crate::rng::Purpose::LodOrder, k);
                Vec3::new(h(0), h(1), h(2)) * 8.0 - 4.0
            })
            .collect();
        for blocks in [false, true] {
            let (mut heads, mut next) = (vec![0u32; 4096], vec![0u32; points.len()]);
            let mut grid = HashGrid::new(&mut heads, &mut next, 0.7);
            if blocks {
                grid = grid.in_blocks();
            }
            for (i, &p) in points.iter().enumerate() {
                grid.insert(i as u32, p);
            }
            for (lo, hi) in [
                (Vec3::splat(-1.0), Vec3::splat(1.3)),
                (Vec3::new(-4.0, 0.2, -2.5), Vec3::new(-0.1, 3.9, 0.0)),
            ] {
                let mut found: Vec<u32> = grid.in_box(lo, hi).collect();
                found.sort_unstable();
                found.dedup();
                let inside = |p: &Vec3| p.cmpge(lo).all() && p.cmple(hi).all();
                let missed = (0..points.len() as u32)
                    .filter(|&i| inside(&points[i as usize]) && found.binary_search(&i).is_err())
                    .count();
                assert_eq!(missed, 0, "blocks {blocks}");
            }
        }
    }
}
