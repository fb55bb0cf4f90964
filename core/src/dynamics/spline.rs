//! The output curve (paper 3.1, step 4): a uniform Catmull-Rom spline
//! through the joints, resampled to the point count the render hairs are
//! expanded from. With as many points as joints it is the joints
//! themselves.

use glam::Vec3;

/// Writes `out.len()` points of the Catmull-Rom spline through `joints`
/// (at least 2), evenly in the spline's parameter from the first joint to
/// the last. The ends are extended by mirroring the end segments. As many
/// points as joints are the joints, exactly.
pub fn resample(joints: &[Vec3], out: &mut [Vec3]) {
    let n = joints.len();
    let m = out.len();
    if n < 2 || m == 0 {
        return;
    }
    if m == n {
        // the spline passes through every joint: the evaluation at them
        // would only round the last one
        out.copy_from_slice(joints);
        return;
    }
    if m == 1 {
        out[0] = joints[0];
        return;
    }
    let at = |i: isize| -> Vec3 {
        if i < 0 {
            joints[0] * 2.0 - joints[1]
        } else if i as usize >= n {
            joints[n - 1] * 2.0 - joints[n - 2]
        } else {
            joints[i as usize]
        }
    };
    let span = (n - 1) as f32 / (m - 1) as f32;
    for (k, o) in out.iter_mut().enumerate() {
        let s = k as f32 * span;
        let i = (s as usize).min(n - 2);
        let t = s - i as f32;
        let (p0, p1, p2, p3) = (
            at(i as isize - 1),
            at(i as isize),
            at(i as isize + 1),
            at(i as isize + 2),
        );
        let (t2, t3) = (t * t, t * t * t);
        *o = (p1 * 2.0
            + (p2 - p0) * t
            + (p0 * 2.0 - p1 * 5.0 + p2 * 4.0 - p3) * t2
            + (p1 * 3.0 - p0 - p2 * 3.0 + p3) * t3)
            * 0.5;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_through_the_joints_and_between_them_smoothly() {
        let joints: Vec<Vec3> = (0..6)
            .map(|i| Vec3::new(i as f32, libm::sinf(i as f32), 0.0))
            .collect();
        let mut same = vec![Vec3::ZERO; 6];
        resample(&joints, &mut same);
        assert_eq!(same, joints);
        let mut fine = vec![Vec3::ZERO; 51];
        resample(&joints, &mut fine);
        for k in 0..6 {
            assert!(fine[k * 10].distance(joints[k]) < 1e-5);
        }
        // no jump between neighbouring samples
        assert!(fine.windows(2).all(|w| w[0].distance(w[1]) < 0.2));
    }
}
