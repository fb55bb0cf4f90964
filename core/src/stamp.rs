//! Poisson stamping of hair roots (paper section 2.3), with the edge
//! violations removed and a nested LOD order.
//!
//! Every triangle is laid flat, scaled by its density, rotated and translated
//! inside a periodic Poisson tile, and takes the tile points that fall inside
//! it. Where the paper places each triangle at random on its own, neighbouring
//! triangles that bend by less than [`chart::MAX_BEND_DEGREES`] and share a
//! density step are unfolded together into charts (see [`chart`]), and each
//! chart takes one random rotation and offset (keyed by its first triangle):
//! across the edges inside a chart the points come from one continuous piece
//! of the tile, so they need no repair. Then:
//! 1. **Edge pass.** Points of different triangles closer than the disk radius
//!    (in 3D) are resolved by dropping the later one, in face order. Only
//!    points whose disk reaches a cut edge, or past a linked neighbour, take
//!    part (27% of them at 1M roots on the creature, 69% with a placement per
//!    triangle). Across a linked edge that bends by `a`, the tile's spacing
//!    shrinks by at most `cos(a / 2)` in 3D (0.99905 at 5 degrees).
//! 2. **Count.** The radius is derived so the *expected* number of stamped
//!    points equals the target: for a uniform random placement in a periodic
//!    tile of density `rho` points per `r^2`, a triangle of flattened area `A`
//!    scaled by `s` receives `rho * A * s^2 / r^2` points on average, hence
//!    `r = sqrt(rho * sum(A_i s_i^2) / N)`. The edge pass removes a
//!    mesh-dependent share, which a model fitted to the measured loss per
//!    length of cut edge predicts for the first pass; the measured count then
//!    corrects the radius until the count is within [`COUNT_TOLERANCE`] of
//!    the target (dense stamps usually need no correction). (The paper's
//!    `0.35 / (sqrt(N) * A_max_normalized)` is not dimensionally a length.)
//! 3. **LOD.** Each tile point carries a nested level. Across triangles, a
//!    point moves to the first level whose spacing it respects from every
//!    point of another triangle that comes before it (a coarser tile level,
//!    or the same level on an earlier triangle); the rule reads tile levels
//!    only, so it needs one query per point and level and no re-checking.
//!    The rank is a counting sort by (level, hash of the index).
//!
//! Triangle stamping takes face ranges ([`Stamper::stamp_faces`]) so a host can
//! spread it over threads; the result is bitwise identical for any split.

use crate::arena::{Arena, ArenaLayout};
use crate::chart::{self, Unfolded};
use crate::grid::{floor_i32, HashGrid};
use crate::rng::{self, Purpose};
use crate::tile::{Tile, CELL, CELLS, LOD_LEVELS, TILE_SIDE};
use crate::{Error, Mesh, Root, ScalarMap};
use bytemuck::{Pod, Zeroable};
use core::ops::Range;
use glam::{BVec4A, Vec2, Vec3, Vec4};

/// Width of the band above the target where the radius correction stops;
/// the surplus is trimmed by LOD rank.
pub const COUNT_TOLERANCE: f32 = 0.02;
/// Grid cells of the edge and LOD passes, in disk radii (times the level's
/// spacing): larger cells mean fewer buckets per face's query box but more
/// points per bucket; 5 measured best against 3, 4, 6 and 8 on the creature
/// at 1M roots.
const GRID_CELL: f32 = 5.0;
/// Points the edge pass removes per disk radius of cut edge (an edge whose
/// two faces are not laid out together, see [`chart`]), and the edge
/// length (in radii) below which the loss falls off: a fit of the measured
/// loss over creature meshes of 16K to 262K triangles and 10K to 3M roots.
/// On the default creature every count from 10K to 1M lands in the count
/// band in one pass; elsewhere the first pass misses by up to 3.5% at 100K
/// roots and more, and by more at 10K on dense meshes. The model only picks
/// the first radius; the measured count corrects the rest.
const EDGE_LOSS: f32 = 0.13;
/// See [`EDGE_LOSS`].
const EDGE_LOSS_KNEE: f32 = 0.12;
/// How far a chart reaches from its first corner, in disk radii: two
/// tiles. Charts cut at the reach add edges to check; a larger reach saves
/// little more (27.0% of the points take part in the edge pass at 1M roots
/// on the creature, 29.1% at one tile, 25.6% unbounded).
const CHART_REACH: f32 = 2.0 * TILE_SIDE as f32;
/// Fixed-point steps of the first radius.
const PREDICTION_STEPS: u32 = 4;
/// Passes that correct the radius from the measured count.
const SECANT_PASSES: u32 = 5;
/// Passes after which the stamp is accepted whatever its count.
const MAX_PASSES: u32 = 16;
/// Lowest radius, relative to the first estimate, a correction may reach
/// (bounds the candidate memory).
const MIN_RADIUS_FACTOR: f32 = 0.7;
/// The same for sparse stamps (fewer than 4 roots per triangle), where the
/// edge pass removes up to half the points; their candidate memory is small.
const MIN_RADIUS_FACTOR_SPARSE: f32 = 0.45;

fn min_radius_factor(target: u32, faces: usize) -> f32 {
    if (target as usize) < 4 * faces {
        MIN_RADIUS_FACTOR_SPARSE
    } else {
        MIN_RADIUS_FACTOR
    }
}

/// Stamping parameters.
#[derive(Clone, Copy, Debug)]
pub struct StampParams<'a> {
    /// Number of roots wanted on the whole mesh (ignored when `radius` is set).
    pub target_count: u32,
    /// A fixed disk radius instead of a count: 0 derives the radius from
    /// `target_count`; a positive value stamps at that spacing and keeps
    /// every root (the paper's setting, where darker maps give fewer roots).
    pub radius: f32,
    /// Seed of every random choice; same seed, same roots.
    pub seed: u64,
    /// Grayscale density in `[0, 1]`, sampled at each triangle's centroid.
    pub density: ScalarMap<'a>,
    /// Triangle scale for black (density 0); white is 1, gray interpolates
    /// linearly. The paper's "black = half size" is 0.5.
    pub black_scale: f32,
    /// Triangles whose density is below this value get no roots (bald
    /// regions such as faces and palms). 0 disables it.
    pub bald_below: f32,
}

impl Default for StampParams<'_> {
    fn default() -> Self {
        StampParams {
            target_count: 0,
            radius: 0.0,
            seed: 0,
            density: ScalarMap::Constant(1.0),
            black_scale: 0.5,
            bald_below: 1.0 / 512.0,
        }
    }
}

/// What stamping did, for logs and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StampReport {
    /// Final disk radius (the minimum 3D spacing in white regions).
    pub radius: f32,
    /// Points taken from the stamp in the last pass.
    pub candidates: u32,
    /// Points the edge pass removed in the last pass.
    pub pruned: u32,
    /// Surplus roots trimmed by LOD rank to land exactly on the target.
    pub trimmed: u32,
    /// Degenerate triangles skipped.
    pub degenerate_triangles: u32,
    /// Stamping passes run (radius corrections + 1).
    pub passes: u32,
}

/// A stamped point before the edge pass: where it is and which tile level it had.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Candidate {
    /// Triangle index.
    pub face: u32,
    /// Barycentric coordinates on the triangle.
    pub uv: [f32; 2],
    /// LOD level inherited from the tile (0 = coarsest).
    pub level: u16,
    /// How many LOD levels, coarsest first, have a spacing (in units of the
    /// local disk radius) that reaches from the point past a cut edge of its
    /// triangle or the far side of a linked neighbour. Within that distance
    /// every point comes from the same piece of the tile, so only at those
    /// levels can the point conflict with points of other triangles;
    /// [`LOD_LEVELS`] means even the disk radius reaches (the point takes
    /// part in the edge pass).
    pub near_levels: u16,
}

impl Candidate {
    /// Whether the disk radius reaches past the triangle's boundary, so that
    /// the point takes part in the edge pass.
    #[inline]
    pub fn near_edge(&self) -> bool {
        self.near_levels as usize == LOD_LEVELS
    }
}

/// The spacing of each LOD level in units of the disk radius: `sqrt(2)`
/// between levels, 1 at the finest.
fn lod_spacings() -> [f32; LOD_LEVELS] {
    core::array::from_fn(|k| libm::powf(2.0, 0.5 * (LOD_LEVELS - 1 - k) as f32))
}

/// Corner 0 of face `f` and its edges to corners 1 and 2: a point at
/// barycentric `(u, v)` lies at `a + e1 * u + e2 * v`.
fn face_frame(mesh: &Mesh, f: usize) -> [Vec3; 3] {
    let [a, b, c] = mesh.corners(f);
    [a, b - a, c - a]
}

/// Per-face data the edge and LOD passes read for every point they test.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
struct Face {
    normal: [f32; 3],
    /// 0 for a skipped (degenerate or bald) face.
    scale: f32,
}

/// Where a face lies in the tile, computed once for every pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
struct TilePlace {
    /// Corners in the chart's plane, turned by the chart's rotation (world
    /// units times the face's scale; a pass divides by the radius). Faces
    /// linked across an edge hold bit-identical copies of its two corners.
    corners: [[f32; 2]; 3],
    /// For each linked edge, the neighbour's third corner, turned the same way.
    across: [[f32; 2]; 3],
    /// Where the chart's plane origin lands in the tile (tile units).
    offset: [f32; 2],
    /// The chart's rotation (cosine, sine).
    rot: [f32; 2],
    /// [`Unfolded::edges`], and in bit `6 + i` whether edge `i` runs from
    /// the lower vertex index to the higher.
    edges: u32,
}

/// A chart's random rotation and offset in the tile.
#[derive(Clone, Copy)]
struct ChartFrame {
    rot: Vec2,
    offset: Vec2,
}

impl ChartFrame {
    /// The frame of the chart whose first face is `chart`.
    fn new(seed: u64, chart: usize) -> Self {
        let id = chart as u64;
        let angle = rng::unit(seed, id, Purpose::StampRotation, 0) * core::f32::consts::TAU;
        ChartFrame {
            rot: Vec2::new(libm::cosf(angle), libm::sinf(angle)),
            offset: Vec2::new(
                rng::unit(seed, id, Purpose::StampOffsetX, 0),
                rng::unit(seed, id, Purpose::StampOffsetY, 0),
            ) * TILE_SIDE as f32,
        }
    }
}

