//! The per-frame guide cache: one frame's posed guides, at each of its
//! shutter samples, coded so the frame decodes from its own file plus the
//! groom file (never from another frame).
//!
//! Each sample is coded against the neutral pose: a guide's rest shape (from
//! the groom file) carried by its root frame on that sample's deformed mesh
//! (which the renderer has). In the root frame, the offset of each point
//! from its rest position is quantized to steps of `L / 2^14` (L the
//! guide's rest length), so every coordinate decodes within `L / 2^15` (plus
//! the float32 rounding of the coordinate itself). Along the guide the
//! quantized offsets are predicted from the two before (a guide bends
//! smoothly), and the prediction errors are bit-packed at the smallest
//! width per guide and axis: a still guide costs 4 bytes. A guide that
//! cannot be coded so (zero length, an offset past 2^30 steps) is stored as
//! raw float32 root-frame coordinates. The exact mode stores world-space
//! float32 points instead, decoded bit for bit.
//!
//! Guides are grouped in blocks of [`BLOCK`] with a table of byte offsets,
//! so ranges of blocks decode independently (on any threads, the same
//! bits).

use super::container::{self, product, Reader, Writer};
use super::groom_file::Groom;
use crate::interp::posed::PosedFrame;
use crate::root::check_root;
use crate::surface::frame::Frame;
use crate::surface::mesh::MAX_COORDINATE;
use crate::{Error, Mesh};
use glam::Vec3;

/// The file's magic.
pub const MAGIC: [u8; 8] = *b"PLGUIDE\0";
/// The format version this build writes and reads.
pub const VERSION: u32 = 1;
/// Guides per block of the offset table.
pub const BLOCK: usize = 256;
const FIELDS: usize = 6;

/// Quantization steps per guide length.
const STEPS: f64 = 16384.0;
/// Largest quantized offset coded packed.
const MAX_STEPS: i64 = 1 << 30;
/// Widest packed field a file may declare.
const MAX_WIDTH: u8 = 40;

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

fn zigzag(v: i64) -> u64 {
    ((v << 1) ^ (v >> 63)) as u64
}

fn unzigzag(v: u64) -> i64 {
    (v >> 1) as i64 ^ -((v & 1) as i64)
}

/// Bytes a packed guide of `n` points with these widths takes.
fn packed_bytes(n: usize, widths: [u8; 3]) -> usize {
    4 + (n * widths.iter().map(|&w| w as usize).sum::<usize>()).div_ceil(8)
}

/// One guide, coded: a tag, then its widths and bits, or raw floats.
struct Coded {
    tag: u8,
    widths: [u8; 3],
    errors: [[u64; 64]; 3],
    raw: [[f32; 3]; 64],
}

/// Codes guide `g` of `frame` (its root-frame points) against `rest`.
fn code(frame: &PosedFrame, g: usize, rest: &[[f32; 3]]) -> Coded {
    let n = rest.len();
    let mut c = Coded {
        tag: RAW,
        widths: [0; 3],
        errors: [[0; 64]; 3],
        raw: [[0.0; 3]; 64],
    };
    for (j, r) in c.raw[..n].iter_mut().enumerate() {
        *r = frame.local_point(g, j).to_array();
    }
    let length = f64::from(rest_length(rest));
    if !(length > 0.0 && length.is_finite()) {
        return c;
    }
    let inv = STEPS / length;
    for axis in 0..3 {
        let mut q = [0i64; 64];
        for ((q, raw), rest) in q.iter_mut().zip(&c.raw[..n]).zip(rest) {
            let d = (f64::from(raw[axis]) - f64::from(rest[axis])) * inv;
            // NaN fails too
            if d.abs().partial_cmp(&(MAX_STEPS as f64)) != Some(core::cmp::Ordering::Less) {
                return c;
            }
            *q = libm::round(d) as i64;
        }
        let mut widest = 0;
        for j in 0..n {
            let predicted = match j {
                0 => 0,
                1 => q[0],
                _ => 2 * q[j - 1] - q[j - 2],
            };
            let e = zigzag(q[j] - predicted);
            c.errors[axis][j] = e;
            widest |= e;
        }
        c.widths[axis] = (64 - widest.leading_zeros()) as u8;
    }
    c.tag = PACKED;
    c
}

