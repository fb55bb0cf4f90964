//! CCD inverse kinematics (paper 3.1, step 3): the guide's control points
//! are joints, the tip the end effector; from tip to root each joint turns
//! the chain beyond it toward the target, sweep after sweep, until the tip
//! is within the tolerance or the sweeps run out. Only rotations: every
//! segment keeps its length, and an unreachable target leaves the tip as
//! close to it as the chain reaches.
//!
//! Pure CCD turns the joints nearest the tip most (the tip curls first).
//! A stiffness per joint, from `root_stiffness` to `tip_stiffness`, lets a
//! joint take only part of its turn, so artists choose where the bend goes:
//! a stiff tip and a supple root sway the whole strand.

use glam::{Quat, Vec3};

/// IK parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkParams {
    /// Stop when the tip is this close to the target, as a share of the
    /// strand length (0..=1).
    pub tolerance: f32,
    /// Most sweeps from tip to root (1..=256).
    pub max_iterations: u32,
    /// Stiffness of the joint at the root (0..1): the share of its turn a
    /// joint does not take. 0 and 0 is pure CCD.
    pub root_stiffness: f32,
    /// Stiffness of the last joint before the tip (0..1); the joints
    /// between go linearly from the root's to the tip's.
    pub tip_stiffness: f32,
}

impl Default for IkParams {
    fn default() -> Self {
        IkParams {
            tolerance: 1e-2,
            max_iterations: 8,
            root_stiffness: 0.0,
            tip_stiffness: 0.9,
        }
    }
}

impl IkParams {
    /// True when every value is finite and in its range.
    pub fn is_valid(&self) -> bool {
        (0.0..=1.0).contains(&self.tolerance)
            && (1..=256).contains(&self.max_iterations)
            && (0.0..1.0).contains(&self.root_stiffness)
            && (0.0..1.0).contains(&self.tip_stiffness)
    }
}

/// Most joints a chain may have.
pub const MAX_JOINTS: usize = 64;

/// Turns the chain `joints` (`joints[0]` the root, which stays) so that
/// its last point approaches `target`; `lengths[i]` is the length segment
/// `i` keeps. `reach` scales the tolerance (the strand length).
pub fn solve(joints: &mut [Vec3], lengths: &[f32], target: Vec3, reach: f32, params: &IkParams) {
    let n = joints.len().min(MAX_JOINTS);
    if n < 2 {
        return;
    }
    let tolerance = params.tolerance * reach;
    let total: f32 = lengths[..n - 1].iter().sum();
    let out = target - joints[0];
    if out.length_squared() >= total * total {
        // out of reach: the closest pose is the chain stretched toward it
        let direction = out.normalize_or_zero();
        for i in 0..n - 1 {
            joints[i + 1] = joints[i] + direction * lengths[i];
        }
        return;
    }
    let mut turns = [Quat::IDENTITY; MAX_JOINTS];
    let last = (n - 2).max(1) as f32;
    for _ in 0..params.max_iterations {
        if joints[n - 1].distance(target) <= tolerance {
            break;
        }
        // within a sweep a turn about joint i moves only the joints past
        // it: joint i is where the sweep found it, and only the tip moves
        let mut tip = joints[n - 1];
        for i in (0..n - 1).rev() {
            let stiffness = params.root_stiffness
                + (params.tip_stiffness - params.root_stiffness) * (i as f32 / last);
            let turn = partial_arc(tip - joints[i], target - joints[i], 1.0 - stiffness);
            tip = joints[i] + turn * (tip - joints[i]);
            turns[i] = turn;
        }
        // segment i turned by every turn about joints 0..=i, the nearest
        // the root last (rotations keep lengths to rounding; the lengths
        // are made exact once, below)
        let mut turned = Quat::IDENTITY;
        let mut before = joints[0];
        for i in 0..n - 1 {
            turned *= turns[i];
            let segment = joints[i + 1] - before;
            before = joints[i + 1];
            joints[i + 1] = joints[i] + turned * segment;
        }
    }
    let mut before = joints[0];
    for i in 0..n - 1 {
        let segment = joints[i + 1] - before;
        before = joints[i + 1];
        joints[i + 1] = joints[i] + segment.normalize_or_zero() * lengths[i];
    }
}

