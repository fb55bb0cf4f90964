//! LOD levels across triangles and the ranks they give.

use super::near::Near;
use super::{face_frame, Candidate, Scratch, Stamper, GRID_CELL};
use crate::rng::{self, Purpose};
use crate::stamp::tile::{LEVEL_STEPS, LOD_LEVELS};
use crate::surface::grid::HashGrid;
use crate::{Error, Root};
use glam::Vec3;

/// Bits of the hash that orders the candidates within one step of a LOD
/// level (ties keep candidate order).
pub(super) const RANK_HASH_BITS: u32 = 10;
/// 2^64 over the golden ratio, odd.
const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;
/// Counters of the rank sort: one per (level, step, hash) key.
pub(super) const RANK_KEYS: usize = (LOD_LEVELS * LEVEL_STEPS) << RANK_HASH_BITS;

impl<'m, 'a> Stamper<'m, 'a> {
    /// Assigns LOD levels across triangles, ranks the candidates, and writes
    /// the [`output_count`](Self::output_count) lowest-ranked ones (any rank
    /// prefix is evenly spread, so the trim keeps the Poisson property) in
    /// candidate order, with ids `0..n`.
    pub fn finish(
        &self,
        cands: &[Candidate],
        scratch: &mut Scratch,
        out: &mut [Root],
    ) -> Result<(), Error> {
        self.finish_reporting(cands, scratch, out, &mut |_| Ok(()))
    }

    /// [`finish`](Self::finish), calling `done` with the share of the work
    /// done after each LOD level and once more before `out` is written; an
    /// error from `done` ends the call there.
    pub(super) fn finish_reporting(
        &self,
        cands: &[Candidate],
        scratch: &mut Scratch,
        out: &mut [Root],
        done: &mut dyn FnMut(f32) -> Result<(), Error>,
    ) -> Result<(), Error> {
        let n = cands.len();
        let m = self.output_count(n);
        if out.len() < m {
            return Err(Error::OutputTooSmall {
                needed: m,
                available: out.len(),
            });
        }
        scratch.check(n)?;
        self.assign_levels(cands, scratch, done)?;
        // a stable counting sort by (level, hash): the slot a candidate
        // takes in it is its rank
        let keys = &mut scratch.next[..n];
        let counts = &mut *scratch.counts;
        counts.fill(0);
        // Fibonacci hashing of the candidate index, offset by the seed: the
        // keys of consecutive candidates (neighbours on one face) step by
        // the golden ratio around the key range, so they land far apart in
        // the order, and any run of keys takes candidates from all over
        let offset = rng::hash(self.seed, 0, Purpose::LodOrder, 0);
        let levels = scratch.level[..n].iter();
        for (j, ((key, &l), c)) in keys.iter_mut().zip(levels).zip(cands).enumerate() {
            let h = offset.wrapping_add(j as u64).wrapping_mul(GOLDEN) >> (64 - RANK_HASH_BITS);
            // a point raised to a finer level comes after that level's
            // own points
            let step = if l == c.level {
                c.step
            } else {
                LEVEL_STEPS as u8 - 1
            };
            let fine = l as u32 * LEVEL_STEPS as u32 + step as u32;
            *key = (fine << RANK_HASH_BITS) | h as u32;
            counts[*key as usize] += 1;
        }
        let mut first = 0;
        for c in counts.iter_mut() {
            (*c, first) = (first, first + *c);
        }
        done(1.0)?;
        // the slot a candidate takes is its rank; they are handed out in
        // candidate order, which is also the output's
        let mut id = 0;
        for (c, &key) in cands.iter().zip(&*keys) {
            let next = &mut counts[key as usize];
            let rank = *next;
            *next += 1;
            if (rank as usize) < m {
                out[id] = Root {
                    face: c.face,
                    u: c.uv[0],
                    v: c.uv[1],
                    id: id as u32,
                    rank,
                };
                id += 1;
            }
        }
        Ok(())
    }