impl TilePlace {
    fn new(mesh: &Mesh, f: usize, laid: &Unfolded, frame: ChartFrame) -> Self {
        let turn = |p: [f32; 2]| frame.rot.rotate(Vec2::from(p)).into();
        let v = mesh.triangles.get(f);
        let forward = (0..3).fold(0, |e, i| e | ((v[i] < v[(i + 1) % 3]) as u32) << (6 + i));
        TilePlace {
            corners: laid.corners.map(turn),
            across: laid.across.map(turn),
            offset: frame.offset.into(),
            rot: frame.rot.into(),
            edges: laid.edges | forward,
        }
    }

    /// The frame of this face's chart.
    fn frame(&self) -> ChartFrame {
        ChartFrame {
            rot: Vec2::from(self.rot),
            offset: Vec2::from(self.offset),
        }
    }

    /// Edge `i` (corner `i` to corner `i + 1`) in the chart's plane.
    fn edge(&self, i: usize) -> Vec2 {
        Vec2::from(self.corners[(i + 1) % 3]) - Vec2::from(self.corners[i])
    }
}

/// The stamping state for one mesh and parameter set: the tile, per-face
/// scales and the current radius.
pub struct Stamper<'m, 'a> {
    mesh: Mesh<'m>,
    seed: u64,
    target: u32,
    tile: Tile<'a>,
    faces: &'a [Face],
    places: &'a [TilePlace],
    scaled_area: f64,
    first_radius: f32,
    radius: f32,
    /// The radius was given: one pass, every root kept.
    fixed: bool,
    /// Radius and kept count of the previous pass, for the secant.
    previous: Option<(f32, usize)>,
    passes: u32,
    degenerate: u32,
    /// [`lod_spacings`].
    spacings: [f32; LOD_LEVELS],
}

/// Smallest `black_scale`: the spacing in black regions is the radius over
/// it, and the grid queries grow with its cube.
pub const MIN_BLACK_SCALE: f32 = 0.1;

/// Largest target count (ids and ranks are 32-bit; arenas stay addressable).
pub const MAX_TARGET: u32 = 1 << 28;

fn validate(mesh: &Mesh, params: &StampParams) -> Result<(), Error> {
    if params.target_count > MAX_TARGET {
        return Err(Error::InvalidArgument("target_count exceeds 2^28"));
    }
    if !params.radius.is_finite() {
        return Err(Error::NonFinite {
            what: "radius",
            index: 0,
        });
    }
    if params.radius < 0.0 {
        return Err(Error::InvalidArgument(
            "radius must be 0 (use the count) or positive",
        ));
    }
    if !params.black_scale.is_finite() {
        return Err(Error::NonFinite {
            what: "black_scale",
            index: 0,
        });
    }
    if !(MIN_BLACK_SCALE..=1.0).contains(&params.black_scale) {
        return Err(Error::InvalidArgument("black_scale must be in [0.1, 1]"));
    }
    if !params.bald_below.is_finite() {
        return Err(Error::NonFinite {
            what: "bald_below",
            index: 0,
        });
    }
    // degenerate faces are counted and skipped by the face setup
    mesh.check()?;
    params.density.validate(mesh, "density")
}

/// Steps the density takes between black and white when it scales faces.
/// Only faces of one scale are laid out together (see [`chart`]), so a
/// smooth gradient is stamped as bands of equal scale: a step is 0.8% of
/// the face size at the paper's `black_scale` of 0.5 (1.6% of the root
/// density in white regions, 3.1% in black ones).
pub const DENSITY_STEPS: f32 = 64.0;

/// What the setup needs of one face, from one read of its corners.
struct FaceSetup {
    face: Face,
    area: f32,
    perimeter: f32,
    degenerate: bool,
}

impl FaceSetup {
    /// The area, normal and degeneracy [`Mesh::shape`] gives, the
    /// perimeter, and the scale of the density (0 = no roots: bald or
    /// degenerate).
    fn new(mesh: &Mesh, params: &StampParams, f: usize) -> Self {
        let shape = mesh.shape(f);
        let [e1, e2, e3] = shape.edges;
        let scale = if shape.degenerate {
            0.0
        } else {
            density_scale(params, params.density.sample(mesh, f, 1.0 / 3.0, 1.0 / 3.0))
        };
        FaceSetup {
            face: Face {
                normal: shape.cross.normalize_or_zero().into(),
                scale,
            },
            area: 0.5 * shape.cross.length(),
            perimeter: e1.length() + e3.length() + e2.length(),
            degenerate: shape.degenerate,
        }
    }
}

/// Scale of a face of density `d` (0 = no roots).
fn density_scale(params: &StampParams, d: f32) -> f32 {
    if d < params.bald_below {
        return 0.0;
    }
    let step = libm::roundf(d.clamp(0.0, 1.0) * DENSITY_STEPS) / DENSITY_STEPS;
    params.black_scale + (1.0 - params.black_scale) * step
}

/// Sums over the faces that size a stamp.
#[derive(Default)]
struct FaceSums {
    /// Area weighted by the squared density scale.
    area: f64,
    /// Perimeter of the stamped faces, weighted by the density scale.
    perimeter: f64,
    stamped: usize,
    degenerate: u32,
}

impl FaceSums {
    /// Sets up every face of `mesh` (validated), handing each to `keep`.
    fn of(mesh: &Mesh, params: &StampParams, mut keep: impl FnMut(usize, Face)) -> Self {
        let mut sums = FaceSums::default();
        for f in 0..mesh.triangle_count() {
            let setup = FaceSetup::new(mesh, params, f);
            let s = setup.face.scale as f64;
            if s != 0.0 {
                sums.area += setup.area as f64 * s * s;
                sums.perimeter += setup.perimeter as f64 * s;
                sums.stamped += 1;
            }
            sums.degenerate += setup.degenerate as u32;
            keep(f, setup.face);
        }
        sums
    }

    /// Upper bound on the candidates of any pass, for every radius the count
    /// correction can reach.
    ///
    /// The sum of the per-face bounds of [`face_bound`] is bounded by the
    /// same expression summed before rounding, plus 2 per face, so one walk
    /// over the faces gives both the scaled area (hence the smallest radius)
    /// and the bound.
    fn bound(&self, mesh: &Mesh, params: &StampParams) -> Result<usize, Error> {
        let r_min = if params.radius > 0.0 {
            params.radius
        } else {
            let density = tile_density_lower_bound();
            let Some(r) = first_radius(self.area, params.target_count, density) else {
                return Ok(0);
            };
            r * min_radius_factor(params.target_count, mesh.triangle_count())
        } as f64;
        let dilated = self.area / (r_min * r_min)
            + 0.5 * self.perimeter / r_min
            + core::f64::consts::FRAC_PI_4 * self.stamped as f64;
        // ids, ranks and sort keys are 32-bit
        let bound = dilated * HEX_PACKING + 2.0 * self.stamped as f64 + 1.0;
        if bound.is_nan() || bound > 4.0 * MAX_TARGET as f64 {
            return Err(Error::InvalidArgument(
                "radius too small for this mesh (over 2^30 candidates)",
            ));
        }
        Ok(bound as usize)
    }
}

