//! Deterministic procedural creature head: a test mesh built like the
//! meshes artists hand over, not like the watertight test creature.
//!
//! It has the features production meshes have and the creature lacks:
//! several intersecting shells, open boundaries, UV seams with split
//! vertices, and triangle sizes that vary by two orders of magnitude.
//! y is up and +z is the front (as for the creature); the head is about
//! one unit across and sits on the origin.
//!
//! # Parts (in face order, see [`HeadParts`])
//!
//! 1. **Head shell**: a deformed ellipsoid (brow, muzzle, cheeks) running
//!    into a neck, open at the bottom (a bust) and with two **open eye
//!    sockets**: the triangles over each socket are removed and the rim
//!    around the hole is pushed 0.035 inward. So the shell has exactly
//!    [`HEAD_BOUNDARY_LOOPS`] boundary loops (two sockets and the neck).
//!    It is star-shaped around the origin ([`skull_radius`]) and meshed on
//!    meridians: fine at the front, where columns are dense and each holds
//!    up to [`HEAD_FRONT_ROWS`] rows, coarse at the back (down to
//!    [`HEAD_BACK_ROWS`] rows on sparse columns); slivers with an aspect
//!    ratio in the hundreds fan around the top pole and stretch down the
//!    neck. Neighbouring meridians with different row counts are zipped
//!    together, as a remesher's transition would be. The seam meridian at
//!    the back (u = 0 and u = 1) is duplicated with bit-identical positions.
//! 2. **Two eyeballs**: closed spheres of radius [`EYE_RADIUS`] with their
//!    own vertices, sitting in the sockets; they stick out of the holes and
//!    cut through the head shell around the rims.
//! 3. **A horn**: a closed, curved, tapered tube with a flat cap at its
//!    base, 0.5 long, rising from the forehead; its base is 0.08 inside the head, so
//!    it cuts through the head shell. It has a duplicated UV seam.
//! 4. **Two ears**: thin closed flattened ellipsoids (0.028 thick, 0.34
//!    long) on the sides of the crown, their base ends 0.05 inside the head.
//!
//! Each closed part is closed once vertices with bit-identical positions
//! are welded, and wound counter-clockwise seen from outside (outward
//! normals, positive signed volume). The head shell, welded, is an
//! orientable surface whose only boundaries are the three loops.
//!
//! Vertex normals are smooth (area-weighted), welded within each part, so
//! seam duplicates share their normal; parts never share vertices.
//!
//! # UVs
//!
//! Every part has its own tile of the unit square: the head shell takes
//! `v` in [0, 0.6] (`u` = longitude / 2 PI, `v` growing from the top pole
//! to the neck), the eyeballs [0, 0.2] and [0.2, 0.4] by [0.6, 0.8] (a
//! planar projection along the gaze), the horn [0.4, 1] by [0.6, 0.8]
//! (around and along), the ears [0, 0.5] and [0.5, 1] by [0.8, 1] (a
//! planar projection on the ear's plane: both sides of an ear share UVs).

use std::collections::HashMap;
use std::f64::consts::PI;
use std::ops::Range;

use glam::DVec3;

use crate::creature::{direction, CreatureMesh};

/// Meridians (longitude segments) of the head shell.
pub const HEAD_COLS: usize = 220;
/// Rows of the densest meridian (at the front, longitude PI).
pub const HEAD_FRONT_ROWS: usize = 240;
/// Rows of the sparsest meridian (at the back, longitude 0).
pub const HEAD_BACK_ROWS: usize = 16;
/// Polar angle of the neck's open rim (radians from +y).
pub const NECK_THETA: f64 = 0.92 * PI;
/// Boundary loops of the welded head shell: two eye sockets and the neck.
pub const HEAD_BOUNDARY_LOOPS: usize = 3;
/// Radius of each eyeball.
pub const EYE_RADIUS: f64 = 0.085;

/// Strength of the longitude warp: meridians are `(1 + w) / (1 - w)` times
/// denser at the front than at the back.
const LON_WARP: f64 = 0.8;
/// Polar angle and longitude offset from the front of the eye centres.
const EYE_THETA: f64 = 0.44 * PI;
const EYE_PHI_OFFSET: f64 = 0.42;
/// Angular radius of a socket hole: vertices closer than this to the
/// socket's centre direction go, with every triangle touching them.
const SOCKET_ANGLE: f64 = 0.13;
/// How far the rim sinks, and over what angle beyond the hole it rises back.
const SOCKET_DEPTH: f64 = 0.035;
const SOCKET_RAMP: f64 = 0.1;
/// Eyeball centre below the undented head surface.
const EYE_SINK: f64 = 0.06;
/// Radius of the neck tube.
const NECK_RADIUS: f64 = 0.2;

