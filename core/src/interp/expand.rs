//! Expanding render strands from posed guides (every frame, any range).
//!
//! Guides are first expressed in their own root frames on the deformed mesh
//! ([`PreparedGuides`], once per frame). A strand's points are the weighted
//! average of its guides' local points, shaped by its groom values, and
//! carried back to world space by the strand's own root frame (paper 2.2).

use crate::arena::{Arena, ArenaLayout};
use crate::guides::Guides;
use crate::interp::bind::{StrandBinding, NO_GUIDE};
use crate::interp::groom::StrandGroom;
use crate::surface::frame::{self, FaceBasis, Frame, FRAME_LANES};
use crate::{Error, Mesh, Root};
use glam::{Vec2, Vec3};

/// Most control points per strand.
pub const MAX_STRAND_POINTS: usize = 64;

/// How curve ends are written for a Catmull-Rom consumer.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EndPoints {
    /// The points as they are; a Catmull-Rom curve (Embree, RenderMan) spans
    /// the second to the second-last point.
    Raw = 0,
    /// First and last points repeated ("pinned" in USD), so the curve runs
    /// from the root to the tip.
    Pinned = 1,
}

/// Expansion parameters.
#[derive(Clone, Copy, Debug)]
pub struct ExpandParams {
    /// Control points per strand before end handling (2..=64); guides are
    /// resampled to it. Catmull-Rom consumers need 4 points per curve, so
    /// with `Raw` ends use at least 4.
    pub points_per_strand: usize,
    /// End-point convention of the output.
    pub end_points: EndPoints,
    /// Length of orphan strands (no eligible guide), grown along the normal.
    pub orphan_length: f32,
}

impl ExpandParams {
    /// Control points written per strand.
    pub fn output_points(&self) -> usize {
        self.points_per_strand + 2 * (self.end_points == EndPoints::Pinned) as usize
    }

    /// Checks the point count and orphan length.
    pub fn check(&self) -> Result<(), Error> {
        if !(2..=MAX_STRAND_POINTS).contains(&self.points_per_strand) {
            return Err(Error::InvalidArgument(
                "points_per_strand must be in 2..=64",
            ));
        }
        if !(self.orphan_length >= 0.0 && self.orphan_length.is_finite()) {
            return Err(Error::InvalidArgument(
                "orphan_length must be finite and >= 0",
            ));
        }
        Ok(())
    }
}

/// Posed guides resampled to the strand point count, in their own root
/// frames (local) and in world space, and the deformed mesh's vertex
/// tangents (see [`frame::vertex_tangents`]), for one frame.
///
/// Each guide is stored as its n local x, then n y, then n z coordinates,
/// then the same for its world points, so the per-strand loops run over
/// contiguous lanes and vectorize (element-wise only: the bits are the same
/// as a scalar loop's on every target), and a strand's clump centre (one of
/// its guides) sits beside that guide's local points.
pub struct PreparedGuides<'a> {
    data: &'a [f32],
    tangents: &'a [[f32; 3]],
    points: usize,
    guides: usize,
}

impl<'a> PreparedGuides<'a> {
    /// Adds the arena bytes [`PreparedGuides::new`] needs for a mesh of
    /// `vertices` vertices.
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

    /// Validates the deformed mesh and posed guides and prepares them.
    pub fn new(
        mesh: &Mesh,
        guides: &Guides,
        points_per_strand: usize,
        arena: &mut Arena<'a>,
    ) -> Result<Self, Error> {
        let slots = GuideSlots::new(mesh, guides, points_per_strand, arena)?;
        slots.filler.fill(0, slots.data);
        Ok(slots.finish())
    }

    /// Number of guides.
    pub fn len(&self) -> usize {
        self.guides
    }

    /// True when there is no guide.
    pub fn is_empty(&self) -> bool {
        self.guides == 0
    }

    /// Points per guide.
    pub fn points(&self) -> usize {
        self.points
    }

    /// The frame expansion gives a root at barycentric (u, v) on `face` of
    /// this frame's mesh.
    pub fn frame(&self, mesh: &Mesh, face: usize, u: f32, v: f32) -> Frame {
        Frame::at(mesh, self.tangents, face, u, v)
    }

    /// Point `j` of guide `g` in the guide's root frame.
    pub fn local_point(&self, g: usize, j: usize) -> Vec3 {
        let l = self.local(g);
        Vec3::new(l[j], l[self.points + j], l[2 * self.points + j])
    }

    /// Guide `g`'s local x, y and z lanes.
    #[inline(always)]
    fn local(&self, g: usize) -> &[f32] {
        let n = self.points;
        &self.data[g * 6 * n..g * 6 * n + 3 * n]
    }

    /// Guide `g`'s world x, y and z lanes.
    #[inline(always)]
    fn world(&self, g: usize) -> &[f32] {
        let n = self.points;
        &self.data[g * 6 * n + 3 * n..(g + 1) * 6 * n]
    }
}

/// [`PreparedGuides::new`] in two steps, for a host that fills the guides
/// in parallel: `new` validates and allocates, the host has
/// [`GuideFiller::fill`] fill every guide through disjoint parts of `data`,
/// then [`GuideSlots::finish`] gives the prepared guides (the same bits as
/// `PreparedGuides::new`, for any split).
pub struct GuideSlots<'r, 'a> {
    /// Fills ranges of guides.
    pub filler: GuideFiller<'r>,
    /// [`GuideFiller::floats_per_guide`] floats per guide, guide after guide.
    pub data: &'a mut [f32],
    tangents: &'a [[f32; 3]],
}

impl<'r, 'a: 'r> GuideSlots<'r, 'a> {
    /// Validates the deformed mesh and posed guides, computes the mesh's
    /// vertex tangents and allocates the guides' slots.
    pub fn new(
        mesh: &'r Mesh<'r>,
        guides: &'r Guides<'r>,
        points_per_strand: usize,
        arena: &mut Arena<'a>,
    ) -> Result<Self, Error> {
        if !(2..=MAX_STRAND_POINTS).contains(&points_per_strand) {
            return Err(Error::InvalidArgument(
                "points_per_strand must be in 2..=64",
            ));
        }
        mesh.check()?;
        guides.validate(mesh)?;
        let tangents = arena.alloc::<[f32; 3]>(mesh.positions.len())?;
        let data = arena.alloc::<f32>(guides.len() * points_per_strand * 6)?;
        frame::vertex_tangents(mesh, tangents);
        let tangents = &*tangents;
        Ok(GuideSlots {
            filler: GuideFiller {
                mesh,
                tangents,
                guides,
                points: points_per_strand,
            },
            data,
            tangents,
        })
    }

    /// The prepared guides, once every guide is filled.
    pub fn finish(self) -> PreparedGuides<'a> {
        PreparedGuides {
            data: self.data,
            tangents: self.tangents,
            points: self.filler.points,
            guides: self.filler.guides.len(),
        }
    }
}

/// Fills the slots of a range of guides (see [`GuideSlots`]).
#[derive(Clone, Copy)]
pub struct GuideFiller<'r> {
    mesh: &'r Mesh<'r>,
    tangents: &'r [[f32; 3]],
    guides: &'r Guides<'r>,
    points: usize,
}