/// The x extent of triangle `t` within the strip y0 <= y <= y1, if any.
fn row_span(t: &[Vec2; 3], y0: f32, y1: f32) -> Option<(f32, f32)> {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for (i, a) in t.iter().enumerate() {
        if (y0..=y1).contains(&a.y) {
            (lo, hi) = (lo.min(a.x), hi.max(a.x));
        }
        let b = t[(i + 1) % 3];
        for y in [y0, y1] {
            if (a.y - y) * (b.y - y) < 0.0 {
                let x = a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y);
                (lo, hi) = (lo.min(x), hi.max(x));
            }
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// Upper bound on the points a face can take at radius `r` (hexagonal
/// packing of the face dilated by r/2).
fn face_bound(mesh: &Mesh, face: usize, scale: f32, r: f32) -> usize {
    if scale == 0.0 {
        return 0;
    }
    let (area, perimeter) = area_and_perimeter(mesh, face);
    let k = scale / r;
    let dilated = area * k * k + 0.5 * perimeter * k + core::f32::consts::FRAC_PI_4;
    // saturating: a radius tiny next to the face is reported by the caller
    (dilated as f64 * HEX_PACKING).min(usize::MAX as f64 / 4.0) as usize + 2
}

/// Points per unit area of the densest packing at unit spacing (2 / sqrt 3).
const HEX_PACKING: f64 = 1.154_700_6;

/// Area and perimeter of `face`.
fn area_and_perimeter(mesh: &Mesh, face: usize) -> (f32, f32) {
    let [a, b, c] = mesh.corners(face);
    let perimeter = (b - a).length() + (c - b).length() + (a - c).length();
    (mesh.area(face), perimeter)
}

/// Upper bound on the roots [`stamp`] writes: the target (surplus stamps
/// are trimmed by LOD rank), or 0 when every face is bald or degenerate;
/// with a fixed radius, a packing bound.
pub fn max_roots(mesh: &Mesh, params: &StampParams) -> Result<usize, Error> {
    if params.radius > 0.0 {
        return candidates_bound(mesh, params);
    }
    validate(mesh, params)?;
    Ok(if FaceSums::of(mesh, params, |_, _| {}).area > 0.0 {
        params.target_count as usize
    } else {
        0
    })
}

/// Upper bound on the candidates of any pass, for every radius the count
/// correction can reach.
fn candidates_bound(mesh: &Mesh, params: &StampParams) -> Result<usize, Error> {
    validate(mesh, params)?;
    FaceSums::of(mesh, params, |_, _| {}).bound(mesh, params)
}

/// The tile's density is not known before it is built, only bounded;
/// sizing with the bound keeps `max_roots` cheap and still an upper bound.
fn tile_density_lower_bound() -> f32 {
    0.5
}

fn first_radius(scaled_area: f64, target: u32, density: f32) -> Option<f32> {
    if target == 0 || scaled_area.is_nan() || scaled_area <= 0.0 {
        return None;
    }
    Some(libm::sqrt(density as f64 * scaled_area / target as f64) as f32)
}

/// Arena bytes [`stamp`] needs for `mesh` and `params`.
pub fn required_bytes(mesh: &Mesh, params: &StampParams) -> Result<usize, Error> {
    let bound = candidates_bound(mesh, params)?;
    Ok(bytes_for(mesh, bound))
}

fn bytes_for(mesh: &Mesh, bound: usize) -> usize {
    let mut layout = ArenaLayout::new();
    Stamper::layout(&mut layout, mesh);
    select_layout(&mut layout, bound);
    layout.add::<Candidate>(bound);
    layout.bytes()
}

fn select_layout(layout: &mut ArenaLayout, candidates: usize) {
    layout
        .add::<u32>(HashGrid::buckets_for(candidates))
        .add::<u32>(candidates)
        .add::<u8>(candidates)
        .add::<Near>(candidates)
        .add::<u32>(RANK_KEYS)
        .add::<f32>(4 * GATHER_SLOTS)
        .add::<u32>(GATHER_SLOTS);
}

/// Tile points a face collects before they become candidates: the inside
/// test runs on every tile point the face covers, the rest only on the
/// points inside, a batch at a time, as vector code.
const BATCH: usize = 128;

/// Tile points found inside one face, waiting to become candidates.
struct Batch {
    x: [f32; BATCH],
    y: [f32; BATCH],
    level: [u8; BATCH],
    len: usize,
}

impl Default for Batch {
    fn default() -> Self {
        Batch {
            x: [0.0; BATCH],
            y: [0.0; BATCH],
            level: [0; BATCH],
            len: 0,
        }
    }
}

/// One face at one radius, in tile units: what placing its tile points needs.
struct Placing {
    corners: [Vec2; 3],
    /// `[x, y, c]`: twice the signed area a point `p` makes with edge `e`
    /// is `x[e] * p.y - y[e] * p.x - c[e]`, the edge taken from its
    /// lower-numbered vertex and negated (exactly) when the face runs it the
    /// other way. The two faces on a linked edge compute the same area bit
    /// for bit, so a tile point on it goes to exactly one. Lanes are edges,
    /// so a point's three tests run as one vector operation; the fourth
    /// lane always passes.
    cross: [Vec4; 3],
    /// Whether the face takes the points exactly on edge `e` (when it runs
    /// the edge from its lower vertex); the fourth lane is unused.
    ties: BVec4A,
    inv_len: [f32; 3],
    inv_det: f32,
    /// Whether edge `e` is linked (not cut).
    linked: [bool; 3],
    /// The far edges of each linked neighbour (from either end of the
    /// shared edge to its third corner): start, unit direction, length.
    far_from: [Vec2; 6],
    far_dir: [Vec2; 6],
    far_len: [f32; 6],
}

impl Placing {
    fn new(face: &TilePlace, k: f32) -> Self {
        let offset = Vec2::from(face.offset);
        let at = |p: [f32; 2]| offset + Vec2::from(p) * k;
        let corners = face.corners.map(at);
        let mut place = Placing {
            corners,
            cross: [Vec4::ZERO; 3],
            ties: BVec4A::FALSE,
            inv_len: [0.0; 3],
            inv_det: 1.0 / (corners[1] - corners[0]).perp_dot(corners[2] - corners[0]),
            linked: [false; 3],
            far_from: [Vec2::ZERO; 6],
            far_dir: [Vec2::ZERO; 6],
            far_len: [0.0; 6],
        };
        // built as arrays (writing a vector's lanes one by one is slower);
        // the fourth lane's area is 1, so it always passes
        let (mut cross, mut ties) = ([[0.0; 4], [0.0; 4], [0.0, 0.0, 0.0, -1.0]], [false; 3]);
        for i in 0..3 {
            let (p, q) = (corners[i], corners[(i + 1) % 3]);
            let forward = face.edges & (64 << i) != 0;
            let (from, to) = if forward { (p, q) } else { (q, p) };
            let (dir, sign) = (to - from, if forward { 1.0 } else { -1.0 });
            cross[0][i] = sign * dir.x;
            cross[1][i] = sign * dir.y;
            cross[2][i] = sign * dir.perp_dot(from);
            ties[i] = forward;
            place.inv_len[i] = 1.0 / (q - p).length();
            if face.edges & (1 << i) != 0 {
                place.linked[i] = true;
                let w = at(face.across[i]);
                for (s, end) in [(2 * i, p), (2 * i + 1, q)] {
                    let d = w - end;
                    place.far_from[s] = end;
                    place.far_len[s] = d.length();
                    place.far_dir[s] = d / place.far_len[s];
                }
            }
        }
        place.cross = cross.map(Vec4::from_array);
        place.ties = BVec4A::new(ties[0], ties[1], ties[2], false);
        place
    }

    /// [`cross`](Self::cross) as arrays, for code that reads it by edge
    /// (a vector read by a varying lane is slower).
    #[inline]
    fn cross_by_edge(&self) -> [[f32; 4]; 3] {
        self.cross.map(<[f32; 4]>::from)
    }

    /// Adds tile point `p` to `batch` when it lies inside the face (the
    /// slot is written either way: a branch would mispredict about every
    /// other point). `batch` must have room.
    #[inline]
    fn test(&self, batch: &mut Batch, p: Vec2, level: u8) {
        let [cx, cy, cc] = self.cross;
        // the same operations in the same order as `emit`'s barycentrics,
        // so the same bits
        let s = cx * Vec4::splat(p.y) - cy * Vec4::splat(p.x) - cc;
        let inside = (s.cmpgt(Vec4::ZERO) | (s.cmpeq(Vec4::ZERO) & self.ties)).all();
        // the caller keeps len below BATCH; the mask spares the bounds checks
        let i = batch.len & (BATCH - 1);
        (batch.x[i], batch.y[i], batch.level[i]) = (p.x, p.y, level);
        batch.len += inside as usize;
    }

    /// Writes the points of `batch` to `out` from slot `n` as candidates of
    /// face `f` and empties the batch; returns the new count.
    fn emit(
        &self,
        batch: &mut Batch,
        f: u32,
        squares: &[f32; LOD_LEVELS],
        out: &mut [Candidate],
        n: usize,
    ) -> Result<usize, Error> {
        let len = batch.len;
        batch.len = 0;
        let available = out.len();
        let out = out.get_mut(n..n + len).ok_or(Error::CapacityExceeded {
            needed: n + len,
            available,
        })?;
        let mut near = [0u16; BATCH];
        let lanes = len.div_ceil(LANES) * LANES;
        self.near_levels(&batch.x[..lanes], &batch.y[..lanes], squares, &mut near);
        let [cx, cy, cc] = self.cross_by_edge();
        for (i, c) in out.iter_mut().enumerate() {
            let (x, y) = (batch.x[i], batch.y[i]);
            // twice the signed area with edge e
            let area = |e: usize| cx[e] * y - cy[e] * x - cc[e];
            let (u, v) = (area(2) * self.inv_det, area(0) * self.inv_det);
            // a point inside by the edge tests can still round a hair
            // outside in barycentrics; u + v then sums to at most 1 in f32
            let u = u.clamp(0.0, 1.0);
            let v = v.clamp(0.0, 1.0 - u);
            *c = Candidate {
                face: f,
                uv: [u, v],
                level: batch.level[i] as u16,
                near_levels: near[i],
            };
        }
        Ok(n + len)
    }

    /// [`Candidate::near_levels`] of tile points `(xs, ys)` (whole lanes),
    /// from the smallest disk around each that crosses a cut edge, or the
    /// far side of a linked neighbour (up to there, every point comes from
    /// one piece of the stamp), and the squared spacings of the levels.
    fn near_levels(&self, xs: &[f32], ys: &[f32], squares: &[f32; LOD_LEVELS], out: &mut [u16]) {
        let [cross_x, cross_y, cross_c] = self.cross_by_edge();
        let lanes = xs.chunks_exact(LANES).zip(ys.chunks_exact(LANES));
        for ((x, y), d) in lanes.zip(out.chunks_exact_mut(LANES)) {
            let mut best = [f32::INFINITY; LANES];
            for e in 0..3 {
                let (cx, cy, cc) = (cross_x[e], cross_y[e], cross_c[e]);
                let inv_len = self.inv_len[e];
                let mut term = [0.0; LANES];
                for l in 0..LANES {
                    let line = (cx * y[l] - cy * x[l] - cc) * inv_len;
                    term[l] = line * line;
                }
                // past a linked edge, the disk must also reach the far side
                // of the neighbour (a cut edge needs no more: one branch per
                // edge, the same for every point of the face)
                if self.linked[e] {
                    let mut far = [f32::INFINITY; LANES];
                    for s in [2 * e, 2 * e + 1] {
                        let (fx, fy) = (self.far_from[s].x, self.far_from[s].y);
                        let (ux, uy, len) = (self.far_dir[s].x, self.far_dir[s].y, self.far_len[s]);
                        for l in 0..LANES {
                            let (dx, dy) = (x[l] - fx, y[l] - fy);
                            let t = dx * ux + dy * uy;
                            let c = if t < 0.0 { 0.0 } else { t };
                            let c = if c > len { len } else { c };
                            let d2 = dx * dx + dy * dy - c * (2.0 * t - c);
                            far[l] = if d2 < far[l] { d2 } else { far[l] };
                        }
                    }
                    for l in 0..LANES {
                        term[l] = if far[l] > term[l] { far[l] } else { term[l] };
                    }
                }
                for l in 0..LANES {
                    best[l] = if term[l] < best[l] { term[l] } else { best[l] };
                }
            }
            let mut near = [0u16; LANES];
            for &s2 in squares {
                for l in 0..LANES {
                    near[l] += (best[l] < s2) as u16;
                }
            }
            d.copy_from_slice(&near);
        }
    }
}

/// Edge-pass mark of a candidate found too close to a point of another face.
const CLASHED: u8 = u8::MAX;
/// Points of other faces one group of tests holds at once; a face with more
/// neighbours is tested in chunks (unit tests use a tiny buffer so that every
/// stamp they run takes that path).
#[cfg(not(test))]
const GATHER: usize = 1024;
#[cfg(test)]
const GATHER: usize = 7;

/// A candidate near its triangle's boundary, copied out of the candidate
/// list so the edge and LOD passes walk small records, one face at a time.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct Near {
    position: [f32; 3],
    face: u32,
    /// [`Candidate::near_levels`].
    near_levels: u32,
    /// Index in the candidate list.
    index: u32,
}

impl Near {
    /// The position, and the face's bits in the fourth lane, in one load.
    #[inline]
    fn head(&self) -> Vec4 {
        let bytes = &bytemuck::bytes_of(self)[..16];
        Vec4::from_array(bytemuck::pod_read_unaligned(bytes))
    }

    /// The record of candidate `c`, at `index`, on a face of frame `frame`
    /// (see [`face_frame`]).
    fn new(c: &Candidate, index: usize, [a, e1, e2]: &[Vec3; 3]) -> Self {
        Near {
            position: (*a + *e1 * c.uv[0] + *e2 * c.uv[1]).into(),
            face: c.face,
            near_levels: c.near_levels as u32,
            index: index as u32,
        }
    }
}

/// The points of other faces one face's points are tested against, with
/// each one's squared clash distance (edge pass) or weight (LOD pass), as
/// flat arrays so the tests run as a vector loop over contiguous memory.
struct Gathered<'a> {
    x: &'a mut [f32],
    y: &'a mut [f32],
    z: &'a mut [f32],
    r2: &'a mut [f32],
    face: &'a mut [u32],
    len: usize,
}

