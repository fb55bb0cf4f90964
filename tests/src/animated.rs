//! The animated creature: a short shot that breaks physical hair solvers.
//! It walks, turns a quarter turn, jumps, sways its upper body (a bend, not
//! a rigid motion), and at [`TELEPORT_FRAME`] it is cut to a place 100
//! units away. Tests and benchmarks of the dynamics, caches and the farm
//! share it.

use crate::creature::CreatureMesh;
use glam::{Quat, Vec3};

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
