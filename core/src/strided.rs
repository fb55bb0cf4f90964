//! Read-only strided views over host memory.

use crate::Error;
use bytemuck::Pod;
use core::marker::PhantomData;
use core::mem::size_of;

/// `count` elements of `T`, `stride` bytes apart, inside `bytes`.
///
/// Elements are read with [`bytemuck::pod_read_unaligned`], so host buffers
/// only need the alignment of their own element type, never that of a SIMD type.
#[derive(Clone, Copy, Debug)]
pub struct Strided<'a, T> {
    bytes: &'a [u8],
    stride: usize,
    count: usize,
    _t: PhantomData<T>,
}

impl<'a, T: Pod> Strided<'a, T> {
    /// Validates that `count` elements at `stride` fit in `bytes`.
    pub fn new(
        bytes: &'a [u8],
        stride: usize,
        count: usize,
        what: &'static str,
    ) -> Result<Self, Error> {
        let bad = Error::BadStride { what };
        if count > 0 {
            if stride < size_of::<T>() {
                return Err(bad);
            }
            let need = stride
                .checked_mul(count - 1)
                .and_then(|b| b.checked_add(size_of::<T>()))
                .ok_or(bad)?;
            if need > bytes.len() {
                return Err(bad);
            }
        }
        Ok(Strided {
            bytes,
            stride,
            count,
            _t: PhantomData,
        })
    }

    /// A tightly packed view over a typed slice.
    pub fn from_slice(items: &'a [T]) -> Self {
        Strided {
            bytes: bytemuck::cast_slice(items),
            stride: size_of::<T>(),
            count: items.len(),
            _t: PhantomData,
        }
    }

    /// An empty view.
    pub fn empty() -> Self {
        Strided {
            bytes: &[],
            stride: size_of::<T>(),
            count: 0,
            _t: PhantomData,
        }
    }

    /// Number of elements.
    #[inline]
    pub fn len(&self) -> usize {
        self.count
    }

    /// True when the view holds no element.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Element `i`. Panics when `i >= len()`, like slice indexing.
    #[inline]
    pub fn get(&self, i: usize) -> T {
        assert!(i < self.count, "strided index out of bounds");
        let at = i * self.stride;
        bytemuck::pod_read_unaligned(&self.bytes[at..at + size_of::<T>()])
    }

    /// Iterates over the elements in order.
    pub fn iter(&self) -> impl Iterator<Item = T> + '_ {
        (0..self.count).map(move |i| self.get(i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_interleaved_and_rejects_short_buffers() {
        let data: [f32; 8] = [1.0, 2.0, 3.0, 9.0, 4.0, 5.0, 6.0, 9.0];
        let bytes: &[u8] = bytemuck::cast_slice(&data);
        let v = Strided::<[f32; 3]>::new(bytes, 16, 2, "p").unwrap();
        assert_eq!(v.get(1), [4.0, 5.0, 6.0]);
        assert!(Strided::<[f32; 3]>::new(bytes, 16, 3, "p").is_err());
        assert!(Strided::<[f32; 3]>::new(bytes, 8, 2, "p").is_err());
        assert!(Strided::<[f32; 3]>::new(&bytes[1..], 16, 2, "p").is_ok());
        assert_eq!(
            Strided::<[f32; 3]>::new(&bytes[1..], 16, 2, "p")
                .unwrap()
                .get(0)[2],
            f32::from_bits(u32::from_le_bytes([
                bytes[9], bytes[10], bytes[11], bytes[12]
            ]))
        );
    }
}
