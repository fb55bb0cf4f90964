//! The frame handle: one frame's deformed mesh and posed guides, prepared
//! once and read by any number of expansions.

use crate::body::{body_in, BodyMemory};
use crate::buffers::{collected, grow, req, req_mut, slice, slice_mut, strided, zeroed};
use crate::colliders::{HostColliders, HostField};
use crate::handles::{free, into_handle, object_mut, Handle};
use crate::status::Failure;
use crate::threads::{chunks_with_progress, split_with_progress, PelageRun, Progress};
use crate::{PelageColliders, PelageGuidesDesc, PelageMeshDesc, PelageStatus};
use pelage_core::arena::ArenaLayout;
use pelage_core::cache::groom_file::Groom;
use pelage_core::cache::guide_cache::{GuideCache, BLOCK};
use pelage_core::collide::{
    Capsule, Colliders, Plane, SignedDistance, Sphere, COLLISION_CELLS_PER_TRIANGLE,
};
use pelage_core::surface::body::Body;

use glam::Vec3;
use pelage_core::interp::posed::PosedFrame;
use pelage_core::surface::mesh::MAX_COORDINATE;
use pelage_core::surface::nearest::Nearest;
use pelage_core::{Arena, Mesh, Strided};

/// The opaque object a `PelageFrame` points to.
// not repr(C): cbindgen declares it in C without a definition
pub struct PelageFrameTy {
    _private: [u8; 0],
}

/// One frame: the deformed mesh (copied and checked), its vertex tangents
/// and the posed guides in their root frames, prepared once by
/// `pelage_frame_new` and `pelage_frame_set_guides`, then read by any
/// number of `pelage_groom_expand` / `pelage_expand` calls (a renderer's
/// patches). Released by `pelage_frame_free`.
pub type PelageFrame = *mut PelageFrameTy;

/// A heap slice the frame borrows for its whole life. Kept as a raw
/// pointer, not a Box: moving a Box asserts unique access to its contents
/// while the frame holds references into them.
struct Buffer<T>(*mut [T]);

impl<T> Buffer<T> {
    fn new(v: Vec<T>) -> Self {
        Buffer(Box::into_raw(v.into_boxed_slice()))
    }

    /// The contents, for as long as the frame that owns this buffer lives.
    ///
    /// # Safety
    /// Called once per buffer, and the borrow must end before the buffer
    /// is dropped (the frame declared before it in `Frame` holds it).
    unsafe fn borrow(&self) -> &'static mut [T] {
        // SAFETY: the pointer came from Box::into_raw and is freed only in
        // drop; the caller borrows it once, for less than its life.
        unsafe { &mut *self.0 }
    }
}

impl<T> Drop for Buffer<T> {
    fn drop(&mut self) {
        // SAFETY: from Box::into_raw in `new`, freed once, here.
        drop(unsafe { Box::from_raw(self.0) });
    }
}

impl Handle for PelageFrameTy {
    type Object = Frame;
    const NAME: &'static str = "frame";
}

/// What a [`PelageFrame`] points to.
pub(crate) struct Frame {
    /// The colliders render strands are pushed out of, if set (their body
    /// borrows only their own memory).
    push: Option<FrameColliders>,
    /// Borrows the buffers below; declared before them, so dropped first.
    posed: PosedFrame<'static>,
    /// Where a guide cache is unpacked before the guides are written
    /// (kept between decodes: a renderer decodes every frame).
    scratch: Vec<u32>,
    _positions: Buffer<[f32; 3]>,
    _triangles: Buffer<[u32; 3]>,
    _uvs: Option<Buffer<[f32; 2]>>,
    _normals: Option<Buffer<[f32; 3]>>,
    _arena: Buffer<u8>,
}

