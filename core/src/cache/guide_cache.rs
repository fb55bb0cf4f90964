//! The per-frame guide cache: one frame's posed guides, at each of its
//! shutter samples, coded so the frame decodes from its own file plus the
//! groom file (never from another frame).
//!
//! Each sample is coded against the neutral pose: a guide's rest shape (from
//! the groom file) carried by its root frame on that sample's deformed mesh
//! (which the renderer has). In the root frame, the offset of each point
//! from its rest position is quantized to steps of `L / 2^14` (L the
//! guide's rest length), so every coordinate decodes within `L / 2^15` (plus
//! the float32 rounding of the coordinate itself). Per axis, the offsets
//! or, when shorter, their differences from the offsets of the guide
//! before in its block (neighbouring guides bend alike: half the bytes of
//! a simulated frame) are predicted along the guide from the two before (a
//! guide bends smoothly), and the prediction errors are Rice-coded with the
//! best parameter per guide and axis: a still guide costs 4 bytes. A guide that
//! cannot be coded so (zero length, an offset past 2^30 steps, a point that
//! could decode past 1e9 by the bound of the coordinates and offsets) is stored as
//! raw float32 root-frame coordinates. The exact mode stores world-space
//! float32 points instead, decoded bit for bit.
//!
//! Guides are grouped in blocks of [`BLOCK`] with a table of byte offsets,
//! so ranges of blocks decode independently (on any threads, the same
//! bits).

use super::bits::{rice_bits, BitReader, BitWriter};
use super::container::{self, product, Reader, Writer};
use super::groom_file::{check_guides, Groom};
use crate::interp::posed::PosedFrame;
use crate::interp::strand::MAX_STRAND_POINTS;
use crate::root::check_root;
use crate::surface::frame::{self, Frame, FRAME_LANES};
use crate::surface::mesh::MAX_COORDINATE;
use crate::{Error, Mesh};
use core::cmp::Ordering;
use glam::Vec3;

/// The file's magic.
pub const MAGIC: [u8; 8] = *b"PLGUIDE\0";
/// The format version this build writes. It reads version 1 too: a
/// version 1 file is a version 2 file that never predicts from a neighbour.
pub const VERSION: u32 = 2;
/// Guides per block of the offset table.
pub const BLOCK: usize = 256;
const FIELDS: usize = 6;
/// Most shutter samples a cache holds.
const MAX_SAMPLES: usize = 255;

/// Quantization steps per guide length.
const STEPS: f64 = 16384.0;
/// Largest quantized offset coded packed.
const MAX_STEPS: i64 = 1 << 30;
/// Largest Rice parameter a file may declare.
const MAX_K: u8 = 40;
/// The parameter byte of an axis whose every error is zero (no bits).
const ZERO: u8 = 0xff;
/// The parameter byte of an axis coded from the guide before it in its
/// block whose every error is zero.
const NEIGHBOUR_ZERO: u8 = 0xfe;
/// Flag of a parameter byte: the axis codes its offsets' difference from
/// those of the guide before it in its block (neighbouring guides bend
/// alike), then the Rice parameter in the low bits.
const NEIGHBOUR: u8 = 0x80;

const PACKED: u8 = 0;
const RAW: u8 = 1;

/// How a cache stores the points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Offsets from the neutral pose, quantized to `L / 2^14` (within
    /// `L / 2^15` per root-frame coordinate).
    Quantized,
    /// World-space float32 points, decoded bit for bit.
    Exact,
}

/// What a cache's checked header says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CacheInfo {
    /// Guides.
    pub guides: usize,
    /// Points per guide.
    pub points: usize,
    /// Shutter samples.
    pub samples: usize,
    /// How the points are stored.
    pub mode: Mode,
    /// The groom file it was coded for (its [`GroomCounts::id`](super::groom_file::GroomCounts::id)).
    pub groom: u32,
}

/// A guide cache's bytes, framing and counts checked.
pub struct GuideCache<'a> {
    info: CacheInfo,
    /// The format version of the bytes: 1 codes no guide from the one
    /// before it.
    version: u32,
    /// `samples * blocks + 1` offsets into `stream`.
    offsets: &'a [u8],
    stream: &'a [u8],
}

