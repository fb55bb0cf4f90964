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
//! caps' solid angle is evaluated exactly.
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

/// Grid placement, computed the same way when sizing and when building.
#[derive(Clone, Copy, Debug)]
struct Shape {
    origin: Vec3,
    inv_cell: f32,
    dims: [usize; 3],
    triangles: usize,
    /// The bounds of the mesh.
    lo: Vec3,
    hi: Vec3,
}

impl Shape {
    /// The grid over the triangles of `mesh` that `solid` keeps (those
    /// not degenerate).
    fn of(mesh: &Mesh, density: f32, solid: impl Fn(usize) -> bool) -> Result<Shape, Error> {
        mesh.check()?;
        let mut bounds = SolidBounds::EMPTY;
        for f in (0..mesh.triangle_count()).filter(|&f| solid(f)) {
            bounds.add(mesh.corners(f));
        }
        Self::of_bounds(bounds, density)
    }

    /// The grid over triangles of bounds `bounds`.
    fn of_bounds(bounds: SolidBounds, density: f32) -> Result<Shape, Error> {
        let (lo, hi, triangles) = (Vec3::from(bounds.lo), Vec3::from(bounds.hi), bounds.count);
        if triangles == 0 {
            return Err(Error::InvalidArgument(
                "a body needs at least one non-degenerate triangle",
            ));
        }
        let extent = hi - lo;
        let volume = extent.x.max(1e-30) * extent.y.max(1e-30) * extent.z.max(1e-30);
        let cell =
            libm::cbrtf(volume / (density * triangles as f32)).max(extent.max_element() / MAX_DIM);
        if !(cell.is_finite() && cell > 0.0) {
            return Err(Error::InvalidArgument("body extent is not finite"));
        }
        let inv_cell = 1.0 / cell;
        // one empty layer before and at least one after every triangle
        let dim = |e: f32| (e * inv_cell) as usize + 4;
        Ok(Shape {
            origin: lo - Vec3::splat(cell),
            inv_cell,
            dims: [dim(extent.x), dim(extent.y), dim(extent.z)],
            triangles,
            lo,
            hi,
        })
    }

    /// The most triangle references the grid can hold for the triangles of
    /// `mesh` that `solid` keeps: every cell of each one's bounds (the
    /// count stage keeps those its plane passes through). Only to size
    /// memory before a build: a build counts its own.
    fn refs_bound(&self, mesh: &Mesh, solid: impl Fn(usize) -> bool) -> usize {
        (0..mesh.triangle_count())
            .filter(|&f| solid(f))
            .map(|f| {
                let [a, b, c] = mesh.corners(f);
                let (a, b) = self.cell_range(a.min(b).min(c), a.max(b).max(c));
                (0..3).map(|k| b[k] - a[k] + 1).product::<usize>()
            })
            .fold(0usize, usize::saturating_add)
    }

    /// The largest coordinate magnitude of the triangles' bounds, and two
    /// cells more: what rounding is measured against (surface cells lie
    /// within a cell of the bounds).
    fn reach(&self) -> f32 {
        self.lo.abs().max(self.hi.abs()).max_element() + 2.0 / self.inv_cell
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
        let pad = Vec3A::splat(1e-3 / self.inv_cell);
        let last = Vec3A::from(self.dims.map(|d| (d - 1) as f32));
        // clamped into the grid first, the coordinate's floor is its
        // truncation: the cell of `cell_of`, clamped
        let cell = |p: Vec3A| {
            let q = ((p - Vec3A::from(self.origin)) * self.inv_cell)
                .max(Vec3A::ZERO)
                .min(last);
            let [x, y, z, _] = f32x4::from(q.extend(0.0).to_array()).trunc_int().to_array();
            [x as usize, y as usize, z as usize]
        };
        (cell(Vec3A::from(lo) - pad), cell(Vec3A::from(hi) + pad))
    }

    #[inline]
    fn index(&self, x: usize, y: usize, z: usize) -> usize {
        (z * self.dims[1] + y) * self.dims[0] + x
    }

    /// The centre of cell `(x, y, z)`.
    fn centre(&self, x: usize, y: usize, z: usize) -> Vec3 {
        self.origin + Vec3::new(x as f32 + 0.5, y as f32 + 0.5, z as f32 + 0.5) / self.inv_cell
    }

    /// Cells in one layer (one z).
    fn layer_cells(&self) -> usize {
        self.dims[0] * self.dims[1]
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
    /// The caps' triangles, one per boundary edge (see the module docs).
    caps: &'a [Stored],
    /// Each cap's bounding ball and the end of its triangles in `caps`.
    loops: &'a [CapBall],
    class: &'a [u8],
}

/// A body's grid being built (from [`Body::parts`]), by stages over its
/// layers of cells (along z), so a host with threads builds the layers at
/// once: [`BodyGrid::count`] per range of layers, [`BodyParts::set_total`]
/// with the ranges' sum (which takes the references' memory then, when
/// their number is known), [`BodyGrid::fill`] per range, [`BodyGrid::classify`]
/// per range, then [`BodyParts::finish`]. Each stage writes only its
/// layers' part of each array, and a cell's result does not depend on the
/// split: any split gives the bits of [`Body::build`].
pub struct BodyParts<'a> {
    grid: BodyGrid<'a>,
    start: &'a mut [u32],
    refs: &'a mut [u32],
    class: &'a mut [u8],
}

