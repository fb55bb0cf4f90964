//! The groom file: written once per asset, read by every render of it.
//!
//! It holds what a renderer needs besides one frame's guides and deformed
//! mesh: the guides' roots and rest shapes (in their root frames: the
//! neutral pose a guide cache is coded against), and every render strand's
//! root, binding and groom record, and the patch table. Header fields:
//! guide count, points per guide, strand count, patch count. Payload, in
//! order: guide roots (20 bytes each), guide rest points (12 bytes each,
//! `points` per guide), strand roots, bindings (72 bytes), grooms (44
//! bytes), patches (8 bytes); every field a little-endian u32 or f32
//! (`docs/FORMAT.md`).

use super::container::{self, product, Reader, Writer};
use crate::interp::bind::StrandBinding;
use crate::interp::groom::StrandGroom;
use crate::interp::patch::Patch;
use crate::interp::strand::MAX_STRAND_POINTS;
use crate::interp::strands::{StrandBounds, Strands};
use crate::root::check_root;
use crate::surface::mesh::MAX_COORDINATE;
use crate::{Error, Root};
use core::mem::size_of;

/// The file's magic.
pub const MAGIC: [u8; 8] = *b"PLGROOM\0";
/// The format version this build writes and reads.
pub const VERSION: u32 = 1;
const FIELDS: usize = 4;

/// A groom, borrowed: what [`encode`] writes and [`decode`] fills.
#[derive(Clone, Copy, Debug)]
pub struct Groom<'a> {
    /// Where each guide grows.
    pub guide_roots: &'a [Root],
    /// Each guide's rest shape in its root frame (`points` per guide, root
    /// first): the neutral pose.
    pub guide_points: &'a [[f32; 3]],
    /// Points per guide (2..=64).
    pub points: usize,
    /// The render strands.
    pub strands: Strands<'a>,
    /// The strands' patches (contiguous ranges covering every strand, in
    /// order; see [`interp::patch`](crate::interp::patch)), or none.
    pub patches: &'a [Patch],
}

/// The buffers [`decode`] fills (each at least as long as the file needs).
pub struct GroomBuffers<'a> {
    /// Guide roots.
    pub guide_roots: &'a mut [Root],
    /// Guide rest points, `points` per guide.
    pub guide_points: &'a mut [[f32; 3]],
    /// Strand roots.
    pub roots: &'a mut [Root],
    /// Strand bindings.
    pub bindings: &'a mut [StrandBinding],
    /// Strand groom records.
    pub grooms: &'a mut [StrandGroom],
    /// Patches.
    pub patches: &'a mut [Patch],
}

/// The counts a groom file holds, read from its checked header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GroomCounts {
    /// Guides.
    pub guides: usize,
    /// Points per guide.
    pub points: usize,
    /// Render strands.
    pub strands: usize,
    /// Patches.
    pub patches: usize,
    /// The file's CRC-32: a guide cache names the groom it was coded for
    /// by it.
    pub id: u32,
}

const ROOT: usize = size_of::<Root>();
const POINT: usize = 12;
const BINDING: usize = size_of::<StrandBinding>();
const GROOM: usize = size_of::<StrandGroom>();
const PATCH: usize = size_of::<Patch>();

fn payload_bytes(guides: usize, points: usize, strands: usize, patches: usize) -> Option<usize> {
    let g = guides.checked_mul(ROOT + points.checked_mul(POINT)?)?;
    let s = strands.checked_mul(ROOT + BINDING + GROOM)?;
    g.checked_add(s)?.checked_add(patches.checked_mul(PATCH)?)
}

/// Checks that `patches` (if any) cut `strands` strands into contiguous,
/// non-empty ranges, in order.
fn check_patches(patches: &[Patch], strands: usize) -> Result<(), Error> {
    if patches.is_empty() {
        return Ok(());
    }
    let mut next = 0u64;
    for (i, p) in patches.iter().enumerate() {
        if u64::from(p.first) != next || p.count == 0 {
            return Err(Error::OutOfDomain {
                what: "patches (contiguous, non-empty, in order)",
                index: i,
            });
        }
        next += u64::from(p.count);
    }
    if next != strands as u64 {
        return Err(Error::InvalidArgument("patches must cover every strand"));
    }
    Ok(())
}

