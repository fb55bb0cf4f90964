//! The edge pass: drops the later of two candidates of different faces
//! closer than the disk radius.

use super::near::Near;
use super::{face_frame, Candidate, Scratch, Stamper, EDGE_GRID_CELL};
use crate::surface::grid::HashGrid;
use crate::Error;
use glam::Vec3;

/// Edge-pass mark of a candidate found too close to a point of another face.
pub(super) const CLASHED: u8 = u8::MAX;

impl<'m, 'a> Stamper<'m, 'a> {
    /// The edge pass: keeps, in order, every candidate that is not closer
    /// than the disk radius to an earlier kept one, compacting them to the
    /// front of `cands`. Returns the number kept.
    ///
    /// Points of one triangle and of its linked neighbours are spaced by the
    /// tile, so only points [`Candidate::near_edge`] take part: this is
    /// exact (up to the bend of linked edges) on any surface whose dihedral
    /// angles at cut edges are above 90 degrees and whose separate
    /// same-facing sheets are a radius apart. A triangle's
    /// points are tested together, against the kept points of earlier
    /// triangles gathered once from the grid (see `gather`).
    pub fn prune(&self, cands: &mut [Candidate], scratch: &mut Scratch) -> Result<usize, Error> {
        let n = cands.len();
        scratch.check(n)?;
        let status = &mut scratch.level[..n];
        status.fill(0);
        // a bucket per candidate, several per point that goes in: blocks of
        // cells then rarely share a bucket, and the table clears fast
        let buckets = HashGrid::buckets_for(2 * n).min(scratch.heads.len());
        let heads = &mut scratch.heads[..buckets];
        let mut grid = HashGrid::new(heads, scratch.next, EDGE_GRID_CELL * self.radius).in_blocks();
        let near = &mut *scratch.near;
        let (mut j, mut inserted, mut kept) = (0, 0, 0);
        while j < n {
            let f = cands[j].face;
            let end = cands[j..]
                .iter()
                .position(|c| c.face != f)
                .map_or(n, |e| j + e);
            // the face's records go after the inserted ones, where those it
            // keeps stay
            let (records, rest) = near.split_at_mut(inserted);
            let mut m = 0;
            let frame = face_frame(&self.mesh, f as usize);
            // every candidate is written and only those near an edge kept:
            // a branch on that would mispredict (about one in four is)
            for (i, c) in (j..end).zip(&cands[j..end]) {
                rest[m] = Near::new(c, i, &frame);
                m += c.near_edge() as usize;
            }
            if m > 0 {
                let group = &rest[..m];
                let reach = self.local_radius(f) * 1.0001;
                let buf = &mut scratch.gathered;
                Self::gather(&grid, records, group, reach, buf, |buf| {
                    self.weigh(buf, f, |scale| {
                        let r = self.radius / scale;
                        r * r
                    });
                    for q in group {
                        let s = &mut status[q.index as usize];
                        if *s != CLASHED && buf.clashes(q.position) {
                            *s = CLASHED;
                        }
                    }
                });
                let first = inserted;
                for g in first..first + m {
                    let q = near[g];
                    if status[q.index as usize] != CLASHED {
                        near[inserted] = q;
                        grid.insert(inserted as u32, Vec3::from(q.position));
                        inserted += 1;
                    }
                }
            }
            // later faces leave this face's marks alone: it is compacted now,
            // while its candidates are still in cache
            for i in j..end {
                let c = cands[i];
                cands[kept] = c;
                kept += (status[i] != CLASHED) as usize;
            }
            j = end;
        }
        Ok(kept)
    }
}