/// Lanes of the clash test; the gathered arrays are padded to a multiple.
const LANES: usize = 8;
/// Slots of each gathered array: [`GATHER`] rounded up to whole lanes.
const GATHER_SLOTS: usize = GATHER.div_ceil(LANES) * LANES;

impl<'a> Gathered<'a> {
    fn new(arena: &mut Arena<'a>) -> Result<Self, Error> {
        let all = arena.alloc::<f32>(4 * GATHER_SLOTS)?;
        let (x, rest) = all.split_at_mut(GATHER_SLOTS);
        let (y, rest) = rest.split_at_mut(GATHER_SLOTS);
        let (z, r2) = rest.split_at_mut(GATHER_SLOTS);
        Ok(Gathered {
            x,
            y,
            z,
            r2,
            face: arena.alloc::<u32>(GATHER_SLOTS)?,
            len: 0,
        })
    }

    /// Writes a point of face `face` in the slot after the last (not full),
    /// without taking it: the caller advances `len` to keep it.
    #[inline]
    fn set(&mut self, p: [f32; 3], face: u32) {
        let i = self.len;
        (self.x[i], self.y[i], self.z[i], self.face[i]) = (p[0], p[1], p[2], face);
    }

    /// Moves gathered point `i` out of reach of every point.
    #[inline]
    fn remove(&mut self, i: usize) {
        self.x[i] = f32::INFINITY;
    }

    /// Fills the slots past `len` up to whole lanes with points out of
    /// reach (at infinity, with a clash distance and a weight of 1), so the
    /// tests run on whole lanes only.
    #[inline]
    fn pad(&mut self) {
        let (len, end) = (self.len, self.len.div_ceil(LANES) * LANES);
        for a in [&mut *self.x, &mut *self.y, &mut *self.z] {
            a[len..end].fill(f32::INFINITY);
        }
        self.r2[len..end].fill(1.0);
    }

    /// The gathered coordinates and values, in whole lanes (after
    /// [`pad`](Self::pad)).
    #[inline]
    fn lanes(&self) -> impl Iterator<Item = (&[f32], &[f32], &[f32], &[f32])> {
        let n = self.len.div_ceil(LANES) * LANES;
        let (xs, ys, zs, rs) = (&self.x[..n], &self.y[..n], &self.z[..n], &self.r2[..n]);
        xs.chunks_exact(LANES)
            .zip(ys.chunks_exact(LANES))
            .zip(zs.chunks_exact(LANES).zip(rs.chunks_exact(LANES)))
            .map(|((x, y), (z, r))| (x, y, z, r))
    }

    /// Whether `p` is closer to a gathered point than its clash distance.
    #[inline]
    fn clashes(&self, p: [f32; 3]) -> bool {
        // no early exit inside a chunk, so each chunk runs as vector code
        self.lanes().any(|(x, y, z, r)| {
            let mut hit = 0u32;
            for l in 0..LANES {
                let (dx, dy, dz) = (x[l] - p[0], y[l] - p[1], z[l] - p[2]);
                hit |= ((dx * dx + dy * dy + dz * dz) < r[l]) as u32;
            }
            hit != 0
        })
    }

    /// The smallest squared distance from `p` to a gathered point, times
    /// that point's weight (infinite when none is in reach).
    #[inline]
    fn nearest(&self, p: [f32; 3]) -> f32 {
        let mut best = [f32::INFINITY; LANES];
        for (x, y, z, w) in self.lanes() {
            for l in 0..LANES {
                let (dx, dy, dz) = (x[l] - p[0], y[l] - p[1], z[l] - p[2]);
                let d = (dx * dx + dy * dy + dz * dz) * w[l];
                // a select, not f32::min: it maps to one vector instruction
                best[l] = if d < best[l] { d } else { best[l] };
            }
        }
        best.into_iter().fold(f32::INFINITY, f32::min)
    }
}

/// Bits of the hash that orders the candidates within one LOD level (ties
/// keep candidate order).
const RANK_HASH_BITS: u32 = 12;
/// Counters of the rank sort: one per (level, hash) key.
const RANK_KEYS: usize = LOD_LEVELS << RANK_HASH_BITS;

/// Working memory of the edge pass and the LOD pass, sized for a candidate
/// bound once and reused by every pass.
pub struct Scratch<'a> {
    /// Bucket heads of the grid.
    heads: &'a mut [u32],
    /// Grid links; in the LOD pass first the candidates that take part, in
    /// the end the rank keys.
    next: &'a mut [u32],
    /// Edge-pass mark or LOD level of each candidate.
    level: &'a mut [u8],
    /// The points of the grid: those the edge pass keeps, in order; in the
    /// LOD pass, the candidates near a boundary, grouped by tile level.
    near: &'a mut [Near],
    /// Counters of the rank sort.
    counts: &'a mut [u32],
    gathered: Gathered<'a>,
}

impl<'a> Scratch<'a> {
    /// Takes scratch for up to `candidates` candidates from `arena`.
    pub fn new(arena: &mut Arena<'a>, candidates: usize) -> Result<Self, Error> {
        Ok(Scratch {
            heads: arena.alloc::<u32>(HashGrid::buckets_for(candidates))?,
            next: arena.alloc::<u32>(candidates)?,
            level: arena.alloc::<u8>(candidates)?,
            near: arena.alloc::<Near>(candidates)?,
            counts: arena.alloc::<u32>(RANK_KEYS)?,
            gathered: Gathered::new(arena)?,
        })
    }

    fn check(&self, n: usize) -> Result<(), Error> {
        if n > self.next.len() {
            return Err(Error::CapacityExceeded {
                needed: n,
                available: self.next.len(),
            });
        }
        Ok(())
    }
}

impl<'m, 'a> Stamper<'m, 'a> {
    /// Adds the bytes [`Stamper::new`] takes from the arena.
    pub fn layout(layout: &mut ArenaLayout, mesh: &Mesh) {
        Tile::layout(layout);
        layout
            .add::<Face>(mesh.triangle_count())
            .add::<TilePlace>(mesh.triangle_count())
            .add::<Unfolded>(mesh.triangle_count());
        chart::layout(layout, mesh);
    }

    /// Validates the inputs, builds the tile and the per-face data, and picks
    /// the first radius. Returns `Ok(None)` when there is nothing to stamp
    /// (target 0, or every face bald or degenerate).
    pub fn new(
        mesh: Mesh<'m>,
        params: &StampParams,
        arena: &mut Arena<'a>,
    ) -> Result<Option<Self>, Error> {
        validate(&mesh, params)?;
        Ok(Self::build(mesh, params, arena)?.0)
    }

    /// [`Stamper::new`] on inputs already validated, with the face sums.
    fn build(
        mesh: Mesh<'m>,
        params: &StampParams,
        arena: &mut Arena<'a>,
    ) -> Result<(Option<Self>, FaceSums), Error> {
        let tile = Tile::build(params.seed, arena)?;
        let faces = arena.alloc::<Face>(mesh.triangle_count())?;
        let places = arena.alloc::<TilePlace>(mesh.triangle_count())?;
        let laid = arena.alloc::<Unfolded>(mesh.triangle_count())?;
        let sums = FaceSums::of(&mesh, params, |f, face| faces[f] = face);
        let area = sums.area;
        let fixed = params.radius > 0.0;
        let radius = if fixed {
            params.radius
        } else {
            match first_radius(area, params.target_count, tile.density()) {
                Some(r) => r,
                None => return Ok((None, sums)),
            }
        };
        let (scale, normal) = (|f: usize| faces[f].scale, |f: usize| faces[f].normal.into());
        chart::unfold(&mesh, scale, normal, CHART_REACH * radius, arena, laid)?;
        // a chart's first face comes before its others: its frame is made
        // once, kept in its slot, and read by the others
        for f in 0..faces.len() {
            places[f] = if faces[f].scale == 0.0 {
                TilePlace::default()
            } else {
                let chart = laid[f].chart as usize;
                let frame = if chart == f {
                    ChartFrame::new(params.seed, chart)
                } else {
                    places[chart].frame()
                };
                TilePlace::new(&mesh, f, &laid[f], frame)
            };
        }
        let mut stamper = Stamper {
            mesh,
            seed: params.seed,
            target: params.target_count,
            tile,
            faces,
            places,
            scaled_area: area,
            first_radius: radius,
            fixed,
            radius,
            previous: None,
            passes: 0,
            degenerate: sums.degenerate,
            spacings: lod_spacings(),
        };
        if !fixed {
            stamper.radius = stamper.predicted_radius();
        }
        Ok((Some(stamper), sums))
    }

