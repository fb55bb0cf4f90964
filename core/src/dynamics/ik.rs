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

use glam::Vec3;
use wide::{f32x8, CmpEq, CmpGt, CmpLt};

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

/// Chains solved together, one per SIMD lane.
pub const LANES: usize = 8;

type F = f32x8;

/// Points of [`LANES`] chains, one per lane.
#[derive(Clone, Copy)]
struct V {
    x: F,
    y: F,
    z: F,
}

impl V {
    const ZERO: V = V {
        x: F::ZERO,
        y: F::ZERO,
        z: F::ZERO,
    };

    #[inline]
    fn add(self, o: V) -> V {
        V {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }

    #[inline]
    fn sub(self, o: V) -> V {
        V {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }

    #[inline]
    fn scale(self, s: F) -> V {
        V {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }

    #[inline]
    fn dot(self, o: V) -> F {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    #[inline]
    fn cross(self, o: V) -> V {
        V {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }

    /// `t` where `mask` is set, `self` elsewhere.
    #[inline]
    fn unless(self, mask: F, t: V) -> V {
        V {
            x: mask.blend(t.x, self.x),
            y: mask.blend(t.y, self.y),
            z: mask.blend(t.z, self.z),
        }
    }

    fn set(&mut self, lane: usize, p: Vec3) {
        self.x.as_array_mut()[lane] = p.x;
        self.y.as_array_mut()[lane] = p.y;
        self.z.as_array_mut()[lane] = p.z;
    }

    fn get(&self, lane: usize) -> Vec3 {
        Vec3::new(
            self.x.as_array_ref()[lane],
            self.y.as_array_ref()[lane],
            self.z.as_array_ref()[lane],
        )
    }
}

/// Rotations of [`LANES`] chains, one per lane.
#[derive(Clone, Copy)]
struct Q {
    v: V,
    w: F,
}

impl Q {
    const IDENTITY: Q = Q {
        v: V::ZERO,
        w: F::ONE,
    };

    /// The Hamilton product `self * o`: `o` turns first.
    #[inline]
    fn mul(self, o: Q) -> Q {
        Q {
            w: self.w * o.w - self.v.dot(o.v),
            v: o.v
                .scale(self.w)
                .add(self.v.scale(o.w))
                .add(self.v.cross(o.v)),
        }
    }

    /// `p` turned by the (unit) rotation.
    #[inline]
    fn rotate(self, p: V) -> V {
        let b = self.v;
        let w = self.w;
        p.scale(w * w - b.dot(b))
            .add(b.scale(p.dot(b) * F::splat(2.0)))
            .add(b.cross(p).scale(w * F::splat(2.0)))
    }
}

/// [`LANES`] chains of the same joint count, one per lane, for
/// [`Chains::solve`]: a lane is loaded with [`Chains::load`] and read with
/// [`Chains::joint`]; lanes not loaded are left alone.
pub struct Chains {
    joints: [V; MAX_JOINTS],
    lengths: [F; MAX_JOINTS],
    target: V,
    reach: F,
    /// All bits set on a loaded lane.
    live: F,
}

impl Default for Chains {
    fn default() -> Self {
        Chains {
            joints: [V::ZERO; MAX_JOINTS],
            lengths: [F::ZERO; MAX_JOINTS],
            target: V::ZERO,
            reach: F::ZERO,
            live: F::ZERO,
        }
    }
}

impl Chains {
    /// Empties every lane.
    pub fn clear(&mut self) {
        self.live = F::ZERO;
    }

    /// Puts a chain (as [`solve`] takes it, in reach of its target: see
    /// [`stretch_if_unreachable`]) into `lane`.
    pub fn load(
        &mut self,
        lane: usize,
        joints: &[Vec3],
        lengths: &[f32],
        target: Vec3,
        reach: f32,
    ) {
        for (k, p) in joints.iter().enumerate().take(MAX_JOINTS) {
            self.joints[k].set(lane, *p);
        }
        for (k, l) in lengths.iter().enumerate().take(MAX_JOINTS) {
            self.lengths[k].as_array_mut()[lane] = *l;
        }
        self.target.set(lane, target);
        self.reach.as_array_mut()[lane] = reach;
        self.live.as_array_mut()[lane] = f32::from_bits(u32::MAX);
    }

    /// Joint `k` of the chain in `lane`.
    pub fn joint(&self, lane: usize, k: usize) -> Vec3 {
        self.joints[k].get(lane)
    }

    /// [`solve`] on every loaded lane, each chain of `n` joints on its own:
    /// a lane's result does not depend on the others. The sweeps run until
    /// every lane is within its tolerance or they run out; a lane that is
    /// done keeps its joints.
    pub fn solve(&mut self, n: usize, params: &IkParams) {
        let n = n.min(MAX_JOINTS);
        if n < 2 {
            return;
        }
        let tolerance = F::splat(params.tolerance) * self.reach;
        let target = self.target;
        let mut turns = [Q::IDENTITY; MAX_JOINTS];
        let last = (n - 2).max(1) as f32;
        let mut active = self.live;
        for _ in 0..params.max_iterations {
            let off = self.joints[n - 1].sub(target);
            active &= off.dot(off).sqrt().cmp_gt(tolerance);
            if active.none() {
                break;
            }
            // within a sweep a turn about joint i moves only the joints past
            // it: joint i is where the sweep found it, and only the tip moves
            let mut tip = self.joints[n - 1];
            for i in (0..n - 1).rev() {
                let stiffness = params.root_stiffness
                    + (params.tip_stiffness - params.root_stiffness) * (i as f32 / last);
                let at = self.joints[i];
                let turn = partial_arc(tip.sub(at), target.sub(at), 1.0 - stiffness);
                tip = at.add(turn.rotate(tip.sub(at)));
                turns[i] = turn;
            }
            // segment i turned by every turn about joints 0..=i, the nearest
            // the root last (rotations keep lengths to rounding; the lengths
            // are made exact once, below)
            let mut turned = Q::IDENTITY;
            let mut before = self.joints[0];
            for (i, &turn) in turns[..n - 1].iter().enumerate() {
                turned = turned.mul(turn);
                let segment = self.joints[i + 1].sub(before);
                before = self.joints[i + 1];
                let moved = self.joints[i].add(turned.rotate(segment));
                self.joints[i + 1] = self.joints[i + 1].unless(active, moved);
            }
        }
        // the sweeps stop within the tolerance, so a target that drifts
        // under it would leave the tip behind, then snap to it once the
        // drift crosses the tolerance: the chain turns rigidly about its
        // root until its tip points at the target, which the tip then
        // follows continuously down to rest
        let root = self.joints[0];
        let aim = partial_arc(self.joints[n - 1].sub(root), target.sub(root), 1.0);
        for k in 1..n {
            let turned = root.add(aim.rotate(self.joints[k].sub(root)));
            self.joints[k] = self.joints[k].unless(self.live, turned);
        }
        let mut before = self.joints[0];
        for i in 0..n - 1 {
            let segment = self.joints[i + 1].sub(before);
            before = self.joints[i + 1];
            let length = segment.dot(segment).sqrt();
            let recip = F::ONE / length;
            let unit = recip.is_finite() & recip.cmp_gt(F::ZERO);
            let exact =
                self.joints[i].add(segment.scale(unit.blend(recip, F::ZERO) * self.lengths[i]));
            self.joints[i + 1] = self.joints[i + 1].unless(self.live, exact);
        }
    }
}

/// Poses `joints` stretched toward `target` when it lies beyond the
/// chain's reach (the closest pose: CCD only creeps toward it) and returns
/// true; returns false and leaves them when it is in reach. A chain of
/// fewer than two joints has nothing to solve (true); a NaN target counts
/// as out of reach and folds every joint onto the root (finite, where CCD
/// would give NaN).
pub fn stretch_if_unreachable(joints: &mut [Vec3], lengths: &[f32], target: Vec3) -> bool {
    let n = joints.len().min(MAX_JOINTS);
    if n < 2 {
        return true;
    }
    let total: f32 = lengths[..n - 1].iter().sum();
    let out = target - joints[0];
    if out.length_squared() < total * total {
        return false;
    }
    let direction = out.normalize_or_zero();
    for i in 0..n - 1 {
        joints[i + 1] = joints[i] + direction * lengths[i];
    }
    true
}

/// Turns the chain `joints` (`joints[0]` the root, which stays) so that
/// its last point approaches `target`; `lengths[i]` is the length segment
/// `i` keeps. `reach` scales the tolerance (the strand length). One chain
/// through [`Chains`]: the same bits as when it shares them with others.
pub fn solve(joints: &mut [Vec3], lengths: &[f32], target: Vec3, reach: f32, params: &IkParams) {
    let n = joints.len().min(MAX_JOINTS);
    if stretch_if_unreachable(&mut joints[..n], lengths, target) {
        return;
    }
    let mut chains = Chains::default();
    chains.load(0, &joints[..n], &lengths[..n - 1], target, reach);
    chains.solve(n, params);
    for (k, p) in joints[..n].iter_mut().enumerate() {
        *p = chains.joint(0, k);
    }
}

/// The rotations that turn `from` toward `to`, taken by the share `amount`
/// (normalized linear interpolation from no turn): square roots and no
/// trigonometry, without normalizing either vector first; no turn where
/// either is zero.
#[inline]
fn partial_arc(from: V, to: V, amount: f32) -> Q {
    let lengths = (from.dot(from) * to.dot(to)).sqrt();
    let d = from.dot(to);
    // (|a||b| + a.b, a x b) is the half-angle quaternion scaled by 2 |a||b| cos(angle / 2)
    let opposite = d.cmp_lt(F::splat(-0.9999) * lengths);
    let (mut w, mut v) = (lengths + d, from.cross(to));
    // rare, and a root and two divisions: made only when a lane needs it
    if opposite.any() {
        // opposite: half a turn about an axis across them, made from the
        // unit `from` (the first of glam's any_orthonormal_pair)
        let unit = from.scale(F::ONE / from.dot(from).sqrt());
        let sign = F::ONE.copysign(unit.z);
        let a = F::splat(-1.0) / (sign + unit.z);
        let across = V {
            x: F::ONE + sign * unit.x * unit.x * a,
            y: sign * unit.x * unit.y * a,
            z: -(sign * unit.x),
        };
        w = opposite.blend(F::ZERO, w);
        v = v.unless(opposite, across);
    }
    // the share of the turn: blend with no turn, both at the same scale
    let scale = (w * w + v.dot(v)).sqrt();
    let amount = F::splat(amount);
    let (w, v) = ((F::ONE - amount) * scale + amount * w, v.scale(amount));
    let recip = F::ONE / (w * w + v.dot(v)).sqrt();
    let turn = Q {
        v: v.scale(recip),
        w: w * recip,
    };
    let none = lengths.cmp_eq(F::ZERO);
    Q {
        v: turn.v.unless(none, V::ZERO),
        w: none.blend(F::ONE, turn.w),
    }
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
