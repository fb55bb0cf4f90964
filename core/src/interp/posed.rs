//! The posed frame: one frame's deformed mesh, its vertex tangents and its
//! posed guides, prepared once and then read by any number of range
//! expansions, on any threads.
//!
//! (`surface::frame::Frame` is a root's coordinate frame, a different
//! thing.) The frame lives in the caller's arena; its guides are filled from
//! host buffers ([`PosedFrame::pose`], or [`PosedFrame::posing`] in
//! parallel), and a guide cache decoder is meant to fill them the same way.

use crate::arena::{Arena, ArenaLayout};
use crate::guides::Guides;
use crate::interp::params::{ExpandParams, MAX_STRAND_POINTS};
use crate::surface::frame::{self, Frame, FRAME_LANES};
use crate::{Error, Mesh, Root};
use glam::Vec3;

/// Largest coordinate of a frame's origin: beyond it a double holds the
/// origin to worse than a tenth of a unit.
pub const MAX_ORIGIN: f64 = 1e15;

/// A deformed mesh with its vertex tangents (see
/// [`frame::vertex_tangents`]) and its posed guides, resampled to the
/// strand point count, in their own root frames (local) and in world space.
///
/// Each guide is stored as its n local x, then n y, then n z coordinates,
/// then the same for its world points, so the per-strand loops run over
/// contiguous lanes and vectorize (element-wise only: the bits are the same
/// as a scalar loop's on every target), and a strand's clump centre (one of
/// its guides) sits beside that guide's local points.
pub struct PosedFrame<'a> {
    mesh: Mesh<'a>,
    tangents: &'a [[f32; 3]],
    data: &'a mut [f32],
    points: usize,
    guides: usize,
    posed: bool,
    /// Where the frame's local space sits in the host's world (see
    /// [`PosedFrame::set_origin`]).
    origin: [f64; 3],
}

impl<'m> PosedFrame<'m> {
    /// Adds the arena bytes [`PosedFrame::new`] needs for a mesh of
    /// `vertices` vertices and `guides` guides.
    pub fn layout(
        layout: &mut ArenaLayout,
        vertices: usize,
        guides: usize,
        points_per_strand: usize,
    ) {
        layout.add::<[f32; 3]>(vertices);
        let n = guides.saturating_mul(points_per_strand).saturating_mul(6);
        layout.add::<f32>(n);
    }

    /// Checks the deformed `mesh`, computes its vertex tangents and makes
    /// room for `guide_count` guides of `points_per_strand` points (2..=64).
    /// The frame has no guides until [`PosedFrame::pose`].
    pub fn new<'a: 'm>(
        mesh: Mesh<'m>,
        guide_count: usize,
        points_per_strand: usize,
        arena: &mut Arena<'a>,
    ) -> Result<Self, Error> {
        let floats = PosedFrame::check_sizes(guide_count, points_per_strand)?;
        mesh.check()?;
        let tangents = arena.alloc::<[f32; 3]>(mesh.positions.len())?;
        let data = arena.alloc::<f32>(floats)?;
        frame::vertex_tangents(&mesh, tangents);
        Ok(PosedFrame {
            mesh,
            tangents,
            data,
            points: points_per_strand,
            guides: guide_count,
            posed: false,
            origin: [0.0; 3],
        })
    }

    /// Checks a guide count (1 .. u32::MAX) and point count (2..=64) and
    /// gives the floats the guides take.
    pub fn check_sizes(guide_count: usize, points_per_strand: usize) -> Result<usize, Error> {
        if !(2..=MAX_STRAND_POINTS).contains(&points_per_strand) {
            return Err(Error::InvalidArgument(
                "points_per_strand must be in 2..=64",
            ));
        }
        if guide_count == 0 {
            return Err(Error::InvalidArgument("no guides"));
        }
        // bindings name guides by u32, with u32::MAX for none
        if guide_count >= u32::MAX as usize {
            return Err(Error::InvalidArgument(
                "more guides than a binding can name",
            ));
        }
        guide_count
            .checked_mul(6 * points_per_strand)
            .filter(|&f| f <= isize::MAX as usize / 4)
            .ok_or(Error::InvalidArgument("guide count too large"))
    }

    /// [`PosedFrame::new`], then [`PosedFrame::pose`] with `guides`.
    pub fn with_guides<'a: 'm>(
        mesh: Mesh<'m>,
        guides: &Guides,
        points_per_strand: usize,
        arena: &mut Arena<'a>,
    ) -> Result<Self, Error> {
        let mut frame = PosedFrame::new(mesh, guides.len(), points_per_strand, arena)?;
        frame.pose(guides)?;
        Ok(frame)
    }