    /// Expected number of points the edge pass removes at radius `r`: each
    /// face's half of an edge of length `l` (scaled by density, `x = l / 2r`)
    /// loses `EDGE_LOSS * x^2 / (x + EDGE_LOSS_KNEE)` points. Long edges lose
    /// a fixed number per radius of length; short ones less, as their faces
    /// hold fewer points.
    fn predicted_loss(&self, r: f32) -> f64 {
        let k = 0.5 / r;
        let mut loss = 0.0f32;
        // branch-free: a linked edge (both sides are one piece of the stamp)
        // and an unstamped face's edges (zero length) add exactly 0
        for place in self.places {
            for i in 0..3 {
                let x = place.edge(i).length() * k;
                let cut = place.edges & (1 << i) == 0;
                loss += if cut {
                    x * x / (x + EDGE_LOSS_KNEE)
                } else {
                    0.0
                };
            }
        }
        EDGE_LOSS as f64 * loss as f64
    }

    /// The radius whose stamp is expected to keep the middle of the count
    /// band after the edge pass, so that most stamps need one pass: the
    /// fixed point of `r = sqrt(rho * area / (aim + loss(r)))`, which
    /// converges fast as the loss moves slowly with `r`.
    fn predicted_radius(&self) -> f32 {
        let aim = self.target as f64 * (1.0 + 0.5 * COUNT_TOLERANCE as f64);
        let stamped = self.first_radius as f64 * self.first_radius as f64 * self.target as f64;
        let floor = self.first_radius * min_radius_factor(self.target, self.mesh.triangle_count());
        let mut r = self.first_radius;
        for _ in 0..PREDICTION_STEPS {
            r = (libm::sqrt(stamped / (aim + self.predicted_loss(r))) as f32).max(floor);
        }
        r
    }

    /// Current disk radius.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Sum of triangle areas weighted by squared density scale.
    pub fn scaled_area(&self) -> f64 {
        self.scaled_area
    }

    /// Upper bound on the candidates [`stamp_faces`](Self::stamp_faces) writes
    /// for `faces`, valid for every radius the correction can reach.
    pub fn candidate_bound(&self, faces: Range<usize>) -> usize {
        let r_min = if self.fixed {
            self.radius
        } else {
            self.first_radius * min_radius_factor(self.target, self.mesh.triangle_count())
        };
        faces
            .map(|f| face_bound(&self.mesh, f, self.faces[f].scale, r_min))
            .sum()
    }

    /// Stamps the triangles in `faces` at the current radius into `out`, in
    /// face order; returns how many were written. Slots past that count may
    /// be overwritten too. Pure: safe to run disjoint ranges on different
    /// threads.
    pub fn stamp_faces(&self, faces: Range<usize>, out: &mut [Candidate]) -> Result<usize, Error> {
        let squares = self.spacings.map(|s| s * s);
        // made once: clearing a batch per face costs more than its tests
        let mut batch = Batch::default();
        let mut n = 0;
        for f in faces {
            if self.faces[f].scale == 0.0 {
                continue;
            }
            n = self.stamp_face(f, &squares, &mut batch, out, n)?;
        }
        Ok(n)
    }

    /// Stamps triangle `f` into `out` from slot `n` (`squares`: the squared
    /// LOD spacings; `batch`: empty, and left empty); returns the new count.
    fn stamp_face(
        &self,
        f: usize,
        squares: &[f32; LOD_LEVELS],
        batch: &mut Batch,
        out: &mut [Candidate],
        mut n: usize,
    ) -> Result<usize, Error> {
        let place = Placing::new(&self.places[f], 1.0 / self.radius);
        let corners = place.corners;
        let lo_y = corners[0].y.min(corners[1].y).min(corners[2].y);
        let hi_y = corners[0].y.max(corners[1].y).max(corners[2].y);
        let (side, cell) = (CELLS as i32, CELL as f32);
        let inv = 1.0 / cell;
        for cy in floor_i32(lo_y * inv)..=floor_i32(hi_y * inv) {
            let wy = cy.rem_euclid(side);
            let shift_y = (cy - wy) as f32 * cell;
            // only the cells the triangle crosses in this row, not its bounding box
            let y0 = cy as f32 * cell;
            let Some((x0, x1)) = row_span(&corners, y0, y0 + cell) else {
                continue;
            };
            let (mut cx, last) = (floor_i32(x0 * inv), floor_i32(x1 * inv));
            while cx <= last {
                // the cells up to the tile's edge are one run of points
                let wx = cx.rem_euclid(side);
                let len = (side - wx).min(last - cx + 1);
                let shift = Vec2::new((cx - wx) as f32 * cell, shift_y);
                let (points, levels) = self.tile.run(wx as usize, wy as usize, len as usize);
                for (&p, &level) in points.iter().zip(levels) {
                    if batch.len == BATCH {
                        n = place.emit(batch, f as u32, squares, out, n)?;
                    }
                    place.test(batch, Vec2::from(p) + shift, level);
                }
                cx += len;
            }
        }
        place.emit(batch, f as u32, squares, out, n)
    }

    /// Gathers into `buf` the points of `grid` (indices into `records`) that
    /// lie in the box around `group` (points of one face) widened by
    /// `reach` and belong to another face, and calls `test` each time `buf`
    /// is full and once at the end if it holds any.
    ///
    /// The grid is walked once for the whole group, where a walk per point
    /// would visit the same buckets again and again; `test` then runs the
    /// group against the gathered points in a vector loop.
    fn gather(
        grid: &HashGrid,
        records: &[Near],
        group: &[Near],
        reach: f32,
        buf: &mut Gathered,
        mut test: impl FnMut(&mut Gathered),
    ) {
        let at = |q: &Near| Vec3::from(q.position);
        let (lo, hi) = group
            .iter()
            .fold((at(&group[0]), at(&group[0])), |(lo, hi), q| {
                (lo.min(at(q)), hi.max(at(q)))
            });
        let (lo, hi) = (lo - Vec3::splat(reach), hi + Vec3::splat(reach));
        // the box test reads a record's position and face as one vector and
        // looks at the first three lanes
        let (lo4, hi4) = (lo.extend(0.0), hi.extend(0.0));
        let f = group[0].face;
        buf.len = 0;
        for i in grid.in_box(lo, hi) {
            if buf.len == GATHER {
                test(buf);
                buf.len = 0;
            }
            let o = &records[i as usize];
            let p = o.head();
            // every point is written and only those of other faces in the box
            // kept: branches on these tests would mispredict
            let inside = (p.cmpge(lo4) & p.cmple(hi4)).bitmask() & 7 == 7;
            let keep = (o.face != f) & inside;
            buf.set(o.position, o.face);
            buf.len += keep as usize;
        }
        if buf.len > 0 {
            test(buf);
        }
    }

    /// Sets the value of each gathered point to `value` of the larger
    /// density scale of its face and face `f`, removes the points of faces
    /// whose normal opposes `f`'s (the two sides of an ear never clash),
    /// and pads the lanes.
    fn weigh(&self, buf: &mut Gathered, f: u32, value: impl Fn(f32) -> f32) {
        let face = &self.faces[f as usize];
        let normal = Vec3::from(face.normal);
        // gathered points come in runs of one face: its value is reused
        let (mut last, mut last_value, mut facing) = (u32::MAX, 0.0, true);
        for i in 0..buf.len {
            let o = buf.face[i];
            if o != last {
                let other = &self.faces[o as usize];
                facing = Vec3::from(other.normal).dot(normal) > 0.0;
                (last, last_value) = (o, value(other.scale.max(face.scale)));
            }
            buf.r2[i] = last_value;
            if !facing {
                buf.remove(i);
            }
        }
        buf.pad();
    }

    /// The local disk radius at face `f` (larger where the density is lower).
    #[inline]
    fn local_radius(&self, f: u32) -> f32 {
        self.radius / self.faces[f as usize].scale
    }

    /// The edge pass: keeps, in order, every candidate that is not closer
    /// than the disk radius to an earlier kept one, compacting them to the
    /// front of `cands`. Returns the number kept.
    ///
    /// Points of one triangle and of its linked neighbours are spaced by the
    /// tile, so only points [`Candidate::near_edge`] take part: this is
    /// exact (up to the bend of linked edges) on any surface whose dihedral
    /// angles at cut edges are above 90 degrees and whose separate
    /// same-facing sheets are a radius apart. A triangle's
    /// points are tested together, against the kept points of earlier
    /// triangles gathered once from the grid (see `gather`).
    pub fn prune(&self, cands: &mut [Candidate], scratch: &mut Scratch) -> Result<usize, Error> {
        let n = cands.len();
        scratch.check(n)?;
        let status = &mut scratch.level[..n];
        status.fill(0);
        let mut grid = HashGrid::new(scratch.heads, scratch.next, GRID_CELL * self.radius);
        let near = &mut *scratch.near;
        let (mut j, mut inserted, mut kept) = (0, 0, 0);
        while j < n {
            let f = cands[j].face;
            let end = cands[j..]
                .iter()
                .position(|c| c.face != f)
                .map_or(n, |e| j + e);
            // the face's records go after the inserted ones, where those it
            // keeps stay
            let (records, rest) = near.split_at_mut(inserted);
            let mut m = 0;
            let frame = face_frame(&self.mesh, f as usize);
            // every candidate is written and only those near an edge kept:
            // a branch on that would mispredict (about one in four is)
            for (i, c) in (j..end).zip(&cands[j..end]) {
                rest[m] = Near::new(c, i, &frame);
                m += c.near_edge() as usize;
            }
            if m > 0 {
                let group = &rest[..m];
                let reach = self.local_radius(f) * 1.0001;
                let buf = &mut scratch.gathered;
                Self::gather(&grid, records, group, reach, buf, |buf| {
                    self.weigh(buf, f, |scale| {
                        let r = self.radius / scale;
                        r * r
                    });
                    for q in group {
                        let s = &mut status[q.index as usize];
                        if *s != CLASHED && buf.clashes(q.position) {
                            *s = CLASHED;
                        }
                    }
                });
                let first = inserted;
                for g in first..first + m {
                    let q = near[g];
                    if status[q.index as usize] != CLASHED {
                        near[inserted] = q;
                        grid.insert(inserted as u32, Vec3::from(q.position));
                        inserted += 1;
                    }
                }
            }
            // later faces leave this face's marks alone: it is compacted now,
            // while its candidates are still in cache
            for i in j..end {
                let c = cands[i];
                cands[kept] = c;
                kept += (status[i] != CLASHED) as usize;
            }
            j = end;
        }
        Ok(kept)
    }

