//! The simulation handle: guide dynamics across frames (paper 3).

use crate::body::BodyMemory;
use crate::buffers::{
    bytes, bytes_mut, grow, opt_mut, req, req_mut, slice_mut, strided, Float3Out,
};
use crate::colliders::HostColliders;
use crate::frame::Frame;
use crate::handles::{free, into_handle, object, object_mut, Handle};
use crate::status::Failure;
use crate::threads::{
    beside, pelage_run_defaults, split_in_chunks, split_pairs_in_chunks, split_with_progress,
    thread_total, PelageRun, Progress,
};
use crate::{PelageArena, PelageRestPose};
use crate::{PelageColliders, PelageFrame, PelageMap, PelageMeshDesc, PelageStatus};
use pelage_core::arena::ArenaLayout;
use pelage_core::collide::COLLISION_CELLS_PER_TRIANGLE;
use pelage_core::dynamics::ik::IkParams;
use pelage_core::dynamics::links::LinkParams;
use pelage_core::dynamics::sim::{PosedFaults, Sim, SimParams, Step, KEPT_FLOATS};
use pelage_core::interp::posed::PosedFrame;
use pelage_core::{Arena, Strided};
use std::ffi::c_void;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The opaque object a `PelageSim` points to.
// not repr(C): cbindgen declares it in C without a definition
pub struct PelageSimTy {
    _private: [u8; 0],
}

/// Simulated guides: the state of the tip springs across frames, the rest
/// shapes, the tip links. Created by `pelage_sim_new` in memory the host
/// provides (sized by `pelage_sim_size`), stepped frame by frame by
/// `pelage_sim_step`, read by `pelage_sim_read`; saved and restored as
/// bytes; released by `pelage_sim_free`.
pub type PelageSim = *mut PelageSimTy;

/// Simulation parameters; start from pelage_sim_params_defaults().
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageSimParams {
    /// Joints per guide (2..64): the guides are resampled to it.
    pub joints: u32,
    /// Points per posed guide (2..64): a Catmull-Rom curve through the
    /// joints, resampled; equal to `joints`, the joints themselves.
    pub points_per_guide: u32,
    /// Tip spring natural frequency in hertz (0..1000), per guide at its root.
    pub frequency: PelageMap,
    /// Share of the spring's lag the tip shows (0: the neutral pose, 1: the
    /// full lag), per guide.
    pub amplitude: PelageMap,
    /// Exponential decay rate of the swing in 1/s (0..10000), per guide.
    pub decay: PelageMap,
    /// IK stops when the tip is this share of the guide's length from its
    /// target (0..1).
    pub ik_tolerance: f32,
    /// Most IK sweeps per step (1..256).
    pub ik_max_iterations: u32,
    /// Stiffness of the root joint (0 <= s < 1): the share of its turn a
    /// joint does not take per sweep. Root 0 and tip 0 is pure CCD, which
    /// bends the tip first; a stiff tip moves the bend toward the root.
    pub root_stiffness: f32,
    /// Stiffness of the last joint; the joints between go linearly.
    pub tip_stiffness: f32,
    /// Tips closer than this at rest may be linked (world units; 0: none).
    pub link_radius: f32,
    /// Most links a tip makes to its nearest tips (0..16).
    pub max_links: u32,
    /// Link relaxations per step (0..16).
    pub link_iterations: u32,
    /// Share of its links' mean correction a tip takes per relaxation (0..1).
    pub link_stiffness: f32,
    /// A step whose roots move, on average, more than this many times the
    /// extent of the roots (the diagonal of their bounding box) is a cut:
    /// each guide's swing is carried along rigidly with its root frame and
    /// the body starts from rest in its new place (> 0; default 1, which
    /// no spin about an axis through the body reaches).
    pub teleport: f32,
    /// Where another simulator takes over (0..1 per guide at its root): the
    /// share of the host's curves (pelage_sim_step's `external_points`) in
    /// the posed guide; a map that fades blends across the region's border.
    /// Default constant 0: pelage's dynamics everywhere.
    pub external: PelageMap,
}