/// A frame's colliders for pushing render strands out
/// (`pelage_frame_set_colliders`): the shapes copied, the body built once.
struct FrameColliders {
    /// Borrows `_body_memory` and `_refs_memory`; declared first, so
    /// dropped first.
    body: Option<Body<'static>>,
    spheres: Vec<Sphere>,
    capsules: Vec<Capsule>,
    planes: Vec<Plane>,
    field: Option<HostField>,
    _body_memory: Option<Buffer<u8>>,
    _refs_memory: Option<Buffer<u8>>,
}

impl Frame {
    /// The distance callback set by `pelage_frame_set_colliders`, if any,
    /// for one call ([`HostField::check`] it afterwards).
    pub(crate) fn push_field(&self) -> Option<HostField> {
        self.push.as_ref()?.field.as_ref().map(HostField::fresh)
    }

    /// The colliders set by `pelage_frame_set_colliders`, if any, with
    /// `field`, this call's of [`push_field`](Self::push_field).
    pub(crate) fn push_colliders<'r>(
        &'r self,
        field: Option<&'r HostField>,
    ) -> Option<Colliders<'r>> {
        self.push.as_ref().map(|c| Colliders {
            spheres: &c.spheres,
            capsules: &c.capsules,
            planes: &c.planes,
            body: c.body.as_ref(),
            field: field.map(|f| f as &dyn SignedDistance),
        })
    }

    /// The body `pelage_frame_set_colliders` built for this frame, if any.
    pub(crate) fn body(&self) -> Option<&Body<'_>> {
        self.push.as_ref().and_then(|c| c.body.as_ref())
    }

    /// The body a query of host points reads, and the progress left for
    /// the query: the frame's own body, or one built in `memory` as the
    /// first `share` of `run`'s progress.
    fn body_for_query<'m>(
        &'m self,
        memory: &'m mut BodyMemory,
        built: &'m mut Option<Body<'m>>,
        run: &PelageRun,
        share: f64,
    ) -> Result<(&'m Body<'m>, Progress), Failure> {
        let progress = run.progress();
        Ok(match self.body() {
            Some(body) => (body, progress),
            None => {
                let mesh = self.posed.mesh();
                let body = memory.body(
                    mesh,
                    COLLISION_CELLS_PER_TRIANGLE,
                    run.thread_count,
                    progress.within(0.0, share),
                )?;
                (&*built.insert(body), progress.within(share, 1.0))
            }
        })
    }

    /// The posed frame, for no longer than this handle lives.
    pub(crate) fn posed(&self) -> &PosedFrame<'_> {
        &self.posed
    }

    /// The posed frame, to pose its guides.
    pub(crate) fn posed_mut(&mut self) -> &mut PosedFrame<'static> {
        &mut self.posed
    }

    /// Decodes shutter sample `sample` of `cache` into this frame's guides,
    /// checked whole first, as `run` says: unpacked by runs of whole
    /// blocks into the frame's scratch (the first half of the progress),
    /// then posed by chunks. Once checked, a failure leaves the frame
    /// without guides.
    pub(crate) fn decode_guides(
        &mut self,
        cache: &GuideCache,
        groom: &Groom,
        groom_id: u32,
        sample: usize,
        run: &PelageRun,
    ) -> Result<(), Failure> {
        cache.check(groom, groom_id, sample, &self.posed)?;
        let progress = run.progress();
        grow(
            &mut self.scratch,
            cache.scratch_words(),
            0,
            "the cache's unpacked guides",
        )?;
        let unpacked = &mut self.scratch[..];
        let per_block = BLOCK * cache.words_per_guide();
        split_with_progress(
            cache.blocks(),
            run.thread_count,
            unpacked,
            per_block,
            progress.within(0.0, 0.5),
            |blocks, part| cache.unpack(groom, sample, blocks, part),
        )?
        .into_iter()
        .collect::<Result<(), _>>()?;
        let unpacked = &self.scratch[..];
        let decoding = cache.decoding(groom, &mut self.posed);
        let filler = decoding.filler;
        let words = cache.words_per_guide();
        let failed = std::sync::Mutex::new(None);
        chunks_with_progress(
            cache.info().guides,
            run.thread_count,
            &mut *decoding.data,
            filler.floats_per_guide(),
            progress.within(0.5, 1.0),
            |range, part| {
                let mine = &unpacked[range.start * words..range.end * words];
                if let Err(e) = filler.fill(range.start, mine, part) {
                    *failed.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
                }
            },
        )?;
        if let Some(e) = failed.into_inner().unwrap_or_else(|p| p.into_inner()) {
            return Err(e.into());
        }
        decoding.finish();
        Ok(())
    }
}

