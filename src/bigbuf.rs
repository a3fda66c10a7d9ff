//! A growable buffer for the large arrays of assembly (the CSR columns and values of A).
//!
//! From 2 MiB on it lives in an anonymous memory map advised for transparent huge pages
//! (where the kernel offers them on request, `madvise` mode, the common default): the CSR
//! arrays are written once, front to back, and with 4 KiB pages a third of the assembly time
//! went to first-touch page faults (measured on the 396 k-unknown box: 0.13 of 0.43 s).
//! Smaller buffers, or a map the system refuses, use a plain `Vec`. Safe code only: the map
//! is viewed as `[T]` through `bytemuck` (a map is page-aligned).

use crate::tuning::MAP_FROM;
use bytemuck::Pod;
use memmap2::{Advice, MmapMut, MmapOptions};
use std::marker::PhantomData;

enum Store<T> {
    Vec(Vec<T>),
    Map(MmapMut),
}

/// A `Vec`-like buffer of plain numbers (see the module doc).
pub struct BigVec<T: Pod> {
    store: Store<T>,
    len: usize,
    _t: PhantomData<T>,
}

impl<T: Pod> Default for BigVec<T> {
    fn default() -> Self {
        BigVec {
            store: Store::Vec(Vec::new()),
            len: 0,
            _t: PhantomData,
        }
    }
}

impl<T: Pod> BigVec<T> {
    /// An empty buffer with room for `cap` elements (a reservation: pages are committed as
    /// they fill; if the system refuses the reservation, the buffer grows on demand).
    pub fn with_capacity(cap: usize) -> BigVec<T> {
        BigVec {
            store: Self::store(cap, false),
            len: 0,
            _t: PhantomData,
        }
    }

    /// `needed`: the room is needed now (a growth), so a refused map falls back to a `Vec` of
    /// that capacity; otherwise to an empty `Vec`.
    fn store(cap: usize, needed: bool) -> Store<T> {
        let bytes = cap * std::mem::size_of::<T>();
        if bytes >= MAP_FROM {
            return match MmapOptions::new().len(bytes).map_anon() {
                Ok(map) => {
                    // Advice only: a kernel without THP leaves the map as it is.
                    let _ = map.advise(Advice::HugePage);
                    Store::Map(map)
                }
                // The system refuses to reserve that much (strict overcommit): grow on demand
                // instead of asking the allocator for the same amount.
                Err(_) if !needed => Store::Vec(Vec::new()),
                Err(_) => Store::Vec(Vec::with_capacity(cap)),
            };
        }
        Store::Vec(Vec::with_capacity(cap))
    }

    fn capacity(&self) -> usize {
        match &self.store {
            Store::Vec(v) => v.capacity(),
            Store::Map(m) => m.len() / std::mem::size_of::<T>(),
        }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Appends `s`, growing the buffer (×2, or to what `s` needs) when it is full.
    pub fn extend_from_slice(&mut self, s: &[T]) {
        let need = self.len + s.len();
        if need > self.capacity() {
            let mut bigger = BigVec {
                store: Self::store(need.max(2 * self.capacity()), true),
                len: 0,
                _t: PhantomData,
            };
            bigger.extend_from_slice(self.as_slice());
            self.store = bigger.store;
        }
        match &mut self.store {
            Store::Vec(v) => v.extend_from_slice(s),
            Store::Map(m) => {
                let all: &mut [T] = bytemuck::cast_slice_mut(&mut m[..]);
                all[self.len..need].copy_from_slice(s);
            }
        }
        self.len = need;
    }

    pub fn as_slice(&self) -> &[T] {
        match &self.store {
            Store::Vec(v) => v,
            Store::Map(m) => &bytemuck::cast_slice(&m[..])[..self.len],
        }
    }

    /// A pointer to the first element, valid (non-null, aligned) even when empty.
    pub fn as_mut_ptr(&mut self) -> *mut T {
        match &mut self.store {
            Store::Vec(v) => v.as_mut_ptr(),
            Store::Map(m) => bytemuck::cast_slice_mut::<u8, T>(&mut m[..]).as_mut_ptr(),
        }
    }
}

impl<T: Pod> std::ops::Deref for BigVec<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        self.as_slice()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grows_from_a_vec_into_a_map_keeping_every_value() {
        let mut b: BigVec<f64> = BigVec::with_capacity(3);
        let mut want = Vec::new();
        // 3 → past MAP_FROM (2 MiB = 262 144 f64): several growths, Vec then map.
        for k in 0..100_000 {
            let s = [k as f64, -(k as f64), 0.5 * k as f64];
            b.extend_from_slice(&s);
            want.extend_from_slice(&s);
        }
        assert_eq!(b.len(), want.len());
        assert!(matches!(b.store, Store::Map(_)));
        assert_eq!(b.as_slice(), &want[..]);
        assert_eq!(b[7], want[7]);
        assert!(!b.as_mut_ptr().is_null());
    }

    #[test]
    fn empty_buffers_have_a_valid_pointer() {
        let mut b: BigVec<i32> = BigVec::default();
        assert!(b.is_empty());
        assert!(!b.as_mut_ptr().is_null());
        let mut m: BigVec<i32> = BigVec::with_capacity(1 << 20);
        assert!(matches!(m.store, Store::Map(_)));
        assert!(m.is_empty() && m.as_slice().is_empty());
        assert!(!m.as_mut_ptr().is_null());
    }
}
