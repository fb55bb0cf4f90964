//! Binding strands to guides.

use crate::buffers::{filled, opt_mut, req, req_mut, slice, slice_mut};
use crate::status::Failure;
use crate::threads::{pelage_run_defaults, split_over_threads, split_with_progress, PelageRun};
use crate::{PelageArena, PelageRestPose};
use crate::{PelageMeshDesc, PelageRegionMap, PelageRoot, PelageStatus};
use bytemuck::{Pod, Zeroable};
use pelage_core::interp::bind::{
    self, BindParams, GuideIndex, StrandBinding, MAX_NEIGHBOURS, WEIGHT_SUM_TOLERANCE,
};
use pelage_core::root::check_roots;
use pelage_core::{Arena, Root};

/// Most guides a strand can use.
pub const PELAGE_MAX_NEIGHBOURS: u32 = 8;

/// How far a bound strand's weights may sum from 1 (pelage_bind's sum to
/// within a few 1e-7).
pub const PELAGE_WEIGHT_SUM_TOLERANCE: f32 = 1e-4;

/// Binding parameters; start from pelage_bind_params_defaults().
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageBindParams {
    /// Fewest guides per strand when that many qualify (>= 1); strands with
    /// fewer eligible guides use those they have.
    pub min_neighbours: u32,
    /// Most guides per strand (<= PELAGE_MAX_NEIGHBOURS); equal to the minimum
    /// turns off the per-strand randomization.
    pub max_neighbours: u32,
    /// Seed of the per-strand neighbour count.
    pub seed: u64,
    /// Guides whose root normal dotted with the strand's is not above this are
    /// excluded (0: the paper's rule, exclude guides facing away; default 0.25).
    /// Within 0.25 above it a guide's weight fades, reaching 0 at the cutoff.
    pub min_normal_dot: f32,
    /// Search radius in units of the local guide spacing (the strand's
    /// distance to its third nearest eligible guide, at most 3 mean spacings).
    pub search_factor: f32,
    /// Excludes guides around a rim: either root below the other's tangent
    /// plane by more than this times their distance. Above half of it a
    /// guide's weight fades, reaching 0 at the cutoff.
    pub max_wrap_slope: f32,
    /// Parting regions (per-vertex ids or an id texture); kind NONE by default.
    pub regions: PelageRegionMap,
    /// Threads and progress (the share of strands bound); a cancelled call
    /// writes nothing. Defaults: 1 thread, no callback.
    pub run: PelageRun,
}

/// Guides and weights of one strand (the flat, Pod binding record; store it
/// with the roots as the groom's "root file").
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PelageStrandBinding {
    /// Guide indices; the first `count` are used.
    pub guides: [u32; 8],
    /// Weights of the first `count` guides, each in 0..1, summing to 1
    /// within PELAGE_WEIGHT_SUM_TOLERANCE (an orphan, count 0, has none);
    /// calls that take bindings refuse others with INVALID_ARGUMENT.
    pub weights: [f32; 8],
    /// Guides used; 0 for an orphan (no eligible guide).
    pub count: u32,
    /// Clump centre guide (nearest eligible), or 0xFFFFFFFF for orphans.
    pub clump: u32,
}

same_layout!(
    PelageStrandBinding,
    StrandBinding,
    guides,
    weights,
    count,
    clump
);
const _: () = assert!(MAX_NEIGHBOURS == PELAGE_MAX_NEIGHBOURS as usize);
const _: () = assert!(WEIGHT_SUM_TOLERANCE == PELAGE_WEIGHT_SUM_TOLERANCE);

/// What binding found.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PelageBindInfo {
    /// Strands with no eligible guide (grown straight along the normal).
    pub orphans: u32,
    /// Mean rest guide length (a good PelageExpandParams.orphan_length).
    pub mean_guide_length: f32,
    /// Mean guide spacing, sqrt(area / guides).
    pub mean_spacing: f32,
}

/// Default binding parameters: 3 to 6 neighbours, seed 0, min_normal_dot 0.25,
/// search_factor 2.5, max_wrap_slope 0.3, no regions, 1 thread.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_bind_params_defaults() -> PelageBindParams {
    let d = BindParams::default();
    PelageBindParams {
        min_neighbours: d.min_neighbours,
        max_neighbours: d.max_neighbours,
        seed: d.seed,
        min_normal_dot: d.min_normal_dot,
        search_factor: d.search_factor,
        max_wrap_slope: d.max_wrap_slope,
        regions: PelageRegionMap::none(),
        run: PelageRun {
            thread_count: 1,
            ..pelage_run_defaults()
        },
    }
}

