//! The body as a solid, for point-in-body queries (collisions, settle).
//!
//! **Inside** means a generalized winding number (Jacobson et al. 2013)
//! above one half: the signed solid angle the whole mesh subtends at the
//! point, over 4 pi. On a closed mesh wound counter-clockwise seen from
//! outside (the normals hair grows along) it is 1 inside and 0 outside; a
//! point inside two intersecting shells (an eyeball in its socket) counts
//! 2, still inside; near a hole (an open eye socket, a neck) it falls off
//! smoothly, and the threshold of one half closes the hole with the surface
//! that spans it. An inside-out mesh has no inside.
//!
//! The winding number is evaluated in two parts. Each boundary loop of the
//! mesh (its [`Rim`]) is closed by a cap, a fan of triangles from the mean
//! of the loop's corners; the capped surface is closed, so its winding
//! number `w` is an integer that changes by one at each crossing of the
//! surface. The mesh's own winding number is `w` minus the caps' solid
//! angle over 4 pi, which matters only near a cap.
//!
//! A uniform grid over the mesh triangles: each cell lists the triangles
//! whose bounds meet it and whose plane passes through it (padded against
//! rounding), the only ones that may cross it. Every cell centre's `w` is
//! found once, by one sweep along x through each row of centres that adds up the
//! signed crossings between consecutive centres. A point in a cell no
//! triangle touches, far from every cap, takes its cell's class by a
//! lookup; a point in a cell the surface passes through takes the centre's
//! `w`, changed by each crossing of a three-leg path (along x, y, then z)
//! from the centre to the point, all inside the cell, so only that cell's
//! triangles are tested. Near a cap the path also meets the caps, and the
//! caps' solid angle decides: "near" is where the caps' bounds, summed,
//! may reach a half turn; there the caps are bounded, then evaluated one by
//! one, nearest first, as a running product of complex numbers (one
//! arctangent a cap, not one a triangle), until the answer is settled by
//! far more than the rounding; a point too close to the threshold for that
//! takes the exact sum, an arctangent per cap triangle.
//!
//! Crossings are counted watertight: edge functions are evaluated with the
//! edge's endpoints in a canonical order, so the two triangles sharing an
//! edge see exactly opposite values, and a line through an edge or a vertex
//! is settled by a fixed symbolic perturbation of the line. A line through a
//! shared edge thus crosses exactly one of the two triangles, whatever the
//! rounding.

use crate::arena::{Arena, ArenaLayout};
use crate::surface::grid::floor_i32;
pub use crate::surface::rim::Rim;
use crate::surface::rim::SolidBounds;
use crate::{Error, Mesh};
use core::ops::Range;
use glam::{Vec3, Vec3A};
use wide::{f32x4, CmpEq, CmpGt, CmpNe};

/// Cells per triangle the grid aims at by default: finer grids answer more
/// points by lookup and test fewer triangles in the others, coarser ones
/// build faster (see [`BodyPlan::with_density`]).
pub const CELLS_PER_TRIANGLE: f32 = 32.0;
/// Most cells along one axis.
const MAX_DIM: f32 = 1024.0;

/// Most caps whose bounds are summed per cell to mark the cells near a
/// cap (see `BodyGrid::mark_near_caps`); a mesh with more holes marks by
/// the cap count alone.
const MAX_SUMMED: usize = 32;

/// The threshold on the generalized winding number above which a point is
/// inside.
pub const INSIDE_WINDING: f32 = 0.5;

/// Cell class bits: the surface passes through the cell (it lists
/// triangles); a cap's solid angle may decide points in it. The bits above
/// them hold the centre's winding number `w` of the capped surface, signed
/// (read as `class as i8 >> WINDING_SHIFT`).
const SURFACE: u8 = 1;
const NEAR_CAP: u8 = 2;
const WINDING_SHIFT: u32 = 2;
/// The range of `w` a class holds; a point inside more than 31 shells at
/// once is read as inside 31.
const MAX_WINDING: i32 = 31;

mod build;
mod plan;

pub use build::{BodyGrid, BodyParts};
use build::{CapBall, Shape};
pub use plan::BodyPlan;

