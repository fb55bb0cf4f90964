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
//!    shrinks by at most `cos(a / 2)` in 3D (0.99905 at 5 degrees). Points
//!    of faces near another shell take part too, and buried skin grows no
//!    root (the `shell` module).
//! 2. **Fill.** Darts thrown along the cut edges fill the holes the edge
//!    pass leaves ([`Stamper::fill`]).
//! 3. **Count.** The radius is derived so the *expected* number of stamped
//!    points equals the target: for a uniform random placement in a periodic
//!    tile of density `rho` points per `r^2`, a triangle of flattened area `A`
//!    scaled by `s` receives `rho * A * s^2 / r^2` points on average, hence
//!    `r = sqrt(rho * sum(A_i s_i^2) / N)`. The edge pass removes a
//!    mesh-dependent share, which a model fitted to the measured loss per
//!    length of cut edge predicts for the first pass; the measured count then
//!    corrects the radius until the count is within [`COUNT_TOLERANCE`] of
//!    the target (dense stamps usually need no correction). (The paper's
//!    `0.35 / (sqrt(N) * A_max_normalized)` is not dimensionally a length.)
//! 4. **LOD.** The tile is grown coarse to fine, one step of a nested
//!    level at a time, so every rank prefix within a chart is a Poisson set
//!    grown for its own size; each point also carries its place in its step
//!    (farthest-point order). Across triangles, a point moves to the first
//!    step whose spacing it respects from every point of another triangle
//!    that comes before it (a coarser tile step, or the same step on an
//!    earlier triangle); the rule reads tile steps only, so it needs one
//!    query per point and no re-checking. The rank is a counting sort by
//!    (step, place in the step, hash of the index); the surplus of the
//!    count leaves from the end, the points nearest to others. A stamp of
//!    up to 65,536 roots, whose charts are narrow next to the coarse steps'
//!    spacing, takes its ranks from weighted sample elimination over the
//!    whole mesh instead (the `eliminate` module), which also removes its
//!    surplus, where the candidates crowd each other most.
//!
//! Triangle stamping takes face ranges ([`Stamper::stamp_faces`]) so a host can
//! spread it over threads; the result is bitwise identical for any split.

// The driver, the stamper's state and its radius live here; the stages
// each have a module: `sizing` (face setup and memory bounds), `place`
// (tile points into candidates), `prune` (the edge pass), `lod` (levels
// and ranks), with the records and buffers the passes share in `near` and
// `scratch`.
pub mod chart;
mod eliminate;
mod fill;
mod lod;
mod near;
mod place;
mod prune;
mod scratch;
mod shell;
mod sizing;
pub mod tile;

use crate::arena::{Arena, ArenaLayout};
use crate::stamp::tile::{level_spacing, LOD_LEVELS, TILE, TILE_SIDE};
use crate::{Error, Mesh, Root, ScalarMap};
use bytemuck::{Pod, Zeroable};
use chart::Unfolded;
use core::ops::Range;
use glam::Vec3;
use place::{ChartFrame, TilePlace};
pub use scratch::Scratch;
use shell::Shells;
use sizing::*;
pub use sizing::{max_roots, required_bytes, DENSITY_STEPS};

/// Roots of two faces whose normals' dot product is above this face the
/// same open air and keep their distance (see [`same_air`]).
pub const SAME_AIR_DOT: f32 = 0.0;

/// Whether roots at `p` and `q` on faces of unit normals `n` and `m` face
/// the same open air, and so keep their distance: their normals are less
/// than 90 degrees apart ([`SAME_AIR_DOT`]), or each lies in front of the
/// other's tangent plane (a concave crease of any angle: an eye corner, a
/// lid against an eyeball, the root of an ear). The two sides of a thin
/// part, or of a convex edge, are behind each other.
#[inline]
pub fn same_air(p: Vec3, n: Vec3, q: Vec3, m: Vec3) -> bool {
    n.dot(m) > SAME_AIR_DOT || ((q - p).dot(n) >= 0.0 && (p - q).dot(m) >= 0.0)
}

/// Width of the band above the target where the radius correction stops;
/// the surplus is trimmed by LOD rank (the end of the last step: the points
/// nearest to others, so the trim opens no hole), or up to 65,536 roots by
/// sample elimination (the most crowded candidates).
pub const COUNT_TOLERANCE: f32 = 0.02;
/// Grid cells of the LOD passes, in disk radii times the level's spacing:
/// larger cells mean fewer buckets per face's query box but more points per
/// bucket; 5 measured best against 3, 4, 6 and 8 on the creature at 1M
/// roots.
const GRID_CELL: f32 = 5.0;
/// Grid cells of the edge pass, in disk radii. Its table is laid out in
/// blocks of cells ([`HashGrid::in_blocks`](crate::surface::grid::HashGrid::in_blocks)),
/// which makes a bucket cheaper to visit, so larger cells pay: 6 measured
/// best against 3, 4, 5, 7, 8 and 10 on the creature at 1M roots.
const EDGE_GRID_CELL: f32 = 6.0;
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
/// Targets below which the sparse floor comes down with the square root of
/// the target, to [`MIN_RADIUS_FACTOR_TINY`]: a stamp of a few roots is a
/// lottery over the tile's windows (at the first radius a pass can stamp
/// none), and the area term of its candidate bound, about `1.7 * target /
/// factor^2`, stays below 2,200 points.
const SMALL_TARGET: u32 = 256;
/// Lowest floor, for a target of one root.
const MIN_RADIUS_FACTOR_TINY: f32 = 0.05;