/// Copies a host buffer into a heap buffer (OUT_OF_MEMORY naming `what`).
fn copy<T: bytemuck::Pod>(s: Strided<T>, what: &str) -> Result<Buffer<T>, Failure> {
    Ok(Buffer::new(collected(s.iter(), s.len(), what)?))
}

/// Creates a frame for `guide_count` posed guides resampled to
/// `points_per_strand` points (2..64, as the expansions will ask for) on
/// the deformed `mesh`, which is copied and checked (the host may change
/// or free its buffers afterwards), and computes its vertex tangents. The
/// frame has no guides until `pelage_frame_set_guides`. On success
/// `*out_frame` is the new frame; on failure it is left untouched.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (point count, no guides,
/// bad stride, mesh values beyond 1e9), MISALIGNED, NON_FINITE,
/// OUT_OF_RANGE (an index past the vertices), OUT_OF_MEMORY, PANIC.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_frame_new(
    mesh: *const PelageMeshDesc,
    guide_count: usize,
    points_per_strand: u32,
    out_frame: *mut PelageFrame,
) -> PelageStatus {
    ffi_boundary! {
        let out = req_mut(out_frame, "out_frame")?;
        let host = req(mesh, "mesh")?.view()?;
        let points = points_per_strand as usize;
        // the counts are checked before anything is allocated, so a bad
        // count is a status, not an allocation that aborts the host (the
        // mesh's values are checked once, on the copy, by PosedFrame::new)
        PosedFrame::check_sizes(guide_count, points)?;
        let mut layout = ArenaLayout::new();
        PosedFrame::layout(&mut layout, host.positions.len(), guide_count, points);
        let arena = Buffer::new(zeroed(layout.bytes(), "the frame")?);
        let positions = copy(host.positions, "the mesh's positions")?;
        let triangles = copy(host.triangles, "the mesh's triangles")?;
        let uvs = host.uvs.map(|s| copy(s, "the mesh's UVs")).transpose()?;
        let normals = host.normals.map(|s| copy(s, "the mesh's normals")).transpose()?;
        // SAFETY: each buffer is borrowed once, by the frame made below,
        // which the handle drops before them.
        let mut mesh = unsafe {
            Mesh::new(
                Strided::from_slice(positions.borrow()),
                Strided::from_slice(triangles.borrow()),
            )
        };
        // SAFETY: as above.
        mesh.uvs = uvs.as_ref().map(|b| Strided::from_slice(unsafe { b.borrow() }));
        // SAFETY: as above.
        mesh.normals = normals.as_ref().map(|b| Strided::from_slice(unsafe { b.borrow() }));
        // SAFETY: as above.
        let posed = PosedFrame::new(mesh, guide_count, points, &mut Arena::new(unsafe { arena.borrow() }))?;
        let frame = Box::new(Frame {
            push: None,
            posed,
            scratch: Vec::new(),
            _positions: positions,
            _triangles: triangles,
            _uvs: uvs,
            _normals: normals,
            _arena: arena,
        });
        *out = into_handle(frame);
        Ok(())
    }
}

