//! The body as a solid, for point-in-body queries (collisions).
//!
//! A uniform grid over the mesh triangles. Every cell centre's parity (inside
//! or outside) is found once, by one sweep along x through each row of
//! centres that counts the crossings between consecutive centres. A point in
//! a cell no triangle touches takes its cell's class by a lookup; a point in
//! a cell the surface passes through takes the centre's parity, flipped by
//! each crossing of a three-leg path (along x, y, then z) from the centre to
//! the point, all inside the cell, so only that cell's triangles are tested.
//!
//! Crossings are counted watertight: edge functions are evaluated with the
//! edge's endpoints in a canonical order, so the two triangles sharing an
//! edge see exactly opposite values, and a line through an edge or a vertex
//! is settled by a fixed symbolic perturbation of the line. A line through a
//! shared edge thus crosses exactly one of the two triangles, whatever the
//! rounding. The mesh should be closed; an open mesh answers by the parity
//! the holes leave.

use crate::arena::{Arena, ArenaLayout};
use crate::surface::grid::floor_i32;
use crate::{Error, Mesh};
use glam::Vec3;

/// Cells per triangle the grid aims at (finer grids answer more points by lookup).
const CELLS_PER_TRIANGLE: f32 = 32.0;
/// Most cells along one axis.
const MAX_DIM: f32 = 1024.0;

/// Cell classes: a cell the surface misses is wholly outside or inside; a
/// cell it passes through keeps its centre's parity.
const OUTSIDE: u8 = 0;
const INSIDE: u8 = 1;
const SURFACE_OUTSIDE: u8 = 2;
const SURFACE_INSIDE: u8 = 3;

/// Grid placement, computed the same way when sizing and when building.
#[derive(Clone, Copy, Debug)]
struct Shape {
    origin: Vec3,
    inv_cell: f32,
    dims: [usize; 3],
    /// Triangle references over all cells.
    refs: usize,
    triangles: usize,
    /// The bounds of the mesh.
    lo: Vec3,
    hi: Vec3,
}

impl Shape {
    fn of(mesh: &Mesh) -> Result<Shape, Error> {
        mesh.validate()?;
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let mut triangles = 0;
        for f in (0..mesh.triangle_count()).filter(|&f| !mesh.is_degenerate(f)) {
            for c in mesh.corners(f) {
                (lo, hi) = (lo.min(c), hi.max(c));
            }
            triangles += 1;
        }
        if triangles == 0 {
            return Err(Error::InvalidArgument(
                "a body needs at least one non-degenerate triangle",
            ));
        }
        let extent = hi - lo;
        let volume = extent.x.max(1e-30) * extent.y.max(1e-30) * extent.z.max(1e-30);
        let cell = libm::cbrtf(volume / (CELLS_PER_TRIANGLE * triangles as f32))
            .max(extent.max_element() / MAX_DIM);
        if !(cell.is_finite() && cell > 0.0) {
            return Err(Error::InvalidArgument("body extent is not finite"));
        }
        let inv_cell = 1.0 / cell;
        // one empty layer before and at least one after every triangle
        let dim = |e: f32| (e * inv_cell) as usize + 4;
        let mut shape = Shape {
            origin: lo - Vec3::splat(cell),
            inv_cell,
            dims: [dim(extent.x), dim(extent.y), dim(extent.z)],
            refs: 0,
            triangles,
            lo,
            hi,
        };
        for f in (0..mesh.triangle_count()).filter(|&f| !mesh.is_degenerate(f)) {
            let [a, b, c] = mesh.corners(f);
            let (a, b) = shape.cell_range(a.min(b).min(c), a.max(b).max(c));
            shape.refs += (0..3).map(|k| b[k] - a[k] + 1).product::<usize>();
        }
        Ok(shape)
    }