/// The rest length of each guide, as coder and decoder both compute it.
fn rest_length(rest: &[[f32; 3]]) -> f32 {
    rest.windows(2)
        .map(|w| Vec3::from(w[1]).distance(Vec3::from(w[0])))
        .sum()
}

/// The quantized offset expected at point `j` from those before it: a
/// guide's offsets from its rest shape grow smoothly from the root, so the
/// second difference along the guide is what is left to code.
/// `q1` and `q2` are the offsets at points `j - 1` and `j - 2`.
#[inline]
fn predict(j: usize, q1: i64, q2: i64) -> i64 {
    match j {
        0 => 0,
        1 => q1,
        _ => q1.wrapping_mul(2).wrapping_sub(q2),
    }
}

fn zigzag(v: i64) -> u64 {
    ((v << 1) ^ (v >> 63)) as u64
}

fn unzigzag(v: u64) -> i64 {
    (v >> 1) as i64 ^ -((v & 1) as i64)
}

/// One guide, coded: a tag, then its Rice parameters and bits, or raw
/// floats.
struct Coded {
    tag: u8,
    ks: [u8; 3],
    errors: [[u64; 64]; 3],
    raw: [[f32; 3]; 64],
    bytes: usize,
    /// The quantized offsets, per axis (packed guides only).
    q: [[i64; 64]; 3],
}

/// The zigzagged second-order errors along the guide of the offsets `q`.
fn errors_of(q: &[i64], errors: &mut [u64]) {
    for j in 0..q.len() {
        let before = |k: usize| if j >= k { q[j - k] } else { 0 };
        errors[j] = zigzag(q[j] - predict(j, before(1), before(2)));
    }
}

/// The parameter byte and bits of the Rice code of `errors` (`zero` for
/// all zero).
fn rice_parameter(errors: &[u64], zero: u8) -> (u8, u64) {
    if errors.iter().all(|&z| z == 0) {
        return (zero, 0);
    }
    let cost = |k: u32| errors.iter().map(|&z| rice_bits(z, k)).sum::<u64>();
    // the best k sits by log2 of the mean (geometric errors)
    let mean = errors.iter().sum::<u64>() / errors.len() as u64;
    let near = (64 - mean.leading_zeros()).min(u32::from(MAX_K));
    let k = (near.saturating_sub(2)..=near)
        .min_by_key(|&k| (cost(k), k))
        .unwrap_or(0);
    (k as u8, cost(k))
}

/// Codes guide `g` of `frame` (its root-frame points) against `rest`; each
/// axis from its own offsets or, when that is shorter, from their
/// difference with `before`'s (the packed guide before it in its block).
fn code(frame: &PosedFrame, g: usize, rest: &[[f32; 3]], before: Option<&Coded>) -> Coded {
    let n = rest.len();
    let mut c = Coded {
        tag: RAW,
        ks: [0; 3],
        errors: [[0; 64]; 3],
        raw: [[0.0; 3]; 64],
        bytes: 1 + 12 * n,
        q: [[0; 64]; 3],
    };
    for (j, r) in c.raw[..n].iter_mut().enumerate() {
        *r = frame.local_point(g, j).to_array();
    }
    let length = f64::from(rest_length(rest));
    if !(length > 0.0 && length.is_finite()) {
        return c;
    }
    let inv = STEPS / length;
    for (j, (raw, rest)) in c.raw[..n].iter().zip(rest).enumerate() {
        for axis in 0..3 {
            let d = (f64::from(raw[axis]) - f64::from(rest[axis])) * inv;
            // NaN fails too
            if d.abs().partial_cmp(&(MAX_STEPS as f64)) != Some(Ordering::Less) {
                return c;
            }
            c.q[axis][j] = libm::round(d) as i64;
        }
    }
    let spread =
        c.q.iter()
            .flat_map(|q| &q[..n])
            .fold(0, |s, q| s.max(q.unsigned_abs()));
    if !fits_packed(rest, spread, length / STEPS) {
        return c;
    }
    let before = before.filter(|b| b.tag == PACKED);
    let mut bits = 0;
    for axis in 0..3 {
        let q = &c.q[axis][..n];
        errors_of(q, &mut c.errors[axis][..n]);
        let (mut k, mut cost) = rice_parameter(&c.errors[axis][..n], ZERO);
        if let Some(b) = before {
            let mut d = [0i64; 64];
            for ((d, &q), &p) in d.iter_mut().zip(q).zip(&b.q[axis]) {
                *d = q - p;
            }
            let mut errors = [0u64; 64];
            errors_of(&d[..n], &mut errors[..n]);
            let (nk, ncost) = rice_parameter(&errors[..n], NEIGHBOUR_ZERO);
            if ncost < cost {
                (k, cost) = (
                    if nk == NEIGHBOUR_ZERO {
                        nk
                    } else {
                        NEIGHBOUR | nk
                    },
                    ncost,
                );
                c.errors[axis] = errors;
            }
        }
        c.ks[axis] = k;
        bits += cost;
    }
    // wild offsets can cost more bits than the floats themselves
    let packed = 4 + bits.div_ceil(8) as usize;
    if packed <= c.bytes {
        c.tag = PACKED;
        c.bytes = packed;
    }
    c
}

