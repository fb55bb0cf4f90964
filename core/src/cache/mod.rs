//! Render-time files (paper 2.1-2.2): only guides go to disk per frame, and
//! a renderer grows the fur itself.
//!
//! - [`groom_file`]: written once per asset; everything a renderer needs
//!   besides the per-frame guides and the deformed mesh.
//! - [`guide_cache`]: one frame's posed guides (each shutter sample), coded
//!   against their neutral pose in their root frames, decoded straight into
//!   a [`PosedFrame`](crate::interp::posed::PosedFrame).
//! - [`trim_file`]: a frame's trim records, and a shot's shortest length
//!   per strand (paper 3.3).
//! - `container` (internal): the framing both share (magic, version, counts, a
//!   CRC-32), and bounds-checked reading.
//! - `bits` (internal): bits least significant first, and the Rice code the
//!   guide cache writes in.
//!
//! All are little-endian and documented byte by byte in `docs/FORMAT.md`.
//! Decoding never trusts the bytes: every count, index, width and float is
//! checked before it is used, and a failed decode writes nothing.

mod bits;
pub(crate) mod container;
pub mod groom_file;
pub mod guide_cache;
pub mod trim_file;

#[cfg(test)]
pub(crate) mod fixture {
    //! A small groom on a sphere, and posed frames of it.
    use super::groom_file::Groom;
    use crate::arena::{Arena, ArenaLayout};
    use crate::guides::{CvLayout, Guides};
    use crate::interp::bind::{StrandBinding, MAX_NEIGHBOURS, NO_GUIDE};
    use crate::interp::groom::StrandGroom;
    use crate::interp::posed::PosedFrame;
    use crate::interp::strands::Strands;
    use crate::testmesh::{roots, sphere, straight_guides, TestMesh};
    use crate::{Root, Strided};

    pub const POINTS: usize = 8;

    pub struct Scene {
        pub rest: TestMesh,
        pub guide_roots: Vec<Root>,
        pub guide_world: Vec<[f32; 3]>,
        pub guide_local: Vec<[f32; 3]>,
        pub roots: Vec<Root>,
        pub bindings: Vec<StrandBinding>,
        pub grooms: Vec<StrandGroom>,
        pub patches: Vec<crate::interp::patch::Patch>,
    }

    impl Scene {
        pub fn new(guides: u32) -> Scene {
            let rest = sphere(16, 32);
            let guide_roots = roots(rest.mesh(), guides, 3);
            let guide_world = straight_guides(&rest.mesh(), &guide_roots, POINTS, 0.3);
            let strand_roots = roots(rest.mesh(), 200, 5);
            let g = guide_roots.len() as u32;
            let bindings = (0..strand_roots.len() as u32)
                .map(|i| {
                    let mut b = StrandBinding {
                        guides: [0; MAX_NEIGHBOURS],
                        weights: [0.0; MAX_NEIGHBOURS],
                        count: 2,
                        clump: if i % 7 == 0 { NO_GUIDE } else { i % g },
                    };
                    b.guides[..2].copy_from_slice(&[i % g, (i * 3 + 1) % g]);
                    b.weights[..2].copy_from_slice(&[0.25, 0.75]);
                    b
                })
                .collect::<Vec<_>>();
            let grooms = (0..strand_roots.len())
                .map(|i| StrandGroom {
                    length: 1.0,
                    root_radius: 0.01,
                    tip_radius: 0.001,
                    bend: 0.1,
                    kink_amplitude: 0.02 * i as f32,
                    kink_frequency: 3.0,
                    kink_phase: [1.0, 0.0],
                    clump: 0.2,
                    lift: [0.0, 0.1],
                })
                .collect();
            let mut scene = Scene {
                rest,
                guide_roots,
                guide_world,
                guide_local: vec![],
                patches: (0..strand_roots.len() as u32)
                    .step_by(64)
                    .map(|first| crate::interp::patch::Patch {
                        first,
                        count: 64.min(strand_roots.len() as u32 - first),
                    })
                    .collect(),
                roots: strand_roots,
                bindings,
                grooms,
            };
            let rest_mesh = scene.rest.clone();
            let world = scene.guide_world.clone();
            scene.guide_local =
                scene.with_frame(&rest_mesh, &world, |f| f.local_points().collect());
            scene
        }

        pub fn groom(&self) -> Groom<'_> {
            Groom {
                guide_roots: &self.guide_roots,
                guide_points: &self.guide_local,
                points: POINTS,
                strands: Strands {
                    roots: &self.roots,
                    bindings: &self.bindings,
                    grooms: &self.grooms,
                },
                patches: &self.patches,
            }
        }

        /// Runs `f` on a frame of `mesh` posed with guides `world`.
        pub fn with_frame<T>(
            &self,
            mesh: &TestMesh,
            world: &[[f32; 3]],
            f: impl FnOnce(&mut PosedFrame) -> T,
        ) -> T {
            let mut layout = ArenaLayout::new();
            let g = self.guide_roots.len();
            PosedFrame::layout(&mut layout, mesh.p.len(), g, POINTS);
            let mut buf = vec![0u8; layout.bytes()];
            let guides = Guides {
                roots: &self.guide_roots,
                points: Strided::from_slice(world),
                layout: CvLayout::Fixed(POINTS),
            };
            let mut frame =
                PosedFrame::with_guides(mesh.mesh(), &guides, POINTS, &mut Arena::new(&mut buf))
                    .unwrap();
            f(&mut frame)
        }

        /// The sphere bent and stretched (time `t`), and guides on it that
        /// swing away from their rest shape.
        pub fn posed(&self, t: f32) -> (TestMesh, Vec<[f32; 3]>) {
            let mut mesh = self.rest.clone();
            for p in mesh.p.iter_mut() {
                let [x, y, z] = *p;
                *p = [
                    x * (1.0 + 0.2 * t) + 0.3 * t * libm::sinf(2.0 * y),
                    y + 5.0 * t,
                    z * (1.0 - 0.1 * t) + 0.2 * t * x * x,
                ];
            }
            let mut world = straight_guides(&mesh.mesh(), &self.guide_roots, POINTS, 0.3);
            for (k, p) in world.iter_mut().enumerate() {
                let along = (k % POINTS) as f32 / (POINTS - 1) as f32;
                p[0] += 0.1 * t * along * along;
                p[2] -= 0.05 * t * along;
            }
            (mesh, world)
        }
    }
}