    fn cells(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// The cell of `p` along each axis (may be out of the grid).
    #[inline]
    fn cell_of(&self, p: Vec3) -> [i32; 3] {
        let q = (p - self.origin) * self.inv_cell;
        [floor_i32(q.x), floor_i32(q.y), floor_i32(q.z)]
    }

    /// The cell of coordinate `v` along `axis` (may be out of the grid).
    #[inline]
    fn cell_on(&self, v: f32, axis: usize) -> i32 {
        floor_i32((v - self.origin[axis]) * self.inv_cell)
    }

    /// Cells the bounds `lo`..`hi` of a triangle touch, padded by a
    /// thousandth of a cell so that a crossing computed with rounding still
    /// lands in a listed cell.
    fn cell_range(&self, lo: Vec3, hi: Vec3) -> ([usize; 3], [usize; 3]) {
        let pad = Vec3::splat(1e-3 / self.inv_cell);
        let (lo, hi) = (self.cell_of(lo - pad), self.cell_of(hi + pad));
        let clamp = |v: i32, k: usize| v.clamp(0, self.dims[k] as i32 - 1) as usize;
        (
            [clamp(lo[0], 0), clamp(lo[1], 1), clamp(lo[2], 2)],
            [clamp(hi[0], 0), clamp(hi[1], 1), clamp(hi[2], 2)],
        )
    }

    #[inline]
    fn index(&self, x: usize, y: usize, z: usize) -> usize {
        (z * self.dims[1] + y) * self.dims[0] + x
    }
}

/// The mesh as a solid, in caller-provided memory.
pub struct Body<'a> {
    shape: Shape,
    /// Triangle list of cell `c`: `refs[start[c]..start[c + 1]]`.
    start: &'a [u32],
    refs: &'a [u32],
    /// The non-degenerate triangles, copied for locality.
    triangles: &'a [Stored],
    class: &'a [u8],
}

/// The grid a mesh's body will have, worked out before its memory is
/// found: [`BodyPlan::bytes`] to size the arena, then [`Body::build`].
#[derive(Clone, Copy, Debug)]
pub struct BodyPlan {
    shape: Shape,
}

impl BodyPlan {
    /// Validates `mesh` and places the grid.
    pub fn of(mesh: &Mesh) -> Result<Self, Error> {
        let shape = Shape::of(mesh)?;
        if shape.refs >= u32::MAX as usize {
            return Err(Error::InvalidArgument("body grid is too large"));
        }
        Ok(BodyPlan { shape })
    }

    /// Arena bytes [`Body::build`] needs.
    pub fn bytes(&self) -> usize {
        let (shape, cells) = (&self.shape, self.shape.cells());
        let mut layout = ArenaLayout::new();
        layout
            .add::<u32>(cells + 1)
            .add::<u32>(shape.refs)
            .add::<Stored>(shape.triangles)
            .add::<u8>(cells);
        layout.bytes()
    }
}

impl<'a> Body<'a> {
    /// Arena bytes [`Body::new`] needs for `mesh` (validates it).
    pub fn required_bytes(mesh: &Mesh) -> Result<usize, Error> {
        Ok(BodyPlan::of(mesh)?.bytes())
    }

    /// Validates `mesh` and builds its grid and cell classes.
    pub fn new(mesh: &Mesh, arena: &mut Arena<'a>) -> Result<Self, Error> {
        Self::build(&BodyPlan::of(mesh)?, mesh, arena)
    }