fn write_coded(w: &mut Writer, c: &Coded, n: usize) {
    w.u8(c.tag);
    if c.tag == RAW {
        w.words(&c.raw[..n]);
        return;
    }
    for &k in &c.ks {
        w.u8(k);
    }
    let mut bits = BitWriter::new(w);
    for axis in (0..3).filter(|&a| c.ks[a] != ZERO && c.ks[a] != NEIGHBOUR_ZERO) {
        let k = u32::from(c.ks[axis] & !NEIGHBOUR);
        for &z in &c.errors[axis][..n] {
            bits.rice(z, k);
        }
    }
    bits.finish();
}

/// The most bytes [`encode`] writes for `samples` shutter samples (1..=255)
/// of `guides` guides (at least 1) of `points` points (2..=64): every
/// guide stored raw; a typical quantized frame takes a tenth of it.
/// Counts outside those ranges, or a stream past 4 GB (the offsets are
/// u32; counts whose product overflows included), are an
/// [`Error::InvalidArgument`].
pub fn max_encoded_bytes(
    guides: usize,
    points: usize,
    samples: usize,
    mode: Mode,
) -> Result<usize, Error> {
    if guides == 0 || !(2..=MAX_STRAND_POINTS).contains(&points) {
        return Err(Error::InvalidArgument(
            "a cache holds at least 1 guide of 2..=64 points",
        ));
    }
    if !(1..=MAX_SAMPLES).contains(&samples) {
        return Err(Error::InvalidArgument(
            "a cache holds 1..=255 shutter samples",
        ));
    }
    let per_guide = match mode {
        Mode::Exact => 12 * points,
        Mode::Quantized => 1 + 12 * points,
    };
    let stream = samples
        .checked_mul(guides)
        .and_then(|n| n.checked_mul(per_guide))
        .filter(|&n| n <= u32::MAX as usize)
        .ok_or(Error::InvalidArgument("a frame's cache is limited to 4 GB"))?;
    let offsets = 4 * (samples * guides.div_ceil(BLOCK) + 1);
    Ok(container::header_bytes(FIELDS) + offsets + stream)
}

fn check_samples(groom: &Groom, samples: &[&PosedFrame]) -> Result<(), Error> {
    if !(1..=MAX_SAMPLES).contains(&samples.len()) {
        return Err(Error::InvalidArgument(
            "a cache holds 1..=255 shutter samples",
        ));
    }
    for frame in samples {
        if frame.guide_count() != groom.guide_roots.len() || frame.points() != groom.points {
            return Err(Error::InvalidArgument(
                "each sample's frame must hold the groom's guides, at its point count",
            ));
        }
        if !frame.is_posed() {
            return Err(Error::InvalidArgument("a sample's frame has no guides"));
        }
    }
    Ok(())
}

/// Writes one frame's cache into `out` (sized by [`max_encoded_bytes`]):
/// `samples` are the frame's posed frames at its shutter samples (each
/// posed with the groom's guides, at the groom's point count), `groom_id`
/// the groom file's id. Returns the bytes written; on error `out` is
/// untouched.
pub fn encode(
    groom: &Groom,
    groom_id: u32,
    samples: &[&PosedFrame],
    mode: Mode,
    out: &mut [u8],
) -> Result<usize, Error> {
    encode_with_progress(groom, groom_id, samples, mode, out, &mut |_| true)
}

/// Blocks coded between two progress reports.
const BLOCKS_PER_REPORT: usize = 64;

