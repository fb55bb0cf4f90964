//! Deterministic procedural "creature" test mesh.
//!
//! The creature is a single closed, watertight surface that is *star-shaped*
//! around the origin: every vertex lies on the ray `dir * radius(dir)` for a
//! direction `dir` taken from a latitude/longitude grid, and the radius
//! function is strictly positive.  Because every triangle's radial projection
//! is a cell of a valid triangulation of the unit sphere, the surface can
//! never self-intersect, however spiky `radius` is.
//!
//! Shape (y is up, +z is the front, the body is roughly 2 units tall):
//!
//! * an ellipsoid-ish body with a snout, a belly bulge and two feet;
//! * two **ears**: thin flat fins lying in the x/y plane (on -x and +x, near
//!   the top).  Along the fin they are ~0.5 rad wide and ~0.45 units long,
//!   across the fin only ~0.03 units thick at half height (~0.045 at the base,
//!   ~0.015 near the rim);
//! * two **hands** (on -x and +x, a bit below the equator), each with five
//!   narrow finger-like spikes (~0.08 units across, 0.22–0.34 units long) on a
//!   small pad.
//!
//! # Grid
//!
//! `creature(rows, cols)` uses `rows` latitude rings (poles excluded) at
//! `theta_i = PI * i / (rows + 1)` (theta measured from the north pole, +y)
//! and `cols` longitude segments.  Longitude sampling is *non-uniform*: the
//! columns are about 4x denser around the two sides (u = 0.25 and u = 0.75)
//! where the ears and fingers are, so that the thin parts span several grid
//! cells across (an ear is ~9 columns across at its base and ~5 at half
//! height in the default mesh; a finger ~10 columns and ~5 rows).
//!
//! The seam column is duplicated (u = 0 and u = 1) with bit-identical
//! positions and normals.  Each pole is a single vertex with a triangle fan,
//! so the default mesh has no degenerate triangles.
//! [`creature_with_pole_rows`] builds the same surface with the naive grid
//! (a full row of duplicated vertices at each pole), which adds `2 * cols`
//! zero-area triangles.
//!
//! # UVs
//!
//! `u = longitude / (2 PI)` (u = 0 / 1 is the back, -z; u = 0.5 is the front,
//! +z; u = 0.25 is the -x side, u = 0.75 the +x side), `v = theta / PI`
//! (v = 0 at the top / north pole, v = 1 at the bottom).  The single pole
//! vertices use u = 0.5.
//!
//! Direction for (theta, phi) with phi = 2 PI u:
//! `(-sin(theta) sin(phi), cos(theta), -sin(theta) cos(phi))`.
//!
//! Triangles are wound counter-clockwise seen from outside (outward normals).

use std::f64::consts::PI;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// Default number of latitude rings (poles excluded).
pub const DEFAULT_ROWS: u32 = 181;
/// Default number of longitude segments.
pub const DEFAULT_COLS: u32 = 180;

/// Centre of the bald face disc in UV space (front of the head).
pub const FACE_UV: [f32; 2] = [0.5, 0.26];
/// Radius (in UV units, Euclidean in (u, v)) of the bald face disc.
pub const FACE_RADIUS_UV: f32 = 0.07;
/// Centres of the two bald palm discs in UV space (front side of each hand
/// pad, next to the fingers).
pub const PALM_UVS: [[f32; 2]; 2] = [[0.31, 0.57], [0.69, 0.57]];
/// Radius (in UV units) of the bald palm discs.
pub const PALM_RADIUS_UV: f32 = 0.045;
/// Centre of the belly gradient (density 0.3 at the centre, rising smoothly
/// to 1.0 at its rim).
pub const BELLY_UV: [f32; 2] = [0.5, 0.68];

/// A triangle mesh with per-vertex attributes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CreatureMesh {
    pub positions: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex UVs in [0, 1].
    pub uvs: Vec<[f32; 2]>,
    /// Smooth (area-weighted) unit vertex normals, pointing outwards.
    pub normals: Vec<[f32; 3]>,
}

impl CreatureMesh {
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Area of triangle `t` (computed in f64 from the f32 positions).
    pub fn triangle_area(&self, t: usize) -> f64 {
        let [a, b, c] = self.triangles[t].map(|i| to64(self.positions[i as usize]));
        0.5 * len(cross(sub(b, a), sub(c, a)))
    }

    /// Axis-aligned bounding box `(min, max)`.
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for p in &self.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }
}

// ---------------------------------------------------------------------------
// Shape
// ---------------------------------------------------------------------------