impl<'a> Groom<'a> {
    /// The guides alone, without strands or patches: what a guide cache is
    /// coded against.
    pub fn of_guides(guide_roots: &'a [Root], guide_points: &'a [[f32; 3]], points: usize) -> Self {
        Groom {
            guide_roots,
            guide_points,
            points,
            strands: Strands {
                roots: &[],
                bindings: &[],
                grooms: &[],
            },
            patches: &[],
        }
    }

    /// Checks the groom: guide and point counts, finite rest points within
    /// the coordinate range, roots inside their triangles, and every strand
    /// record (as expansion checks it) naming only these guides.
    pub fn check(&self) -> Result<(), Error> {
        if self.guide_roots.is_empty() {
            return Err(Error::InvalidArgument("no guides"));
        }
        if !(2..=MAX_STRAND_POINTS).contains(&self.points) {
            return Err(Error::InvalidArgument("points per guide must be in 2..=64"));
        }
        if Some(self.guide_points.len()) != self.guide_roots.len().checked_mul(self.points) {
            return Err(Error::InvalidArgument(
                "guide points must be points per guide times the guide count",
            ));
        }
        check_guides(self.guide_roots, self.guide_points)?;
        check_patches(self.patches, self.strands.len())?;
        StrandBounds::new(&self.strands)?.fits(u32::MAX as usize, self.guide_roots.len())
    }

    /// Bytes [`encode`] writes for this groom.
    pub fn encoded_bytes(&self) -> Result<usize, Error> {
        payload_bytes(
            self.guide_roots.len(),
            self.points,
            self.strands.len(),
            self.patches.len(),
        )
        .and_then(|p| p.checked_add(container::header_bytes(FIELDS)))
        .ok_or(Error::InvalidArgument("groom too large"))
    }
}

/// Checks guide roots (inside their triangles) and rest points (finite,
/// within 1e9).
pub(crate) fn check_guides(roots: &[Root], points: &[[f32; 3]]) -> Result<(), Error> {
    for (i, r) in roots.iter().enumerate() {
        check_root(u32::MAX as usize, r, "guide roots").map_err(|e| e.shifted(i))?;
    }
    for (i, p) in points.iter().enumerate() {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(Error::NonFinite {
                what: "guide rest points",
                index: i,
            });
        }
        if !p.iter().all(|c| c.abs() <= MAX_COORDINATE) {
            return Err(Error::OutOfDomain {
                what: "guide rest points (within 1e9)",
                index: i,
            });
        }
    }
    Ok(())
}

/// Checks `groom` and writes it as a groom file into `out`; returns the
/// bytes written ([`Groom::encoded_bytes`]). On error `out` is untouched.
pub fn encode(groom: &Groom, out: &mut [u8]) -> Result<usize, Error> {
    groom.check()?;
    let n = groom.encoded_bytes()?;
    if out.len() < n {
        return Err(Error::OutputTooSmall {
            needed: n,
            available: out.len(),
        });
    }
    let s = groom.strands.len();
    let fields = [
        groom.guide_roots.len() as u64,
        groom.points as u64,
        s as u64,
        groom.patches.len() as u64,
    ];
    let written = container::write(&mut out[..n], &MAGIC, VERSION, &fields, |w: &mut Writer| {
        w.words(groom.guide_roots);
        w.words(groom.guide_points);
        w.words(&groom.strands.roots[..s]);
        w.words(&groom.strands.bindings[..s]);
        w.words(&groom.strands.grooms[..s]);
        w.words(groom.patches);
    });
    debug_assert_eq!(written, n);
    Ok(n)
}

/// Reads the header of a groom file and checks its framing (magic,
/// version, length, checksum) and counts.
pub fn counts(bytes: &[u8]) -> Result<GroomCounts, Error> {
    Ok(parse(bytes)?.0)
}