/// What every stage of a [`BodyParts`] reads: the grid's placement, the
/// triangles and the caps.
pub struct BodyGrid<'a> {
    shape: Shape,
    triangles: &'a [Stored],
    /// The cells each triangle's bounds touch (see [`Shape::cell_range`]),
    /// found once for every stage.
    spans: &'a [Span],
    caps: &'a [Stored],
    loops: &'a [CapBall],
}

impl<'a> BodyParts<'a> {
    /// Layers of cells (along z).
    pub fn layers(&self) -> usize {
        self.grid.shape.dims[2]
    }

    /// Cells in one layer: a range of layers `l` owns the cells (and class
    /// entries) `l.start * layer_cells() .. l.end * layer_cells()`.
    pub fn layer_cells(&self) -> usize {
        self.grid.shape.layer_cells()
    }

    /// The grid every stage reads, and the arrays they write: each cell's
    /// first reference (one entry per cell, then the total), the
    /// references (none before [`set_total`](Self::set_total)), and the
    /// cells' classes.
    pub fn split(&mut self) -> (&BodyGrid<'a>, &mut [u32], &mut [u32], &mut [u8]) {
        (&self.grid, self.start, self.refs, self.class)
    }

    /// Records the references of every layer (the sum of what
    /// [`BodyGrid::count`] returned) and takes their memory, 4 bytes each,
    /// from `arena` (which may be the one the parts came from).
    ///
    /// Errors: `InvalidArgument` when there are 2^32 - 1 or more (the grid
    /// is too large), `CapacityExceeded` when `arena` is short.
    pub fn set_total(&mut self, total: u64, arena: &mut Arena<'a>) -> Result<(), Error> {
        Self::refs_bytes(total)?;
        self.refs = arena.alloc::<u32>(total as usize)?;
        let cells = self.start.len() - 1;
        self.start[cells] = total as u32;
        Ok(())
    }

    /// The bytes [`set_total`](Self::set_total) takes for `total`
    /// references, with room to align them in any memory;
    /// `InvalidArgument` when there are too many.
    pub fn refs_bytes(total: u64) -> Result<usize, Error> {
        let too_large = Error::InvalidArgument("body grid is too large");
        if total >= u64::from(u32::MAX) {
            return Err(too_large);
        }
        let total = usize::try_from(total).map_err(|_| too_large)?;
        if total.checked_mul(size_of::<u32>()).is_none() {
            return Err(too_large);
        }
        let mut layout = ArenaLayout::new();
        layout.add::<u32>(total);
        Ok(layout.bytes())
    }

    /// The body, once every stage ran on every layer.
    pub fn finish(self) -> Body<'a> {
        Body {
            shape: self.grid.shape,
            start: self.start,
            refs: self.refs,
            triangles: self.grid.triangles,
            caps: self.grid.caps,
            loops: self.grid.loops,
            class: self.class,
        }
    }
}

