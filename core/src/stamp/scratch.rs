//! Working memory of the edge and LOD passes.

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