/// Poses the frame's guides: checks `guides` (guide_count as given to
/// `pelage_frame_new`, roots on the mesh, finite points within 1e9, no
/// zero-length guide) and stores them resampled, in their root frames on
/// the frame's mesh. Runs as `run` says (progress: the share of guides
/// posed). May be called again for new guides (a simulation's output).
/// When the guides are refused the frame keeps the guides it had; once
/// they are checked, a cancelled call (or a PANIC) leaves the frame
/// without guides until the next successful call.
///
/// Returns OK, NULL_PARAMETER, INVALID_ARGUMENT (also guide points beyond
/// 1e9), MISALIGNED, NON_FINITE, OUT_OF_RANGE, CANCELLED, PANIC (also when
/// a worker thread cannot start).
///
/// Thread safety: writes `frame`.
#[no_mangle]
pub extern "C" fn pelage_frame_set_guides(
    frame: PelageFrame,
    guides: *const PelageGuidesDesc,
    run: PelageRun,
) -> PelageStatus {
    ffi_boundary! {
        let frame = object_mut(frame)?;
        let guides = req(guides, "guides")?.view()?;
        let mut posing = frame.posed.posing(&guides)?;
        posing.unpose();
        let filler = posing.filler;
        let per = filler.floats_per_guide();
        split_with_progress(guides.len(), run.thread_count, &mut *posing.data, per, run.progress(), |range, part| {
            filler.fill(range.start, part)
        })?;
        posing.finish();
        Ok(())
    }
}

/// Sets the colliders that render strands selected by a push mask
/// (`PelageStrandEdits.push_mask`) are pushed out of when expanded on this
/// frame: `colliders` is copied; NULL clears them. Their body, when set, is
/// this frame's mesh, built once here as `run` says (progress: the body's
/// stages): `pelage_sim_step` on this frame collides with it rather than
/// building its own. A distance
/// callback is kept: it and its user data must stay valid until the
/// colliders are replaced or the frame is freed.
/// On failure the frame keeps the colliders it had.
///
/// Returns OK, NULL_PARAMETER, NON_FINITE (a collider's value),
/// INVALID_ARGUMENT (a collider, a body of this frame's mesh too large),
/// MISALIGNED, CANCELLED, OUT_OF_MEMORY, PANIC.
///
/// Thread safety: writes `frame`.
#[no_mangle]
pub extern "C" fn pelage_frame_set_colliders(
    frame: PelageFrame,
    colliders: *const PelageColliders,
    run: PelageRun,
) -> PelageStatus {
    ffi_boundary! {
        let frame = object_mut(frame)?;
        if colliders.is_null() {
            frame.push = None;
            return Ok(());
        }
        let host = HostColliders::read(colliders)?;
        let shapes = Colliders { spheres: host.spheres, capsules: host.capsules, planes: host.planes, body: None, field: None };
        shapes.check()?;
        let spheres = collected(host.spheres.iter().copied(), host.spheres.len(), "the spheres")?;
        let capsules = collected(host.capsules.iter().copied(), host.capsules.len(), "the capsules")?;
        let planes = collected(host.planes.iter().copied(), host.planes.len(), "the planes")?;
        let (mut body_memory, mut refs_memory, mut body) = (None, None, None);
        if host.body {
            let (memory, refs): (&mut Option<Buffer<u8>>, &mut Option<Buffer<u8>>) = (&mut body_memory, &mut refs_memory);
            body = Some(body_in(
                frame.posed.mesh(),
                &mut Vec::new(),
                COLLISION_CELLS_PER_TRIANGLE,
                run.thread_count,
                run.progress(),
                |bytes| {
                    let buffer = memory.insert(Buffer::new(zeroed(bytes, "the body")?));
                    // SAFETY: the buffer is borrowed once, by the body made
                    // here, which FrameColliders drops before it.
                    Ok(unsafe { buffer.borrow() })
                },
                |bytes| {
                    let buffer = refs.insert(Buffer::new(zeroed(bytes, "the body's triangle references")?));
                    // SAFETY: as the body's buffer above.
                    Ok(unsafe { buffer.borrow() })
                },
            )?);
        }
        frame.push = Some(FrameColliders {
            body,
            spheres,
            capsules,
            planes,
            field: host.field,
            _body_memory: body_memory,
            _refs_memory: refs_memory,
        });
        Ok(())
    }
}