/// [`encode`], calling `progress` with the share of blocks coded (0
/// first, 1 last, every 64 blocks); a false return
/// stops with [`Error::Cancelled`], `out` then holding part of a cache.
pub fn encode_with_progress(
    groom: &Groom,
    groom_id: u32,
    samples: &[&PosedFrame],
    mode: Mode,
    out: &mut [u8],
    progress: &mut dyn FnMut(f32) -> bool,
) -> Result<usize, Error> {
    groom.check()?;
    check_samples(groom, samples)?;
    let (g, n) = (groom.guide_roots.len(), groom.points);
    let most = max_encoded_bytes(g, n, samples.len(), mode)?;
    if out.len() < most {
        return Err(Error::OutputTooSmall {
            needed: most,
            available: out.len(),
        });
    }
    let fields = [
        g as u64,
        n as u64,
        samples.len() as u64,
        (mode == Mode::Exact) as u64,
        u64::from(groom_id),
        BLOCK as u64,
    ];
    if !progress(0.0) {
        return Err(Error::Cancelled);
    }
    let blocks = samples.len() * g.div_ceil(BLOCK);
    let mut cancelled = false;
    let written = container::write(out, &MAGIC, VERSION, &fields, |w| {
        // the offset table, filled in as the stream is written
        let table = w.position();
        for _ in 0..samples.len() * g.div_ceil(BLOCK) + 1 {
            w.u32(0);
        }
        let stream = w.position();
        let mut entry = table;
        // the guide before, in its block
        let mut before: Option<Coded> = None;
        for frame in samples {
            for i in 0..g {
                if i % BLOCK == 0 {
                    let block = (entry - table) / 4;
                    if block % BLOCKS_PER_REPORT == 0 && block > 0 {
                        cancelled = !progress(block as f32 / blocks as f32);
                        if cancelled {
                            return;
                        }
                    }
                    w.patch_u32(entry, (w.position() - stream) as u32);
                    entry += 4;
                    before = None;
                }
                match mode {
                    Mode::Exact => {
                        for j in 0..n {
                            w.words(&[frame.world_point(i, j).to_array()]);
                        }
                    }
                    Mode::Quantized => {
                        let rest = &groom.guide_points[i * n..(i + 1) * n];
                        let coded = code(frame, i, rest, before.as_ref());
                        write_coded(w, &coded, n);
                        before = Some(coded);
                    }
                }
            }
        }
        w.patch_u32(entry, (w.position() - stream) as u32);
    });
    if cancelled || !progress(1.0) {
        return Err(Error::Cancelled);
    }
    Ok(written)
}