/// The mesh as a solid, in caller-provided memory.
pub struct Body<'a> {
    shape: Shape,
    /// Triangle list of cell `c`: `refs[start[c]..start[c + 1]]`.
    start: &'a [u32],
    refs: &'a [u32],
    /// The non-degenerate triangles, copied for locality.
    triangles: &'a [Stored],
    /// The caps' triangles, one per boundary edge (see the module docs).
    caps: &'a [Stored],
    /// Each cap's bounding ball and the end of its triangles in `caps`.
    loops: &'a [CapBall],
    class: &'a [u8],
}

impl<'a> Body<'a> {
    /// The references of the triangles listed in cell `c`.
    #[inline]
    fn listed(&self, c: usize) -> &[u32] {
        &self.refs[self.start[c] as usize..self.start[c + 1] as usize]
    }

    /// The centre of cell `(x, y, z)`.
    fn centre(&self, x: usize, y: usize, z: usize) -> Vec3 {
        self.shape.centre(x, y, z)
    }

    /// True when `p` is inside the body: its generalized winding number is
    /// above [`INSIDE_WINDING`].
    pub fn contains(&self, p: Vec3) -> bool {
        let p = self.shape.local(p);
        match self.capped(p) {
            (w, false) => w >= 1,
            (w, true) => self.caps_decide(w, p),
        }
    }

    /// The winding number at `p` of the mesh with its holes closed by the
    /// caps (see the module docs): an integer, exact everywhere, and equal
    /// to the generalized winding number on a closed mesh. It reads a
    /// hole's cap as skin, where [`contains`](Self::contains) follows the
    /// winding number's smooth fall across the hole; cheaper near a hole.
    pub fn capped_winding(&self, p: Vec3) -> i32 {
        self.capped(self.shape.local(p)).0
    }

    /// [`capped_winding`](Self::capped_winding), and whether a cap may
    /// decide [`contains`](Self::contains) at `p` (local).
    fn capped(&self, p: Vec3) -> (i32, bool) {
        let c = self.shape.cell_of(p);
        let inside = (0..3).all(|k| c[k] >= 0 && (c[k] as usize) < self.shape.dims[k]);
        if !inside {
            return (0, false);
        }
        let cell = [c[0] as usize, c[1] as usize, c[2] as usize];
        let c = self.shape.index(cell[0], cell[1], cell[2]);
        let class = self.class[c];
        let mut w = ((class as i8) >> WINDING_SHIFT) as i32;
        let near_cap = class & NEAR_CAP != 0;
        if class & (SURFACE | NEAR_CAP) == 0 {
            return (w, false);
        }
        let at = self.centre(cell[0], cell[1], cell[2]);
        // the cap triangles whose bounds meet the cell (the legs stay in it),
        // from the caps whose ball reaches it
        let half = 0.5 / self.shape.inv_cell;
        let (lo, hi) = (
            at - Vec3::splat(half * 1.001),
            at + Vec3::splat(half * 1.001),
        );
        let mut met = [0u32; 32];
        let (mut listed, mut spill) = (0, false);
        if near_cap {
            let reach = libm::sqrtf(3.0) * half;
            let mut first = 0;
            for ball in self.loops {
                let fan = first..ball.end as usize;
                first = ball.end as usize;
                if Vec3::from(ball.centre).distance(at) > ball.radius * 1.001 + reach {
                    continue;
                }
                for t in fan {
                    let (tlo, thi) = self.caps[t].bounds();
                    let meets = Vec3::from(tlo).cmple(hi).all() && Vec3::from(thi).cmpge(lo).all();
                    if meets {
                        if listed < met.len() {
                            met[listed] = t as u32;
                            listed += 1;
                        } else {
                            spill = true;
                        }
                    }
                }
            }
        }
        let caps: &[Stored] = if spill { self.caps } else { &[] };
        let met = &met[..if spill { 0 } else { listed }];
        // the path centre -> (p.x, centre.y, centre.z) -> (p.x, p.y,
        // centre.z) -> p, a leg per axis
        let legs = Legs {
            body: self,
            listed: self.listed(c),
            caps,
            met,
            to: p,
        };
        w += legs.crossings(at);
        (w, near_cap)
    }

    /// Whether `w` less the caps' solid angle at `p` over 4 pi is above
    /// [`INSIDE_WINDING`]: [`caps_bounded`](Self::caps_bounded) when it
    /// settles it, else [`caps_exact`](Self::caps_exact).
    fn caps_decide(&self, w: i32, p: Vec3) -> bool {
        #[cfg(test)]
        if EXACT_CAPS.with(|e| e.get()) {
            return self.caps_exact(w, p);
        }
        let settled = self.caps_bounded(w, p);
        #[cfg(test)]
        FAST.with(|f| {
            let mut counts = f.get();
            counts[settled.is_some() as usize] += 1;
            f.set(counts)
        });
        settled.unwrap_or_else(|| self.caps_exact(w, p))
    }