/// Defaults: 16 joints and points, frequency 1.5 Hz, amplitude 1, decay
/// 3/s, IK tolerance 1e-2 (of the guide length) with 8 sweeps, stiffness 0 at the root and 0.9
/// at the tip, no links (radius 0; 4 links, 2 relaxations, stiffness 0.5
/// once a radius is set), teleport at 1 (the roots' extent).
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_sim_params_defaults() -> PelageSimParams {
    let d = SimParams::default();
    let constant = |m: &pelage_core::ScalarMap| match m {
        pelage_core::ScalarMap::Constant(c) => PelageMap::constant(*c),
        _ => PelageMap::constant(0.0),
    };
    PelageSimParams {
        joints: d.joints as u32,
        points_per_guide: d.points as u32,
        frequency: constant(&d.frequency),
        amplitude: constant(&d.amplitude),
        decay: constant(&d.decay),
        ik_tolerance: d.ik.tolerance,
        ik_max_iterations: d.ik.max_iterations,
        root_stiffness: d.ik.root_stiffness,
        tip_stiffness: d.ik.tip_stiffness,
        link_radius: d.links.radius,
        max_links: d.links.max_links,
        link_iterations: d.links.iterations,
        link_stiffness: d.links.stiffness,
        teleport: d.teleport,
        external: constant(&d.external),
    }
}

fn core_params<'a>(p: &'a PelageSimParams, vertex_count: usize) -> Result<SimParams<'a>, Failure> {
    let params = SimParams {
        joints: p.joints as usize,
        points: p.points_per_guide as usize,
        frequency: p.frequency.view(vertex_count, "frequency map")?,
        amplitude: p.amplitude.view(vertex_count, "amplitude map")?,
        decay: p.decay.view(vertex_count, "decay map")?,
        ik: IkParams {
            tolerance: p.ik_tolerance,
            max_iterations: p.ik_max_iterations,
            root_stiffness: p.root_stiffness,
            tip_stiffness: p.tip_stiffness,
        },
        links: LinkParams {
            radius: p.link_radius,
            max_links: p.max_links,
            iterations: p.link_iterations,
            stiffness: p.link_stiffness,
        },
        teleport: p.teleport,
        external: p.external.view(vertex_count, "external map")?,
    };
    params.check()?;
    Ok(params)
}

impl Handle for PelageSimTy {
    type Object = SimBox;
    const NAME: &'static str = "sim";
}

/// What a [`PelageSim`] points to.
pub(crate) struct SimBox {
    /// Lives in the host's memory, which outlives the handle (the header's
    /// contract).
    pub(crate) sim: Sim<'static>,
    /// The body of the last step that collided with the body.
    body: BodyMemory,
    /// Each guide's state before a step that builds its body beside the
    /// guides (to take that step back).
    kept: Vec<f32>,
    /// That step's guide curves before the push-out.
    shaped: Vec<f32>,
    /// Every block before a step with a host field (to take it back whole
    /// when the field gives a NaN).
    whole: Vec<f32>,
}

/// Memory bytes pelage_sim_new needs for `guide_count` guides on
/// `rest_mesh` with `params`.
///
/// Returns OK, NULL_PARAMETER, NON_FINITE (a parameter), INVALID_ARGUMENT
/// (also a guide count of 0 or of u32::MAX and above), MISALIGNED, PANIC.
/// The mesh's and the maps' values are not read: pelage_sim_new checks
/// them.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_sim_size(
    rest_mesh: *const PelageMeshDesc,
    guide_count: usize,
    params: *const PelageSimParams,
    memory_bytes: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let mesh = req(rest_mesh, "rest_mesh")?.view()?;
        let p = core_params(req(params, "params")?, mesh.positions.len())?;
        let out = req_mut(memory_bytes, "memory_bytes")?;
        PosedFrame::check_sizes(guide_count, p.joints)?;
        let mut layout = ArenaLayout::new();
        Sim::layout(&mut layout, mesh.positions.len(), guide_count, &p);
        *out = layout.bytes();
        Ok(())
    }
}

