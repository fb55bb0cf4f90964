//! Working memory of the edge and LOD passes.

use super::eliminate::{BUCKETS_PER_ROOT, ELIMINATION_ROOM};
use super::lod::RANK_KEYS;
use super::near::{Gathered, Near};
use crate::arena::{Arena, ArenaLayout};
use crate::surface::grid::HashGrid;
use crate::Error;

/// Working memory of the edge pass and the LOD pass, sized for a candidate
/// bound once and reused by every pass.
pub struct Scratch<'a> {
    /// Bucket heads of the grid.
    pub(super) heads: &'a mut [u32],
    /// Grid links; in the LOD pass first the candidates that take part, in
    /// the end the rank keys.
    pub(super) next: &'a mut [u32],
    /// Edge-pass mark or LOD level of each candidate.
    pub(super) level: &'a mut [u8],
    /// The points of the grid: those the edge pass keeps, in order; in the
    /// LOD pass, the candidates near a boundary, grouped by tile level.
    pub(super) near: &'a mut [Near],
    /// Counters of the rank sort.
    pub(super) counts: &'a mut [u32],
    pub(super) gathered: Gathered<'a>,
    /// The rank elimination's records, for up to
    /// [`ELIMINATION_ROOM`] candidates.
    pub(super) elimination: Elimination<'a>,
}

/// Per root, what [`Stamper::rank_by_elimination`](super::Stamper) keeps:
/// its weight, its place in the heap and the heap, the mark of the last
/// query that met it, its record (position, density scale, face
/// normal), and in the end its rank.
pub(super) struct Elimination<'a> {
    /// Bucket heads of the elimination's grid.
    pub(super) heads: &'a mut [u32],
    pub(super) weight: &'a mut [f64],
    pub(super) heap: &'a mut [u32],
    pub(super) slot: &'a mut [u32],
    pub(super) mark: &'a mut [u32],
    pub(super) at: &'a mut [[f32; 8]],
    pub(super) rank: &'a mut [u32],
}

impl<'a> Scratch<'a> {
    /// Adds the bytes [`Scratch::new`] takes for `candidates` to `layout`.
    pub(super) fn layout(layout: &mut ArenaLayout, candidates: usize) {
        layout
            .add::<u32>(HashGrid::buckets_for(candidates))
            .add::<u32>(candidates)
            .add::<u8>(candidates)
            .add::<Near>(candidates)
            .add::<u32>(RANK_KEYS);
        Gathered::layout(layout);
        let roots = candidates.min(ELIMINATION_ROOM);
        layout
            .add::<u32>((BUCKETS_PER_ROOT * roots).next_power_of_two())
            .add::<f64>(roots)
            .add::<u32>(4 * roots)
            .add::<[f32; 8]>(roots);
    }

    /// Takes scratch for up to `candidates` candidates from `arena`.
    pub fn new(arena: &mut Arena<'a>, candidates: usize) -> Result<Self, Error> {
        Ok(Scratch {
            heads: arena.alloc::<u32>(HashGrid::buckets_for(candidates))?,
            next: arena.alloc::<u32>(candidates)?,
            level: arena.alloc::<u8>(candidates)?,
            near: arena.alloc::<Near>(candidates)?,
            counts: arena.alloc::<u32>(RANK_KEYS)?,
            gathered: Gathered::new(arena)?,
            elimination: {
                let roots = candidates.min(ELIMINATION_ROOM);
                let heads = arena.alloc::<u32>((BUCKETS_PER_ROOT * roots).next_power_of_two())?;
                let weight = arena.alloc::<f64>(roots)?;
                let (heap, rest) = arena.alloc::<u32>(4 * roots)?.split_at_mut(roots);
                let (slot, rest) = rest.split_at_mut(roots);
                let (mark, rank) = rest.split_at_mut(roots);
                Elimination {
                    heads,
                    weight,
                    heap,
                    slot,
                    mark,
                    at: arena.alloc::<[f32; 8]>(roots)?,
                    rank,
                }
            },
        })
    }

    pub(super) fn check(&self, n: usize) -> Result<(), Error> {
        if n > self.next.len() {
            // in bytes of the per-candidate arrays, which the arena holds
            let per = 4 + 1 + core::mem::size_of::<Near>();
            return Err(Error::CapacityExceeded {
                needed: n * per,
                available: self.next.len() * per,
            });
        }
        Ok(())
    }
}