    /// [`caps_exact`](Self::caps_exact)'s answer, when the caps' bounds,
    /// then [`fan_angle`] on the caps nearest `p`, settle it by far more
    /// than their rounding (`None` otherwise: near the threshold, a
    /// doubtful evaluation, or more than [`MAX_SUMMED`] caps). The answer
    /// is the sign of `limit - S`, `S` the caps' solid angle: where the
    /// evaluated caps' sum and the others' bounds put `S` farther from
    /// `limit` than they can err, that sign is the exact evaluation's,
    /// found without an arctangent per cap triangle, most often with one
    /// cap evaluated or none (most points near a hole are far from the
    /// threshold: outside, seeing a small part of its cap).
    fn caps_bounded(&self, w: i32, p: Vec3) -> Option<bool> {
        const TURN: f64 = 4.0 * core::f64::consts::PI;
        // a margin far above the evaluations' rounding (~1e-12 a triangle)
        const MARGIN: f64 = 1e-8;
        if self.loops.len() > MAX_SUMMED {
            return None;
        }
        let limit = TURN * (w as f64 - INSIDE_WINDING as f64);
        let mut bounds = [0.0f64; MAX_SUMMED];
        let bounds = &mut bounds[..self.loops.len()];
        for (b, ball) in bounds.iter_mut().zip(self.loops) {
            *b = ball.bound(p);
        }
        // the caps evaluated one by one, the largest bound first, until
        // the evaluated caps' angle and the other caps' bounds settle it
        let (mut angle, mut error) = (0.0f64, 0.0f64);
        loop {
            let slack: f64 = bounds.iter().sum();
            let value = limit - angle;
            if libm::fabs(value) > slack + error + MARGIN {
                #[cfg(test)]
                if error == 0.0 {
                    FAST.with(|f| {
                        let mut counts = f.get();
                        counts[2] += 1;
                        f.set(counts)
                    });
                }
                return Some(value > 0.0);
            }
            let (k, &largest) = bounds
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))?;
            if largest == 0.0 {
                return None;
            }
            let first = match k {
                0 => 0,
                _ => self.loops[k - 1].end as usize,
            };
            let (a, e) = fan_angle(&self.caps[first..self.loops[k].end as usize], p)?;
            (angle, error, bounds[k]) = (angle + a, error + e, 0.0);
        }
    }

    /// Whether `w` less the caps' solid angle at `p` over 4 pi is above
    /// [`INSIDE_WINDING`], a cap triangle at a time. Caps near `p` are
    /// evaluated exactly; the far ones only when their bounds leave the
    /// answer open.
    fn caps_exact(&self, w: i32, p: Vec3) -> bool {
        const NEAR: f64 = 0.8;
        let turn = 4.0 * core::f64::consts::PI;
        let (mut exact, mut slack) = (0.0f64, 0.0f64);
        let mut first = 0;
        for ball in self.loops {
            let fan = &self.caps[first..ball.end as usize];
            first = ball.end as usize;
            let bound = ball.bound(p);
            if bound > NEAR {
                exact += fan.iter().map(|t| solid_angle(t, p)).sum::<f64>();
            } else {
                slack += bound;
            }
        }
        let value = w as f64 - exact / turn - INSIDE_WINDING as f64;
        if libm::fabs(value) > slack / turn {
            return value > 0.0;
        }
        let all: f64 = self.caps.iter().map(|t| solid_angle(t, p)).sum();
        w as f64 - all / turn > INSIDE_WINDING as f64
    }

    /// True when the segment from `a` to `b` meets a triangle of the body.
    pub fn blocks(&self, a: Vec3, b: Vec3) -> bool {
        let (a, b) = (self.shape.local(a), self.shape.local(b));
        let mut hit = false;
        self.walk(a, b, |refs, _| {
            hit = refs
                .iter()
                .any(|&t| meet(&self.triangles[t as usize], a, b - a).is_some());
            hit
        });
        hit
    }

    /// Where the segment from `a` to `b` first meets a triangle of the body
    /// (of its own triangles; the caps over its holes are not met): the
    /// parameter `t` in `[0, 1]` of the point `a + t (b - a)`, or `None`.
    pub fn first_meet(&self, a: Vec3, b: Vec3) -> Option<f32> {
        let (a, b) = (self.shape.local(a), self.shape.local(b));
        let mut first: Option<f32> = None;
        self.walk(a, b, |refs, leave| {
            for &t in refs {
                if let Some(at) = meet(&self.triangles[t as usize], a, b - a) {
                    first = Some(first.map_or(at, |f| f.min(at)));
                }
            }
            // a triangle listed in a later cell meets the segment later
            // than this cell's stretch, so a meet within it is the first
            first.is_some_and(|f| f <= leave)
        });
        first
    }

    /// Walks the grid cells the segment from `a` to `b` (local) passes through, in
    /// order, from where it enters the grid to where it leaves it, handing
    /// `visit` each cell's triangles and the segment parameter at which it
    /// leaves the cell, until `visit` returns true.
    fn walk(&self, a: Vec3, b: Vec3, mut visit: impl FnMut(&[u32], f32) -> bool) {
        let shape = &self.shape;
        let (from, to) = (a * shape.inv_cell, b * shape.inv_cell);
        if !(from.is_finite() && to.is_finite()) {
            return;
        }
        let d = to - from;
        let dims = shape.dims.map(|n| n as i32);
        // the stretch of the segment inside the grid, as parameters t of
        // from + t * d, and the t at which it crosses its next cell wall
        // along each axis
        let (mut t0, mut t1) = (0.0f32, 1.0f32);
        let (mut step, mut next, mut delta) = ([0i32; 3], [f32::INFINITY; 3], [0.0f32; 3]);
        for k in 0..3 {
            if d[k] == 0.0 {
                if !(0.0..dims[k] as f32).contains(&from[k]) {
                    return;
                }
                continue;
            }
            let (enter, leave) = ((0.0 - from[k]) / d[k], (dims[k] as f32 - from[k]) / d[k]);
            (t0, t1) = (t0.max(enter.min(leave)), t1.min(enter.max(leave)));
            (step[k], delta[k]) = (if d[k] > 0.0 { 1 } else { -1 }, 1.0 / libm::fabsf(d[k]));
        }
        if t0 > t1 {
            return;
        }
        let start = from + d * t0;
        let mut cell = [0, 1, 2].map(|k| floor_i32(start[k]).clamp(0, dims[k] - 1));
        for k in (0..3).filter(|&k| d[k] != 0.0) {
            let wall = (cell[k] + (d[k] > 0.0) as i32) as f32;
            next[k] = (wall - from[k]) / d[k];
        }
        // a straight walk crosses each wall at most once
        for _ in 0..dims.iter().sum::<i32>() {
            let c = shape.index(cell[0] as usize, cell[1] as usize, cell[2] as usize);
            let refs = self.listed(c);
            let k = if next[0] <= next[1] && next[0] <= next[2] {
                0
            } else if next[1] <= next[2] {
                1
            } else {
                2
            };
            if visit(refs, next[k].min(t1)) {
                return;
            }
            cell[k] += step[k];
            if next[k] > t1 || !(0..dims[k]).contains(&cell[k]) {
                return;
            }
            next[k] += delta[k];
        }
    }
}

