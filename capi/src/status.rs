//! Status codes, messages and the panic boundary.

use pelage_core::Error;
use std::cell::RefCell;
use std::ffi::{c_char, CString};

/// Result of every pelage call. Values are stable: a retired code is never reused.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PelageStatus {
    /// Success; outputs were written.
    Ok = 0,
    /// A required pointer was NULL.
    NullParameter = 1,
    /// A parameter is outside its documented domain (including bad strides);
    /// for a number, a finite value outside its range.
    InvalidArgument = 2,
    /// An input number (a value in a buffer, a parameter) is NaN or
    /// infinite: any non-finite input gets this status, whatever range the
    /// number has.
    NonFinite = 3,
    /// An index in the input is out of range.
    OutOfRange = 4,
    /// The arena or an output buffer is too small; required sizes were reported.
    CapacityExceeded = 5,
    /// A pointer or stride is not 4-byte aligned.
    Misaligned = 6,
    /// Serialized data is truncated or corrupt.
    CorruptData = 7,
    /// Serialized data or a struct comes from an incompatible version.
    VersionMismatch = 8,
    /// The progress callback returned false. Calls that write only at
    /// their end (stamp, bind) leave their outputs untouched; those that
    /// write in place (expand, settle) say in their docs what is then
    /// unspecified.
    Cancelled = 9,
    /// An internal error (a bug in pelage, or the system refused a thread);
    /// outputs may be partly written.
    Panic = 10,
    /// The system refused memory pelage asked for (the call's own working
    /// memory or a copy it keeps); nothing was written or changed.
    OutOfMemory = 11,
}

/// A static, human-readable description of a PelageStatus value (never NULL;
/// "unknown status" for values this library does not define).
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_status_message(status: i32) -> *const c_char {
    const ALL: [PelageStatus; 12] = [
        PelageStatus::Ok,
        PelageStatus::NullParameter,
        PelageStatus::InvalidArgument,
        PelageStatus::NonFinite,
        PelageStatus::OutOfRange,
        PelageStatus::CapacityExceeded,
        PelageStatus::Misaligned,
        PelageStatus::CorruptData,
        PelageStatus::VersionMismatch,
        PelageStatus::Cancelled,
        PelageStatus::Panic,
        PelageStatus::OutOfMemory,
    ];
    let Some(&status) = ALL.iter().find(|s| **s as i32 == status) else {
        return c"unknown status".as_ptr();
    };
    let s: &'static std::ffi::CStr = match status {
        PelageStatus::Ok => c"ok",
        PelageStatus::NullParameter => c"a required pointer is NULL",
        PelageStatus::InvalidArgument => c"invalid argument",
        PelageStatus::NonFinite => c"input holds NaN or infinity",
        PelageStatus::OutOfRange => c"index out of range",
        PelageStatus::CapacityExceeded => c"arena or output buffer too small",
        PelageStatus::Misaligned => c"pointer or stride not 4-byte aligned",
        PelageStatus::CorruptData => c"data truncated or corrupt",
        PelageStatus::VersionMismatch => c"version mismatch",
        PelageStatus::Cancelled => c"cancelled",
        PelageStatus::Panic => c"internal error (panic caught)",
        PelageStatus::OutOfMemory => c"out of memory",
    };
    s.as_ptr()
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

/// The detailed message of the last failed call on the calling thread ("" if
/// none yet; successful calls leave it unchanged). The pointer stays valid
/// until the next failed pelage call on this thread.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_last_error() -> *const c_char {
    // while the thread's locals are torn down there is no message to give
    LAST_ERROR
        .try_with(|m| m.borrow().as_ptr())
        .unwrap_or(c"".as_ptr())
}

/// A failed call: its status and a message for `pelage_last_error`.
#[derive(Debug)]
pub(crate) struct Failure {
    pub status: PelageStatus,
    pub message: String,
}

impl Failure {
    pub fn new(status: PelageStatus, message: impl Into<String>) -> Self {
        Failure {
            status,
            message: message.into(),
        }
    }
}

impl From<Error> for Failure {
    fn from(e: Error) -> Self {
        let status = match e {
            Error::CapacityExceeded { .. } | Error::OutputTooSmall { .. } => {
                PelageStatus::CapacityExceeded
            }
            Error::InvalidArgument(_)
            | Error::BadStride { .. }
            | Error::OutOfDomain { .. }
            | Error::WeightSum { .. } => PelageStatus::InvalidArgument,
            Error::NonFinite { .. } => PelageStatus::NonFinite,
            Error::OutOfRange { .. } | Error::NotBetween { .. } => PelageStatus::OutOfRange,
            Error::Corrupt { .. } => PelageStatus::CorruptData,
            Error::VersionMismatch { .. } => PelageStatus::VersionMismatch,
            Error::Cancelled => PelageStatus::Cancelled,
            // a variant newer than this layer: still a failure, never OK
            _ => PelageStatus::InvalidArgument,
        };
        Failure::new(status, e.to_string())
    }
}

pub(crate) fn set_last_error(message: &str) {
    let c = CString::new(message.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|m| *m.borrow_mut() = c);
}

/// Runs a fallible FFI body, catching panics, recording the message of a
/// failure and returning its status.
pub(crate) fn boundary(body: impl FnOnce() -> Result<(), Failure>) -> PelageStatus {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(body)) {
        Ok(Ok(())) => PelageStatus::Ok,
        Ok(Err(f)) => {
            set_last_error(&f.message);
            f.status
        }
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            set_last_error(&format!("internal error: {what}"));
            PelageStatus::Panic
        }
    }
}

/// Wraps an `extern "C"` body in [`boundary`].
macro_rules! ffi_boundary {
    ($($body:tt)*) => {
        $crate::status::boundary(move || -> Result<(), $crate::status::Failure> { $($body)* })
    };
}

/// Asserts at compile time that a C record and its core twin (cast into
/// each other by bytemuck) have the same size, alignment and every named
/// field at the same offset.
macro_rules! same_layout {
    ($c:ty, $core:ty, $($field:ident),+) => {
        const _: () = {
            assert!(std::mem::size_of::<$c>() == std::mem::size_of::<$core>());
            assert!(std::mem::align_of::<$c>() == std::mem::align_of::<$core>());
            $(assert!(std::mem::offset_of!($c, $field) == std::mem::offset_of!($core, $field));)+
        };
    };
}