impl GuideFiller<'_> {
    /// Floats each guide takes.
    pub fn floats_per_guide(&self) -> usize {
        6 * self.points
    }

    /// Fills the guides `first ..` that `part` holds (its length over
    /// [`GuideFiller::floats_per_guide`]).
    pub fn fill(&self, first: usize, part: &mut [f32]) {
        let n = self.points;
        let step = 1.0 / (n - 1) as f32;
        for (i, slot) in part.chunks_exact_mut(6 * n).enumerate() {
            let g = first + i;
            let r = &self.guides.roots[g];
            let frame = Frame::at(self.mesh, self.tangents, r.face as usize, r.u, r.v);
            let (_, count) = self.guides.span(g);
            let (local, world) = slot.split_at_mut(3 * n);
            for j in 0..n {
                let p = if count == n {
                    self.guides.point(g, j)
                } else {
                    self.guides.sample(g, j as f32 * step)
                };
                let l = frame.to_local(p);
                (local[j], local[n + j], local[2 * n + j]) = (l.x, l.y, l.z);
                (world[j], world[n + j], world[2 * n + j]) = (p.x, p.y, p.z);
            }
        }
    }
}

/// The per-strand inputs of expansion: parallel arrays, index for index.
#[derive(Clone, Copy, Debug)]
pub struct Strands<'a> {
    /// Where each strand grows (its `id` seeds nothing here; grooms hold
    /// the per-strand randomness).
    pub roots: &'a [Root],
    /// Guides and weights of each strand.
    pub bindings: &'a [StrandBinding],
    /// Groom values of each strand.
    pub grooms: &'a [StrandGroom],
}

impl<'a> Strands<'a> {
    /// Number of strands.
    pub fn len(&self) -> usize {
        self.roots.len()
    }

    /// True when there is no strand.
    pub fn is_empty(&self) -> bool {
        self.roots.is_empty()
    }

    /// The strands in `range` (of the roots; bindings and grooms are cut alike).
    pub fn range(&self, range: core::ops::Range<usize>) -> Strands<'a> {
        Strands {
            roots: &self.roots[range.clone()],
            bindings: &self.bindings[range.clone()],
            grooms: &self.grooms[range],
        }
    }
}

/// Validates everything [`expand`] reads, for an output of `out_len` bytes:
/// the mesh, [`check_frame`], [`check_output`] and [`check_strands`]
/// ([`PreparedGuides::new`] has validated its mesh already). A threaded host
/// runs these before splitting (the strand checks may themselves run per
/// range, in parallel), so that no range writes when another would fail.
pub fn check_inputs(
    mesh: &Mesh,
    strands: &Strands,
    guides: &PreparedGuides,
    params: &ExpandParams,
    out_len: usize,
    stride: usize,
) -> Result<(), Error> {
    mesh.check()?;
    check_frame(guides, params)?;
    check_output(strands.len(), params, out_len, stride)?;
    check_strands(mesh, strands, guides)
}

/// Validates the parameters, and that `guides` were prepared for the point
/// count.
pub fn check_frame(guides: &PreparedGuides, params: &ExpandParams) -> Result<(), Error> {
    params.check()?;
    if params.points_per_strand != guides.points {
        return Err(Error::InvalidArgument(
            "guides were prepared for another point count",
        ));
    }
    Ok(())
}

/// Checks that `out_len` bytes hold the curves of `count` strands at `stride`.
pub fn check_output(
    count: usize,
    params: &ExpandParams,
    out_len: usize,
    stride: usize,
) -> Result<(), Error> {
    if stride < 16 {
        return Err(Error::BadStride {
            what: "curve points",
        });
    }
    let needed = count
        .checked_mul(params.output_points())
        .and_then(|total| total.checked_sub(1))
        .map_or(Some(0), |last| {
            last.checked_mul(stride).and_then(|b| b.checked_add(16))
        })
        .ok_or(Error::InvalidArgument("curve output size overflows"))?;
    if out_len < needed {
        return Err(Error::OutputTooSmall {
            needed,
            available: out_len,
        });
    }
    Ok(())
}

/// Validates the strands, their bindings and grooms against a mesh already
/// validated (by [`Mesh::validate`] or [`PreparedGuides::new`]) and the
/// prepared `guides`. The first faulty strand is reported.
pub fn check_strands(mesh: &Mesh, strands: &Strands, guides: &PreparedGuides) -> Result<(), Error> {
    check_strands_within(strands, mesh.triangle_count(), guides.guides)
}

/// [`check_strands`] against `faces` triangles and `guides` guides.
fn check_strands_within(strands: &Strands, faces: usize, guides: usize) -> Result<(), Error> {
    let Strands {
        roots,
        bindings,
        grooms,
    } = *strands;
    if bindings.len() < roots.len() || grooms.len() < roots.len() {
        return Err(Error::InvalidArgument(
            "bindings and grooms must cover every strand",
        ));
    }
    // this runs every frame over every strand: a branch-free screen passes
    // the valid ones, and the detailed checks run only on a strand it
    // rejects, to name the fault
    for (i, ((r, b), g)) in roots.iter().zip(bindings).zip(grooms).enumerate() {
        if !strand_is_valid(faces, guides, r, b, g) {
            check_strand(faces, guides, r, b, g).map_err(|e| e.shifted(i))?;
        }
    }
    Ok(())
}

/// The smallest mesh and guide set that strand records checked by
/// [`StrandBounds::new`] fit: all that is left to check per frame.
///
/// A host that keeps a groom's strands across frames checks the records
/// once, then each frame checks only these two counts (O(1)) before
/// [`expand_checked`], instead of reading every record again with
/// [`check_strands`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StrandBounds {
    /// Largest root face + 1 (0 without strands), and a strand on it.
    faces: (usize, usize),
    /// Largest guide index a binding uses + 1 (0 when none), and a strand using it.
    guides: (usize, usize),
}

impl StrandBounds {
    /// Checks everything about `strands` that does not depend on the mesh
    /// or the guides (what [`check_strands`] checks, short of face and
    /// guide counts), and finds the counts they need.
    pub fn new(strands: &Strands) -> Result<Self, Error> {
        // every index a u32 holds is some mesh's face; NO_GUIDE is no guide
        check_strands_within(strands, u32::MAX as usize, NO_GUIDE as usize)?;
        let mut bounds = StrandBounds::default();
        for (i, (r, b)) in strands.roots.iter().zip(strands.bindings).enumerate() {
            if r.face as usize >= bounds.faces.0 {
                bounds.faces = (r.face as usize + 1, i);
            }
            let clump = (b.clump != NO_GUIDE).then_some(&b.clump);
            for &g in b.guides[..b.count as usize].iter().chain(clump) {
                if g as usize >= bounds.guides.0 {
                    bounds.guides = (g as usize + 1, i);
                }
            }
        }
        Ok(bounds)
    }

    /// Checks that the strands fit `mesh` and `guides`: with [`check_frame`]
    /// and [`check_output`], what [`check_inputs`] checks.
    pub fn check(&self, mesh: &Mesh, guides: &PreparedGuides) -> Result<(), Error> {
        self.fits(mesh.triangle_count(), guides.len())
    }