/// Where the segment `a + t * d`, `t` in `[0, 1]`, meets triangle `t`: that
/// `t`, or `None` (Moller-Trumbore; a segment in the triangle's plane does
/// not meet it).
#[inline]
fn meet(t: &Stored, a: Vec3, d: Vec3) -> Option<f32> {
    let [p, q, r] = t.corners().map(Vec3::from);
    let (e1, e2) = (q - p, r - p);
    let h = d.cross(e2);
    let det = e1.dot(h);
    if det == 0.0 {
        return None;
    }
    let s = (a - p) / det;
    let u = s.dot(h);
    let w = s.cross(e1);
    let v = d.dot(w);
    let along = e2.dot(w);
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && (0.0..=1.0).contains(&along)).then_some(along)
}

/// A triangle as stored, a cache line each: its corners, and its plane as
/// the grid's lists and the queries cull by it, the plane first.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct Stored {
    /// The first corner `c0`, and the plane's slack: how far a crossing
    /// computed with the triangle may seem to lie from its plane, as
    /// `n . (x - c0)` measures (the rounding of that measure at the
    /// coordinates of the grid, the 4e-6 term, ~33 units in the last place
    /// where ~10 are needed; and [`stray`]).
    first: [f32; 4],
    /// The computed normal `n = (c1 - c0) x (c2 - c0)`, unnormalized (and
    /// a zero).
    normal: [f32; 4],
    /// The second and the third corner (and a zero each).
    rest: [[f32; 4]; 2],
}