impl BodyGrid<'_> {
    /// Visits the cells of layers `layers` that triangle `t` may touch, by
    /// their index within those layers: the cells of its bounds (its span)
    /// that its plane passes through. The cells are padded as the bounds
    /// are, and the plane's distance is given more than its rounding, so
    /// every cell where a crossing with the triangle can be computed is
    /// visited (most of a bounding box's corners are not).
    #[inline]
    fn each_cell(&self, t: usize, layers: &Range<usize>, mut visit: impl FnMut(usize)) {
        let shape = &self.shape;
        let [a0, a1, a2, b0, b1, b2] = self.spans[t].map(usize::from);
        let (a, b) = ([a0, a1, a2], [b0, b1, b2]);
        let zs = a[2].max(layers.start)..=b[2].min(layers.end.wrapping_sub(1));
        // another thread's layers: the triangle is not read
        if zs.is_empty() {
            return;
        }
        let t = &self.triangles[t];
        let (p, n) = (t.corner(), Vec3::from(t.normal()));
        // half a cell and the bounds' pad, and the plane's slack
        let half = (0.5 + 1e-3) / shape.inv_cell;
        let reach = n.abs().element_sum() * half + t.slack();
        let skip = layers.start * shape.layer_cells();
        for z in zs {
            for y in a[1]..=b[1] {
                for x in a[0]..=b[0] {
                    if n.dot(shape.centre(x, y, z) - p).abs() <= reach {
                        visit(shape.index(x, y, z) - skip);
                    }
                }
            }
        }
    }

    /// Stage 1: counts the triangles of each cell of `layers` into `start`
    /// (those layers' cells), as each cell's end among the layers'
    /// references; returns the layers' references (the ends are right
    /// when all of them, over every layer, are fewer than 2^32).
    pub fn count(&self, layers: Range<usize>, start: &mut [u32]) -> u64 {
        start.fill(0);
        if layers.is_empty() {
            return 0;
        }
        for t in 0..self.spans.len() {
            self.each_cell(t, &layers, |c| start[c] += 1);
        }
        let mut sum = 0u64;
        for s in start.iter_mut() {
            sum += u64::from(*s);
            *s = sum as u32;
        }
        sum
    }

    /// Stage 2: lists the triangles of each cell of `layers` in `refs` (the
    /// layers' references, which begin at `base`, the references of every
    /// layer before them), and makes `start` (those layers' cells) each
    /// cell's first reference.
    pub fn fill(&self, layers: Range<usize>, base: u32, start: &mut [u32], refs: &mut [u32]) {
        if layers.is_empty() {
            return;
        }
        // filled backwards from each cell's end, so each ends at its start
        for t in 0..self.spans.len() {
            self.each_cell(t, &layers, |c| {
                start[c] -= 1;
                refs[start[c] as usize] = t as u32;
            });
        }
        for s in start.iter_mut() {
            *s += base;
        }
    }

    /// Stage 3: the class of each cell of `layers` into `class` (those
    /// layers' cells), with every cell's first reference in `start` (all of
    /// them, after stage 2).
    pub fn classify(&self, layers: Range<usize>, start: &[u32], class: &mut [u8]) {
        if layers.is_empty() {
            return;
        }
        self.sweep(&layers, start, class);
        self.mark_near_caps(&layers, class);
    }

    /// Sweeps each row of cell centres along x from the grid's empty first
    /// layer (outside), adding up the signed crossings of the capped
    /// surface. Each triangle's crossings with the rows' lines are added
    /// first to the centre each comes before.
    fn sweep(&self, layers: &Range<usize>, start: &[u32], class: &mut [u8]) {
        let shape = &self.shape;
        let skip = layers.start * shape.layer_cells();
        class.fill(0);
        // a triangle's rows lie within a layer of its span (the caps have
        // none)
        let spans = self
            .spans
            .iter()
            .map(Some)
            .chain(self.caps.iter().map(|_| None));
        for (t, span) in self.triangles.iter().chain(self.caps).zip(spans) {
            if span.is_some_and(|s| {
                usize::from(s[5]) + 1 < layers.start || usize::from(s[2]) > layers.end
            }) {
                continue;
            }
            let (lo, hi) = t.bounds();
            // the rows whose line may pass within the bounds (one more each
            // way: the bounds and `crossing_within` decide exactly)
            let first = shape.cell_of(Vec3::from(lo) - 0.5 / shape.inv_cell);
            let last = shape.cell_of(Vec3::from(hi) - 0.5 / shape.inv_cell);
            let rows = |k: usize| {
                let n = shape.dims[k] as i32;
                first[k].clamp(0, n - 1) as usize..=(last[k] + 1).clamp(0, n - 1) as usize
            };
            let zs = rows(2);
            for z in (*zs.start()).max(layers.start)..=(*zs.end()).min(layers.end.wrapping_sub(1)) {
                // a line strictly outside the bounds misses the triangle,
                // perturbed or not
                let at_z = shape.centre(0, 0, z).z;
                if at_z < lo.z || at_z > hi.z {
                    continue;
                }
                for y in rows(1) {
                    let at = shape.centre(0, y, z);
                    if at.y < lo.y || at.y > hi.y {
                        continue;
                    }
                    let Some((h, step)) = crossing_within::<0>(t, at) else {
                        continue;
                    };
                    // the first centre at or past the crossing
                    let x = shape.cell_on(h, 0);
                    if !(0..shape.dims[0] as i32).contains(&x) {
                        continue;
                    }
                    let x = x as usize + (h > shape.centre(x as usize, y, z).x) as usize;
                    if x < shape.dims[0] {
                        let c = &mut class[shape.index(x, y, z) - skip];
                        *c = (*c as i8).wrapping_add(step as i8) as u8;
                    }
                }
            }
        }
        let nx = shape.dims[0];
        let first_row = layers.start * shape.dims[1];
        for (r, row) in class.chunks_exact_mut(nx).enumerate() {
            let r = first_row + r;
            let mut w = 0i32;
            // a cell the surface passes through lists triangles
            let listed = start[r * nx..=(r + 1) * nx].windows(2);
            for (c, ends) in row.iter_mut().zip(listed) {
                w += (*c as i8) as i32;
                let winding = w.clamp(-MAX_WINDING - 1, MAX_WINDING) as i8;
                *c = ((winding << WINDING_SHIFT) as u8) | ((ends[0] != ends[1]) as u8 * SURFACE);
            }
        }
    }

    /// Marks the cells where the caps' solid angle may reach a half turn
    /// (2 pi): where it cannot, the capped surface's integer winding number
    /// decides alone. A cap within a ball of radius `R` subtends at most
    /// `2 pi (1 - sqrt(1 - R^2 / D^2))` from a distance `D > R` to the
    /// ball's centre; with `K` caps, each kept below `2 pi / K`, their sum
    /// stays below a half turn.
    fn mark_near_caps(&self, layers: &Range<usize>, class: &mut [u8]) {
        let shape = &self.shape;
        let skip = layers.start * shape.layer_cells();
        let share = 1.0 - 1.0 / self.loops.len() as f32;
        let reach = 1.0 / libm::sqrtf(1.0 - share * share);
        let half_diagonal = 0.5 * libm::sqrtf(3.0) / shape.inv_cell;
        for ball in self.loops {
            let centre = Vec3::from(ball.centre);
            let d = ball.radius * reach * 1.001 + half_diagonal;
            let (a, b) = shape.cell_range(centre - Vec3::splat(d), centre + Vec3::splat(d));
            for z in a[2].max(layers.start)..=b[2].min(layers.end.wrapping_sub(1)) {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        if shape.centre(x, y, z).distance(centre) <= d {
                            class[shape.index(x, y, z) - skip] |= NEAR_CAP;
                        }
                    }
                }
            }
        }
    }
}

/// A ball around one cap: every triangle of the cap lies inside it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct CapBall {
    centre: [f32; 3],
    radius: f32,
    /// The cap's triangles end here in [`Body::caps`] (they start where
    /// the previous cap's end).
    end: u32,
}