/// The rotation that turns `from` toward `to`, taken by the share `amount`
/// (normalized linear interpolation from no turn): two square roots and
/// no trigonometry, without normalizing either vector first.
#[inline]
fn partial_arc(from: Vec3, to: Vec3, amount: f32) -> Quat {
    let lengths = libm::sqrtf(from.length_squared() * to.length_squared());
    if lengths == 0.0 {
        return Quat::IDENTITY;
    }
    let d = from.dot(to);
    // (|a||b| + a.b, a x b) is the half-angle quaternion scaled by 2 |a||b| cos(angle / 2)
    let (w, v) = if d < -0.9999 * lengths {
        // opposite: half a turn about any axis across them
        (0.0, from.any_orthonormal_vector())
    } else {
        (lengths + d, from.cross(to))
    };
    // the share of the turn: blend with no turn, both at the same scale
    let scale = libm::sqrtf(w * w + v.length_squared());
    let (w, v) = ((1.0 - amount) * scale + amount * w, v * amount);
    let norm = libm::sqrtf(w * w + v.length_squared());
    Quat::from_xyzw(v.x / norm, v.y / norm, v.z / norm, w / norm)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight(n: usize) -> (Vec<Vec3>, Vec<f32>) {
        let joints = (0..n)
            .map(|i| Vec3::new(0.0, 0.0, i as f32 * 0.1))
            .collect();
        (joints, vec![0.1; n - 1])
    }

    fn lengths_kept(joints: &[Vec3], lengths: &[f32]) -> bool {
        joints
            .windows(2)
            .zip(lengths)
            .all(|(w, &l)| (w[0].distance(w[1]) - l).abs() < 1e-6)
    }

    #[test]
    fn reaches_a_reachable_target_and_keeps_every_length() {
        let (mut joints, lengths) = straight(16);
        let target = Vec3::new(0.6, 0.2, 1.1);
        let pure = IkParams {
            root_stiffness: 0.0,
            tip_stiffness: 0.0,
            max_iterations: 64,
            tolerance: 1e-3,
        };
        solve(&mut joints, &lengths, target, 1.5, &pure);
        assert!(joints[15].distance(target) <= 1.5e-3, "{}", joints[15]);
        assert!(lengths_kept(&joints, &lengths));
        assert_eq!(joints[0], Vec3::ZERO);
    }

    #[test]
    fn an_unreachable_target_gets_the_closest_reach() {
        let (mut joints, lengths) = straight(8);
        let target = Vec3::new(3.0, 0.0, 3.0);
        let params = IkParams {
            max_iterations: 64,
            ..IkParams::default()
        };
        solve(&mut joints, &lengths, target, 0.7, &params);
        // fully stretched toward the target
        let reach = joints[7].length();
        assert!((reach - 0.7).abs() < 1e-3, "{reach}");
        assert!(joints[7].normalize().dot(target.normalize()) > 0.999);
        assert!(lengths_kept(&joints, &lengths));
    }

    /// The turn at each inner joint (between its two segments).
    fn turns(joints: &[Vec3]) -> Vec<f32> {
        (1..joints.len() - 1)
            .map(|i| (joints[i] - joints[i - 1]).angle_between(joints[i + 1] - joints[i]))
            .collect()
    }

    /// The share of the bend in the half of the strand nearer the root.
    fn root_share(joints: &[Vec3]) -> f32 {
        let t = turns(joints);
        t[..t.len() / 2].iter().sum::<f32>() / t.iter().sum::<f32>()
    }

    #[test]
    fn stiffness_moves_the_bend_from_the_tip_to_the_root() {
        let pure = IkParams {
            root_stiffness: 0.0,
            tip_stiffness: 0.0,
            max_iterations: 64,
            tolerance: 1e-3,
        };
        let profiled = IkParams {
            tip_stiffness: 0.95,
            ..pure
        };
        for target in [Vec3::new(0.5, 0.0, 1.35), Vec3::new(0.9, 0.0, 0.9)] {
            let (mut a, lengths) = straight(16);
            let mut b = a.clone();
            solve(&mut a, &lengths, target, 1.5, &pure);
            solve(&mut b, &lengths, target, 1.5, &profiled);
            let (tip_first, spread) = (root_share(&a), root_share(&b));
            // pure CCD bends the tip half about four times as much as the root
            // half; the profile moves a good part of the bend to the root
            assert!(tip_first < 0.25, "pure CCD: root half takes {tip_first}");
            assert!(
                spread > 1.5 * tip_first,
                "profile: {spread}, pure: {tip_first}"
            );
            assert!(b[15].distance(target) < 3e-3);
            assert!(lengths_kept(&b, &lengths));
        }
    }

    #[test]
    fn zero_length_segments_stay_finite() {
        let mut joints = vec![
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 0.1),
            Vec3::new(0.0, 0.0, 0.1),
        ];
        let lengths = [0.0, 0.1, 0.0];
        solve(
            &mut joints,
            &lengths,
            Vec3::new(0.1, 0.0, 0.0),
            0.1,
            &IkParams::default(),
        );
        assert!(joints.iter().all(|p| p.is_finite()));
        assert!(lengths_kept(&joints, &lengths));
    }
}