fn parse(bytes: &[u8]) -> Result<(GroomCounts, &[u8]), Error> {
    let file = container::read(bytes, &MAGIC, VERSION, FIELDS)?;
    let [guides, points, strands, patches, ..] = file.fields;
    if guides == 0 || !(2..=MAX_STRAND_POINTS as u64).contains(&points) {
        return Err(Error::Corrupt {
            what: "guide or point count",
        });
    }
    let (guides, points) = (product(&[guides])?, points as usize);
    let (strands, patches) = (product(&[strands])?, product(&[patches])?);
    if payload_bytes(guides, points, strands, patches) != Some(file.payload.len()) {
        return Err(Error::Corrupt {
            what: "payload length does not match the counts",
        });
    }
    let counts = GroomCounts {
        guides,
        points,
        strands,
        patches,
        id: file.crc,
    };
    Ok((counts, file.payload))
}

/// Records checked per step of the validation pass.
const CHUNK: usize = 64;

/// Decodes a groom file into `out` (each buffer at least as long as
/// [`counts`] says) and returns its counts. The file is checked whole
/// first (framing, counts, then every record as [`Groom::check`] would):
/// on error nothing is written.
pub fn decode(bytes: &[u8], out: GroomBuffers) -> Result<GroomCounts, Error> {
    let (c, payload) = parse(bytes)?;
    let needs = [
        (out.guide_roots.len(), c.guides),
        (out.guide_points.len(), c.guides * c.points),
        (out.roots.len(), c.strands),
        (out.bindings.len(), c.strands),
        (out.grooms.len(), c.strands),
        (out.patches.len(), c.patches),
    ];
    for (available, needed) in needs {
        if available < needed {
            return Err(Error::OutputTooSmall { needed, available });
        }
    }
    let at_points = c.guides * ROOT;
    let at_strands = at_points + c.guides * c.points * POINT;
    let at_bindings = at_strands + c.strands * ROOT;
    let at_grooms = at_bindings + c.strands * BINDING;
    let at_patches = at_grooms + c.strands * GROOM;
    let section = |at: usize| Reader::new(&payload[at..]);
    // validation pass, through small buffers
    let (mut guides, mut points) = (section(0), section(at_points));
    let mut g = 0;
    while g < c.guides {
        let k = CHUNK.min(c.guides - g);
        let mut roots = [Root::default(); CHUNK];
        let mut p = [[0.0f32; 3]; CHUNK];
        guides.words(&mut roots[..k])?;
        check_guides(&roots[..k], &[]).map_err(|e| corrupt(e, "guide roots"))?;
        for _ in 0..c.points {
            points.words(&mut p[..k])?;
            check_guides(&[], &p[..k]).map_err(|e| corrupt(e, "guide rest points"))?;
        }
        g += k;
    }
    let (mut roots, mut bindings, mut grooms) = (
        section(at_strands),
        section(at_bindings),
        section(at_grooms),
    );
    let mut s = 0;
    while s < c.strands {
        let k = CHUNK.min(c.strands - s);
        let mut r = [Root::default(); CHUNK];
        let mut b = [StrandBinding::default(); CHUNK];
        let mut m = [StrandGroom::default(); CHUNK];
        roots.words(&mut r[..k])?;
        bindings.words(&mut b[..k])?;
        grooms.words(&mut m[..k])?;
        let chunk = Strands {
            roots: &r[..k],
            bindings: &b[..k],
            grooms: &m[..k],
        };
        StrandBounds::new(&chunk)
            .and_then(|bounds| bounds.fits(u32::MAX as usize, c.guides))
            .map_err(|e| corrupt(e, "strand records"))?;
        s += k;
    }
    let mut patches = section(at_patches);
    let mut next = 0u64;
    for _ in 0..c.patches {
        let mut p = [Patch::default()];
        patches.words(&mut p)?;
        if u64::from(p[0].first) != next || p[0].count == 0 {
            return Err(Error::Corrupt {
                what: "patches are not contiguous ranges in order",
            });
        }
        next += u64::from(p[0].count);
    }
    if c.patches > 0 && next != c.strands as u64 {
        return Err(Error::Corrupt {
            what: "patches do not cover the strands",
        });
    }
    // the copy
    let mut all = section(0);
    all.words(&mut out.guide_roots[..c.guides])?;
    all.words(&mut out.guide_points[..c.guides * c.points])?;
    all.words(&mut out.roots[..c.strands])?;
    all.words(&mut out.bindings[..c.strands])?;
    all.words(&mut out.grooms[..c.strands])?;
    all.words(&mut out.patches[..c.patches])?;
    Ok(c)
}