/// Which faces of [`head_with_parts`] belong to which part; the ranges are
/// contiguous, in this order, and cover every face.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HeadParts {
    /// The open head shell (eye sockets and neck open).
    pub head: Range<usize>,
    /// The two closed eyeballs (the -x one first).
    pub eyes: [Range<usize>; 2],
    /// The closed horn.
    pub horn: Range<usize>,
    /// The two closed ears (the -x one first).
    pub ears: [Range<usize>; 2],
}

impl HeadParts {
    /// The closed parts: eyeballs, horn, ears.
    pub fn closed(&self) -> [Range<usize>; 5] {
        let [e0, e1] = self.eyes.clone();
        let [a0, a1] = self.ears.clone();
        [e0, e1, self.horn.clone(), a0, a1]
    }

    /// The shell of every face: 0 for the head shell, then 1 to 5 for the
    /// parts of [`HeadParts::closed`] in order.
    pub fn shells(&self) -> Vec<u32> {
        let mut shells = vec![0u32; self.head.len()];
        for (s, part) in self.closed().into_iter().enumerate() {
            shells.resize(part.end, s as u32 + 1);
        }
        shells
    }
}

/// The head test mesh (42,957 vertices, 85,440 triangles: 59,072 in the
/// head shell, 5,120 per eyeball, 3,840 in the horn, 6,144 per ear).
pub fn head() -> CreatureMesh {
    head_with_parts().0
}

/// The head test mesh and the face ranges of its parts.
pub fn head_with_parts() -> (CreatureMesh, HeadParts) {
    let mut mesh = CreatureMesh::default();
    let head = append(&mut mesh, head_shell());
    let eyes = eye_dirs().map(|(i, d)| append(&mut mesh, eyeball(i, d)));
    let horn = append(&mut mesh, horn());
    let ears = [0, 1].map(|i| append(&mut mesh, ear(i)));
    (
        mesh,
        HeadParts {
            head,
            eyes,
            horn,
            ears,
        },
    )
}

/// Distance from the origin to the head shell along the unit direction `d`
/// (the shell is star-shaped around the origin), sockets included.
pub fn skull_radius(d: DVec3) -> f64 {
    let mut r = undented_radius(d);
    for (_, eye) in eye_dirs() {
        let a = angle_between(d, eye);
        r -= SOCKET_DEPTH * (1.0 - smoothstep(SOCKET_ANGLE, SOCKET_ANGLE + SOCKET_RAMP, a));
    }
    r
}

/// The head without its socket dents: skull, brow, muzzle, cheeks, neck.
fn undented_radius(d: DVec3) -> f64 {
    let e = (d.x / 0.42).powi(2) + (d.y / 0.48).powi(2) + (d.z / 0.5).powi(2);
    let mut r = 1.0 / e.sqrt();
    r += bump(d, dir(0.58 * PI, PI), 0.3, 0.12);
    r += bump(d, dir(0.36 * PI, PI), 0.25, 0.03);
    for side in [-1.0, 1.0] {
        r += bump(d, dir(0.55 * PI, PI + side * 0.75), 0.3, 0.04);
    }
    // the neck is a tube: its radius over the sine of the polar angle,
    // blended with a smooth maximum so the surface stays smooth
    let sin = (1.0 - d.y * d.y).max(1e-12).sqrt();
    let neck = NECK_RADIUS / sin * smoothstep(0.0, 0.3, -d.y);
    let k = 0.05;
    0.5 * (r + neck + ((r - neck).powi(2) + k * k).sqrt())
}

pub(crate) fn dir(theta: f64, phi: f64) -> DVec3 {
    DVec3::from(direction(theta, phi))
}

fn angle_between(a: DVec3, b: DVec3) -> f64 {
    // the chord form stays accurate for the small angles of the sockets
    2.0 * (0.5 * (a - b).length()).min(1.0).asin()
}

pub(crate) fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