/// Strength of the longitude warp (columns are `1 / (1 - LON_WARP)` times
/// denser at the sides than on average).
const LON_WARP: f64 = 0.75;

/// Longitude (radians, [0, 2 PI]) of grid column `s = j / cols` in [0, 1].
fn column_longitude(s: f64) -> f64 {
    // d(phi)/ds = 2 PI (1 + a cos(4 PI s)): smallest at s = 1/4 and 3/4.
    2.0 * PI * s + 0.5 * LON_WARP * (4.0 * PI * s).sin()
}

/// Unit direction for polar angle `theta` (from +y) and longitude `phi`.
pub fn direction(theta: f64, phi: f64) -> [f64; 3] {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    [-st * sp, ct, -st * cp]
}

/// Angle between two unit vectors, accurate for small angles.
fn angle_between(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = len(sub(a, b));
    2.0 * (0.5 * d).min(1.0).asin()
}

fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

struct Ear {
    /// Longitude of the fin plane.
    phi: f64,
}

const EARS: [Ear; 2] = [Ear { phi: 0.5 * PI }, Ear { phi: 1.5 * PI }];
/// Polar angle of the ear centre line.
const EAR_THETA: f64 = 0.62;
/// Half width of the ear along the fin (radians of polar angle).
const EAR_HALF_WIDTH: f64 = 0.26;
/// Ear length (radial extent above the body).
const EAR_LENGTH: f64 = 0.45;
/// Half thickness of the ear base, as a tangential angle (sin of the angle
/// between the direction and the fin plane).
const EAR_HALF_THICK: f64 = 0.025;

fn ear_bump(d: [f64; 3], theta: f64, ear: &Ear) -> f64 {
    let y = theta - EAR_THETA;
    if y.abs() >= EAR_HALF_WIDTH {
        return 0.0;
    }
    // Horizontal direction of the ear, and the normal of the fin plane
    // (which contains the y axis and the ear direction).
    let (sp, cp) = ear.phi.sin_cos();
    let h = [-sp, 0.0, -cp];
    let n = [-cp, 0.0, sp];
    if dot(d, h) <= 0.0 {
        return 0.0;
    }
    let s = dot(d, n) / EAR_HALF_THICK;
    if s.abs() >= 1.0 {
        return 0.0;
    }
    let along = 1.0 - (y / EAR_HALF_WIDTH).powi(2);
    let across = (1.0 - s * s).powi(2);
    EAR_LENGTH * along * across
}

/// Polar angle of the hand centres.
const HAND_THETA: f64 = 1.78;
const HAND_PHIS: [f64; 2] = [0.5 * PI, 1.5 * PI];
/// Angular radius of a finger.
const FINGER_RADIUS: f64 = 0.042;
/// Angular spacing between finger axes (along the polar angle).
const FINGER_SPACING: f64 = 0.12;
const FINGER_LENGTHS: [f64; 5] = [0.22, 0.30, 0.34, 0.31, 0.25];

fn finger_dirs() -> impl Iterator<Item = [f64; 3]> {
    HAND_PHIS.iter().flat_map(|&phi| {
        FINGER_LENGTHS.iter().enumerate().map(move |(k, _)| {
            let t = HAND_THETA + (k as f64 - 2.0) * FINGER_SPACING;
            direction(t, phi)
        })
    })
}

fn bump(d: [f64; 3], centre: [f64; 3], width: f64, height: f64) -> f64 {
    let a = angle_between(d, centre) / width;
    height * (-a * a).exp()
}

/// The radius function `r(dir)` of the star-shaped creature (for a unit
/// direction `dir`).  Always strictly positive (>= ~0.68).
pub fn radius(dir: [f32; 3]) -> f32 {
    let d = normalize(to64(dir));
    radius64(d) as f32
}

fn radius64(d: [f64; 3]) -> f64 {
    // Body: ellipsoid, semi-axes 0.75 (x), 1.0 (y), 0.68 (z).
    let e = (d[0] / 0.75).powi(2) + d[1].powi(2) + (d[2] / 0.68).powi(2);
    let mut r = 1.0 / e.sqrt();

    // Snout, belly bulge, feet.
    r += bump(d, direction(0.85, PI), 0.22, 0.10);
    r += bump(d, direction(1.95, PI), 0.55, 0.10);
    r += bump(d, direction(2.7, PI - 0.55), 0.22, 0.14);
    r += bump(d, direction(2.7, PI + 0.55), 0.22, 0.14);

    // Ears.
    let theta = d[1].clamp(-1.0, 1.0).acos();
    for ear in &EARS {
        r += ear_bump(d, theta, ear);
    }

    // Hands: a pad plus five finger spikes each.
    for &phi in &HAND_PHIS {
        r += bump(d, direction(HAND_THETA, phi), 0.2, 0.12);
    }
    for (i, f) in finger_dirs().enumerate() {
        let s = angle_between(d, f) / FINGER_RADIUS;
        if s < 1.0 {
            // Elliptic profile: nearly constant width, rounded tip.
            r += FINGER_LENGTHS[i % FINGER_LENGTHS.len()] * (1.0 - s * s).sqrt();
        }
    }
    r
}