/// Creates a simulation of `rest->guides` on `rest->mesh` (both at rest:
/// the guides' shapes in their root frames are their neutral pose) in the
/// host's `memory` (`memory.bytes` from pelage_sim_size, any alignment),
/// which must stay valid and untouched until pelage_sim_free. The maps are
/// sampled at the guide roots; tips within `link_radius` are linked. Every
/// guide starts at its neutral pose. On failure `*out_sim` is untouched.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (a parameter, or a map
/// value out of its range at some guide), NON_FINITE, OUT_OF_RANGE,
/// CAPACITY_EXCEEDED (the memory), MISALIGNED, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_sim_new(
    rest: *const PelageRestPose,
    params: *const PelageSimParams,
    memory: PelageArena,
    out_sim: *mut PelageSim,
) -> PelageStatus {
    ffi_boundary! {
        let out = req_mut(out_sim, "out_sim")?;
        let (mesh, guides) = req(rest, "rest")?.view()?;
        let p = core_params(req(params, "params")?, mesh.positions.len())?;
        // the memory outlives the handle (the header's contract), so the
        // simulation may borrow it for as long as the handle lives
        let memory: &'static mut [u8] = memory.view("memory")?;
        // the rest mesh is read only while the simulation is made: the
        // guides' rest shapes and roots are copied into its memory
        let sim = Sim::new(mesh, &guides, &p, &mut Arena::new(memory))?;
        *out = into_handle(Box::new(SimBox { sim, body: BodyMemory::default(), kept: Vec::new(), shaped: Vec::new(), whole: Vec::new() }));
        Ok(())
    }
}

/// Releases a simulation (its memory is the host's again). NULL is
/// accepted and does nothing.
///
/// Thread safety: frees `sim`.
#[no_mangle]
pub extern "C" fn pelage_sim_free(sim: PelageSim) {
    free(sim);
}

/// What one step of a simulation takes besides the simulation and the
/// frame; start from pelage_step_params_defaults().
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageStepParams {
    /// Seconds since the last step (1e-5 <= dt <= 1; it may change from
    /// step to step).
    pub dt: f32,
    /// What the guides collide with (NULL: nothing).
    pub colliders: *const PelageColliders,
    /// Another simulator's curves (NULL: none): float3 points, relative to
    /// the frame's origin, `external_stride` bytes apart, points_per_guide
    /// per guide; the
    /// guides the simulation's `external` map selects take their shape
    /// from them (blended, lengths kept).
    pub external_points: *const c_void,
    /// Bytes between consecutive external points (>= 12, a multiple of 4).
    pub external_stride: usize,
    /// Threads and progress, heard before the step and after each of its
    /// phases (the advance, each link relaxation, the bend and push-out);
    /// a cancelled step is taken back. Defaults: every core, no callback.
    pub run: PelageRun,
}

/// Defaults: dt 1/24, all cores, no colliders, no external curves, no
/// progress callback.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_step_params_defaults() -> PelageStepParams {
    PelageStepParams {
        dt: 1.0 / 24.0,
        colliders: std::ptr::null(),
        external_points: std::ptr::null(),
        external_stride: 12,
        run: pelage_run_defaults(),
    }
}

/// What a step reports.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PelageStepInfo {
    /// Guides left in their groomed shape (pushed out as far as it goes):
    /// no tried rotation freed their bent curve from a collider (a crease,
    /// a landing), or their bend overflowed near the coordinate limit.
    pub groomed_guides: usize,
}