impl CapBall {
    /// An upper bound on the solid angle anything inside the ball
    /// subtends at `p`, infinite when `p` is inside.
    fn bound(&self, p: Vec3) -> f64 {
        let d = p.distance(Vec3::from(self.centre)) as f64;
        let r = self.radius as f64 * 1.001;
        if d <= r {
            return f64::INFINITY;
        }
        let s = r / d;
        2.0 * core::f64::consts::PI * (1.0 - libm::sqrt(1.0 - s * s))
    }
}

/// The grid a mesh's body will have, worked out before its memory is
/// found: [`BodyPlan::build_bytes`] sizes the arena of [`Body::build`];
/// [`BodyPlan::bytes`] that of [`Body::parts`], whose references then take
/// [`BodyParts::refs_bytes`] more.
#[derive(Clone, Copy, Debug)]
pub struct BodyPlan {
    shape: Shape,
    /// Boundary edges and loops of the mesh.
    cap_triangles: usize,
    loops: usize,
}

impl BodyPlan {
    /// Validates `mesh` and places the grid; `rim` is the mesh's boundary,
    /// found or refreshed on the mesh as it is now (the grid is placed by
    /// the bounds of the solid triangles it found; see [`Rim`] for when it
    /// must be found again).
    pub fn of(mesh: &Mesh, rim: &Rim) -> Result<Self, Error> {
        Self::with_density(mesh, rim, CELLS_PER_TRIANGLE)
    }

    /// [`of`](Self::of), the grid aiming at `cells_per_triangle` cells per
    /// triangle (1 to 64; the grid has at most 1024 cells a side): a body
    /// built for few queries (a guide simulation's step) builds faster
    /// coarse, one queried by a million render strands answers faster fine.
    /// The solid is the same at any density (answers may differ only for
    /// points within rounding of the surface).
    pub fn with_density(mesh: &Mesh, rim: &Rim, cells_per_triangle: f32) -> Result<Self, Error> {
        if !(1.0..=64.0).contains(&cells_per_triangle) {
            return Err(Error::InvalidArgument(
                "body grid density must be 1 to 64 cells per triangle",
            ));
        }
        rim.check_mesh(mesh)?;
        mesh.check()?;
        // the rim found its solid triangles' bounds with them
        let shape = Shape::of_bounds(rim.solid_bounds(), cells_per_triangle)?;
        Ok(BodyPlan {
            shape,
            cap_triangles: rim.edge_count(),
            loops: rim.loop_count(),
        })
    }

    /// Arena bytes [`Body::parts`] takes: the grid without its triangle
    /// references, whose memory [`BodyParts::set_total`] takes once they
    /// are counted.
    pub fn bytes(&self) -> usize {
        Self::bytes_with(&self.shape, self.cap_triangles, self.loops, 0)
    }

    /// Arena bytes [`Body::build`] needs for `mesh` and `rim` (the plan's):
    /// [`bytes`](Self::bytes) and room for the most references the
    /// triangles could list (found by a pass over them; a build lists
    /// fewer).
    pub fn build_bytes(&self, mesh: &Mesh, rim: &Rim) -> usize {
        let refs = self.shape.refs_bound(mesh, |f| rim.is_solid(f));
        Self::bytes_with(&self.shape, self.cap_triangles, self.loops, refs)
    }

    /// The bytes of the parts, in the order [`Body::build`] takes them,
    /// with `refs` references last.
    fn bytes_with(shape: &Shape, cap_triangles: usize, loops: usize, refs: usize) -> usize {
        let cells = shape.cells();
        let mut layout = ArenaLayout::new();
        layout
            .add::<u32>(cells + 1)
            .add::<Stored>(shape.triangles)
            .add::<Span>(shape.triangles)
            .add::<Stored>(cap_triangles)
            .add::<CapBall>(loops)
            .add::<u8>(cells)
            .add::<u32>(refs);
        layout.bytes()
    }
}

impl<'a> Body<'a> {
    /// Arena bytes [`Body::new`] needs for `mesh` (validates it): its rim's
    /// and its body's, for the most boundary edges the mesh could have.
    pub fn required_bytes(mesh: &Mesh) -> Result<usize, Error> {
        let solid = |f| !mesh.is_degenerate(f);
        let shape = Shape::of(mesh, CELLS_PER_TRIANGLE, solid)?;
        // a loop has three edges or more
        let edges = 3 * mesh.triangle_count();
        let refs = shape.refs_bound(mesh, solid);
        let body = BodyPlan::bytes_with(&shape, edges, edges / 3, refs);
        Ok(Rim::required_bytes(mesh).saturating_add(body))
    }

    /// Validates `mesh`, finds its rim and builds its grid and cell
    /// classes, all in `arena`.
    pub fn new(mesh: &Mesh, arena: &mut Arena<'a>) -> Result<Self, Error> {
        let needed = Self::required_bytes(mesh)?;
        if arena.remaining() < needed {
            return Err(Error::CapacityExceeded {
                needed: arena.capacity() - arena.remaining() + needed,
                available: arena.capacity(),
            });
        }
        let rim = Rim::new(mesh, arena)?;
        Self::build(&BodyPlan::of(mesh, &rim)?, mesh, &rim, arena)
    }

