//! Bits least significant first, and the Rice code with an escape that
//! the guide cache writes its prediction errors in (`docs/FORMAT.md`):
//! a value `z` with parameter `k` is `z >> k` one-bits, a zero-bit, then
//! the `k` low bits of `z`; or, when `z >> k` reaches [`ESCAPE`], that
//! many one-bits and `z` in [`RAW_BITS`] bits.

use super::container::Writer;
use crate::Error;

/// A value whose quotient reaches this many ones is escaped: the ones,
/// then the value in [`RAW_BITS`] bits.
pub(crate) const ESCAPE: u64 = 24;
/// Bits of an escaped value (zigzagged offsets stay below 2^33).
pub(crate) const RAW_BITS: u32 = 40;

/// Bits of `z` Rice-coded with parameter `k`.
pub(crate) fn rice_bits(z: u64, k: u32) -> u64 {
    let q = z >> k;
    if q < ESCAPE {
        q + 1 + u64::from(k)
    } else {
        ESCAPE + u64::from(RAW_BITS)
    }
}

/// Writes bits least significant first.
pub(crate) struct BitWriter<'w, 'a> {
    w: &'w mut Writer<'a>,
    acc: u128,
    bits: u32,
}

impl<'w, 'a> BitWriter<'w, 'a> {
    /// Bits into `w`, from its position on.
    pub(crate) fn new(w: &'w mut Writer<'a>) -> Self {
        BitWriter { w, acc: 0, bits: 0 }
    }

    fn put(&mut self, value: u64, bits: u32) {
        self.acc |= u128::from(value) << self.bits;
        self.bits += bits;
        while self.bits >= 8 {
            self.w.u8(self.acc as u8);
            self.acc >>= 8;
            self.bits -= 8;
        }
    }

    /// `z` Rice-coded with parameter `k` ([`rice_bits`] bits).
    pub(crate) fn rice(&mut self, z: u64, k: u32) {
        let q = z >> k;
        if q < ESCAPE {
            // q ones, a zero, then the k low bits
            self.put((1 << q) - 1, q as u32 + 1);
            self.put(z & ((1 << k) - 1), k);
        } else {
            self.put((1 << ESCAPE) - 1, ESCAPE as u32);
            self.put(z, RAW_BITS);
        }
    }

    /// Writes the last bits, zero-padded to a byte.
    pub(crate) fn finish(self) {
        if self.bits > 0 {
            self.w.u8(self.acc as u8);
        }
    }
}

/// Reads bits least significant first from a slice, failing past its end.
pub(crate) struct BitReader<'a> {
    bytes: &'a [u8],
    /// Bytes counted into `acc`.
    next: usize,
    /// The bits held, the first `have` counted; any above are the bytes
    /// from `next` on, loaded early.
    acc: u64,
    have: u32,
}

impl<'a> BitReader<'a> {
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        BitReader {
            bytes,
            next: 0,
            acc: 0,
            have: 0,
        }
    }

    /// Counts whole bytes in while they fit: at least 56 bits held unless
    /// the slice ends.
    #[inline(always)]
    fn refill(&mut self) {
        if let Some(w) = self.bytes.get(self.next..self.next + 8) {
            let word = u64::from_le_bytes([w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]]);
            self.acc |= word << self.have;
            self.next += ((63 - self.have) >> 3) as usize;
            self.have |= 56;
        } else {
            self.refill_tail();
        }
    }

    #[cold]
    fn refill_tail(&mut self) {
        while self.have <= 56 {
            let Some(&b) = self.bytes.get(self.next) else {
                return;
            };
            self.acc |= u64::from(b) << self.have;
            self.next += 1;
            self.have += 8;
        }
    }

    /// Bytes read so far, the last one perhaps in part (a guide's bits
    /// end on a byte).
    pub(crate) fn bytes_used(&self) -> usize {
        self.next - (self.have / 8) as usize
    }

    /// The `bits` (<= 40) next bits.
    #[inline]
    fn take(&mut self, bits: u32) -> Result<u64, Error> {
        if self.have < bits {
            self.refill();
            if self.have < bits {
                return Err(truncated());
            }
        }
        let v = self.acc & ((1u64 << bits) - 1);
        self.acc >>= bits;
        self.have -= bits;
        Ok(v)
    }

    /// One Rice-coded value with parameter `k`: a run of ones (the
    /// quotient), a zero, `k` low bits; a run of [`ESCAPE`] ones is
    /// followed by the value in [`RAW_BITS`] bits.
    #[inline(always)]
    pub(crate) fn rice(&mut self, k: u32) -> Result<u64, Error> {
        if self.have < 32 {
            self.refill();
        }
        // bits past `have` may be zeros that end the run early: the fast
        // path takes a code only when it lies within `have`
        let run = (!self.acc).trailing_zeros();
        let used = run + 1 + k;
        if run < ESCAPE as u32 && used <= self.have {
            let v = (u64::from(run) << k) | ((self.acc >> (run + 1)) & ((1u64 << k) - 1));
            self.acc >>= used;
            self.have -= used;
            return Ok(v);
        }
        self.rice_slow(k)
    }

    /// [`BitReader::rice`] for a long or escaped code, or near the
    /// slice's end.
    #[cold]
    #[inline(never)]
    fn rice_slow(&mut self, k: u32) -> Result<u64, Error> {
        self.refill();
        let run = (!self.acc).trailing_zeros().min(self.have);
        if run >= ESCAPE as u32 {
            self.take(ESCAPE as u32)?;
            return self.take(RAW_BITS);
        }
        if run == self.have {
            return Err(truncated());
        }
        self.take(run + 1)?;
        Ok((u64::from(run) << k) | self.take(k)?)
    }
}

fn truncated() -> Error {
    Error::Corrupt {
        what: "truncated guide bits",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::container;

    #[test]
    fn rice_codes_read_back_as_written() {
        let values = [0u64, 1, 5, 63, 64, 1000, (1 << 33) - 1, 7 << 30];
        for k in [0u32, 3, 12, 40] {
            let mut file = [0u8; 512];
            let end = container::write(&mut file, b"PLBITS\0\0", 1, &[], |w| {
                let mut bits = BitWriter::new(w);
                for &z in &values {
                    bits.rice(z, k);
                }
                bits.finish();
            });
            let payload = &file[container::header_bytes(0)..end];
            let expected: u64 = values.iter().map(|&z| rice_bits(z, k)).sum();
            assert_eq!(payload.len() as u64, expected.div_ceil(8), "k {k}");
            let mut r = BitReader::new(payload);
            for &z in &values {
                assert_eq!(r.rice(k), Ok(z), "k {k}");
            }
            assert_eq!(r.bytes_used(), payload.len());
            // one code short: the reader fails, never reads past the slice
            let mut short = BitReader::new(&payload[..payload.len() - 1]);
            assert!(values.iter().any(|_| short.rice(k).is_err()));
        }
    }
}
