//! The simulation: guides' state across steps, and one step (paper 3.1).
//!
//! Per guide and step: (1) the neutral configuration, the guide's rest
//! shape carried by its root frame on the step's mesh; (2) the tip spring
//! toward the neutral tip; the tip links relax the spring targets;
//! (3) CCD IK bends the guide toward its target; (4) a Catmull-Rom curve
//! through the joints, resampled; then the push-out from the colliders.
//!
//! [`Sim::begin`] checks a step's inputs and hands its phases
//! ([`super::step`]) to the host, which splits them over threads;
//! [`Sim::step`] runs them on one. [`StepContext::keep`] and
//! [`Sim::undo`] take back a step that cannot finish. The state carried
//! from step to step ([`super::state`]) is saved to and restored from bytes
//! ([`Sim::save`], [`Sim::restore`]).

use super::links::Links;
use super::params::GuideConstants;
use super::spring::TipSpring;
use super::state::{
    posed, read_state, state, state_file_bytes, write_state, Fingerprint, StateHeader,
};
use crate::arena::{Arena, ArenaLayout};
use crate::collide::Colliders;
use crate::guides::Guides;
use crate::interp::posed::{GuidePoints, PosedFrame, Posing};
use crate::surface::frame::Frame;
use crate::surface::map::ScalarMap;
use crate::{Error, Mesh, Root, Strided};
use core::ops::Range;
use glam::Vec3;

pub use super::params::{SimParams, MAX_JOINTS, MIN_DT};
pub use super::state::{GuideState, KEPT_FLOATS, STATE_VERSION};
pub use super::step::{Step, StepContext};

/// Simulated guides.
pub struct Sim<'a> {
    pub(super) params: SimParams<'static>,
    pub(super) roots: &'a [Root],
    /// Rest joints in their root frames, 3 floats each.
    pub(super) rest: &'a [f32],
    /// Segment lengths, `joints - 1` per guide.
    pub(super) lengths: &'a [f32],
    pub(super) constants: &'a [GuideConstants],
    pub(super) links: Links<'a>,
    pub(super) blocks: &'a mut [f32],
    pub(super) snapshot: &'a mut [[f32; 3]],
    /// The rest mesh's triangle and vertex counts, which every frame's has.
    pub(super) topology: (usize, usize),
    /// A step has begun since the simulation was made, reset or restored:
    /// there are posed guides to read.
    pub(super) stepped: bool,
    /// Of the parameters, roots, rest guides and per-guide constants: a
    /// saved state restores only into a simulation with the same.
    pub(super) fingerprint: u64,
    /// The origin of the frame of the last step: the state's positions are
    /// relative to it (see [`PosedFrame::set_origin`]).
    pub(super) origin: [f64; 3],
}

/// What a host keeps before a step to take it back ([`Sim::undo`],
/// [`Sim::put_back`]): whether a step had run, and the origin the state
/// was relative to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepMark {
    stepped: bool,
    origin: [f64; 3],
}

impl<'a> Sim<'a> {
    /// Floats each guide's block takes.
    fn block_floats(params: &SimParams) -> usize {
        KEPT_FLOATS + 3 * params.points
    }

    /// Adds the arena bytes [`Sim::new`] needs for `guides` guides on a
    /// rest mesh of `vertices` vertices.
    pub fn layout(layout: &mut ArenaLayout, vertices: usize, guides: usize, params: &SimParams) {
        PosedFrame::layout(layout, vertices, guides, params.joints);
        layout.add::<Root>(guides);
        layout.add::<f32>(guides.saturating_mul(3 * params.joints));
        layout.add::<f32>(guides.saturating_mul(params.joints.saturating_sub(1)));
        layout.add::<GuideConstants>(guides);
        Links::layout(layout, guides, &params.links);
        layout.add::<f32>(guides.saturating_mul(Self::block_floats(params)));
        layout.add::<[f32; 3]>(guides);
    }

