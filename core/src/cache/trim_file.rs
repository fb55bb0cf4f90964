//! Trimming's two files (paper 3.3; `docs/FORMAT.md`).
//!
//! - A frame's **trim records**: where its posed guides first meet the
//!   cloth or a collider ([`TrimRecord`]). Header fields: guide count
//!   (1..=[`MAX_GUIDES`]), points per guide, record count. Payload: the
//!   records, 12 bytes each (guide, cv as u32, length as f32).
//! - A shot's **trim lengths**: the shot pass's shortest length per render
//!   strand, what expansion reads. Header field: strand count. Payload: one
//!   u16 per strand (2 bytes per hair; [`WHOLE`](crate::trim::WHOLE) is
//!   untrimmed), zero-padded to a multiple of 4 bytes.

use super::container::{self, product, Reader, Writer};
use crate::interp::strand::MAX_STRAND_POINTS;
use crate::trim::TrimRecord;
use crate::Error;

/// The records file's magic.
pub const RECORDS_MAGIC: [u8; 8] = *b"PLTRIMR\0";
/// The lengths file's magic.
pub const LENGTHS_MAGIC: [u8; 8] = *b"PLTRIML\0";
/// The format version this build writes and reads (both files).
pub const VERSION: u32 = 1;
const RECORD_FIELDS: usize = 3;
const LENGTH_FIELDS: usize = 1;
const RECORD_BYTES: usize = 12;
/// Most guides of a records file's frame: guides are named by u32, and
/// u32::MAX names none.
pub const MAX_GUIDES: u64 = u32::MAX as u64;

/// What a records file holds besides its records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RecordsInfo {
    /// Guides of the frame the records were found on.
    pub guides: usize,
    /// Points per guide of that frame.
    pub points: usize,
    /// Records in the file.
    pub records: usize,
}

/// Bytes of a records file of `records` records.
pub fn records_bytes(records: usize) -> Option<usize> {
    records
        .checked_mul(RECORD_BYTES)?
        .checked_add(container::header_bytes(RECORD_FIELDS))
}

/// Checks `records` (found on a frame of `info.guides` guides of
/// `info.points` points; `info.records` is ignored) and writes them as a
/// records file into `out`; returns the bytes written. On error `out` is
/// untouched.
pub fn encode_records(
    records: &[TrimRecord],
    info: RecordsInfo,
    out: &mut [u8],
) -> Result<usize, Error> {
    check_shape(info.guides as u64, info.points as u64).map_err(|_| {
        Error::InvalidArgument("trim records: guides must be in 1..=2^32 - 1 and points in 2..=64")
    })?;
    for (i, r) in records.iter().enumerate() {
        r.check(i, info.guides, info.points)?;
    }
    let n = records_bytes(records.len()).ok_or(Error::InvalidArgument("too many records"))?;
    if out.len() < n {
        return Err(Error::OutputTooSmall {
            needed: n,
            available: out.len(),
        });
    }
    let fields = [info.guides as u64, info.points as u64, records.len() as u64];
    let written = container::write(
        &mut out[..n],
        &RECORDS_MAGIC,
        VERSION,
        &fields,
        |w: &mut Writer| w.words(records),
    );
    debug_assert_eq!(written, n);
    Ok(n)
}

fn check_shape(guides: u64, points: u64) -> Result<(), Error> {
    if !(1..=MAX_GUIDES).contains(&guides) || !(2..=MAX_STRAND_POINTS as u64).contains(&points) {
        return Err(Error::Corrupt {
            what: "guide or point count",
        });
    }
    Ok(())
}

/// Reads the header of a records file and checks its framing (magic,
/// version, length, checksum) and counts.
pub fn records_info(bytes: &[u8]) -> Result<RecordsInfo, Error> {
    Ok(parse_records(bytes)?.0)
}

