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
    /// Random variation of the length, 0 to 1: each strand keeps `1 - v u`
    /// of its length, `u` uniform in [0, 1) and keyed by its id, so the
    /// tips do not end on one surface (0, the default: every strand its
    /// interpolated length).
    pub length_random: ScalarMap<'a>,
    /// Random variation of the clump pull, 0 to 1, likewise: clumps whose
    /// hairs gather by different amounts have soft borders, not one edge.
    pub clump_random: ScalarMap<'a>,
}

/// Every default is a constant map (the C API hands them out as constants).
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
            length_random: ScalarMap::Constant(0.0),
            clump_random: ScalarMap::Constant(0.0),
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
    /// [`settle`](crate::interp::settle) where a strand would enter the body.
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
        self.clump.validate(mesh, "clump map")?;
        self.length_random.validate(mesh, "length random map")?;
        self.clump_random.validate(mesh, "clump random map")
    }

    /// Evaluates the maps at each root into `out` (same length as `roots`).
    /// Negative widths and lengths clamp to 0, clump and the random
    /// variations to [0, 1]. Every random value is keyed by `seed` and the
    /// strand's id, so a strand keeps its look in any order or patch.
    pub fn evaluate(
        &self,
        mesh: &Mesh,
        roots: &[Root],
        seed: u64,
        out: &mut [StrandGroom],
    ) -> Result<(), Error> {
        if out.len() < roots.len() {
            return Err(Error::OutputTooSmall {
                needed: roots.len(),
                available: out.len(),
            });
        }
        mesh.validate()?;
        self.validate(mesh)?;
        crate::root::check_roots(mesh, roots, "strand roots")?;
        for (r, g) in roots.iter().zip(out.iter_mut()) {
            let at = |m: &ScalarMap| m.sample(mesh, r.face as usize, r.u, r.v);
            // a variation of 0 multiplies by exactly 1: the values without
            // one keep their bits
            let kept = |m: &ScalarMap, purpose| {
                1.0 - at(m).clamp(0.0, 1.0) * rng::unit(seed, r.id as u64, purpose, 0)
            };
            *g = StrandGroom {
                length: at(&self.length).max(0.0)
                    * kept(&self.length_random, Purpose::LengthRandom),
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
                clump: at(&self.clump).clamp(0.0, 1.0)
                    * kept(&self.clump_random, Purpose::ClumpRandom),
                lift: [0.0; 2],
            };
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::map::{Texels, Texture};
    use crate::testmesh::{graded_plane, roots};
    use crate::Strided;

    /// A linear function of the surface point: barycentric and bilinear
    /// interpolation both reproduce it exactly, so every strand's value is
    /// known.
    fn linear(x: f32, y: f32) -> f32 {
        0.2 + 0.5 * x + 0.25 * y
    }

    #[test]
    fn maps_give_each_strand_the_value_at_its_root() {
        // the plane's UVs are its x and y, so all three maps below hold the
        // same function; a 64 x 64 float texture and an 8-bit one quantized
        // to 1/255
        let m = graded_plane(12, 4.0);
        let mesh = m.mesh();
        let per_vertex: Vec<f32> = m.p.iter().map(|p| linear(p[0], p[1])).collect();
        let size = 64;
        let centre = |i: usize| (i as f32 + 0.5) / size as f32;
        let texels: Vec<f32> = (0..size * size)
            .map(|i| linear(centre(i % size), centre(i / size)))
            .collect();
        let bytes: Vec<u8> = texels.iter().map(|v| (v * 255.0).round() as u8).collect();
        let texture = |texels, row_stride| {
            ScalarMap::Texture(Texture {
                texels,
                width: size,
                height: size,
                row_stride,
            })
        };
        let maps = GroomMaps {
            length: ScalarMap::PerVertex(Strided::from_slice(&per_vertex)),
            root_width: texture(Texels::F32(bytemuck::cast_slice(&texels)), 4 * size),
            tip_width: texture(Texels::U8(&bytes), size),
            bend: ScalarMap::Constant(-0.1),
            kink_amplitude: ScalarMap::Constant(0.02),
            kink_frequency: ScalarMap::Constant(4.0),
            clump: ScalarMap::PerVertex(Strided::from_slice(&per_vertex)),
            ..GroomMaps::default()
        };
        let rs = roots(mesh, 2000, 4);
        let mut out = vec![StrandGroom::default(); rs.len()];
        maps.evaluate(&mesh, &rs, 9, &mut out).unwrap();
        let mut inside = 0;
        for (r, g) in rs.iter().zip(&out) {
            let p = mesh.point(r.face as usize, r.u, r.v);
            let want = linear(p.x, p.y);
            assert!(
                (g.length - want).abs() < 1e-5,
                "per-vertex {} vs {want}",
                g.length
            );
            assert!((g.clump - want.min(1.0)).abs() < 1e-5, "clamped clump");
            assert_eq!(
                (g.bend, g.kink_amplitude, g.kink_frequency),
                (-0.1, 0.02, 4.0)
            );
            // within half a texel of the border the lookup clamps
            let interior = (0.5 / size as f32..1.0 - 0.5 / size as f32).contains(&p.x)
                && (0.5 / size as f32..1.0 - 0.5 / size as f32).contains(&p.y);
            if interior {
                inside += 1;
                assert!((2.0 * g.root_radius - want).abs() < 1e-5, "float texture");
                assert!(
                    (2.0 * g.tip_radius - want).abs() < 0.5 / 255.0 + 1e-5,
                    "8-bit texture"
                );
            }
            let [c, s] = g.kink_phase;
            assert!((c * c + s * s - 1.0).abs() < 1e-5);
        }
        assert!(inside > rs.len() * 9 / 10);
        // the phase is keyed by strand id alone: the same ids in another
        // order, on other faces, give the same phases; another seed does not
        let mut moved: Vec<crate::Root> = rs.iter().rev().copied().collect();
        for (r, o) in moved.iter_mut().zip(rs.iter()) {
            (r.face, r.u, r.v) = (o.face, o.u, o.v);
        }
        let mut again = vec![StrandGroom::default(); rs.len()];
        maps.evaluate(&mesh, &moved, 9, &mut again).unwrap();
        for (r, g) in moved.iter().zip(&again) {
            let first = rs.iter().position(|o| o.id == r.id).unwrap();
            assert_eq!(g.kink_phase, out[first].kink_phase);
        }
        maps.evaluate(&mesh, &rs, 10, &mut again).unwrap();
        let same = again
            .iter()
            .zip(&out)
            .filter(|(a, b)| a.kink_phase == b.kink_phase);
        assert!(same.count() < rs.len() / 100);
    }

    #[test]
    fn negative_values_clamp() {
        let m = graded_plane(4, 1.0);
        let mesh = m.mesh();
        let maps = GroomMaps {
            length: ScalarMap::Constant(-1.0),
            root_width: ScalarMap::Constant(-0.1),
            tip_width: ScalarMap::Constant(-0.1),
            clump: ScalarMap::Constant(-2.0),
            ..GroomMaps::default()
        };
        let rs = roots(mesh, 50, 1);
        let mut out = vec![StrandGroom::default(); rs.len()];
        maps.evaluate(&mesh, &rs, 0, &mut out).unwrap();
        assert!(out.iter().all(|g| g.length == 0.0
            && g.root_radius == 0.0
            && g.tip_radius == 0.0
            && g.clump == 0.0));
    }

    #[test]
    fn random_variations_spread_length_and_clump_by_strand_id() {
        let m = graded_plane(8, 1.0);
        let mesh = m.mesh();
        let rs = roots(mesh, 4000, 2);
        let plain = GroomMaps {
            clump: ScalarMap::Constant(0.8),
            ..GroomMaps::default()
        };
        let varied = GroomMaps {
            length_random: ScalarMap::Constant(0.5),
            clump_random: ScalarMap::Constant(1.0),
            ..plain
        };
        let mut base = vec![StrandGroom::default(); rs.len()];
        let mut out = base.clone();
        plain.evaluate(&mesh, &rs, 3, &mut base).unwrap();
        varied.evaluate(&mesh, &rs, 3, &mut out).unwrap();
        // lengths in (0.5, 1], uniform: mean 0.75; clump in (0, 0.8]
        let n = rs.len() as f32;
        let mean = |f: &dyn Fn(&StrandGroom) -> f32| out.iter().map(f).sum::<f32>() / n;
        assert!(out.iter().all(|g| g.length > 0.5 && g.length <= 1.0));
        assert!(out.iter().all(|g| g.clump > 0.0 && g.clump <= 0.8));
        assert!((mean(&|g| g.length) - 0.75).abs() < 0.01);
        assert!((mean(&|g| g.clump) - 0.4).abs() < 0.015);
        // independent streams: length and clump do not move together
        let cov = mean(&|g| (g.length - 0.75) * (g.clump - 0.4));
        assert!(cov.abs() < 0.003, "{cov}");
        // everything else as without the variations, which change nothing
        for (a, b) in out.iter().zip(&base) {
            assert_eq!(
                (a.root_radius, a.tip_radius, a.kink_phase),
                (b.root_radius, b.tip_radius, b.kink_phase)
            );
            assert_eq!((b.length, b.clump), (1.0, 0.8));
        }
        // keyed by id: the same strand, listed elsewhere, varies alike
        let reversed: Vec<Root> = rs.iter().rev().copied().collect();
        let mut again = vec![StrandGroom::default(); rs.len()];
        varied.evaluate(&mesh, &reversed, 3, &mut again).unwrap();
        assert!(again.iter().rev().zip(&out).all(|(a, b)| a == b));
    }
}
