//! Every cast between a C handle and the Rust object behind it. A handle
//! is a `Box` given to the host by [`into_handle`]; the header's contract
//! is that a non-NULL handle came from its `_new` call and is not freed
//! yet, so it points to a live object of its type.

use crate::buffers::{req, req_mut};
use crate::status::Failure;

/// An opaque C handle type (`PelageFrameTy`, ...) and the object behind it.
pub(crate) trait Handle {
    /// What the handle points to.
    type Object;
    /// The handle's argument name in messages.
    const NAME: &'static str;
}

/// The object behind `handle`, shared, or NULL_PARAMETER: for the calls
/// that only read it, which the header lets run at once.
pub(crate) fn object<'a, H: Handle>(handle: *mut H) -> Result<&'a H::Object, Failure> {
    req(handle.cast::<H::Object>().cast_const(), H::NAME)
}

/// The object behind `handle`, for a call that changes it (the header
/// forbids other calls on it meanwhile), or NULL_PARAMETER.
pub(crate) fn object_mut<'a, H: Handle>(handle: *mut H) -> Result<&'a mut H::Object, Failure> {
    req_mut(handle.cast::<H::Object>(), H::NAME)
}

/// A new handle owning `object`.
pub(crate) fn into_handle<H: Handle>(object: Box<H::Object>) -> *mut H {
    Box::into_raw(object).cast::<H>()
}

/// Drops the object behind `handle`; NULL does nothing.
pub(crate) fn free<H: Handle>(handle: *mut H) {
    if handle.is_null() {
        return;
    }
    // dropping plain data cannot panic; the boundary is kept so that no
    // exported body can unwind into the host
    let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        // SAFETY: `handle` came from `into_handle` for this type and is
        // freed once, as the header requires.
        drop(unsafe { Box::from_raw(handle.cast::<H::Object>()) });
    }));
}
