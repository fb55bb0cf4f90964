//! The body as a solid, for point-in-body queries (collisions).
//!
//! A uniform grid over the mesh triangles. Cells that no triangle touches are
//! classified once, inside or outside: each 6-connected group of empty cells
//! takes the parity of one exact ray from its first cell. A point in an empty
//! cell is answered by a lookup; a point in a cell the surface passes through
//! casts a ray along +x to the next empty cell and counts crossings.
//!
//! Crossings are counted watertight: edge functions are evaluated with the
//! edge's endpoints in a canonical order, so the two triangles sharing an
//! edge see exactly opposite values, and a ray through an edge or a vertex is
//! settled by a fixed symbolic perturbation of the ray. A ray through a shared
//! edge thus crosses exactly one of the two triangles, whatever the rounding.
//! The mesh should be closed; an open mesh answers by the parity the holes leave.

use crate::arena::{Arena, ArenaLayout};
use crate::surface::grid::floor_i32;
use crate::{Error, Mesh};
use glam::Vec3;

/// Cells per triangle the grid aims at (finer grids answer more points by lookup).
const CELLS_PER_TRIANGLE: f32 = 4.0;
/// Most cells along one axis.
const MAX_DIM: f32 = 1024.0;

const UNKNOWN: u8 = 0;
const OUTSIDE: u8 = 1;
const INSIDE: u8 = 2;
const SURFACE: u8 = 3;