/// Advances the simulation by `params->dt` seconds to `frame` (this
/// frame's deformed mesh; its guides are not read, nor its colliders:
/// the step collides with `params->colliders` only, and takes from the
/// frame only the body it built, below). Per guide: the neutral pose (the
/// rest shape carried by the root frame), the tip spring, the tip links,
/// CCD IK, the Catmull-Rom curve, the push-out. The body collider
/// (`colliders->body`) is the frame's mesh: the body
/// `pelage_frame_set_colliders` built for the frame when it has one (the
/// same solid, built once per frame), else built here, every step: on
/// several threads, beside the guides' advance, links and IK (the body's
/// stages that run on one thread run on one while the guides bend on the
/// others), so the body costs less than built first; a body that cannot
/// be built then (no triangle with area, memory) takes the step back, and
/// the state is unchanged, as when it is built first. A root whose
/// triangle has collapsed in the frame (zero area, no vertex normals) has
/// no frame there (every axis zero): its guide collapses onto the root for
/// that step, as render hairs expanded there do, and comes back with the
/// triangle. The state is carried to the frame's origin
/// (pelage_frame_set_origin) from the last step's by their difference in
/// double precision, so a character followed by its origin simulates as it
/// would at the world's origin. Everything is checked first; when a check
/// fails the state is unchanged. `info` (optional, NULL to skip) gets what the step reports.
/// PANIC (a worker thread that could not start, or a panic) can leave the
/// step half made: reset or restore the simulation before stepping again.
///
/// Returns OK, NULL_PARAMETER, NON_FINITE (dt, a collider's value, an
/// external point where the `external` map is above 0; a NaN from the
/// distance callback, and the step is taken back), INVALID_ARGUMENT (dt
/// out of range, a collider, a frame of another mesh, the body grid too
/// large, a body of a frame without a triangle of area, the external
/// curves' count or stride, an external point beyond 1e9 where the
/// `external` map is above 0), CANCELLED (the step is taken back),
/// MISALIGNED, OUT_OF_MEMORY, PANIC.
///
/// Thread safety: writes `sim`; reads `frame`.
#[no_mangle]
pub extern "C" fn pelage_sim_step(
    sim: PelageSim,
    frame: PelageFrame,
    params: *const PelageStepParams,
    info: *mut PelageStepInfo,
) -> PelageStatus {
    ffi_boundary! {
        let sim = object_mut(sim)?;
        let frame = object(frame)?;
        let p = req(params, "params")?;
        let host = HostColliders::read(p.colliders)?;
        let external = match p.external_points.is_null() {
            true => None,
            false => Some(strided::<[f32; 3]>(p.external_points, p.external_stride, sim.sim.len() * sim.sim.points(), "params.external_points")?),
        };
        let progress = p.run.progress();
        // a NaN from the host's field or a cancel fails the step after it
        // moved the guides: the state before it is kept to put back
        let whole = host.field.is_some() || progress.is_set();
        if whole {
            let blocks = sim.sim.blocks();
            grow(&mut sim.whole, blocks.len(), 0.0, "the state kept through a step")?;
            sim.whole[..blocks.len()].copy_from_slice(blocks);
        }
        let mark = sim.sim.mark();
        let done = step(sim, frame, &host, external, p, &progress)
            .and_then(|groomed| host.check_field().map(|()| groomed));
        match done {
            Ok(groomed) => {
                if let Some(info) = opt_mut(info) {
                    *info = PelageStepInfo { groomed_guides: groomed };
                }
                Ok(())
            }
            Err(failure) => {
                if whole {
                    let n = sim.sim.blocks().len();
                    sim.sim.put_back(&sim.whole[..n], mark);
                }
                Err(failure)
            }
        }
    }
}

/// [`pelage_sim_step`] with its inputs read: the guides it left in their
/// groomed shape.
fn step(
    sim: &mut SimBox,
    frame: &Frame,
    host: &HostColliders,
    external: Option<Strided<[f32; 3]>>,
    p: &PelageStepParams,
    progress: &Progress,
) -> Result<usize, Failure> {
    let (dt, thread_count) = (p.dt, p.run.thread_count);
    if host.body && frame.body().is_none() && thread_total(thread_count) > 1 {
        return step_beside_body(sim, frame.posed(), host, external, p, progress);
    }
    // the frame's own body, when its colliders have one, is this mesh's:
    // built once per frame, shared with the render strands' push-out
    let built;
    let body = match (host.body, frame.body()) {
        (false, _) => None,
        (true, Some(body)) => Some(body),
        (true, None) => {
            // a bad input is reported before a body that cannot be
            // built, as on several threads
            sim.sim
                .check_step(frame.posed(), &host.colliders(None), external, dt)?;
            built = sim.body.body(
                frame.posed().mesh(),
                COLLISION_CELLS_PER_TRIANGLE,
                thread_count,
                Progress::none(),
            )?;
            Some(&built)
        }
    };
    let colliders = host.colliders(body);
    let Step {
        context,
        blocks,
        snapshot,
    } = sim.sim.begin(frame.posed(), &colliders, external, dt)?;
    let (n, per) = (snapshot.len(), context.block_floats());
    let phases = Phases::new(progress, context.link_iterations())?;
    context.bend(blocks, snapshot, |blocks, phase| {
        split_in_chunks(n, thread_count, blocks, per, |range, part| {
            phase(range.start, part)
        })?;
        phases.done()
    })?;
    let groomed = AtomicUsize::new(0);
    split_in_chunks(n, thread_count, &mut *blocks, per, |range, part| {
        groomed.fetch_add(context.finish(range.start, part), Ordering::Relaxed);
    })?;
    phases.done()?;
    Ok(groomed.into_inner())
}

