//! The animated creature: a short shot that breaks physical hair solvers.
//! It walks, turns a quarter turn, jumps, sways its upper body (a bend, not
//! a rigid motion), and at [`TELEPORT_FRAME`] it is cut to a place 100
//! units away. Tests and benchmarks of the dynamics, caches and the farm
//! share it.

use crate::creature::CreatureMesh;
use crate::measure::mesh_view;
use glam::{Quat, Vec3};
use pelage::{PelageCapsule, PelageColliders};
use pelage_core::Root;

/// Frames per second of the shot.
pub const FPS: f32 = 24.0;
/// Frames in the shot.
pub const FRAMES: u32 = 96;
/// The frame at which the creature teleports (a cut).
pub const TELEPORT_FRAME: u32 = 72;

/// The rigid part of the pose at `frame`: turn and position.
pub fn placement(frame: u32) -> (Quat, Vec3) {
    let t = frame as f32 / FPS;
    // a quarter turn between 1 s and 2 s
    let s = ((t - 1.0).clamp(0.0, 1.0) * core::f32::consts::PI).cos();
    let yaw = core::f32::consts::FRAC_PI_4 * (1.0 - s);
    // a jump 0.4 high between 2 s and 2.5 s
    let j = ((t - 2.0) / 0.5).clamp(0.0, 1.0);
    let lift = 1.6 * j * (1.0 - j);
    let cut = if frame >= TELEPORT_FRAME { 100.0 } else { 0.0 };
    (Quat::from_rotation_y(yaw), Vec3::new(1.2 * t, lift, cut))
}

/// The creature at `frame` of the shot: the upper body sways (a bend that
/// grows with height), then the whole turns and moves. Normals turn with
/// the body (the sway's tilt of them is left out: it is small).
pub fn pose(rest: &CreatureMesh, frame: u32) -> CreatureMesh {
    let t = frame as f32 / FPS;
    let (turn, shift) = placement(frame);
    let sway = 0.08 * (core::f32::consts::TAU * 1.5 * t).sin();
    CreatureMesh {
        positions: rest
            .positions
            .iter()
            .map(|&p| {
                let up = p[1].max(0.0);
                let bent = Vec3::new(p[0] + sway * up * up, p[1], p[2]);
                (turn * bent + shift).to_array()
            })
            .collect(),
        normals: rest
            .normals
            .iter()
            .map(|&n| (turn * Vec3::from(n)).to_array())
            .collect(),
        ..rest.clone()
    }
}

/// Sixteen capsules that ride with the creature's lower body (props,
/// straps, a held stick), 0.03 off the skin, in the guides' way but clear
/// of every root of `guide_roots` (a root inside a collider has no way
/// out); placed at `frame` of the shot.
pub fn capsules(rest: &CreatureMesh, guide_roots: &[Root], frame: u32) -> Vec<PelageCapsule> {
    let mesh = mesh_view(rest);
    let roots: Vec<Vec3> = guide_roots
        .iter()
        .map(|r| mesh.point(r.face as usize, r.u, r.v))
        .collect();
    let (turn, shift) = placement(frame);
    let at = |p: Vec3| (turn * p + shift).to_array();
    // vertices below the sway (which bends only the upper body)
    let low: Vec<usize> = (0..rest.positions.len())
        .filter(|&i| rest.positions[i][1] < -0.05)
        .collect();
    (0..)
        .map(|k: usize| {
            let v = low[(k * 7919 + 13) % low.len()];
            let (p, n) = (Vec3::from(rest.positions[v]), Vec3::from(rest.normals[v]));
            let centre = p + n * 0.06;
            let along = n.any_orthonormal_vector() * 0.03;
            (centre - along, centre + along)
        })
        .filter(|&(a, b)| roots.iter().all(|&r| segment_distance(r, a, b) > 0.035))
        .take(16)
        .map(|(a, b)| PelageCapsule {
            a: at(a),
            b: at(b),
            radius: 0.03,
        })
        .collect()
}

