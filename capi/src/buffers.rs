//! Turning host pointers into checked Rust views.

use crate::status::Failure;
use crate::PelageStatus;
use pelage_core::Strided;
use std::mem::size_of;

/// `*const T` to `&T`, or NULL_PARAMETER naming the argument.
pub(crate) fn req<'a, T>(ptr: *const T, name: &str) -> Result<&'a T, Failure> {
    // SAFETY: the C contract requires a non-NULL pointer to a live, initialised T
    // that outlives the call; NULL is rejected here.
    unsafe { ptr.as_ref() }
        .ok_or_else(|| Failure::new(PelageStatus::NullParameter, format!("{name} is NULL")))
}

/// An optional output: `None` for NULL.
pub(crate) fn opt_mut<'a, T>(ptr: *mut T) -> Option<&'a mut T> {
    // SAFETY: the C contract allows NULL or a pointer to a live T the host
    // lets us write for the duration of the call.
    unsafe { ptr.as_mut() }
}

/// `*mut T` to `&mut T`, or NULL_PARAMETER naming the argument.
pub(crate) fn req_mut<'a, T>(ptr: *mut T, name: &str) -> Result<&'a mut T, Failure> {
    // SAFETY: as `req`, and the host grants exclusive access for the call.
    unsafe { ptr.as_mut() }
        .ok_or_else(|| Failure::new(PelageStatus::NullParameter, format!("{name} is NULL")))
}

fn check_align(ptr: usize, stride: usize, name: &str) -> Result<(), Failure> {
    if ptr % 4 != 0 || stride % 4 != 0 {
        return Err(Failure::new(
            PelageStatus::Misaligned,
            format!("{name}: pointer and stride must be multiples of 4"),
        ));
    }
    Ok(())
}

fn byte_len<T>(stride: usize, count: usize, name: &str) -> Result<usize, Failure> {
    if count == 0 {
        return Ok(0);
    }
    if stride < size_of::<T>() {
        return Err(Failure::new(
            PelageStatus::InvalidArgument,
            format!(
                "{name}: stride {stride} is smaller than the element ({} bytes)",
                size_of::<T>()
            ),
        ));
    }
    stride
        .checked_mul(count - 1)
        .and_then(|b| b.checked_add(size_of::<T>()))
        .filter(|&b| b <= isize::MAX as usize)
        .ok_or_else(|| {
            Failure::new(
                PelageStatus::InvalidArgument,
                format!("{name}: buffer size overflows"),
            )
        })
}

/// A strided input buffer of `count` elements. `(NULL, 0)` is a valid empty view.
pub(crate) fn strided<'a, T: bytemuck::Pod>(
    ptr: *const std::ffi::c_void,
    stride: usize,
    count: usize,
    name: &'static str,
) -> Result<Strided<'a, T>, Failure> {
    if count == 0 {
        return Ok(Strided::empty());
    }
    if ptr.is_null() {
        return Err(Failure::new(
            PelageStatus::NullParameter,
            format!("{name} is NULL"),
        ));
    }
    check_align(ptr as usize, stride, name)?;
    let len = byte_len::<T>(stride, count, name)?;
    // SAFETY: the host promises `count` elements `stride` bytes apart starting at
    // `ptr`, alive and unmodified for the duration of the call.
    let bytes = unsafe { std::slice::from_raw_parts(ptr.cast::<u8>(), len) };
    Ok(Strided::new(bytes, stride, count, name)?)
}

/// Raw bytes of an input buffer. `(NULL, 0)` is valid.
pub(crate) fn bytes<'a>(
    ptr: *const std::ffi::c_void,
    len: usize,
    name: &str,
) -> Result<&'a [u8], Failure> {
    if len == 0 {
        return Ok(&[]);
    }
    check_array(ptr.cast::<u8>(), len, name)?;
    // SAFETY: the host promises `len` readable bytes at `ptr` for the call;
    // check_array rejected NULL and lengths past isize::MAX.
    Ok(unsafe { std::slice::from_raw_parts(ptr.cast::<u8>(), len) })
}