/// A record that fails its check inside a file is corrupt data, whatever
/// check found it.
fn corrupt(e: Error, what: &'static str) -> Error {
    match e {
        Error::Corrupt { .. } => e,
        _ => Error::Corrupt { what },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::fixture::{Scene, POINTS};

    struct Out {
        guide_roots: Vec<Root>,
        guide_points: Vec<[f32; 3]>,
        roots: Vec<Root>,
        bindings: Vec<StrandBinding>,
        grooms: Vec<StrandGroom>,
        patches: Vec<Patch>,
    }

    impl Out {
        fn new(g: usize, s: usize) -> Out {
            Out {
                guide_roots: vec![Root::default(); g],
                guide_points: vec![[7.0; 3]; g * POINTS],
                roots: vec![Root::default(); s],
                bindings: vec![StrandBinding::default(); s],
                grooms: vec![StrandGroom::default(); s],
                patches: vec![Patch::default(); 4],
            }
        }

        fn decode(&mut self, bytes: &[u8]) -> Result<GroomCounts, Error> {
            decode(
                bytes,
                GroomBuffers {
                    guide_roots: &mut self.guide_roots,
                    guide_points: &mut self.guide_points,
                    roots: &mut self.roots,
                    bindings: &mut self.bindings,
                    grooms: &mut self.grooms,
                    patches: &mut self.patches,
                },
            )
        }

        fn untouched(&self) -> bool {
            self.guide_points.iter().all(|p| *p == [7.0; 3])
                && self.roots.iter().all(|r| *r == Root::default())
        }
    }

    fn encoded(scene: &Scene) -> Vec<u8> {
        let groom = scene.groom();
        let mut bytes = vec![0u8; groom.encoded_bytes().unwrap()];
        assert_eq!(encode(&groom, &mut bytes), Ok(bytes.len()));
        bytes
    }

    /// Rewrites the CRC so a deliberately changed file passes the checksum.
    fn reseal(bytes: &mut [u8]) {
        let at = container::header_bytes(FIELDS) - 8;
        let mut h = crc32fast::Hasher::new();
        h.update(&bytes[..at]);
        h.update(&bytes[at + 8..]);
        let crc = h.finalize();
        bytes[at..at + 4].copy_from_slice(&crc.to_le_bytes());
    }

    #[test]
    fn a_groom_round_trips_bit_for_bit() {
        let scene = Scene::new(40);
        let bytes = encoded(&scene);
        let c = counts(&bytes).unwrap();
        assert_eq!(
            (c.guides, c.points, c.strands),
            (scene.guide_roots.len(), POINTS, 200)
        );
        let mut out = Out::new(c.guides, c.strands);
        assert_eq!(out.decode(&bytes), Ok(c));
        assert_eq!(out.guide_roots, scene.guide_roots);
        assert_eq!(out.guide_points, scene.guide_local);
        assert_eq!(out.roots, scene.roots);
        assert_eq!(out.bindings, scene.bindings);
        assert_eq!(out.grooms, scene.grooms);
        assert_eq!(out.patches, scene.patches);
        // the same groom, the same bytes and id
        assert_eq!(encoded(&scene), bytes);
    }

    #[test]
    fn damaged_files_are_refused_and_nothing_is_written() {
        let scene = Scene::new(40);
        let bytes = encoded(&scene);
        let (g, s) = (scene.guide_roots.len(), scene.roots.len());
        let mut out = Out::new(g, s);
        // every truncation
        for len in 0..bytes.len() {
            assert!(out.decode(&bytes[..len]).is_err(), "truncated to {len}");
        }
        // a flipped bit anywhere
        for at in (0..bytes.len()).step_by(97) {
            let mut bad = bytes.clone();
            bad[at] ^= 0x10;
            assert!(out.decode(&bad).is_err(), "bit flipped at {at}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert_eq!(
            out.decode(&longer),
            Err(Error::Corrupt {
                what: "bytes after the payload"
            })
        );
        let mut magic = bytes.clone();
        magic[0] = b'X';
        assert_eq!(
            out.decode(&magic),
            Err(Error::VersionMismatch {
                found: 0,
                supported: VERSION
            })
        );
        let mut version = bytes.clone();
        version[8] = 2;
        reseal(&mut version);
        assert_eq!(
            out.decode(&version),
            Err(Error::VersionMismatch {
                found: 2,
                supported: VERSION
            })
        );
        // counts that overflow, or disagree with the payload, sealed
        let mut huge = bytes.clone();
        huge[16..24].copy_from_slice(&u64::MAX.to_le_bytes());
        reseal(&mut huge);
        assert!(matches!(out.decode(&huge), Err(Error::Corrupt { .. })));
        // a NaN weight in a sealed file is corrupt data
        let mut nan = bytes.clone();
        let weight = container::header_bytes(FIELDS) + g * (20 + 12 * POINTS) + s * 20 + 32;
        nan[weight..weight + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        reseal(&mut nan);
        assert!(matches!(out.decode(&nan), Err(Error::Corrupt { .. })));
        // weights in 0..1 that sum to 2 (the fixture's are 0.25 and 0.75)
        let mut sum = bytes.clone();
        sum[weight..weight + 4].copy_from_slice(&1.0f32.to_le_bytes());
        sum[weight + 4..weight + 8].copy_from_slice(&1.0f32.to_le_bytes());
        reseal(&mut sum);
        assert!(matches!(out.decode(&sum), Err(Error::Corrupt { .. })));
        // a binding naming a guide past the count
        let mut index = bytes.clone();
        let guide = weight - 32;
        index[guide..guide + 4].copy_from_slice(&(g as u32).to_le_bytes());
        reseal(&mut index);
        assert!(matches!(out.decode(&index), Err(Error::Corrupt { .. })));
        assert!(out.untouched());
        // buffers too small
        let mut small = Out::new(g, s - 1);
        assert!(matches!(
            small.decode(&bytes),
            Err(Error::OutputTooSmall { .. })
        ));
        assert!(small.untouched());
    }

    #[test]
    fn bad_grooms_are_not_written() {
        let scene = Scene::new(20);
        let mut groom = scene.groom();
        let mut out = vec![0u8; groom.encoded_bytes().unwrap()];
        assert!(matches!(
            encode(&groom, &mut out[..10]),
            Err(Error::OutputTooSmall { .. })
        ));
        let mut points = scene.guide_local.clone();
        points[3][1] = f32::INFINITY;
        groom.guide_points = &points;
        assert!(matches!(
            encode(&groom, &mut out),
            Err(Error::NonFinite { index: 3, .. })
        ));
        let mut far = scene.guide_local.clone();
        far[3][1] = 2e9;
        groom.guide_points = &far;
        assert!(matches!(
            encode(&groom, &mut out),
            Err(Error::OutOfDomain { index: 3, .. })
        ));
        groom.guide_points = &points[1..];
        assert!(matches!(
            encode(&groom, &mut out),
            Err(Error::InvalidArgument(_))
        ));
        groom.guide_points = &scene.guide_local;
        let gap = [
            Patch {
                first: 0,
                count: 10,
            },
            Patch {
                first: 11,
                count: 189,
            },
        ];
        groom.patches = &gap;
        assert!(matches!(
            encode(&groom, &mut out),
            Err(Error::OutOfDomain { .. })
        ));
        assert!(out.iter().all(|&b| b == 0));
    }
}