    /// Checks `guides` against the mesh and the guide count and fills the
    /// frame with them. On error the frame keeps the guides it had.
    pub fn pose(&mut self, guides: &Guides) -> Result<(), Error> {
        let posing = self.posing(guides)?;
        posing.filler.fill(0, posing.data);
        posing.finish();
        Ok(())
    }

    /// [`PosedFrame::pose`] in steps, for a host that fills the guides in
    /// parallel: this checks `guides`; the host has [`GuideFiller::fill`]
    /// fill every guide through disjoint parts of [`Posing::data`], then
    /// calls [`Posing::finish`] (the same bits as `pose` for any split).
    pub fn posing<'r>(&'r mut self, guides: &'r Guides<'r>) -> Result<Posing<'r>, Error> {
        guides.validate(&self.mesh)?;
        self.posing_from(guides)
    }

    /// [`posing`](Self::posing) from guide points already checked (finite,
    /// within range, roots on this frame's mesh): only their count is.
    pub(crate) fn posing_from<'r, S: GuidePoints>(
        &'r mut self,
        source: S,
    ) -> Result<Posing<'r, S>, Error> {
        if source.roots().len() != self.guides {
            return Err(Error::InvalidArgument(
                "the guide count differs from the frame's",
            ));
        }
        Ok(Posing {
            filler: GuideFiller {
                mesh: &self.mesh,
                tangents: self.tangents,
                source,
                points: self.points,
            },
            data: self.data,
            posed: &mut self.posed,
        })
    }

    /// Checks `params`, and that the frame is posed for their point count.
    pub fn check_params(&self, params: &ExpandParams) -> Result<(), Error> {
        params.check()?;
        if !self.posed {
            return Err(Error::InvalidArgument("the frame has no posed guides"));
        }
        if params.points_per_strand != self.points {
            return Err(Error::InvalidArgument(
                "the frame was posed for another point count",
            ));
        }
        Ok(())
    }

    /// Sets where the frame's local space sits in the host's world: its
    /// mesh, guides, colliders and every output are relative to `origin`
    /// (world = origin + local), which the host keeps in double precision.
    /// A character far from the world's origin, given relative to an
    /// origin near it, keeps float32's precision (at 1e4 a float32 world
    /// point is only good to about 1e-3). A simulation stepping through
    /// frames whose origins differ carries its state across by their
    /// difference, taken in double precision (see
    /// [`Sim::begin`](crate::dynamics::sim::Sim::begin)). The origin must
    /// be finite and within [`MAX_ORIGIN`].
    pub fn set_origin(&mut self, origin: [f64; 3]) -> Result<(), Error> {
        if let Some(index) = origin.iter().position(|c| !c.is_finite()) {
            return Err(Error::NonFinite {
                what: "origin",
                index,
            });
        }
        if origin.iter().any(|c| c.abs() > MAX_ORIGIN) {
            return Err(Error::InvalidArgument("origin beyond 1e15"));
        }
        self.origin = origin;
        Ok(())
    }

    /// Where the frame's local space sits in the host's world.
    pub fn origin(&self) -> [f64; 3] {
        self.origin
    }

    /// The deformed mesh (checked).
    pub fn mesh(&self) -> &Mesh<'m> {
        &self.mesh
    }

    /// Number of guides.
    pub fn guide_count(&self) -> usize {
        self.guides
    }

    /// Points per guide (the strand point count it was made for).
    pub fn points(&self) -> usize {
        self.points
    }

    /// True once guides were posed.
    pub fn is_posed(&self) -> bool {
        self.posed
    }

    /// The root frame at barycentric (u, v) on `face` of this frame's mesh.
    pub fn root_frame(&self, face: usize, u: f32, v: f32) -> Frame {
        Frame::at(&self.mesh, self.tangents, face, u, v)
    }

    /// Every guide's points in its root frame, guide after guide (on the
    /// rest mesh: the rest shapes a groom file stores).
    pub fn local_points(&self) -> impl Iterator<Item = [f32; 3]> + '_ {
        let n = self.points;
        (0..self.guides * n).map(move |k| self.local_point(k / n, k % n).to_array())
    }

    /// Point `j` of guide `g` in the guide's root frame.
    pub fn local_point(&self, g: usize, j: usize) -> Vec3 {
        let l = self.local(g);
        Vec3::new(l[j], l[self.points + j], l[2 * self.points + j])
    }

    /// Point `j` of guide `g` in world space.
    pub fn world_point(&self, g: usize, j: usize) -> Vec3 {
        let w = self.world(g);
        Vec3::new(w[j], w[self.points + j], w[2 * self.points + j])
    }

    /// For decoders in this crate: the mesh, its tangents, every guide
    /// slot (see [`GuideFiller::floats_per_guide`]) and the posed flag.
    pub(crate) fn slots(&mut self) -> (&Mesh<'m>, &[[f32; 3]], &mut [f32], &mut bool) {
        (&self.mesh, self.tangents, self.data, &mut self.posed)
    }

    /// The mesh's vertex tangents.
    pub(crate) fn tangents(&self) -> &[[f32; 3]] {
        self.tangents
    }

    /// Guide `g`'s local x, y and z lanes.
    #[inline(always)]
    pub(crate) fn local(&self, g: usize) -> &[f32] {
        let n = self.points;
        &self.data[g * 6 * n..g * 6 * n + 3 * n]
    }

    /// Guide `g`'s world x, y and z lanes.
    #[inline(always)]
    pub(crate) fn world(&self, g: usize) -> &[f32] {
        let n = self.points;
        &self.data[g * 6 * n + 3 * n..(g + 1) * 6 * n]
    }
}