impl Stored {
    /// Triangle `corners` in a grid of cells `1 / inv_cell` wide whose
    /// coordinates reach `reach` ([`Shape::reach`]).
    #[inline]
    fn new(corners: [Vec3; 3], reach: f32, inv_cell: f32) -> Self {
        let [c0, c1, c2] = corners.map(Vec3A::from);
        let (e0, e1, e2) = (c1 - c0, c2 - c0, c2 - c1);
        let n = e0.cross(e1);
        let longest = e0
            .length_squared()
            .max(e1.length_squared())
            .max(e2.length_squared());
        let slack = n.abs().element_sum() * 4e-6 * (reach + c0.abs().max_element())
            + stray(longest, inv_cell);
        Stored {
            first: c0.extend(slack).into(),
            normal: n.extend(0.0).into(),
            rest: [c1.extend(0.0).into(), c2.extend(0.0).into()],
        }
    }

    /// The first corner.
    #[inline]
    fn corner(&self) -> Vec3 {
        Vec3::from_slice(&self.first)
    }

    /// The first corner, as a vector type (its fourth lane holds the
    /// slack: fine for the three-lane operations it takes part in).
    #[inline]
    fn corner_a(&self) -> Vec3A {
        Vec3A::from_vec4(glam::Vec4::from_array(self.first))
    }

    /// The normal.
    #[inline]
    fn normal(&self) -> Vec3A {
        Vec3A::from_vec4(glam::Vec4::from_array(self.normal))
    }

    /// The slack (see `first`).
    #[inline]
    fn slack(&self) -> f32 {
        self.first[3]
    }

    /// The three corners.
    #[inline]
    fn corners(&self) -> [[f32; 3]; 3] {
        let xyz = |v: &[f32; 4]| [v[0], v[1], v[2]];
        [xyz(&self.first), xyz(&self.rest[0]), xyz(&self.rest[1])]
    }

    /// The low and the high corner of the triangle's bounds.
    #[inline]
    fn bounds(&self) -> (Vec3A, Vec3A) {
        let [a, b, c] = [self.first, self.rest[0], self.rest[1]]
            .map(|v| Vec3A::from_vec4(glam::Vec4::from_array(v)));
        (a.min(b).min(c), a.max(b).max(c))
    }
}

/// The cells a triangle's bounds touch: the first and the last along x, y
/// and z.
type Span = [u16; 6];

/// The path of [`Body::capped`] from a cell's centre to a point in it, and
/// the triangles it may cross: the cell's, and the caps that meet it
/// (`met`) or, when too many do, every cap (`caps`).
struct Legs<'b> {
    body: &'b Body<'b>,
    /// The cell's triangle references.
    listed: &'b [u32],
    caps: &'b [Stored],
    met: &'b [u32],
    to: Vec3,
}