    /// Builds the grid and cell classes of `mesh`, placed by `plan` (made
    /// from this mesh).
    pub fn build(plan: &BodyPlan, mesh: &Mesh, arena: &mut Arena<'a>) -> Result<Self, Error> {
        let shape = plan.shape;
        let needed = plan.bytes();
        if arena.remaining() < needed {
            return Err(Error::CapacityExceeded {
                needed: arena.capacity() - arena.remaining() + needed,
                available: arena.capacity(),
            });
        }
        let cells = shape.cells();
        let start = arena.alloc::<u32>(cells + 1)?;
        let refs = arena.alloc::<u32>(shape.refs)?;
        let triangles = arena.alloc::<Stored>(shape.triangles)?;
        let class = arena.alloc::<u8>(cells)?;

        let another = Error::InvalidArgument("body plan made from another mesh");
        let mut solid = (0..mesh.triangle_count()).filter(|&f| !mesh.is_degenerate(f));
        for t in triangles.iter_mut() {
            let [a, b, c] = mesh.corners(solid.next().ok_or(another)?);
            let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
            if !(lo.cmpge(shape.lo).all() && hi.cmple(shape.hi).all()) {
                return Err(another);
            }
            *t = [a, b, c, lo, hi].map(Into::into);
        }
        if solid.next().is_some() {
            return Err(another);
        }
        // counting sort of triangle references by cell
        start.fill(0);
        let each_cell = |t: usize, visit: &mut dyn FnMut(usize)| {
            let [.., lo, hi] = triangles[t];
            let (a, b) = shape.cell_range(lo.into(), hi.into());
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        visit(shape.index(x, y, z));
                    }
                }
            }
        };
        // counts, summed in place to each cell's end, then filled
        // backwards so each ends at its cell's start
        for t in 0..shape.triangles {
            each_cell(t, &mut |c| start[c] += 1);
        }
        let mut sum = 0u64;
        for s in start[..cells].iter_mut() {
            sum += u64::from(*s);
            *s = sum as u32;
        }
        if sum != shape.refs as u64 {
            return Err(another);
        }
        start[cells] = sum as u32;
        for t in 0..shape.triangles {
            each_cell(t, &mut |c| {
                start[c] -= 1;
                refs[start[c] as usize] = t as u32;
            });
        }
        let mut body = Body {
            shape,
            start,
            refs,
            triangles,
            class: &[],
        };
        body.classify(class);
        body.class = class;
        Ok(body)
    }

    /// The triangles listed in cell `c`.
    #[inline]
    fn listed(&self, c: usize) -> impl Iterator<Item = &Stored> {
        self.refs[self.start[c] as usize..self.start[c + 1] as usize]
            .iter()
            .map(|&t| &self.triangles[t as usize])
    }

    /// The centre of cell `(x, y, z)`.
    fn centre(&self, x: usize, y: usize, z: usize) -> Vec3 {
        self.shape.origin
            + Vec3::new(x as f32 + 0.5, y as f32 + 0.5, z as f32 + 0.5) / self.shape.inv_cell
    }

    /// Sweeps each row of cell centres along x from the grid's empty first
    /// layer (outside), flipping the parity at each crossing. Each
    /// triangle's crossings with the rows' lines are marked first, in the
    /// cell each falls in, as before or after that cell's centre.
    fn classify(&self, class: &mut [u8]) {
        const BEFORE: u8 = 4;
        const AFTER: u8 = 8;
        let shape = &self.shape;
        class.fill(0);
        for t in self.triangles {
            let [.., lo, hi] = *t;
            // the rows whose line may pass within the bounds (one more each
            // way: `crossing` decides exactly)
            let first = shape.cell_of(Vec3::from(lo) - 0.5 / shape.inv_cell);
            let last = shape.cell_of(Vec3::from(hi) - 0.5 / shape.inv_cell);
            let rows = |k: usize| {
                let n = shape.dims[k] as i32;
                first[k].clamp(0, n - 1) as usize..=(last[k] + 1).clamp(0, n - 1) as usize
            };
            for z in rows(2) {
                for y in rows(1) {
                    let Some(h) = crossing::<0>(t, self.centre(0, y, z)) else {
                        continue;
                    };
                    let x = shape.cell_on(h, 0);
                    if (0..shape.dims[0] as i32).contains(&x) {
                        let x = x as usize;
                        class[shape.index(x, y, z)] ^= if h <= self.centre(x, y, z).x {
                            BEFORE
                        } else {
                            AFTER
                        };
                    }
                }
            }
        }
        let nx = shape.dims[0];
        for (r, row) in class.chunks_exact_mut(nx).enumerate() {
            let mut odd = false;
            // a cell the surface passes through lists triangles
            let listed = self.start[r * nx..=(r + 1) * nx].windows(2);
            for (flips, ends) in row.iter_mut().zip(listed) {
                let f = *flips;
                odd ^= f & BEFORE != 0;
                *flips = match (ends[0] != ends[1], odd) {
                    (false, false) => OUTSIDE,
                    (false, true) => INSIDE,
                    (true, false) => SURFACE_OUTSIDE,
                    (true, true) => SURFACE_INSIDE,
                };
                odd ^= f & AFTER != 0;
            }
        }
    }

    /// True when `p` is inside the body.
    pub fn contains(&self, p: Vec3) -> bool {
        let c = self.shape.cell_of(p);
        let inside = (0..3).all(|k| c[k] >= 0 && (c[k] as usize) < self.shape.dims[k]);
        if !inside {
            return false;
        }
        let cell = [c[0] as usize, c[1] as usize, c[2] as usize];
        let c = self.shape.index(cell[0], cell[1], cell[2]);
        match self.class[c] {
            OUTSIDE => false,
            INSIDE => true,
            class => {
                // the path centre -> (p.x, centre.y, centre.z) -> (p.x, p.y,
                // centre.z) -> p, a leg per axis, with each crossing h of a
                // leg from `from` to `to` counted when from < h <= to or
                // to < h <= from (as the sweep counts them)
                let mut at = self.centre(cell[0], cell[1], cell[2]);
                let mut odd = class == SURFACE_INSIDE;
                let mut leg = |axis: usize, hit: &dyn Fn(&Stored, Vec3) -> Option<f32>| {
                    let (lo, hi) = (at[axis].min(p[axis]), at[axis].max(p[axis]));
                    for t in self.listed(c) {
                        if let Some(h) = hit(t, at) {
                            odd ^= lo < h && h <= hi;
                        }
                    }
                    at[axis] = p[axis];
                };
                leg(0, &crossing::<0>);
                leg(1, &crossing::<1>);
                leg(2, &crossing::<2>);
                odd
            }
        }
    }

    /// True when the segment from `a` to `b` meets a triangle of the body.
    /// Walks the grid cells the segment passes through, in order, from
    /// where it enters the grid to where it leaves it.
    pub fn blocks(&self, a: Vec3, b: Vec3) -> bool {
        let shape = &self.shape;
        let (from, to) = (
            (a - shape.origin) * shape.inv_cell,
            (b - shape.origin) * shape.inv_cell,
        );
        if !(from.is_finite() && to.is_finite()) {
            return false;
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
                    return false;
                }
                continue;
            }
            let (enter, leave) = ((0.0 - from[k]) / d[k], (dims[k] as f32 - from[k]) / d[k]);
            (t0, t1) = (t0.max(enter.min(leave)), t1.min(enter.max(leave)));
            (step[k], delta[k]) = (if d[k] > 0.0 { 1 } else { -1 }, 1.0 / libm::fabsf(d[k]));
        }
        if t0 > t1 {
            return false;
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
            let refs = &self.refs[self.start[c] as usize..self.start[c + 1] as usize];
            if refs
                .iter()
                .any(|&t| meets(&self.triangles[t as usize], a, b - a))
            {
                return true;
            }
            let k = if next[0] <= next[1] && next[0] <= next[2] {
                0
            } else if next[1] <= next[2] {
                1
            } else {
                2
            };
            cell[k] += step[k];
            if next[k] > t1 || !(0..dims[k]).contains(&cell[k]) {
                return false;
            }
            next[k] += delta[k];
        }
        false
    }
}