/// The world points a frame's guides are posed from: a host's guides
/// ([`Guides`]) or a simulation's last step
/// ([`Sim::posing`](crate::dynamics::sim::Sim::posing)).
pub trait GuidePoints: Copy + Sync {
    /// Each guide's root.
    fn roots(&self) -> &[Root];
    /// Hands `visit` each point `j` of guide `g` resampled to `n` points
    /// (n >= 2), in order.
    fn each_point(&self, g: usize, n: usize, visit: impl FnMut(usize, Vec3));
}

impl GuidePoints for &Guides<'_> {
    fn roots(&self) -> &[Root] {
        self.roots
    }

    #[inline]
    fn each_point(&self, g: usize, n: usize, mut visit: impl FnMut(usize, Vec3)) {
        let step = 1.0 / (n - 1) as f32;
        let (_, count) = self.span(g);
        for j in 0..n {
            visit(
                j,
                if count == n {
                    self.point(g, j)
                } else {
                    self.sample(g, j as f32 * step)
                },
            );
        }
    }
}

/// A [`PosedFrame`] being filled with checked guides (see
/// [`PosedFrame::posing`]).
pub struct Posing<'r, S = &'r Guides<'r>> {
    /// Fills ranges of guides.
    pub filler: GuideFiller<'r, S>,
    /// [`GuideFiller::floats_per_guide`] floats per guide, guide after guide.
    pub data: &'r mut [f32],
    posed: &'r mut bool,
}

impl Posing<'_> {
    /// Marks the frame posed, once every guide is filled.
    pub fn finish(self) {
        *self.posed = true;
    }
}

impl<S> Posing<'_, S> {
    /// Marks the frame posed, for a source whose own finish checked it.
    pub(crate) fn finish_unchecked(self) {
        *self.posed = true;
    }

    /// Marks the frame without guides until it is finished: for guides
    /// checked while they fill it.
    pub fn unpose(&mut self) {
        *self.posed = false;
    }

    /// The points the guides are posed from.
    pub(crate) fn source(&self) -> &S {
        &self.filler.source
    }
}

/// Fills the slots of a range of guides (see [`Posing`]).
#[derive(Clone, Copy)]
pub struct GuideFiller<'r, S = &'r Guides<'r>> {
    mesh: &'r Mesh<'r>,
    tangents: &'r [[f32; 3]],
    source: S,
    points: usize,
}

impl<S: GuidePoints> GuideFiller<'_, S> {
    /// Floats each guide takes.
    pub fn floats_per_guide(&self) -> usize {
        6 * self.points
    }

    /// Fills the guides `first ..` that `part` holds (its length over
    /// [`GuideFiller::floats_per_guide`]).
    pub fn fill(&self, first: usize, part: &mut [f32]) {
        let n = self.points;
        // frames a block at a time (their square-root chains overlap)
        let (mut frames, mut basis) = ([Frame::default(); FRAME_LANES], None);
        for (i, slot) in part.chunks_exact_mut(6 * n).enumerate() {
            let g = first + i;
            if i % FRAME_LANES == 0 {
                let roots = &self.source.roots()[g..];
                frame::frames(self.mesh, self.tangents, roots, &mut basis, &mut frames);
            }
            let frame = &frames[i % FRAME_LANES];
            let (local, world) = slot.split_at_mut(3 * n);
            self.source.each_point(g, n, |j, p| {
                let l = frame.to_local(p);
                (local[j], local[n + j], local[2 * n + j]) = (l.x, l.y, l.z);
                (world[j], world[n + j], world[2 * n + j]) = (p.x, p.y, p.z);
            });
        }
    }
}
