//! Stored lengths along a curve and the cut: a length is a fraction of a
//! strand's curve parameter in 16 bits ([`WHOLE`] is the whole strand).
//! Shared by the push-out (a strand cut where it enters a collider),
//! expansion (a trimmed render strand) and trimming (the shot's lengths).

/// The stored length of a whole (untrimmed) strand.
pub const WHOLE: u16 = u16::MAX;

/// Cuts an expanded curve's `points` (evenly spaced along the strand) at
/// stored length `length`: the points are respread over the kept part, so
/// the count stays and the kept part keeps its shape and radii.
pub(crate) fn cut(points: &mut [[f32; 4]], length: u16) {
    let n = points.len();
    if length == WHOLE || n < 2 {
        return;
    }
    let f = length as f32 / WHOLE as f32;
    // in place from the tip down: point k reads the points at f k and the
    // next, both at most k (f < 1), so not yet rewritten; the root stays
    for k in (1..n).rev() {
        let u = f * k as f32;
        let i = (u as usize).min(n - 2);
        let a = u - i as f32;
        let (lo, hi) = (points[i], points[i + 1]);
        points[k] = [
            lo[0] + (hi[0] - lo[0]) * a,
            lo[1] + (hi[1] - lo[1]) * a,
            lo[2] + (hi[2] - lo[2]) * a,
            lo[3] + (hi[3] - lo[3]) * a,
        ];
    }
}
