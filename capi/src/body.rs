//! The body solid of a frame's mesh, built in one place for every call
//! that collides with it (a frame's colliders, a step, trimming): the rim,
//! the grid's placement and the triangles' copy on one thread, then the
//! grid's counts, lists and classes split by layers over threads (the same
//! bits on any count). A step runs the stages apart to overlap them with
//! the guides' advance.

use crate::buffers::grow;
use crate::status::Failure;
use crate::threads::{cut_into, run_parts, thread_total, Progress};
use pelage_core::surface::body::{Body, BodyParts, BodyPlan, Rim};
use pelage_core::{Arena, Mesh};
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

/// The memory of a body built every call, kept from call to call: its
/// rim, its grid and the grid's triangle references.
#[derive(Default)]
pub(crate) struct BodyMemory {
    rim: Vec<u8>,
    grid: Vec<u8>,
    refs: Vec<u8>,
}

impl BodyMemory {
    /// The solid of `mesh` in this memory (grown as needed), its grid of
    /// `density` cells per triangle built over `thread_count` threads,
    /// reporting each stage to `progress`.
    pub(crate) fn body<'a>(
        &'a mut self,
        mesh: &Mesh,
        density: f32,
        thread_count: u32,
        progress: Progress,
    ) -> Result<Body<'a>, Failure> {
        progress.report(0.0)?;
        let (parts, refs) = self.parts(mesh, density)?;
        body_grid(parts, thread_count, progress, |bytes| refs.take(bytes))
    }

    /// The body of `mesh` built on this thread beside a step's guides,
    /// which bend on the others while `bending` holds: the stages that
    /// run on one thread, then the counts, lists and classes (split as on
    /// `threads` threads) for as long as the guides still bend. What is
    /// left runs over every thread in [`Built::body`]; the bits are those
    /// of [`body`](Self::body).
    pub(crate) fn beside(
        &mut self,
        mesh: &Mesh,
        density: f32,
        threads: usize,
        bending: &AtomicBool,
    ) -> Result<Built<'_>, Failure> {
        let (parts, refs) = self.parts(mesh, density)?;
        if !bending.load(Ordering::Relaxed) {
            return Ok(Built::Placed(parts, refs));
        }
        let mut counted = counted(parts, threads, false, |bytes| refs.take(bytes))?;
        if bending.load(Ordering::Relaxed) {
            counted.list(false)?;
            if bending.load(Ordering::Relaxed) {
                counted.classify(false)?;
            }
        }
        Ok(Built::Counted(counted))
    }

    /// [`body`](Self::body)'s stages that run on one thread, and the
    /// memory the rest takes for the references.
    fn parts<'a>(
        &'a mut self,
        mesh: &Mesh,
        density: f32,
    ) -> Result<(BodyParts<'a>, RefsMemory<'a>), Failure> {
        let grid = &mut self.grid;
        let parts = body_parts(mesh, &mut self.rim, density, |bytes| {
            grow(grid, bytes, 0, "the body")?;
            Ok(grid)
        })?;
        Ok((parts, RefsMemory(&mut self.refs)))
    }
}

/// The memory of a body's triangle references, to be sized once counted.
pub(crate) struct RefsMemory<'a>(&'a mut Vec<u8>);

impl<'a> RefsMemory<'a> {
    /// `bytes` of it (grown as needed).
    fn take(self, bytes: usize) -> Result<&'a mut [u8], Failure> {
        grow(self.0, bytes, 0, "the body's triangle references")?;
        Ok(self.0.as_mut_slice())
    }
}

/// The solid of `mesh`, its rim found in `rim_arena` (grown as needed; the
/// rim an earlier call left there is taken again while it still fits), its
/// grid of `density` cells per triangle in the memory `memory` gives for
/// the bytes it needs, and its triangle references, once counted, in the
/// memory `refs_memory` gives; built by layers over `thread_count` threads
/// (the same bits on any count), each stage reported to `progress`.
pub(crate) fn body_in<'a>(
    mesh: &Mesh,
    rim_arena: &mut Vec<u8>,
    density: f32,
    thread_count: u32,
    progress: Progress,
    memory: impl FnOnce(usize) -> Result<&'a mut [u8], Failure>,
    refs_memory: impl FnOnce(usize) -> Result<&'a mut [u8], Failure>,
) -> Result<Body<'a>, Failure> {
    progress.report(0.0)?;
    body_grid(
        body_parts(mesh, rim_arena, density, memory)?,
        thread_count,
        progress,
        refs_memory,
    )
}

/// The stages of [`body_in`] that run on one thread: the rim, the grid's
/// placement, the triangles copied.
fn body_parts<'a>(
    mesh: &Mesh,
    rim_arena: &mut Vec<u8>,
    density: f32,
    memory: impl FnOnce(usize) -> Result<&'a mut [u8], Failure>,
) -> Result<BodyParts<'a>, Failure> {
    grow(
        rim_arena,
        Rim::required_bytes(mesh),
        0,
        "the mesh's boundary loops",
    )?;
    let rim = Rim::refresh(mesh, &mut Arena::new(rim_arena))?;
    let plan = BodyPlan::with_density(mesh, &rim, density)?;
    Ok(Body::parts(
        &plan,
        mesh,
        &rim,
        &mut Arena::new(memory(plan.bytes())?),
    )?)
}

/// The stages of [`body_in`] split by layers over `thread_count` threads:
/// the grid's triangles counted, listed, the cells classified; the first
/// quarter of `progress` went to the stages before.
fn body_grid<'a>(
    parts: BodyParts<'a>,
    thread_count: u32,
    progress: Progress,
    refs_memory: impl FnOnce(usize) -> Result<&'a mut [u8], Failure>,
) -> Result<Body<'a>, Failure> {
    progress.report(0.25)?;
    let counted = counted(parts, thread_total(thread_count), true, refs_memory)?;
    progress.report(0.5)?;
    counted.body(progress)
}