    /// Nested LOD levels across triangles. A point `q` of tile level `t(q)`
    /// takes the finest of `t(q)` and, for every point `p` of another
    /// triangle that comes before it (a coarser tile level, or the same one
    /// on an earlier triangle) and lies closer than the spacing of `t(q)`,
    /// the first level whose spacing their distance respects.
    ///
    /// Every pair then respects the spacing of every level both are in:
    /// only the later point of a pair needs to move, and only when it is
    /// closer than its own level's spacing, since the earlier point's tile
    /// level is coarser still. The rule reads tile levels only, so each
    /// level is one query per point, in any order, with no re-checking as
    /// levels change.
    ///
    /// A candidate whose [`Candidate::near_levels`] stop before its tile
    /// level conflicts with no other triangle at that level or any
    /// finer one, so it keeps its tile level; the others are copied to
    /// [`Near`] records grouped by tile level. Level `k` puts the records of
    /// coarser levels within its spacing of a boundary into a grid, then
    /// tests its own records against it one triangle at a time, adding each
    /// triangle's records after its test.
    fn assign_levels(
        &self,
        cands: &[Candidate],
        scratch: &mut Scratch,
        done: &mut dyn FnMut(f32) -> Result<(), Error>,
    ) -> Result<(), Error> {
        let n = cands.len();
        let finest = LOD_LEVELS - 1;
        let squares = self.spacings.map(|s| s * s);
        let level = &mut scratch.level[..n];
        let takes_part =
            |c: &Candidate| (c.level as u16) < c.near_levels && (c.level as usize) < finest;
        let taking = &mut *scratch.next;
        let mut start = [0usize; LOD_LEVELS + 1];
        let mut m = 0;
        for (j, (c, l)) in cands.iter().zip(level.iter_mut()).enumerate() {
            *l = c.level;
            // branch-free: which candidates take part is close to random
            let takes = takes_part(c) as usize;
            start[c.level as usize + 1] += takes;
            taking[m] = j as u32;
            m += takes;
        }
        for l in 0..LOD_LEVELS {
            start[l + 1] += start[l];
        }
        let mut fill = start;
        let mut frame = (u32::MAX, [Vec3::ZERO; 3]);
        for &j in &taking[..m] {
            let c = &cands[j as usize];
            if c.face != frame.0 {
                frame = (c.face, face_frame(&self.mesh, c.face as usize));
            }
            scratch.near[fill[c.level as usize]] = Near::new(c, j as usize, &frame.1);
            fill[c.level as usize] += 1;
        }
        let near = &scratch.near[..m];
        // no level holds more than the records: the rest of the table is
        // never read, nor cleared
        let buckets = HashGrid::buckets_for(m).min(scratch.heads.len());
        let mut grid = HashGrid::new(&mut scratch.heads[..buckets], scratch.next, self.radius);
        for k in 0..finest {
            let s = self.spacings[k];
            let (coarser, end) = (start[k], start[k + 1]);
            grid.reset(GRID_CELL * self.radius * s, end);
            // coarser levels block every other triangle; this level's
            // records block the triangles after their own, so go in after it
            for (i, q) in near[..coarser].iter().enumerate() {
                grid.insert_if((k as u32) < q.near_levels, i as u32, q.position.into());
            }
            let mut first = coarser;
            for group in near[coarser..end].chunk_by(|a, b| a.face == b.face) {
                let f = group[0].face;
                let reach = self.local_radius(f) * s * 1.0001;
                let buf = &mut scratch.gathered;
                Self::gather(&grid, near, group, reach, buf, |buf| {
                    // squared distances in units of the pair's local radius
                    self.weigh(buf, f, |scale| {
                        let w = scale / self.radius;
                        w * w
                    });
                    for q in group {
                        let d = buf.nearest(q.position);
                        let l = &mut level[q.index as usize];
                        while (*l as usize) < finest && d < squares[*l as usize] {
                            *l += 1;
                        }
                    }
                });
                for (i, q) in (first..).zip(group) {
                    grid.insert(i as u32, Vec3::from(q.position));
                }
                first += group.len();
            }
            done((k + 1) as f32 / LOD_LEVELS as f32)?;
        }
        Ok(())
    }
}
