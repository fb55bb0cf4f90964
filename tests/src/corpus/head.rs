//! The corpus head: a procedural head grown from `crate::head`, with what
//! that head lacks (a mouth, teeth, a box brow, a stray fin, zero-area
//! triangles, ears thinner than the hair spacing), at any resolution and
//! scale.
//!
//! y is up and +z is the front; at scale 1 the head is about one unit
//! across and sits on the origin. The head shell is star-shaped around the
//! origin, meshed on meridians like `crate::head`'s (dense at the front,
//! sparse at the back, neighbouring meridians with different row counts
//! zipped together), and open at two almond eye sockets, a smiling mouth
//! and the neck. Each hole's rim is pushed inward by a depth that varies
//! along it (deeper at the inner eye corners and at the mouth corners), so
//! no rim is planar.

use std::f64::consts::PI;
use std::ops::Range;

use glam::DVec3;

use crate::creature::CreatureMesh;
use crate::head::{bump, dir, ellipsoid_grid, smooth_normals, smoothstep};

/// Resolution of a corpus head.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Detail {
    /// Meridians of the head shell.
    pub cols: usize,
    /// Rows of the densest meridian (the front).
    pub front_rows: usize,
    /// Rows of the sparsest meridian (the back).
    pub back_rows: usize,
    /// Rings and segments of each eyeball.
    pub eye: (usize, usize),
    /// Rings and segments of each ear.
    pub ear: (usize, usize),
    /// Rings and segments of each tooth.
    pub tooth: (usize, usize),
}

/// The production-like resolution: 44,908 triangles (31,948 in the head
/// shell).
pub const FULL: Detail = Detail {
    cols: 160,
    front_rows: 150,
    back_rows: 24,
    eye: (30, 44),
    ear: (40, 56),
    tooth: (10, 14),
};

/// The resolution of the representative subset: 11,964 triangles (8,404
/// in the head shell).
pub const COARSE: Detail = Detail {
    cols: 84,
    front_rows: 76,
    back_rows: 12,
    eye: (14, 22),
    ear: (20, 28),
    tooth: (6, 10),
};

/// Polar angle of the neck's open rim (radians from +y).
const NECK_THETA: f64 = 0.92 * PI;
/// Radius of the neck tube.
const NECK_RADIUS: f64 = 0.2;
/// Meridians are `(1 + w) / (1 - w)` times denser at the front than at the
/// back.
const LON_WARP: f64 = 0.8;

/// The eyes' centre polar angle and longitude offset from the front.
const EYE_THETA: f64 = 0.44 * PI;
const EYE_PHI_OFFSET: f64 = 0.42;
/// Radius of each eyeball, and its centre's depth below the undented skin.
const EYE_RADIUS: f64 = 0.085;
const EYE_SINK: f64 = 0.06;

/// The mouth's centre polar angle.
const MOUTH_THETA: f64 = 0.65 * PI;
/// Teeth along the upper lip.
pub const TEETH: usize = 8;

/// The brow: a shelf over both eyes whose lower edge is a 90 degree step
/// `BROW_HEIGHT` high at about `BROW_THETA`, over longitudes within
/// `BROW_HALF_WIDTH` of the front; it rises from the forehead over
/// `BROW_RISE` of polar angle and tapers to nothing over `BROW_TAPER`
/// meridians at each end.
const BROW_THETA: f64 = 1.2;
const BROW_HEIGHT: f64 = 0.03;
const BROW_HALF_WIDTH: f64 = 0.75;
const BROW_RISE: f64 = 0.3;
const BROW_TAPER: usize = 5;

/// Height of the stray fin triangle on the back of the head.
const FIN_HEIGHT: f64 = 0.04;

/// Ear size: length, width and half thickness (the two sides are at most
/// `2 * EAR_HALF_THICK` apart).
const EAR_SIZE: [f64; 3] = [0.17, 0.09, EAR_HALF_THICK];
/// Half the thickness of an ear.
pub const EAR_HALF_THICK: f64 = 0.004;

/// A hole of the head shell: an ellipse in (longitude x sin, polar angle)
/// around its centre, bent by `smile` (the ends rise by `smile` half
/// heights), whose rim sinks by a depth that varies along it.
struct Hole {
    theta: f64,
    phi: f64,
    /// Half width (radians along the parallel) and half height (radians of
    /// polar angle).
    half: [f64; 2],
    smile: f64,
    /// Depth at the centre line, extra depth toward the +x end (scaled by
    /// `toward`), extra depth at both ends.
    depth: [f64; 3],
    toward: f64,
}