fn parse_records(bytes: &[u8]) -> Result<(RecordsInfo, &[u8]), Error> {
    let file = container::read(bytes, &RECORDS_MAGIC, VERSION, RECORD_FIELDS)?;
    let [guides, points, records, ..] = file.fields;
    check_shape(guides, points)?;
    let info = RecordsInfo {
        guides: product(&[guides])?,
        points: points as usize,
        records: product(&[records])?,
    };
    if product(&[records, RECORD_BYTES as u64])? != file.payload.len() {
        return Err(Error::Corrupt {
            what: "payload length does not match the counts",
        });
    }
    Ok((info, file.payload))
}

/// Decodes a records file into `out` (at least [`records_info`]'s count
/// long) and returns its info. Every record is checked against the file's
/// guide and point counts first: on error nothing is written.
pub fn decode_records(bytes: &[u8], out: &mut [TrimRecord]) -> Result<RecordsInfo, Error> {
    let (info, payload) = parse_records(bytes)?;
    if out.len() < info.records {
        return Err(Error::OutputTooSmall {
            needed: info.records,
            available: out.len(),
        });
    }
    let mut r = Reader::new(payload);
    for i in 0..info.records {
        let mut one = [TrimRecord::default()];
        r.words(&mut one)?;
        one[0]
            .check(i, info.guides, info.points)
            .map_err(|_| Error::Corrupt {
                what: "a trim record outside the frame's guides, points or 0..=1",
            })?;
    }
    Reader::new(payload).words(&mut out[..info.records])?;
    Ok(info)
}

/// Bytes of a lengths file of `strands` strands.
pub fn lengths_bytes(strands: usize) -> Option<usize> {
    payload_of(strands)?.checked_add(container::header_bytes(LENGTH_FIELDS))
}

/// Payload bytes of `strands` lengths: 2 each, padded to 4.
fn payload_of(strands: usize) -> Option<usize> {
    (strands.checked_add(1)? / 2).checked_mul(4)
}

/// Writes the stored lengths of a shot's strands as a lengths file into
/// `out`; returns the bytes written. On error `out` is untouched.
pub fn encode_lengths(lengths: &[u16], out: &mut [u8]) -> Result<usize, Error> {
    let n = lengths_bytes(lengths.len()).ok_or(Error::InvalidArgument("too many lengths"))?;
    if out.len() < n {
        return Err(Error::OutputTooSmall {
            needed: n,
            available: out.len(),
        });
    }
    let fields = [lengths.len() as u64];
    let written = container::write(
        &mut out[..n],
        &LENGTHS_MAGIC,
        VERSION,
        &fields,
        |w: &mut Writer| {
            for pair in lengths.chunks(2) {
                let hi = pair.get(1).copied().unwrap_or(0);
                w.u32(u32::from(pair[0]) | u32::from(hi) << 16);
            }
        },
    );
    debug_assert_eq!(written, n);
    Ok(n)
}

/// Reads the header of a lengths file, checks its framing and returns its
/// strand count.
pub fn lengths_count(bytes: &[u8]) -> Result<usize, Error> {
    Ok(parse_lengths(bytes)?.0)
}

fn parse_lengths(bytes: &[u8]) -> Result<(usize, &[u8]), Error> {
    let file = container::read(bytes, &LENGTHS_MAGIC, VERSION, LENGTH_FIELDS)?;
    let strands = product(&[file.fields[0]])?;
    if strands == 0 && !file.payload.is_empty() || payload_of(strands) != Some(file.payload.len()) {
        return Err(Error::Corrupt {
            what: "payload length does not match the counts",
        });
    }
    let padded = strands % 2 == 1 && file.payload[file.payload.len() - 2..] != [0, 0];
    if padded {
        return Err(Error::Corrupt {
            what: "padding is not zero",
        });
    }
    Ok((strands, file.payload))
}

