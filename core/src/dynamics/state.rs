//! A guide's state across steps, and the simulation's state file.
//!
//! Each guide owns one block of floats: its [`GuideState`] record, then
//! its posed points in its root frame. A step's phases write the blocks
//! of the guides they are given; the state file holds every block, so a
//! restored simulation reads the posed guides of the step it was saved
//! after and goes on with the same bits as an uninterrupted run.

use crate::cache::container::{self, Reader};
use crate::interp::posed::MAX_ORIGIN;
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
/// Header fields: guides, joints, points, the fingerprint, stepped, and
/// the origin's three doubles (their bits).
const FIELDS: usize = 8;

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

/// What a state file holds besides its blocks.
#[derive(Clone, Copy, PartialEq)]
pub(super) struct StateHeader {
    /// Guides, joints per guide, points per posed guide.
    pub(super) counts: [u64; 3],
    /// Of the simulation's inputs ([`Fingerprint`]).
    pub(super) fingerprint: u64,
    /// A step had run: the blocks hold posed guides.
    pub(super) stepped: bool,
    /// The origin the blocks' positions are relative to.
    pub(super) origin: [f64; 3],
}

/// Bytes a state file of `blocks` takes.
pub(super) fn state_file_bytes(blocks: &[f32]) -> usize {
    container::header_bytes(FIELDS) + blocks.len() * 4
}

/// Writes a state file of `header` and `blocks` to `out`, which holds at
/// least [`state_file_bytes`]; returns the bytes written.
pub(super) fn write_state(out: &mut [u8], header: StateHeader, blocks: &[f32]) -> usize {
    let [guides, joints, points] = header.counts;
    let fields = [
        guides,
        joints,
        points,
        header.fingerprint,
        header.stepped as u64,
        header.origin[0].to_bits(),
        header.origin[1].to_bits(),
        header.origin[2].to_bits(),
    ];
    let needed = state_file_bytes(blocks);
    container::write(&mut out[..needed], MAGIC, STATE_VERSION, &fields, |w| {
        w.words(blocks)
    })
}

/// Reads a state file into `blocks` (guide after guide, `blocks.len()` /
/// guides floats each) when its framing, counts, fingerprint and values
/// are those `expected` has and sound, returning whether a step had run
/// and the origin; on error `blocks` is unchanged.
pub(super) fn read_state(
    bytes: &[u8],
    expected: StateHeader,
    blocks: &mut [f32],
) -> Result<(bool, [f64; 3]), Error> {
    let file = container::read(bytes, MAGIC, STATE_VERSION, FIELDS)?;
    let [guides, joints, points, fingerprint, stepped, x, y, z, ..] = file.fields;
    let origin = [x, y, z].map(f64::from_bits);
    if origin
        .iter()
        .any(|c| !c.is_finite() || c.abs() > MAX_ORIGIN)
    {
        return Err(Error::Corrupt {
            what: "state's origin is not finite or beyond 1e15",
        });
    }
    if [guides, joints, points] != expected.counts {
        return Err(Error::InvalidArgument(
            "the state is of another guide set (guide, joint or point count)",
        ));
    }
    if fingerprint != expected.fingerprint {
        return Err(Error::InvalidArgument(
            "the state was saved by a simulation of other rest guides, roots, maps or parameters",
        ));
    }
    if stepped > 1 {
        return Err(Error::Corrupt {
            what: "state's stepped field is neither 0 nor 1",
        });
    }
    if file.payload.len() != blocks.len() * 4 {
        return Err(Error::Corrupt {
            what: "state payload does not match its counts",
        });
    }
    let per = blocks.len() / guides.max(1) as usize;
    let mut r = Reader::new(file.payload);
    let mut sound = true;
    for k in 0..blocks.len() {
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
    Reader::new(file.payload).words(blocks)?;
    Ok((stepped == 1, origin))
}

/// Where [`GuideState::started`] sits in a block.
const STARTED_FLOAT: usize = core::mem::offset_of!(GuideState, started) / 4;
