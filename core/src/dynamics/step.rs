//! A step's phases over ranges of guides: [`StepContext::bend`] runs the
//! advance (neutral pose, tip spring, target) and the link relaxations in
//! their order; then [`StepContext::finish`] (IK, curve, push-out), or
//! [`StepContext::shape`] then [`StepContext::collide`] for a host that
//! builds a collider while the guides bend. A host splits each phase over
//! threads as it likes: any split gives the same bits.

use super::ik;
use super::links::Links;
use super::params::{GuideConstants, SimParams, MAX_JOINTS};
use super::spline;
use super::spring::TipSpring;
use super::state::{state, state_mut, GuideState, KEPT_FLOATS};
use crate::collide::{field_verdicts, push_out, push_out_known, Colliders, PushOut, FIELD_BATCH};
use crate::interp::posed::PosedFrame;
use crate::surface::body::Body;
use crate::surface::frame::Frame;
use crate::{Root, Strided};
use glam::Vec3;

/// A step begun: what its phases read, and what they write.
pub struct Step<'s> {
    /// What every phase reads.
    pub context: StepContext<'s>,
    /// Every guide's block, [`StepContext::block_floats`] floats each.
    pub blocks: &'s mut [f32],
    /// One target per guide, for the link relaxations.
    pub snapshot: &'s mut [[f32; 3]],
}

/// What every phase of a step reads (see [`Sim::begin`](super::sim::Sim::begin)).
pub struct StepContext<'s> {
    pub(super) params: &'s SimParams<'static>,
    pub(super) roots: &'s [Root],
    pub(super) rest: &'s [f32],
    pub(super) lengths: &'s [f32],
    pub(super) constants: &'s [GuideConstants],
    pub(super) links: &'s Links<'s>,
    pub(super) frame: &'s PosedFrame<'s>,
    pub(super) colliders: &'s Colliders<'s>,
    pub(super) external: Option<Strided<'s, [f32; 3]>>,
    pub(super) dt: f32,
    pub(super) block: usize,
    /// The step is a cut ([`SimParams::teleport`]).
    pub(super) cut: bool,
    /// Added to a position of the last step's state to make it relative to
    /// this step's frame's origin.
    pub(super) shift: Vec3,
}