    /// Sets up the simulation of `guides` at rest on `rest` (the rest mesh)
    /// with `params`, every guide at its neutral pose. The maps are sampled
    /// at the guides' roots; a value out of its range is an error naming
    /// the guide.
    pub fn new(
        rest: Mesh<'_>,
        guides: &Guides,
        params: &SimParams,
        arena: &mut Arena<'a>,
    ) -> Result<Self, Error> {
        params.check()?;
        for (map, what) in [
            (&params.frequency, "frequency map"),
            (&params.amplitude, "amplitude map"),
            (&params.decay, "decay map"),
            (&params.external, "external map"),
        ] {
            map.validate(&rest, what)?;
        }
        let frame = PosedFrame::with_guides(rest, guides, params.joints, arena)?;
        let n = guides.len();
        let j = params.joints;
        let roots = arena.alloc::<Root>(n)?;
        roots.copy_from_slice(guides.roots);
        let local = arena.alloc::<f32>(n * 3 * j)?;
        let lengths = arena.alloc::<f32>(n * (j - 1))?;
        let constants = arena.alloc::<GuideConstants>(n)?;
        for g in 0..n {
            let r = &roots[g];
            let (face, u, v) = (r.face as usize, r.u, r.v);
            let spring = TipSpring {
                frequency: params.frequency.sample(&rest, face, u, v),
                amplitude: params.amplitude.sample(&rest, face, u, v),
                decay: params.decay.sample(&rest, face, u, v),
            };
            let external = params.external.sample(&rest, face, u, v);
            if !(0.0..=1.0).contains(&external) {
                return Err(Error::OutOfDomain {
                    what: "external map (0..=1)",
                    index: g,
                });
            }
            if !spring.is_valid() {
                return Err(Error::OutOfDomain {
                    what: "guide springs (frequency 0..=1000, amplitude 0..=1, decay 0..=10000)",
                    index: g,
                });
            }
            let mut reach = 0.0;
            for k in 0..j {
                let p = frame.local_point(g, k);
                local[(g * j + k) * 3..(g * j + k) * 3 + 3].copy_from_slice(&p.to_array());
                if k > 0 {
                    let len = p.distance(frame.local_point(g, k - 1));
                    lengths[g * (j - 1) + k - 1] = len;
                    reach += len;
                }
            }
            constants[g] = GuideConstants {
                spring_frequency: spring.frequency,
                spring_amplitude: spring.amplitude,
                spring_decay: spring.decay,
                reach,
                external,
            };
        }
        // the links are made at rest, between the guides' rest tips
        let rest_tips = arena.alloc::<[f32; 3]>(n)?;
        for (g, t) in rest_tips.iter_mut().enumerate() {
            *t = frame.world_point(g, j - 1).to_array();
        }
        let links = Links::new(rest_tips, &params.links, arena)?;
        let blocks = arena.alloc::<f32>(n * Self::block_floats(params))?;
        blocks.fill(0.0);
        let p = params;
        let fingerprint = Fingerprint::new()
            .add(&[p.joints as u32, p.points as u32, p.ik.max_iterations])
            .add(&[p.ik.tolerance, p.ik.root_stiffness, p.ik.tip_stiffness])
            .add(&[p.links.max_links, p.links.iterations])
            .add(&[p.links.radius, p.links.stiffness, p.teleport])
            .add(roots)
            .add(local)
            .add(lengths)
            .add(constants)
            .value();
        Ok(Sim {
            params: SimParams {
                frequency: ScalarMap::Constant(0.0),
                amplitude: ScalarMap::Constant(0.0),
                decay: ScalarMap::Constant(0.0),
                external: ScalarMap::Constant(0.0),
                ..*params
            },
            roots,
            rest: local,
            lengths,
            constants,
            links,
            blocks,
            snapshot: rest_tips,
            topology: (rest.triangle_count(), rest.positions.len()),
            stepped: false,
            fingerprint,
            origin: [0.0; 3],
        })
    }

    /// Number of guides.
    pub fn len(&self) -> usize {
        self.roots.len()
    }

    /// True without guides (never: [`Sim::new`] needs one).
    pub fn is_empty(&self) -> bool {
        self.roots.is_empty()
    }

    /// Points per posed guide.
    pub fn points(&self) -> usize {
        self.params.points
    }

    /// The guides' roots.
    pub fn roots(&self) -> &[Root] {
        self.roots
    }