/// Sets where the frame's local space sits in the host's world: `origin`,
/// 3 doubles (zero for a new frame), with world = origin + local. The
/// frame's mesh, its guides and colliders (the host's distance callback
/// too) are then given relative to it, and everything read from the frame
/// or a simulation stepped on it (expanded hairs, posed guides) comes back
/// relative to it; a host adds it back in double precision. A character
/// far from the world's origin keeps float32's precision this way: at 1e4
/// a float32 world point holds about 1e-3, relative to an origin that
/// follows the character it holds the character's own detail. Frames of
/// one shot may have different origins: a simulation stepping from one to
/// the next carries its state across by the difference (see
/// pelage_sim_step).
///
/// Returns OK, NULL_PARAMETER, NON_FINITE, INVALID_ARGUMENT (a coordinate
/// beyond 1e15), MISALIGNED, PANIC.
///
/// Thread safety: writes `frame`.
#[no_mangle]
pub extern "C" fn pelage_frame_set_origin(frame: PelageFrame, origin: *const f64) -> PelageStatus {
    ffi_boundary! {
        let frame = object_mut(frame)?;
        let origin = slice(origin, 3, "origin")?;
        frame.posed.set_origin([origin[0], origin[1], origin[2]])?;
        Ok(())
    }
}

/// Writes the frame's origin (pelage_frame_set_origin) to `origin`, 3
/// doubles.
///
/// Returns OK, NULL_PARAMETER, MISALIGNED, PANIC.
///
/// Thread safety: reads `frame`.
#[no_mangle]
pub extern "C" fn pelage_frame_origin(frame: PelageFrame, origin: *mut f64) -> PelageStatus {
    ffi_boundary! {
        let frame = crate::handles::object(frame)?;
        slice_mut(origin, 3, "origin")?.copy_from_slice(&frame.posed.origin());
        Ok(())
    }
}

/// Releases a frame. NULL is accepted and does nothing.
///
/// Thread safety: frees `frame`.
#[no_mangle]
pub extern "C" fn pelage_frame_free(frame: PelageFrame) {
    free(frame);
}

/// Whether each of `count` host points (float3, `point_stride` bytes
/// apart, >= 12 and a multiple of 4) lies inside the body of this frame's
/// mesh, by pelage's one inside rule: the generalized winding number of
/// the mesh above 1/2 (1 inside a closed shell, falling smoothly to 0
/// across a hole). The body collider, settle and trimming use the same
/// rule. Writes 1 (inside) or 0 to `inside[i]`. Uses the body
/// `pelage_frame_set_colliders` built for the frame when it has one, else
/// builds one for the call. Runs as `run` says (progress: the body's build,
/// when the call makes one, as the first fifth, then the share of points).
/// On failure `inside` is untouched, but for CANCELLED and PANIC (then
/// unspecified).
///
/// Returns OK, NULL_PARAMETER, NON_FINITE (a point), INVALID_ARGUMENT (a
/// point beyond 1e9, the stride, a body of this frame's mesh too large),
/// MISALIGNED, CANCELLED, OUT_OF_MEMORY, PANIC.
///
/// Thread safety: reads `frame`.
#[no_mangle]
pub extern "C" fn pelage_frame_inside(
    frame: PelageFrame,
    points: *const std::ffi::c_void,
    point_stride: usize,
    count: usize,
    run: PelageRun,
    inside: *mut u8,
) -> PelageStatus {
    ffi_boundary! {
        let frame = crate::handles::object(frame)?;
        let points = host_points(points, point_stride, count)?;
        let out = slice_mut(inside, count, "inside")?;
        let (mut memory, mut built) = (BodyMemory::default(), None);
        let (body, rest) = frame.body_for_query(&mut memory, &mut built, &run, 0.2)?;
        split_with_progress(count, run.thread_count, out, 1, rest, |range, part| {
            for (o, i) in part.iter_mut().zip(range) {
                *o = body.contains(Vec3::from(points.get(i))) as u8;
            }
        })?;
        Ok(())
    }
}