impl Legs<'_> {
    /// The change of winding number along the three legs from the cell's
    /// centre `centre` to `to`. A crossing h of a leg counts when from < h
    /// <= to, and counts negated when to < h <= from (as the sweep counts
    /// them).
    ///
    /// One pass over the triangles serves the three legs: a triangle whose
    /// plane the legs' box lies wholly beside is passed by first, with its
    /// stored plane alone; for the rest, the bounds say at once which legs'
    /// lines may pass through it (most miss all three), where a pass per
    /// leg branched on every triangle thrice. The sum is of integers, so
    /// the order does not change it.
    #[inline]
    fn crossings(&self, centre: Vec3) -> i32 {
        let p = self.to;
        // where each leg starts: it runs along its axis from there
        let starts = [
            centre,
            Vec3::new(p.x, centre.y, centre.z),
            Vec3::new(p.x, p.y, centre.z),
        ];
        let span = |axis: usize| {
            let (from, to) = (starts[axis][axis], p[axis]);
            if from <= to {
                (from, to, 1)
            } else {
                (to, from, -1)
            }
        };
        let spans = [span(0), span(1), span(2)];
        let (q1, q2) = (Vec3A::from(starts[1]), Vec3A::from(starts[2]));
        // the box of the legs (padded against rounding), whose sides a
        // triangle's plane must not leave all on one side
        let shape = &self.body.shape;
        let cell = 1.0 / shape.inv_cell;
        let mid = Vec3A::from((centre + p) * 0.5);
        let half = Vec3A::from((p - centre).abs() * 0.5 + Vec3::splat(1e-3 * cell));
        // a counted crossing lies on a leg, in the box, and (as computed)
        // within the plane's slack of it: a plane farther from the box's
        // middle than the box reaches has none (the legs of most points in
        // a cell pass its triangles by)
        let culled = |t: &Stored| {
            let n = t.normal();
            let reach = n.abs().dot(half) + t.slack();
            #[cfg(test)]
            let reach = if UNCULLED.with(|u| u.get()) {
                f32::INFINITY
            } else {
                reach
            };
            let culled = libm::fabsf(n.dot(mid - t.corner_a())) > reach;
            #[cfg(test)]
            CULLED.with(|c| c.set(c.get() + culled as usize));
            culled
        };
        let share = |t: &Stored| {
            let (lo, hi) = t.bounds();
            let within = |q: Vec3A| (lo.cmple(q) & q.cmple(hi)).bitmask();
            // leg 0's line is (y, z) of starts[1], leg 1's (x, z) of it,
            // leg 2's (x, y) of starts[2]
            let (a, b) = (within(q1), within(q2));
            if a & 6 != 6 && a & 5 != 5 && b & 3 != 3 {
                return 0;
            }
            let mut w = 0;
            if a & 6 == 6 {
                w += counted(crossing_within::<0>(t, starts[0]), spans[0]);
            }
            if a & 5 == 5 {
                w += counted(crossing_within::<1>(t, starts[1]), spans[1]);
            }
            if b & 3 == 3 {
                w += counted(crossing_within::<2>(t, starts[2]), spans[2]);
            }
            w
        };
        // the cell's own triangles, then the caps (none in most cells): the
        // cheap plane cull inline, the bounds and crossings apart for the
        // few left
        let mut w = 0;
        for &t in self.listed {
            let t = &self.body.triangles[t as usize];
            if !culled(t) {
                w += share(t);
            }
        }
        let near = self.met.iter().map(|&t| &self.body.caps[t as usize]);
        for t in self.caps.iter().chain(near) {
            if !culled(t) {
                w += share(t);
            }
        }
        w
    }
}

#[cfg(test)]
std::thread_local! {
    /// Queries on this thread test every triangle whose bounds a leg's
    /// line meets, as before the planes culled them: the reference the
    /// culled queries are compared with.
    static UNCULLED: core::cell::Cell<bool> = const { core::cell::Cell::new(false) };
    /// Triangles the planes culled on this thread.
    static CULLED: core::cell::Cell<usize> = const { core::cell::Cell::new(0) };
    /// Queries on this thread decide near a cap by [`Body::caps_exact`]
    /// alone, and bodies built on it mark near-cap cells by the cap count
    /// alone, as before [`fan_angle`] and the summed bounds: the reference
    /// the fast answers are compared with.
    static EXACT_CAPS: core::cell::Cell<bool> = const { core::cell::Cell::new(false) };
    /// Near-cap queries on this thread: left to the exact evaluation,
    /// settled fast, settled by the bounds alone.
    static FAST: core::cell::Cell<[usize; 3]> = const { core::cell::Cell::new([0; 3]) };
}

/// How far from a triangle's plane, in units of its computed normal `n`
/// (as `n . (x - corner)` measures), a crossing [`crossing_within`]
/// computes may seem to lie, for a triangle whose longest edge squared is
/// `e2` in a grid of cells `1 / inv_cell` wide. `n`, a cross product of
/// differences, rounds by ~3 units in the last place of |e|^2 in each
/// component, and that error grows with the distance from the corner it
/// is measured at: up to the triangle's size and two cells (a crossing in
/// a cell the triangle's bounds reach). A computed crossing also lies off
/// the plane by up to ~12 units of |e|^3 (its weights round like n). A
/// thin triangle's crossings stray the most.
#[inline]
fn stray(e2: f32, inv_cell: f32) -> f32 {
    64.0 * f32::EPSILON * e2 * (libm::sqrtf(e2) + 2.0 / inv_cell)
}