fn coded_bytes(c: &Coded, n: usize) -> usize {
    match c.tag {
        PACKED => packed_bytes(n, c.widths),
        _ => 1 + 12 * n,
    }
}

fn write_coded(w: &mut Writer, c: &Coded, n: usize) {
    w.u8(c.tag);
    if c.tag == RAW {
        w.words(&c.raw[..n]);
        return;
    }
    for &width in &c.widths {
        w.u8(width);
    }
    let (mut acc, mut bits) = (0u128, 0u32);
    for axis in 0..3 {
        let width = u32::from(c.widths[axis]);
        for &e in &c.errors[axis][..n] {
            acc |= u128::from(e) << bits;
            bits += width;
            while bits >= 8 {
                w.u8(acc as u8);
                acc >>= 8;
                bits -= 8;
            }
        }
    }
    if bits > 0 {
        w.u8(acc as u8);
    }
}

/// Bytes [`encode`] writes for these samples.
pub fn encoded_bytes(groom: &Groom, samples: &[&PosedFrame], mode: Mode) -> Result<usize, Error> {
    check_samples(groom, samples)?;
    let (g, n) = (groom.guide_roots.len(), groom.points);
    let stream = match mode {
        Mode::Exact => product(&[samples.len() as u64, g as u64, n as u64, 12])?,
        Mode::Quantized => {
            let mut total = 0usize;
            for frame in samples {
                for i in 0..g {
                    let rest = &groom.guide_points[i * n..(i + 1) * n];
                    total += coded_bytes(&code(frame, i, rest), n);
                }
            }
            total
        }
    };
    let offsets = 4 * (samples.len() * g.div_ceil(BLOCK) + 1);
    if stream > u32::MAX as usize {
        return Err(Error::InvalidArgument("a frame's cache is limited to 4 GB"));
    }
    Ok(container::header_bytes(FIELDS) + offsets + stream)
}