    /// The link network.
    pub fn links(&self) -> &Links<'a> {
        &self.links
    }

    /// Posed point `k` of guide `g` after the last step, relative to
    /// [`origin`](Self::origin) (zero before the first step).
    pub fn posed(&self, g: usize, k: usize) -> Vec3 {
        self.root_frame(g).to_world(self.posed_local(g, k))
    }

    /// Posed point `k` of guide `g` after the last step, in its root frame.
    pub fn posed_local(&self, g: usize, k: usize) -> Vec3 {
        let p = &posed(self.block(g))[3 * k..3 * k + 3];
        Vec3::new(p[0], p[1], p[2])
    }

    /// Guide `g`'s root frame at the last step.
    pub fn root_frame(&self, g: usize) -> Frame {
        state(self.block(g)).root_frame()
    }

    /// The spring target of guide `g` at the last step (after the links).
    pub fn target(&self, g: usize) -> Vec3 {
        Vec3::from(state(self.block(g)).target)
    }

    /// The origin of the frame of the last step, which the posed guides
    /// and the state are relative to (zero before the first step).
    pub fn origin(&self) -> [f64; 3] {
        self.origin
    }

    /// What [`undo`](Self::undo) and [`put_back`](Self::put_back) take to
    /// return to the simulation as it is now.
    pub fn mark(&self) -> StepMark {
        StepMark {
            stepped: self.stepped,
            origin: self.origin,
        }
    }

    fn block(&self, g: usize) -> &[f32] {
        let per = Self::block_floats(&self.params);
        &self.blocks[g * per..(g + 1) * per]
    }

    /// True when a step has begun since the simulation was made, reset or
    /// restored, and was not taken back ([`undo`](Self::undo)): there are
    /// posed guides to read.
    pub fn has_stepped(&self) -> bool {
        self.stepped
    }

    /// Takes back a step that could not finish, before its push-out
    /// ([`StepContext::collide`]) began: every guide's state and spring
    /// target as [`StepContext::keep`] saved them in `kept` before the step
    /// advanced them ([`KEPT_FLOATS`] per guide, all of them), and `mark`,
    /// what [`mark`](Self::mark) said before the step began. A step that shaped its guides apart
    /// ([`StepContext::shape`]) wrote no posed point before its push-out,
    /// so the simulation is then as it was.
    pub fn undo(&mut self, kept: &[f32], mark: StepMark) {
        let per = Self::block_floats(&self.params);
        for (b, k) in self
            .blocks
            .chunks_exact_mut(per)
            .zip(kept.chunks_exact(KEPT_FLOATS))
        {
            b[..KEPT_FLOATS].copy_from_slice(k);
        }
        (self.stepped, self.origin) = (mark.stepped, mark.origin);
    }

    /// Every guide's block, its state then its posed points: what
    /// [`put_back`](Self::put_back) takes to undo a whole step.
    pub fn blocks(&self) -> &[f32] {
        self.blocks
    }

    /// Takes back a whole step, push-out included: every block as
    /// [`blocks`](Self::blocks) gave them before it (all of them), and
    /// `mark`, what [`mark`](Self::mark) said then.
    pub fn put_back(&mut self, blocks: &[f32], mark: StepMark) {
        self.blocks.copy_from_slice(blocks);
        (self.stepped, self.origin) = (mark.stepped, mark.origin);
    }

    /// Forgets the motion: the next step starts from the neutral pose.
    pub fn reset(&mut self) {
        self.blocks.fill(0.0);
        self.stepped = false;
        self.origin = [0.0; 3];
    }

    /// Poses `frame`'s guides with the posed guides of the last step, for
    /// a host to fill in parallel as [`PosedFrame::posing`] does, checking
    /// them as it fills: the host has [`GuideFiller::fill`] fill every
    /// guide and [`posed_faults`](Self::posed_faults) check every guide, then
    /// calls [`Posing::finish_checked`] with their faults merged in order
    /// ([`PosedFaults::then`]). The bits are those
    /// the step's world points would give through [`PosedFrame::posing`]
    /// (from the same roots), and the errors those it would return. The
    /// frame must be of a mesh with the rest mesh's counts and take
    /// [`points`](Self::points) points per strand, and a step must have run
    /// since the simulation was made, reset or restored, with a frame of
    /// the same origin ([`origin`](Self::origin)); when those hold,
    /// the frame has no guides from here until a successful finish.
    ///
    /// [`GuideFiller::fill`]: crate::interp::posed::GuideFiller::fill
    pub fn posing<'r>(
        &'r self,
        frame: &'r mut PosedFrame<'_>,
    ) -> Result<Posing<'r, SimGuides<'r, 'a>>, Error> {
        let mesh = frame.mesh();
        if (mesh.triangle_count(), mesh.positions.len()) != self.topology {
            return Err(Error::InvalidArgument(
                "the frame's mesh has other triangle or vertex counts than the rest mesh",
            ));
        }
        if frame.points() != self.points() {
            return Err(Error::InvalidArgument(
                "the frame's points per strand differ from the simulation's",
            ));
        }
        if !self.stepped {
            return Err(Error::InvalidArgument(
                "the simulation has no posed guides until it steps (after being made, reset or restored)",
            ));
        }
        if frame.origin() != self.origin {
            return Err(Error::InvalidArgument(
                "the frame's origin differs from that of the frame the simulation last stepped with",
            ));
        }
        let mut posing = frame.posing_from(SimGuides { sim: self })?;
        posing.unpose();
        Ok(posing)
    }

    /// What [`Guides::validate`] would refuse of the world points
    /// [`posed`](Self::posed) gives for guides `guides` (see
    /// [`posing`](Self::posing)): a point not finite or beyond 1e9, a guide
    /// of zero length (its root triangle collapsed).
    pub fn posed_faults(&self, guides: Range<usize>) -> PosedFaults {
        let limit = crate::surface::mesh::MAX_COORDINATE;
        let m = self.points();
        let mut faults = PosedFaults {
            guides: guides.len(),
            ..PosedFaults::default()
        };
        for g in guides {
            let frame = self.root_frame(g);
            if self.plainly_posed(g, &frame) {
                continue;
            }
            let (mut length, mut last) = (0.0f32, Vec3::ZERO);
            for j in 0..m {
                let p = frame.to_world(self.posed_local(g, j));
                let index = g * m + j;
                if !p.is_finite() {
                    faults.not_finite = faults.not_finite.or(Some(index));
                } else if p.abs().max_element() > limit {
                    faults.far = faults.far.or(Some(index));
                }
                if j > 0 {
                    length += p.distance(last);
                }
                last = p;
            }
            faults.zero |= length.is_nan() || length <= 0.0;
        }
        faults
    }

    /// True when guide `g`, on its root frame `frame`, has none of the
    /// faults [`posed_faults`](Self::posed_faults) looks for, for certain, from its local
    /// points alone (no world point made): the frame and the points
    /// finite, the frame's axes unit and square (not collapsed), every point within
    /// half the coordinate limit, and consecutive points farther apart than
    /// the world points' rounding could close (a few units in the last
    /// place of the largest coordinate; 1e-5 of it is ~100).
    fn plainly_posed(&self, g: usize, frame: &Frame) -> bool {
        let (t, b, n) = (frame.t, frame.b, frame.n);
        let unit = [t, b, n]
            .iter()
            .all(|a| (a.length_squared() - 1.0).abs() < 1e-3);
        let square = [t.dot(b), t.dot(n), b.dot(n)]
            .iter()
            .all(|d| d.abs() < 1e-3);
        if !(frame.origin.is_finite() && unit && square) {
            return false;
        }
        // the block's posed points, read once (x, y, z per point)
        let local = posed(self.block(g));
        if !local.iter().all(|x| x.is_finite()) {
            return false;
        }
        let square = |p: &[f32]| p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        let farthest = local.chunks_exact(3).map(square).fold(0.0f32, f32::max);
        let closest = local
            .chunks_exact(3)
            .zip(local[3..].chunks_exact(3))
            .map(|(a, b)| square(&[b[0] - a[0], b[1] - a[1], b[2] - a[2]]))
            .fold(f32::INFINITY, f32::min);
        let scale = frame.origin.abs().max_element() + 1.01 * libm::sqrtf(farthest);
        let limit = crate::surface::mesh::MAX_COORDINATE;
        // with a floor: squares of steps near the smallest floats vanish
        scale < 0.5 * limit && closest > ((1e-5 * scale) * (1e-5 * scale)).max(1e-30)
    }

    /// The checks [`begin`](Self::begin) makes of a step's inputs, for a
    /// host that has more to do before it begins (a body to build) and
    /// would report a bad input first.
    pub fn check_step(
        &self,
        frame: &PosedFrame,
        colliders: &Colliders,
        external: Option<Strided<[f32; 3]>>,
        dt: f32,
    ) -> Result<(), Error> {
        if !dt.is_finite() {
            return Err(Error::NonFinite {
                what: "dt",
                index: 0,
            });
        }
        if !(MIN_DT..=1.0).contains(&dt) {
            return Err(Error::InvalidArgument("dt must be in [1e-5, 1] seconds"));
        }
        let mesh = frame.mesh();
        if (mesh.triangle_count(), mesh.positions.len()) != self.topology {
            return Err(Error::InvalidArgument(
                "the frame's mesh has other triangle or vertex counts than the rest mesh",
            ));
        }
        colliders.check()?;
        if let Some(curves) = external {
            let m = self.params.points;
            if curves.len() != self.len() * m {
                return Err(Error::InvalidArgument(
                    "external curves need points_per_guide points per guide",
                ));
            }
            let limit = crate::surface::mesh::MAX_COORDINATE;
            let taking = self.constants.iter().map(|c| c.external > 0.0);
            for g in taking.enumerate().filter_map(|(g, t)| t.then_some(g)) {
                let values = || (0..m).flat_map(|k| curves.get(g * m + k));
                if values().any(|x| !x.is_finite()) {
                    return Err(Error::NonFinite {
                        what: "external curves",
                        index: g,
                    });
                }
                if values().any(|x| x.abs() > limit) {
                    return Err(Error::OutOfDomain {
                        what: "external curves (within 1e9)",
                        index: g,
                    });
                }
            }
        }
        Ok(())
    }

    /// Checks the step's inputs and splits the simulation into what the
    /// step's phases read and the per-guide blocks they write (see the
    /// module docs); [`Sim::step`] runs every phase on one thread.
    ///
    /// `external` holds the host's curves for the guides the `external`
    /// map selects (world space, `points` per guide, guide after guide;
    /// checked finite and within 1e9 where the map is above 0); without
    /// them, those guides keep pelage's dynamics.
    pub fn begin<'s>(
        &'s mut self,
        frame: &'s PosedFrame,
        colliders: &'s Colliders<'s>,
        external: Option<Strided<'s, [f32; 3]>>,
        dt: f32,
    ) -> Result<Step<'s>, Error> {
        self.check_step(frame, colliders, external, dt)?;
        let block = Self::block_floats(&self.params);
        let shift = self.shift_to(frame.origin());
        let cut = self.is_cut(frame, shift);
        self.stepped = true;
        self.origin = frame.origin();
        Ok(Step {
            context: StepContext {
                params: &self.params,
                roots: self.roots,
                rest: self.rest,
                lengths: self.lengths,
                constants: self.constants,
                links: &self.links,
                frame,
                colliders,
                external,
                dt,
                block,
                cut,
                shift,
            },
            blocks: &mut *self.blocks,
            snapshot: &mut *self.snapshot,
        })
    }

    /// What carries a position of the last step's state to one relative to
    /// `origin`: the difference of the origins, taken in double precision
    /// and rounded once (zero when they are the same).
    fn shift_to(&self, origin: [f64; 3]) -> Vec3 {
        let [x, y, z] = core::array::from_fn(|i| (self.origin[i] - origin[i]) as f32);
        Vec3::new(x, y, z)
    }

    /// True when `frame` is a cut from the last step: its roots moved, on
    /// average, farther than `teleport` times the extent of the roots (the
    /// diagonal of their box). A measure of the body as a whole: a fast
    /// spin or run moves some roots far and others little, and stays
    /// below the body's own size per step. Summed in one order on one
    /// thread, so any split of the step sees the same answer.
    fn is_cut(&self, frame: &PosedFrame, shift: Vec3) -> bool {
        let mesh = frame.mesh();
        let block = Self::block_floats(&self.params);
        let (mut moved, mut lo, mut hi) = (0.0f64, Vec3::MAX, Vec3::MIN);
        for (r, b) in self.roots.iter().zip(self.blocks.chunks_exact(block)) {
            let last = state(b);
            if last.started == 0.0 {
                return false;
            }
            let p = mesh.point(r.face as usize, r.u, r.v);
            // `- shift`, not `+ shift` on the last root: subtracting a zero
            // shift keeps every bit, so a fixed origin changes nothing
            moved += f64::from((p - shift).distance(Vec3::from(last.frame[0])));
            (lo, hi) = (lo.min(p), hi.max(p));
        }
        let mean = moved / self.roots.len().max(1) as f64;
        mean > f64::from(self.params.teleport) * f64::from((hi - lo).length())
    }

    /// One step of `dt` seconds on `frame` (the step's deformed mesh) with
    /// `colliders`, on the calling thread. Returns how many guides took
    /// their groomed shape ([`StepContext::finish`]).
    pub fn step(
        &mut self,
        frame: &PosedFrame,
        colliders: &Colliders,
        dt: f32,
    ) -> Result<usize, Error> {
        let Step {
            context: ctx,
            blocks,
            snapshot,
        } = self.begin(frame, colliders, None, dt)?;
        ctx.bend(blocks, snapshot, |blocks, phase| {
            phase(0, blocks);
            Ok::<(), Error>(())
        })?;
        Ok(ctx.finish(0, blocks))
    }
}