    /// [`StrandBounds::check`] against `faces` triangles and `guides` guides.
    fn fits(&self, faces: usize, guides: usize) -> Result<(), Error> {
        let ((needed, face_strand), (used, guide_strand)) = (self.faces, self.guides);
        if needed > faces {
            return Err(Error::OutOfRange {
                what: "strand roots",
                index: face_strand,
                value: needed - 1,
                bound: faces,
            });
        }
        if used > guides {
            return Err(Error::OutOfRange {
                what: "bindings",
                index: guide_strand,
                value: used - 1,
                bound: guides,
            });
        }
        Ok(())
    }
}

/// Exactly the conditions [`check_strand`] tests, without a branch.
#[inline]
fn strand_is_valid(
    faces: usize,
    guides: usize,
    r: &Root,
    b: &StrandBinding,
    g: &StrandGroom,
) -> bool {
    // comparisons are false for NaN, and an infinite coordinate fails the sum
    let e = crate::root::BARYCENTRIC_SLACK;
    let root = ((r.face as usize) < faces) & (r.u >= -e) & (r.v >= -e) & (r.u + r.v <= 1.0 + e);
    let count = b.count as usize;
    let mut binding = count <= crate::interp::bind::MAX_NEIGHBOURS;
    for k in 0..crate::interp::bind::MAX_NEIGHBOURS {
        let fine = ((b.guides[k] as usize) < guides) & b.weights[k].is_finite();
        binding &= (k >= count) | fine;
    }
    binding &= (b.clump == NO_GUIDE) | ((b.clump as usize) < guides);
    let values: &[f32] = bytemuck::cast_slice(core::slice::from_ref(g));
    let finite = values.iter().fold(true, |all, v| all & v.is_finite());
    let pi2 = core::f32::consts::PI * core::f32::consts::PI;
    let groom = finite
        & (g.root_radius >= 0.0)
        & (g.tip_radius >= 0.0)
        & (g.length >= 0.0)
        & (Vec2::from(g.lift).length_squared() <= pi2);
    root & binding & groom
}

/// Checks one strand, naming the first fault (element index 0).
fn check_strand(
    faces: usize,
    bound: usize,
    r: &Root,
    b: &StrandBinding,
    g: &StrandGroom,
) -> Result<(), Error> {
    crate::root::check_root(faces, r, "strand roots")?;
    let count = b.count as usize;
    if count > crate::interp::bind::MAX_NEIGHBOURS {
        return Err(Error::OutOfRange {
            what: "binding counts",
            index: 0,
            value: count,
            bound: crate::interp::bind::MAX_NEIGHBOURS + 1,
        });
    }
    let bad_guide = b.guides[..count].iter().find(|&&g| g as usize >= bound);
    let bad_clump = (b.clump != NO_GUIDE && b.clump as usize >= bound).then_some(&b.clump);
    if let Some(&value) = bad_guide.or(bad_clump) {
        return Err(Error::OutOfRange {
            what: "bindings",
            index: 0,
            value: value as usize,
            bound,
        });
    }
    if !b.weights[..count].iter().all(|w| w.is_finite()) {
        return Err(Error::NonFinite {
            what: "binding weights",
            index: 0,
        });
    }
    let values: &[f32] = bytemuck::cast_slice(core::slice::from_ref(g));
    if !values.iter().all(|v| v.is_finite()) {
        return Err(Error::NonFinite {
            what: "grooms",
            index: 0,
        });
    }
    if g.root_radius < 0.0 || g.tip_radius < 0.0 || g.length < 0.0 {
        return Err(Error::InvalidArgument(
            "a groom has a negative radius or length",
        ));
    }
    if Vec2::from(g.lift).length_squared() > core::f32::consts::PI * core::f32::consts::PI {
        return Err(Error::InvalidArgument(
            "a groom's lift turns by more than pi",
        ));
    }
    Ok(())
}

/// Writes the curves of `strands` into `out`: `output_points()` float4
/// (x, y, z, radius) per strand, `stride` bytes apart, strand after strand.
///
/// Every strand is a pure function of its inputs, so any split of a strand
/// list into ranges gives the same bits. Nothing is written on error.
pub fn expand(
    mesh: &Mesh,
    strands: &Strands,
    guides: &PreparedGuides,
    params: &ExpandParams,
    out: &mut [u8],
    stride: usize,
) -> Result<(), Error> {
    check_inputs(mesh, strands, guides, params, out.len(), stride)?;
    expand_checked(mesh, strands, guides, params, out, stride);
    Ok(())
}

/// [`expand`] without the input checks, for a host that ran
/// [`check_inputs`] once over all strands before splitting them into ranges
/// (each range of checked inputs is itself checked). Inputs that would have
/// failed the checks make it panic instead of returning an error.
pub fn expand_checked(
    mesh: &Mesh,
    strands: &Strands,
    guides: &PreparedGuides,
    params: &ExpandParams,
    out: &mut [u8],
    stride: usize,
) {
    expand_kernel(mesh, strands, guides, params, out, stride);
}

/// [`expand_checked`] compiled for AVX2: the same operations in the same
/// order (no fused multiply-add), so the same bits, in wider registers.
///
/// # Safety
/// The CPU must have AVX2: a host checks first (for example with
/// `is_x86_feature_detected!("avx2")`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub fn expand_checked_avx2(
    mesh: &Mesh,
    strands: &Strands,
    guides: &PreparedGuides,
    params: &ExpandParams,
    out: &mut [u8],
    stride: usize,
) {
    expand_kernel(mesh, strands, guides, params, out, stride);
}

/// The body of [`expand_checked`], inlined whole into each entry so that the
/// AVX2 entry compiles every per-strand step for AVX2.
#[inline(always)]
fn expand_kernel(
    mesh: &Mesh,
    strands: &Strands,
    guides: &PreparedGuides,
    params: &ExpandParams,
    out: &mut [u8],
    stride: usize,
) {
    // the common counts get loops of known length (see `strand`), chosen
    // once per call rather than per strand
    match params.points_per_strand {
        8 => fill_all::<8>(mesh, strands, guides, params, out, stride),
        16 => fill_all::<16>(mesh, strands, guides, params, out, stride),
        32 => fill_all::<32>(mesh, strands, guides, params, out, stride),
        _ => fill_all::<0>(mesh, strands, guides, params, out, stride),
    }
}

/// [`expand_kernel`] for `N` points per strand (0: any).
#[inline(always)]
fn fill_all<const N: usize>(
    mesh: &Mesh,
    strands: &Strands,
    guides: &PreparedGuides,
    params: &ExpandParams,
    out: &mut [u8],
    stride: usize,
) {
    let per = params.output_points();
    let mut filler = Filler {
        mesh,
        strands,
        guides,
        params,
        lanes: Lanes::new(params.points_per_strand),
        basis: None,
        frames: [Frame::default(); FRAME_LANES],
    };
    let n = strands.len();
    // packed float4 output is written in place
    if stride == 16 {
        if let Ok(all) = bytemuck::try_cast_slice_mut::<u8, [f32; 4]>(&mut out[..n * per * 16]) {
            for (s, curve) in all.chunks_exact_mut(per).enumerate() {
                filler.fill::<N>(s, curve);
            }
            return;
        }
    }
    let mut buffer = [[0.0f32; 4]; MAX_STRAND_POINTS + 2];
    for s in 0..n {
        filler.fill::<N>(s, &mut buffer[..per]);
        let region = &mut out[s * per * stride..];
        for (j, p) in buffer[..per].iter().enumerate() {
            region[j * stride..j * stride + 16].copy_from_slice(bytemuck::bytes_of(p));
        }
    }
}