    /// Starts building the grid of `mesh`, placed by `plan` (made from
    /// this mesh and `rim`): the triangles and the caps are copied into
    /// `arena`; the stages of [`BodyGrid`] then build the rest, on any split
    /// of the layers (see [`BodyParts`]).
    pub fn parts(
        plan: &BodyPlan,
        mesh: &Mesh,
        rim: &Rim,
        arena: &mut Arena<'a>,
    ) -> Result<BodyParts<'a>, Error> {
        let shape = plan.shape;
        let needed = plan.bytes();
        if arena.remaining() < needed {
            return Err(Error::CapacityExceeded {
                needed: arena.capacity() - arena.remaining() + needed,
                available: arena.capacity(),
            });
        }
        let another = Error::InvalidArgument("body plan made from another mesh");
        rim.check_mesh(mesh)?;
        if (rim.edge_count(), rim.loop_count()) != (plan.cap_triangles, plan.loops) {
            return Err(another);
        }
        let cells = shape.cells();
        let start = arena.alloc::<u32>(cells + 1)?;
        let triangles = arena.alloc::<Stored>(shape.triangles)?;
        let spans = arena.alloc::<Span>(shape.triangles)?;
        let caps = arena.alloc::<Stored>(plan.cap_triangles)?;
        let loops = arena.alloc::<CapBall>(plan.loops)?;
        let class = arena.alloc::<u8>(cells)?;