/// A step's phases as the host hears of them: before the first, and after
/// each (the advance, each link relaxation, the bend and push-out).
struct Phases<'p> {
    progress: &'p Progress,
    total: u32,
    done: std::cell::Cell<u32>,
}

impl<'p> Phases<'p> {
    /// Reports the start of a step of `relaxations` link relaxations.
    fn new(progress: &'p Progress, relaxations: u32) -> Result<Self, Failure> {
        progress.report(0.0)?;
        Ok(Phases {
            progress,
            total: relaxations + 2,
            done: std::cell::Cell::new(0),
        })
    }

    /// Reports one more phase done; CANCELLED when the host says so.
    fn done(&self) -> Result<(), Failure> {
        self.done.set(self.done.get() + 1);
        self.progress
            .report(f64::from(self.done.get()) / f64::from(self.total))
    }
}

/// A step on several threads that builds its own body collider: the
/// body's stages that run on one thread (rim, placement, copies; then,
/// while the guides still bend, the counts, lists and classes) run beside
/// the guides' advance, links and IK on the other threads; the rest of the
/// grid is then built over every thread, and the guides pushed out. The
/// bits are those of building the body first. A failure once the guides
/// have moved and before the push-out (the body refused, memory, a
/// spawned thread that could not start or panicked) takes the step back,
/// so the simulation is as it was.
fn step_beside_body(
    sim: &mut SimBox,
    frame: &PosedFrame,
    host: &HostColliders,
    external: Option<Strided<[f32; 3]>>,
    p: &PelageStepParams,
    progress: &Progress,
) -> Result<usize, Failure> {
    let (dt, thread_count) = (p.dt, p.run.thread_count);
    let SimBox {
        sim,
        body: memory,
        kept,
        shaped,
        ..
    } = sim;
    let (n, m) = (sim.len(), sim.points());
    grow(kept, n * KEPT_FLOATS, 0.0, "the state kept through a step")?;
    grow(
        shaped,
        n * 3 * m,
        0.0,
        "the guides' curves before the push-out",
    )?;
    let mark = sim.mark();
    let shapes = host.colliders(None);
    let Step {
        context,
        blocks,
        snapshot,
    } = sim.begin(frame, &shapes, external, dt)?;
    let per = context.block_floats();
    context.keep(blocks, kept);
    let threads = thread_total(thread_count);
    let guide_threads = threads as u32 - 1;
    let bending = AtomicBool::new(true);
    let built = beside(
        || {
            memory.beside(
                frame.mesh(),
                COLLISION_CELLS_PER_TRIANGLE,
                threads,
                &bending,
            )
        },
        || -> Result<(), Failure> {
            let phases = Phases::new(progress, context.link_iterations())?;
            context.bend(blocks, snapshot, |blocks, phase| {
                split_in_chunks(n, guide_threads, blocks, per, |range, part| {
                    phase(range.start, part)
                })?;
                phases.done()
            })?;
            let shaped = split_pairs_in_chunks(
                n,
                guide_threads,
                blocks,
                per,
                shaped,
                3 * m,
                |range, part, out| context.shape(range.start, part, out),
            );
            bending.store(false, Ordering::Relaxed);
            shaped
        },
    )
    .and_then(|(built, bent)| {
        bent?;
        built?.body(thread_count)
    });
    let body = match built {
        Ok(body) => body,
        Err(failure) => {
            sim.undo(kept, mark);
            return Err(failure);
        }
    };
    let shaped = &*shaped;
    let groomed = AtomicUsize::new(0);
    // a thread that cannot start here leaves the step half made (PANIC)
    split_in_chunks(n, thread_count, blocks, per, |range, part| {
        let mine = &shaped[range.start * 3 * m..range.end * 3 * m];
        let count = context.collide(range.start, part, mine, Some(&body));
        groomed.fetch_add(count, Ordering::Relaxed);
    })?;
    // the last phase's report: a cancel here is taken back by the caller
    progress.report(1.0)?;
    Ok(groomed.into_inner())
}