/// The signed distance from each of `count` host points (as for
/// pelage_frame_inside) to this frame's mesh: the distance to the nearest
/// point of its triangles, negative inside by pelage's inside rule (as a
/// PelageDistanceFn's), so a host can push its own points out of the body
/// or measure how deep they went. Near a hole the inside reaches across
/// it while the distance is to the skin (the rim). Writes `distances[i]`.
/// Uses the frame's body as pelage_frame_inside does; the nearest-point
/// tree is built for the call (progress: the body's build, when the call
/// makes one, as the first fifth; then the tree, a quarter of what is
/// left; then the share of points). On failure `distances` is untouched,
/// but for CANCELLED and PANIC (then unspecified).
///
/// Returns OK, NULL_PARAMETER, NON_FINITE (a point), INVALID_ARGUMENT (a
/// point beyond 1e9, the stride, a body of this frame's mesh too large, a
/// mesh without a triangle of area), MISALIGNED, CANCELLED, OUT_OF_MEMORY,
/// PANIC.
///
/// Thread safety: reads `frame`.
#[no_mangle]
pub extern "C" fn pelage_frame_signed_distance(
    frame: PelageFrame,
    points: *const std::ffi::c_void,
    point_stride: usize,
    count: usize,
    run: PelageRun,
    distances: *mut f32,
) -> PelageStatus {
    ffi_boundary! {
        let frame = crate::handles::object(frame)?;
        let points = host_points(points, point_stride, count)?;
        let out = slice_mut(distances, count, "distances")?;
        let (mut memory, mut built) = (BodyMemory::default(), None);
        let (body, rest) = frame.body_for_query(&mut memory, &mut built, &run, 0.2)?;
        let mesh = frame.posed.mesh();
        let mut layout = ArenaLayout::new();
        Nearest::layout(&mut layout, mesh);
        let mut bytes = zeroed(layout.bytes(), "the nearest-point tree")?;
        let nearest = Nearest::new(mesh, &mut Arena::new(&mut bytes))?;
        // a body needs a triangle of area, and so does every distance being
        // finite: checked again here, as the frame's body is not the tree's
        if nearest.is_empty() {
            return Err(Failure::new(PelageStatus::InvalidArgument, "the frame's mesh has no triangle of area"));
        }
        rest.within(0.0, 0.25).report(1.0)?;
        split_with_progress(count, run.thread_count, out, 1, rest.within(0.25, 1.0), |range, part| {
            for (o, i) in part.iter_mut().zip(range) {
                let p = Vec3::from(points.get(i));
                let d = nearest.distance(p);
                *o = if body.contains(p) { -d } else { d };
            }
        })?;
        Ok(())
    }
}

/// `count` host points, `stride` bytes apart, checked finite and within
/// the coordinate limit.
fn host_points<'p>(
    points: *const std::ffi::c_void,
    stride: usize,
    count: usize,
) -> Result<Strided<'p, [f32; 3]>, Failure> {
    let points = strided::<[f32; 3]>(points, stride, count, "points")?;
    for (i, p) in points.iter().enumerate() {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(pelage_core::Error::NonFinite {
                what: "points",
                index: i,
            }
            .into());
        }
        if !p.iter().all(|c| c.abs() <= MAX_COORDINATE) {
            return Err(pelage_core::Error::OutOfDomain {
                what: "points (within 1e9)",
                index: i,
            }
            .into());
        }
    }
    Ok(points)
}
