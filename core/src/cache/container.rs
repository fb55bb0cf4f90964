//! The framing of pelage's files: magic, version, a file's counts, the
//! payload's length and a CRC-32 over everything but the CRC itself.
//!
//! ```text
//! offset  size  field
//! 0       8     magic (ASCII, names the file kind)
//! 8       4     format version (u32)
//! 12      4     count of header fields K (u32)
//! 16      8*K   header fields (u64 each; the file kind defines them)
//! 16+8K   8     payload length in bytes (u64)
//! 24+8K   4     CRC-32 (IEEE) of every other byte of the file
//! 28+8K   4     zero
//! 32+8K   ...   payload
//! ```

use crate::Error;
use bytemuck::Pod;

/// Bytes before the payload of a file with `fields` header fields.
pub(crate) const fn header_bytes(fields: usize) -> usize {
    32 + 8 * fields
}

/// Writes a file into `out`: the header, then `payload` fills the payload
/// through a [`Writer`] (within `out`, which the encoders size for the
/// largest payload), then the payload length and the CRC. Returns the
/// file's length.
pub(crate) fn write(
    out: &mut [u8],
    magic: &[u8; 8],
    version: u32,
    fields: &[u64],
    payload: impl FnOnce(&mut Writer),
) -> usize {
    let start = header_bytes(fields.len());
    let mut w = Writer { out, at: 0 };
    w.bytes(magic);
    w.u32(version);
    w.u32(fields.len() as u32);
    for &f in fields {
        w.u64(f);
    }
    w.u64(0);
    w.u64(0);
    payload(&mut w);
    let end = w.at;
    let out = &mut w.out[..end];
    out[start - 16..start - 8].copy_from_slice(&((end - start) as u64).to_le_bytes());
    let crc = checksum(out, start - 8);
    out[start - 8..start - 4].copy_from_slice(&crc.to_le_bytes());
    end
}

fn checksum(bytes: &[u8], crc_at: usize) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(&bytes[..crc_at]);
    h.update(&bytes[crc_at + 8..]);
    h.finalize()
}

/// A parsed file: its header fields and its payload, checked against the
/// magic, the version, the length and the CRC.
pub(crate) struct File<'a> {
    pub fields: [u64; MAX_FIELDS],
    pub payload: &'a [u8],
    pub crc: u32,
}

/// Most header fields a file kind has.
pub(crate) const MAX_FIELDS: usize = 8;

/// Parses `bytes` as a file of kind `magic`, version `version`, with
/// `fields` header fields.
pub(crate) fn read<'a>(
    bytes: &'a [u8],
    magic: &[u8; 8],
    version: u32,
    fields: usize,
) -> Result<File<'a>, Error> {
    let start = header_bytes(fields);
    if bytes.len() < 16 {
        return Err(Error::Corrupt {
            what: "shorter than a header",
        });
    }
    let mut r = Reader::new(bytes);
    if r.take(8)? != magic {
        return Err(Error::VersionMismatch {
            found: 0,
            supported: version,
        });
    }
    let found = r.u32()?;
    if found != version {
        return Err(Error::VersionMismatch {
            found,
            supported: version,
        });
    }
    if r.u32()? as usize != fields {
        return Err(Error::Corrupt {
            what: "header field count",
        });
    }
    if bytes.len() < start {
        return Err(Error::Corrupt {
            what: "truncated header",
        });
    }
    let mut out = [0u64; MAX_FIELDS];
    for f in out.iter_mut().take(fields) {
        *f = r.u64()?;
    }
    let payload_len = r.u64()?;
    let crc = r.u32()?;
    let payload = &bytes[start..];
    if payload_len != payload.len() as u64 {
        return Err(Error::Corrupt {
            what: if payload_len > payload.len() as u64 {
                "truncated payload"
            } else {
                "bytes after the payload"
            },
        });
    }
    if r.u32()? != 0 || checksum(bytes, start - 8) != crc {
        return Err(Error::Corrupt {
            what: "checksum mismatch",
        });
    }
    Ok(File {
        fields: out,
        payload,
        crc,
    })
}

/// Writes little-endian values into a buffer sized beforehand.
pub(crate) struct Writer<'a> {
    out: &'a mut [u8],
    at: usize,
}

impl Writer<'_> {
    /// Bytes written so far.
    pub fn position(&self) -> usize {
        self.at
    }

    /// Overwrites the u32 at `at` (written before).
    pub fn patch_u32(&mut self, at: usize, v: u32) {
        self.out[at..at + 4].copy_from_slice(&v.to_le_bytes());
    }

    pub fn bytes(&mut self, b: &[u8]) {
        self.out[self.at..self.at + b.len()].copy_from_slice(b);
        self.at += b.len();
    }

    pub fn u8(&mut self, v: u8) {
        self.bytes(&[v]);
    }

    pub fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }

    pub fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }

    /// Records made only of 4-byte words (u32, f32), word by word.
    pub fn words<T: Pod>(&mut self, items: &[T]) {
        let words: &[u32] = bytemuck::cast_slice(items);
        for &w in words {
            self.u32(w);
        }
    }
}

/// Reads little-endian values, failing with [`Error::Corrupt`] past the end.
pub(crate) struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    pub fn new(bytes: &'a [u8]) -> Self {
        Reader { bytes, at: 0 }
    }

    pub fn position(&self) -> usize {
        self.at
    }

    /// The bytes not read yet.
    pub fn rest(&self) -> &'a [u8] {
        &self.bytes[self.at..]
    }

    pub fn take(&mut self, n: usize) -> Result<&'a [u8], Error> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or(Error::Corrupt {
            what: "truncated payload",
        })?;
        let b = &self.bytes[self.at..end];
        self.at = end;
        Ok(b)
    }

    pub fn u8(&mut self) -> Result<u8, Error> {
        Ok(self.take(1)?[0])
    }

    pub fn u32(&mut self) -> Result<u32, Error> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    pub fn u64(&mut self) -> Result<u64, Error> {
        let lo = u64::from(self.u32()?);
        Ok(lo | u64::from(self.u32()?) << 32)
    }

    /// Fills records made only of 4-byte words (u32, f32).
    pub fn words<T: Pod>(&mut self, out: &mut [T]) -> Result<(), Error> {
        let words: &mut [u32] = bytemuck::cast_slice_mut(out);
        let b = self.take(words.len() * 4)?;
        for (w, c) in words.iter_mut().zip(b.chunks_exact(4)) {
            *w = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        }
        Ok(())
    }
}

/// `a * b * c` as a byte or element count, or a corrupt-file error when it
/// overflows.
pub(crate) fn product(factors: &[u64]) -> Result<usize, Error> {
    factors
        .iter()
        .try_fold(1u64, |acc, &f| acc.checked_mul(f))
        .and_then(|n| usize::try_from(n).ok())
        .filter(|&n| n <= isize::MAX as usize)
        .ok_or(Error::Corrupt {
            what: "counts overflow",
        })
}