/// What [`expand_kernel`] carries from strand to strand.
struct Filler<'r, 'a> {
    mesh: &'r Mesh<'a>,
    strands: &'r Strands<'a>,
    guides: &'r PreparedGuides<'a>,
    params: &'r ExpandParams,
    lanes: Lanes,
    basis: Option<(u32, FaceBasis)>,
    /// Root frames of the current block of strands.
    frames: [Frame; FRAME_LANES],
}

impl Filler<'_, '_> {
    /// Writes strand `s` to `curve`. Strands are filled in order: the
    /// frames of a block are computed at its first strand, so that their
    /// square-root chains overlap (see `frame::frames`).
    #[inline(always)]
    fn fill<const N: usize>(&mut self, s: usize, curve: &mut [[f32; 4]]) {
        let slot = s % FRAME_LANES;
        if slot == 0 {
            let roots = &self.strands.roots[s..];
            let tangents = self.guides.tangents;
            frame::frames(
                self.mesh,
                tangents,
                roots,
                &mut self.basis,
                &mut self.frames,
            );
        }
        strand_n::<N>(
            &self.frames[slot],
            &self.strands.bindings[s],
            &self.strands.grooms[s],
            self.guides,
            self.params,
            &mut self.lanes,
            curve,
        );
    }
}

/// Per-strand working lanes, reused across the strands of one call (zeroing
/// fresh arrays per strand would cost more than the arithmetic).
pub(crate) struct Lanes {
    /// Parameter of each point along the strand, j / (n - 1).
    t: [f32; MAX_STRAND_POINTS],
    local: [f32; 3 * MAX_STRAND_POINTS],
    /// The kink wave without phase for `wave_frequency` (bits; NaN when
    /// none yet): neighbouring strands share a frequency, so it is reused.
    wave: [[f32; MAX_STRAND_POINTS]; 2],
    wave_frequency: u32,
}

impl Lanes {
    pub(crate) fn new(n: usize) -> Self {
        let mut t = [0.0f32; MAX_STRAND_POINTS];
        let step = 1.0 / (n - 1) as f32;
        for (j, tj) in t[..n].iter_mut().enumerate() {
            *tj = j as f32 * step;
        }
        Lanes {
            t,
            local: [0.0; 3 * MAX_STRAND_POINTS],
            wave: [[0.0; MAX_STRAND_POINTS]; 2],
            wave_frequency: f32::NAN.to_bits(),
        }
    }
}

/// Writes one strand into `out`: its `points_per_strand` points, and with
/// pinned ends the first and last again around them
/// ([`ExpandParams::output_points`] in all).
#[inline]
pub(crate) fn strand(
    frame: &Frame,
    bind: &StrandBinding,
    groom: &StrandGroom,
    guides: &PreparedGuides,
    params: &ExpandParams,
    lanes: &mut Lanes,
    out: &mut [[f32; 4]],
) {
    // the common counts get loops of known length (unrolled, vectorized
    // whole); the same operations in the same order, so the same bits
    match params.points_per_strand {
        8 => strand_n::<8>(frame, bind, groom, guides, params, lanes, out),
        16 => strand_n::<16>(frame, bind, groom, guides, params, lanes, out),
        32 => strand_n::<32>(frame, bind, groom, guides, params, lanes, out),
        _ => strand_n::<0>(frame, bind, groom, guides, params, lanes, out),
    }
}

/// [`strand`] for `N` points, or for `params.points_per_strand` when `N` is 0.
#[inline(always)]
fn strand_n<const N: usize>(
    frame: &Frame,
    bind: &StrandBinding,
    groom: &StrandGroom,
    guides: &PreparedGuides,
    params: &ExpandParams,
    lanes: &mut Lanes,
    out: &mut [[f32; 4]],
) {
    // checked by ExpandParams::check; the min lets the compiler drop bounds checks
    let n = if N == 0 {
        params.points_per_strand.min(MAX_STRAND_POINTS)
    } else {
        N
    };
    let t = &lanes.t[..n];
    // x lanes, then y, then z, as a prepared guide stores its points: the
    // weighted sum is one flat loop over both
    let local = &mut lanes.local[..3 * n];
    // the tip is summed again in scalars, in the same order (so to the same
    // bits): read back from the vector sums, it would wait for their stores
    let tip = if bind.count == 0 {
        local[..2 * n].fill(0.0);
        for (z, tj) in local[2 * n..].iter_mut().zip(t) {
            *z = params.orphan_length * tj;
        }
        Vec3::new(0.0, 0.0, local[3 * n - 1])
    } else {
        let (g, w) = (
            &guides.local(bind.guides[0] as usize)[..3 * n],
            bind.weights[0],
        );
        let mut sum = Vec3::new(g[n - 1], g[2 * n - 1], g[3 * n - 1]) * w;
        for (a, g) in local.iter_mut().zip(g) {
            *a = g * w;
        }
        for k in 1..bind.count as usize {
            let w = bind.weights[k];
            let g = &guides.local(bind.guides[k] as usize)[..3 * n];
            sum += Vec3::new(g[n - 1], g[2 * n - 1], g[3 * n - 1]) * w;
            for (a, g) in local.iter_mut().zip(g) {
                *a += g * w;
            }
        }
        sum
    };
    let (ax, rest) = local.split_at_mut(n);
    let (ay, az) = rest.split_at_mut(n);
    let scale = groom.length;
    let length = tip.length() * scale;
    let bend = groom.bend * length;
    let mut shape = [scale, bend];
    if groom.lift != [0.0; 2] {
        // the lift turns the scaled, bent strand, so it is shaped first
        for j in 0..n {
            ax[j] = ax[j] * scale + bend * t[j] * t[j];
            ay[j] *= scale;
            az[j] *= scale;
        }
        lift(groom.lift, ax, ay, az);
        shape = [1.0, 0.0];
    }
    let clump = if bind.clump == NO_GUIDE {
        0.0
    } else {
        groom.clump
    };
    let kink = groom.kink_amplitude * length;
    let (r0, dr) = (groom.root_radius, groom.tip_radius - groom.root_radius);
    let look = Look {
        shape,
        clump,
        kink,
        phase: groom.kink_phase,
        radius: [r0, dr],
    };
    let pinned = params.end_points == EndPoints::Pinned;
    let shift = pinned as usize;
    let local = [&*ax, &*ay, &*az];
    let dst = &mut out[shift..shift + n];
    if clump == 0.0 && kink == 0.0 {
        place::<false>(frame, t, local, &NO_CLUMP, &lanes.wave, &look, dst);
    } else {
        if kink != 0.0 && lanes.wave_frequency != groom.kink_frequency.to_bits() {
            let [ws, wc] = &mut lanes.wave;
            kink_wave(groom.kink_frequency, n, &mut ws[..n], &mut wc[..n]);
            lanes.wave_frequency = groom.kink_frequency.to_bits();
        }
        let centre = match bind.clump {
            NO_GUIDE => &NO_CLUMP[..3 * n],
            g => &guides.world(g as usize)[..3 * n],
        };
        place::<true>(frame, t, local, centre, &lanes.wave, &look, dst);
    }
    // the output was stored point by point (16 bytes), so these loads
    // forward from the stores
    if pinned {
        out[0] = out[1];
        out[n + 1] = out[n];
    }
}

