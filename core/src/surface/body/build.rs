//! Building a body's grid: the triangles and caps copied, then the grid's
//! counts, lists and cell classes, by layers on any split over threads.

use super::*;

/// Grid placement, computed the same way when sizing and when building.
///
/// A body stores its triangles, caps and cell centres relative to the
/// grid's `origin` (a cell below the mesh's bounds), and a query moves its
/// points there first: far from the world's origin the subtraction is
/// exact (the point and the origin are within a factor 2), so the
/// crossings are computed at the mesh's own scale instead of at the
/// rounding of coordinates in the thousands.
#[derive(Clone, Copy, Debug)]
pub(super) struct Shape {
    /// The grid's corner (world).
    pub(super) origin: Vec3,
    pub(super) inv_cell: f32,
    pub(super) dims: [usize; 3],
    pub(super) triangles: usize,
    /// The bounds of the mesh (world).
    pub(super) lo: Vec3,
    pub(super) hi: Vec3,
}

impl Shape {
    /// The grid over the triangles of `mesh` that `solid` keeps (those
    /// not degenerate).
    pub(super) fn of(
        mesh: &Mesh,
        density: f32,
        solid: impl Fn(usize) -> bool,
    ) -> Result<Shape, Error> {
        mesh.check()?;
        let mut bounds = SolidBounds::EMPTY;
        for f in (0..mesh.triangle_count()).filter(|&f| solid(f)) {
            bounds.add(mesh.corners(f));
        }
        Self::of_bounds(bounds, density)
    }

    /// The grid over triangles of bounds `bounds`.
    pub(super) fn of_bounds(bounds: SolidBounds, density: f32) -> Result<Shape, Error> {
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
    pub(super) fn refs_bound(&self, mesh: &Mesh, solid: impl Fn(usize) -> bool) -> usize {
        (0..mesh.triangle_count())
            .filter(|&f| solid(f))
            .map(|f| {
                let [a, b, c] = mesh.corners(f).map(|p| self.local(p));
                let (a, b) = self.cell_range(a.min(b).min(c), a.max(b).max(c));
                (0..3).map(|k| b[k] - a[k] + 1).product::<usize>()
            })
            .fold(0usize, usize::saturating_add)
    }

    /// The largest local coordinate of the triangles' bounds, and two
    /// cells more: what rounding is measured against (surface cells lie
    /// within a cell of the bounds, which start a cell from the origin).
    pub(super) fn reach(&self) -> f32 {
        (self.hi - self.lo).max_element() + 3.0 / self.inv_cell
    }

    /// World point `p` relative to the grid's origin.
    #[inline]
    pub(super) fn local(&self, p: Vec3) -> Vec3 {
        p - self.origin
    }

    pub(super) fn cells(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// The cell of local point `p` along each axis (may be out of the
    /// grid).
    #[inline]
    pub(super) fn cell_of(&self, p: Vec3) -> [i32; 3] {
        let q = p * self.inv_cell;
        [floor_i32(q.x), floor_i32(q.y), floor_i32(q.z)]
    }

    /// The cell of local coordinate `v` along any axis (may be out of the
    /// grid).
    #[inline]
    pub(super) fn cell_on(&self, v: f32) -> i32 {
        floor_i32(v * self.inv_cell)
    }

    /// Cells the local bounds `lo`..`hi` of a triangle touch, padded by a
    /// thousandth of a cell so that a crossing computed with rounding still
    /// lands in a listed cell.
    pub(super) fn cell_range(&self, lo: Vec3, hi: Vec3) -> ([usize; 3], [usize; 3]) {
        let pad = Vec3A::splat(1e-3 / self.inv_cell);
        let last = Vec3A::from(self.dims.map(|d| (d - 1) as f32));
        // clamped into the grid first, the coordinate's floor is its
        // truncation: the cell of `cell_of`, clamped
        let cell = |p: Vec3A| {
            let q = (p * self.inv_cell).max(Vec3A::ZERO).min(last);
            let [x, y, z, _] = f32x4::from(q.extend(0.0).to_array()).trunc_int().to_array();
            [x as usize, y as usize, z as usize]
        };
        (cell(Vec3A::from(lo) - pad), cell(Vec3A::from(hi) + pad))
    }

    #[inline]
    pub(super) fn index(&self, x: usize, y: usize, z: usize) -> usize {
        (z * self.dims[1] + y) * self.dims[0] + x
    }

    /// The centre of cell `(x, y, z)` (local).
    #[inline]
    pub(super) fn centre(&self, x: usize, y: usize, z: usize) -> Vec3 {
        Vec3::new(x as f32 + 0.5, y as f32 + 0.5, z as f32 + 0.5) / self.inv_cell
    }

    /// Cells in one layer (one z).
    pub(super) fn layer_cells(&self) -> usize {
        self.dims[0] * self.dims[1]
    }
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
                    let x = shape.cell_on(h);
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
    /// ball's centre. A cell is marked when the sum of those bounds over
    /// every cap, each at the cell's nearest point, reaches a half turn
    /// (with [`MAX_SUMMED`] caps or fewer: the sum is taken only within
    /// the cells where, with `K` caps, some cap's bound reaches `2 pi / K`,
    /// which holds every cell whose sum does; past that count, every cell
    /// there is marked). Most of those cells are far enough from every
    /// cap: a mesh open at the neck, the mouth and the eyes has its near
    /// cells within about a cap's radius of a cap, where the share alone
    /// reaches 1.7 radii of the neck, over much of the head.
    fn mark_near_caps(&self, layers: &Range<usize>, class: &mut [u8]) {
        let shape = &self.shape;
        let skip = layers.start * shape.layer_cells();
        let share = 1.0 - 1.0 / self.loops.len() as f32;
        let reach = 1.0 / libm::sqrtf(1.0 - share * share);
        let half_diagonal = 0.5 * libm::sqrtf(3.0) / shape.inv_cell;
        let summed = self.loops.len() <= MAX_SUMMED;
        #[cfg(test)]
        let summed = summed && !super::EXACT_CAPS.with(|e| e.get());
        for ball in self.loops {
            let centre = Vec3::from(ball.centre);
            let d = ball.radius * reach * 1.001 + half_diagonal;
            let (a, b) = shape.cell_range(centre - Vec3::splat(d), centre + Vec3::splat(d));
            for z in a[2].max(layers.start)..=b[2].min(layers.end.wrapping_sub(1)) {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        let at = shape.centre(x, y, z);
                        let c = &mut class[shape.index(x, y, z) - skip];
                        if *c & NEAR_CAP == 0
                            && at.distance(centre) <= d
                            && (!summed || self.caps_may_reach(at, half_diagonal))
                        {
                            *c |= NEAR_CAP;
                        }
                    }
                }
            }
        }
    }

