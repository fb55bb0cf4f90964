//! Square roots as one instruction in the encoding of the code around them.
//!
//! libm's hardware square root is inline assembly, so it is always the SSE
//! encoding (`sqrtss`), even inlined into the AVX2 expansion kernel, where
//! mixing it with AVX code stalls the core: one per strand made the kernel
//! 2.5x slower on an AMD EPYC (Zen 3). Here the square root goes through
//! the compiler's intrinsic (via `wide`), which it encodes like its
//! neighbours. A square root is correctly rounded either way, so every path
//! gives the same bits; without the `hardware-sqrt` feature (Miri) and off
//! x86_64 it is libm's.

use glam::Vec3;

/// `sqrt(x)`, correctly rounded.
#[inline(always)]
pub(crate) fn sqrtf(x: f32) -> f32 {
    #[cfg(all(target_arch = "x86_64", feature = "hardware-sqrt"))]
    {
        wide::f32x4::splat(x).sqrt().to_array()[0]
    }
    #[cfg(not(all(target_arch = "x86_64", feature = "hardware-sqrt")))]
    {
        libm::sqrtf(x)
    }
}

/// [`sqrtf`] of every value of `v`, four at a time where the CPU has the
/// instruction for it.
#[inline]
pub(crate) fn sqrt_lanes(v: &mut [f32]) {
    #[cfg(all(target_arch = "x86_64", feature = "hardware-sqrt"))]
    {
        let mut quads = v.chunks_exact_mut(4);
        for q in &mut quads {
            let r = wide::f32x4::from([q[0], q[1], q[2], q[3]]).sqrt();
            q.copy_from_slice(&r.to_array());
        }
        for x in quads.into_remainder() {
            *x = sqrtf(*x);
        }
    }
    #[cfg(not(all(target_arch = "x86_64", feature = "hardware-sqrt")))]
    for x in v {
        *x = libm::sqrtf(*x);
    }
}

/// `v.length()`, operation for operation.
#[inline(always)]
pub(crate) fn length(v: Vec3) -> f32 {
    sqrtf(v.dot(v))
}

/// `v.normalize_or_zero()`, operation for operation (the same bits).
#[inline(always)]
pub(crate) fn normalize_or_zero(v: Vec3) -> Vec3 {
    let rcp = 1.0 / length(v);
    if rcp.is_finite() && rcp > 0.0 {
        v * rcp
    } else {
        Vec3::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_bits_as_glam_and_libm() {
        let mut x = 0x3f80_0001u32;
        for _ in 0..100_000 {
            x = x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let f = f32::from_bits(x);
            assert_eq!(sqrtf(f).to_bits(), libm::sqrtf(f).to_bits(), "{f}");
            let mut lanes = [f, f * 0.5, f * 3.0, f + 1.0, f * 7.0];
            let want = lanes.map(libm::sqrtf);
            sqrt_lanes(&mut lanes);
            assert_eq!(lanes.map(f32::to_bits), want.map(f32::to_bits));
            let v = Vec3::new(f, f32::from_bits(x.rotate_left(7)), 1.5);
            assert_eq!(length(v).to_bits(), v.length().to_bits());
            let (a, b) = (normalize_or_zero(v), v.normalize_or_zero());
            assert_eq!(
                a.to_array().map(f32::to_bits),
                b.to_array().map(f32::to_bits)
            );
        }
        for v in [
            Vec3::ZERO,
            Vec3::splat(f32::NAN),
            Vec3::splat(1e-30),
            Vec3::splat(f32::MAX),
        ] {
            assert_eq!(
                normalize_or_zero(v).to_array().map(f32::to_bits),
                v.normalize_or_zero().to_array().map(f32::to_bits)
            );
        }
    }
}