/// A leg's share of a crossing `(h, step)` on its span `(lo, hi, sign)`.
#[inline]
fn counted(crossing: Option<(f32, i32)>, (lo, hi, sign): (f32, f32, i32)) -> i32 {
    match crossing {
        Some((h, step)) if lo < h && h <= hi => sign * step,
        _ => 0,
    }
}

/// Where the line through `p` along axis `AXIS` crosses triangle `t` (that
/// coordinate), if it passes through it, and how the winding number changes
/// there going along the axis: +1 entering the triangle's back (its normal
/// against the axis), -1 leaving through its front. The coordinates are
/// rotated so `AXIS` comes first; every triangle sharing an edge rotates it
/// alike. For a line within the triangle's bounds on the other two axes:
/// one strictly outside them misses the triangle, perturbed or not, and the
/// callers pass it by first (most lines through a cell miss most of its
/// triangles).
#[inline]
fn crossing_within<const AXIS: usize>(t: &Stored, p: Vec3) -> Option<(f32, i32)> {
    let (j, k) = ((AXIS + 1) % 3, (AXIS + 2) % 3);
    let [a, b, c] = t.corners();
    let turn = |v: [f32; 3]| [v[AXIS], v[j], v[k]];
    let (a, b, c, p) = (turn(a), turn(b), turn(c), turn(p.to_array()));
    // the edges b -> c, c -> a, a -> b in lanes 0, 1, 2
    let from = [b, c, a];
    let to = [c, a, b];
    let gather = |v: &[[f32; 3]; 3], i: usize| f32x4::from([v[0][i], v[1][i], v[2][i], 0.0]);
    let (w, positive) = edges(
        [gather(&from, 1), gather(&from, 2)],
        [gather(&to, 1), gather(&to, 2)],
        [p[1], p[2]],
    );
    let sides = positive & 7;
    if sides != 0 && sides != 7 {
        return None;
    }
    let [w0, w1, w2, _] = w.to_array();
    let sum = w0 + w1 + w2;
    let step = if sides == 7 { -1 } else { 1 };
    Some(((w0 * a[0] + w1 * b[0] + w2 * c[0]) / sum, step))
}

/// The edge functions of `p` against the edges `from -> to` (y and z of
/// each, an edge per lane) in the plane of those two coordinates, and a
/// bit per lane for the side `p` is on. Each is evaluated with the edge's
/// endpoints in a canonical order (the lower (y, z) first), so the
/// neighbour across an edge sees its exact negation; on an exact zero the
/// side is the one a fixed infinitesimal shift of `p`, (0, -eps^2, eps),
/// would give, so a point on an edge belongs to exactly one of its
/// triangles. In the canonical order the edge's dy is >= 0, and dz >= 0
/// where dy is 0: that shift then puts `p` on the positive side of every
/// edge but a point's.
#[inline]
fn edges(from: [f32x4; 2], to: [f32x4; 2], p: [f32; 2]) -> (f32x4, i32) {
    let zero = f32x4::ZERO;
    let swap = from[0].cmp_gt(to[0]) | (from[0].cmp_eq(to[0]) & from[1].cmp_gt(to[1]));
    let (ly, lz) = (swap.blend(to[0], from[0]), swap.blend(to[1], from[1]));
    let (hy, hz) = (swap.blend(from[0], to[0]), swap.blend(from[1], to[1]));
    let (dy, dz) = (hy - ly, hz - lz);
    let e = dy * (f32x4::splat(p[1]) - lz) - dz * (f32x4::splat(p[0]) - ly);
    let positive = e.cmp_gt(zero) | (e.cmp_eq(zero) & (dy.cmp_ne(zero) | dz.cmp_ne(zero)));
    // negated by its sign bit (wide's `-e` is `0 - e`, which loses -0)
    let negated = e ^ f32x4::splat(-0.0);
    (swap.blend(negated, e), (positive ^ swap).move_mask())
}

/// The signed solid angle triangle `t` subtends at `p` (Van Oosterom and
/// Strackee), positive when `p` sees its back.
fn solid_angle(t: &Stored, p: Vec3) -> f64 {
    let [a, b, c] = t.corners().map(|corner| {
        let v = Vec3::from(corner) - p;
        glam::DVec3::new(v.x as f64, v.y as f64, v.z as f64)
    });
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let det = a.dot(b.cross(c));
    let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * libm::atan2(det, den)
}