/// How far beyond its hole (in units of the hole's size) a rim's dent
/// rises back to the skin.
const DENT_RAMP: f64 = 0.8;

impl Hole {
    /// Normalized coordinates of (theta, phi): x along the hole, y across
    /// its bent centre line; inside the hole where x^2 + y^2 < 1.
    fn local(&self, theta: f64, phi: f64) -> (f64, f64) {
        let x = (phi - self.phi) * self.theta.sin() / self.half[0];
        let y = (theta - self.theta) / self.half[1] + self.smile * x * x;
        (x, y)
    }

    fn rho(&self, theta: f64, phi: f64) -> f64 {
        let (x, y) = self.local(theta, phi);
        x.hypot(y)
    }

    fn dent(&self, theta: f64, phi: f64) -> f64 {
        let (x, y) = self.local(theta, phi);
        let [d0, lin, quad] = self.depth;
        let depth = d0 + lin * smoothstep(-1.0, 1.0, x * self.toward) + quad * (x * x).min(1.0);
        depth * (1.0 - smoothstep(1.0, 1.0 + DENT_RAMP, x.hypot(y)))
    }
}

/// The two eye sockets (-x first) and the mouth.
fn holes() -> [Hole; 3] {
    let eye = |side: f64| Hole {
        theta: EYE_THETA,
        phi: PI + side * EYE_PHI_OFFSET,
        half: [0.16, 0.1],
        smile: 0.15,
        depth: [0.02, 0.02, 0.03],
        // the inner corner, toward the nose, sinks deepest
        toward: -side,
    };
    [
        eye(-1.0),
        eye(1.0),
        Hole {
            theta: MOUTH_THETA,
            phi: PI,
            half: [0.32, 0.07],
            smile: 0.8,
            depth: [0.015, 0.0, 0.035],
            toward: 0.0,
        },
    ]
}

/// The skull without holes, dents or brow: `crate::head`'s ellipsoid,
/// muzzle and cheeks, with a neck tube at most `neck_cap` wide (infinite
/// for the open head; the closed reference caps it to close the bottom).
fn skull(d: DVec3, neck_cap: f64) -> f64 {
    let e = (d.x / 0.42).powi(2) + (d.y / 0.48).powi(2) + (d.z / 0.5).powi(2);
    let mut r = 1.0 / e.sqrt();
    r += bump(d, dir(0.58 * PI, PI), 0.3, 0.12);
    for side in [-1.0, 1.0] {
        r += bump(d, dir(0.55 * PI, PI + side * 0.75), 0.3, 0.04);
    }
    let sin = (1.0 - d.y * d.y).max(1e-12).sqrt();
    let tube = NECK_RADIUS / sin;
    // a smooth cap, so the closed bottom has no crease
    let tube = if neck_cap.is_finite() {
        neck_cap * (tube / neck_cap).tanh()
    } else {
        tube
    };
    let neck = tube * smoothstep(0.0, 0.3, -d.y);
    let k = 0.05;
    0.5 * (r + neck + ((r - neck).powi(2) + k * k).sqrt())
}

/// The head shell's distance from the origin at (theta, phi), dents
/// included, brow excluded.
fn shell_radius(theta: f64, phi: f64) -> f64 {
    let r = skull(dir(theta, phi), f64::INFINITY);
    r - holes().iter().map(|h| h.dent(theta, phi)).sum::<f64>()
}

/// One part's geometry before it joins the mesh (unit scale, f64).
#[derive(Default)]
pub(super) struct Piece {
    positions: Vec<DVec3>,
    uvs: Vec<[f64; 2]>,
    triangles: Vec<[u32; 3]>,
}

impl Piece {
    fn vertex(&mut self, p: DVec3, uv: [f64; 2]) -> u32 {
        self.positions.push(p);
        self.uvs.push(uv);
        self.positions.len() as u32 - 1
    }
}

/// A mesh under construction at `scale`, with the face range of each
/// named part.
pub(super) struct Builder {
    pub mesh: CreatureMesh,
    pub parts: Vec<(&'static str, Range<usize>)>,
    scale: f64,
}

impl Builder {
    pub fn new(scale: f64) -> Self {
        Builder {
            mesh: CreatureMesh::default(),
            parts: Vec::new(),
            scale,
        }
    }

