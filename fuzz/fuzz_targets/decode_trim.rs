//! The trim files' decoders (records and lengths) on damaged and arbitrary
//! bytes: never a panic; on failure nothing written, on success every
//! record within its frame's guides, points and 0..=1.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pelage_core::cache::trim_file::{self, RecordsInfo};
use pelage_core::trim::TrimRecord;
use std::sync::OnceLock;

const GUIDES: usize = 40;
const POINTS: usize = 8;

/// A valid records file and a valid lengths file.
fn files() -> &'static [Vec<u8>; 2] {
    static F: OnceLock<[Vec<u8>; 2]> = OnceLock::new();
    F.get_or_init(|| {
        let records: Vec<TrimRecord> = (0..GUIDES as u32)
            .step_by(3)
            .map(|g| TrimRecord {
                guide: g,
                cv: 1 + g % (POINTS as u32 - 1),
                length: g as f32 / GUIDES as f32,
            })
            .collect();
        let info = RecordsInfo {
            guides: GUIDES,
            points: POINTS,
            records: 0,
        };
        let mut a = vec![0u8; trim_file::records_bytes(records.len()).unwrap()];
        trim_file::encode_records(&records, info, &mut a).unwrap();
        let lengths: Vec<u16> = (0..101u16).map(|i| i.wrapping_mul(647)).collect();
        let mut b = vec![0u8; trim_file::lengths_bytes(lengths.len()).unwrap()];
        trim_file::encode_lengths(&lengths, &mut b).unwrap();
        [a, b]
    })
}

fuzz_target!(|data: &[u8]| {
    let Some((&flags, edits)) = data.split_first() else {
        return;
    };
    let kind = (flags >> 1) as usize & 1;
    let bytes = if flags & 1 == 1 {
        edits.to_vec()
    } else {
        // a valid file with bytes overwritten at offsets the input names
        let mut b = files()[kind].clone();
        for pair in edits.chunks_exact(2) {
            let at = pair[0] as usize % b.len();
            b[at] = pair[1];
        }
        b
    };
    if kind == 0 {
        let mut out = vec![TrimRecord::default(); 64];
        match trim_file::decode_records(&bytes, &mut out) {
            Ok(info) => {
                for (i, r) in out[..info.records].iter().enumerate() {
                    r.check(i, info.guides, info.points)
                        .expect("a decoded record is valid");
                }
            }
            Err(_) => assert!(out.iter().all(|r| *r == TrimRecord::default())),
        }
    } else {
        let mut out = vec![0u16; 256];
        if trim_file::decode_lengths(&bytes, &mut out).is_err() {
            assert!(out.iter().all(|&l| l == 0), "a failed decode wrote lengths");
        }
    }
});