impl<'a> GuideCache<'a> {
    /// Checks a cache's framing (magic, version, length, checksum), counts
    /// and offset table.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, Error> {
        let (file, version) = match container::read(bytes, &MAGIC, VERSION, FIELDS) {
            Err(Error::VersionMismatch { found: 1, .. }) => {
                (container::read(bytes, &MAGIC, 1, FIELDS)?, 1)
            }
            file => (file?, VERSION),
        };
        let [guides, points, samples, mode, groom, block, ..] = file.fields;
        let bad = |what| Err(Error::Corrupt { what });
        if guides == 0
            || guides >= u64::from(u32::MAX)
            || !(2..=MAX_STRAND_POINTS as u64).contains(&points)
        {
            return bad("guide or point count");
        }
        if !(1..=MAX_SAMPLES as u64).contains(&samples) || mode > 1 || groom > u64::from(u32::MAX) {
            return bad("sample count, mode or groom id");
        }
        if block != BLOCK as u64 {
            return bad("block size");
        }
        let blocks = product(&[guides.div_ceil(BLOCK as u64), samples])?;
        let table = product(&[blocks as u64 + 1, 4])?;
        if file.payload.len() < table {
            return bad("truncated offset table");
        }
        let (offsets, stream) = file.payload.split_at(table);
        let mut r = Reader::new(offsets);
        let mut last = 0;
        for _ in 0..=blocks {
            let at = r.u32()?;
            if at < last {
                return bad("offset table out of order");
            }
            last = at;
        }
        if last as usize != stream.len() || Reader::new(offsets).u32()? != 0 {
            return bad("offset table does not span the stream");
        }
        Ok(GuideCache {
            info: CacheInfo {
                guides: guides as usize,
                points: points as usize,
                samples: samples as usize,
                mode: if mode == 1 {
                    Mode::Exact
                } else {
                    Mode::Quantized
                },
                groom: groom as u32,
            },
            version,
            offsets,
            stream,
        })
    }

    /// The checked header.
    pub fn info(&self) -> CacheInfo {
        self.info
    }

    fn offset(&self, i: usize) -> usize {
        let b = &self.offsets[4 * i..4 * i + 4];
        u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize
    }

    /// Scratch words [`GuideCache::unpack`] writes per guide: a tag and
    /// three per point.
    pub fn words_per_guide(&self) -> usize {
        1 + 3 * self.info.points
    }

    /// Scratch words one whole sample takes ([`GuideCache::decode`]).
    pub fn scratch_words(&self) -> usize {
        self.info.guides * self.words_per_guide()
    }

    /// Decodes shutter sample `sample` into `frame` (made on that sample's
    /// deformed mesh, for the groom's guide and point counts): every guide,
    /// local and world. `groom` and `groom_id` are the groom file's
    /// contents and id; `scratch` (at least [`GuideCache::scratch_words`]
    /// words) holds the unpacked sample meanwhile. The cache is checked
    /// whole before the frame is written: on error the frame keeps the
    /// guides it had. (A host that decodes on several threads runs the
    /// same steps: [`GuideCache::check`], [`GuideCache::unpack`] over runs
    /// of blocks, then [`GuideCache::decoding`] over any runs of guides.)
    pub fn decode(
        &self,
        groom: &Groom,
        groom_id: u32,
        sample: usize,
        frame: &mut PosedFrame,
        scratch: &mut [u32],
    ) -> Result<(), Error> {
        self.check(groom, groom_id, sample, frame)?;
        let words = scratch
            .get_mut(..self.scratch_words())
            .ok_or(Error::InvalidArgument(
                "the scratch is smaller than the cache's scratch_words",
            ))?;
        self.unpack(groom, sample, 0..self.blocks(), words)?;
        let Decoding {
            filler,
            data,
            posed,
        } = self.decoding(groom, frame);
        filler.fill(0, words, data)?;
        *posed = true;
        Ok(())
    }

    /// Blocks of [`BLOCK`] guides per sample.
    pub fn blocks(&self) -> usize {
        self.info.guides.div_ceil(BLOCK)
    }

    /// Unpacks blocks `blocks` of sample `sample` (a sample
    /// [`GuideCache::check`] accepted) into `scratch`, exactly
    /// [`GuideCache::words_per_guide`] words per guide of those blocks,
    /// checking every tag, Rice parameter, bit, offset and stored point.
    /// Writes nothing but `scratch`.
    pub fn unpack(
        &self,
        groom: &Groom,
        sample: usize,
        blocks: core::ops::Range<usize>,
        scratch: &mut [u32],
    ) -> Result<(), Error> {
        let g = self.info.guides;
        let per = self.words_per_guide();
        let guides = (blocks.end * BLOCK)
            .min(g)
            .saturating_sub(blocks.start * BLOCK);
        if blocks.end > self.blocks() || Some(scratch.len()) != guides.checked_mul(per) {
            return Err(Error::InvalidArgument(
                "unpacked blocks take words_per_guide words per guide",
            ));
        }
        for (b, out) in blocks.zip(scratch.chunks_mut(BLOCK * per)) {
            self.unpack_block(groom, sample, b, out)?;
        }
        Ok(())
    }

    /// The frame's guide slots and a filler that poses unpacked guides
    /// into them, for a host that splits them over threads; [`Decoding::finish`]
    /// marks the frame posed. Unpack first ([`GuideCache::check`],
    /// [`GuideCache::unpack`]).
    pub fn decoding<'r>(&'r self, groom: &'r Groom<'r>, frame: &'r mut PosedFrame) -> Decoding<'r> {
        let (mesh, tangents, data, posed) = frame.slots();
        // half-filled guides are no guides: posed again by finish
        *posed = false;
        Decoding {
            filler: CacheFiller {
                cache: self,
                groom,
                mesh,
                tangents,
            },
            data,
            posed,
        }
    }

    /// Checks that sample `sample` can decode into `frame` for `groom`:
    /// the groom id, the guide and point counts, the sample index, the
    /// guide roots on the frame's mesh, and the rest points.
    pub fn check(
        &self,
        groom: &Groom,
        groom_id: u32,
        sample: usize,
        frame: &PosedFrame,
    ) -> Result<(), Error> {
        let info = &self.info;
        if groom_id != info.groom {
            return Err(Error::InvalidArgument(
                "the cache was coded for another groom file",
            ));
        }
        if groom.guide_roots.len() != info.guides || groom.points != info.points {
            return Err(Error::InvalidArgument(
                "the groom's guide or point count differs from the cache's",
            ));
        }
        if frame.guide_count() != info.guides || frame.points() != info.points {
            return Err(Error::InvalidArgument(
                "the frame's guide or point count differs from the cache's",
            ));
        }
        if sample >= info.samples {
            return Err(Error::InvalidArgument("no such shutter sample"));
        }
        if Some(groom.guide_points.len()) != info.guides.checked_mul(info.points) {
            return Err(Error::InvalidArgument(
                "the groom's rest points must be points per guide times the guide count",
            ));
        }
        let faces = frame.mesh().triangle_count();
        for (i, r) in groom.guide_roots.iter().enumerate() {
            check_root(faces, r, "guide roots").map_err(|e| e.shifted(i))?;
        }
        check_guides(&[], groom.guide_points)
    }

    /// Unpacks block `b` of `sample` into `out` (its guides' words).
    fn unpack_block(
        &self,
        groom: &Groom,
        sample: usize,
        b: usize,
        out: &mut [u32],
    ) -> Result<(), Error> {
        let (g, n) = (self.info.guides, self.info.points);
        let index = sample * self.blocks() + b;
        let (start, end) = (self.offset(index), self.offset(index + 1));
        let mut r = Reader::new(&self.stream[start..end]);
        let first = b * BLOCK;
        // whether the guide before is packed: its offsets are the base of
        // this one's differences
        let mut before = false;
        let mut offsets = [[[0i64; 64]; 3]; 2];
        let guides = first..(first + BLOCK).min(g);
        for (i, words) in guides.zip(out.chunks_exact_mut(self.words_per_guide())) {
            let (tag, lanes) = words.split_at_mut(1);
            let rest = &groom.guide_points[i * n..(i + 1) * n];
            match self.info.mode {
                Mode::Exact => {
                    tag[0] = TAG_WORLD;
                    for j in 0..n {
                        put_bits(lanes, n, j, read_point(&mut r)?);
                    }
                }
                Mode::Quantized => {
                    // the two slots take turns (no copy)
                    let [even, odd] = &mut offsets;
                    let (previous, q) = if i % 2 == 0 { (odd, even) } else { (even, odd) };
                    let before_q = before.then_some(&*previous);
                    before = unpack_guide(&mut r, rest, self.version, before_q, q, tag, lanes)?;
                }
            }
        }
        if r.position() != end - start {
            return Err(Error::Corrupt {
                what: "a block's guides do not fill it",
            });
        }
        Ok(())
    }
}

