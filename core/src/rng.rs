//! Counter-based randomness: every random number is a pure hash of
//! (seed, id, purpose), so no result depends on evaluation order.

/// What a random number is for; distinct purposes give independent streams.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    /// Rotation of a triangle inside the Poisson stamp.
    StampRotation = 1,
    /// Translation of a triangle inside the Poisson stamp (x).
    StampOffsetX = 2,
    /// Translation of a triangle inside the Poisson stamp (y).
    StampOffsetY = 3,
    /// Candidate generation while building the Poisson tile.
    TileCandidate = 4,
    /// Order of roots within one LOD level.
    LodOrder = 5,
    /// Uniform random sampling (the baseline stamping is compared against).
    Uniform = 6,
    /// Number of neighbour guides of a strand.
    NeighbourCount = 7,
    /// Phase of a strand's kink.
    KinkPhase = 8,
    /// Darts of the stamp's fill pass.
    FillDart = 9,
    /// A strand's share of its length's random variation.
    LengthRandom = 10,
    /// A strand's share of its clump pull's random variation.
    ClumpRandom = 11,
}

/// Mixes (seed, id, purpose, counter) into 64 well-distributed bits.
#[inline]
pub fn hash(seed: u64, id: u64, purpose: Purpose, counter: u32) -> u64 {
    let mut x = seed ^ 0x9E37_79B9_7F4A_7C15;
    x = mix(x ^ id.wrapping_mul(0xD1B5_4A32_D192_ED03));
    x = mix(x ^ (((purpose as u64) << 32) | counter as u64).wrapping_mul(0x8CB9_2BA7_2F3D_8DD7));
    x
}

/// A uniform float in `[0, 1)` from (seed, id, purpose, counter).
#[inline]
pub fn unit(seed: u64, id: u64, purpose: Purpose, counter: u32) -> f32 {
    to_unit(hash(seed, id, purpose, counter))
}

/// The top 24 bits of `h` as a float in `[0, 1)`.
#[inline]
pub fn to_unit(h: u64) -> f32 {
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// The SplitMix64 / Stafford variant-13 finalizer.
#[inline]
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_independent_and_uniform() {
        let mut sum = 0.0f64;
        let n = if cfg!(miri) { 4_000 } else { 100_000 };
        for i in 0..n {
            let a = unit(7, i, Purpose::StampOffsetX, 0);
            assert!((0.0..1.0).contains(&a));
            sum += a as f64;
        }
        assert!((sum / n as f64 - 0.5).abs() < 0.02);
        assert_ne!(
            hash(1, 2, Purpose::StampOffsetX, 0),
            hash(1, 2, Purpose::StampOffsetY, 0)
        );
        assert_ne!(
            hash(1, 2, Purpose::LodOrder, 0),
            hash(2, 2, Purpose::LodOrder, 0)
        );
    }
}