/// Stand-in clump centre for a strand without one (its pull is 0).
static NO_CLUMP: [f32; 3 * MAX_STRAND_POINTS] = [0.0; 3 * MAX_STRAND_POINTS];

/// One strand's look, from its groom values and its length.
struct Look {
    /// Length scale, and bend offset at the tip (both applied to local points).
    shape: [f32; 2],
    /// Pull toward the clump centre at the tip.
    clump: f32,
    /// Kink amplitude at the tip.
    kink: f32,
    /// Cosine and sine of the kink phase.
    phase: [f32; 2],
    /// Root radius, and tip minus root radius.
    radius: [f32; 2],
}

/// Places the local points `a` in the world through `frame`, pulls them
/// toward the clump centre `c` and adds the kink wave `wave` (when
/// `CLUMP_KINK`), and writes the points with their radii to `out`.
///
/// One pass per point with everything in registers: separate passes
/// stored and reloaded every lane between steps. A zero pull or kink
/// changes nothing, so one loop serves a strand with either.
#[inline(always)]
fn place<const CLUMP_KINK: bool>(
    frame: &Frame,
    t: &[f32],
    a: [&[f32]; 3],
    c: &[f32],
    wave: &[[f32; MAX_STRAND_POINTS]; 2],
    look: &Look,
    out: &mut [[f32; 4]],
) {
    let n = out.len();
    let (t, [ax, ay, az]) = (&t[..n], a.map(|a| &a[..n]));
    let (cx, cy, cz) = (&c[..n], &c[n..2 * n], &c[2 * n..3 * n]);
    let (ws, wc) = (&wave[0][..n], &wave[1][..n]);
    let (o, tt, b, nn) = (frame.origin, frame.t, frame.b, frame.n);
    let [scale, bend] = look.shape;
    let [cp, sp] = look.phase;
    let [r0, dr] = look.radius;
    for j in 0..n {
        let lx = ax[j] * scale + bend * t[j] * t[j];
        let (ly, lz) = (ay[j] * scale, az[j] * scale);
        let mut x = o.x + tt.x * lx + b.x * ly + nn.x * lz;
        let mut y = o.y + tt.y * lx + b.y * ly + nn.y * lz;
        let mut z = o.z + tt.z * lx + b.z * ly + nn.z * lz;
        if CLUMP_KINK {
            let pull = look.clump * t[j];
            x += (cx[j] - x) * pull;
            y += (cy[j] - y) * pull;
            z += (cz[j] - z) * pull;
            // sin and cos of (phase + j delta)
            let (ks, kc) = (sp * wc[j] + cp * ws[j], cp * wc[j] - sp * ws[j]);
            let k = look.kink * t[j];
            x += (tt.x * ks + b.x * kc) * k;
            y += (tt.y * ks + b.y * kc) * k;
            z += (tt.z * ks + b.z * kc) * k;
        }
        out[j] = [x, y, z, r0 + dr * t[j]];
    }
}

/// Rotates local points about the root by the rotation vector `(w.x, w.y, 0)`
/// (Rodrigues' formula): the paper's collision push-out by rotation about
/// the root, fixed per strand at rest in the strand's own frame, so it
/// follows the body and does not depend on the pose.
fn lift(w: [f32; 2], x: &mut [f32], y: &mut [f32], z: &mut [f32]) {
    let angle = libm::sqrtf(w[0] * w[0] + w[1] * w[1]);
    // a vector too small to square turns nothing (and has no axis)
    if angle == 0.0 {
        return;
    }
    let (kx, ky) = (w[0] / angle, w[1] / angle);
    let (s, c) = libm::sincosf(angle);
    for j in 0..x.len() {
        let (vx, vy, vz) = (x[j], y[j], z[j]);
        let along = (kx * vx + ky * vy) * (1.0 - c);
        x[j] = vx * c + ky * vz * s + kx * along;
        y[j] = vy * c - kx * vz * s + ky * along;
        z[j] = vz * c + (kx * vy - ky * vx) * s;
    }
}