fn check_samples(groom: &Groom, samples: &[&PosedFrame]) -> Result<(), Error> {
    if samples.is_empty() || samples.len() > 255 {
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

/// Writes one frame's cache: `samples` are the frame's posed frames at its
/// shutter samples (each posed with the groom's guides, at the groom's
/// point count), `groom_id` the groom file's id. Returns the bytes written
/// ([`encoded_bytes`]); on error `out` is untouched.
pub fn encode(
    groom: &Groom,
    groom_id: u32,
    samples: &[&PosedFrame],
    mode: Mode,
    out: &mut [u8],
) -> Result<usize, Error> {
    groom.check()?;
    let total = encoded_bytes(groom, samples, mode)?;
    if out.len() < total {
        return Err(Error::OutputTooSmall {
            needed: total,
            available: out.len(),
        });
    }
    let (g, n) = (groom.guide_roots.len(), groom.points);
    let fields = [
        g as u64,
        n as u64,
        samples.len() as u64,
        (mode == Mode::Exact) as u64,
        u64::from(groom_id),
        BLOCK as u64,
    ];
    container::write(&mut out[..total], &MAGIC, VERSION, &fields, |w| {
        // offsets first (sizes only), then the stream
        let mut at = 0u32;
        for frame in samples {
            for i in 0..g {
                if i % BLOCK == 0 {
                    w.u32(at);
                }
                at += match mode {
                    Mode::Exact => 12 * n as u32,
                    Mode::Quantized => {
                        let rest = &groom.guide_points[i * n..(i + 1) * n];
                        coded_bytes(&code(frame, i, rest), n) as u32
                    }
                };
            }
        }
        w.u32(at);
        for frame in samples {
            for i in 0..g {
                match mode {
                    Mode::Exact => {
                        for j in 0..n {
                            let p = frame.world_point(i, j);
                            w.words(&[p.to_array()]);
                        }
                    }
                    Mode::Quantized => {
                        let rest = &groom.guide_points[i * n..(i + 1) * n];
                        write_coded(w, &code(frame, i, rest), n);
                    }
                }
            }
        }
    });
    Ok(total)
}

impl<'a> GuideCache<'a> {
    /// Checks a cache's framing (magic, version, length, checksum), counts
    /// and offset table.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, Error> {
        let file = container::read(bytes, &MAGIC, VERSION, FIELDS)?;
        let [guides, points, samples, mode, groom, block, ..] = file.fields;
        let bad = |what| Err(Error::Corrupt { what });
        if guides == 0 || guides >= u64::from(u32::MAX) || !(2..=64).contains(&points) {
            return bad("guide or point count");
        }
        if !(1..=255).contains(&samples) || mode > 1 || groom > u64::from(u32::MAX) {
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

    /// Decodes shutter sample `sample` into `frame` (made on that sample's
    /// deformed mesh, for the groom's guide and point counts): every guide,
    /// local and world. `groom` and `groom_id` are the groom file's
    /// contents and id. The cache is decoded whole before the frame is
    /// written: on error the frame keeps the guides it had.
    pub fn decode(
        &self,
        groom: &Groom,
        groom_id: u32,
        sample: usize,
        frame: &mut PosedFrame,
    ) -> Result<(), Error> {
        self.check_target(groom, groom_id, sample, frame)?;
        let blocks = self.info.guides.div_ceil(BLOCK);
        // a dry run over the stream catches corrupt guides before any write
        {
            let (mesh, tangents, _, _) = frame.slots();
            let mut scratch = [0.0f32; 6 * 64];
            for b in 0..blocks {
                self.decode_block(groom, mesh, tangents, sample, b, &mut scratch, true)?;
            }
        }
        let (mesh, tangents, data, posed) = frame.slots();
        let per = 6 * self.info.points;
        for (b, part) in data.chunks_mut(BLOCK * per).enumerate() {
            self.decode_block(groom, mesh, tangents, sample, b, part, false)?;
        }
        *posed = true;
        Ok(())
    }

    fn check_target(
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
        let faces = frame.mesh().triangle_count();
        for (i, r) in groom.guide_roots.iter().enumerate() {
            check_root(faces, r, "guide roots").map_err(|e| e.shifted(i))?;
        }
        Ok(())
    }

    /// Decodes block `b` of `sample` into `out` (its guides' slots), or
    /// only checks it (`dry`: `out` holds one guide's slot, rewritten).
    #[allow(clippy::too_many_arguments)]
    fn decode_block(
        &self,
        groom: &Groom,
        mesh: &Mesh,
        tangents: &[[f32; 3]],
        sample: usize,
        b: usize,
        out: &mut [f32],
        dry: bool,
    ) -> Result<(), Error> {
        let (g, n) = (self.info.guides, self.info.points);
        let blocks = g.div_ceil(BLOCK);
        let index = sample * blocks + b;
        let (start, end) = (self.offset(index), self.offset(index + 1));
        let mut r = Reader::new(&self.stream[start..end]);
        let first = b * BLOCK;
        for i in first..(first + BLOCK).min(g) {
            let slot = if dry {
                &mut out[..6 * n]
            } else {
                &mut out[(i - first) * 6 * n..(i - first + 1) * 6 * n]
            };
            let root = &groom.guide_roots[i];
            let frame = Frame::at(mesh, tangents, root.face as usize, root.u, root.v);
            let rest = &groom.guide_points[i * n..(i + 1) * n];
            let (local, world) = slot.split_at_mut(3 * n);
            match self.info.mode {
                Mode::Exact => {
                    for j in 0..n {
                        let p = read_point(&mut r)?;
                        let l = frame.to_local(p);
                        put(local, world, n, j, l, p);
                    }
                }
                Mode::Quantized => decode_guide(&mut r, &frame, rest, local, world)?,
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

fn put(local: &mut [f32], world: &mut [f32], n: usize, j: usize, l: Vec3, p: Vec3) {
    (local[j], local[n + j], local[2 * n + j]) = (l.x, l.y, l.z);
    (world[j], world[n + j], world[2 * n + j]) = (p.x, p.y, p.z);
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

fn decode_guide(
    r: &mut Reader,
    frame: &Frame,
    rest: &[[f32; 3]],
    local: &mut [f32],
    world: &mut [f32],
) -> Result<(), Error> {
    let n = rest.len();
    match r.u8()? {
        RAW => {
            for j in 0..n {
                let l = read_point(r)?;
                put(local, world, n, j, l, frame.to_world(l));
            }
            Ok(())
        }
        PACKED => {
            let mut widths = [0u8; 3];
            for w in widths.iter_mut() {
                *w = r.u8()?;
                if *w > MAX_WIDTH {
                    return Err(Error::Corrupt {
                        what: "a packed width past 40 bits",
                    });
                }
            }
            let bits = r.take(packed_bytes(n, widths) - 4)?;
            let step = f64::from(rest_length(rest)) / STEPS;
            let (mut acc, mut have, mut next) = (0u128, 0u32, 0usize);
            for axis in 0..3 {
                let width = u32::from(widths[axis]);
                let mask = (1u128 << width) - 1;
                let (mut q1, mut q2) = (0i64, 0i64);
                for j in 0..n {
                    while have < width {
                        acc |= u128::from(bits[next]) << have;
                        next += 1;
                        have += 8;
                    }
                    let e = unzigzag((acc & mask) as u64);
                    acc >>= width;
                    have -= width;
                    let predicted = match j {
                        0 => 0,
                        1 => q1,
                        _ => q1.wrapping_mul(2).wrapping_sub(q2),
                    };
                    let q = e.wrapping_add(predicted);
                    if !(-MAX_STEPS..=MAX_STEPS).contains(&q) {
                        return Err(Error::Corrupt {
                            what: "a quantized offset past 2^30 steps",
                        });
                    }
                    (q2, q1) = (q1, q);
                    local[axis * n + j] = (f64::from(rest[j][axis]) + q as f64 * step) as f32;
                }
            }
            for j in 0..n {
                let l = Vec3::new(local[j], local[n + j], local[2 * n + j]);
                let p = frame.to_world(l);
                (world[j], world[n + j], world[2 * n + j]) = (p.x, p.y, p.z);
            }
            Ok(())
        }
        _ => Err(Error::Corrupt {
            what: "a guide's tag is neither packed nor raw",
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::fixture::{Scene, POINTS};

    const GROOM_ID: u32 = 77;

    fn write(groom: &Groom, samples: &[&PosedFrame], mode: Mode) -> Vec<u8> {
        let mut out = vec![0u8; encoded_bytes(groom, samples, mode).unwrap()];
        assert_eq!(
            encode(groom, GROOM_ID, samples, mode, &mut out),
            Ok(out.len())
        );
        out
    }

    /// The scene posed at `t0` and `t1`: the cache of both samples, and a
    /// check run on each source frame.
    fn two_samples(
        scene: &Scene,
        (t0, t1): (f32, f32),
        mode: Mode,
        mut check: impl FnMut(&[u8], usize, &PosedFrame, &crate::testmesh::TestMesh),
    ) {
        let (m0, w0) = scene.posed(t0);
        let (m1, w1) = scene.posed(t1);
        scene.with_frame(&m0, &w0, |f0| {
            scene.with_frame(&m1, &w1, |f1| {
                let bytes = write(&scene.groom(), &[f0, f1], mode);
                check(&bytes, 0, f0, &m0);
                check(&bytes, 1, f1, &m1);
            })
        });
    }

    #[test]
    fn quantized_samples_decode_within_the_bound() {
        let scene = Scene::new(600);
        let groom = scene.groom();
        let mut worst = 0.0f32;
        two_samples(
            &scene,
            (0.8, 1.0),
            Mode::Quantized,
            |bytes, s, source, mesh| {
                let cache = GuideCache::parse(bytes).unwrap();
                assert_eq!(cache.info().samples, 2);
                // decoded into a frame of the sample's mesh, posed with other guides
                let (_, other) = scene.posed(0.3);
                scene.with_frame(mesh, &other, |f| {
                    cache.decode(&groom, GROOM_ID, s, f).unwrap();
                    for g in 0..f.guide_count() {
                        let rest = &groom.guide_points[g * POINTS..(g + 1) * POINTS];
                        let bound = rest_length(rest) / 32768.0;
                        for j in 0..POINTS {
                            let (a, b) = (f.local_point(g, j), source.local_point(g, j));
                            let err = (a - b).abs().max_element();
                            let ulp = b.abs().max_element() * f32::EPSILON;
                            assert!(err <= bound + ulp, "guide {g} point {j}: {err} > {bound}");
                            worst = worst.max(err / bound);
                            assert!(f.world_point(g, j).is_finite());
                        }
                    }
                });
            },
        );
        // the bound is reached, not far above what rounding gives
        assert!(worst > 0.9, "{worst}");
    }

    #[test]
    fn exact_samples_decode_bit_for_bit() {
        let scene = Scene::new(300);
        let groom = scene.groom();
        two_samples(&scene, (0.5, 1.0), Mode::Exact, |bytes, s, source, mesh| {
            let cache = GuideCache::parse(bytes).unwrap();
            let (_, other) = scene.posed(0.1);
            scene.with_frame(mesh, &other, |f| {
                cache.decode(&groom, GROOM_ID, s, f).unwrap();
                for g in 0..f.guide_count() {
                    for j in 0..POINTS {
                        assert_eq!(f.world_point(g, j), source.world_point(g, j));
                        assert_eq!(f.local_point(g, j), source.local_point(g, j));
                    }
                }
            });
        });
    }

    #[test]
    fn a_guide_at_its_neutral_pose_costs_four_bytes() {
        let scene = Scene::new(300);
        let groom = scene.groom();
        scene.with_frame(&scene.rest, &scene.guide_world, |f| {
            let bytes = write(&groom, &[f], Mode::Quantized);
            let g = f.guide_count();
            let table = 4 * (g.div_ceil(BLOCK) + 1);
            assert_eq!(bytes.len(), container::header_bytes(FIELDS) + table + 4 * g);
        });
    }

    #[test]
    fn damaged_caches_are_refused_and_the_frame_kept() {
        let scene = Scene::new(300);
        let groom = scene.groom();
        two_samples(
            &scene,
            (0.2, 0.9),
            Mode::Quantized,
            |bytes, s, source, mesh| {
                if s == 1 {
                    return;
                }
                let (_, other) = scene.posed(0.5);
                scene.with_frame(mesh, &other, |f| {
                    let before: Vec<_> = (0..f.guide_count() * POINTS)
                        .map(|k| f.world_point(k / POINTS, k % POINTS))
                        .collect();
                    let kept = |f: &PosedFrame| {
                        (0..f.guide_count() * POINTS)
                            .all(|k| f.world_point(k / POINTS, k % POINTS) == before[k])
                    };
                    let mut decode = |b: &[u8]| {
                        GuideCache::parse(b).and_then(|c| c.decode(&groom, GROOM_ID, 0, f))
                    };
                    for len in (0..bytes.len()).step_by(7) {
                        assert!(decode(&bytes[..len]).is_err(), "truncated to {len}");
                    }
                    for at in (0..bytes.len()).step_by(13) {
                        let mut bad = bytes.to_vec();
                        bad[at] ^= 0x04;
                        assert!(decode(&bad).is_err(), "bit flipped at {at}");
                    }
                    // a width past 40 bits and a bad tag, sealed with a valid CRC
                    let stream = container::header_bytes(FIELDS) + 4 * (2 * 2 + 1);
                    for (at, value) in [(stream + 1, 41u8), (stream, 9)] {
                        let mut bad = bytes.to_vec();
                        bad[at] = value;
                        let crc_at = container::header_bytes(FIELDS) - 8;
                        let mut h = crc32fast::Hasher::new();
                        h.update(&bad[..crc_at]);
                        h.update(&bad[crc_at + 8..]);
                        let crc = h.finalize().to_le_bytes();
                        bad[crc_at..crc_at + 4].copy_from_slice(&crc);
                        assert!(matches!(decode(&bad), Err(Error::Corrupt { .. })));
                    }
                    let cache = GuideCache::parse(bytes).unwrap();
                    assert!(matches!(
                        cache.decode(&groom, GROOM_ID + 1, 0, f),
                        Err(Error::InvalidArgument(_))
                    ));
                    assert!(matches!(
                        cache.decode(&groom, GROOM_ID, 2, f),
                        Err(Error::InvalidArgument(_))
                    ));
                    assert!(kept(f));
                    cache.decode(&groom, GROOM_ID, 0, f).unwrap();
                    assert!(!kept(f));
                    let err = (f.world_point(5, 3) - source.world_point(5, 3)).length();
                    assert!(err < 1e-4, "{err}");
                });
            },
        );
    }
}