/// A corner of a cap triangle seen from `p`, as [`solid_angle`] takes it
/// (the difference rounded to f32 first): the vector, its length, and its
/// reciprocal.
#[derive(Clone, Copy)]
struct Seen {
    at: [f32; 3],
    v: glam::DVec3,
    length: f64,
    inverse: f64,
}

impl Seen {
    #[inline]
    fn new(at: [f32; 3], p: Vec3) -> Self {
        let v = Vec3::from(at) - p;
        let v = glam::DVec3::new(v.x as f64, v.y as f64, v.z as f64);
        let length = v.length();
        Seen {
            at,
            v,
            length,
            inverse: 1.0 / length,
        }
    }
}

/// The signed solid angle the cap triangles `fan` subtend at `p` (the sum
/// of [`solid_angle`] over them), and a bound on its error: each
/// triangle's `2 atan2(det, den)` is not taken, the arguments `(den, det)`
/// (scaled to the unit sphere) are multiplied up as complex numbers, whole
/// turns counted as the product goes round, and one arctangent taken at the
/// end. Corners shared with the previous triangle (a fan's centre, the
/// rim corner consecutive triangles share) are seen once. `None` when an
/// argument or the running product lies so near the negative real axis, or
/// an argument so near zero (`p` on a triangle's edge line), that rounding
/// could move a turn: the caller evaluates exactly then.
fn fan_angle(fan: &[Stored], p: Vec3) -> Option<(f64, f64)> {
    // relative closeness to the negative real axis, and smallest scaled
    // argument, taken as doubtful: each keeps an argument's rounding
    // (~1e-15 of its terms) below ~1e-12 of a radian
    const AXIS: f64 = 1e-6;
    const SMALLEST: f64 = 1e-3;
    let (mut re, mut im, mut turns) = (1.0f64, 0.0f64, 0i64);
    let mut seen: Option<[Seen; 3]> = None;
    for (k, t) in fan.iter().enumerate() {
        let [b, a, m] = t.corners();
        let look = |at: [f32; 3], before: Option<Seen>| match before {
            Some(s) if s.at.map(f32::to_bits) == at.map(f32::to_bits) => s,
            _ => Seen::new(at, p),
        };
        // this triangle's first corner is often the last one's second,
        // and every triangle of a cap shares its third
        let (sb, sa, sm) = match seen {
            Some([lb, _, lm]) => (Seen::new(b, p), look(a, Some(lb)), look(m, Some(lm))),
            None => (Seen::new(b, p), Seen::new(a, p), Seen::new(m, p)),
        };
        seen = Some([sb, sa, sm]);
        if sb.length == 0.0 || sa.length == 0.0 || sm.length == 0.0 {
            return None;
        }
        // solid_angle's terms for (b, a, m), over the three lengths
        let (vb, va, vm) = (sb.v, sa.v, sm.v);
        let scale = sb.inverse * sa.inverse * sm.inverse;
        let det = vb.dot(va.cross(vm)) * scale;
        let den = (sb.length * sa.length * sm.length
            + vb.dot(va) * sm.length
            + vb.dot(vm) * sa.length
            + va.dot(vm) * sb.length)
            * scale;
        if det * det + den * den < SMALLEST * SMALLEST
            || (den < 0.0 && libm::fabs(det) <= AXIS * -den)
        {
            return None;
        }
        let (r, i) = (re * den - im * det, re * det + im * den);
        // the arguments add within (-2 pi, 2 pi]: past pi when both were
        // in the upper half-plane and the product is in the lower one
        if im >= 0.0 && det >= 0.0 && i < 0.0 {
            turns += 1;
        } else if im < 0.0 && det < 0.0 && i >= 0.0 {
            turns -= 1;
        }
        if r < 0.0 && libm::fabs(i) <= AXIS * -r {
            return None;
        }
        (re, im) = (r, i);
        // each factor is at most 4 and at least 1e-3 in size
        if k % 64 == 63 {
            let size = libm::fabs(re).max(libm::fabs(im));
            (re, im) = (re / size, im / size);
        }
    }
    let angle = 2.0 * (libm::atan2(im, re) + core::f64::consts::TAU * turns as f64);
    Some((angle, 1e-10 * (fan.len() as f64 + 1.0)))
}

#[cfg(test)]
mod tests;
