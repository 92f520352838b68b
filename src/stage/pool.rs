//! The frame pool: the planes of the taps (primitive lists, setups, fragment lists, sample
//! buffers, frame memories, pixel codes, the depth-of-field's layer planes), kept across the
//! frames of a run so that the second frame allocates no frame-sized buffer. A buffer taken from the pool has the
//! length asked for and every element set, exactly as a fresh `vec![v; n]`, so a run's
//! result never depends on what the pool held; only its allocations and page faults do.
//!
//! A stage takes its planes through [`Cx::pool`](super::Cx); the runner of a sequence of
//! frames (`pipeline::fast::Emulator`) gives the taps of a finished frame back with
//! [`Pool::recycle`]. A one-shot run uses an empty pool, which only allocates.

use super::{Memo, Taps};
use crate::scene::MeshCache;
use rayon::prelude::*;
use std::any::{Any, TypeId};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Buffers kept per element type (the largest are kept when more are given back).
const KEEP: usize = 24;

/// Memo values kept (the oldest goes when more are made).
const MEMO_KEEP: usize = 32;

/// A memo value and its key.
type MemoEntry = (u64, Arc<dyn Any + Send + Sync>);

/// A pool of buffers by element type (see the module docs). It is also the [`Memo`] of a
/// run without a stage cache: values made from the configuration alone (a LUT's contents)
/// are made once per run of frames, not once per frame.
#[derive(Default)]
pub struct Pool {
    shelves: Mutex<HashMap<TypeId, Vec<Box<dyn Any + Send>>>>,
    memo: Mutex<Vec<MemoEntry>>,
    meshes: MeshCache,
}

impl std::fmt::Debug for Pool {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pool")
            .field("buffers", &self.len())
            .finish()
    }
}

impl Pool {
    /// An empty pool.
    pub fn new() -> Self {
        Self::default()
    }

    /// The meshes of the canonical objects met in the run's frames (the host front end's).
    pub fn meshes(&self) -> &MeshCache {
        &self.meshes
    }

    /// Buffers held.
    pub fn len(&self) -> usize {
        self.lock().values().map(Vec::len).sum()
    }

    /// Whether the pool holds no buffer.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<TypeId, Vec<Box<dyn Any + Send>>>> {
        // A panic while holding the lock leaves whole buffers behind: still usable.
        self.shelves.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// An empty buffer with room for `cap` elements: the smallest kept one that holds
    /// them, else the largest kept one grown, else a new one.
    pub fn take<T: Send + 'static>(&self, cap: usize) -> Vec<T> {
        let Some(mut v) = self.pick(cap) else {
            return Vec::with_capacity(cap);
        };
        v.clear();
        v.reserve(cap);
        v
    }

    /// A kept list of lists as it was given back (its inner lists keep their buffers, for
    /// work split in parts whose lists live across frames), else an empty one.
    pub fn take_lists<T: Send + 'static>(&self) -> Vec<Vec<T>> {
        self.pick(0).unwrap_or_default()
    }

    /// A buffer of `n` elements for a kernel that overwrites every one of them: a kept
    /// buffer's old elements stay as they are (no fill pass over a frame-sized plane from
    /// the second frame on), only elements beyond its length are set to `value`.
    pub fn scratch<T: Copy + Send + 'static>(&self, n: usize, value: T) -> Vec<T> {
        // A new buffer of zeros comes from the allocator already zeroed (no fill pass: its
        // pages are touched first by the kernel that writes them).
        let Some(mut v) = self.pick(n) else {
            return vec![value; n];
        };
        if v.len() >= n {
            v.truncate(n);
        } else {
            v.resize(n, value);
        }
        v
    }

    /// The kept buffer [`Pool::take`] would choose for `cap` elements, as it was kept
    /// (`None`: none is kept).
    fn pick<T: Send + 'static>(&self, cap: usize) -> Option<Vec<T>> {
        let mut shelves = self.lock();
        let shelf = shelves.get_mut(&TypeId::of::<T>())?;
        let cap_of = |b: &Box<dyn Any + Send>| b.downcast_ref::<Vec<T>>().map_or(0, Vec::capacity);
        let fits = (0..shelf.len())
            .filter(|&j| cap_of(&shelf[j]) >= cap)
            .min_by_key(|&j| cap_of(&shelf[j]));
        let j = fits.or_else(|| (0..shelf.len()).max_by_key(|&j| cap_of(&shelf[j])))?;
        Some(
            *shelf
                .swap_remove(j)
                .downcast::<Vec<T>>()
                .expect("a shelf holds its own type"),
        )
    }

    /// The buffer of `T`s kept last, with its elements (objects kept whole between frames,
    /// e.g. the threads' scratch of a stage); empty when none is kept.
    pub fn reuse<T: Send + 'static>(&self) -> Vec<T> {
        let mut shelves = self.lock();
        shelves
            .get_mut(&TypeId::of::<T>())
            .and_then(Vec::pop)
            .map(|b| *b.downcast::<Vec<T>>().expect("a shelf holds its own type"))
            .unwrap_or_default()
    }

    /// A buffer of `n` copies of `value` (as `vec![value; n]`), filled on the threads when
    /// it is large (a frame's plane).
    pub fn filled<T: Clone + Send + 'static>(&self, n: usize, value: T) -> Vec<T> {
        const PARALLEL: usize = 1 << 16;
        let mut v = self.take(n);
        if n >= PARALLEL {
            v.par_extend(rayon::iter::repeat_n(value, n));
        } else {
            v.resize(n, value);
        }
        v
    }

    /// A copy of `src` in a pooled buffer.
    pub fn copy<T: Copy + Send + 'static>(&self, src: &[T]) -> Vec<T> {
        let mut v = self.take(src.len());
        v.extend_from_slice(src);
        v
    }

    /// Keeps `v` for a later [`Pool::take`] (an unallocated buffer is dropped).
    pub fn give<T: Send + 'static>(&self, v: Vec<T>) {
        if v.capacity() == 0 {
            return;
        }
        let mut shelves = self.lock();
        let shelf = shelves.entry(TypeId::of::<T>()).or_default();
        shelf.push(Box::new(v));
        if shelf.len() > KEEP {
            let cap_of =
                |b: &Box<dyn Any + Send>| b.downcast_ref::<Vec<T>>().map_or(0, Vec::capacity);
            let smallest = (0..shelf.len())
                .min_by_key(|&j| cap_of(&shelf[j]))
                .expect("not empty");
            shelf.swap_remove(smallest);
        }
    }

    /// Gives back the planes of every tap in `taps` (the taps after each stage of a
    /// finished frame; taps shared between them are given back once, when the last holder
    /// lets go).
    pub fn recycle(&self, taps: impl IntoIterator<Item = Taps>) {
        let mut prims = Vec::new();
        let mut setups = Vec::new();
        let mut frags = Vec::new();
        let mut samples = Vec::new();
        let mut frames = Vec::new();
        let mut pixels = Vec::new();
        for t in taps {
            let f = t.fixed;
            prims.extend(f.prims);
            setups.extend(f.setups);
            frags.extend(f.frags);
            samples.extend(f.samples);
            samples.extend(f.more_samples);
            frames.extend(f.frame);
            pixels.extend(f.pixels);
            if let Some(c) = t.channels {
                frames.extend(Arc::try_unwrap(c).ok().into_iter().flat_map(|c| c.fixed));
            }
        }
        for a in prims {
            if let Ok(p) = Arc::try_unwrap(a) {
                self.give(p.q);
            }
        }
        for a in setups {
            if let Ok(s) = Arc::try_unwrap(a) {
                self.give(s);
            }
        }
        for a in frags {
            if let Ok(f) = Arc::try_unwrap(a) {
                // Kept whole: the next frame's raster tasks take their parts back in order.
                self.give(f.runs.parts);
                self.give(f.runs.spans);
            }
        }
        for a in samples {
            if let Ok(s) = Arc::try_unwrap(a) {
                // The depth and id planes are the channels' own only when the last one lets go.
                for plane in [s.samples.z, s.samples.prim] {
                    if let Ok(v) = Arc::try_unwrap(plane) {
                        self.give(v);
                    }
                }
                self.give(s.samples.i);
            }
        }
        // The pixels first: a deferred gamma tap holds the frame it reads.
        for a in pixels {
            if let Ok(p) = Arc::try_unwrap(a) {
                let (codes, frame) = p.into_planes();
                codes.into_iter().for_each(|c| self.give(c));
                frames.extend(frame);
            }
        }
        for a in frames {
            if let Ok(f) = Arc::try_unwrap(a) {
                self.give(f.frame.acc);
                self.give(f.frame.depth);
                self.give(f.frame.coverage);
            }
        }
    }
}