/// A writable byte buffer (an arena). `(NULL, 0)` is valid.
pub(crate) fn bytes_mut<'a>(
    ptr: *mut std::ffi::c_void,
    len: usize,
    name: &str,
) -> Result<&'a mut [u8], Failure> {
    if len == 0 {
        return Ok(&mut []);
    }
    check_array(ptr.cast_const().cast::<u8>(), len, name)?;
    // SAFETY: the host grants exclusive access to `len` bytes at `ptr` for the
    // call; check_array rejected NULL and lengths past isize::MAX.
    Ok(unsafe { std::slice::from_raw_parts_mut(ptr.cast::<u8>(), len) })
}

/// Checks a host array of `count` `T` (count > 0): not NULL, aligned for
/// `T`, and addressable.
fn check_array<T>(ptr: *const T, count: usize, name: &str) -> Result<(), Failure> {
    if ptr.is_null() {
        return Err(Failure::new(
            PelageStatus::NullParameter,
            format!("{name} is NULL"),
        ));
    }
    if !ptr.is_aligned() {
        return Err(Failure::new(
            PelageStatus::Misaligned,
            format!(
                "{name}: pointer not aligned to {} bytes",
                std::mem::align_of::<T>()
            ),
        ));
    }
    if count
        .checked_mul(size_of::<T>())
        .is_none_or(|b| b > isize::MAX as usize)
    {
        return Err(Failure::new(
            PelageStatus::InvalidArgument,
            format!("{name}: size overflows"),
        ));
    }
    Ok(())
}

/// A contiguous input array of Pod `T`. `(NULL, 0)` is valid.
pub(crate) fn slice<'a, T: bytemuck::Pod>(
    ptr: *const T,
    count: usize,
    name: &str,
) -> Result<&'a [T], Failure> {
    if count == 0 {
        return Ok(&[]);
    }
    check_array(ptr, count, name)?;
    // SAFETY: non-NULL, aligned for T, and the host promises `count`
    // initialised elements for the duration of the call.
    Ok(unsafe { std::slice::from_raw_parts(ptr, count) })
}

/// A writable array of Pod `T`. `(NULL, 0)` is valid.
pub(crate) fn slice_mut<'a, T: bytemuck::Pod>(
    ptr: *mut T,
    count: usize,
    name: &str,
) -> Result<&'a mut [T], Failure> {
    if count == 0 {
        return Ok(&mut []);
    }
    check_array(ptr.cast_const(), count, name)?;
    // SAFETY: non-NULL, aligned, and the host grants exclusive access to
    // `count` elements for the duration of the call.
    Ok(unsafe { std::slice::from_raw_parts_mut(ptr, count) })
}

/// A strided float3 output buffer, checked but not yet written. It holds a
/// raw pointer rather than a slice so that two outputs may interleave in one
/// host buffer (positions and normals in one vertex array).
pub(crate) struct Float3Out {
    ptr: *mut u8,
    stride: usize,
    count: usize,
}

impl Float3Out {
    /// `count` float3 slots `stride` bytes apart; NULL gives `None` (output not wanted).
    pub fn new(
        ptr: *mut std::ffi::c_void,
        stride: usize,
        count: usize,
        name: &str,
    ) -> Result<Option<Self>, Failure> {
        if ptr.is_null() || count == 0 {
            return Ok(None);
        }
        check_align(ptr as usize, stride, name)?;
        byte_len::<[f32; 3]>(stride, count, name)?;
        Ok(Some(Float3Out {
            ptr: ptr.cast(),
            stride,
            count,
        }))
    }

    pub fn set(&mut self, i: usize, v: [f32; 3]) {
        assert!(i < self.count, "float3 output index out of range");
        // SAFETY: `i < count`, and the host grants write access to `count`
        // float3 slots `stride` bytes apart (byte_len checked the span fits
        // in isize); the write is unaligned-safe and creates no reference.
        unsafe {
            self.ptr
                .add(i * self.stride)
                .cast::<[f32; 3]>()
                .write_unaligned(v)
        }
    }
}

/// A host array of `count` handles (opaque pointers). `(NULL, 0)` is valid.
pub(crate) fn handles<'a, T>(
    ptr: *const *mut T,
    count: usize,
    name: &str,
) -> Result<&'a [*mut T], Failure> {
    if count == 0 {
        return Ok(&[]);
    }
    check_array(ptr, count, name)?;
    // SAFETY: non-NULL, aligned, and the host promises `count` initialised
    // handles for the duration of the call.
    Ok(unsafe { std::slice::from_raw_parts(ptr, count) })
}