impl Sim<'_> {
    /// The header of this simulation's state file.
    fn state_header(&self) -> StateHeader {
        StateHeader {
            counts: [self.len(), self.params.joints, self.params.points].map(|c| c as u64),
            fingerprint: self.fingerprint,
            stepped: self.stepped,
            origin: self.origin,
        }
    }

    /// Bytes [`Sim::save`] writes.
    pub fn state_bytes(&self) -> usize {
        state_file_bytes(self.blocks)
    }

    /// Writes the simulation's state to `out` (at least
    /// [`Sim::state_bytes`]) in pelage's file framing (docs/FORMAT.md):
    /// the counts, the fingerprint of the parameters and rest guides that
    /// [`Sim::restore`] checks, whether a step has run, and every guide's
    /// block. Returns the bytes written.
    pub fn save(&self, out: &mut [u8]) -> Result<usize, Error> {
        let needed = self.state_bytes();
        if out.len() < needed {
            return Err(Error::OutputTooSmall {
                needed,
                available: out.len(),
            });
        }
        Ok(write_state(out, self.state_header(), self.blocks))
    }

    /// Restores a state [`Sim::save`] wrote for a simulation made from the
    /// same rest guides, roots, maps and parameters (its fingerprint).
    /// Checks everything first (framing, checksum, counts, fingerprint,
    /// values) and changes nothing on error. Once restored, the posed
    /// guides are those of the step saved, if any.
    pub fn restore(&mut self, bytes: &[u8]) -> Result<(), Error> {
        (self.stepped, self.origin) = read_state(bytes, self.state_header(), self.blocks)?;
        Ok(())
    }
}