// ---------------------------------------------------------------------------
// Mesh generation
// ---------------------------------------------------------------------------

/// Default creature: 181 rings x 180 columns, 32,763 vertices, 65,160
/// triangles, no degenerate triangles.
pub fn default_creature() -> CreatureMesh {
    creature(DEFAULT_ROWS, DEFAULT_COLS)
}

/// Default-resolution creature built with duplicated pole rows (contains
/// 2 * 180 = 360 zero-area triangles).
pub fn default_creature_with_pole_rows() -> CreatureMesh {
    creature_with_pole_rows(DEFAULT_ROWS, DEFAULT_COLS)
}

/// Creature with `lat` latitude rings (poles excluded) and `lon` longitude
/// segments.  One vertex per pole with triangle fans; the seam column is
/// duplicated.  `2 + lat * (lon + 1)` vertices, `2 * lat * lon` triangles.
pub fn creature(lat: u32, lon: u32) -> CreatureMesh {
    build(lat, lon, false)
}

/// The same surface as [`creature`], but built on the naive lat-long grid
/// with a full row of (bit-identical) vertices at each pole:
/// `(lat + 2) * (lon + 1)` vertices and `2 * (lat + 1) * lon` triangles, of
/// which `2 * lon` (one per pole quad) have zero area.
pub fn creature_with_pole_rows(lat: u32, lon: u32) -> CreatureMesh {
    build(lat, lon, true)
}

fn build(rows: u32, cols: u32, pole_rows: bool) -> CreatureMesh {
    assert!(rows >= 1, "need at least one latitude ring");
    assert!(cols >= 3, "need at least three longitude segments");
    let bands = rows + 1;
    let stride = cols + 1;

    // Per-column longitude and direction factors.
    let phis: Vec<f64> = (0..=cols)
        .map(|j| {
            if j == cols {
                2.0 * PI
            } else {
                column_longitude(j as f64 / cols as f64)
            }
        })
        .collect();
    let col_u = |j: u32| -> f32 {
        if j == cols {
            1.0
        } else {
            (phis[j as usize] / (2.0 * PI)) as f32
        }
    };

    let pole = |north: bool| -> [f32; 3] {
        let d = [0.0, if north { 1.0 } else { -1.0 }, 0.0];
        to32(scale(d, radius64(d)))
    };
    let ring = |i: u32| -> Vec<[f32; 3]> {
        let theta = PI * i as f64 / bands as f64;
        let mut v: Vec<[f32; 3]> = (0..cols)
            .map(|j| {
                let d = direction(theta, phis[j as usize]);
                to32(scale(d, radius64(d)))
            })
            .collect();
        v.push(v[0]); // seam duplicate: bit-identical
        v
    };

    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    // Canonical vertex id (merging seam / pole duplicates) for normals.
    let mut canon: Vec<u32> = Vec::new();
    let mut triangles = Vec::new();

    if pole_rows {
        for i in 0..=bands {
            let v = i as f32 / bands as f32;
            let v = if i == bands { 1.0 } else { v };
            let row: Vec<[f32; 3]> = if i == 0 || i == bands {
                vec![pole(i == 0); stride as usize]
            } else {
                ring(i)
            };
            for (j, p) in row.into_iter().enumerate() {
                let j = j as u32;
                positions.push(p);
                uvs.push([col_u(j), v]);
                let base = i * stride;
                canon.push(if i == 0 || i == bands {
                    base
                } else {
                    base + j % cols
                });
            }
        }
        let idx = |i: u32, j: u32| i * stride + j;
        for i in 0..bands {
            for j in 0..cols {
                triangles.push([idx(i, j), idx(i + 1, j), idx(i, j + 1)]);
                triangles.push([idx(i, j + 1), idx(i + 1, j), idx(i + 1, j + 1)]);
            }
        }
    } else {
        positions.push(pole(true));
        uvs.push([0.5, 0.0]);
        canon.push(0);
        for i in 1..=rows {
            let v = i as f32 / bands as f32;
            let base = 1 + (i - 1) * stride;
            for (j, p) in ring(i).into_iter().enumerate() {
                let j = j as u32;
                positions.push(p);
                uvs.push([col_u(j), v]);
                canon.push(base + j % cols);
            }
        }
        let south = positions.len() as u32;
        positions.push(pole(false));
        uvs.push([0.5, 1.0]);
        canon.push(south);

        let idx = |i: u32, j: u32| 1 + (i - 1) * stride + j;
        for j in 0..cols {
            triangles.push([0, idx(1, j), idx(1, j + 1)]);
        }
        for i in 1..rows {
            for j in 0..cols {
                triangles.push([idx(i, j), idx(i + 1, j), idx(i, j + 1)]);
                triangles.push([idx(i, j + 1), idx(i + 1, j), idx(i + 1, j + 1)]);
            }
        }
        for j in 0..cols {
            triangles.push([idx(rows, j), south, idx(rows, j + 1)]);
        }
    }

    let normals = smooth_normals(&positions, &triangles, &canon);
    CreatureMesh {
        positions,
        triangles,
        uvs,
        normals,
    }
}

