//! LOD levels across triangles and the ranks they give.

use super::eliminate::ELIMINATION_LIMIT;
use super::near::Near;
use super::{face_frame, Candidate, Scratch, Stamper, GRID_CELL};
use crate::rng::{self, Purpose};
use crate::stamp::tile::{step_spacing, LEVEL_STEPS, LOD_LEVELS, TILE_SIDE};
use crate::surface::grid::HashGrid;
use crate::{Error, Root};
use glam::Vec3;

/// Bits of the key that orders the candidates within one step of a LOD
/// level: their order from the tile (8 bits), then a hash (ties keep
/// candidate order).
pub(super) const RANK_ORDER_BITS: u32 = 8 + HASH_BITS;
/// Bits of the hash below the tile order: it spreads the points of one
/// order over the mesh.
const HASH_BITS: u32 = 2;
/// 2^64 over the golden ratio, odd.
const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;
/// Counters of the rank sort: one per (step, order, hash) key.
pub(super) const RANK_KEYS: usize = (LOD_LEVELS * LEVEL_STEPS) << RANK_ORDER_BITS;

impl<'m, 'a> Stamper<'m, 'a> {
    /// Assigns LOD levels across triangles, ranks the candidates, and writes
    /// the [`output_count`](Self::output_count) lowest-ranked ones (any rank
    /// prefix is evenly spread, so the trim keeps the Poisson property) in
    /// candidate order, with ids `0..n`. Up to 65,536 roots are ranked by
    /// sample elimination instead, and their surplus leaves by it (where
    /// the candidates crowd each other most).
    pub fn finish(
        &self,
        cands: &[Candidate],
        scratch: &mut Scratch,
        out: &mut [Root],
    ) -> Result<(), Error> {
        self.finish_reporting(cands, scratch, out, &mut |_| Ok(()))
    }

