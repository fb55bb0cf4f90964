//! The colliders a host gives (spheres, capsules, half-spaces, the body,
//! a distance callback) and their conversion to the core's.

use crate::buffers::{req, slice};
use crate::status::Failure;
use crate::PelageStatus;
use pelage_core::collide::{Capsule, Colliders, Plane, SignedDistance, Sphere};
use pelage_core::surface::body::Body;
use std::ffi::c_void;
use std::sync::atomic::{AtomicBool, Ordering};

/// A solid sphere collider.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PelageSphere {
    /// Centre.
    pub centre: [f32; 3],
    /// Radius (>= 0).
    pub radius: f32,
}

/// A solid capsule collider: the points within `radius` of the segment a-b.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PelageCapsule {
    /// One end of the axis.
    pub a: [f32; 3],
    /// The other end.
    pub b: [f32; 3],
    /// Radius (>= 0).
    pub radius: f32,
}

/// A solid half-space collider: the points p with dot(normal, p) < offset
/// (normal not zero, used as given).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PelagePlane {
    /// Outward normal.
    pub normal: [f32; 3],
    /// dot(normal, p) on the surface.
    pub offset: f32,
}

same_layout!(PelageSphere, Sphere, centre, radius);
same_layout!(PelageCapsule, Capsule, a, b, radius);
same_layout!(PelagePlane, Plane, normal, offset);

/// A host's signed distance field (negative inside): writes the distance
/// of each of `count` points (x, y, z floats, packed) to `distances`.
/// Called from the threads of the call that uses it (`pelage_sim_step`,
/// `pelage_trim_find`, `pelage_trim_shortest_hairs`, and every thread that
/// expands with a push mask on a frame holding it), possibly at once: it
/// must be safe to call concurrently. pelage asks for many points a call
/// where it can: a step asks once for the guides of a batch of 32 (some
/// 500 points for guides of 16) before their push-outs, an expansion once
/// for the pushed strands of a batch of 32, and both once for all the
/// rotations of a strand they try toward its normal; trimming asks once
/// for every point of 32 guides (or hairs), then once per bisection step
/// for all their entries. A NaN distance
/// fails the call with NON_FINITE: a step is taken back whole, trimming
/// writes nothing, an expansion's curves are unspecified.
pub type PelageDistanceFn = Option<
    unsafe extern "C" fn(
        user_data: *mut c_void,
        points: *const f32,
        count: usize,
        distances: *mut f32,
    ),
>;

/// What guides (a step, trimming) or pushed render strands collide with;
/// every array may be NULL with a count of 0.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageColliders {
    /// Spheres.
    pub spheres: *const PelageSphere,
    /// Number of spheres.
    pub sphere_count: usize,
    /// Capsules.
    pub capsules: *const PelageCapsule,
    /// Number of capsules.
    pub capsule_count: usize,
    /// Half-spaces.
    pub planes: *const PelagePlane,
    /// Number of half-spaces.
    pub plane_count: usize,
    /// Nonzero: collide with the body itself, the frame's (deformed) mesh
    /// as a solid: inside where its generalized winding number is above 0.5
    /// (open meshes and intersecting shells work; its grid is built each
    /// step).
    pub body: u32,
    /// A signed distance field, or NULL.
    pub distance: PelageDistanceFn,
    /// Passed unchanged to `distance`.
    pub distance_user_data: *mut c_void,
}

/// A host's colliders, checked for NULL arrays (the shapes' values are
/// checked by `Colliders::check`).
pub(crate) struct HostColliders<'a> {
    pub(crate) spheres: &'a [Sphere],
    pub(crate) capsules: &'a [Capsule],
    pub(crate) planes: &'a [Plane],
    pub(crate) field: Option<HostField>,
    /// The body collides.
    pub(crate) body: bool,
}

impl<'a> HostColliders<'a> {
    /// The colliders `colliders` points to; none for NULL.
    pub(crate) fn read(colliders: *const PelageColliders) -> Result<Self, Failure> {
        let host = match colliders.is_null() {
            true => None,
            false => Some(req(colliders, "colliders")?),
        };
        Ok(HostColliders {
            spheres: bytemuck::cast_slice(host.map_or(Ok(&[][..]), |c| {
                slice(c.spheres, c.sphere_count, "colliders.spheres")
            })?),
            capsules: bytemuck::cast_slice(host.map_or(Ok(&[][..]), |c| {
                slice(c.capsules, c.capsule_count, "colliders.capsules")
            })?),
            planes: bytemuck::cast_slice(host.map_or(Ok(&[][..]), |c| {
                slice(c.planes, c.plane_count, "colliders.planes")
            })?),
            field: host.and_then(|c| {
                c.distance.map(|callback| HostField {
                    callback,
                    user_data: c.distance_user_data,
                    nan: AtomicBool::new(false),
                })
            }),
            body: host.is_some_and(|c| c.body != 0),
        })
    }

    /// NON_FINITE when the distance callback gave a NaN during this call.
    pub(crate) fn check_field(&self) -> Result<(), Failure> {
        self.field.as_ref().map_or(Ok(()), HostField::check)
    }

    /// The core's colliders, with `body` (built when `self.body` is set).
    pub(crate) fn colliders<'r>(&'r self, body: Option<&'r Body<'r>>) -> Colliders<'r> {
        Colliders {
            spheres: self.spheres,
            capsules: self.capsules,
            planes: self.planes,
            body,
            field: self.field.as_ref().map(|f| f as &dyn SignedDistance),
        }
    }
}

/// The host's distance callback as a core field, for one call: a NaN
/// distance counts as inside (never trusted as clear) and is remembered,
/// so that the call fails with NON_FINITE rather than return what it made
/// of it ([`HostField::check`]).
pub(crate) struct HostField {
    callback: unsafe extern "C" fn(*mut c_void, *const f32, usize, *mut f32),
    user_data: *mut c_void,
    nan: AtomicBool,
}

// SAFETY: the header requires the callback to be safe to call from any
// thread at once with its user data; pelage only passes the pointer on.
unsafe impl Sync for HostField {}
// SAFETY: as above: the pointer is only passed back to the host.
unsafe impl Send for HostField {}

impl HostField {
    /// The same callback for another call, nothing remembered.
    pub(crate) fn fresh(&self) -> HostField {
        HostField {
            callback: self.callback,
            user_data: self.user_data,
            nan: AtomicBool::new(false),
        }
    }

    /// NON_FINITE when the callback gave a NaN distance during the call.
    pub(crate) fn check(&self) -> Result<(), Failure> {
        match self.nan.load(Ordering::Relaxed) {
            false => Ok(()),
            true => Err(Failure::new(
                PelageStatus::NonFinite,
                "the distance callback returned NaN for a point",
            )),
        }
    }
}

impl SignedDistance for HostField {
    fn distances(&self, points: &[[f32; 3]], out: &mut [f32]) {
        let n = points.len().min(out.len());
        // SAFETY: the host's callback, with `n` packed points and room for
        // `n` distances, as its contract says.
        unsafe { (self.callback)(self.user_data, points.as_ptr().cast(), n, out.as_mut_ptr()) };
        if out[..n].iter().any(|d| d.is_nan()) {
            self.nan.store(true, Ordering::Relaxed);
        }
    }
}