/// Area-weighted vertex normals, accumulated over vertices sharing the same
/// canonical id so that duplicated seam / pole vertices get identical normals.
fn smooth_normals(positions: &[[f32; 3]], triangles: &[[u32; 3]], canon: &[u32]) -> Vec<[f32; 3]> {
    let mut acc = vec![[0.0f64; 3]; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| to64(positions[i as usize]));
        let n = cross(sub(b, a), sub(c, a)); // length = 2 * area
        for &i in t {
            let k = canon[i as usize] as usize;
            acc[k] = add(acc[k], n);
        }
    }
    (0..positions.len())
        .map(|i| {
            let n = acc[canon[i] as usize];
            let l = len(n);
            if l > 0.0 {
                to32(scale(n, 1.0 / l))
            } else {
                // Cannot happen for this surface; fall back to the radial
                // direction.
                to32(normalize(to64(positions[i])))
            }
        })
        .collect()
}

// ---------------------------------------------------------------------------
// Density maps
// ---------------------------------------------------------------------------

fn uv_dist(a: [f32; 2], b: [f32; 2]) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

fn smoothstep32(e0: f32, e1: f32, x: f32) -> f32 {
    smoothstep(e0 as f64, e1 as f64, x as f64) as f32
}

/// Hair density of the creature as a function of UV, in [0, 1]:
///
/// * exactly 0.0 inside the face disc ([`FACE_UV`], [`FACE_RADIUS_UV`]) and
///   the two palm discs ([`PALM_UVS`], [`PALM_RADIUS_UV`]), with a smooth
///   0.03-wide ramp back to 1.0 around them;
/// * a smooth gray gradient on the belly: 0.3 at [`BELLY_UV`] rising to 1.0
///   at the rim of an ellipse with radii (0.12, 0.16);
/// * 1.0 everywhere else.
pub fn bald_density(uv: [f32; 2]) -> f32 {
    let face = smoothstep32(FACE_RADIUS_UV, FACE_RADIUS_UV + 0.03, uv_dist(uv, FACE_UV));
    let palms = PALM_UVS
        .iter()
        .map(|&c| smoothstep32(PALM_RADIUS_UV, PALM_RADIUS_UV + 0.03, uv_dist(uv, c)))
        .fold(1.0f32, f32::min);
    let bu = (uv[0] - BELLY_UV[0]) / 0.12;
    let bv = (uv[1] - BELLY_UV[1]) / 0.16;
    let t = (bu * bu + bv * bv).sqrt();
    let belly = 0.3 + 0.7 * smoothstep32(0.0, 1.0, t);
    face.min(palms).min(belly).clamp(0.0, 1.0)
}

/// Sample `f` into a `width x height` 8-bit grayscale image, row-major.
///
/// Convention: texel (x, y) covers uv = ((x + 0.5) / width, (y + 0.5) / height),
/// i.e. row 0 holds v near 0 (top of the creature) and the image is stored
/// top row first, as PNG expects.  Values are `round(255 * clamp(f, 0, 1))`.
pub fn sample_texture(width: u32, height: u32, f: impl Fn([f32; 2]) -> f32) -> Vec<u8> {
    let mut out = Vec::with_capacity(width as usize * height as usize);
    for y in 0..height {
        let v = (y as f32 + 0.5) / height as f32;
        for x in 0..width {
            let u = (x as f32 + 0.5) / width as f32;
            out.push((f([u, v]).clamp(0.0, 1.0) * 255.0).round() as u8);
        }
    }
    out
}