/// Arena bytes pelage_bind needs for `rest_mesh` (validated) and
/// `guide_count` guides.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT, MISALIGNED, NON_FINITE,
/// OUT_OF_RANGE, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_bind_size(
    rest_mesh: *const PelageMeshDesc,
    guide_count: usize,
    arena_bytes: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let mesh = req(rest_mesh, "rest_mesh")?.view()?;
        let out = req_mut(arena_bytes, "arena_bytes")?;
        *out = bind::required_bytes(&mesh, guide_count)?;
        Ok(())
    }
}

/// Binds `strand_count` strands to guides on the rest pose (rest mesh, rest
/// guides): neighbour guides by root distance, excluding guides facing away,
/// of another parting region, or beyond the search radius; a randomized count
/// per strand; inverse-distance weights that fade to zero as a guide leaves
/// the set. Writes `strand_count` records to `bindings` and, optionally,
/// `info`. Nothing is written on failure. Strands are split over
/// `params->run.thread_count` threads; the bindings do not depend on it.
/// `params->run.progress`, when set, hears the share of strands bound and may
/// cancel; the bindings are then made in a buffer of the library's and
/// copied at the end, so a cancelled call writes nothing.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT, NON_FINITE, OUT_OF_RANGE,
/// CAPACITY_EXCEEDED (the arena or `bindings_capacity`), MISALIGNED,
/// CANCELLED, OUT_OF_MEMORY, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_bind(
    rest: *const PelageRestPose,
    strands: *const PelageRoot,
    strand_count: usize,
    params: *const PelageBindParams,
    arena: PelageArena,
    bindings: *mut PelageStrandBinding,
    bindings_capacity: usize,
    info: *mut PelageBindInfo,
) -> PelageStatus {
    ffi_boundary! {
        let (mesh, guides) = req(rest, "rest")?.view()?;
        let strands: &[Root] = bytemuck::cast_slice(slice(strands, strand_count, "strands")?);
        let p = req(params, "params")?;
        let regions = p.regions.view(mesh.positions.len())?;
        let core = BindParams {
            min_neighbours: p.min_neighbours,
            max_neighbours: p.max_neighbours,
            seed: p.seed,
            min_normal_dot: p.min_normal_dot,
            search_factor: p.search_factor,
            max_wrap_slope: p.max_wrap_slope,
            regions,
        };
        if bindings_capacity < strand_count {
            return Err(Failure::new(
                PelageStatus::CapacityExceeded,
                format!("bindings: {strand_count} needed, {bindings_capacity} available"),
            ));
        }
        let out: &mut [StrandBinding] = bytemuck::cast_slice_mut(slice_mut(bindings, strand_count, "bindings")?);
        let arena = arena.view("arena")?;
        // with progress the bindings are made aside, and written only when
        // every range is done: their memory is asked for before anything
        let mut made = match p.run.progress {
            Some(_) => filled(strand_count, StrandBinding::default(), "the bindings")?,
            None => Vec::new(),
        };
        let index = GuideIndex::new(&mesh, &guides, &core, &mut Arena::new(arena))?;
        // every strand is checked before any range writes
        check_roots(&mesh, strands, "strand roots")?;
        let work = |range: std::ops::Range<usize>, part: &mut [StrandBinding]| index.bind(&mesh, &strands[range], &core, part);
        let reports = if p.run.progress.is_none() {
            split_over_threads(strand_count, p.run.thread_count, out, 1, work)?
        } else {
            let reports = split_with_progress(strand_count, p.run.thread_count, &mut made, 1, p.run.progress(), work)?;
            if reports.iter().all(Result::is_ok) {
                out.copy_from_slice(&made);
            }
            reports
        };
        let mut report = index.report();
        for r in reports {
            report.merge(r?);
        }
        if let Some(info) = opt_mut(info) {
            *info = PelageBindInfo {
                orphans: report.orphans,
                mean_guide_length: report.mean_guide_length,
                mean_spacing: report.mean_spacing,
            };
        }
        Ok(())
    }
}
