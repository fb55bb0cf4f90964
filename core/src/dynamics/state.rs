//! A guide's state across steps, and the simulation's state file.
//!
//! Each guide owns one block of floats: its [`GuideState`] record, then
//! its posed points in its root frame. A step's phases write the blocks
//! of the guides they are given; [`Sim::save`] writes every block, so a
//! restored simulation reads the posed guides of the step it was saved
//! after and goes on with the same bits as an uninterrupted run.

use super::sim::Sim;
use crate::cache::container::{self, Reader};
use crate::surface::frame::Frame;
use crate::Error;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// One guide's state at its last step: what carries to the next step, and
/// the step's spring target.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GuideState {
    /// Tip offset from the neutral tip (world).
    pub swing: [f32; 3],
    /// Its velocity.
    pub swing_velocity: [f32; 3],
    /// The neutral tip.
    pub tip: [f32; 3],
    /// The neutral tip's velocity over the step.
    pub tip_velocity: [f32; 3],
    /// The root frame: origin, t, b, n.
    pub frame: [[f32; 3]; 4],
    /// 1 once the guide has stepped (0 after init or reset).
    pub started: f32,
    /// The spring target after the links (world).
    pub target: [f32; 3],
}

/// Floats of a [`GuideState`]: the first of every guide's block, all a
/// step writes before its push-out (what a step taken back restores).
pub const KEPT_FLOATS: usize = core::mem::size_of::<GuideState>() / 4;

impl GuideState {
    /// The root frame the guide stepped with.
    pub fn root_frame(&self) -> Frame {
        let [origin, t, b, n] = self.frame.map(Vec3::from);
        Frame { origin, t, b, n }
    }
}

/// The state record at the head of a guide's block.
pub(super) fn state(block: &[f32]) -> &GuideState {
    &bytemuck::cast_slice(&block[..KEPT_FLOATS])[0]
}

/// The state record at the head of a guide's block, and its posed points.
pub(super) fn state_mut(block: &mut [f32]) -> (&mut GuideState, &mut [f32]) {
    let (head, posed) = block.split_at_mut(KEPT_FLOATS);
    (&mut bytemuck::cast_slice_mut(head)[0], posed)
}

/// The posed points after a guide's state record (root frame, x y z each).
pub(super) fn posed(block: &[f32]) -> &[f32] {
    &block[KEPT_FLOATS..]
}

/// Largest magnitude of a restored state value, above any a step stores:
/// positions stay within about 1e11 (a root within 1e9, the swing within
/// twice a reach of at most ~5e10), speeds within about 1e17 (a reach over
/// the shortest step, times the stiffest spring).
const MAX_STATE: f32 = 1e18;

/// State-file magic (docs/FORMAT.md).
const MAGIC: &[u8; 8] = b"PLGSTATE";
/// State-file format version (1 was the unframed "PLGS" state of 0.11).
pub const STATE_VERSION: u32 = 2;
/// Header fields: guides, joints, points, the fingerprint, stepped.
const FIELDS: usize = 5;

/// A 64-bit fingerprint of words, for telling one simulation's inputs
/// from another's (not a defence against forgery: the CRC guards the
/// bytes).
#[derive(Clone, Copy)]
pub(super) struct Fingerprint(u64);

impl Fingerprint {
    pub(super) const fn new() -> Self {
        Fingerprint(0x6a09_e667_f3bc_c908)
    }

    /// Adds every 32-bit word of `items`.
    pub(super) fn add<T: Pod>(self, items: &[T]) -> Self {
        let bytes: &[u8] = bytemuck::cast_slice(items);
        let mut h = self.0;
        for w in bytes.chunks(4) {
            let mut word = [0u8; 4];
            word[..w.len()].copy_from_slice(w);
            h = (h.rotate_left(5) ^ u32::from_le_bytes(word) as u64)
                .wrapping_mul(0x517c_c1b7_2722_0a95);
        }
        Fingerprint(h)
    }

    pub(super) fn value(self) -> u64 {
        self.0
    }
}

impl Sim<'_> {
    /// Bytes [`Sim::save`] writes.
    pub fn state_bytes(&self) -> usize {
        container::header_bytes(FIELDS) + self.blocks.len() * 4
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
        let fields = [
            self.len() as u64,
            self.params.joints as u64,
            self.params.points as u64,
            self.fingerprint,
            self.stepped as u64,
        ];
        Ok(container::write(
            &mut out[..needed],
            MAGIC,
            STATE_VERSION,
            &fields,
            |w| w.words(self.blocks),
        ))
    }

    /// Restores a state [`Sim::save`] wrote for a simulation made from the
    /// same rest guides, roots, maps and parameters (its fingerprint).
    /// Checks everything first (framing, checksum, counts, fingerprint,
    /// values) and changes nothing on error. Once restored, the posed
    /// guides are those of the step saved, if any.
    pub fn restore(&mut self, bytes: &[u8]) -> Result<(), Error> {
        let file = container::read(bytes, MAGIC, STATE_VERSION, FIELDS)?;
        let [guides, joints, points, fingerprint, stepped, ..] = file.fields;
        if (guides, joints, points)
            != (
                self.len() as u64,
                self.params.joints as u64,
                self.params.points as u64,
            )
        {
            return Err(Error::InvalidArgument(
                "the state is of another guide set (guide, joint or point count)",
            ));
        }
        if fingerprint != self.fingerprint {
            return Err(Error::InvalidArgument(
                "the state was saved by a simulation of other rest guides, roots, maps or parameters",
            ));
        }
        if stepped > 1 {
            return Err(Error::Corrupt {
                what: "state's stepped field is neither 0 nor 1",
            });
        }
        if file.payload.len() != self.blocks.len() * 4 {
            return Err(Error::Corrupt {
                what: "state payload does not match its counts",
            });
        }
        let per = self.blocks.len() / self.len();
        let mut r = Reader::new(file.payload);
        let mut sound = true;
        for k in 0..self.blocks.len() {
            let x = f32::from_bits(r.u32()?);
            sound &= if k % per == STARTED_FLOAT {
                x == 0.0 || x == 1.0
            } else {
                x.abs() <= MAX_STATE
            };
        }
        if !sound {
            return Err(Error::Corrupt {
                what: "state holds a value out of its range",
            });
        }
        Reader::new(file.payload).words(self.blocks)?;
        self.stepped = stepped == 1;
        Ok(())
    }
}

/// Where [`GuideState::started`] sits in a block.
const STARTED_FLOAT: usize = core::mem::offset_of!(GuideState, started) / 4;