/// What [`Sim::posed_faults`] found on a range of guides.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PosedFaults {
    /// The first point not finite.
    not_finite: Option<usize>,
    /// The first point beyond 1e9.
    far: Option<usize>,
    /// Some guide has zero length.
    zero: bool,
    /// Guides checked.
    guides: usize,
}

impl PosedFaults {
    /// These faults and those of a `later` range.
    pub fn then(self, later: PosedFaults) -> PosedFaults {
        PosedFaults {
            not_finite: self.not_finite.or(later.not_finite),
            far: self.far.or(later.far),
            zero: self.zero || later.zero,
            guides: self.guides + later.guides,
        }
    }

    /// The error [`Guides::validate`] gives for these faults (the first
    /// point not finite, else the first beyond 1e9, else a zero length).
    pub fn result(self) -> Result<(), Error> {
        if let Some(index) = self.not_finite {
            return Err(Error::NonFinite {
                what: "guide points",
                index,
            });
        }
        if let Some(index) = self.far {
            return Err(Error::OutOfDomain {
                what: "guide points (within 1e9)",
                index,
            });
        }
        if self.zero {
            return Err(Error::InvalidArgument("a guide has zero length"));
        }
        Ok(())
    }
}

impl Posing<'_, SimGuides<'_, '_>> {
    /// Marks the frame posed when `faults`, every guide's merged in order,
    /// are none: else the error [`Guides::validate`] gives for them (or for
    /// faults of fewer guides than the simulation has, an invalid
    /// argument), and the frame stays without guides.
    pub fn finish_checked(self, faults: PosedFaults) -> Result<(), Error> {
        if faults.guides != self.source().sim.len() {
            return Err(Error::InvalidArgument(
                "the posed guides' faults must cover every guide",
            ));
        }
        faults.result()?;
        self.finish_unchecked();
        Ok(())
    }
}

/// The posed guides of a simulation's last step, in world space (see
/// [`Sim::posing`]).
#[derive(Clone, Copy)]
pub struct SimGuides<'r, 'a> {
    sim: &'r Sim<'a>,
}

impl GuidePoints for SimGuides<'_, '_> {
    fn roots(&self) -> &[Root] {
        self.sim.roots
    }

    /// `n` is the simulation's point count ([`Sim::posing`] checks it).
    #[inline]
    fn each_point(&self, g: usize, n: usize, mut visit: impl FnMut(usize, Vec3)) {
        let frame = self.sim.root_frame(g);
        for j in 0..n {
            visit(j, frame.to_world(self.sim.posed_local(g, j)));
        }
    }
}

#[cfg(test)]
mod tests;