pub(crate) fn bump(d: DVec3, centre: DVec3, width: f64, height: f64) -> f64 {
    let a = angle_between(d, centre) / width;
    height * (-a * a).exp()
}

/// The eyes' indices and gaze directions (-x first).
fn eye_dirs() -> [(usize, DVec3); 2] {
    [0, 1].map(|i| {
        let side = if i == 0 { -1.0 } else { 1.0 };
        // longitude below PI is the -x side of the face
        (i, dir(EYE_THETA, PI + side * EYE_PHI_OFFSET))
    })
}

/// One part's geometry before it joins the mesh.
#[derive(Default)]
struct Part {
    positions: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    triangles: Vec<[u32; 3]>,
}

impl Part {
    fn vertex(&mut self, p: DVec3, uv: [f64; 2]) -> u32 {
        self.positions.push(p.as_vec3().into());
        self.uvs.push(uv.map(|x| x as f32));
        self.positions.len() as u32 - 1
    }

    /// A copy of vertex `i` with other UVs (a seam duplicate).
    fn split(&mut self, i: u32, uv: [f64; 2]) -> u32 {
        self.positions.push(self.positions[i as usize]);
        self.uvs.push(uv.map(|x| x as f32));
        self.positions.len() as u32 - 1
    }
}

/// Appends `part` with smooth normals; returns its face range.
fn append(mesh: &mut CreatureMesh, part: Part) -> Range<usize> {
    let base = mesh.positions.len() as u32;
    let first = mesh.triangles.len();
    mesh.normals
        .extend(smooth_normals(&part.positions, &part.triangles));
    mesh.positions.extend(part.positions);
    mesh.uvs.extend(part.uvs);
    mesh.triangles
        .extend(part.triangles.iter().map(|t| t.map(|i| i + base)));
    first..mesh.triangles.len()
}

/// Area-weighted vertex normals, summed over vertices with bit-identical
/// positions so seam duplicates agree (zero-area faces add nothing; a
/// vertex of only such faces points up).
pub(crate) fn smooth_normals(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Vec<[f32; 3]> {
    let mut ids = HashMap::new();
    let canon: Vec<usize> = positions
        .iter()
        .enumerate()
        .map(|(i, p)| *ids.entry(p.map(f32::to_bits)).or_insert(i))
        .collect();
    let mut acc = vec![DVec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| DVec3::from(positions[i as usize].map(f64::from)));
        let n = (b - a).cross(c - a);
        for &i in t {
            acc[canon[i as usize]] += n;
        }
    }
    canon
        .iter()
        .map(|&k| acc[k].normalize_or(DVec3::Y).as_vec3().into())
        .collect()
}

/// Longitude of head meridian `s = j / HEAD_COLS`: dense at the front
/// (s = 0.5, longitude PI), sparse at the back seam.
fn column_phi(s: f64) -> f64 {
    // d(phi)/ds = 2 PI (1 + w cos(2 PI s)) is smallest at s = 1/2
    2.0 * PI * s + LON_WARP * (2.0 * PI * s).sin()
}

/// Rows of the meridian at longitude `phi`.
fn column_rows(phi: f64) -> usize {
    let front = ((1.0 - phi.cos()) / 2.0).powi(3);
    let rows = HEAD_BACK_ROWS as f64 + (HEAD_FRONT_ROWS - HEAD_BACK_ROWS) as f64 * front;
    rows.round() as usize
}

fn head_shell() -> Part {
    let mut part = Part::default();
    let top = part.vertex(DVec3::Y * skull_radius(DVec3::Y), [0.5, 0.0]);
    // vertex ids and polar angles of each meridian, the top pole first;
    // the last meridian is the seam copy of the first
    let mut columns: Vec<Vec<(u32, f64)>> = (0..HEAD_COLS)
        .map(|j| {
            let s = j as f64 / HEAD_COLS as f64;
            let phi = column_phi(s);
            let rows = column_rows(phi);
            let mut col = vec![(top, 0.0)];
            col.extend((1..=rows).map(|k| {
                let theta = NECK_THETA * k as f64 / rows as f64;
                let d = dir(theta, phi);
                let uv = [s, 0.6 * k as f64 / rows as f64];
                (part.vertex(d * skull_radius(d), uv), theta)
            }));
            col
        })
        .collect();
    let rows = columns[0].len() - 1;
    let seam = columns[0]
        .iter()
        .enumerate()
        .map(|(k, &(id, theta))| match k {
            0 => (id, theta),
            _ => (part.split(id, [1.0, 0.6 * k as f64 / rows as f64]), theta),
        })
        .collect();
    columns.push(seam);
    for pair in columns.windows(2) {
        zip(&mut part.triangles, &pair[0], &pair[1]);
    }
    cut_sockets(part)
}

