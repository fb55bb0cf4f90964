//! Where a body's grid goes and how large it is, before it is built.

use super::*;

/// The grid a mesh's body will have, worked out before its memory is
/// found: [`BodyPlan::build_bytes`] sizes the arena of [`Body::build`];
/// [`BodyPlan::bytes`] that of [`Body::parts`], whose references then take
/// [`BodyParts::refs_bytes`] more.
#[derive(Clone, Copy, Debug)]
pub struct BodyPlan {
    pub(super) shape: Shape,
    /// Boundary edges and loops of the mesh.
    pub(super) cap_triangles: usize,
    pub(super) loops: usize,
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
    pub(super) fn bytes_with(
        shape: &Shape,
        cap_triangles: usize,
        loops: usize,
        refs: usize,
    ) -> usize {
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