        let mut solid = (0..mesh.triangle_count()).filter(|&f| rim.is_solid(f));
        let reach = shape.reach();
        for (t, span) in triangles.iter_mut().zip(spans.iter_mut()) {
            let [a, b, c] = mesh.corners(solid.next().ok_or(another)?);
            let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
            if !(lo.cmpge(shape.lo).all() && hi.cmple(shape.hi).all()) {
                return Err(another);
            }
            *t = Stored::new([a, b, c], reach, shape.inv_cell);
            let (a, b) = shape.cell_range(lo, hi);
            // at most MAX_DIM + 4 cells a side
            *span = [a[0], a[1], a[2], b[0], b[1], b[2]].map(|c| c as u16);
        }
        if solid.next().is_some() {
            return Err(another);
        }
        cap(mesh, rim, &shape, caps, loops);
        Ok(BodyParts {
            grid: BodyGrid {
                shape,
                triangles,
                spans,
                caps,
                loops,
            },
            start,
            refs: &mut [],
            class,
        })
    }

    /// Builds the grid and cell classes of `mesh`, placed by `plan` (made
    /// from this mesh and `rim`), on the calling thread (see
    /// [`BodyParts`] to build it on several), in `arena`
    /// ([`BodyPlan::build_bytes`] is enough).
    pub fn build(
        plan: &BodyPlan,
        mesh: &Mesh,
        rim: &Rim,
        arena: &mut Arena<'a>,
    ) -> Result<Self, Error> {
        let mut parts = Self::parts(plan, mesh, rim, arena)?;
        let layers = 0..parts.layers();
        let (grid, start, _, _) = parts.split();
        let cells = start.len() - 1;
        let total = grid.count(layers.clone(), &mut start[..cells]);
        parts.set_total(total, arena)?;
        let (grid, start, refs, class) = parts.split();
        grid.fill(layers.clone(), 0, &mut start[..cells], refs);
        grid.classify(layers, start, class);
        Ok(parts.finish())
    }

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
        self.capped(p).0
    }

    /// [`capped_winding`](Self::capped_winding), and whether a cap may
    /// decide [`contains`](Self::contains) at `p`.
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
    /// [`INSIDE_WINDING`]. Caps near `p` are evaluated exactly; the far
    /// ones only when their bounds leave the answer open.
    fn caps_decide(&self, w: i32, p: Vec3) -> bool {
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

    /// Walks the grid cells the segment from `a` to `b` passes through, in
    /// order, from where it enters the grid to where it leaves it, handing
    /// `visit` each cell's triangles and the segment parameter at which it
    /// leaves the cell, until `visit` returns true.
    fn walk(&self, a: Vec3, b: Vec3, mut visit: impl FnMut(&[u32], f32) -> bool) {
        let shape = &self.shape;
        let (from, to) = (
            (a - shape.origin) * shape.inv_cell,
            (b - shape.origin) * shape.inv_cell,
        );
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

/// Fills `caps` with the fans that close `rim`'s loops on `mesh`: for a
/// boundary edge `a -> b` of a loop whose corners have the mean `m`, the
/// triangle `(b, a, m)`, which runs the edge the other way.
fn cap(mesh: &Mesh, rim: &Rim, shape: &Shape, caps: &mut [Stored], loops: &mut [CapBall]) {
    let at = |v: u32| Vec3::from(mesh.positions.get(v as usize));
    let reach = shape.reach();
    let mut next = 0;
    for (k, ball) in loops.iter_mut().enumerate() {
        let (mean, radius) = rim.ball(k, mesh);
        for e in rim.loop_edges(k) {
            let (a, b) = (at(e[0]), at(e[1]));
            caps[next] = Stored::new([b, a, mean], reach, shape.inv_cell);
            next += 1;
        }
        *ball = CapBall {
            centre: mean.into(),
            radius,
            end: next as u32,
        };
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::{self, Purpose};
    use crate::testmesh::{graded_plane, sphere};

    fn build<'a>(mesh: &Mesh, buf: &'a mut Vec<u8>) -> Body<'a> {
        *buf = vec![0u8; Body::required_bytes(mesh).unwrap()];
        Body::new(mesh, &mut Arena::new(buf)).unwrap()
    }

    /// The body of `mesh` at `density` cells per triangle, in `buf`.
    fn build_at<'a>(mesh: &Mesh, density: f32, buf: &'a mut Vec<u8>) -> Body<'a> {
        let mut rim_memory = vec![0u8; Rim::required_bytes(mesh)];
        let rim = Rim::new(mesh, &mut Arena::new(&mut rim_memory)).unwrap();
        let plan = BodyPlan::with_density(mesh, &rim, density).unwrap();
        *buf = vec![0u8; plan.build_bytes(mesh, &rim)];
        Body::build(&plan, mesh, &rim, &mut Arena::new(buf)).unwrap()
    }

    /// One edge at a time, with branches: what [`edges`] computes in lanes.
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

    /// [`crossing_within`] for any line: none for a line outside the
    /// bounds.
    fn crossing<const AXIS: usize>(t: &Stored, p: Vec3) -> Option<(f32, i32)> {
        let (j, k) = ((AXIS + 1) % 3, (AXIS + 2) % 3);
        let (lo, hi) = t.bounds();
        if p[j] < lo[j] || p[j] > hi[j] || p[k] < lo[k] || p[k] > hi[k] {
            return None;
        }
        crossing_within::<AXIS>(t, p)
    }

    /// A stored triangle for the tests of what reads only its corners.
    fn corners_only(corners: [Vec3; 3]) -> Stored {
        let [a, b, c] = corners.map(|v| v.extend(0.0).into());
        Stored {
            first: a,
            rest: [b, c],
            ..Stored::default()
        }
    }

    /// [`crossing`] from [`edge`].
    fn crossing_by_edge<const AXIS: usize>(t: &Stored, p: Vec3) -> Option<(f32, i32)> {
        let (j, k) = ((AXIS + 1) % 3, (AXIS + 2) % 3);
        let (lo, hi) = t.bounds();
        if p[j] < lo[j] || p[j] > hi[j] || p[k] < lo[k] || p[k] > hi[k] {
            return None;
        }
        let turn = |v: [f32; 3]| [v[AXIS], v[j], v[k]];
        let [a, b, c] = t.corners();
        let (a, b, c, p) = (turn(a), turn(b), turn(c), turn(p.to_array()));
        let (w0, s0) = edge(b, c, p);
        let (w1, s1) = edge(c, a, p);
        let (w2, s2) = edge(a, b, p);
        if s0 != s1 || s1 != s2 {
            return None;
        }
        let sum = w0 + w1 + w2;
        Some((
            (w0 * a[0] + w1 * b[0] + w2 * c[0]) / sum,
            if s0 { -1 } else { 1 },
        ))
    }

    #[test]
    fn slivers_are_listed_wherever_their_crossings_can_fall() {
        // three bands of 1,500 slivers (aspect ~300) from pole to pole, and
        // points within 0.01 of them, at a coarse and a fine grid
        let m = sphere(3, 1500);
        let mesh = m.mesh();
        for density in [2.0, 32.0] {
            let mut memory = vec![];
            let body = build_at(&mesh, density, &mut memory);
            let mut inside = 0;
            for i in 0..1500u64 {
                let r = |c| rng::unit(17, i, Purpose::Uniform, c);
                let f =
                    ((r(0) * mesh.triangle_count() as f32) as usize).min(mesh.triangle_count() - 1);
                let (u, v) = (r(1), r(2));
                let (u, v) = if u + v > 1.0 {
                    (1.0 - u, 1.0 - v)
                } else {
                    (u, v)
                };
                let [a, b, c] = mesh.corners(f);
                let n = (b - a).cross(c - a).normalize();
                let p = a + (b - a) * u + (c - a) * v + n * (0.01 * (r(3) * 2.0 - 1.0));
                let w = winding(&mesh, p);
                if (w - 0.5).abs() < 1e-3 {
                    continue;
                }
                assert_eq!(
                    body.contains(p),
                    w > 0.5,
                    "{p}: winding {w}, density {density}"
                );
                inside += (w > 0.5) as usize;
            }
            assert!((400..1100).contains(&inside), "{inside}");
        }
    }

    #[test]
    fn crossings_in_lanes_match_one_edge_at_a_time() {
        // small integer coordinates make lines through edges and vertices,
        // collinear and repeated corners common; the rest are arbitrary
        let mut checked = 0;
        for i in 0..400_000u64 {
            let mut next = {
                let mut k = 0u32;
                move || {
                    k += 1;
                    rng::unit(11, i, Purpose::Uniform, k)
                }
            };
            let exact = i % 2 == 0;
            let mut value = || {
                let u = next();
                if exact {
                    libm::floorf(u * 4.0) - 1.0
                } else {
                    u * 2.0 - 1.0
                }
            };
            let corners: [[f32; 3]; 3] = core::array::from_fn(|_| [value(), value(), value()]);
            let p = Vec3::new(value(), value(), value());
            let [a, b, c] = corners.map(Vec3::from);
            let t = corners_only([a, b, c]);
            let same = |x: Option<(f32, i32)>, y: Option<(f32, i32)>| match (x, y) {
                (Some((h, s)), Some((g, r))) => h.to_bits() == g.to_bits() && s == r,
                (None, None) => true,
                _ => false,
            };
            assert!(
                same(crossing::<0>(&t, p), crossing_by_edge::<0>(&t, p)),
                "{t:?} {p}"
            );
            assert!(
                same(crossing::<1>(&t, p), crossing_by_edge::<1>(&t, p)),
                "{t:?} {p}"
            );
            assert!(
                same(crossing::<2>(&t, p), crossing_by_edge::<2>(&t, p)),
                "{t:?} {p}"
            );
            checked += crossing_by_edge::<2>(&t, p).is_some() as u32;
        }
        assert!(checked > 10_000, "{checked} crossings");
    }

    #[test]
    fn planes_cull_only_triangles_no_leg_crosses() {
        // slivers, a sphere moved far from the origin, a lattice of small
        // integers (points on edges and corners) and a sphere with a hole
        // (its cap's triangles culled too), at coarse to fine grids:
        // points on and within rounding of the surface, and in cells it
        // passes through, take the same winding number with the planes'
        // cull and without it
        let slivers = sphere(3, 1500);
        let mut far = sphere(12, 24);
        far.p.iter_mut().for_each(|p| p[0] += 3e4);
        let mut lattice = sphere(6, 8);
        lattice
            .p
            .iter_mut()
            .for_each(|p| *p = p.map(|c| libm::roundf(c * 8.0) * 0.5));
        let holed = holed_sphere(0.7);
        // (3e4 from the origin the room for rounding is wider than a
        // cell there: nothing is culled)
        let meshes = [
            (&slivers, 1.0f32, true),
            (&far, 1.0, false),
            (&lattice, 4.0, true),
            (&holed, 1.0, true),
        ];
        for (m, scale, culls) in meshes {
            let mesh = m.mesh();
            for density in [2.0, 8.0, 32.0] {
                let mut memory = vec![];
                let body = build_at(&mesh, density, &mut memory);
                let mut differs = 0;
                CULLED.with(|c| c.set(0));
                for i in 0..20_000u64 {
                    let r = |c| rng::unit(23, i, Purpose::Uniform, c);
                    let f = ((r(0) * mesh.triangle_count() as f32) as usize)
                        .min(mesh.triangle_count() - 1);
                    let [a, b, c] = mesh.corners(f);
                    let (u, v) = match i % 4 {
                        // a corner, an edge's middle
                        0 => (0.0, 0.0),
                        1 => (0.5, 0.0),
                        _ => {
                            let (u, v) = (r(1), r(2));
                            if u + v > 1.0 {
                                (1.0 - u, 1.0 - v)
                            } else {
                                (u, v)
                            }
                        }
                    };
                    let n = (b - a).cross(c - a).normalize_or_zero();
                    let off = [0.0, 1e-6, 1e-3, 0.05][(i / 4 % 4) as usize] * scale;
                    let p = a + (b - a) * u + (c - a) * v + n * (off * (r(3) * 2.0 - 1.0));
                    let culled = body.capped_winding(p);
                    UNCULLED.with(|u| u.set(true));
                    let all = body.capped_winding(p);
                    UNCULLED.with(|u| u.set(false));
                    differs += (culled != all) as usize;
                }
                assert_eq!(differs, 0, "density {density}");
                let culled = CULLED.with(|c| c.get());
                assert_eq!(culled > 1000, culls, "{culled} culled at density {density}");
            }
        }
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
        // points on the grid's own lattice and on mesh vertices do not break the count
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

    /// The generalized winding number of `mesh` at `p`, triangle by triangle.
    fn winding(mesh: &Mesh, p: Vec3) -> f64 {
        let total: f64 = (0..mesh.triangle_count())
            .map(|f| {
                let [a, b, c] = mesh.corners(f);
                solid_angle(&corners_only([a, b, c]), p)
            })
            .sum();
        total / (4.0 * core::f64::consts::PI)
    }

    /// `contains` against the winding number, brute force, at random points
    /// of the box `lo..hi` (points within `margin` of the threshold are
    /// ties, left out); returns how many points were inside.
    fn agrees_with_winding(mesh: &Mesh, lo: Vec3, hi: Vec3, points: u64, margin: f64) -> usize {
        let mut buf = vec![];
        let body = build(mesh, &mut buf);
        let mut inside = 0;
        for i in 0..points {
            let r = |c| rng::unit(5, i, Purpose::Uniform, c);
            let p = lo + (hi - lo) * Vec3::new(r(0), r(1), r(2));
            let w = winding(mesh, p);
            if (w - 0.5).abs() < margin {
                continue;
            }
            assert_eq!(body.contains(p), w > 0.5, "{p}: winding {w}");
            inside += (w > 0.5) as usize;
        }
        inside
    }

    #[test]
    fn any_split_of_the_layers_builds_the_same_grid() {
        // a holed sphere: caps and near-cap cells too
        let m = holed_sphere(0.5);
        let mesh = m.mesh();
        let mut rim_memory = vec![0u8; Rim::required_bytes(&mesh)];
        let rim = Rim::new(&mesh, &mut Arena::new(&mut rim_memory)).unwrap();
        let plan = BodyPlan::of(&mesh, &rim).unwrap();
        let mut whole_memory = vec![0u8; plan.build_bytes(&mesh, &rim)];
        let whole = Body::build(&plan, &mesh, &rim, &mut Arena::new(&mut whole_memory)).unwrap();
        let n = whole.shape.dims[2];
        for cuts in [
            vec![0, n],
            vec![0, 0, n / 2, n],
            vec![0, 1, 2, n / 3, n - 1, n, n],
        ] {
            let mut memory = vec![0u8; plan.bytes()];
            let mut parts = Body::parts(&plan, &mesh, &rim, &mut Arena::new(&mut memory)).unwrap();
            // the references in memory of their own, as a host with
            // threads may give them
            let per = parts.layer_cells();
            let ranges: Vec<Range<usize>> = cuts.windows(2).map(|w| w[0]..w[1]).collect();
            let (grid, start, _, _) = parts.split();
            let totals: Vec<u64> = ranges
                .iter()
                .map(|l| grid.count(l.clone(), &mut start[l.start * per..l.end * per]))
                .collect();
            let total: u64 = totals.iter().sum();
            let mut refs_memory = vec![0u8; BodyParts::refs_bytes(total).unwrap()];
            // (a vector's memory is aligned: the bytes of the references
            // themselves, less one)
            let mut short = vec![0u8; 4 * total as usize - 1];
            // short memory is refused, and leaves the parts to try again
            assert!(matches!(
                parts.set_total(total, &mut Arena::new(&mut short)),
                Err(Error::CapacityExceeded { .. })
            ));
            parts
                .set_total(total, &mut Arena::new(&mut refs_memory))
                .unwrap();
            let (grid, start, refs, class) = parts.split();
            let mut base = 0u32;
            for (l, &total) in ranges.iter().zip(&totals) {
                let part = &mut refs[base as usize..(base + total as u32) as usize];
                grid.fill(
                    l.clone(),
                    base,
                    &mut start[l.start * per..l.end * per],
                    part,
                );
                base += total as u32;
            }
            for l in &ranges {
                grid.classify(l.clone(), start, &mut class[l.start * per..l.end * per]);
            }
            let body = parts.finish();
            assert!(body.start == whole.start, "{cuts:?}");
            assert!(body.refs == whole.refs, "{cuts:?}");
            assert!(body.class == whole.class, "{cuts:?}");
        }
        assert!(matches!(
            BodyParts::refs_bytes(u64::from(u32::MAX)),
            Err(Error::InvalidArgument(_))
        ));
    }

    /// A sphere with the triangles whose centroid has `y > cut` removed.
    fn holed_sphere(cut: f32) -> crate::testmesh::TestMesh {
        let mut m = sphere(12, 24);
        let p = m.p.clone();
        m.t.retain(|t| t.iter().map(|&v| p[v as usize][1]).sum::<f32>() / 3.0 <= cut);
        m
    }

    #[test]
    fn open_meshes_follow_the_generalized_winding_number() {
        // a small hole (an eye socket), a wide one (a bowl), and a sliver
        for cut in [0.9f32, 0.2, -0.6] {
            let m = holed_sphere(cut);
            let mesh = m.mesh();
            let inside =
                agrees_with_winding(&mesh, Vec3::splat(-1.3), Vec3::splat(1.3), 4000, 1e-4);
            assert!(inside > 50, "cut {cut}: {inside} inside");
        }
    }

    #[test]
    fn intersecting_shells_and_a_shell_inside_another() {
        // a sphere, a second one overlapping it, and a small one inside the
        // first: inside one or more counts as inside
        let (a, b, c) = (sphere(10, 20), sphere(10, 20), sphere(6, 12));
        let mut p: Vec<[f32; 3]> = a.p.clone();
        p.extend(b.p.iter().map(|v| [v[0] + 0.8, v[1] * 0.7, v[2]]));
        p.extend(
            c.p.iter()
                .map(|v| [v[0] * 0.3 - 0.4, v[1] * 0.3, v[2] * 0.3]),
        );
        let mut t = a.t.clone();
        let shift = |m: &crate::testmesh::TestMesh, by: usize| {
            m.t.iter()
                .map(move |f| f.map(|v| v + by as u32))
                .collect::<Vec<_>>()
        };
        t.extend(shift(&b, a.p.len()));
        t.extend(shift(&c, a.p.len() + b.p.len()));
        let mesh = Mesh::new(
            crate::Strided::from_slice(&p),
            crate::Strided::from_slice(&t),
        );
        let lo = Vec3::new(-1.2, -1.2, -1.2);
        let hi = Vec3::new(2.0, 1.2, 1.2);
        assert!(agrees_with_winding(&mesh, lo, hi, 4000, 1e-4) > 500);
        let mut buf = vec![];
        let body = build(&mesh, &mut buf);
        // inside both spheres, and inside the inner one (winding 2)
        assert!(body.contains(Vec3::new(0.5, 0.0, 0.0)));
        assert!(body.contains(Vec3::new(-0.4, 0.0, 0.0)));
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
        let mut rim_memory = vec![0u8; Rim::required_bytes(&other.mesh())];
        let rim = Rim::new(&other.mesh(), &mut Arena::new(&mut rim_memory)).unwrap();
        let plan = BodyPlan::of(&other.mesh(), &rim).unwrap();
        let bytes = plan.build_bytes(&other.mesh(), &rim);
        let mut big = vec![0u8; bytes.max(Body::required_bytes(&mesh).unwrap())];
        assert!(matches!(
            Body::build(&plan, &mesh, &rim, &mut Arena::new(&mut big)),
            Err(Error::InvalidArgument(_))
        ));
        let mut small = vec![0u8; Body::required_bytes(&mesh).unwrap() - 1];
        assert!(matches!(
            Body::new(&mesh, &mut Arena::new(&mut small)),
            Err(Error::CapacityExceeded { .. })
        ));
    }
}