/// The tag word of an unpacked guide whose points are world-space floats.
const TAG_WORLD: u32 = u32::MAX - 1;
/// The tag word of an unpacked guide whose points are root-frame floats.
/// (A packed guide's tag is its rest length, a finite float's bits.)
const TAG_LOCAL: u32 = u32::MAX;

/// Stores point `j`'s bits in unpacked lanes of `n` points.
fn put_bits(lanes: &mut [u32], n: usize, j: usize, p: Vec3) {
    (lanes[j], lanes[n + j], lanes[2 * n + j]) = (p.x.to_bits(), p.y.to_bits(), p.z.to_bits());
}

fn read_point(r: &mut Reader) -> Result<Vec3, Error> {
    let mut p = [[0.0f32; 3]];
    r.words(&mut p)?;
    if !p[0].iter().all(|c| c.abs() <= MAX_COORDINATE) {
        return Err(Error::Corrupt {
            what: "a stored point is not finite or beyond 1e9",
        });
    }
    Ok(Vec3::from(p[0]))
}

/// Unpacks one guide's record (of a file of format `version`) into its
/// `tag` and `lanes`; `before` holds the quantized offsets of the guide
/// before in the block when that one is packed, and `q` takes this one's.
/// Returns whether it is packed.
fn unpack_guide(
    r: &mut Reader,
    rest: &[[f32; 3]],
    version: u32,
    before: Option<&[[i64; 64]; 3]>,
    q: &mut [[i64; 64]; 3],
    tag: &mut [u32],
    lanes: &mut [u32],
) -> Result<bool, Error> {
    let n = rest.len();
    match r.u8()? {
        RAW => {
            tag[0] = TAG_LOCAL;
            for j in 0..n {
                put_bits(lanes, n, j, read_point(r)?);
            }
            Ok(false)
        }
        PACKED => {
            let mut ks = [0u8; 3];
            for k in ks.iter_mut() {
                *k = r.u8()?;
                if *k & !NEIGHBOUR > MAX_K && *k != ZERO && *k != NEIGHBOUR_ZERO {
                    return Err(Error::Corrupt {
                        what: "a Rice parameter past 40",
                    });
                }
                // version 1 has no such code: a file that claims it and
                // holds one was not written by a version 1 encoder
                if *k & NEIGHBOUR != 0 && *k != ZERO && version < 2 {
                    return Err(Error::Corrupt {
                        what: "a version 1 cache codes a guide from the one before it (version 2 does)",
                    });
                }
                if *k & NEIGHBOUR != 0 && *k != ZERO && before.is_none() {
                    return Err(Error::Corrupt {
                        what: "a guide coded from a guide before it that is not packed",
                    });
                }
            }
            let mut bits = BitReader::new(r.rest());
            let mut spread = 0u64;
            for (axis, &k) in ks.iter().enumerate() {
                let q = &mut q[axis];
                // the offsets the coded ones are differences from
                let base = match before {
                    Some(b) if k & NEIGHBOUR != 0 && k != ZERO => &b[axis],
                    _ => &[0; 64],
                };
                if k == ZERO || k == NEIGHBOUR_ZERO {
                    q[..n].copy_from_slice(&base[..n]);
                    spread = q[..n].iter().fold(spread, |s, q| s.max(q.unsigned_abs()));
                } else {
                    let k = u32::from(k & !NEIGHBOUR);
                    spread = spread.max(rice_axis(&mut bits, k, &base[..n], &mut q[..n])?);
                }
            }
            let length = rest_length(rest);
            if !fits_packed(rest, spread, f64::from(length) / STEPS) {
                return Err(Error::Corrupt {
                    what: "a quantized offset past 2^30 steps or a decoded point beyond 1e9",
                });
            }
            r.take(bits.bytes_used())?;
            tag[0] = length.to_bits();
            for (lane, q) in lanes.chunks_exact_mut(n).zip(q.iter()) {
                for (w, &q) in lane.iter_mut().zip(q) {
                    // within 2^30: an i32
                    *w = q as i32 as u32;
                }
            }
            Ok(true)
        }
        _ => Err(Error::Corrupt {
            what: "a guide's tag is neither packed nor raw",
        }),
    }
}