    /// Appends `piece` scaled, with smooth normals welded within it.
    pub fn append(&mut self, name: &'static str, piece: Piece) {
        let m = &mut self.mesh;
        let base = m.positions.len() as u32;
        let first = m.triangles.len();
        let positions: Vec<[f32; 3]> = piece
            .positions
            .iter()
            .map(|p| (*p * self.scale).as_vec3().into())
            .collect();
        m.normals
            .extend(smooth_normals(&positions, &piece.triangles));
        m.positions.extend(positions);
        m.uvs
            .extend(piece.uvs.iter().map(|uv| uv.map(|x| x as f32)));
        m.triangles
            .extend(piece.triangles.iter().map(|t| t.map(|i| i + base)));
        self.parts.push((name, first..m.triangles.len()));
    }
}

/// The corpus head at `detail` and `scale`, with its parts in face order:
/// `head` (the open shell with its fin), `eye` x2 (-x first), `tooth` x
/// [`TEETH`] (left to right), `ear` x2 (-x first).
pub(super) fn build(detail: &Detail, scale: f64) -> Builder {
    let mut b = Builder::new(scale);
    b.append("head", head_shell(detail));
    for (i, hole) in holes()[..2].iter().enumerate() {
        b.append("eye", eyeball(i, hole, detail.eye));
    }
    for i in 0..TEETH {
        b.append("tooth", tooth(i, detail.tooth));
    }
    for i in 0..2 {
        b.append("ear", ear(i, detail.ear));
    }
    b
}

/// Longitude of meridian `s = j / cols`: dense at the front (s = 1/2).
fn column_phi(s: f64) -> f64 {
    2.0 * PI * s + LON_WARP * (2.0 * PI * s).sin()
}

fn column_rows(detail: &Detail, phi: f64) -> usize {
    let front = ((1.0 - phi.cos()) / 2.0).powi(3);
    let (f, b) = (detail.front_rows as f64, detail.back_rows as f64);
    (b + (f - b) * front).round() as usize
}

/// A vertex of a meridian: its id, and its key down the meridian (polar
/// angle, then 0 for the top and 1 for the foot of the brow step).
type Level = (u32, (f64, u8));

fn head_shell(detail: &Detail) -> Piece {
    let mut p = Piece::default();
    // (theta, phi) of every vertex, to cut the holes
    let mut at: Vec<(f64, f64)> = Vec::new();
    let top = p.vertex(DVec3::Y * shell_radius(0.0, 0.0), [0.5, 0.0]);
    at.push((0.0, 0.0));
    let phis: Vec<f64> = (0..detail.cols)
        .map(|j| column_phi(j as f64 / detail.cols as f64))
        .collect();
    let brow: Vec<usize> = (0..detail.cols)
        .filter(|&j| (phis[j] - PI).abs() <= BROW_HALF_WIDTH)
        .collect();
    let (j0, j1) = (brow[0], brow[brow.len() - 1]);
    // exactly zero at both end meridians: their step collapses to
    // zero-area triangles; a steep ramp after it makes slivers
    let brow_height = |j: usize| {
        let t = (j - j0).min(j1 - j) as f64 / BROW_TAPER as f64;
        BROW_HEIGHT * t.min(1.0).powi(4)
    };
    let mut columns: Vec<Vec<Level>> = Vec::with_capacity(detail.cols + 1);
    for (j, &phi) in phis.iter().enumerate() {
        let s = j as f64 / detail.cols as f64;
        let rows = column_rows(detail, phi);
        let theta_k = |k: usize| NECK_THETA * k as f64 / rows as f64;
        // the step is at the same polar angle on every meridian, so its
        // wall lies on one cone and meets the skin at 90 degrees
        let step = BROW_THETA;
        let kb = (1..=rows)
            .find(|&k| theta_k(k) > step)
            .expect("the step is above the neck");
        let h = if (j0..=j1).contains(&j) {
            Some(brow_height(j))
        } else {
            None
        };
        let v_of = |theta: f64| 0.6 * theta / NECK_THETA;
        let mut col = vec![(top, (0.0, 0))];
        for k in 1..=rows {
            let theta = theta_k(k);
            if let (Some(h), true) = (h, k == kb) {
                // the step: its top (raised) and its foot (not), with UVs
                // apart by a share of a row as wide as the step is high
                let d = dir(step, phi);
                let r = shell_radius(step, phi);
                let dv = 0.25 * 0.6 / rows as f64 * h / BROW_HEIGHT;
                let up = p.vertex(d * (r + h), [s, v_of(step) - dv]);
                let foot = p.vertex(d * r, [s, v_of(step) + dv]);
                at.extend([(step, phi); 2]);
                col.push((up, (step, 0)));
                col.push((foot, (step, 1)));
            }
            let raise = match h {
                Some(h) if theta < step => h * smoothstep(step - BROW_RISE, step, theta),
                _ => 0.0,
            };
            let r = shell_radius(theta, phi) + raise;
            col.push((p.vertex(dir(theta, phi) * r, [s, v_of(theta)]), (theta, 0)));
            at.push((theta, phi));
        }
        columns.push(col);
    }
    // the seam: a copy of the first meridian with u = 1
    let seam = columns[0]
        .iter()
        .map(|&(id, key)| {
            if id == top {
                return (id, key);
            }
            let (pos, uv) = (p.positions[id as usize], p.uvs[id as usize]);
            at.push(at[id as usize]);
            (p.vertex(pos, [1.0, uv[1]]), key)
        })
        .collect();
    columns.push(seam);
    for pair in columns.windows(2) {
        zip(&mut p.triangles, &pair[0], &pair[1]);
    }
    let mut p = cut_holes(p, &at);
    add_fin(&mut p);
    p
}

/// Triangulates the strip between two meridians (`a` west of `b`, both from
/// the shared pole down to the neck), always advancing along the meridian
/// whose next vertex is higher, so the triangles never overlap; at the brow
/// the top of a step comes before its foot.
fn zip(out: &mut Vec<[u32; 3]>, a: &[Level], b: &[Level]) {
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

/// Removes every triangle touching a vertex inside a hole, then the
/// vertices no triangle uses.
fn cut_holes(p: Piece, at: &[(f64, f64)]) -> Piece {
    let holes = holes();
    let inside: Vec<bool> = at
        .iter()
        .map(|&(theta, phi)| holes.iter().any(|h| h.rho(theta, phi) < 1.0))
        .collect();
    let mut remap = vec![u32::MAX; p.positions.len()];
    let mut out = Piece::default();
    for t in p.triangles {
        if t.iter().any(|&i| inside[i as usize]) {
            continue;
        }
        let t = t.map(|i| {
            let i = i as usize;
            if remap[i] == u32::MAX {
                remap[i] = out.vertex(p.positions[i], p.uvs[i]);
            }
            remap[i]
        });
        out.triangles.push(t);
    }
    out
}

/// A stray fin: one triangle standing on an edge of the back of the head,
/// so that edge has three faces (a non-manifold edge, as a modelling slip
/// leaves).
fn add_fin(p: &mut Piece) {
    let target = dir(0.45 * PI, 0.5);
    let centre = |t: &[u32; 3]| t.iter().map(|&i| p.positions[i as usize]).sum::<DVec3>() / 3.0;
    let t = *p
        .triangles
        .iter()
        .min_by(|s, t| {
            let (a, b) = (centre(s).normalize(), centre(t).normalize());
            a.distance(target).total_cmp(&b.distance(target))
        })
        .expect("the head shell has triangles");
    let (a, b) = (t[0] as usize, t[1] as usize);
    let mid = 0.5 * (p.positions[a] + p.positions[b]);
    let uv = [0, 1].map(|k| 0.5 * (p.uvs[a][k] + p.uvs[b][k]));
    let c = p.vertex(mid + mid.normalize() * FIN_HEIGHT, uv);
    p.triangles.push([t[0], t[1], c]);
}

/// [`ellipsoid_grid`] (the legacy head's, outward) as a piece.
fn ellipsoid(
    centre: DVec3,
    pole: DVec3,
    e1: DVec3,
    axes: [f64; 3],
    rows_cols: (usize, usize),
    uv: impl Fn(DVec3) -> [f64; 2],
) -> Piece {
    let (positions, uvs, triangles) = ellipsoid_grid(centre, pole, e1, axes, rows_cols, uv);
    Piece {
        positions,
        uvs,
        triangles,
    }
}

/// Eyeball `i` in socket `hole`: a sphere sunk [`EYE_SINK`] below the
/// undented skin, so it sticks out of the hole and cuts the shell around
/// the rim.
fn eyeball(i: usize, hole: &Hole, res: (usize, usize)) -> Piece {
    let gaze = dir(hole.theta, hole.phi);
    let centre = gaze * (skull(gaze, f64::INFINITY) - EYE_SINK);
    let e1 = gaze.cross(DVec3::Y).normalize();
    let u0 = 0.2 * i as f64;
    ellipsoid(centre, gaze, e1, [EYE_RADIUS; 3], res, |q| {
        let (x, y) = (q.dot(e1), q.dot(gaze.cross(e1)));
        [u0 + 0.1 + 0.1 * x / EYE_RADIUS, 0.7 + 0.1 * y / EYE_RADIUS]
    })
}

/// Tooth `i` of the upper row: an ellipsoid hanging from the upper lip
/// into the mouth, centred on the (extended) skin and lying along it, so
/// the lip's skin passes through it.
fn tooth(i: usize, res: (usize, usize)) -> Piece {
    let mouth = &holes()[2];
    let x = -0.75 + 1.5 * i as f64 / (TEETH - 1) as f64;
    // 0.2 half heights below the upper rim
    let theta = mouth.theta + mouth.half[1] * (-0.8 - mouth.smile * x * x);
    let phi = mouth.phi + x * mouth.half[0] / mouth.theta.sin();
    let at = |theta: f64, phi: f64| dir(theta, phi) * shell_radius(theta, phi);
    let centre = at(theta, phi);
    // down the skin (the chin slopes), and along the lip
    let e = 1e-4;
    let down = (at(theta + e, phi) - at(theta - e, phi)).normalize();
    let along = at(theta, phi + e) - at(theta, phi - e);
    let along = (along - down * along.dot(down)).normalize();
    let axes = [0.05, 0.012, 0.01];
    let u0 = 0.4 + 0.075 * i as f64;
    ellipsoid(centre, -down, along, axes, res, |q| {
        [
            u0 + 0.0375 + 0.0375 * q.dot(along) / axes[1],
            0.7 - 0.1 * q.dot(down) / axes[0],
        ]
    })
}

/// Ear `i` (-x first): a flattened ellipsoid at most `2 *
/// EAR_HALF_THICK` thick on the side of the crown, its base end 0.05
/// inside the head.
fn ear(i: usize, res: (usize, usize)) -> Piece {
    let side = if i == 0 { -1.0 } else { 1.0 };
    let (theta, phi) = (0.3 * PI, PI + side * 0.5 * PI);
    let base = dir(theta, phi);
    let foot = base * shell_radius(theta, phi);
    let long = (base + DVec3::Y * 0.5).normalize();
    let [length, width, thick] = EAR_SIZE;
    let centre = foot + long * (length - 0.05);
    let across = long.cross(DVec3::Z).normalize();
    let u0 = 0.5 * i as f64;
    ellipsoid(centre, long, across, [length, width, thick], res, |q| {
        [
            u0 + 0.25 + 0.25 * q.dot(across) / width,
            0.9 + 0.1 * q.dot(long) / length,
        ]
    })
}

/// A closed single shell of about `triangles` triangles as large as the
/// corpus head at `scale`: its skull (no holes, dents or brow) with the
/// neck closed at the bottom, on a latitude-longitude grid with a single
/// vertex at each pole and a split UV seam.
pub(super) fn closed(triangles: usize, scale: f64) -> Builder {
    // 2 cols rows triangles for `rows` rings
    let cols = ((triangles as f64 / 2.0).sqrt().round() as usize).max(3);
    let rows = ((triangles as f64 / (2.0 * cols as f64)).round() as usize).max(2);
    let mut p = Piece::default();
    let at = |theta: f64, phi: f64| dir(theta, phi) * skull(dir(theta, phi), 0.62);
    let north = p.vertex(at(0.0, 0.0), [0.5, 0.0]);
    for i in 1..=rows {
        let theta = PI * i as f64 / (rows + 1) as f64;
        for j in 0..=cols {
            let s = j as f64 / cols as f64;
            p.vertex(at(theta, 2.0 * PI * s), [s, theta / PI]);
        }
    }
    let south = p.vertex(at(PI, 0.0), [0.5, 1.0]);
    let v = |i: usize, j: usize| (1 + (i - 1) * (cols + 1) + j) as u32;
    let t = &mut p.triangles;
    for j in 0..cols {
        t.push([north, v(1, j), v(1, j + 1)]);
        t.push([v(rows, j), south, v(rows, j + 1)]);
        for i in 1..rows {
            t.push([v(i, j), v(i + 1, j), v(i, j + 1)]);
            t.push([v(i, j + 1), v(i + 1, j), v(i + 1, j + 1)]);
        }
    }
    // the seam's copies with u = 1 take the positions of u = 0 exactly
    for i in 1..=rows {
        p.positions[v(i, cols) as usize] = p.positions[v(i, 0) as usize];
    }
    let mut b = Builder::new(scale);
    b.append("closed", p);
    b
}
