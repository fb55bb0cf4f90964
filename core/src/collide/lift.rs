//! The paper's push-out (3.3): a strand that enters a collider is rotated
//! rigidly about its root, toward its normal, by the smallest of a few
//! steps that frees it. Settling (render strands at rest, stored as the
//! groom's `lift`) and the guide dynamics (posed guides, every step) share
//! the rotation and the search.

use crate::sqrt;
use core::f32::consts::FRAC_PI_2;
use glam::{Vec2, Vec3};

/// Lift angles tried between none and a right angle.
pub(crate) const LIFT_STEPS: u32 = 16;

/// The angle between two tried lifts.
pub(crate) const LIFT_STEP: f32 = FRAC_PI_2 / LIFT_STEPS as f32;

/// Rotates local points about the root by the rotation vector `(w.x, w.y, 0)`
/// (Rodrigues' formula): the paper's collision push-out by rotation about
/// the root, fixed per strand at rest in the strand's own frame, so it
/// follows the body and does not depend on the pose.
pub(crate) fn lift(w: [f32; 2], x: &mut [f32], y: &mut [f32], z: &mut [f32]) {
    if let Some(turn) = Turn::new(w) {
        for j in 0..x.len() {
            (x[j], y[j], z[j]) = turn.apply(x[j], y[j], z[j]);
        }
    }
}

/// The rotation [`lift`] makes, worked out once for points turned one at a
/// time: each comes out with the bits [`lift`] gives it.
#[derive(Clone, Copy)]
pub(crate) struct Turn {
    kx: f32,
    ky: f32,
    s: f32,
    c: f32,
}

impl Turn {
    /// The rotation by `(w.x, w.y, 0)`; none for a vector too small to
    /// square, which turns nothing (and has no axis).
    #[inline]
    pub(crate) fn new(w: [f32; 2]) -> Option<Turn> {
        let angle = sqrt::sqrtf(w[0] * w[0] + w[1] * w[1]);
        if angle == 0.0 {
            return None;
        }
        let (s, c) = libm::sincosf(angle);
        Some(Turn {
            kx: w[0] / angle,
            ky: w[1] / angle,
            s,
            c,
        })
    }

    /// The point `(vx, vy, vz)` turned.
    #[inline]
    pub(crate) fn apply(&self, vx: f32, vy: f32, vz: f32) -> (f32, f32, f32) {
        let Turn { kx, ky, s, c } = *self;
        let along = (kx * vx + ky * vy) * (1.0 - c);
        (
            vx * c + ky * vz * s + kx * along,
            vy * c - kx * vz * s + ky * along,
            vz * c + (kx * vy - ky * vx) * s,
        )
    }
}

/// The lift that turns a strand whose root-frame tip is `tip` toward the
/// normal: its axis in the tangent plane (a rotation vector direction) and
/// the angle that brings the tip onto the normal (0 for a tip on it).
pub(crate) fn toward_normal(tip: Vec3) -> (Vec2, f32) {
    let h = libm::sqrtf(tip.x * tip.x + tip.y * tip.y);
    if h > 0.0 {
        (Vec2::new(tip.y, -tip.x) / h, libm::atan2f(h, tip.z))
    } else {
        (Vec2::X, 0.0)
    }
}

/// The first angle `from * LIFT_STEP, (from + 1) * LIFT_STEP, ...` (each at
/// most `limit`, up to the right angle) that `clear` accepts, then one step
/// more when that is clear too and within `limit` (a margin against the
/// surface); `None` when none is clear.
pub(crate) fn first_clear(
    limit: f32,
    from: u32,
    mut clear: impl FnMut(f32) -> bool,
) -> Option<f32> {
    let a = (from..=LIFT_STEPS)
        .map(|k| (k as f32 * LIFT_STEP).min(limit))
        .find(|&a| clear(a))?;
    Some(if a + LIFT_STEP <= limit && clear(a + LIFT_STEP) {
        a + LIFT_STEP
    } else {
        a
    })
}

/// True when none of the points `0..count` is `inside`. The point `hint`
/// (the last, when `hint` is past it) is tested first, and the point found inside (if any) becomes the hint:
/// a tried rotation that does not free a strand mostly leaves the same
/// point inside, and one test then answers. The answer does not depend on
/// the order.
pub(crate) fn none_inside(
    count: usize,
    hint: &mut usize,
    mut inside: impl FnMut(usize) -> bool,
) -> bool {
    let first = (*hint).min(count.saturating_sub(1));
    let found = core::iter::once(first)
        .filter(|&j| j < count)
        .chain((0..count).filter(|&j| j != first))
        .find(|&j| inside(j));
    if let Some(j) = found {
        *hint = j;
    }
    found.is_none()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn none_inside_answers_as_a_scan_and_keeps_the_point_it_found() {
        // every set of up to 6 points inside, from every hint (past the
        // end included)
        for count in 0..=6usize {
            for set in 0u32..1 << count {
                for start in 0..=count + 1 {
                    let is_inside = |j: usize| set & (1 << j) != 0;
                    let (mut hint, mut tests) = (start, 0);
                    let clear = none_inside(count, &mut hint, |j| {
                        tests += 1;
                        is_inside(j)
                    });
                    assert_eq!(clear, set == 0);
                    assert!(tests <= count, "a point tested twice");
                    if clear {
                        assert_eq!((hint, tests), (start, count));
                    } else {
                        assert!(is_inside(hint));
                    }
                    // asked again, the kept point answers in one test
                    if !clear {
                        let mut again = 0;
                        assert!(!none_inside(count, &mut hint, |j| {
                            again += 1;
                            is_inside(j)
                        }));
                        assert_eq!(again, 1);
                    }
                }
            }
        }
    }
}
