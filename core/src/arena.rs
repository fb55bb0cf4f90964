//! A bump arena over caller-provided bytes.
//!
//! Stages never allocate: they carve typed, aligned slices out of an
//! [`Arena`]. [`ArenaLayout`] mirrors the same sequence of requests without
//! memory, so `required_bytes` functions give an exact upper bound up front.

use crate::Error;
use bytemuck::Pod;
use core::mem::{align_of, size_of};

/// Hands out aligned `Pod` slices from a borrowed byte buffer.
pub struct Arena<'a> {
    rest: &'a mut [u8],
    total: usize,
}

impl<'a> Arena<'a> {
    /// Wraps `buf`; the arena never touches bytes outside it.
    pub fn new(buf: &'a mut [u8]) -> Self {
        let total = buf.len();
        Arena { rest: buf, total }
    }

    /// Bytes not yet handed out (before alignment padding).
    pub fn remaining(&self) -> usize {
        self.rest.len()
    }

    /// Size of the buffer the arena was created over.
    pub fn capacity(&self) -> usize {
        self.total
    }

    /// Takes `n` elements of `T`. Their contents are whatever the buffer held:
    /// stages write before they read, and skipping a fill keeps big arenas cheap.
    ///
    /// Fails with [`Error::CapacityExceeded`] (bytes used so far plus this
    /// request, against the buffer size) when the buffer is exhausted.
    pub fn alloc<T: Pod>(&mut self, n: usize) -> Result<&'a mut [T], Error> {
        let rest = core::mem::take(&mut self.rest);
        let pad = rest.as_ptr().align_offset(align_of::<T>());
        let bytes = n
            .checked_mul(size_of::<T>())
            .ok_or(Error::CapacityExceeded {
                needed: usize::MAX,
                available: self.total,
            })?;
        if pad > rest.len() || bytes > rest.len() - pad {
            let used = self.total - rest.len();
            self.rest = rest;
            return Err(Error::CapacityExceeded {
                needed: used.saturating_add(pad).saturating_add(bytes),
                available: self.total,
            });
        }
        let (_, aligned) = rest.split_at_mut(pad);
        let (mine, rest) = aligned.split_at_mut(bytes);
        self.rest = rest;
        Ok(bytemuck::cast_slice_mut(mine))
    }
}

/// Accumulates the worst-case size of a sequence of [`Arena::alloc`] calls.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ArenaLayout {
    bytes: usize,
}

impl ArenaLayout {
    /// An empty layout.
    pub const fn new() -> Self {
        ArenaLayout { bytes: 0 }
    }

    /// Accounts for `n` elements of `T`, including worst-case alignment padding.
    pub fn add<T: Pod>(&mut self, n: usize) -> &mut Self {
        self.bytes = self
            .bytes
            .saturating_add(align_of::<T>() - 1)
            .saturating_add(n.saturating_mul(size_of::<T>()));
        self
    }

    /// Total bytes an arena needs for every request added so far.
    pub fn bytes(&self) -> usize {
        self.bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alloc_is_aligned_and_bounded() {
        let mut buf = [0xAAu8; 100];
        let mut arena = Arena::new(&mut buf[1..]);
        let a: &mut [u32] = arena.alloc(3).unwrap();
        assert_eq!(a.as_ptr() as usize % 4, 0);
        let b: &mut [u64] = arena.alloc(2).unwrap();
        assert_eq!(b.as_ptr() as usize % 8, 0);
        let err = arena.alloc::<u64>(100).unwrap_err();
        match err {
            Error::CapacityExceeded { needed, available } => {
                assert_eq!(available, 99);
                assert!(needed > 800);
            }
            e => panic!("{e:?}"),
        }
        // a failed request leaves the arena usable
        assert!(arena.alloc::<u8>(1).is_ok());
    }

    #[test]
    fn layout_bounds_any_start_alignment() {
        let mut layout = ArenaLayout::new();
        layout.add::<u8>(3).add::<u64>(5).add::<[f32; 3]>(7);
        for offset in 0..8 {
            let mut buf = [0u8; 256];
            let end = offset + layout.bytes();
            let mut arena = Arena::new(&mut buf[offset..end]);
            arena.alloc::<u8>(3).unwrap();
            arena.alloc::<u64>(5).unwrap();
            arena.alloc::<[f32; 3]>(7).unwrap();
        }
    }
}