/// OUT_OF_MEMORY for `bytes` bytes of `what`.
fn refused(bytes: usize, what: &str) -> Failure {
    Failure::new(
        PelageStatus::OutOfMemory,
        format!("cannot allocate {bytes} bytes for {what}"),
    )
}

/// Grows `v` to at least `n` elements, new ones `value`, or OUT_OF_MEMORY
/// naming `what` when the system refuses the memory (where `vec!` or
/// `resize` would abort the host's process).
pub(crate) fn grow<T: Clone>(
    v: &mut Vec<T>,
    n: usize,
    value: T,
    what: &str,
) -> Result<(), Failure> {
    if n > v.len() {
        v.try_reserve_exact(n - v.len())
            .map_err(|_| refused(n.saturating_mul(size_of::<T>()), what))?;
        v.resize(n, value);
    }
    Ok(())
}

/// `n` copies of `value`, or OUT_OF_MEMORY (see [`grow`]).
pub(crate) fn filled<T: Clone>(n: usize, value: T, what: &str) -> Result<Vec<T>, Failure> {
    let mut v = Vec::new();
    grow(&mut v, n, value, what)?;
    Ok(v)
}

/// `n` zero bytes, or OUT_OF_MEMORY (see [`grow`]). The system's zeroed
/// memory, as `vec![0u8; n]` takes it: pages are zeroed as they are first
/// touched, not written here.
pub(crate) fn zeroed(n: usize, what: &str) -> Result<Vec<u8>, Failure> {
    if n == 0 {
        return Ok(Vec::new());
    }
    let layout = std::alloc::Layout::array::<u8>(n).map_err(|_| refused(n, what))?;
    // SAFETY: the layout's size is not zero.
    let p = unsafe { std::alloc::alloc_zeroed(layout) };
    if p.is_null() {
        return Err(refused(n, what));
    }
    // SAFETY: `p` is a live allocation of the global allocator for `n`
    // bytes with u8's alignment, all of them initialised (zero).
    Ok(unsafe { Vec::from_raw_parts(p, n, n) })
}

/// The `n` items of `items` in a new vector, or OUT_OF_MEMORY (see
/// [`grow`]).
pub(crate) fn collected<T>(
    items: impl Iterator<Item = T>,
    n: usize,
    what: &str,
) -> Result<Vec<T>, Failure> {
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| refused(n.saturating_mul(size_of::<T>()), what))?;
    v.extend(items);
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_the_system_refuses_is_a_status_not_an_abort() {
        let huge = usize::MAX / 2;
        let e = filled(huge, 0u8, "the test").unwrap_err();
        assert_eq!(e.status, PelageStatus::OutOfMemory);
        assert!(e.message.contains("the test"), "{}", e.message);
        let mut v = vec![1u32; 3];
        assert_eq!(
            grow(&mut v, huge, 0, "more").unwrap_err().status,
            PelageStatus::OutOfMemory
        );
        assert_eq!(v, [1, 1, 1], "a refused growth leaves the vector as it was");
        grow(&mut v, 5, 7, "more").unwrap();
        grow(&mut v, 2, 9, "less").unwrap();
        assert_eq!(v, [1, 1, 1, 7, 7], "it grows and never shrinks");
        assert_eq!(
            zeroed(huge, "zeros").unwrap_err().status,
            PelageStatus::OutOfMemory
        );
        assert_eq!(zeroed(5, "zeros").unwrap(), [0u8; 5]);
        assert!(zeroed(0, "zeros").unwrap().is_empty());
        let e = collected(0..3u64, huge, "the items").unwrap_err();
        assert_eq!(e.status, PelageStatus::OutOfMemory);
        assert_eq!(collected(0..3u64, 3, "the items").unwrap(), [0, 1, 2]);
    }
}

/// Working memory the host lends a call (pelage_stamp, pelage_bind,
/// pelage_settle) or a simulation (pelage_sim_new): `bytes` bytes at
/// `memory`, as many as the call's pelage_*_size reported.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageArena {
    /// The memory; any alignment.
    pub memory: *mut std::ffi::c_void,
    /// Its size in bytes.
    pub bytes: usize,
}

impl PelageArena {
    /// The memory, checked, for as long as the host lends it.
    pub(crate) fn view<'a>(self, name: &str) -> Result<&'a mut [u8], Failure> {
        bytes_mut(self.memory, self.bytes, name)
    }
}