/// [`bald_density`] sampled at texel centres (see [`sample_texture`] for the
/// convention: texel (x, y) covers uv = ((x+0.5)/w, (y+0.5)/h), row 0 = v≈0).
pub fn density_texture(width: u32, height: u32) -> Vec<u8> {
    sample_texture(width, height, bald_density)
}

fn fig5_white(_uv: [f32; 2]) -> f32 {
    1.0
}

/// Mid-gray gradient: 0.25 at the top (v = 0) to 0.75 at the bottom (v = 1),
/// average 0.5.
fn fig5_gradient(uv: [f32; 2]) -> f32 {
    (0.25 + 0.5 * uv[1]).clamp(0.0, 1.0)
}

/// Dark map: 0.35 gray with black stripes across u and black discs.
fn fig5_dark(uv: [f32; 2]) -> f32 {
    // Ten vertical stripes, the first 40% of each black.
    let stripe = (uv[0] * 10.0).fract() < 0.4;
    // Black discs on the face and around the hands.
    let disc = uv_dist(uv, FACE_UV) < 0.1 || PALM_UVS.iter().any(|&c| uv_dist(uv, c) < 0.08);
    if stripe || disc {
        0.0
    } else {
        0.35
    }
}

/// Three grayscale density maps in the spirit of the paper's Figure 5
/// experiment: `("white", 1.0 everywhere)`, `("gradient", 0.25..0.75 along v)`,
/// `("dark", 0.35 gray with black stripes and discs)`.
#[allow(clippy::type_complexity)]
pub fn figure5_maps() -> [(&'static str, fn([f32; 2]) -> f32); 3] {
    [
        ("white", fig5_white as fn([f32; 2]) -> f32),
        ("gradient", fig5_gradient),
        ("dark", fig5_dark),
    ]
}

// ---------------------------------------------------------------------------
// Output
// ---------------------------------------------------------------------------

/// Write the mesh as a Wavefront OBJ (`v`, `vt`, `vn`, `f a/a/a ...`, 1-based).
/// Floats are written with Rust's shortest round-tripping `{}` formatting, so
/// reading them back as f32 gives the identical bits.
pub fn write_obj(mesh: &CreatureMesh, path: &Path) -> io::Result<()> {
    let mut w = BufWriter::new(std::fs::File::create(path)?);
    writeln!(
        w,
        "# pelage creature: {} vertices, {} triangles",
        mesh.positions.len(),
        mesh.triangles.len()
    )?;
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
    }
    for t in &mesh.uvs {
        writeln!(w, "vt {} {}", t[0], t[1])?;
    }
    for n in &mesh.normals {
        writeln!(w, "vn {} {} {}", n[0], n[1], n[2])?;
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        writeln!(w, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}")?;
    }
    w.flush()
}

/// Write an 8-bit grayscale PNG (`data` is row-major, row 0 on top).
pub fn write_png_gray(path: &Path, width: u32, height: u32, data: &[u8]) -> io::Result<()> {
    if data.len() != width as usize * height as usize {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "expected {}x{} = {} bytes, got {}",
                width,
                height,
                width as usize * height as usize,
                data.len()
            ),
        ));
    }
    let file = BufWriter::new(std::fs::File::create(path)?);
    let mut enc = png::Encoder::new(file, width, height);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().map_err(io::Error::other)?;
    writer.write_image_data(data).map_err(io::Error::other)?;
    writer.finish().map_err(io::Error::other)?;
    Ok(())
}

// ---------------------------------------------------------------------------
// Small vector helpers
// ---------------------------------------------------------------------------