/// Whether the segment `a + t * d`, `t` in `[0, 1]`, meets triangle `t`
/// (Moller-Trumbore; a segment in the triangle's plane does not).
#[inline]
fn meets(t: &Stored, a: Vec3, d: Vec3) -> bool {
    let [p, q, r, ..] = t.map(Vec3::from);
    let (e1, e2) = (q - p, r - p);
    let h = d.cross(e2);
    let det = e1.dot(h);
    if det == 0.0 {
        return false;
    }
    let s = (a - p) / det;
    let u = s.dot(h);
    let w = s.cross(e1);
    let v = d.dot(w);
    let along = e2.dot(w);
    u >= 0.0 && v >= 0.0 && u + v <= 1.0 && (0.0..=1.0).contains(&along)
}

/// A triangle as stored: its three corners, then the low and the high
/// corner of its bounds.
type Stored = [[f32; 3]; 5];

/// Where the line through `p` along axis `AXIS` crosses triangle `t` (that
/// coordinate), if it passes through it. The coordinates are rotated so
/// `AXIS` comes first; every triangle sharing an edge rotates it alike.
#[inline]
fn crossing<const AXIS: usize>(t: &Stored, p: Vec3) -> Option<f32> {
    let (j, k) = ((AXIS + 1) % 3, (AXIS + 2) % 3);
    // a line strictly outside the triangle's bounds misses it, perturbed or
    // not; most lines through a cell miss most of its triangles
    let [.., lo, hi] = t;
    if p[j] < lo[j] || p[j] > hi[j] || p[k] < lo[k] || p[k] > hi[k] {
        return None;
    }
    let turn = |v: [f32; 3]| [v[AXIS], v[j], v[k]];
    let (a, b, c, p) = (turn(t[0]), turn(t[1]), turn(t[2]), turn(p.to_array()));
    let (w0, s0) = edge(b, c, p);
    let (w1, s1) = edge(c, a, p);
    let (w2, s2) = edge(a, b, p);
    if s0 != s1 || s1 != s2 {
        return None;
    }
    let sum = w0 + w1 + w2;
    Some((w0 * a[0] + w1 * b[0] + w2 * c[0]) / sum)
}