    /// Feeds back the count of the last pass. Returns true when it is close
    /// enough to the target; otherwise adjusts the radius for another pass.
    pub fn converged(&mut self, candidates: usize, kept: usize) -> bool {
        self.passes += 1;
        if self.fixed {
            return true;
        }
        let target = self.target as f32;
        let excess = (kept as f32 - target) / target;
        if (0.0..=COUNT_TOLERANCE).contains(&excess) || kept == 0 || self.passes >= MAX_PASSES {
            return true;
        }
        let aim = target as f64 * (1.0 + 0.5 * COUNT_TOLERANCE as f64);
        let r1 = self.radius as f64;
        let corrected = if self.passes < SECANT_PASSES {
            match self.previous {
                // a secant in log-log space through the last two passes
                Some((r0, k0)) if r0 != self.radius && k0 != kept && k0 > 0 => {
                    let slope = libm::log(kept as f64 / k0 as f64) / libm::log(r1 / r0 as f64);
                    (r1 * libm::pow(aim / kept as f64, 1.0 / slope)) as f32
                }
                // Stamped points scale like 1/r^2 and the edge pass removes a
                // share proportional to r (boundary length over area), so
                // kept(r) = c / r^2 * (1 - f * r / r1) with c and f measured
                // at the current radius r1. Aim inside the band [target,
                // target * (1 + tolerance)]; `finish` trims the surplus.
                _ => {
                    let c = candidates as f64 * r1 * r1;
                    let f = 1.0 - kept as f64 / candidates.max(1) as f64;
                    let b = c * f / r1;
                    ((-b + libm::sqrt(b * b + 4.0 * aim * c)) / (2.0 * aim)) as f32
                }
            }
        } else if excess > 0.0 {
            // small counts move in steps: accept any surplus, trim it
            return true;
        } else {
            self.radius * 0.97
        };
        let floor = self.first_radius * min_radius_factor(self.target, self.mesh.triangle_count());
        let clamped = corrected.max(floor);
        self.previous = Some((self.radius, kept));
        if clamped == self.radius {
            return true;
        }
        self.radius = clamped;
        false
    }

    /// Roots [`finish`](Self::finish) writes for `kept` candidates: the
    /// target, or all of them when the stamp fell short.
    pub fn output_count(&self, kept: usize) -> usize {
        if self.fixed {
            return kept;
        }
        kept.min(self.target as usize)
    }

    /// Assigns LOD levels across triangles, ranks the candidates, and writes
    /// the [`output_count`](Self::output_count) lowest-ranked ones (any rank
    /// prefix is evenly spread, so the trim keeps the Poisson property) in
    /// candidate order, with ids `0..n`.
    pub fn finish(
        &self,
        cands: &[Candidate],
        scratch: &mut Scratch,
        out: &mut [Root],
    ) -> Result<(), Error> {
        self.finish_reporting(cands, scratch, out, &mut |_| Ok(()))
    }

    /// [`finish`](Self::finish), calling `done` with the share of the work
    /// done after each LOD level and once more before `out` is written; an
    /// error from `done` ends the call there.
    fn finish_reporting(
        &self,
        cands: &[Candidate],
        scratch: &mut Scratch,
        out: &mut [Root],
        done: &mut dyn FnMut(f32) -> Result<(), Error>,
    ) -> Result<(), Error> {
        let n = cands.len();
        let m = self.output_count(n);
        if out.len() < m {
            return Err(Error::OutputTooSmall {
                needed: m,
                available: out.len(),
            });
        }
        scratch.check(n)?;
        self.assign_levels(cands, scratch, done)?;
        // a stable counting sort by (level, hash): the slot a candidate
        // takes in it is its rank
        let keys = &mut scratch.next[..n];
        let counts = &mut *scratch.counts;
        counts.fill(0);
        for (j, (key, &l)) in keys.iter_mut().zip(&scratch.level[..n]).enumerate() {
            let h = rng::hash(self.seed, j as u64, Purpose::LodOrder, 0) >> (64 - RANK_HASH_BITS);
            *key = ((l as u32) << RANK_HASH_BITS) | h as u32;
            counts[*key as usize] += 1;
        }
        let mut first = 0;
        for c in counts.iter_mut() {
            (*c, first) = (first, first + *c);
        }
        done(1.0)?;
        // the slot a candidate takes is its rank; they are handed out in
        // candidate order, which is also the output's
        let mut id = 0;
        for (c, &key) in cands.iter().zip(&*keys) {
            let next = &mut counts[key as usize];
            let rank = *next;
            *next += 1;
            if (rank as usize) < m {
                out[id] = Root {
                    face: c.face,
                    u: c.uv[0],
                    v: c.uv[1],
                    id: id as u32,
                    rank,
                };
                id += 1;
            }
        }
        Ok(())
    }

    /// Nested LOD levels across triangles. A point `q` of tile level `t(q)`
    /// takes the finest of `t(q)` and, for every point `p` of another
    /// triangle that comes before it (a coarser tile level, or the same one
    /// on an earlier triangle) and lies closer than the spacing of `t(q)`,
    /// the first level whose spacing their distance respects.
    ///
    /// Every pair then respects the spacing of every level both are in:
    /// only the later point of a pair needs to move, and only when it is
    /// closer than its own level's spacing, since the earlier point's tile
    /// level is coarser still. The rule reads tile levels only, so each
    /// level is one query per point, in any order, with no re-checking as
    /// levels change.
    ///
    /// A candidate whose [`Candidate::near_levels`] stop before its tile
    /// level conflicts with no other triangle at that level or any
    /// finer one, so it keeps its tile level; the others are copied to
    /// [`Near`] records grouped by tile level. Level `k` puts the records of
    /// coarser levels within its spacing of a boundary into a grid, then
    /// tests its own records against it one triangle at a time, adding each
    /// triangle's records after its test.
    fn assign_levels(
        &self,
        cands: &[Candidate],
        scratch: &mut Scratch,
        done: &mut dyn FnMut(f32) -> Result<(), Error>,
    ) -> Result<(), Error> {
        let n = cands.len();
        let finest = LOD_LEVELS - 1;
        let squares = self.spacings.map(|s| s * s);
        let level = &mut scratch.level[..n];
        let takes_part = |c: &Candidate| c.level < c.near_levels && (c.level as usize) < finest;
        let taking = &mut *scratch.next;
        let mut start = [0usize; LOD_LEVELS + 1];
        let mut m = 0;
        for (j, (c, l)) in cands.iter().zip(level.iter_mut()).enumerate() {
            *l = c.level as u8;
            // branch-free: which candidates take part is close to random
            let takes = takes_part(c) as usize;
            start[c.level as usize + 1] += takes;
            taking[m] = j as u32;
            m += takes;
        }
        for l in 0..LOD_LEVELS {
            start[l + 1] += start[l];
        }
        let mut fill = start;
        let mut frame = (u32::MAX, [Vec3::ZERO; 3]);
        for &j in &taking[..m] {
            let c = &cands[j as usize];
            if c.face != frame.0 {
                frame = (c.face, face_frame(&self.mesh, c.face as usize));
            }
            scratch.near[fill[c.level as usize]] = Near::new(c, j as usize, &frame.1);
            fill[c.level as usize] += 1;
        }
        let near = &scratch.near[..m];
        let mut grid = HashGrid::new(scratch.heads, scratch.next, self.radius);
        for k in 0..finest {
            let s = self.spacings[k];
            let (coarser, end) = (start[k], start[k + 1]);
            grid.reset(GRID_CELL * self.radius * s, end);
            // coarser levels block every other triangle; this level's
            // records block the triangles after their own, so go in after it
            for (i, q) in near[..coarser].iter().enumerate() {
                grid.insert_if((k as u32) < q.near_levels, i as u32, q.position.into());
            }
            let mut first = coarser;
            for group in near[coarser..end].chunk_by(|a, b| a.face == b.face) {
                let f = group[0].face;
                let reach = self.local_radius(f) * s * 1.0001;
                let buf = &mut scratch.gathered;
                Self::gather(&grid, near, group, reach, buf, |buf| {
                    // squared distances in units of the pair's local radius
                    self.weigh(buf, f, |scale| {
                        let w = scale / self.radius;
                        w * w
                    });
                    for q in group {
                        let d = buf.nearest(q.position);
                        let l = &mut level[q.index as usize];
                        while (*l as usize) < finest && d < squares[*l as usize] {
                            *l += 1;
                        }
                    }
                });
                for (i, q) in (first..).zip(group) {
                    grid.insert(i as u32, Vec3::from(q.position));
                }
                first += group.len();
            }
            done((k + 1) as f32 / LOD_LEVELS as f32)?;
        }
        Ok(())
    }

    fn report(&self, candidates: usize, kept: usize) -> StampReport {
        StampReport {
            radius: self.radius,
            candidates: candidates as u32,
            pruned: (candidates - kept) as u32,
            trimmed: (kept - self.output_count(kept)) as u32,
            degenerate_triangles: self.degenerate,
            passes: self.passes,
        }
    }
}

/// Stamps roots on `mesh` into `out` (capacity from [`max_roots`]) using an
/// arena of [`required_bytes`]. Returns the number of roots written and a report.
///
/// Nothing is written to `out` unless the call succeeds.
pub fn stamp(
    mesh: Mesh,
    params: &StampParams,
    arena: &mut Arena,
    out: &mut [Root],
) -> Result<(usize, StampReport), Error> {
    stamp_with_progress(mesh, params, arena, out, &mut |_| true)
}

/// Faces stamped between two progress reports.
const PROGRESS_FACES: usize = 8192;
/// Share of the progress the stamping passes take (the LOD levels and the
/// ranks take the rest): pass `i` ends at `PASSES_SHARE * (1 - 2^-(i+1))`,
/// as the number of passes is not known in advance.
const PASSES_SHARE: f32 = 0.6;