/// Triangulates the strip between two meridians (`a` west of `b`, both from
/// the shared pole down to the neck), always advancing along the meridian
/// whose next vertex is higher, so the triangles never overlap.
fn zip(out: &mut Vec<[u32; 3]>, a: &[(u32, f64)], b: &[(u32, f64)]) {
    out.push([a[0].0, a[1].0, b[1].0]);
    let (mut i, mut k) = (1, 1);
    while i + 1 < a.len() || k + 1 < b.len() {
        let down_a = k + 1 == b.len() || (i + 1 < a.len() && a[i + 1].1 <= b[k + 1].1);
        if down_a {
            out.push([a[i].0, a[i + 1].0, b[k].0]);
            i += 1;
        } else {
            out.push([a[i].0, b[k + 1].0, b[k].0]);
            k += 1;
        }
    }
}

/// Removes every triangle touching a vertex inside a socket, then the
/// vertices no triangle uses.
fn cut_sockets(part: Part) -> Part {
    let inside: Vec<bool> = part
        .positions
        .iter()
        .map(|p| {
            let d = DVec3::from(p.map(f64::from)).normalize();
            eye_dirs()
                .iter()
                .any(|&(_, e)| angle_between(d, e) < SOCKET_ANGLE)
        })
        .collect();
    let kept: Vec<[u32; 3]> = part
        .triangles
        .into_iter()
        .filter(|t| t.iter().all(|&i| !inside[i as usize]))
        .collect();
    let mut remap = vec![u32::MAX; part.positions.len()];
    let mut out = Part::default();
    for t in &kept {
        let t = t.map(|i| {
            let i = i as usize;
            if remap[i] == u32::MAX {
                remap[i] = out.positions.len() as u32;
                out.positions.push(part.positions[i]);
                out.uvs.push(part.uvs[i]);
            }
            remap[i]
        });
        out.triangles.push(t);
    }
    out
}

/// A closed UV ellipsoid around `centre` with semi-axis `axes[0]` along the
/// pole axis `pole`, `axes[1]` along `e1` and `axes[2]` along `pole x e1`;
/// `rows` rings between single pole vertices, `cols` segments, no seam
/// (`uv` maps a point, relative to the centre, to its UVs), wound outward:
/// its points, their UVs and its triangles.
pub(crate) fn ellipsoid_grid(
    centre: DVec3,
    pole: DVec3,
    e1: DVec3,
    axes: [f64; 3],
    (rows, cols): (usize, usize),
    uv: impl Fn(DVec3) -> [f64; 2],
) -> (Vec<DVec3>, Vec<[f64; 2]>, Vec<[u32; 3]>) {
    let e2 = pole.cross(e1);
    let (mut points, mut uvs) = (Vec::new(), Vec::new());
    let mut at = |theta: f64, phi: f64| {
        let q = pole * (axes[0] * theta.cos())
            + (e1 * (axes[1] * phi.cos()) + e2 * (axes[2] * phi.sin())) * theta.sin();
        points.push(centre + q);
        uvs.push(uv(q));
        points.len() as u32 - 1
    };
    let north = at(0.0, 0.0);
    for i in 1..=rows {
        let theta = PI * i as f64 / (rows + 1) as f64;
        for j in 0..cols {
            at(theta, 2.0 * PI * j as f64 / cols as f64);
        }
    }
    let south = at(PI, 0.0);
    let v = |i: usize, j: usize| (1 + (i - 1) * cols + j % cols) as u32;
    let mut t = Vec::with_capacity(2 * rows * cols);
    for j in 0..cols {
        t.push([north, v(1, j), v(1, j + 1)]);
        t.push([v(rows, j), south, v(rows, j + 1)]);
    }
    for i in 1..rows {
        for j in 0..cols {
            t.push([v(i, j), v(i + 1, j), v(i, j + 1)]);
            t.push([v(i, j + 1), v(i + 1, j), v(i + 1, j + 1)]);
        }
    }
    (points, uvs, t)
}