// a frame's guides from the simulation: here, above both objects
/// Poses `frame`'s guides with `sim`'s posed guides of the last step,
/// without copying them out: the bits and the statuses of pelage_sim_read
/// then pelage_frame_set_guides (with the simulation's roots), in less
/// time. The frame must be of the simulation's mesh (its counts) with the
/// simulation's points_per_guide points per strand, made for as many
/// guides as the simulation has, with the origin of the frame the
/// simulation last stepped on (pelage_sim_origin: set the frame's origin
/// first; pelage_frame_set_origin only relabels a frame, it moves nothing
/// already in it); `sim` must have stepped since it was created, reset or
/// restored (after a PANIC from pelage_sim_step, reset or restore it
/// first: a half-made step is not refused here). Runs as
/// `run` says (progress: the share of guides posed). The guides are
/// checked as they are written: when one is refused or the call is
/// cancelled, the frame has no guides (expansions from it are refused)
/// until guides are set again; when the frame or the simulation is refused
/// (the counts, the origin, no step yet), the frame keeps the guides it had.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (another mesh's counts,
/// another point or guide count, another origin, no step yet; a simulated guide with a
/// point beyond 1e9 or of zero length, on a collapsed root triangle, as
/// pelage_frame_set_guides refuses them), NON_FINITE (only after a failed
/// step), CANCELLED, PANIC (also when a worker thread cannot start: the
/// frame then has no guides until guides are set again).
///
/// Thread safety: writes `frame`; reads `sim`.
#[no_mangle]
pub extern "C" fn pelage_frame_set_sim_guides(
    frame: PelageFrame,
    sim: PelageSim,
    run: PelageRun,
) -> PelageStatus {
    ffi_boundary! {
        let frame = object_mut(frame)?;
        let sim = &object(sim)?.sim;
        let posing = sim.posing(frame.posed_mut())?;
        let filler = posing.filler;
        let per = filler.floats_per_guide();
        let faults = split_with_progress(sim.len(), run.thread_count, &mut *posing.data, per, run.progress(), |range, part| {
            filler.fill(range.start, part);
            sim.posed_faults(range)
        })?;
        posing.finish_checked(faults.into_iter().fold(PosedFaults::default(), PosedFaults::then))?;
        Ok(())
    }
}

/// Writes the posed guides of the last step, or of the step a restored
/// state was saved after, relative to pelage_sim_origin: `points_per_guide`
/// float3 per guide, guide after guide, `point_stride` bytes apart (>= 12,
/// a multiple of 4), capacity `point_capacity` points. Hand them to
/// pelage_frame_set_guides (with the simulated guides' roots, on a frame
/// of the same origin) to expand render hairs from them.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (stride; no posed guides:
/// no step since pelage_sim_new or pelage_sim_reset, or a state restored
/// that was saved before any step), CAPACITY_EXCEEDED, MISALIGNED, PANIC.
///
/// Thread safety: reads `sim`.
#[no_mangle]
pub extern "C" fn pelage_sim_read(
    sim: PelageSim,
    points: *mut c_void,
    point_stride: usize,
    point_capacity: usize,
) -> PelageStatus {
    ffi_boundary! {
        let sim = &object(sim)?.sim;
        if !sim.has_stepped() {
            return Err(Failure::new(PelageStatus::InvalidArgument, "the simulation has no posed guides: it has not stepped since it was made or reset, or its restored state was saved before any step"));
        }
        let (n, m) = (sim.len(), sim.points());
        let needed = n * m;
        if point_capacity < needed {
            return Err(Failure::new(PelageStatus::CapacityExceeded, format!("points: {needed} needed, {point_capacity} available")));
        }
        if points.is_null() {
            return Err(Failure::new(PelageStatus::NullParameter, "points is NULL"));
        }
        if let Some(mut out) = Float3Out::new(points, point_stride, needed, "points")? {
            for g in 0..n {
                let frame = sim.root_frame(g);
                for k in 0..m {
                    out.set(g * m + k, frame.to_world(sim.posed_local(g, k)).to_array());
                }
            }
        }
        Ok(())
    }
}