fn min_radius_factor(target: u32, faces: usize) -> f32 {
    if (target as usize) >= 4 * faces {
        MIN_RADIUS_FACTOR
    } else if target >= SMALL_TARGET {
        MIN_RADIUS_FACTOR_SPARSE
    } else {
        let small = libm::sqrtf(target as f32 / SMALL_TARGET as f32);
        (MIN_RADIUS_FACTOR_SPARSE * small).max(MIN_RADIUS_FACTOR_TINY)
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
    /// Points the fill pass added in the last pass.
    pub filled: u32,
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
    pub level: u8,
    /// The step of its level the tile took it in (see
    /// [`step_spacing`](tile::step_spacing)): the rank orders a level's
    /// points by step.
    pub step: u8,
    /// Its place within its step, from the tile (0 first, 255 last; see
    /// [`Tile::run`](tile::Tile::run)): the rank orders a step's points by
    /// it, so the count trim drops those nearest to others.
    pub order: u8,
    /// How many LOD levels, coarsest first, have a spacing (in units of the
    /// local disk radius) that reaches from the point past a cut edge of its
    /// triangle or the far side of a linked neighbour. Within that distance
    /// every point comes from the same piece of the tile, so only at those
    /// levels can the point conflict with points of other triangles;
    /// [`LOD_LEVELS`] means even the disk radius reaches (the point takes
    /// part in the edge pass), and is also given to every point of a face
    /// near another shell and to the fill's darts.
    pub near_levels: u8,
}

impl Candidate {
    /// Whether the disk radius reaches past the triangle's boundary, so that
    /// the point takes part in the edge pass.
    #[inline]
    pub fn near_edge(&self) -> bool {
        self.near_levels as usize == LOD_LEVELS
    }

    /// The root this candidate becomes, with its `id` and `rank`.
    #[inline]
    pub(super) fn root(&self, id: u32, rank: u32) -> Root {
        Root {
            face: self.face,
            u: self.uv[0],
            v: self.uv[1],
            id,
            rank,
        }
    }
}

/// Corner 0 of face `f` and its edges to corners 1 and 2: a point at
/// barycentric `(u, v)` lies at `a + e1 * u + e2 * v`.
#[inline]
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
/// The stamping state for one mesh and parameter set: per-face scales and
/// placements in the tile, and the current radius.
pub struct Stamper<'m, 'a> {
    mesh: Mesh<'m>,
    seed: u64,
    target: u32,
    faces: &'a [Face],
    places: &'a [TilePlace],
    shells: Shells<'a>,
    first_radius: f32,
    /// The faces' area weighted by their squared density scale.
    area: f64,
    /// Share of the scaled area on skin that is not buried (1 on a mesh
    /// without a body): the first pass aims at the skin that grows roots.
    unburied: f64,
    radius: f32,
    /// The radius was given: one pass, every root kept.
    fixed: bool,
    /// Radius and kept count of the previous pass, for the secant.
    previous: Option<(f32, usize)>,
    passes: u32,
    degenerate: u32,
    /// [`level_spacing`] of each level.
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

impl<'m, 'a> Stamper<'m, 'a> {
    /// Adds the bytes [`Stamper::new`] takes from the arena.
    pub fn layout(layout: &mut ArenaLayout, mesh: &Mesh) {
        layout
            .add::<Face>(mesh.triangle_count())
            .add::<TilePlace>(mesh.triangle_count())
            .add::<Unfolded>(mesh.triangle_count());
        chart::layout(layout, mesh);
        Shells::layout(layout, mesh);
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
        let faces = arena.alloc::<Face>(mesh.triangle_count())?;
        let places = arena.alloc::<TilePlace>(mesh.triangle_count())?;
        let laid = arena.alloc::<Unfolded>(mesh.triangle_count())?;
        let sums = FaceSums::of(&mesh, params, |f, face| faces[f] = face);
        let area = sums.area;
        let fixed = params.radius > 0.0;
        let radius = if fixed {
            params.radius
        } else {
            match first_radius(area, params.target_count, TILE.density()) {
                Some(r) => r,
                None => return Ok((None, sums)),
            }
        };
        let (scale, normal) = (|f: usize| faces[f].scale, |f: usize| faces[f].normal.into());
        chart::unfold(&mesh, scale, normal, CHART_REACH * radius, arena, laid)?;
        let reach = |f: usize| match faces[f].scale {
            0.0 => 0.0,
            s => shell::REACH_MARGIN * radius / s,
        };
        let shells = Shells::new(&mesh, reach, arena)?;
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
            faces,
            places,
            shells,
            first_radius: radius,
            area: sums.area,
            unburied: 1.0,
            fixed,
            radius,
            previous: None,
            passes: 0,
            degenerate: sums.degenerate,
            spacings: core::array::from_fn(level_spacing),
        };
        if !fixed {
            stamper.unburied = stamper.unburied_share();
            stamper.radius = stamper.predicted_radius();
        }
        Ok((Some(stamper), sums))
    }

    /// Expected number of points the edge pass removes at radius `r`, net of
    /// what the fill wins back: each face's half of an edge of length `l`
    /// (scaled by density, `x = l / 2r`) loses `EDGE_LOSS * x^2 / (x +
    /// EDGE_LOSS_KNEE)` points, of which the fill restores a share (see
    /// [`REFILLED`](fill::REFILLED)), more than all when the loss is a
    /// large share of the target. Long edges lose a fixed number per
    /// radius of length; short ones less, as their faces hold fewer points.
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
        let gross = EDGE_LOSS as f64 * loss as f64;
        let refilled = if self.fills() {
            fill::REFILLED as f64 + fill::REFILL_SLOPE as f64 * gross / self.target.max(1) as f64
        } else {
            0.0
        };
        (1.0 - refilled) * gross
    }

    /// Share of [`area`](Self::area) on skin that is not buried,
    /// at the first radius, each face counted by its centroid (one test a
    /// face: the placement tests the points of a face near another shell
    /// one by one, but an estimate for the first radius needs no more).
    fn unburied_share(&self) -> f64 {
        let buried: f64 = (0..self.faces.len())
            .filter(|&f| self.faces[f].scale > 0.0)
            .filter(|&f| {
                // the radius is still the first one
                let lift = place::BURY_LIFT * self.local_radius(f as u32);
                let [a, b, c] = self.mesh.corners(f);
                let normal = Vec3::from(self.faces[f].normal);
                self.shells
                    .face_buried(f)
                    .unwrap_or_else(|| self.shells.buried((a + b + c) / 3.0, normal, lift))
            })
            .map(|f| {
                let scale = self.faces[f].scale as f64;
                self.mesh.area(f) as f64 * scale * scale
            })
            .sum();
        if self.area > 0.0 {
            (1.0 - buried / self.area).clamp(0.0, 1.0)
        } else {
            1.0
        }
    }

    /// The radius whose stamp is expected to keep the middle of the count
    /// band after the edge pass, so that most stamps need one pass: the
    /// fixed point of `r = sqrt(rho * area / (aim + loss(r)))` over the area
    /// that is not buried, which converges fast as the loss moves slowly
    /// with `r`.
    fn predicted_radius(&self) -> f32 {
        let aim = self.target as f64 * (1.0 + 0.5 * COUNT_TOLERANCE as f64);
        let stamped = self.first_radius as f64
            * self.first_radius as f64
            * self.target as f64
            * self.unburied;
        let floor = self.first_radius * min_radius_factor(self.target, self.mesh.triangle_count());
        let mut r = self.first_radius;
        for _ in 0..PREDICTION_STEPS {
            r = (libm::sqrt(stamped / (aim + self.predicted_loss(r))) as f32).max(floor);
        }
        r
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

    /// The local disk radius at face `f` (larger where the density is lower).
    #[inline]
    fn local_radius(&self, f: u32) -> f32 {
        self.radius / self.faces[f as usize].scale
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
        if (0.0..=COUNT_TOLERANCE).contains(&excess) || self.passes >= MAX_PASSES {
            return true;
        }
        let aim = target as f64 * (1.0 + 0.5 * COUNT_TOLERANCE as f64);
        let r1 = self.radius as f64;
        let corrected = if kept == 0 {
            // a small target can miss every face: there is no count to
            // correct from, so go halfway (in log) back to a smaller radius
            // that stamped roots, or shrink
            match self.previous {
                Some((r0, k0)) if k0 > 0 && r0 < self.radius => libm::sqrtf(r0 * self.radius),
                _ => self.radius * 0.7,
            }
        } else if self.passes < SECANT_PASSES {
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

    fn report(&self, candidates: usize, pruned_to: usize, filled_to: usize) -> StampReport {
        StampReport {
            radius: self.radius,
            candidates: candidates as u32,
            pruned: (candidates - pruned_to) as u32,
            filled: (filled_to - pruned_to) as u32,
            trimmed: (filled_to - self.output_count(filled_to)) as u32,
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
    if arena.remaining() < passes_bytes(bound) {
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
        let filled = stamper.fill(cands, kept, &mut scratch)?;
        done(pass_end)?;
        if stamper.converged(n, filled) {
            let m = stamper.output_count(filled);
            if out.len() < m {
                return Err(Error::OutputTooSmall {
                    needed: m,
                    available: out.len(),
                });
            }
            let mut finishing = |share: f32| done(pass_end + (1.0 - pass_end) * share);
            stamper.finish_reporting(
                &cands[..filled],
                &mut scratch,
                &mut out[..m],
                &mut finishing,
            )?;
            return Ok((m, stamper.report(n, kept, filled)));
        }
        pass_start = pass_end;
    }
}

#[cfg(test)]
mod tests;
