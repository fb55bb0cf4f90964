//! Per-strand groom parameters from grayscale maps.

use crate::rng::{self, Purpose};
use crate::{Error, Mesh, Root, ScalarMap};
use bytemuck::{Pod, Zeroable};

/// Maps (or constants) that drive the look of each strand, sampled at the root.
#[derive(Clone, Copy, Debug)]
pub struct GroomMaps<'a> {
    /// Multiplies the interpolated strand length.
    pub length: ScalarMap<'a>,
    /// Strand width (diameter) at the root, world units.
    pub root_width: ScalarMap<'a>,
    /// Strand width at the tip.
    pub tip_width: ScalarMap<'a>,
    /// Curl toward the root tangent: tip offset as a fraction of the length.
    pub bend: ScalarMap<'a>,
    /// Kink amplitude as a fraction of the length (the paper's small perturbations).
    pub kink_amplitude: ScalarMap<'a>,
    /// Kink waves along the strand.
    pub kink_frequency: ScalarMap<'a>,
    /// Pull of the tip toward the clump centre guide, 0 (none) to 1 (onto it).
    pub clump: ScalarMap<'a>,
}

impl Default for GroomMaps<'_> {
    fn default() -> Self {
        GroomMaps {
            length: ScalarMap::Constant(1.0),
            root_width: ScalarMap::Constant(0.002),
            tip_width: ScalarMap::Constant(0.0005),
            bend: ScalarMap::Constant(0.0),
            kink_amplitude: ScalarMap::Constant(0.0),
            kink_frequency: ScalarMap::Constant(3.0),
            clump: ScalarMap::Constant(0.0),
        }
    }
}

/// Groom values of one strand, evaluated once per groom.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct StrandGroom {
    /// Length multiplier.
    pub length: f32,
    /// Radius at the root.
    pub root_radius: f32,
    /// Radius at the tip.
    pub tip_radius: f32,
    /// Bend (fraction of length).
    pub bend: f32,
    /// Kink amplitude (fraction of length).
    pub kink_amplitude: f32,
    /// Kink waves along the strand.
    pub kink_frequency: f32,
    /// Kink phase, random per strand id, as the unit vector (cos, sin) of
    /// the angle (expansion needs no trigonometry per strand).
    pub kink_phase: [f32; 2],
    /// Clump pull at the tip.
    pub clump: f32,
    /// Rotation of the whole strand about its root, as a rotation vector in
    /// the root frame's tangent plane (tangent and bitangent components; its
    /// length is the angle in radians): 0 from the maps, set by
    /// [`settle`](crate::settle) where a strand would enter the body.
    pub lift: [f32; 2],
}

impl GroomMaps<'_> {
    /// Checks every map against `mesh`.
    pub fn validate(&self, mesh: &Mesh) -> Result<(), Error> {
        self.length.validate(mesh, "length map")?;
        self.root_width.validate(mesh, "root width map")?;
        self.tip_width.validate(mesh, "tip width map")?;
        self.bend.validate(mesh, "bend map")?;
        self.kink_amplitude.validate(mesh, "kink amplitude map")?;
        self.kink_frequency.validate(mesh, "kink frequency map")?;
        self.clump.validate(mesh, "clump map")
    }

    /// Evaluates the maps at each root into `out` (same length as `roots`).
    /// Negative widths and lengths clamp to 0, clump to [0, 1].
    pub fn evaluate(
        &self,
        mesh: &Mesh,
        roots: &[Root],
        seed: u64,
        out: &mut [StrandGroom],
    ) -> Result<(), Error> {
        if out.len() < roots.len() {
            return Err(Error::CapacityExceeded {
                needed: roots.len(),
                available: out.len(),
            });
        }
        mesh.validate()?;
        self.validate(mesh)?;
        crate::root::check_roots(mesh, roots, "strand roots")?;
        for (r, g) in roots.iter().zip(out.iter_mut()) {
            let at = |m: &ScalarMap| m.sample(mesh, r.face as usize, r.u, r.v);
            *g = StrandGroom {
                length: at(&self.length).max(0.0),
                root_radius: 0.5 * at(&self.root_width).max(0.0),
                tip_radius: 0.5 * at(&self.tip_width).max(0.0),
                bend: at(&self.bend),
                kink_amplitude: at(&self.kink_amplitude),
                kink_frequency: at(&self.kink_frequency),
                kink_phase: {
                    let angle = rng::unit(seed, r.id as u64, Purpose::KinkPhase, 0)
                        * core::f32::consts::TAU;
                    let (sin, cos) = libm::sincosf(angle);
                    [cos, sin]
                },
                clump: at(&self.clump).clamp(0.0, 1.0),
                lift: [0.0; 2],
            };
        }
        Ok(())
    }
}
