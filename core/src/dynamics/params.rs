//! The simulation's parameters.

use super::ik::{self, IkParams};
use super::links::LinkParams;
use super::spring::TipSpring;
use crate::surface::map::ScalarMap;
use crate::Error;

/// Most joints a guide is simulated with, and most points it is written with.
pub const MAX_JOINTS: usize = ik::MAX_JOINTS;

/// Simulation parameters.
#[derive(Clone, Copy, Debug)]
pub struct SimParams<'m> {
    /// Joints per guide (2..=64): the guides are resampled to it.
    pub joints: usize,
    /// Points per posed guide written (2..=64): the Catmull-Rom curve
    /// through the joints, resampled (equal to `joints`: the joints).
    pub points: usize,
    /// Tip spring frequency per guide in hertz (0..=1000), at its root.
    pub frequency: ScalarMap<'m>,
    /// Tip spring amplitude per guide (0..=1), at its root.
    pub amplitude: ScalarMap<'m>,
    /// Tip spring decay rate per guide in 1/s (0..=10000), at its root.
    pub decay: ScalarMap<'m>,
    /// IK.
    pub ik: IkParams,
    /// Tip links.
    pub links: LinkParams,
    /// A step whose roots move, on average, farther than this many times
    /// the extent of the roots (the diagonal of their bounding box) is a
    /// cut (a new shot, a reset of the animation): every guide's swing is
    /// carried rigidly with its root frame, without a whip, and the body
    /// starts from rest in its new place (> 0). A rigid spin about an axis
    /// through the body moves the roots less than its extent per step, so
    /// the default, 1, never takes one for a cut.
    pub teleport: f32,
    /// Where another simulator takes over (paper 3.3: regions re-simulated
    /// in Maya nHair from the cached data), per guide at its root, 0..=1:
    /// the share of the host's curves ([`Sim::begin`](super::sim::Sim::begin)'s `external`) in the
    /// posed guide; 0 (the default) is pelage's dynamics alone, and a map
    /// that fades blends the two across the region's border.
    pub external: ScalarMap<'m>,
}

impl Default for SimParams<'_> {
    fn default() -> Self {
        let spring = TipSpring::default();
        SimParams {
            joints: 16,
            points: 16,
            frequency: ScalarMap::Constant(spring.frequency),
            amplitude: ScalarMap::Constant(spring.amplitude),
            decay: ScalarMap::Constant(spring.decay),
            ik: IkParams::default(),
            links: LinkParams::default(),
            teleport: 1.0,
            external: ScalarMap::Constant(0.0),
        }
    }
}

impl SimParams<'_> {
    /// Checks the counts and constants (map values are checked per guide
    /// by [`Sim::new`](super::sim::Sim::new)).
    pub fn check(&self) -> Result<(), Error> {
        if !(2..=MAX_JOINTS).contains(&self.joints) || !(2..=MAX_JOINTS).contains(&self.points) {
            return Err(Error::InvalidArgument(
                "joints and points must be in 2..=64",
            ));
        }
        let ik = &self.ik;
        let links = &self.links;
        let values = [
            ("IK tolerance", ik.tolerance),
            ("IK root stiffness", ik.root_stiffness),
            ("IK tip stiffness", ik.tip_stiffness),
            ("link radius", links.radius),
            ("link stiffness", links.stiffness),
            ("teleport", self.teleport),
        ];
        if let Some((what, _)) = values.iter().find(|(_, x)| !x.is_finite()) {
            return Err(Error::NonFinite { what, index: 0 });
        }
        if !self.ik.is_valid() {
            return Err(Error::InvalidArgument(
                "IK: tolerance 0..=1, max_iterations 1..=256, stiffness 0..1",
            ));
        }
        if !self.links.is_valid() {
            return Err(Error::InvalidArgument(
                "links: radius 0..=1e9, max_links 0..=16, iterations 0..=16, stiffness 0..=1",
            ));
        }
        if !(self.teleport > 0.0 && self.teleport <= 1e9) {
            return Err(Error::InvalidArgument("teleport must be in (0, 1e9]"));
        }
        Ok(())
    }
}

/// Shortest step: below it the neutral tip's speed (distance over dt)
/// leaves the float range for ordinary motion.
pub const MIN_DT: f32 = 1e-5;

/// One guide's constants: its parameters sampled from the maps at its
/// root, and its length.
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(crate) struct GuideConstants {
    pub(crate) spring_frequency: f32,
    pub(crate) spring_amplitude: f32,
    pub(crate) spring_decay: f32,
    /// Sum of the segment lengths.
    pub(crate) reach: f32,
    /// Share of the host's curves in the posed guide.
    pub(crate) external: f32,
}