    /// [`finish`](Self::finish), calling `done` with the share of the work
    /// done after each LOD level (or elimination step) and once more before
    /// `out` is written; an error from `done` ends the call there.
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
        if m <= ELIMINATION_LIMIT && n <= scratch.elimination.rank.len() {
            self.rank_by_elimination(cands, m, scratch, done)?;
            done(1.0)?;
            let ranks = &scratch.elimination.rank[..n];
            let kept = cands
                .iter()
                .zip(ranks)
                .filter(|(_, &rank)| (rank as usize) < m);
            for (id, (c, &rank)) in kept.enumerate() {
                out[id] = c.root(id as u32, rank);
            }
            return Ok(());
        }
        self.assign_levels(cands, scratch, done)?;
        // a stable counting sort by (step, order in the step, hash): the
        // slot a candidate takes in it is its rank
        let keys = &mut scratch.next[..n];
        let counts = &mut *scratch.counts;
        counts.fill(0);
        // Fibonacci hashing of the candidate index, offset by the seed: the
        // keys of consecutive candidates (neighbours on one face) of one
        // order step by the golden ratio around the hash range
        let offset = rng::hash(self.seed, 0, Purpose::LodOrder, 0);
        let levels = scratch.level[..n].iter();
        for (j, ((key, &t), c)) in keys.iter_mut().zip(levels).zip(cands).enumerate() {
            let h = offset.wrapping_add(j as u64).wrapping_mul(GOLDEN) >> (64 - HASH_BITS);
            // the count trim drops the end of the last step: not points
            // near a cut, where the edge pass has thinned the roots already
            // (whatever crowded them in the tile may lie across the cut)
            let order = if t as usize == SUB_LEVELS - 1 && c.near_edge() {
                0
            } else {
                c.order
            };
            *key = (t as u32) << RANK_ORDER_BITS | (order as u32) << HASH_BITS | h as u32;
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
                out[id] = c.root(id as u32, rank);
                id += 1;
            }
        }
        Ok(())
    }

    /// Nested LOD steps across triangles. The steps of all levels, coarsest
    /// first, are the sub-levels here (`level * LEVEL_STEPS + step`, see
    /// [`step_spacing`]); a prefix of the rank is a prefix of them, so each
    /// one's spacing holds across triangles as it does inside the tile. A
    /// point `q` of tile sub-level `t(q)` takes the finest of `t(q)` and,
    /// for every point `p` of another triangle that comes before it (a
    /// coarser tile sub-level, or the same one on an earlier triangle) and
    /// lies closer than the spacing of `t(q)`, the first sub-level whose
    /// spacing their distance respects.
    ///
    /// Every pair then respects the spacing of every sub-level both are in:
    /// only the later point of a pair needs to move, and only when it is
    /// closer than its own sub-level's spacing, since the earlier point's
    /// tile sub-level is coarser still. The rule reads tile sub-levels only,
    /// so each is one query per point, in any order, with no re-checking as
    /// levels change. The finest sub-level's spacing is the disk radius,
    /// which the edge pass keeps.
    ///
    /// A candidate whose [`Candidate::near_levels`] show that no disk of its
    /// step's spacing reaches past its triangle conflicts with no other
    /// triangle there or finer, so it keeps its tile sub-level; the others
    /// are copied to [`Near`] records grouped by tile sub-level. Level `k`
    /// puts the records of coarser levels whose disk reaches a boundary into
    /// a grid, then tests each step's records against it one triangle at a
    /// time, adding each triangle's records after its test.
    pub(super) fn assign_levels(
        &self,
        cands: &[Candidate],
        scratch: &mut Scratch,
        done: &mut dyn FnMut(f32) -> Result<(), Error>,
    ) -> Result<(), Error> {
        let n = cands.len();
        let finest = SUB_LEVELS - 1;
        let squares: [f32; SUB_LEVELS] = core::array::from_fn(|t| {
            let s = step_spacing(t / LEVEL_STEPS, t % LEVEL_STEPS);
            s * s
        });
        let level = &mut scratch.level[..n];
        let taking = &mut *scratch.next;
        let mut start = [0usize; SUB_LEVELS + 1];
        let mut m = 0;
        // the steps whose spacing is wider than the tile: a triangle wider
        // than the tile holds copies of one such point, one tile apart,
        // which only a test within the triangle finds
        let tile_square = (TILE_SIDE * TILE_SIDE) as f32;
        let wider = |t: usize| squares[t] > tile_square;
        for (j, (c, l)) in cands.iter().zip(level.iter_mut()).enumerate() {
            *l = sub_level(c);
            // branch-free: which candidates take part is close to random
            let near = reaches(c, c.level as usize) | wider(*l as usize);
            let takes = (near && (*l as usize) < finest) as usize;
            start[*l as usize + 1] += takes;
            taking[m] = j as u32;
            m += takes;
        }
        for t in 0..SUB_LEVELS {
            start[t + 1] += start[t];
        }
        let mut fill = start;
        let mut frame = (u32::MAX, [Vec3::ZERO; 3]);
        for &j in &taking[..m] {
            let c = &cands[j as usize];
            if c.face != frame.0 {
                frame = (c.face, face_frame(&self.mesh, c.face as usize));
            }
            let t = sub_level(c) as usize;
            scratch.near[fill[t]] = Near::new(c, j as usize, &frame.1);
            fill[t] += 1;
        }
        let near = &scratch.near[..m];
        // no level holds more than the records: the rest of the table is
        // never read, nor cleared
        let buckets = HashGrid::buckets_for(m).min(scratch.heads.len());
        let mut grid = HashGrid::new(&mut scratch.heads[..buckets], scratch.next, self.radius);
        for k in 0..LOD_LEVELS {
            let steps = k * LEVEL_STEPS..((k + 1) * LEVEL_STEPS).min(finest);
            let coarser = start[steps.start];
            grid.reset(
                GRID_CELL * self.radius * step_spacing(k, 0),
                start[steps.end],
            );
            // coarser levels block every other triangle; each step's records
            // block the triangles after their own and the later steps, so
            // go in after it
            for (i, q) in near[..coarser].iter().enumerate() {
                let reaching = k <= q.near_levels as usize;
                grid.insert_if(reaching, i as u32, q.position.into());
            }
            let mut first = coarser;
            for t in steps {
                let s = libm::sqrtf(squares[t]);
                for group in near[first..start[t + 1]].chunk_by(|a, b| a.face == b.face) {
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
                            respect(&mut level[q.index as usize], d, &squares);
                        }
                    });
                    if wider(t) {
                        self.part_copies(group, &squares, level);
                    }
                    for (i, q) in (first..).zip(group) {
                        grid.insert(i as u32, Vec3::from(q.position));
                    }
                    first += group.len();
                }
            }
            done((k + 1) as f32 / LOD_LEVELS as f32)?;
        }
        Ok(())
    }

    /// Raises each point of `group` (one triangle's records of a step
    /// wider than the tile) that lies closer than its sub-level's spacing
    /// (`squares`, squared) to an earlier one of the group, to the first
    /// sub-level whose spacing their distance respects, as
    /// [`assign_levels`](Self::assign_levels) does across triangles.
    fn part_copies(&self, group: &[Near], squares: &[f32; SUB_LEVELS], level: &mut [u8]) {
        let scale = self.faces[group[0].face as usize].scale / self.radius;
        for (k, q) in group.iter().enumerate() {
            let at = Vec3::from(q.position);
            let d = group[..k]
                .iter()
                .map(|p| Vec3::from(p.position).distance_squared(at))
                .fold(f32::INFINITY, f32::min);
            respect(&mut level[q.index as usize], d * (scale * scale), squares);
        }
    }
}

/// Moves sub-level `l` to the first (up to the finest) whose spacing,
/// squared in `squares`, the squared distance `d` to an earlier point
/// respects.
#[inline]
fn respect(l: &mut u8, d: f32, squares: &[f32; SUB_LEVELS]) {
    while (*l as usize) < SUB_LEVELS - 1 && d < squares[*l as usize] {
        *l += 1;
    }
}

/// The steps of all LOD levels, as the sub-levels of the rank.
const SUB_LEVELS: usize = LOD_LEVELS * LEVEL_STEPS;

/// Candidate `c`'s tile sub-level: `level * LEVEL_STEPS + step`.
#[inline]
fn sub_level(c: &Candidate) -> u8 {
    c.level * LEVEL_STEPS as u8 + c.step
}

/// Whether a disk of `c`'s step spacing, at level `k` or a coarser one,
/// may reach past its triangle: the steps before a level's last are wider
/// than its spacing but narrower than the coarser level's, which
/// [`Candidate::near_levels`] counts.
#[inline]
fn reaches(c: &Candidate, k: usize) -> bool {
    let last = c.step as usize == LEVEL_STEPS - 1;
    k < c.near_levels as usize + !last as usize
}