    /// Whether the caps' bounds at the nearest point of the ball of radius
    /// `half_diagonal` around `at` (a cell) sum to a half turn, or nearly
    /// (by far more than their rounding).
    fn caps_may_reach(&self, at: Vec3, half_diagonal: f32) -> bool {
        let half_turn = core::f64::consts::TAU * (1.0 - 1e-4);
        let mut sum = 0.0f64;
        for ball in self.loops {
            let d = at.distance(Vec3::from(ball.centre)) as f64 - half_diagonal as f64 * 1.001;
            let r = ball.radius as f64 * 1.001;
            if d <= r {
                return true;
            }
            let s = r / d;
            sum += core::f64::consts::TAU * (1.0 - libm::sqrt(1.0 - s * s));
            if sum >= half_turn {
                return true;
            }
        }
        false
    }
}

/// A ball around one cap: every triangle of the cap lies inside it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct CapBall {
    pub(super) centre: [f32; 3],
    pub(super) radius: f32,
    /// The cap's triangles end here in [`Body::caps`] (they start where
    /// the previous cap's end).
    pub(super) end: u32,
}

impl CapBall {
    /// An upper bound on the solid angle anything inside the ball
    /// subtends at `p`, infinite when `p` is inside.
    pub(super) fn bound(&self, p: Vec3) -> f64 {
        let d = p.distance(Vec3::from(self.centre)) as f64;
        let r = self.radius as f64 * 1.001;
        if d <= r {
            return f64::INFINITY;
        }
        let s = r / d;
        2.0 * core::f64::consts::PI * (1.0 - libm::sqrt(1.0 - s * s))
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
            *t = Stored::new([a, b, c].map(|p| shape.local(p)), reach, shape.inv_cell);
            let (a, b) = shape.cell_range(shape.local(lo), shape.local(hi));
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
}

/// Fills `caps` with the fans that close `rim`'s loops on `mesh`: for a
/// boundary edge `a -> b` of a loop whose corners have the mean `m`, the
/// triangle `(b, a, m)`, which runs the edge the other way.
pub(super) fn cap(
    mesh: &Mesh,
    rim: &Rim,
    shape: &Shape,
    caps: &mut [Stored],
    loops: &mut [CapBall],
) {
    let at = |v: u32| shape.local(Vec3::from(mesh.positions.get(v as usize)));
    let reach = shape.reach();
    let mut next = 0;
    for (k, ball) in loops.iter_mut().enumerate() {
        let (mean, radius) = rim.ball(k, mesh);
        let mean = shape.local(mean);
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