/// Decodes one axis of a packed guide: its Rice-coded errors (parameter
/// `k`) into the offsets `q`, predicted along the guide as [`predict`]
/// does and added to `base`. Returns the largest offset's magnitude.
#[inline]
fn rice_axis(bits: &mut BitReader, k: u32, base: &[i64], q: &mut [i64]) -> Result<u64, Error> {
    // points 0 and 1 predict from nothing and from one point: peeled, so
    // the loop's prediction has no branch
    let mut d2 = unzigzag(bits.rice(k)?);
    let mut d1 = unzigzag(bits.rice(k)?).wrapping_add(d2);
    q[0] = d2.wrapping_add(base[0]);
    q[1] = d1.wrapping_add(base[1]);
    let mut spread = q[0].unsigned_abs().max(q[1].unsigned_abs());
    for (q, &base) in q.iter_mut().zip(base).skip(2) {
        let d = unzigzag(bits.rice(k)?).wrapping_add(predict(2, d1, d2));
        (d2, d1) = (d1, d);
        *q = d.wrapping_add(base);
        spread = spread.max(q.unsigned_abs());
    }
    Ok(spread)
}

/// Whether a guide with rest points `rest`, offsets of magnitude up to
/// `spread` steps of `step`, may be packed: the offsets stay within 2^30
/// steps and every decoded coordinate within 1e9. Coder and decoder test
/// this one bound per guide (rounding is monotonic, so no point can
/// exceed it), not each point.
fn fits_packed(rest: &[[f32; 3]], spread: u64, step: f64) -> bool {
    // rest points are finite (the groom is checked): no NaN to order
    let reach = rest
        .iter()
        .flatten()
        .fold(0.0f32, |m, c| if c.abs() > m { c.abs() } else { m });
    spread <= MAX_STEPS as u64
        && f64::from(reach) + spread as f64 * step <= f64::from(MAX_COORDINATE)
}