/// [`ellipsoid_grid`] as a part.
fn ellipsoid(
    centre: DVec3,
    pole: DVec3,
    e1: DVec3,
    axes: [f64; 3],
    rows_cols: (usize, usize),
    uv: impl Fn(DVec3) -> [f64; 2],
) -> Part {
    let (points, uvs, triangles) = ellipsoid_grid(centre, pole, e1, axes, rows_cols, uv);
    let mut part = Part::default();
    for (p, uv) in points.into_iter().zip(uvs) {
        part.vertex(p, uv);
    }
    part.triangles = triangles;
    part
}

fn eyeball(i: usize, gaze: DVec3) -> Part {
    let centre = gaze * (undented_radius(gaze) - EYE_SINK);
    let e1 = gaze.cross(DVec3::Y).normalize();
    let u0 = 0.2 * i as f64;
    ellipsoid(centre, gaze, e1, [EYE_RADIUS; 3], (40, 64), |q| {
        let (x, y) = (q.dot(e1), q.dot(gaze.cross(e1)));
        [u0 + 0.1 + 0.1 * x / EYE_RADIUS, 0.7 + 0.1 * y / EYE_RADIUS]
    })
}

fn ear(i: usize) -> Part {
    let side = if i == 0 { -1.0 } else { 1.0 };
    let base = dir(0.3 * PI, PI + side * 0.5 * PI);
    let foot = base * skull_radius(base);
    // the long axis leans up from the side of the head
    let long = (base + DVec3::Y * 0.5).normalize();
    let (length, width, thick) = (0.17, 0.09, 0.014);
    let centre = foot + long * (length - 0.05);
    let across = long.cross(DVec3::Z).normalize();
    let u0 = 0.5 * i as f64;
    ellipsoid(
        centre,
        long,
        across,
        [length, width, thick],
        (48, 64),
        |q| {
            [
                u0 + 0.25 + 0.25 * q.dot(across) / width,
                0.9 + 0.1 * q.dot(long) / length,
            ]
        },
    )
}

/// Rings along the horn, and segments around it.
const HORN_RINGS: usize = 40;
const HORN_SEGMENTS: usize = 48;

fn horn() -> Part {
    let root = dir(0.2 * PI, PI);
    let start = root * (skull_radius(root) - 0.08);
    let back = root.cross(DVec3::X).normalize();
    // the spine leans forward along the root direction and bends upward
    let spine = |t: f64| start + root * (0.5 * t) + back * (0.15 * t * t);
    let tangent = |t: f64| (root * 0.5 + back * (0.3 * t)).normalize();
    let radius = |t: f64| 0.075 * (1.0 - t).powf(0.9);
    let mut part = Part::default();
    let mut rings = Vec::with_capacity(HORN_RINGS);
    for k in 0..HORN_RINGS {
        let t = k as f64 / HORN_RINGS as f64;
        let tan = tangent(t);
        let b1 = (DVec3::X - tan * tan.x).normalize();
        let b2 = tan.cross(b1);
        let mut ring: Vec<u32> = (0..HORN_SEGMENTS)
            .map(|a| {
                let s = a as f64 / HORN_SEGMENTS as f64;
                let (sin, cos) = (2.0 * PI * s).sin_cos();
                let p = spine(t) + (b1 * cos + b2 * sin) * radius(t);
                part.vertex(p, [0.4 + 0.6 * s, 0.6 + 0.2 * t])
            })
            .collect();
        ring.push(part.split(ring[0], [1.0, 0.6 + 0.2 * t]));
        rings.push(ring);
    }
    let tip = part.vertex(spine(1.0), [0.7, 0.8]);
    let cap = part.vertex(start, [0.7, 0.6]);
    let t = &mut part.triangles;
    for a in 0..HORN_SEGMENTS {
        t.push([cap, rings[0][a + 1], rings[0][a]]);
        for k in 0..HORN_RINGS - 1 {
            let (r0, r1) = (&rings[k], &rings[k + 1]);
            t.push([r0[a], r0[a + 1], r1[a]]);
            t.push([r0[a + 1], r1[a + 1], r1[a]]);
        }
        let last = &rings[HORN_RINGS - 1];
        t.push([last[a], last[a + 1], tip]);
    }
    part
}