/// Writes the origin the simulation's state and posed guides are relative
/// to, 3 doubles: that of the frame it last stepped on (see
/// pelage_frame_set_origin), or of the step a restored state was saved
/// after; zero before any step and after pelage_sim_reset.
///
/// Returns OK, NULL_PARAMETER, MISALIGNED, PANIC.
///
/// Thread safety: reads `sim`.
#[no_mangle]
pub extern "C" fn pelage_sim_origin(sim: PelageSim, origin: *mut f64) -> PelageStatus {
    ffi_boundary! {
        let sim = &object(sim)?.sim;
        slice_mut(origin, 3, "origin")?.copy_from_slice(&sim.origin());
        Ok(())
    }
}

/// Forgets the motion: the next step starts every guide from its neutral
/// pose (a cut, the start of a shot).
///
/// Returns OK, NULL_PARAMETER, PANIC.
///
/// Thread safety: writes `sim`.
#[no_mangle]
pub extern "C" fn pelage_sim_reset(sim: PelageSim) -> PelageStatus {
    ffi_boundary! {
        object_mut(sim)?.sim.reset();
        Ok(())
    }
}

/// Writes the bytes pelage_sim_save needs to `*bytes`.
///
/// Returns OK, NULL_PARAMETER, PANIC.
///
/// Thread safety: reads `sim`.
#[no_mangle]
pub extern "C" fn pelage_sim_state_size(sim: PelageSim, bytes: *mut usize) -> PelageStatus {
    ffi_boundary! {
        let size = object(sim)?.sim.state_bytes();
        *req_mut(bytes, "bytes")? = size;
        Ok(())
    }
}

/// Saves the simulation's state (docs/FORMAT.md: the file framing, magic
/// "PLGSTATE", every guide's state and posed points, a fingerprint of the
/// parameters and rest guides, a CRC-32) to `out` (capacity `capacity`
/// bytes), so that a farm task can restore it, read the saved step's
/// guides and go on with the same bits as an uninterrupted run.
/// `*written` gets the size.
///
/// Returns OK, NULL_PARAMETER, CAPACITY_EXCEEDED (the needed size is in
/// `*written`), PANIC.
///
/// Thread safety: reads `sim`.
#[no_mangle]
pub extern "C" fn pelage_sim_save(
    sim: PelageSim,
    out: *mut c_void,
    capacity: usize,
    written: *mut usize,
) -> PelageStatus {
    ffi_boundary! {
        let sim = &object(sim)?.sim;
        let written = req_mut(written, "written")?;
        let needed = sim.state_bytes();
        if capacity < needed {
            *written = needed;
            return Err(Failure::new(PelageStatus::CapacityExceeded, format!("state: {needed} bytes needed, {capacity} available")));
        }
        let out = bytes_mut(out, needed, "out")?;
        *written = sim.save(out)?;
        Ok(())
    }
}

/// Restores a state pelage_sim_save wrote, for a simulation made from the
/// same rest mesh's guides, maps and parameters (the state's fingerprint
/// of them must match). Everything is checked first (framing, checksum,
/// counts, fingerprint, values); on failure nothing changes. Afterwards
/// pelage_sim_read gives the posed guides of the step saved, and
/// pelage_sim_origin the origin they are relative to.
///
/// Returns OK, NULL_PARAMETER, CORRUPT_DATA (truncated, checksum, values),
/// VERSION_MISMATCH (magic or format version; 0.11's states are version
/// 1), INVALID_ARGUMENT (another guide count, other rest guides, roots,
/// maps or parameters), PANIC.
///
/// Thread safety: writes `sim`.
#[no_mangle]
pub extern "C" fn pelage_sim_restore(
    sim: PelageSim,
    data: *const c_void,
    data_bytes: usize,
) -> PelageStatus {
    ffi_boundary! {
        let sim = object_mut(sim)?;
        sim.sim.restore(bytes(data, data_bytes, "data")?)?;
        Ok(())
    }
}