/// A frame being filled from an unpacked cache (see [`GuideCache::decoding`]).
pub struct Decoding<'r> {
    /// Poses runs of unpacked guides.
    pub filler: CacheFiller<'r>,
    /// [`CacheFiller::floats_per_guide`] floats per guide, guide after guide.
    pub data: &'r mut [f32],
    posed: &'r mut bool,
}

impl Decoding<'_> {
    /// Marks the frame posed, once every guide is filled.
    pub fn finish(self) {
        *self.posed = true;
    }
}

/// Poses runs of unpacked guides (see [`Decoding`]).
#[derive(Clone, Copy)]
pub struct CacheFiller<'r> {
    cache: &'r GuideCache<'r>,
    groom: &'r Groom<'r>,
    mesh: &'r Mesh<'r>,
    tangents: &'r [[f32; 3]],
}

impl CacheFiller<'_> {
    /// Floats each guide takes.
    pub fn floats_per_guide(&self) -> usize {
        6 * self.cache.info.points
    }

    /// Poses the guides `first ..` that `part` holds from their words in
    /// `unpacked` (as [`GuideCache::unpack`] wrote them for these guides:
    /// `part`'s guides times [`GuideCache::words_per_guide`]). Any split
    /// into runs gives the same bits.
    pub fn fill(&self, first: usize, unpacked: &[u32], part: &mut [f32]) -> Result<(), Error> {
        let n = self.cache.info.points;
        let (per, words) = (self.floats_per_guide(), self.cache.words_per_guide());
        let guides = part.len() / per;
        if part.len() % per != 0
            || first + guides > self.cache.info.guides
            || unpacked.len() != guides * words
        {
            return Err(Error::InvalidArgument(
                "a filled run takes the unpacked words of its guides",
            ));
        }
        // frames a block at a time (their square-root chains overlap)
        let (mut frames, mut basis) = ([Frame::default(); FRAME_LANES], None);
        let slots = part.chunks_exact_mut(per).zip(unpacked.chunks_exact(words));
        for (i, (slot, words)) in slots.enumerate() {
            let g = first + i;
            if i % FRAME_LANES == 0 {
                let roots = &self.groom.guide_roots[g..];
                frame::frames(self.mesh, self.tangents, roots, &mut basis, &mut frames);
            }
            let frame = &frames[i % FRAME_LANES];
            let rest = &self.groom.guide_points[g * n..(g + 1) * n];
            let (local, world) = slot.split_at_mut(3 * n);
            let lanes = &words[1..];
            match words[0] {
                TAG_WORLD => {
                    for j in 0..n {
                        let p = Vec3::new(
                            f32::from_bits(lanes[j]),
                            f32::from_bits(lanes[n + j]),
                            f32::from_bits(lanes[2 * n + j]),
                        );
                        let l = frame.to_local(p);
                        (local[j], local[n + j], local[2 * n + j]) = (l.x, l.y, l.z);
                        (world[j], world[n + j], world[2 * n + j]) = (p.x, p.y, p.z);
                    }
                    continue;
                }
                TAG_LOCAL => {
                    for (l, &w) in local.iter_mut().zip(lanes) {
                        *l = f32::from_bits(w);
                    }
                }
                length => {
                    let step = f64::from(f32::from_bits(length)) / STEPS;
                    let lanes = local.chunks_exact_mut(n).zip(lanes.chunks_exact(n));
                    for (axis, (lane, q)) in lanes.enumerate() {
                        for ((l, &q), rest) in lane.iter_mut().zip(q).zip(rest) {
                            *l = (f64::from(rest[axis]) + f64::from(q as i32) * step) as f32;
                        }
                    }
                }
            }
            for j in 0..n {
                let p = frame.to_world(Vec3::new(local[j], local[n + j], local[2 * n + j]));
                (world[j], world[n + j], world[2 * n + j]) = (p.x, p.y, p.z);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