/// sin and cos of `j * delta` for the `n` points of a kink wave of
/// `frequency` waves per strand, by rotation recurrences: four interleaved
/// chains, so the serial dependency is a quarter as long as one chain's.
/// A pure function of `frequency` and `n`.
fn kink_wave(frequency: f32, n: usize, sin: &mut [f32], cos: &mut [f32]) {
    const CHAINS: usize = 4;
    let delta = core::f32::consts::TAU * frequency / (n - 1) as f32;
    let (s1, c1) = libm::sincosf(delta);
    // the rotation by 4 delta by two double-angle steps, not another sincos
    let (s2, c2) = (2.0 * s1 * c1, c1 * c1 - s1 * s1);
    let (s4, c4) = (2.0 * s2 * c2, c2 * c2 - s2 * s2);
    let (mut s, mut c) = ([0.0f32; CHAINS], [1.0f32; CHAINS]);
    for i in 1..CHAINS {
        (s[i], c[i]) = (s[i - 1] * c1 + c[i - 1] * s1, c[i - 1] * c1 - s[i - 1] * s1);
    }
    for (sj, cj) in sin.chunks_mut(CHAINS).zip(cos.chunks_mut(CHAINS)) {
        sj.copy_from_slice(&s[..sj.len()]);
        cj.copy_from_slice(&c[..cj.len()]);
        for i in 0..CHAINS {
            (s[i], c[i]) = (s[i] * c4 + c[i] * s4, c[i] * c4 - s[i] * s4);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guides::CvLayout;
    use crate::interp::bind::{bind, BindParams};
    use crate::interp::groom::GroomMaps;
    use crate::testmesh::{bumpy_plane, graded_plane, roots, straight_guides, TestMesh};
    use crate::Strided;
    use proptest::prelude::*;

    const CVS: usize = 8;

    struct Scene {
        m: TestMesh,
        guide_roots: Vec<Root>,
        guide_points: Vec<[f32; 3]>,
        strands: Vec<Root>,
    }

    impl Scene {
        fn plane(guides: u32, strands: u32) -> Scene {
            Scene::on(graded_plane(16, 1.0), guides, strands)
        }

        fn on(m: TestMesh, guides: u32, strands: u32) -> Scene {
            let guide_roots = roots(m.mesh(), guides, 5);
            let guide_points = straight_guides(&m.mesh(), &guide_roots, CVS, 0.1);
            let strands = roots(m.mesh(), strands, 9);
            Scene {
                m,
                guide_roots,
                guide_points,
                strands,
            }
        }

        fn guides(&self) -> Guides<'_> {
            Guides {
                roots: &self.guide_roots,
                points: Strided::from_slice(&self.guide_points),
                layout: CvLayout::Fixed(CVS),
            }
        }

        fn bind(&self, params: &BindParams) -> Vec<StrandBinding> {
            let mut buf =
                vec![
                    0u8;
                    crate::interp::bind::required_bytes(&self.m.mesh(), self.guide_roots.len())
                        .unwrap()
                ];
            let mut out = vec![StrandBinding::default(); self.strands.len()];
            bind(
                &self.m.mesh(),
                &self.guides(),
                &self.strands,
                params,
                &mut Arena::new(&mut buf),
                &mut out,
            )
            .unwrap();
            out
        }

        /// Runs `f` with this scene's guides prepared for `n` points.
        fn prepared<R>(&self, n: usize, f: impl FnOnce(&Mesh, &PreparedGuides) -> R) -> R {
            let mesh = self.m.mesh();
            let mut layout = ArenaLayout::new();
            PreparedGuides::layout(&mut layout, self.m.p.len(), self.guide_roots.len(), n);
            let mut buf = vec![0u8; layout.bytes()];
            let mut arena = Arena::new(&mut buf);
            let prepared = PreparedGuides::new(&mesh, &self.guides(), n, &mut arena).unwrap();
            f(&mesh, &prepared)
        }

        fn expand(
            &self,
            bindings: &[StrandBinding],
            grooms: &[StrandGroom],
            params: &ExpandParams,
            chunks: usize,
        ) -> Vec<[f32; 4]> {
            self.prepared(params.points_per_strand, |mesh, prepared| {
                let per = params.output_points();
                let n = self.strands.len();
                let mut out = vec![[0.0f32; 4]; n * per];
                for c in 0..chunks {
                    let r = c * n / chunks..(c + 1) * n / chunks;
                    let bytes: &mut [u8] =
                        bytemuck::cast_slice_mut(&mut out[r.start * per..r.end * per]);
                    let all = Strands {
                        roots: &self.strands,
                        bindings,
                        grooms,
                    };
                    expand(mesh, &all.range(r), prepared, params, bytes, 16).unwrap();
                }
                out
            })
        }
    }

    fn plain_grooms(n: usize) -> Vec<StrandGroom> {
        vec![
            StrandGroom {
                length: 1.0,
                root_radius: 0.001,
                tip_radius: 0.0005,
                ..StrandGroom::default()
            };
            n
        ]
    }

    /// Strand `i`'s groom with every shaping value set (no clump): bend,
    /// a kink whose phase turns with `i`, and a sideways lift.
    fn styled(i: usize) -> StrandGroom {
        StrandGroom {
            length: 0.9,
            root_radius: 0.002,
            tip_radius: 0.0005,
            bend: 0.2,
            kink_amplitude: 0.05,
            kink_frequency: 3.0,
            kink_phase: [libm::cosf(i as f32), libm::sinf(i as f32)],
            lift: [0.1 * libm::sinf(i as f32), 0.0],
            ..StrandGroom::default()
        }
    }

    fn raw(n: usize) -> ExpandParams {
        ExpandParams {
            points_per_strand: n,
            end_points: EndPoints::Raw,
            orphan_length: 0.1,
        }
    }

    #[test]
    fn identical_bits_for_any_chunking() {
        let s = Scene::plane(200, 3000);
        let b = s.bind(&BindParams::default());
        let mut grooms = plain_grooms(s.strands.len());
        let maps = GroomMaps {
            kink_amplitude: crate::ScalarMap::Constant(0.1),
            clump: crate::ScalarMap::Constant(0.5),
            bend: crate::ScalarMap::Constant(0.2),
            ..GroomMaps::default()
        };
        maps.evaluate(&s.m.mesh(), &s.strands, 3, &mut grooms)
            .unwrap();
        let one = s.expand(&b, &grooms, &raw(CVS), 1);
        for chunks in [2, 7] {
            let other = s.expand(&b, &grooms, &raw(CVS), chunks);
            assert!(bytemuck::cast_slice::<_, u8>(&one) == bytemuck::cast_slice::<_, u8>(&other));
        }
        assert!(one
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite()) && p[3] >= 0.0));
    }

    #[test]
    fn a_lift_too_small_to_square_turns_nothing() {
        let s = Scene::plane(100, 400);
        let b = s.bind(&BindParams::default());
        let plain = plain_grooms(s.strands.len());
        let tiny: Vec<StrandGroom> = plain
            .iter()
            .map(|g| StrandGroom {
                lift: [1e-25, -1e-30],
                ..*g
            })
            .collect();
        assert_eq!(
            s.expand(&b, &plain, &raw(CVS), 1),
            s.expand(&b, &tiny, &raw(CVS), 1)
        );
    }

    #[test]
    fn roots_sit_on_the_surface_and_pinned_ends_repeat() {
        let s = Scene::plane(150, 500);
        let b = s.bind(&BindParams::default());
        let params = ExpandParams {
            end_points: EndPoints::Pinned,
            ..raw(CVS)
        };
        let out = s.expand(&b, &plain_grooms(s.strands.len()), &params, 1);
        let per = params.output_points();
        for (i, r) in s.strands.iter().enumerate() {
            let root = s.m.mesh().point(r.face as usize, r.u, r.v);
            let c = &out[i * per..(i + 1) * per];
            assert!(Vec3::new(c[1][0], c[1][1], c[1][2]).distance(root) < 1e-5);
            assert_eq!(c[0], c[1]);
            assert_eq!(c[per - 1], c[per - 2]);
            assert!(c[per - 1][2] > 0.0, "tip above the plane");
        }
    }

    #[test]
    fn curves_follow_a_moving_body_without_swimming() {
        // the character walks and turns: the mesh and the posed guides move
        // rigidly; every curve must move with them, shape, kink, clump and
        // lift included (frames come from the triangles, not from world axes)
        let s = Scene::plane(60, 400);
        let b = s.bind(&BindParams::default());
        let grooms: Vec<StrandGroom> = (0..s.strands.len())
            .map(|i| StrandGroom {
                length: 0.8 + 0.001 * i as f32,
                clump: 0.3,
                ..styled(i)
            })
            .collect();
        let params = ExpandParams {
            end_points: EndPoints::Pinned,
            ..raw(CVS)
        };
        let rest = s.expand(&b, &grooms, &params, 1);
        let turn = glam::Quat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 2.3);
        let walk = Vec3::new(3.0, -1.0, 0.5);
        let moved = |p: &[f32; 3]| (turn * Vec3::from(*p) + walk).into();
        let posed = Scene {
            m: TestMesh {
                p: s.m.p.iter().map(moved).collect(),
                ..s.m.clone()
            },
            guide_roots: s.guide_roots.clone(),
            guide_points: s.guide_points.iter().map(moved).collect(),
            strands: s.strands.clone(),
        };
        let out = posed.expand(&b, &grooms, &params, 1);
        let mut worst = 0.0f32;
        for (a, o) in rest.iter().zip(&out) {
            let expect = turn * Vec3::new(a[0], a[1], a[2]) + walk;
            worst = worst.max(expect.distance(Vec3::new(o[0], o[1], o[2])));
            assert_eq!(a[3], o[3], "radius");
        }
        // float rounding at coordinates of a few units, not a swim
        assert!(worst < 2e-5, "curves moved {worst} away from the body");
    }

    #[test]
    fn each_groom_value_shapes_the_curve_as_documented() {
        // on a curved skin, every groom value against the plain curve:
        // length scales the root-relative shape, bend moves point j by
        // bend L t^2 along the root tangent, kink by kink L t in the tangent
        // plane turning kink_frequency waves over the strand from the
        // strand's phase, clump pulls point j toward the clump guide by
        // clump t, widths run linearly from root to tip
        let s = Scene::on(bumpy_plane(16), 60, 300);
        let b = s.bind(&BindParams::default());
        let n = s.strands.len();
        let phase = |i: usize| 0.7 * i as f32;
        let plain = StrandGroom {
            length: 1.0,
            root_radius: 0.002,
            tip_radius: 0.0005,
            kink_frequency: 2.5,
            ..StrandGroom::default()
        };
        let with = |f: &dyn Fn(&mut StrandGroom)| {
            let grooms: Vec<StrandGroom> = (0..n)
                .map(|i| {
                    let (sin, cos) = libm::sincosf(phase(i));
                    let mut g = StrandGroom {
                        kink_phase: [cos, sin],
                        ..plain
                    };
                    f(&mut g);
                    g
                })
                .collect();
            s.expand(&b, &grooms, &raw(CVS), 1)
        };
        let base = with(&|_| {});
        let long = with(&|g| g.length = 1.5);
        let bent = with(&|g| g.bend = 0.3);
        let kinked = with(&|g| g.kink_amplitude = 0.05);
        let clumped = with(&|g| g.clump = 0.6);
        let at = |c: &[[f32; 4]], i: usize, j: usize| Vec3::from_slice(&c[i * CVS + j][..3]);
        let delta = core::f32::consts::TAU * 2.5 / (CVS - 1) as f32;
        let close = |a: Vec3, e: Vec3, what: &str, i: usize, j: usize| {
            assert!(
                a.distance(e) < 2e-5,
                "{what}: strand {i} point {j}: {a} vs {e}"
            );
        };
        // an orphan (no guide passes the gates, here on a steep bump) has no
        // clump centre; the clump check needs nearly every strand bound
        let orphans = b
            .iter()
            .filter(|x| x.clump == crate::interp::bind::NO_GUIDE)
            .count();
        assert!(orphans * 100 <= n, "{orphans} orphans of {n}");
        s.prepared(CVS, |mesh, prepared| {
            for (i, r) in s.strands.iter().enumerate() {
                let f = prepared.frame(mesh, r.face as usize, r.u, r.v);
                let root = at(&base, i, 0);
                let len = at(&base, i, CVS - 1).distance(root);
                assert!(len > 0.05, "strand {i} has length {len}");
                for j in 0..CVS {
                    let t = j as f32 / (CVS - 1) as f32;
                    let p = at(&base, i, j);
                    let radius = base[i * CVS + j][3];
                    assert!(
                        (radius - (0.002 - 0.0015 * t)).abs() < 1e-7,
                        "radius {radius}"
                    );
                    close(at(&long, i, j) - root, (p - root) * 1.5, "length", i, j);
                    close(at(&bent, i, j), p + f.t * (0.3 * len * t * t), "bend", i, j);
                    let (sin, cos) = libm::sincosf(phase(i) + j as f32 * delta);
                    let wave = (f.t * sin + f.b * cos) * (0.05 * len * t);
                    close(at(&kinked, i, j), p + wave, "kink", i, j);
                    if b[i].clump == crate::interp::bind::NO_GUIDE {
                        continue;
                    }
                    let c = prepared.world(b[i].clump as usize);
                    let centre = Vec3::new(c[j], c[CVS + j], c[2 * CVS + j]);
                    close(
                        at(&clumped, i, j),
                        p + (centre - p) * (0.6 * t),
                        "clump",
                        i,
                        j,
                    );
                }
            }
        });
    }

    #[test]
    fn curves_keep_their_shape_on_a_bending_body() {
        // the skin rolls around a cylinder (a bend, not a rigid motion) and
        // each posed guide rides on its root, keeping its shape in its root
        // frame: every strand must keep its shape in its own root frame,
        // bend, kink and lift included (clump is left out: it pulls toward
        // the guides' world points, which the bend moves apart)
        let mut flat = graded_plane(16, 1.0);
        flat.n = vec![[0.0, 0.0, 1.0]; flat.p.len()];
        let s = Scene::on(flat, 60, 400);
        let b = s.bind(&BindParams::default());
        let grooms: Vec<StrandGroom> = (0..s.strands.len())
            .map(|i| StrandGroom {
                lift: [0.1 * libm::sinf(i as f32), 0.05],
                ..styled(i)
            })
            .collect();
        let params = raw(CVS);
        let rest = s.expand(&b, &grooms, &params, 1);
        let radius = 0.4;
        let rolled = |p: &[f32; 3]| {
            let (sin, cos) = libm::sincosf(p[0] / radius);
            [(radius + p[2]) * sin, p[1], (radius + p[2]) * cos - radius]
        };
        let bent = TestMesh {
            p: s.m.p.iter().map(rolled).collect(),
            n: s.m
                .p
                .iter()
                .map(|p| {
                    let (sin, cos) = libm::sincosf(p[0] / radius);
                    [sin, 0.0, cos]
                })
                .collect(),
            ..s.m.clone()
        };
        let frames = |scene: &Scene, roots: &[Root]| {
            scene.prepared(CVS, |mesh, prepared| {
                roots
                    .iter()
                    .map(|r| prepared.frame(mesh, r.face as usize, r.u, r.v))
                    .collect::<Vec<_>>()
            })
        };
        let mut posed = Scene {
            m: bent,
            guide_roots: s.guide_roots.clone(),
            guide_points: s.guide_points.clone(),
            strands: s.strands.clone(),
        };
        let (rest_guides, bent_guides) =
            (frames(&s, &s.guide_roots), frames(&posed, &s.guide_roots));
        for (g, points) in posed.guide_points.chunks_mut(CVS).enumerate() {
            for p in points {
                *p = bent_guides[g]
                    .to_world(rest_guides[g].to_local(Vec3::from(*p)))
                    .into();
            }
        }
        let out = posed.expand(&b, &grooms, &params, 1);
        let (rest_frames, bent_frames) = (frames(&s, &s.strands), frames(&posed, &s.strands));
        let mut worst = 0.0f32;
        for (i, (a, o)) in rest.chunks(CVS).zip(out.chunks(CVS)).enumerate() {
            for (p, q) in a.iter().zip(o) {
                let before = rest_frames[i].to_local(Vec3::from_slice(&p[..3]));
                let after = bent_frames[i].to_local(Vec3::from_slice(&q[..3]));
                worst = worst.max(before.distance(after));
                assert_eq!(p[3], q[3], "radius");
            }
        }
        assert!(
            worst < 2e-5,
            "strands changed shape by {worst} in their frames"
        );
        // and the skin did bend under them: the frames turned by up to 2.5 rad
        let turn = rest_frames
            .iter()
            .zip(&bent_frames)
            .map(|(a, b)| a.n.angle_between(b.n));
        assert!(turn.fold(0.0f32, f32::max) > 2.0);
    }

    /// Roots along the segment y = 0.37 + 0.1 x, x in [0.1, 0.9], on the plane.
    fn path(mesh: &Mesh, steps: u32) -> Vec<Root> {
        (0..steps)
            .map(|i| {
                let x = 0.1 + 0.8 * i as f32 / steps as f32;
                let p = Vec3::new(x, 0.37 + 0.1 * x, 0.0);
                let bary = |f: usize| {
                    let [a, b, c] = mesh.corners(f);
                    let (e1, e2, d) = (b - a, c - a, p - a);
                    let det = e1.x * e2.y - e1.y * e2.x;
                    (
                        (d.x * e2.y - d.y * e2.x) / det,
                        (e1.x * d.y - e1.y * d.x) / det,
                    )
                };
                let face = (0..mesh.triangle_count())
                    .find(|&f| {
                        let (u, v) = bary(f);
                        u >= -1e-6 && v >= -1e-6 && u + v <= 1.0 + 1e-6
                    })
                    .unwrap();
                let (u, v) = bary(face);
                Root {
                    face: face as u32,
                    u,
                    v,
                    id: i,
                    rank: i,
                }
            })
            .collect()
    }

    /// Largest change of root-relative shape between consecutive path roots.
    fn largest_step_change(s: &Scene, steps: u32) -> f32 {
        let strands = path(&s.m.mesh(), steps);
        let scene = Scene {
            m: s.m.clone(),
            guide_roots: s.guide_roots.clone(),
            guide_points: s.guide_points.clone(),
            strands,
        };
        let fixed = BindParams {
            min_neighbours: 4,
            max_neighbours: 4,
            ..BindParams::default()
        };
        let b = scene.bind(&fixed);
        let out = scene.expand(&b, &plain_grooms(steps as usize), &raw(CVS), 1);
        let rel = |c: &[[f32; 4]], j: usize| {
            Vec3::new(c[j][0] - c[0][0], c[j][1] - c[0][1], c[j][2] - c[0][2])
        };
        let mut worst = 0.0f32;
        for i in 1..steps as usize {
            let (p, q) = (&out[(i - 1) * CVS..i * CVS], &out[i * CVS..(i + 1) * CVS]);
            for j in 0..CVS {
                worst = worst.max(rel(p, j).distance(rel(q, j)));
            }
        }
        worst
    }

    /// Refining the path 8x must shrink the largest change between
    /// neighbouring strands about 8x, to within a constant times the step
    /// (0.8 / steps): a jump (a seam) stays the same size at every
    /// resolution.
    fn assert_shapes_change_continuously(s: &Scene) {
        let coarse = largest_step_change(s, 1000);
        let fine = largest_step_change(s, 8000);
        assert!(
            fine < 0.3 * coarse,
            "largest change {coarse} at 1000 steps, {fine} at 8000 steps"
        );
        assert!(fine < 20.0 * 0.8 / 8000.0, "change {fine} per step");
    }

    #[test]
    fn shapes_change_continuously_along_a_path() {
        // continuous weights: a hard k cutoff would leave a jump
        assert_shapes_change_continuously(&Scene::plane(120, 10));
    }

    #[test]
    fn shapes_change_continuously_on_a_curved_skin() {
        // on a bumpy skin every triangle turns against its neighbours: the
        // root frame's tangent must not jump at triangle edges (a
        // per-triangle tangent turns leaning strands by a fixed angle there)
        assert_shapes_change_continuously(&Scene::on(bumpy_plane(16), 120, 10));
    }

    fn special() -> impl Strategy<Value = f32> {
        prop::sample::select(vec![
            0.0,
            0.3,
            0.9,
            -1e-3,
            -1e-5,
            1.0,
            4.0,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ])
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]
        #[test]
        fn the_strand_screen_agrees_with_the_detailed_checks(
            changes in prop::collection::vec((0usize..32, special(), 0u32..12), 0..3),
        ) {
            let m = crate::testmesh::graded_plane(2, 1.0);
            let mesh = m.mesh();
            // a valid strand, then up to two fields changed
            let mut r = Root { face: 1, u: 0.2, v: 0.3, id: 0, rank: 0 };
            let mut b = StrandBinding { guides: [0, 1, 2, 0, 0, 0, 0, 0], weights: [0.3; 8], count: 3, clump: 0 };
            let mut g = StrandGroom { length: 1.0, root_radius: 0.01, tip_radius: 0.001, ..StrandGroom::default() };
            for &(field, x, i) in &changes {
                match field {
                    0 => r.face = i,
                    1 => r.u = x,
                    2 => r.v = x,
                    3 => b.count = i,
                    4..=11 => b.guides[field - 4] = i,
                    12..=19 => b.weights[field - 12] = x,
                    20 => b.clump = if i > 9 { NO_GUIDE } else { i },
                    _ => bytemuck::cast_slice_mut::<StrandGroom, f32>(core::slice::from_mut(&mut g))[field - 21] = x,
                }
            }
            let faces = mesh.triangle_count();
            let screen = strand_is_valid(faces, 6, &r, &b, &g);
            let detailed = check_strand(faces, 6, &r, &b, &g).is_ok();
            prop_assert_eq!(screen, detailed);
            // records checked once, then only the counts: the same verdict
            let strands = Strands { roots: &[r], bindings: &[b], grooms: &[g] };
            let split = StrandBounds::new(&strands).and_then(|bounds| bounds.fits(faces, 6));
            prop_assert_eq!(split.is_ok(), detailed);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        #[test]
        fn strand_stays_in_its_guides_envelope(seed in 0u64..1000, kmin in 1u32..5, extra in 0u32..4) {
            let s = Scene::plane(80, 300);
            let params = BindParams { min_neighbours: kmin, max_neighbours: kmin + extra, seed, ..BindParams::default() };
            let b = s.bind(&params);
            let out = s.expand(&b, &plain_grooms(s.strands.len()), &raw(CVS), 1);
            s.prepared(CVS, |mesh, prepared| {
            for (i, r) in s.strands.iter().enumerate() {
                let frame = prepared.frame(mesh, r.face as usize, r.u, r.v);
                for j in 0..CVS {
                    let p = out[i * CVS + j];
                    let local = frame.to_local(Vec3::new(p[0], p[1], p[2]));
                    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
                    for k in 0..b[i].count as usize {
                        let l = prepared.local_point(b[i].guides[k] as usize, j);
                        lo = lo.min(l);
                        hi = hi.max(l);
                    }
                    prop_assert!(local.cmpge(lo - 1e-5).all() && local.cmple(hi + 1e-5).all(),
                        "strand {} point {}: {:?} outside {:?}..{:?}", i, j, local, lo, hi);
                }
            }
            Ok(())
            })?;
        }
    }

    #[test]
    fn variable_cv_counts_resample() {
        let s = Scene::plane(60, 200);
        let b = s.bind(&BindParams::default());
        // the same guides stored with offsets give the same curves
        let offsets: Vec<u32> = (0..=s.guide_roots.len() as u32)
            .map(|g| g * CVS as u32)
            .collect();
        let mesh = s.m.mesh();
        let guides = Guides {
            roots: &s.guide_roots,
            points: Strided::from_slice(&s.guide_points),
            layout: CvLayout::Offsets(&offsets),
        };
        let mut buf = vec![0u8; 1 << 20];
        let prepared = PreparedGuides::new(&mesh, &guides, 15, &mut Arena::new(&mut buf)).unwrap();
        let mut out = vec![[0.0f32; 4]; s.strands.len() * 15];
        let grooms = plain_grooms(s.strands.len());
        let strands = Strands {
            roots: &s.strands,
            bindings: &b,
            grooms: &grooms,
        };
        expand(
            &mesh,
            &strands,
            &prepared,
            &raw(15),
            bytemuck::cast_slice_mut(&mut out),
            16,
        )
        .unwrap();
        let straight = s.expand(&b, &plain_grooms(s.strands.len()), &raw(CVS), 1);
        for i in 0..s.strands.len() {
            let tip_a = out[i * 15 + 14];
            let tip_b = straight[i * CVS + CVS - 1];
            assert!((0..3).all(|c| (tip_a[c] - tip_b[c]).abs() < 1e-5));
        }
    }
}