impl Memo for Pool {
    fn get_or_make(
        &self,
        key: u64,
        make: &mut dyn FnMut() -> Arc<dyn Any + Send + Sync>,
    ) -> Arc<dyn Any + Send + Sync> {
        let lock = || self.memo.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, v)) = lock().iter().find(|(k, _)| *k == key) {
            return v.clone();
        }
        // Made outside the lock (a value may take a while, or read the memo itself).
        let v = make();
        let mut m = lock();
        if m.len() >= MEMO_KEEP {
            m.remove(0);
        }
        m.push((key, v.clone()));
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_taken_buffer_is_as_fresh_and_reuses_the_allocation() {
        let pool = Pool::new();
        let mut v = pool.filled(1000, 7u32);
        assert_eq!(v, vec![7u32; 1000]);
        v[3] = 9;
        let at = v.as_ptr();
        pool.give(v);
        let w = pool.filled(800, 1u32);
        assert_eq!(w, vec![1u32; 800]);
        assert_eq!(w.as_ptr(), at, "the kept allocation is reused");
        // Another type has its own shelf.
        assert!(pool.take::<u16>(10).capacity() >= 10);
        pool.give(w);
        assert_eq!(pool.len(), 1);
        // A frame-sized buffer (filled on the threads) over a kept one's old elements.
        let mut big = pool.filled(300_000, 5u64);
        big[1000] = 6;
        let at = big.as_ptr();
        pool.give(big);
        let big = pool.filled(250_000, 0u64);
        assert_eq!(big, vec![0u64; 250_000]);
        assert_eq!(big.as_ptr(), at);
    }

    #[test]
    fn a_scratch_buffer_keeps_old_elements_and_fills_only_the_new_ones() {
        let pool = Pool::new();
        let mut v = pool.scratch(4, 0u32);
        assert_eq!(v, [0; 4]);
        v.copy_from_slice(&[1, 2, 3, 4]);
        let at = v.as_ptr();
        pool.give(v);
        let w = pool.scratch(3, 9u32);
        assert_eq!(w, [1, 2, 3], "no fill pass over a kept buffer");
        assert_eq!(w.as_ptr(), at);
        pool.give(w);
        assert_eq!(pool.scratch(6, 9u32), [1, 2, 3, 9, 9, 9]);
    }

    #[test]
    fn the_smallest_fitting_buffer_is_taken() {
        let pool = Pool::new();
        pool.give(Vec::<u8>::with_capacity(100));
        pool.give(Vec::<u8>::with_capacity(10));
        pool.give(Vec::<u8>::with_capacity(50));
        assert_eq!(pool.take::<u8>(20).capacity(), 50);
        assert_eq!(pool.take::<u8>(200).capacity(), 200);
        assert_eq!(pool.len(), 1);
    }
}