/// Decodes a lengths file into `out` (at least [`lengths_count`] long) and
/// returns the strand count. On error nothing is written.
pub fn decode_lengths(bytes: &[u8], out: &mut [u16]) -> Result<usize, Error> {
    let (strands, payload) = parse_lengths(bytes)?;
    if out.len() < strands {
        return Err(Error::OutputTooSmall {
            needed: strands,
            available: out.len(),
        });
    }
    for (l, b) in out[..strands].iter_mut().zip(payload.chunks_exact(2)) {
        *l = u16::from_le_bytes([b[0], b[1]]);
    }
    Ok(strands)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trim::WHOLE;

    fn records() -> Vec<TrimRecord> {
        (0..5)
            .map(|g| TrimRecord {
                guide: 2 * g,
                cv: 1 + g,
                length: 0.1 * g as f32,
            })
            .collect()
    }

    const INFO: RecordsInfo = RecordsInfo {
        guides: 10,
        points: 8,
        records: 0,
    };

    #[test]
    fn records_round_trip_and_reject_damage() {
        let recs = records();
        let mut file = vec![0u8; records_bytes(recs.len()).unwrap()];
        let n = encode_records(&recs, INFO, &mut file).unwrap();
        assert_eq!(n, file.len());
        let mut back = vec![TrimRecord::default(); recs.len()];
        let info = decode_records(&file, &mut back).unwrap();
        assert_eq!(back, recs);
        assert_eq!(info, RecordsInfo { records: 5, ..INFO });
        for cut in [0, 10, file.len() - 1] {
            assert!(records_info(&file[..cut]).is_err(), "cut at {cut}");
        }
        for at in 0..file.len() {
            let mut bad = file.clone();
            bad[at] ^= 0x10;
            let mut out = vec![TrimRecord::default(); 16];
            assert!(decode_records(&bad, &mut out).is_err(), "flip at {at}");
            assert!(out.iter().all(|r| *r == TrimRecord::default()));
        }
        let mut short = vec![TrimRecord::default(); 4];
        assert!(decode_records(&file, &mut short).is_err());
        let bad = [TrimRecord {
            guide: 10,
            ..recs[1]
        }];
        assert!(encode_records(&bad, INFO, &mut file).is_err());
    }

    #[test]
    fn a_frame_has_at_most_two_to_the_32_minus_one_guides() {
        let recs = records();
        let mut file = vec![0u8; records_bytes(recs.len()).unwrap()];
        let most = RecordsInfo {
            guides: u32::MAX as usize,
            ..INFO
        };
        encode_records(&recs, most, &mut file).unwrap();
        assert_eq!(records_info(&file).unwrap().guides, u32::MAX as usize);
        let past = RecordsInfo {
            guides: u32::MAX as usize + 1,
            ..INFO
        };
        assert!(matches!(
            encode_records(&recs, past, &mut file),
            Err(Error::InvalidArgument(_))
        ));
        let mut header = vec![0u8; records_bytes(0).unwrap()];
        for (guides, fine) in [
            (0, false),
            (1, true),
            (MAX_GUIDES, true),
            (MAX_GUIDES + 1, false),
        ] {
            container::write(
                &mut header,
                &RECORDS_MAGIC,
                VERSION,
                &[guides, 8, 0],
                |_| {},
            );
            assert_eq!(records_info(&header).is_ok(), fine, "{guides}");
        }
    }

    #[test]
    fn lengths_round_trip_at_two_bytes_a_strand() {
        for count in [0usize, 1, 2, 7] {
            let lengths: Vec<u16> = (0..count as u16).map(|i| WHOLE - 1000 * i).collect();
            let mut file = vec![0u8; lengths_bytes(count).unwrap()];
            assert_eq!(file.len(), 40 + count.div_ceil(2) * 4);
            encode_lengths(&lengths, &mut file).unwrap();
            let mut back = vec![0u16; count];
            assert_eq!(decode_lengths(&file, &mut back).unwrap(), count);
            assert_eq!(back, lengths);
            for cut in 0..file.len() {
                assert!(lengths_count(&file[..cut]).is_err());
            }
        }
        // a count whose payload size overflows, in a well-framed file
        assert_eq!(lengths_bytes(usize::MAX), None);
        assert_eq!(lengths_bytes(usize::MAX / 2), None);
        for huge in [1u64 << 62, (1u64 << 63) - 1, u64::MAX] {
            let mut file = vec![0u8; 40];
            container::write(&mut file, &LENGTHS_MAGIC, VERSION, &[huge], |_| {});
            assert!(lengths_count(&file).is_err(), "{huge}");
        }
    }
}