fn to64(p: [f32; 3]) -> [f64; 3] {
    p.map(|x| x as f64)
}
fn to32(p: [f64; 3]) -> [f32; 3] {
    p.map(|x| x as f32)
}
fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn len(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
fn normalize(a: [f64; 3]) -> [f64; 3] {
    scale(a, 1.0 / len(a))
}

// ---------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;
    use std::sync::OnceLock;

    fn mesh() -> &'static CreatureMesh {
        static M: OnceLock<CreatureMesh> = OnceLock::new();
        M.get_or_init(default_creature)
    }

    fn pos_key(p: [f32; 3]) -> [u32; 3] {
        p.map(|x| x.to_bits())
    }

    /// Count undirected and directed edge uses, merging vertices by position,
    /// skipping zero-area triangles.
    fn check_watertight(m: &CreatureMesh) {
        let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
        let vid: Vec<u32> = m
            .positions
            .iter()
            .map(|&p| {
                let n = ids.len() as u32;
                *ids.entry(pos_key(p)).or_insert(n)
            })
            .collect();
        let mut undirected: HashMap<(u32, u32), u32> = HashMap::new();
        let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
        for (ti, t) in m.triangles.iter().enumerate() {
            if m.triangle_area(ti) == 0.0 {
                continue;
            }
            let v = t.map(|i| vid[i as usize]);
            assert!(v[0] != v[1] && v[1] != v[2] && v[0] != v[2]);
            for k in 0..3 {
                let (a, b) = (v[k], v[(k + 1) % 3]);
                *undirected.entry((a.min(b), a.max(b))).or_default() += 1;
                *directed.entry((a, b)).or_default() += 1;
            }
        }
        for (e, c) in &undirected {
            assert_eq!(*c, 2, "edge {e:?} used {c} times");
        }
        for (e, c) in &directed {
            assert_eq!(
                *c, 1,
                "directed edge {e:?} used {c} times (inconsistent winding)"
            );
        }
        // Euler characteristic of a sphere.
        let used: std::collections::HashSet<u32> = vid.iter().copied().collect();
        let faces = m
            .triangles
            .iter()
            .enumerate()
            .filter(|(i, _)| m.triangle_area(*i) > 0.0)
            .count();
        assert_eq!(
            used.len() as i64 - undirected.len() as i64 + faces as i64,
            2
        );
    }

    #[test]
    fn counts_and_indices() {
        let m = mesh();
        let nt = m.triangle_count();
        assert!((64_000..=66_000).contains(&nt), "{nt} triangles");
        assert_eq!(nt, 2 * 181 * 180);
        assert_eq!(m.vertex_count(), 2 + 181 * 181);
        assert_eq!(m.uvs.len(), m.vertex_count());
        assert_eq!(m.normals.len(), m.vertex_count());
        let nv = m.vertex_count() as u32;
        for t in &m.triangles {
            for &i in t {
                assert!(i < nv);
            }
        }
        for uv in &m.uvs {
            assert!((0.0..=1.0).contains(&uv[0]) && (0.0..=1.0).contains(&uv[1]));
        }
        let (lo, hi) = m.bounds();
        let height = hi[1] - lo[1];
        assert!((1.8..2.6).contains(&height), "height {height}");
    }

    #[test]
    fn deterministic() {
        assert_eq!(creature(40, 36), creature(40, 36));
    }

    #[test]
    fn no_degenerate_triangles_in_default() {
        let m = mesh();
        for i in 0..m.triangle_count() {
            assert!(m.triangle_area(i) > 0.0, "triangle {i} is degenerate");
        }
    }

    #[test]
    fn pole_rows_variant_has_degenerates() {
        let m = default_creature_with_pole_rows();
        let degenerate = (0..m.triangle_count())
            .filter(|&i| m.triangle_area(i) == 0.0)
            .count();
        assert_eq!(degenerate, 2 * DEFAULT_COLS as usize);
        assert_eq!(m.triangle_count(), 2 * 182 * 180);
        check_watertight(&m);
        // Same surface as the default mesh.
        let d = mesh();
        let area = |m: &CreatureMesh| {
            (0..m.triangle_count())
                .map(|i| m.triangle_area(i))
                .sum::<f64>()
        };
        assert!((area(&m) - area(d)).abs() < 1e-9 * area(d));
    }

    #[test]
    fn watertight() {
        check_watertight(mesh());
        check_watertight(&creature(7, 5));
        // Seam duplicates are bit-identical, in position and normal.
        let m = mesh();
        let stride = DEFAULT_COLS as usize + 1;
        for i in 0..DEFAULT_ROWS as usize {
            let a = 1 + i * stride;
            let b = a + DEFAULT_COLS as usize;
            assert_eq!(pos_key(m.positions[a]), pos_key(m.positions[b]));
            assert_eq!(pos_key(m.normals[a]), pos_key(m.normals[b]));
            assert_eq!(m.uvs[a][0], 0.0);
            assert_eq!(m.uvs[b][0], 1.0);
        }
    }

    #[test]
    fn outward_and_star_shaped() {
        let m = mesh();
        let mut volume = 0.0;
        for (i, t) in m.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|k| to64(m.positions[k as usize]));
            let n = cross(sub(b, a), sub(c, a));
            let centroid = scale(add(add(a, b), c), 1.0 / 3.0);
            // Each triangle faces away from the origin: star-shaped.
            assert!(dot(n, centroid) > 0.0, "triangle {i} faces the origin");
            volume += dot(a, cross(b, c)) / 6.0;
        }
        assert!(volume > 1.5 && volume < 4.0, "volume {volume}");
    }

    #[test]
    fn radius_positive() {
        let mut min = f32::INFINITY;
        for i in 0..=400 {
            for j in 0..800 {
                let d = direction(PI * i as f64 / 400.0, 2.0 * PI * j as f64 / 800.0);
                min = min.min(radius(to32(d)));
            }
        }
        assert!(min > 0.5, "min radius {min}");
    }

    #[test]
    fn normals_unit_and_outward() {
        let m = mesh();
        for n in &m.normals {
            let l = len(to64(*n));
            assert!((l - 1.0).abs() < 1e-5, "normal length {l}");
            assert!(n.iter().all(|x| x.is_finite()));
        }
        // Poles point up / down.
        assert!(m.normals[0][1] > 0.99);
        assert!(m.normals[m.vertex_count() - 1][1] < -0.99);
    }

    /// Pairs of vertices closer than `max_dist` whose normals are opposite.
    fn opposite_pairs(m: &CreatureMesh, max_dist: f32) -> Vec<(usize, usize, f32)> {
        let cell = max_dist;
        let key = |p: [f32; 3]| p.map(|x| (x / cell).floor() as i32);
        let mut grid: HashMap<[i32; 3], Vec<usize>> = HashMap::new();
        for (i, p) in m.positions.iter().enumerate() {
            grid.entry(key(*p)).or_default().push(i);
        }
        let mut out = Vec::new();
        for (i, p) in m.positions.iter().enumerate() {
            let k = key(*p);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let Some(list) = grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) else {
                            continue;
                        };
                        for &j in list {
                            if j <= i {
                                continue;
                            }
                            let d = len(sub(to64(m.positions[j]), to64(*p))) as f32;
                            if d < max_dist && dot(to64(m.normals[i]), to64(m.normals[j])) < -0.5 {
                                out.push((i, j, d));
                            }
                        }
                    }
                }
            }
        }
        out
    }

    #[test]
    fn thin_parts_exist() {
        let m = mesh();
        let pairs = opposite_pairs(m, 0.05);
        let is_ear = |p: [f32; 3]| p[1] > 0.5;
        let is_hand = |p: [f32; 3]| p[1] < 0.1 && p[0].abs() > 0.6;
        let count = |f: &dyn Fn([f32; 3]) -> bool, side: f32| {
            pairs
                .iter()
                .filter(|(i, _, _)| f(m.positions[*i]) && m.positions[*i][0] * side > 0.0)
                .count()
        };
        for side in [-1.0, 1.0] {
            let ears = count(&is_ear, side);
            let hands = count(&is_hand, side);
            println!("side {side}: {ears} ear pairs, {hands} finger pairs");
            assert!(
                ears >= 20,
                "ear on side {side} not thin enough ({ears} pairs)"
            );
        }
        let min_ear = pairs
            .iter()
            .filter(|(i, _, _)| is_ear(m.positions[*i]))
            .map(|p| p.2)
            .fold(f32::INFINITY, f32::min);
        println!(
            "{} opposite-normal pairs < 0.05 apart; closest ear pair {min_ear}",
            pairs.len()
        );
    }

    /// Analytic ear thickness across the fin (along z) at a fraction of its
    /// height, on the ear centre line.
    fn ear_thickness(height_frac: f64) -> f64 {
        let base = radius64(direction(EAR_THETA, 0.5 * PI + 0.2));
        let target = base + height_frac * EAR_LENGTH;
        // Bisect the longitude offset where r drops to the target radius.
        let (mut lo, mut hi) = (0.0f64, 0.2f64);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if radius64(direction(EAR_THETA, 0.5 * PI + mid)) > target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let p = scale(direction(EAR_THETA, 0.5 * PI + lo), target);
        2.0 * p[2].abs()
    }

    #[test]
    fn ear_is_thin_and_resolved() {
        let mid = ear_thickness(0.5);
        let base = ear_thickness(0.05);
        let rim = ear_thickness(0.9);
        println!("ear thickness: base {base:.4}, mid {mid:.4}, near rim {rim:.4}");
        assert!((0.02..=0.04).contains(&mid), "mid thickness {mid}");
        assert!(base < 0.1 && rim < mid);
        // Columns across the ear at the default resolution.
        let cols = DEFAULT_COLS;
        let across = |half_angle: f64| {
            (0..cols)
                .filter(|&j| {
                    let phi = column_longitude(j as f64 / cols as f64);
                    (phi - 0.5 * PI).abs() * EAR_THETA.sin() < half_angle
                })
                .count()
        };
        let at_base = across(EAR_HALF_THICK);
        let at_mid = across(EAR_HALF_THICK * (1.0 - 0.5f64.sqrt()).sqrt());
        println!("columns across ear: base {at_base}, mid height {at_mid}");
        assert!(at_base >= 8 && at_mid >= 3);
        // Rows along the ear and across a finger.
        let rows_across = |half: f64| {
            (1..=DEFAULT_ROWS)
                .filter(|&i| (PI * i as f64 / (DEFAULT_ROWS + 1) as f64 - HAND_THETA).abs() < half)
                .count()
        };
        let finger_rows = rows_across(FINGER_RADIUS);
        println!("rows across a finger: {finger_rows}");
        assert!(finger_rows >= 4);
    }

    #[test]
    fn fingers_stick_out() {
        for (i, f) in finger_dirs().enumerate() {
            let tip = radius64(f);
            let around = radius64(normalize(add(f, [0.0, 0.0, 0.1])));
            assert!(
                tip - around > 0.15,
                "finger {i}: tip {tip}, around {around}"
            );
        }
    }

    #[test]
    fn density_map() {
        assert_eq!(bald_density(FACE_UV), 0.0);
        assert_eq!(
            bald_density([FACE_UV[0] + 0.9 * FACE_RADIUS_UV, FACE_UV[1]]),
            0.0
        );
        for c in PALM_UVS {
            assert_eq!(bald_density(c), 0.0);
        }
        assert_eq!(bald_density([0.05, 0.5]), 1.0);
        assert_eq!(bald_density([0.5, 0.05]), 1.0);
        let belly = bald_density(BELLY_UV);
        assert!((belly - 0.3).abs() < 1e-6);
        let b2 = bald_density([BELLY_UV[0], BELLY_UV[1] + 0.08]);
        assert!(b2 > 0.35 && b2 < 0.95, "{b2}");
        let tex = density_texture(64, 32);
        assert_eq!(tex.len(), 64 * 32);
        let ones = tex.iter().filter(|&&x| x == 255).count();
        assert!(ones > tex.len() / 2, "most of the body is fully furred");
        assert!(tex.contains(&0));
        // Texel convention: texel (32, 8) covers uv = (32.5/64, 8.5/32).
        assert_eq!(
            tex[8 * 64 + 32],
            (bald_density([32.5 / 64.0, 8.5 / 32.0]) * 255.0).round() as u8
        );
        for (name, f) in figure5_maps() {
            for y in 0..20 {
                for x in 0..20 {
                    let v = f([(x as f32 + 0.5) / 20.0, (y as f32 + 0.5) / 20.0]);
                    assert!((0.0..=1.0).contains(&v), "{name}: {v}");
                }
            }
        }
        let maps = figure5_maps();
        assert_eq!((maps[0].1)([0.3, 0.3]), 1.0);
        assert!(((maps[1].1)([0.3, 0.5]) - 0.5).abs() < 1e-6);
        assert_eq!((maps[2].1)([0.01, 0.5]), 0.0);
    }

    #[test]
    fn obj_and_png_round_trip() {
        let dir = std::env::temp_dir().join(format!("pelage_creature_test_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let m = creature(10, 12);
        let obj = dir.join("c.obj");
        write_obj(&m, &obj).unwrap();
        let text = std::fs::read_to_string(&obj).unwrap();
        let mut pos = Vec::new();
        let mut faces = Vec::new();
        for line in text.lines() {
            let mut it = line.split_whitespace();
            match it.next() {
                Some("v") => pos.push([0; 3].map(|_| it.next().unwrap().parse::<f32>().unwrap())),
                Some("f") => faces.push([0; 3].map(|_| {
                    let s = it.next().unwrap();
                    s.split('/').next().unwrap().parse::<u32>().unwrap() - 1
                })),
                _ => {}
            }
        }
        assert_eq!(pos.len(), m.positions.len());
        for (a, b) in pos.iter().zip(&m.positions) {
            assert_eq!(pos_key(*a), pos_key(*b));
        }
        assert_eq!(faces, m.triangles);

        let png_path = dir.join("d.png");
        let tex = density_texture(16, 8);
        write_png_gray(&png_path, 16, 8, &tex).unwrap();
        let dec = png::Decoder::new(std::fs::File::open(&png_path).unwrap());
        let mut reader = dec.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (16, 8));
        assert_eq!(info.color_type, png::ColorType::Grayscale);
        assert_eq!(&buf[..info.buffer_size()], &tex[..]);
        assert!(write_png_gray(&png_path, 16, 8, &tex[1..]).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