/// Distance from `p` to the segment `a`-`b`.
pub fn segment_distance(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// Colliders of `capsules`, and the body when `body` is set.
pub fn colliders(capsules: &[PelageCapsule], body: bool) -> PelageColliders {
    PelageColliders {
        spheres: std::ptr::null(),
        sphere_count: 0,
        capsules: capsules.as_ptr(),
        capsule_count: capsules.len(),
        planes: std::ptr::null(),
        plane_count: 0,
        body: body as u32,
        distance: None,
        distance_user_data: std::ptr::null_mut(),
    }
}

/// The shot simulated: the rest creature, guide roots and rest guides, and
/// per frame the deformed mesh and the posed guides (world space).
pub struct SimulatedShot {
    /// The creature at rest.
    pub rest: CreatureMesh,
    /// Guide roots.
    pub roots: Vec<Root>,
    /// Rest guides, `points` per guide.
    pub rest_points: Vec<[f32; 3]>,
    /// Points per guide.
    pub points: usize,
    /// Each frame's deformed mesh.
    pub meshes: Vec<CreatureMesh>,
    /// Each frame's posed guides.
    pub posed: Vec<Vec<[f32; 3]>>,
}

impl SimulatedShot {
    /// The guides' rest shapes in their root frames on the rest creature,
    /// guide after guide (what a groom file stores).
    pub fn rest_local(&self) -> Vec<[f32; 3]> {
        use pelage_core::guides::{CvLayout, Guides};
        use pelage_core::interp::posed::PosedFrame;
        let mut layout = pelage_core::ArenaLayout::new();
        PosedFrame::layout(
            &mut layout,
            self.rest.positions.len(),
            self.roots.len(),
            self.points,
        );
        let mut buf = vec![0u8; layout.bytes()];
        let guides = Guides {
            roots: &self.roots,
            points: pelage_core::Strided::from_slice(&self.rest_points),
            layout: CvLayout::Fixed(self.points),
        };
        let arena = &mut pelage_core::Arena::new(&mut buf);
        let rest =
            PosedFrame::with_guides(mesh_view(&self.rest), &guides, self.points, arena).unwrap();
        rest.local_points().collect()
    }
}

/// A simulation (C API) of `joints`-joint guides on the rest creature, with
/// tip links within 0.05, in memory it owns; freed on drop.
pub struct ShotSim {
    /// The handle.
    pub sim: pelage::PelageSim,
    memory: Vec<u8>,
    /// The guides at rest (roots, points), which each step's neutral pose
    /// carries.
    roots: Vec<Root>,
    points: Vec<[f32; 3]>,
    joints: usize,
}

impl ShotSim {
    /// Creates the simulation of the guides `points` rooted at `roots`.
    pub fn new(rest: &CreatureMesh, roots: &[Root], points: &[[f32; 3]], joints: usize) -> ShotSim {
        use crate::measure::{guides_desc, mesh_desc};
        use pelage::*;
        let desc = mesh_desc(rest);
        let params = PelageSimParams {
            joints: joints as u32,
            points_per_guide: joints as u32,
            link_radius: 0.05,
            ..pelage_sim_params_defaults()
        };
        let mut bytes = 0;
        assert_eq!(
            pelage_sim_size(&desc, roots.len(), &params, &mut bytes),
            PelageStatus::Ok
        );
        let mut memory = vec![0u8; bytes];
        let mut sim = std::ptr::null_mut();
        let guides = guides_desc(roots, points);
        let s = pelage_sim_new(
            &PelageRestPose {
                mesh: &desc,
                guides: &guides,
            },
            &params,
            PelageArena {
                memory: memory.as_mut_ptr().cast(),
                bytes,
            },
            &mut sim,
        );
        assert_eq!(s, PelageStatus::Ok);
        ShotSim {
            sim,
            memory,
            roots: roots.to_vec(),
            points: points.to_vec(),
            joints,
        }
    }

    /// Steps the simulation by one frame of the shot (2 threads) to `body`,
    /// colliding with `colliders`, and reads the posed guides back.
    pub fn step(&self, body: &CreatureMesh, colliders: &pelage::PelageColliders) -> Vec<[f32; 3]> {
        use crate::measure::{frame, guides_desc, mesh_desc, on_threads};
        use pelage::*;
        let rest = guides_desc(&self.roots, &self.points);
        let neutral = frame(&mesh_desc(body), &rest, self.joints as u32, 2).unwrap();
        let s = pelage_sim_step(
            self.sim,
            neutral.0,
            &PelageStepParams {
                dt: 1.0 / FPS,
                run: on_threads(2),
                colliders,
                ..pelage_step_params_defaults()
            },
            std::ptr::null_mut(),
        );
        assert_eq!(s, PelageStatus::Ok);
        let mut posed = vec![[0.0f32; 3]; self.points.len()];
        assert_eq!(
            pelage_sim_read(self.sim, posed.as_mut_ptr().cast(), 12, posed.len()),
            PelageStatus::Ok
        );
        posed
    }

    /// Bytes the simulation lives in.
    pub fn bytes(&self) -> usize {
        self.memory.len()
    }
}

impl Drop for ShotSim {
    fn drop(&mut self) {
        pelage::pelage_sim_free(self.sim);
    }
}

/// Simulates `guides` combed guides of `points` joints over the whole shot
/// (tip links, the 16 capsules; 2 threads) through the C API.
pub fn simulate_shot(guides: u32, points: usize) -> SimulatedShot {
    use crate::measure::{combed_guides, stamp_roots};
    let rest = crate::creature::default_creature();
    let roots = stamp_roots(mesh_view(&rest), guides, 1);
    let rest_points = combed_guides(&mesh_view(&rest), &roots, points, 0.06);
    let shot_sim = ShotSim::new(&rest, &roots, &rest_points, points);
    let (mut meshes, mut posed) = (vec![], vec![]);
    for f in 0..FRAMES {
        let mesh = pose(&rest, f);
        let caps = capsules(&rest, &roots, f);
        posed.push(shot_sim.step(&mesh, &colliders(&caps, false)));
        meshes.push(mesh);
    }

    SimulatedShot {
        rest,
        roots,
        rest_points,
        points,
        meshes,
        posed,
    }
}