impl StepContext<'_> {
    /// Floats per guide block: a range of `n` guides takes `n` blocks.
    pub fn block_floats(&self) -> usize {
        self.block
    }

    /// Link relaxations this step runs.
    pub fn link_iterations(&self) -> u32 {
        if self.links.is_empty() {
            0
        } else {
            self.params.links.iterations
        }
    }

    /// Phase 1 for the guides `first ..` whose blocks `blocks` holds: the
    /// neutral pose, the tip spring, the target.
    pub fn advance(&self, first: usize, blocks: &mut [f32]) {
        let j = self.params.joints;
        for (i, b) in blocks.chunks_exact_mut(self.block).enumerate() {
            let g = first + i;
            let r = &self.roots[g];
            let frame = self.frame.root_frame(r.face as usize, r.u, r.v);
            let tip = frame.to_world(rest_joint(self.rest, j, g, j - 1));
            let (state, _) = state_mut(b);
            let c = self.constants[g];
            let spring = TipSpring {
                frequency: c.spring_frequency,
                amplitude: c.spring_amplitude,
                decay: c.spring_decay,
            };
            let (mut y, mut v, mut velocity) = (
                Vec3::from(state.swing),
                Vec3::from(state.swing_velocity),
                Vec3::ZERO,
            );
            if state.started != 0.0 {
                if self.cut {
                    // the swing rides along with the root frame; the body
                    // starts from rest in its new place (no velocity of the
                    // last shot carried into this one's next step)
                    let last = state.root_frame();
                    let carry = |w: Vec3| {
                        let l = Vec3::new(w.dot(last.t), w.dot(last.b), w.dot(last.n));
                        frame.t * l.x + frame.b * l.y + frame.n * l.z
                    };
                    y = carry(y);
                    v = carry(v);
                } else {
                    // the last tip in this step's origin; subtracting a zero
                    // shift keeps every bit
                    velocity = (tip - Vec3::from(state.tip) - self.shift) / self.dt;
                    // the tip keeps its velocity; the neutral tip's changed
                    v += Vec3::from(state.tip_velocity) - velocity;
                }
                (y, v) = spring.advance(y, v, self.dt);
                // bounded whatever the motion: the tip can never be farther
                // than twice the reach from the neutral tip
                let reach = 2.0 * c.reach;
                if y.length() > reach {
                    y = y.normalize_or_zero() * reach;
                }
                let speed = reach
                    * (core::f32::consts::TAU * spring.frequency + spring.decay + 1.0 / self.dt);
                if v.length() > speed {
                    v = v.normalize_or_zero() * speed;
                }
                // a value that overflowed on the way restarts the swing,
                // never carries a NaN into the next step
                if !(y.is_finite() && v.is_finite() && velocity.is_finite()) {
                    (y, v, velocity) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
                }
            }
            *state = GuideState {
                swing: y.to_array(),
                swing_velocity: v.to_array(),
                tip: tip.to_array(),
                tip_velocity: velocity.to_array(),
                frame: [frame.origin, frame.t, frame.b, frame.n].map(|a| a.to_array()),
                started: 1.0,
                target: (tip + y * spring.amplitude).to_array(),
            };
        }
    }

    /// Phases 1 and 2 in their order, the one place it is written: the
    /// advance, then each link relaxation against a snapshot of every
    /// target. `each` runs one phase over every guide's block in `blocks`,
    /// split as the caller likes (one thread or many; the bits are the
    /// same): the phase takes the first guide of a range and its blocks.
    /// Phase 3 follows: [`finish`](Self::finish), or [`shape`](Self::shape)
    /// then [`collide`](Self::collide).
    pub fn bend<E>(
        &self,
        blocks: &mut [f32],
        snapshot: &mut [[f32; 3]],
        mut each: impl FnMut(&mut [f32], &(dyn Fn(usize, &mut [f32]) + Sync)) -> Result<(), E>,
    ) -> Result<(), E> {
        each(blocks, &|first, part| self.advance(first, part))?;
        for _ in 0..self.link_iterations() {
            self.snapshot(blocks, snapshot);
            let snapshot = &*snapshot;
            each(blocks, &|first, part| self.relax(first, part, snapshot))?;
        }
        Ok(())
    }

    /// Copies every guide's target from `blocks` (all of them) to `snapshot`.
    pub fn snapshot(&self, blocks: &[f32], snapshot: &mut [[f32; 3]]) {
        for (b, s) in blocks.chunks_exact(self.block).zip(snapshot.iter_mut()) {
            *s = state(b).target;
        }
    }

    /// Phase 2, one relaxation, for the guides `first ..` whose blocks
    /// `blocks` holds, against the `snapshot` of every target.
    pub fn relax(&self, first: usize, blocks: &mut [f32], snapshot: &[[f32; 3]]) {
        let stiffness = self.params.links.stiffness;
        for (i, b) in blocks.chunks_exact_mut(self.block).enumerate() {
            let t = self.links.relaxed(first + i, snapshot, stiffness);
            state_mut(b).0.target = t.to_array();
        }
    }

    /// Copies the state and spring target of the guides whose blocks
    /// `blocks` holds into `kept` ([`KEPT_FLOATS`] per guide), before
    /// [`advance`](Self::advance) overwrites them: what [`Sim::undo`](super::sim::Sim::undo) puts
    /// back when the step cannot finish (a host that builds a collider
    /// while the guides bend).
    pub fn keep(&self, blocks: &[f32], kept: &mut [f32]) {
        for (b, k) in blocks
            .chunks_exact(self.block)
            .zip(kept.chunks_exact_mut(KEPT_FLOATS))
        {
            k.copy_from_slice(&b[..KEPT_FLOATS]);
        }
    }

    /// Phase 3 for the guides `first ..` whose blocks `blocks` holds: IK
    /// toward the target, the Catmull-Rom curve, the push-out from the
    /// step's colliders. The same as [`shape`](Self::shape) then
    /// [`collide`](Self::collide), without keeping the curves in between.
    /// Returns how many of them took their groomed shape: no tried rotation
    /// freed their curve from a collider, or their bend overflowed.
    pub fn finish(&self, first: usize, blocks: &mut [f32]) -> usize {
        let m = self.params.points;
        if self.colliders.field.is_none() {
            let mut groomed = 0;
            self.solve(first, blocks, |g, b, joints| {
                let mut posed = [Vec3::ZERO; MAX_JOINTS];
                self.curve(g, b, joints, &mut posed[..m]);
                groomed += self.push(g, b, &mut posed[..m], self.colliders, None) as usize;
            });
            return groomed;
        }
        // with a host field, the guides' curves are made a batch at a time
        // and the field asked once for the batch (each guide's curve is its
        // own whatever it is solved with: the same bits)
        let mut groomed = 0;
        for (k, part) in blocks.chunks_mut(FIELD_BATCH * self.block).enumerate() {
            let first = first + k * FIELD_BATCH;
            let mut curves = [[Vec3::ZERO; MAX_JOINTS]; FIELD_BATCH];
            self.solve(first, part, |g, b, joints| {
                self.curve(g, b, joints, &mut curves[g - first][..m]);
            });
            groomed += self.push_batch(first, part, &mut curves, self.colliders);
        }
        groomed
    }

    /// Phase 3 without its push-out, for a host that builds a collider
    /// meanwhile: IK and the Catmull-Rom curve of the guides `first ..`
    /// whose blocks `blocks` holds, written to `shaped` (in their root
    /// frames, [`Sim::points`](super::sim::Sim::points) float3 per guide) and not to the blocks
    /// (only read here; mutable as [`finish`](Self::finish)'s, which
    /// shares the IK's driver), whose posed guides stay those of the last
    /// step until [`collide`](Self::collide).
    pub fn shape(&self, first: usize, blocks: &mut [f32], shaped: &mut [f32]) {
        let m = self.params.points;
        self.solve(first, blocks, |g, b, joints| {
            let mut posed = [Vec3::ZERO; MAX_JOINTS];
            self.curve(g, b, joints, &mut posed[..m]);
            let i = g - first;
            let out = &mut shaped[i * 3 * m..(i + 1) * 3 * m];
            for (o, p) in out.chunks_exact_mut(3).zip(&posed[..m]) {
                o.copy_from_slice(&p.to_array());
            }
        });
    }

    /// The rest of phase 3 after [`shape`](Self::shape): the push-out of
    /// the guides `first ..` whose blocks `blocks` holds and whose curves
    /// `shaped` holds, from the step's colliders with `body` (built
    /// meanwhile) as their body, into the blocks. The bits and the count
    /// returned are [`finish`](Self::finish)'s with that body.
    pub fn collide(
        &self,
        first: usize,
        blocks: &mut [f32],
        shaped: &[f32],
        body: Option<&Body>,
    ) -> usize {
        let colliders = Colliders {
            body,
            ..*self.colliders
        };
        let colliders = &colliders;
        let m = self.params.points;
        let mut groomed = 0;
        for (k, part) in blocks.chunks_mut(FIELD_BATCH * self.block).enumerate() {
            let first = first + k * FIELD_BATCH;
            let shaped = &shaped[k * FIELD_BATCH * 3 * m..];
            let mut curves = [[Vec3::ZERO; MAX_JOINTS]; FIELD_BATCH];
            for (curve, s) in curves.iter_mut().zip(shaped.chunks(3 * m)) {
                for (p, s) in curve[..m].iter_mut().zip(s.chunks_exact(3)) {
                    *p = Vec3::new(s[0], s[1], s[2]);
                }
            }
            groomed += self.push_batch(first, part, &mut curves, colliders);
        }
        groomed
    }

    /// The push-outs of the guides `first ..` whose blocks `blocks` holds
    /// (at most [`FIELD_BATCH`]) and whose curves `curves` holds, the host
    /// field (if any) asked once for all of them first.
    fn push_batch(
        &self,
        first: usize,
        blocks: &mut [f32],
        curves: &mut [[Vec3; MAX_JOINTS]; FIELD_BATCH],
        colliders: &Colliders,
    ) -> usize {
        let m = self.params.points;
        let mut verdicts = [None; FIELD_BATCH];
        let guides = blocks.len() / self.block;
        let blocks_read = &*blocks;
        let curves_read = &*curves;
        field_verdicts(
            colliders,
            |i| {
                let curve = &curves_read[i][..m];
                let frame = state(&blocks_read[i * self.block..]).root_frame();
                curve
                    .iter()
                    .all(|p| p.is_finite())
                    .then_some((frame, curve))
            },
            &mut verdicts[..guides],
        );
        let mut groomed = 0;
        for (i, b) in blocks.chunks_exact_mut(self.block).enumerate() {
            groomed +=
                self.push(first + i, b, &mut curves[i][..m], colliders, verdicts[i]) as usize;
        }
        groomed
    }

    /// IK toward the target for the guides `first ..` whose blocks `blocks`
    /// holds, handing `done` each guide's index, block and solved joints
    /// (root frame). The guides whose target is in reach are solved
    /// [`ik::LANES`] at a time, in the order they come; each one's result
    /// is its own whatever it is solved with.
    fn solve(
        &self,
        first: usize,
        blocks: &mut [f32],
        mut done: impl FnMut(usize, &mut [f32], &[Vec3]),
    ) {
        let j = self.params.joints;
        let mut joints = [Vec3::ZERO; MAX_JOINTS];
        let mut chains = ik::Chains::default();
        let mut queued = [0usize; ik::LANES];
        let mut waiting = 0;
        let guides = blocks.len() / self.block;
        for i in 0..guides {
            let g = first + i;
            // in the root frame: the neutral joints are the rest joints,
            // and lengths hold to the last bit whatever the world
            // coordinates
            for (k, p) in joints[..j].iter_mut().enumerate() {
                *p = rest_joint(self.rest, j, g, k);
            }
            let b = &mut blocks[i * self.block..(i + 1) * self.block];
            let state = state(b);
            let target = state.root_frame().to_local(Vec3::from(state.target));
            let lengths = &self.lengths[g * (j - 1)..(g + 1) * (j - 1)];
            if ik::stretch_if_unreachable(&mut joints[..j], lengths, target) {
                done(g, b, &joints[..j]);
                continue;
            }
            chains.load(
                waiting,
                &joints[..j],
                lengths,
                target,
                self.constants[g].reach,
            );
            queued[waiting] = i;
            waiting += 1;
            if waiting == ik::LANES {
                self.solve_queued(&mut chains, &queued, first, blocks, &mut done);
                waiting = 0;
            }
        }
        self.solve_queued(&mut chains, &queued[..waiting], first, blocks, &mut done);
    }

    /// Solves the chains in `chains`, those of the guides `first + i` for
    /// the `i` `queued` lists lane by lane, hands each to `done`, and
    /// empties `chains`.
    fn solve_queued(
        &self,
        chains: &mut ik::Chains,
        queued: &[usize],
        first: usize,
        blocks: &mut [f32],
        done: &mut impl FnMut(usize, &mut [f32], &[Vec3]),
    ) {
        if queued.is_empty() {
            return;
        }
        let j = self.params.joints;
        chains.solve(j, &self.params.ik);
        let mut joints = [Vec3::ZERO; MAX_JOINTS];
        for (lane, &i) in queued.iter().enumerate() {
            for (k, p) in joints[..j].iter_mut().enumerate() {
                *p = chains.joint(lane, k);
            }
            let b = &mut blocks[i * self.block..(i + 1) * self.block];
            done(first + i, b, &joints[..j]);
        }
        chains.clear();
    }

    /// Guide `g`'s curve from its solved `joints` (root frame; its block
    /// `b` holds the frame): the Catmull-Rom curve through them, resampled
    /// to `posed`, and the host's curves blended in.
    fn curve(&self, g: usize, b: &[f32], joints: &[Vec3], posed: &mut [Vec3]) {
        spline::resample(joints, posed);
        let share = self.constants[g].external;
        if let (Some(curves), true) = (self.external, share > 0.0) {
            blend(&state(b).root_frame(), curves, g, share, posed);
        }
    }

    /// Guide `g`'s `posed` curve pushed out of `colliders` and written to
    /// its block `b` as its posed points.
    fn push(
        &self,
        g: usize,
        b: &mut [f32],
        posed: &mut [Vec3],
        colliders: &Colliders,
        field: Option<bool>,
    ) -> bool {
        let j = self.params.joints;
        let frame = state(b).root_frame();
        let reach = self.constants[g].reach;
        // the IK's products overflow for guides and moves near the
        // coordinate limit (lengths past ~1e9 each way): such a guide takes
        // its groomed shape rather than a non-finite point
        let lost = !posed.iter().all(|p| p.is_finite());
        let groomed =
            lost || push_out_known(colliders, &frame, posed, reach, field) == PushOut::Stuck;
        if groomed {
            // bent into a place no rotation leaves (a crease, a landing), or
            // lost: the groomed shape, pushed out in turn
            let mut rest = [Vec3::ZERO; MAX_JOINTS];
            for (k, p) in rest[..j].iter_mut().enumerate() {
                *p = rest_joint(self.rest, j, g, k);
            }
            spline::resample(&rest[..j], posed);
            push_out(colliders, &frame, posed, reach);
        }
        let (_, out) = state_mut(b);
        for (o, p) in out.chunks_exact_mut(3).zip(posed.iter()) {
            o.copy_from_slice(&p.to_array());
        }
        groomed
    }
}

/// Blends the posed guide `g` (root frame) toward the host's curve by
/// `share`: each segment turns toward the host curve's and keeps its length.
fn blend(frame: &Frame, curves: Strided<[f32; 3]>, g: usize, share: f32, posed: &mut [Vec3]) {
    let m = posed.len();
    let host = |k: usize| frame.to_local(Vec3::from(curves.get(g * m + k)));
    let mut from = posed[0];
    for k in 1..m {
        let own = posed[k] - from;
        from = posed[k];
        let direction = (own.normalize_or_zero() * (1.0 - share)
            + (host(k) - host(k - 1)).normalize_or_zero() * share)
            .normalize_or_zero();
        posed[k] = posed[k - 1]
            + if direction == Vec3::ZERO {
                own
            } else {
                direction * own.length()
            };
    }
}

/// Joint `k` of guide `g` at rest, in its root frame.
fn rest_joint(rest: &[f32], joints: usize, g: usize, k: usize) -> Vec3 {
    let at = (g * joints + k) * 3;
    Vec3::new(rest[at], rest[at + 1], rest[at + 2])
}