/// [`stamp`], calling `progress` with the share of the work done, in
/// `[0, 1]`, never decreasing, every few thousand triangles and after each
/// stage (the last call, with 1, comes before `out` is written). Returning
/// `false` cancels: the call returns [`Error::Cancelled`] having written
/// nothing to `out`. The calls do not change the result.
pub fn stamp_with_progress(
    mesh: Mesh,
    params: &StampParams,
    arena: &mut Arena,
    out: &mut [Root],
    progress: &mut dyn FnMut(f32) -> bool,
) -> Result<(usize, StampReport), Error> {
    let mut done = |fraction: f32| {
        if progress(fraction) {
            Ok(())
        } else {
            Err(Error::Cancelled)
        }
    };
    done(0.0)?;
    validate(&mesh, params)?;
    let available = arena.remaining();
    let too_small = |bound| Error::CapacityExceeded {
        needed: bytes_for(&mesh, bound),
        available,
    };
    // the faces are set up once, for the stamper and the bound (which holds
    // for every radius the stamper reaches); an arena too small for the
    // stamper itself is reported with the whole need
    let (stamper, sums) = match Stamper::build(mesh, params, arena) {
        Err(Error::CapacityExceeded { .. }) => {
            let sums = FaceSums::of(&mesh, params, |_, _| {});
            return Err(too_small(sums.bound(&mesh, params)?));
        }
        built => built?,
    };
    let bound = sums.bound(&mesh, params)?;
    if available < bytes_for(&mesh, bound) {
        return Err(too_small(bound));
    }
    let Some(mut stamper) = stamper else {
        done(1.0)?;
        let report = StampReport {
            degenerate_triangles: sums.degenerate,
            ..StampReport::default()
        };
        return Ok((0, report));
    };
    let faces = mesh.triangle_count();
    let mut scratch = Scratch::new(arena, bound)?;
    let cands = arena.alloc::<Candidate>(bound)?;
    let mut pass_start = 0.0;
    loop {
        let pass_end = PASSES_SHARE - 0.5 * (PASSES_SHARE - pass_start);
        let placed_end = pass_start + 0.4 * (pass_end - pass_start);
        let mut n = 0;
        for first in (0..faces).step_by(PROGRESS_FACES) {
            let last = (first + PROGRESS_FACES).min(faces);
            n += stamper.stamp_faces(first..last, &mut cands[n..])?;
            done(pass_start + (placed_end - pass_start) * last as f32 / faces as f32)?;
        }
        let kept = stamper.prune(&mut cands[..n], &mut scratch)?;
        done(pass_end)?;
        if stamper.converged(n, kept) {
            let m = stamper.output_count(kept);
            if out.len() < m {
                return Err(Error::OutputTooSmall {
                    needed: m,
                    available: out.len(),
                });
            }
            let mut finishing = |share: f32| done(pass_end + (1.0 - pass_end) * share);
            stamper.finish_reporting(
                &cands[..kept],
                &mut scratch,
                &mut out[..m],
                &mut finishing,
            )?;
            return Ok((m, stamper.report(n, kept)));
        }
        pass_start = pass_end;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testmesh::{graded_plane, seamed_sphere, sphere};
    use crate::Strided;

    pub(crate) fn run(mesh: Mesh, params: &StampParams) -> (Vec<Root>, StampReport) {
        let mut buf = vec![0u8; required_bytes(&mesh, params).unwrap()];
        let mut out = vec![Root::default(); max_roots(&mesh, params).unwrap()];
        let mut arena = Arena::new(&mut buf);
        let (n, report) = stamp(mesh, params, &mut arena, &mut out).unwrap();
        out.truncate(n);
        // in the triangle, in f32 as a host checks it
        for r in &out {
            assert!(r.u >= 0.0 && r.v >= 0.0 && r.u + r.v <= 1.0, "{r:?}");
        }
        (out, report)
    }

    /// Minimum 3D distance between same-side roots (normals not opposed).
    fn min_spacing(mesh: &Mesh, roots: &[Root]) -> f32 {
        let pts: Vec<(Vec3, Vec3)> = roots
            .iter()
            .map(|r| {
                (
                    mesh.point(r.face as usize, r.u, r.v),
                    mesh.face_normal(r.face as usize),
                )
            })
            .collect();
        let mut best = f32::INFINITY;
        for (i, a) in pts.iter().enumerate() {
            for b in &pts[i + 1..] {
                if a.1.dot(b.1) > 0.0 {
                    best = best.min(a.0.distance(b.0));
                }
            }
        }
        best
    }

    fn params(target: u32) -> StampParams<'static> {
        StampParams {
            target_count: target,
            seed: 11,
            ..StampParams::default()
        }
    }

    #[test]
    fn count_hits_target_on_uniform_and_graded_meshes() {
        for (name, m) in [
            ("sphere", sphere(24, 48)),
            ("graded 1e4", graded_plane(40, 100.0)),
            ("coarse plane", graded_plane(2, 1.0)),
            ("two triangles", graded_plane(1, 1.0)),
        ] {
            for target in [10u32, 30, 100, 500, 3000, 20000] {
                let (roots, report) = run(m.mesh(), &params(target));
                // the stamp lands in [target, target * 1.02] and the surplus
                // is trimmed by rank, so the count is exact
                assert_eq!(roots.len(), target as usize, "{name}: {report:?}");
            }
        }
    }

    /// Barycentrics from the signed areas can round a hair past an edge for
    /// a point the edge tests take; every root still lies in its triangle.
    /// The mesh is the C contract test's sphere (a duplicated seam column,
    /// pole rows of repeated points), where seed 42 once put a root a
    /// rounding error outside.
    #[test]
    fn roots_lie_in_their_triangle_on_a_seamed_sphere() {
        let m = seamed_sphere(24, 48);
        for seed in [42, 43] {
            // `run` checks every root
            run(
                m.mesh(),
                &StampParams {
                    seed,
                    ..params(3000)
                },
            );
        }
    }

    #[test]
    fn no_two_roots_closer_than_the_radius_and_lod_prefixes_spread() {
        let m = sphere(16, 32);
        let mesh = m.mesh();
        let (roots, report) = run(mesh, &params(4000));
        let min = min_spacing(&mesh, &roots);
        assert!(
            min >= report.radius * 0.999,
            "min {min} < r {}",
            report.radius
        );
        let n = roots.len();
        for frac in [2usize, 4, 16] {
            let prefix: Vec<Root> = roots
                .iter()
                .copied()
                .filter(|r| (r.rank as usize) < n / frac)
                .collect();
            let spacing = min_spacing(&mesh, &prefix);
            // a Poisson set of n/frac roots has spacing ~ r * sqrt(frac)
            let expect = report.radius * libm::sqrtf(frac as f32);
            assert!(spacing >= 0.5 * expect, "1/{frac}: {spacing} vs {expect}");
        }
        let mut ranks: Vec<u32> = roots.iter().map(|r| r.rank).collect();
        ranks.sort_unstable();
        assert!(ranks.iter().enumerate().all(|(i, &r)| r == i as u32));
        assert!(roots.iter().enumerate().all(|(i, r)| r.id == i as u32));
    }

    /// Every pair of kept points, on any two triangles, is at least the
    /// spacing of the finer of their two LOD levels apart (in units of the
    /// pair's clash distance, up to the bend of linked edges), on a curved
    /// mesh of many charts with two densities.
    #[test]
    fn each_lod_level_keeps_its_spacing_across_triangles() {
        let m = sphere(16, 32);
        let mesh = m.mesh();
        let values: Vec<f32> =
            m.p.iter()
                .map(|p| if p[1] < 0.0 { 0.4 } else { 1.0 })
                .collect();
        with_candidates(mesh, &graded(&values), |stamper, scratch, mut cands| {
            let kept = stamper.prune(&mut cands, scratch).unwrap();
            let cands = &cands[..kept];
            let mut out = vec![Root::default(); kept];
            stamper.finish(cands, scratch, &mut out).unwrap();
            check_lod_spacing(stamper, cands, &scratch.level[..kept]);
        });
    }

    fn check_lod_spacing(stamper: &Stamper, cands: &[Candidate], levels: &[u8]) {
        let mut raised = 0;
        for (c, &l) in cands.iter().zip(levels) {
            assert!(l as u16 >= c.level && (l as usize) < LOD_LEVELS);
            raised += (l as u16 > c.level) as usize;
        }
        assert!(raised > 0, "no level was raised: nothing to check");
        let at = |c: &Candidate| position(&stamper.mesh, c);
        let spacings = lod_spacings();
        for (i, a) in cands.iter().enumerate() {
            for (b, &lb) in cands[i + 1..].iter().zip(&levels[i + 1..]) {
                let (fa, fb) = (
                    &stamper.faces[a.face as usize],
                    &stamper.faces[b.face as usize],
                );
                if Vec3::from(fa.normal).dot(Vec3::from(fb.normal)) <= 0.0 {
                    continue;
                }
                let k = levels[i].max(lb) as usize;
                let r = stamper.radius / fa.scale.max(fb.scale);
                let d = at(a).distance(at(b));
                assert!(
                    d >= spacings[k] * r * 0.999,
                    "levels {} and {lb}: {d} < {} * {r}",
                    levels[i],
                    spacings[k]
                );
            }
        }
    }

    /// The position the passes compute for `c`, to the bit.
    fn position(mesh: &Mesh, c: &Candidate) -> Vec3 {
        Vec3::from(Near::new(c, 0, &face_frame(mesh, c.face as usize)).position)
    }

    /// 3000 roots over a per-vertex density map.
    fn graded(values: &[f32]) -> StampParams<'_> {
        StampParams {
            density: ScalarMap::PerVertex(Strided::from_slice(values)),
            ..params(3000)
        }
    }

    /// Stamps one pass of 3000 roots on `mesh` with per-vertex density
    /// `values` and hands the stamper, its scratch and the candidates to
    /// `check`.
    fn with_candidates(
        mesh: Mesh,
        p: &StampParams,
        check: impl FnOnce(&Stamper, &mut Scratch, Vec<Candidate>),
    ) {
        let mut buf = vec![0u8; required_bytes(&mesh, p).unwrap()];
        let mut arena = Arena::new(&mut buf);
        let stamper = Stamper::new(mesh, p, &mut arena).unwrap().unwrap();
        let faces = 0..mesh.triangle_count();
        let bound = stamper.candidate_bound(faces.clone());
        let mut scratch = Scratch::new(&mut arena, bound).unwrap();
        let mut cands = vec![Candidate::default(); bound];
        let n = stamper.stamp_faces(faces, &mut cands).unwrap();
        cands.truncate(n);
        check(&stamper, &mut scratch, cands);
    }

    #[test]
    fn edge_pass_matches_a_brute_force_scan() {
        let m = graded_plane(12, 30.0);
        // gray and white faces: clash distances differ per pair
        let values: Vec<f32> =
            m.p.iter()
                .map(|p| if p[1] < 0.4 { 0.3 } else { 1.0 })
                .collect();
        with_candidates(m.mesh(), &graded(&values), check_edge_pass);
    }

    fn check_edge_pass(stamper: &Stamper, scratch: &mut Scratch, mut cands: Vec<Candidate>) {
        let n = cands.len();
        let at = |c: &Candidate| position(&stamper.mesh, c);
        let mut expect: Vec<Candidate> = Vec::new();
        for c in &cands {
            let clash = c.near_edge()
                && expect.iter().any(|k| {
                    let (fk, fc) = (
                        &stamper.faces[k.face as usize],
                        &stamper.faces[c.face as usize],
                    );
                    let r = stamper.radius / fk.scale.max(fc.scale);
                    k.face != c.face
                        && k.near_edge()
                        && Vec3::from(fk.normal).dot(Vec3::from(fc.normal)) > 0.0
                        && at(k).distance_squared(at(c)) < r * r
                });
            if !clash {
                expect.push(*c);
            }
        }
        let kept = stamper.prune(&mut cands, scratch).unwrap();
        assert!(kept < n, "the pass removed nothing to compare");
        assert_eq!(&cands[..kept], &expect[..]);
    }

    #[test]
    fn progress_rises_to_one_and_a_false_return_cancels_with_nothing_written() {
        let m = graded_plane(30, 10.0);
        let mesh = m.mesh();
        let p = params(6000);
        let (reference, report) = run(mesh, &p);
        let mut buf = vec![0u8; required_bytes(&mesh, &p).unwrap()];
        let mut out = vec![Root::default(); max_roots(&mesh, &p).unwrap()];
        let mut seen = Vec::new();
        let (n, again) =
            stamp_with_progress(mesh, &p, &mut Arena::new(&mut buf), &mut out, &mut |f| {
                seen.push(f);
                true
            })
            .unwrap();
        assert_eq!((&out[..n], again), (&reference[..], report));
        assert!(seen.windows(2).all(|w| w[0] <= w[1]), "{seen:?}");
        assert_eq!((seen[0], *seen.last().unwrap()), (0.0, 1.0));
        // placement chunks, the edge pass and every LOD level report
        assert!(seen.len() >= LOD_LEVELS + 2, "{seen:?}");
        for stop in [1, seen.len() / 2, seen.len()] {
            let mut calls = 0;
            let mut untouched = vec![Root::default(); out.len()];
            let result = stamp_with_progress(
                mesh,
                &p,
                &mut Arena::new(&mut buf),
                &mut untouched,
                &mut |_| {
                    calls += 1;
                    calls != stop
                },
            );
            assert_eq!(result, Err(Error::Cancelled));
            assert_eq!(calls, stop);
            assert!(untouched.iter().all(|r| *r == Root::default()));
        }
    }

    #[test]
    fn a_flat_chart_is_one_piece_of_the_tile() {
        // a flat plane unfolds onto itself: every candidate, on either side
        // of any edge, is a point of one Poisson set, and a tile point on a
        // shared edge goes to exactly one of its two faces
        let m = graded_plane(10, 1.0);
        // few enough roots that the chart reaches across the whole plane
        with_candidates(m.mesh(), &params(2000), |stamper, _, cands| {
            assert!(stamper
                .places
                .iter()
                .all(|t| t.offset == stamper.places[0].offset));
            let at = |c: &Candidate| position(&stamper.mesh, c);
            let mut closest = f32::INFINITY;
            for (i, a) in cands.iter().enumerate() {
                for b in &cands[i + 1..] {
                    closest = closest.min(at(a).distance(at(b)));
                }
            }
            assert!(
                closest >= stamper.radius * 0.9999,
                "{closest} vs {}",
                stamper.radius
            );
            assert!(cands.iter().all(|c| c.near_levels as usize <= LOD_LEVELS));
        });
    }

    #[test]
    fn an_output_of_exactly_the_count_is_enough() {
        let m = sphere(12, 24);
        // stamped once into room for the bound
        with_candidates(m.mesh(), &params(3000), |stamper, _, roomy| {
            let (faces, n) = (0..stamper.mesh.triangle_count(), roomy.len());
            let mut exact = vec![Candidate::default(); n];
            assert_eq!(stamper.stamp_faces(faces.clone(), &mut exact), Ok(n));
            assert_eq!(exact, roomy);
            let mut short = vec![Candidate::default(); n - 1];
            assert_eq!(
                stamper.stamp_faces(faces, &mut short),
                Err(Error::CapacityExceeded {
                    needed: n,
                    available: n - 1
                })
            );
        });
    }

    #[test]
    fn identical_for_any_face_chunking() {
        let m = graded_plane(30, 10.0);
        let mesh = m.mesh();
        let p = params(6000);
        let (reference, _) = run(mesh, &p);
        for chunks in [2usize, 7, 64] {
            let mut buf = vec![0u8; required_bytes(&mesh, &p).unwrap()];
            let mut arena = Arena::new(&mut buf);
            let mut stamper = Stamper::new(mesh, &p, &mut arena).unwrap().unwrap();
            let faces = mesh.triangle_count();
            let bound = stamper.candidate_bound(0..faces);
            let mut scratch = Scratch::new(&mut arena, bound).unwrap();
            let mut cands = vec![Candidate::default(); bound];
            let kept = loop {
                let mut n = 0;
                for c in 0..chunks {
                    let range = c * faces / chunks..(c + 1) * faces / chunks;
                    let mut part =
                        vec![Candidate::default(); stamper.candidate_bound(range.clone())];
                    let k = stamper.stamp_faces(range, &mut part).unwrap();
                    cands[n..n + k].copy_from_slice(&part[..k]);
                    n += k;
                }
                let kept = stamper.prune(&mut cands[..n], &mut scratch).unwrap();
                if stamper.converged(n, kept) {
                    break kept;
                }
            };
            let mut out = vec![Root::default(); stamper.output_count(kept)];
            stamper
                .finish(&cands[..kept], &mut scratch, &mut out)
                .unwrap();
            assert_eq!(out.len(), reference.len(), "{chunks} chunks: count");
            let first = out.iter().zip(&reference).position(|(a, b)| a != b);
            assert!(
                first.is_none(),
                "{chunks} chunks differ at {first:?}: {:?} vs {:?}",
                first.map(|i| out[i]),
                first.map(|i| reference[i])
            );
        }
    }

    #[test]
    fn density_map_scales_and_bald_regions_stay_bald() {
        let m = graded_plane(20, 1.0);
        let mesh = m.mesh();
        // left half black, right half white
        let values: Vec<f32> =
            m.p.iter()
                .map(|p| if p[0] < 0.5 { 0.0 } else { 1.0 })
                .collect();
        let mut p = params(4000);
        p.density = ScalarMap::PerVertex(Strided::from_slice(&values));
        let (roots, _) = run(mesh, &p);
        assert!(roots
            .iter()
            .all(|r| mesh.point(r.face as usize, r.u, r.v).x > 0.44));
        p.bald_below = 0.0;
        let (roots, _) = run(mesh, &p);
        let left = roots
            .iter()
            .filter(|r| mesh.point(r.face as usize, r.u, r.v).x < 0.45)
            .count();
        let right = roots
            .iter()
            .filter(|r| mesh.point(r.face as usize, r.u, r.v).x > 0.55)
            .count();
        // black = half size: a quarter of the density
        let ratio = left as f32 / right as f32;
        assert!((ratio - 0.25).abs() < 0.05, "left/right = {ratio}");
    }

    #[test]
    fn a_fixed_radius_keeps_every_root_and_its_spacing() {
        let m = sphere(16, 32);
        let mesh = m.mesh();
        let (white, report) = run(mesh, &params(3000));
        let fixed = |density: ScalarMap<'static>| StampParams {
            radius: report.radius,
            density,
            bald_below: 0.0,
            ..params(0)
        };
        let (same, r2) = run(mesh, &fixed(ScalarMap::Constant(1.0)));
        assert_eq!((r2.trimmed, r2.passes), (0, 1));
        assert!(min_spacing(&mesh, &same) >= report.radius * 0.999);
        // uniform gray 0.5 with black = half size: scale 0.75, density 0.5625
        let (gray, _) = run(mesh, &fixed(ScalarMap::Constant(0.5)));
        let ratio = gray.len() as f32 / same.len() as f32;
        assert!((ratio - 0.5625).abs() < 0.05, "gray/white = {ratio}");
        assert!(white.len() == 3000 && (same.len() as f32 / 3000.0 - 1.0).abs() < 0.06);
    }

    #[test]
    fn rejects_bad_input_before_writing() {
        let m = sphere(8, 16);
        let mut bad = m.p.clone();
        bad[3][1] = f32::NAN;
        let mesh = Mesh::new(Strided::from_slice(&bad), Strided::from_slice(&m.t));
        assert!(matches!(
            required_bytes(&mesh, &params(100)),
            Err(Error::NonFinite { .. })
        ));
        let mesh = m.mesh();
        let need = required_bytes(&mesh, &params(100)).unwrap();
        let mut out = vec![Root::default(); 100];
        // too small for the stamper itself, and big enough for it but not
        // for the passes: both report the whole need
        for size in [100, need - 1] {
            let mut buf = vec![0u8; size];
            let mut arena = Arena::new(&mut buf);
            let err = stamp(mesh, &params(100), &mut arena, &mut out).unwrap_err();
            assert_eq!(
                err,
                Error::CapacityExceeded {
                    needed: need,
                    available: size
                }
            );
        }
        assert!(out.iter().all(|r| *r == Root::default()));
        let mut p = params(100);
        p.black_scale = 0.0;
        assert!(matches!(
            required_bytes(&mesh, &p),
            Err(Error::InvalidArgument(_))
        ));
    }
}