/// Grid placement, computed the same way when sizing and when building.
#[derive(Clone, Copy, Debug)]
struct Shape {
    origin: Vec3,
    inv_cell: f32,
    dims: [usize; 3],
    /// Triangle references over all cells.
    refs: usize,
    triangles: usize,
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
        };
        for f in (0..mesh.triangle_count()).filter(|&f| !mesh.is_degenerate(f)) {
            let (a, b) = shape.cell_range(mesh.corners(f));
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

    /// Cells a triangle's bounds touch, padded by a thousandth of a cell so
    /// that a crossing computed with rounding still lands in a listed cell.
    fn cell_range(&self, corners: [Vec3; 3]) -> ([usize; 3], [usize; 3]) {
        let [a, b, c] = corners;
        let pad = Vec3::splat(1e-3 / self.inv_cell);
        let lo = self.cell_of(a.min(b).min(c) - pad);
        let hi = self.cell_of(a.max(b).max(c) + pad);
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
    /// Corners of the non-degenerate triangles, copied for locality.
    corners: &'a [[[f32; 3]; 3]],
    class: &'a [u8],
}

impl<'a> Body<'a> {
    /// Arena bytes [`Body::new`] needs for `mesh` (validates it).
    pub fn required_bytes(mesh: &Mesh) -> Result<usize, Error> {
        let shape = Shape::of(mesh)?;
        Ok(Self::layout(&shape).bytes())
    }

    fn layout(shape: &Shape) -> ArenaLayout {
        let cells = shape.cells();
        let mut layout = ArenaLayout::new();
        layout
            .add::<u32>(cells + 1)
            .add::<u32>(shape.refs)
            .add::<[[f32; 3]; 3]>(shape.triangles)
            .add::<u8>(cells)
            .add::<u32>(cells);
        layout
    }

    /// Validates `mesh` and builds its grid and cell classes.
    pub fn new(mesh: &Mesh, arena: &mut Arena<'a>) -> Result<Self, Error> {
        let shape = Shape::of(mesh)?;
        if shape.refs >= u32::MAX as usize {
            return Err(Error::InvalidArgument("body grid is too large"));
        }
        let needed = Self::layout(&shape).bytes();
        if arena.remaining() < needed {
            return Err(Error::CapacityExceeded {
                needed: arena.capacity() - arena.remaining() + needed,
                available: arena.capacity(),
            });
        }
        let cells = shape.cells();
        let start = arena.alloc::<u32>(cells + 1)?;
        let refs = arena.alloc::<u32>(shape.refs)?;
        let corners = arena.alloc::<[[f32; 3]; 3]>(shape.triangles)?;
        let class = arena.alloc::<u8>(cells)?;
        let queue = arena.alloc::<u32>(cells)?;

        let solid = (0..mesh.triangle_count()).filter(|&f| !mesh.is_degenerate(f));
        for (t, f) in solid.clone().enumerate() {
            corners[t] = mesh.corners(f).map(Into::into);
        }
        // counting sort of triangle references by cell
        start.fill(0);
        let each_cell = |t: usize, visit: &mut dyn FnMut(usize)| {
            let (a, b) = shape.cell_range(corners[t].map(Vec3::from));
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        visit(shape.index(x, y, z));
                    }
                }
            }
        };
        for t in 0..shape.triangles {
            each_cell(t, &mut |c| start[c + 1] += 1);
        }
        for c in 0..cells {
            start[c + 1] += start[c];
        }
        for t in 0..shape.triangles {
            each_cell(t, &mut |c| {
                refs[start[c] as usize] = t as u32;
                start[c] += 1;
            });
        }
        for c in (1..=cells).rev() {
            start[c] = start[c - 1];
        }
        start[0] = 0;
        for c in 0..cells {
            class[c] = if start[c + 1] > start[c] {
                SURFACE
            } else {
                UNKNOWN
            };
        }
        let mut body = Body {
            shape,
            start,
            refs,
            corners,
            class: &[],
        };
        body.classify(class, queue);
        body.class = class;
        Ok(body)
    }

    /// Gives each 6-connected group of empty cells the class of its first
    /// cell, found by an exact ray from that cell's centre.
    fn classify(&self, class: &mut [u8], queue: &mut [u32]) {
        let [nx, ny, nz] = self.shape.dims;
        let cell = 1.0 / self.shape.inv_cell;
        for seed in 0..class.len() {
            if class[seed] != UNKNOWN {
                continue;
            }
            let (x, y, z) = (seed % nx, seed / nx % ny, seed / (nx * ny));
            let centre = self.shape.origin
                + Vec3::new(x as f32 + 0.5, y as f32 + 0.5, z as f32 + 0.5) * cell;
            let value = if self.ray_parity(centre, [x, y, z], class) {
                INSIDE
            } else {
                OUTSIDE
            };
            class[seed] = value;
            queue[0] = seed as u32;
            let (mut head, mut tail) = (0, 1);
            while head < tail {
                let c = queue[head] as usize;
                head += 1;
                let (x, y, z) = (c % nx, c / nx % ny, c / (nx * ny));
                let mut visit = |n: usize| {
                    if class[n] == UNKNOWN {
                        class[n] = value;
                        queue[tail] = n as u32;
                        tail += 1;
                    }
                };
                if x > 0 {
                    visit(c - 1);
                }
                if x + 1 < nx {
                    visit(c + 1);
                }
                if y > 0 {
                    visit(c - nx);
                }
                if y + 1 < ny {
                    visit(c + nx);
                }
                if z > 0 {
                    visit(c - nx * ny);
                }
                if z + 1 < nz {
                    visit(c + nx * ny);
                }
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
        match self.class[self.shape.index(cell[0], cell[1], cell[2])] {
            INSIDE => true,
            OUTSIDE => false,
            _ => self.ray_parity(p, cell, self.class),
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
                .any(|&t| meets(&self.corners[t as usize], a, b - a))
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

    /// Walks the row of `cell` along +x from `p` to the first cell already
    /// classified inside or outside (or off the grid, outside), and returns
    /// whether `p` is inside: that cell's class flipped by each crossing.
    fn ray_parity(&self, p: Vec3, cell: [usize; 3], class: &[u8]) -> bool {
        let [x0, y, z] = cell;
        let mut odd = false;
        for x in x0..self.shape.dims[0] {
            let c = self.shape.index(x, y, z);
            match class[c] {
                INSIDE => return !odd,
                OUTSIDE => return odd,
                _ => {}
            }
            for &t in &self.refs[self.start[c] as usize..self.start[c + 1] as usize] {
                if let Some(hit_x) = crossing(&self.corners[t as usize], p) {
                    // a triangle listed in several cells is counted in the
                    // one cell its crossing falls in
                    let hx = floor_i32((hit_x - self.shape.origin.x) * self.shape.inv_cell);
                    odd ^= hit_x > p.x && hx == x as i32;
                }
            }
        }
        odd
    }
}

/// Whether the segment `a + t * d`, `t` in `[0, 1]`, meets triangle `t`
/// (Moller-Trumbore; a segment in the triangle's plane does not).
#[inline]
fn meets(t: &[[f32; 3]; 3], a: Vec3, d: Vec3) -> bool {
    let [p, q, r] = t.map(Vec3::from);
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

/// Where the ray from `p` along x crosses triangle `t` (its x), if the ray's
/// line passes through it.
#[inline]
fn crossing(t: &[[f32; 3]; 3], p: Vec3) -> Option<f32> {
    let [a, b, c] = *t;
    let (w0, s0) = edge(b, c, p);
    let (w1, s1) = edge(c, a, p);
    let (w2, s2) = edge(a, b, p);
    if s0 != s1 || s1 != s2 {
        return None;
    }
    let sum = w0 + w1 + w2;
    Some((w0 * a[0] + w1 * b[0] + w2 * c[0]) / sum)
}

/// The (y, z) edge function of `p` against edge `a -> b`, and which side `p`
/// is on. The value is evaluated with the endpoints in a canonical order, so
/// the neighbour across the edge sees its exact negation; on an exact zero
/// the side is the one a fixed infinitesimal shift of `p`, (0, -eps^2, eps),
/// would give, so a point on an edge belongs to exactly one of its triangles.
#[inline]
fn edge(a: [f32; 3], b: [f32; 3], p: Vec3) -> (f32, bool) {
    let swap = (a[1], a[2]) > (b[1], b[2]);
    let (a, b) = if swap { (b, a) } else { (a, b) };
    let (dy, dz) = (b[1] - a[1], b[2] - a[2]);
    let e = dy * (p.z - a[2]) - dz * (p.y - a[1]);
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
        let mut small = vec![0u8; Body::required_bytes(&mesh).unwrap() - 1];
        assert!(matches!(
            Body::new(&mesh, &mut Arena::new(&mut small)),
            Err(Error::CapacityExceeded { .. })
        ));
    }
}
