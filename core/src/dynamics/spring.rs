//! The tip spring (paper 3.1, step 2): the tip is a point mass tied to the
//! neutral tip by a zero-rest-length, damped spring.
//!
//! The state is the offset `y` of the simulated tip from the neutral tip and
//! its velocity `v`. Between steps the neutral tip moves at the constant
//! velocity it had over the step, so `y'' = -w^2 y - 2 decay y'` holds
//! exactly and is advanced with the closed-form solution: no time step is
//! too large, and a time step that changes mid-shot changes nothing but the
//! sampling. When the neutral tip's velocity changes between steps, the
//! tip keeps its own: `v` takes the difference (that is the lag).

use glam::Vec3;

/// The spring of one guide.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipSpring {
    /// Natural frequency in hertz (0..=1000): how fast the tip swings
    /// back. 0 is no spring (with no decay the tip drifts, bounded by the
    /// strand's reach).
    pub frequency: f32,
    /// Share of the oscillator's lag the tip shows (0..=1): 0 follows the
    /// neutral pose exactly, 1 shows the full lag; the state runs the same
    /// either way.
    pub amplitude: f32,
    /// Exponential decay rate of the swing in 1/s (0..=10000): the swing's
    /// envelope falls as e^(-decay t). 0 swings forever; above
    /// 2 pi frequency it creeps back without overshoot.
    pub decay: f32,
}

impl Default for TipSpring {
    fn default() -> Self {
        TipSpring {
            frequency: 1.5,
            amplitude: 1.0,
            decay: 3.0,
        }
    }
}

/// Largest frequency accepted.
pub const MAX_FREQUENCY: f32 = 1000.0;
/// Largest decay rate accepted.
pub const MAX_DECAY: f32 = 10000.0;

impl TipSpring {
    /// True when every value is finite and in its range.
    pub fn is_valid(&self) -> bool {
        (0.0..=MAX_FREQUENCY).contains(&self.frequency)
            && (0.0..=1.0).contains(&self.amplitude)
            && (0.0..=MAX_DECAY).contains(&self.decay)
    }

    /// Advances the offset `y` and its velocity `v` by `dt` seconds, exactly.
    pub fn advance(&self, y: Vec3, v: Vec3, dt: f32) -> (Vec3, Vec3) {
        let w = core::f32::consts::TAU * self.frequency;
        let (w2, l) = (w * w, self.decay);
        let q = w2 - l * l;
        // y(t) = e^(-l t) (y0 c + (v0 + l y0) s), v(t) = e^(-l t) (v0 c - (w^2 y0 + l v0) s)
        // with c, s the cosine-like and sine-like solutions of q; ec = e c, es = e s
        let (ec, es) = if q > 0.0 {
            let wd = libm::sqrtf(q);
            let (sin, cos) = libm::sincosf(wd * dt);
            let e = libm::expf(-l * dt);
            (e * cos, e * sin / wd)
        } else if q < 0.0 {
            // overdamped: cosh and sinh against e^(-l t), as exponentials
            // that never grow (l >= m), so a stiff decay cannot overflow
            let m = libm::sqrtf(-q);
            let e = libm::expf(-l * dt);
            let (a, b) = (libm::expf((m - l) * dt), libm::expf(-(m + l) * dt));
            // sinh(m t) / m near critical damping (m -> 0) without the
            // cancellation of a - b: e (expm1(m t) - expm1(-m t)) / (2 m)
            let s = e * (libm::expm1f(m * dt) - libm::expm1f(-m * dt)) / (2.0 * m);
            (
                0.5 * (a + b),
                if s.is_finite() { s } else { 0.5 * (a - b) / m },
            )
        } else {
            let e = libm::expf(-l * dt);
            (e, e * dt)
        };
        let y1 = y * ec + (v + y * l) * es;
        let v1 = v * ec - (y * w2 + v * l) * es;
        (y1, v1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_exact_step_does_not_depend_on_how_time_is_cut() {
        for spring in [
            TipSpring::default(),
            TipSpring {
                frequency: 0.0,
                amplitude: 1.0,
                decay: 0.0,
            },
            TipSpring {
                frequency: 0.5,
                amplitude: 1.0,
                decay: 40.0,
            },
            TipSpring {
                frequency: 3.0 / core::f32::consts::TAU,
                amplitude: 1.0,
                decay: 3.0,
            },
        ] {
            let (y0, v0) = (Vec3::new(0.1, -0.2, 0.05), Vec3::new(1.0, 0.0, -0.5));
            let (a, av) = spring.advance(y0, v0, 0.5);
            let (mut y, mut v) = (y0, v0);
            for _ in 0..120 {
                (y, v) = spring.advance(y, v, 0.5 / 120.0);
            }
            assert!(a.distance(y) < 1e-5 && av.distance(v) < 1e-4, "{spring:?}");
        }
    }

    #[test]
    fn a_damped_swing_dies_out_and_an_undamped_one_keeps_its_energy() {
        let damped = TipSpring::default();
        let (mut y, mut v) = (Vec3::X, Vec3::ZERO);
        for _ in 0..240 {
            (y, v) = damped.advance(y, v, 1.0 / 24.0);
        }
        assert!(y.length() < 1e-3 && v.length() < 1e-2);
        let free = TipSpring {
            decay: 0.0,
            ..damped
        };
        let w = core::f32::consts::TAU * free.frequency;
        let energy = |y: Vec3, v: Vec3| v.length_squared() + w * w * y.length_squared();
        let (mut y, mut v) = (Vec3::X, Vec3::ZERO);
        for _ in 0..1000 {
            (y, v) = free.advance(y, v, 1.0 / 12.0);
        }
        assert!((energy(y, v) / energy(Vec3::X, Vec3::ZERO) - 1.0).abs() < 1e-3);
    }
}
