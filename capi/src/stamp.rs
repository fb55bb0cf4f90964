//! Poisson stamping of hair roots.

use crate::buffers::{opt_mut, req, req_mut, slice_mut};
use crate::status::Failure;
use crate::threads::{pelage_run_defaults, PelageRun};
use crate::PelageArena;
use crate::{PelageMap, PelageMeshDesc, PelageRoot, PelageStatus};
use pelage_core::{stamp, Arena, Root, StampParams};

/// Stamping parameters; start from pelage_stamp_params_defaults().
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageStampParams {
    /// Number of roots wanted on the whole mesh (at most 2^28; unused when
    /// `radius` is set). The result is
    /// exactly this unless the mesh cannot hold that many at any spacing the
    /// correction reaches (then a little fewer).
    pub target_count: u32,
    /// Fixed disk radius (world units) instead of a count: 0 uses
    /// target_count; a positive value stamps at that spacing and keeps every
    /// root, so darker density maps give fewer roots (the paper's setting).
    pub radius: f32,
    /// Seed of every random choice; same inputs and seed give the same bits.
    pub seed: u64,
    /// Grayscale density in [0, 1], sampled at each triangle's centroid.
    pub density: PelageMap,
    /// Triangle scale for black, in [0.1, 1]; white is 1. The paper's
    /// "black = half size" is 0.5.
    pub black_scale: f32,
    /// Triangles with density below this get no roots (bald regions); 0 disables it.
    pub bald_below: f32,
    /// Progress, heard every few thousand triangles and after each stage;
    /// the last report, 1, comes before any root is written, and a
    /// cancelled stamp writes nothing. The stamp runs on the calling
    /// thread: `run.thread_count` is not read.
    pub run: PelageRun,
}

/// What a stamping call did.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PelageStampInfo {
    /// Disk radius: no two roots (on the same side of a surface) are closer,
    /// save by at most 0.1% across the bends of under 5 degrees that one
    /// piece of the stamp spans (measured: 1-3 pairs at 0.9998 of it in a
    /// million roots).
    pub radius: f32,
    /// Points taken from the stamp in the final pass.
    pub candidates: u32,
    /// Points removed by the edge pass in the final pass.
    pub pruned: u32,
    /// Surplus roots trimmed by LOD rank to land exactly on the target.
    pub trimmed: u32,
    /// Degenerate triangles skipped.
    pub degenerate_triangles: u32,
    /// Stamping passes (radius corrections + 1).
    pub passes: u32,
    /// Points the fill pass added where the edge pass left holes, in the
    /// final pass.
    pub filled: u32,
}

/// Default parameters: density constant 1, black_scale 0.5, bald_below 1/512,
/// seed 0, target_count 0, radius 0 (derived from the count), no progress
/// callback.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_stamp_params_defaults() -> PelageStampParams {
    let d = StampParams::default();
    PelageStampParams {
        target_count: d.target_count,
        radius: d.radius,
        seed: d.seed,
        density: PelageMap::constant(1.0),
        black_scale: d.black_scale,
        bald_below: d.bald_below,
        run: pelage_run_defaults(),
    }
}

fn core_params<'a>(
    mesh: &PelageMeshDesc,
    p: &'a PelageStampParams,
) -> Result<StampParams<'a>, Failure> {
    Ok(StampParams {
        target_count: p.target_count,
        radius: p.radius,
        seed: p.seed,
        density: p.density.view(mesh.vertex_count, "density map")?,
        black_scale: p.black_scale,
        bald_below: p.bald_below,
    })
}

/// Sizes a stamping call: the arena bytes `pelage_stamp` needs and an upper
/// bound on the roots it writes. Validates the mesh and parameters.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (parameters, density map,
/// strides, mesh values beyond 1e9), NON_FINITE, OUT_OF_RANGE, MISALIGNED,
/// PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_stamp_size(
    mesh: *const PelageMeshDesc,
    params: *const PelageStampParams,
    arena_bytes: *mut usize,
    max_roots: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let desc = req(mesh, "mesh")?;
        let params = req(params, "params")?;
        let arena_bytes = req_mut(arena_bytes, "arena_bytes")?;
        let max_roots = req_mut(max_roots, "max_roots")?;
        let mesh = desc.view()?;
        let p = core_params(desc, params)?;
        let bytes = stamp::required_bytes(&mesh, &p)?;
        let roots = stamp::max_roots(&mesh, &p)?;
        *arena_bytes = bytes;
        *max_roots = roots;
        Ok(())
    }
}

/// Stamps Poisson-distributed roots on `mesh` (paper section 2.3, without its
/// edge violations), in face order, each with a stable id (its index) and an LOD rank: the roots
/// with rank < k are an evenly spread subset of k roots. Several shells
/// keep their spacing; no root grows on buried skin (inside the body, its
/// holes capped).
///
/// `arena`: scratch memory of at least the size from `pelage_stamp_size`
/// (any alignment). `roots`: capacity `roots_capacity`;
/// the max_roots bound from the query (the target count) always suffices. On success
/// `*root_count` is the number written and `info` (optional, may be NULL) is
/// filled. On PELAGE_STATUS_CAPACITY_EXCEEDED, `*root_count` holds the number
/// of roots needed when the root buffer was the limit; nothing else is written.
/// `params->run.progress`, when set, reports progress and can cancel the call
/// (PELAGE_STATUS_CANCELLED, nothing written).
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT, NON_FINITE, OUT_OF_RANGE,
/// CAPACITY_EXCEEDED (the arena, or `roots_capacity`), MISALIGNED,
/// CANCELLED, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_stamp(
    mesh: *const PelageMeshDesc,
    params: *const PelageStampParams,
    arena: PelageArena,
    roots: *mut PelageRoot,
    roots_capacity: usize,
    root_count: *mut usize,
    info: *mut PelageStampInfo,
) -> PelageStatus {
    ffi_boundary! {
        let desc = req(mesh, "mesh")?;
        let params = req(params, "params")?;
        let root_count = req_mut(root_count, "root_count")?;
        let mesh = desc.view()?;
        let p = core_params(desc, params)?;
        let arena = arena.view("arena")?;
        let out = slice_mut(roots, roots_capacity, "roots")?;
        let out: &mut [Root] = bytemuck::cast_slice_mut(out);
        // the arena is checked here so that CAPACITY_EXCEEDED from the core
        // can only mean the root buffer, whose needed size is reported
        let need = stamp::required_bytes(&mesh, &p)?;
        if arena.len() < need {
            return Err(Failure::new(
                PelageStatus::CapacityExceeded,
                format!("arena too small: {need} bytes needed, {} available", arena.len()),
            ));
        }
        let run = params.run.progress();
        let mut progress = |fraction: f32| run.report(fraction as f64).is_ok();
        match stamp::stamp_with_progress(mesh, &p, &mut Arena::new(arena), out, &mut progress) {
            Ok((n, report)) => {
                *root_count = n;
                if let Some(info) = opt_mut(info) {
                    *info = PelageStampInfo {
                        radius: report.radius,
                        candidates: report.candidates,
                        pruned: report.pruned,
                        trimmed: report.trimmed,
                        degenerate_triangles: report.degenerate_triangles,
                        passes: report.passes,
                        filled: report.filled,
                    };
                }
                Ok(())
            }
            Err(e @ pelage_core::Error::OutputTooSmall { needed, .. }) => {
                *root_count = needed;
                Err(Failure::from(e))
            }
            Err(e) => Err(Failure::from(e)),
        }
    }
}