/// A body grid with its triangles counted by layers, and the memory of its
/// references taken: what is left of it is split alike.
pub(crate) struct Counted<'a> {
    parts: BodyParts<'a>,
    /// The layers of each part of the split.
    ranges: Vec<Range<usize>>,
    /// Each part's cells.
    cells: Vec<usize>,
    /// Each part's references.
    totals: Vec<u64>,
    /// Stages run.
    listed: bool,
    classified: bool,
}

/// Counts the triangles of `parts`' grid in layers split for `threads`
/// threads, on as many threads or (`parallel` false) one after the other on
/// this one, and takes the references' memory from `refs_memory`.
fn counted<'a>(
    mut parts: BodyParts<'a>,
    threads: usize,
    parallel: bool,
    refs_memory: impl FnOnce(usize) -> Result<&'a mut [u8], Failure>,
) -> Result<Counted<'a>, Failure> {
    let (layers, per) = (parts.layers(), parts.layer_cells());
    let threads = threads.clamp(1, layers.max(1));
    let ranges: Vec<Range<usize>> = (0..threads)
        .map(|t| t * layers / threads..(t + 1) * layers / threads)
        .collect();
    let cells: Vec<usize> = ranges.iter().map(|l| l.len() * per).collect();
    let (grid, start, _, _) = parts.split();
    let work: Vec<_> = ranges
        .iter()
        .cloned()
        .zip(cut_into(start, &cells))
        .collect();
    let count = |(l, part): (Range<usize>, &mut [u32])| grid.count(l, part);
    let totals = run_parts_if(parallel, work, count)?;
    let total = totals.iter().sum();
    let refs = refs_memory(BodyParts::refs_bytes(total)?)?;
    parts.set_total(total, &mut Arena::new(refs))?;
    Ok(Counted {
        parts,
        ranges,
        cells,
        totals,
        listed: false,
        classified: false,
    })
}

/// [`run_parts`] when `parallel`, else each part in turn on this thread.
fn run_parts_if<P: Send, R: Send>(
    parallel: bool,
    parts: Vec<P>,
    work: impl Fn(P) -> R + Sync,
) -> Result<Vec<R>, Failure> {
    match parallel {
        true => run_parts(parts, work),
        false => Ok(parts.into_iter().map(work).collect()),
    }
}

/// A part of [`Counted::list`]'s work: its layers, its references' first
/// index, its cells' starts and its references.
type Listing<'p> = (Range<usize>, u32, &'p mut [u32], &'p mut [u32]);

impl<'a> Counted<'a> {
    /// Lists the grid's triangles, the parts of the split on as many
    /// threads or (`parallel` false) one after the other on this one.
    fn list(&mut self, parallel: bool) -> Result<(), Failure> {
        let (ranges, cells) = (&self.ranges, &self.cells);
        let (grid, start, refs, _) = self.parts.split();
        // each below the total, which set_total found below 2^32
        let bases = self.totals.iter().scan(0u32, |sum, &t| {
            let base = *sum;
            *sum += t as u32;
            Some(base)
        });
        let lists: Vec<usize> = self.totals.iter().map(|&t| t as usize).collect();
        let work: Vec<Listing> = ranges
            .iter()
            .cloned()
            .zip(bases)
            .zip(cut_into(start, cells))
            .zip(cut_into(refs, &lists))
            .map(|(((layers, base), start), refs)| (layers, base, start, refs))
            .collect();
        let fill = |(layers, base, start, refs): Listing| grid.fill(layers, base, start, refs);
        run_parts_if(parallel, work, fill)?;
        self.listed = true;
        Ok(())
    }

    /// Classifies the grid's cells (once [`list`](Self::list)ed), as
    /// [`list`](Self::list) splits its work.
    fn classify(&mut self, parallel: bool) -> Result<(), Failure> {
        debug_assert!(self.listed, "cells classified before their lists");
        let (ranges, cells) = (&self.ranges, &self.cells);
        let (grid, start, _, class) = self.parts.split();
        let start = &*start;
        let work: Vec<_> = ranges.iter().cloned().zip(cut_into(class, cells)).collect();
        let sweep = |(l, class): (Range<usize>, &mut [u8])| grid.classify(l, start, class);
        run_parts_if(parallel, work, sweep)?;
        self.classified = true;
        Ok(())
    }

    /// The body, its stages not run yet run on the split's threads (the
    /// last half of `progress`).
    fn body(mut self, progress: Progress) -> Result<Body<'a>, Failure> {
        if !self.listed {
            self.list(true)?;
        }
        progress.report(0.75)?;
        if !self.classified {
            self.classify(true)?;
        }
        progress.report(1.0)?;
        Ok(self.parts.finish())
    }
}

/// How far a step's body thread built the body while the guides bent: the
/// stages it did not run then run on every thread.
pub(crate) enum Built<'a> {
    /// The grid placed and its triangles copied.
    Placed(BodyParts<'a>, RefsMemory<'a>),
    /// Its triangles counted too, and maybe listed and classified.
    Counted(Counted<'a>),
}

impl<'a> Built<'a> {
    /// The body, its stages not run yet run over `thread_count` threads.
    pub(crate) fn body(self, thread_count: u32) -> Result<Body<'a>, Failure> {
        match self {
            Built::Placed(parts, refs) => {
                body_grid(parts, thread_count, Progress::none(), |bytes| {
                    refs.take(bytes)
                })
            }
            Built::Counted(counted) => counted.body(Progress::none()),
        }
    }
}