/// The edge function of `p` against edge `a -> b` in the plane of the last
/// two coordinates, and which side `p` is on. The value is evaluated with the
/// endpoints in a canonical order, so the neighbour across the edge sees its
/// exact negation; on an exact zero the side is the one a fixed infinitesimal
/// shift of `p`, (0, -eps^2, eps), would give, so a point on an edge belongs
/// to exactly one of its triangles.
#[inline]
fn edge(a: [f32; 3], b: [f32; 3], p: [f32; 3]) -> (f32, bool) {
    let swap = (a[1], a[2]) > (b[1], b[2]);
    let (a, b) = if swap { (b, a) } else { (a, b) };
    let (dy, dz) = (b[1] - a[1], b[2] - a[2]);
    let e = dy * (p[2] - a[2]) - dz * (p[1] - a[1]);
    let positive = if e != 0.0 {
        e > 0.0
    } else if dy != 0.0 {
        dy > 0.0
    } else {
        dz > 0.0
    };
    if swap {
        (-e, !positive)
    } else {
        (e, positive)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::{self, Purpose};
    use crate::testmesh::{graded_plane, sphere};

    fn build<'a>(mesh: &Mesh, buf: &'a mut Vec<u8>) -> Body<'a> {
        *buf = vec![0u8; Body::required_bytes(mesh).unwrap()];
        Body::new(mesh, &mut Arena::new(buf)).unwrap()
    }

    #[test]
    fn a_segment_is_blocked_where_it_meets_the_surface() {
        let m = sphere(24, 48);
        let mesh = m.mesh();
        let mut buf = vec![];
        let body = build(&mesh, &mut buf);
        let v = |x, y, z| Vec3::new(x, y, z);
        // through the sphere, into it, and out of it, along and across axes
        assert!(body.blocks(v(-2.0, 0.1, 0.2), v(2.0, 0.1, 0.2)));
        assert!(body.blocks(v(0.3, -1.5, 1.5), v(-0.2, 0.1, -0.1)));
        assert!(body.blocks(v(0.1, 0.2, 0.3), v(1.3, 1.2, -1.1)));
        // past it, short of it, and wholly inside it
        assert!(!body.blocks(v(-2.0, 1.2, 0.0), v(2.0, 1.2, 0.0)));
        assert!(!body.blocks(v(1.5, 1.5, 1.5), v(0.7, 0.7, 0.7)));
        assert!(!body.blocks(v(-0.5, 0.1, 0.2), v(0.5, -0.1, 0.0)));
        // from far outside the grid, and wholly outside it
        assert!(body.blocks(v(-1e4, 0.1, 0.2), v(1e4, 0.3, -0.2)));
        assert!(body.blocks(v(3e3, -2e3, 1e3), v(0.0, 0.0, 0.0)));
        assert!(!body.blocks(v(-1e4, 5.0, 0.0), v(1e4, 5.0, 0.0)));
        // a point, and segments with a NaN or infinite end, meet nothing
        assert!(!body.blocks(v(1.5, 0.0, 0.0), v(1.5, 0.0, 0.0)));
        assert!(!body.blocks(v(0.9, 0.1, 0.0), v(0.9, 0.1, 0.0)));
        assert!(!body.blocks(v(-2.0, 0.0, 0.0), v(f32::NAN, 0.0, 0.0)));
        assert!(!body.blocks(v(-2.0, 0.0, 0.0), v(f32::INFINITY, 0.0, 0.0)));
        // every chord between two points just outside opposite sides
        for i in 0..2000u64 {
            let r = |c| rng::unit(3, i, Purpose::Uniform, c) * 2.0 - 1.0;
            let dir = v(r(0), r(1), r(2)).normalize_or_zero();
            if dir == Vec3::ZERO {
                continue;
            }
            assert!(body.blocks(dir * 1.01, -dir * 1.01), "{dir}");
            assert!(!body.blocks(dir * 1.01, dir * 1.5), "{dir}");
        }
    }

    #[test]
    fn sphere_inside_matches_the_radius() {
        let m = sphere(24, 48);
        let mesh = m.mesh();
        let mut buf = vec![];
        let body = build(&mesh, &mut buf);
        // the polyhedron lies between the inscribed and circumscribed radii
        let inner = (0..mesh.triangle_count())
            .filter(|&f| !mesh.is_degenerate(f))
            .map(|f| {
                let [a, ..] = mesh.corners(f);
                mesh.face_normal(f).dot(a).abs()
            })
            .fold(f32::INFINITY, f32::min);
        let mut checked = 0;
        for i in 0..200_000u64 {
            let r = |c| rng::unit(7, i, Purpose::Uniform, c) * 2.4 - 1.2;
            let p = Vec3::new(r(0), r(1), r(2));
            let d = p.length();
            if d < inner - 1e-4 {
                assert!(body.contains(p), "{p} at {d} is inside");
                checked += 1;
            } else if d > 1.0 + 1e-4 {
                assert!(!body.contains(p), "{p} at {d} is outside");
                checked += 1;
            }
        }
        assert!(checked > 190_000);
        // points on the grid's own lattice and on mesh vertices do not break parity
        for &v in m.p.iter() {
            let p = Vec3::from(v) * 0.999;
            assert!(body.contains(p), "{p} just inside a vertex");
            assert!(!body.contains(Vec3::from(v) * 1.001));
            // rays along x through the vertex itself (and its edges' ends)
            if v[0].abs() > 0.3 {
                assert!(
                    body.contains(Vec3::new(0.0, v[1], v[2])),
                    "ray through {v:?}"
                );
                assert!(
                    !body.contains(Vec3::new(-1.2, v[1], v[2])),
                    "ray through {v:?}"
                );
            }
        }
    }

    #[test]
    fn open_and_degenerate_meshes() {
        let m = graded_plane(8, 1.0);
        let mesh = m.mesh();
        let mut buf = vec![];
        let body = build(&mesh, &mut buf);
        // a plane encloses nothing
        for p in [Vec3::new(0.5, 0.5, 0.01), Vec3::new(0.3, 0.7, -0.01)] {
            assert!(!body.contains(p));
        }
        let p = [[0.0f32; 3]; 3];
        let t = [[0u32, 1, 2]];
        let flat = Mesh::new(
            crate::Strided::from_slice(&p),
            crate::Strided::from_slice(&t),
        );
        assert!(matches!(
            Body::required_bytes(&flat),
            Err(Error::InvalidArgument(_))
        ));
        // a plan from another mesh is refused, not trusted
        let other = sphere(8, 16);
        let plan = BodyPlan::of(&other.mesh()).unwrap();
        let mut big = vec![0u8; plan.bytes().max(Body::required_bytes(&mesh).unwrap())];
        assert!(matches!(
            Body::build(&plan, &mesh, &mut Arena::new(&mut big)),
            Err(Error::InvalidArgument(_))
        ));
        let mut small = vec![0u8; Body::required_bytes(&mesh).unwrap() - 1];
        assert!(matches!(
            Body::new(&mesh, &mut Arena::new(&mut small)),
            Err(Error::CapacityExceeded { .. })
        ));
    }
}
