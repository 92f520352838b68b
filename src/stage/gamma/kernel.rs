//! The LUT lookup over slices, the one kernel every gamma LUT (plain, extended, reduced, log)
//! runs: `out[i] = table[min(acc[i] >> shift, len - 1)]`, the clamp hoisted so the loop has
//! no bounds check, split into one equal chunk per thread (rayon).
//!
//! On x86-64 CPUs with AVX2 (detected at run time; the binary still runs on any x86-64) the
//! same loop is compiled a second time with AVX2 enabled: the compiler packs the looked-up
//! entries into vector stores, which makes the lookup 1.2-1.3 times as fast on the 2-core
//! development machine (docs/dither.md). Both builds compute the same codes; the
//! portable one stays reachable ([`lookup_block_portable`]) so tests compare the two.

use crate::stage::parts::run_parts;

/// Smallest chunk of [`lookup`] handed to a thread (smaller frames run on the caller).
pub const BLOCK: usize = 1 << 14;

/// One block of [`lookup`], serial: `out[i] = table[min(acc[i] >> shift, table.len() - 1)]`
/// for `i < min(acc.len(), out.len())`. An empty table writes the default value; a shift of
/// 32 or more addresses entry 0. Uses AVX2 when the CPU has it.
#[inline]
pub fn lookup_block<T: Copy, O: From<T> + Default>(
    table: &[T],
    acc: &[u32],
    shift: u32,
    out: &mut [O],
) {
    lookup_with(table, acc, shift, out, simd::avx2())
}

/// [`lookup_block`] in the portable build only (baseline x86-64 on that target): the same
/// codes, for comparing the two builds.
pub fn lookup_block_portable<T: Copy, O: From<T> + Default>(
    table: &[T],
    acc: &[u32],
    shift: u32,
    out: &mut [O],
) {
    lookup_with(table, acc, shift, out, false)
}

#[inline]
fn lookup_with<T: Copy, O: From<T> + Default>(
    table: &[T],
    acc: &[u32],
    shift: u32,
    out: &mut [O],
    avx2: bool,
) {
    if table.is_empty() {
        out.iter_mut().for_each(|o| *o = O::default());
        return;
    };
    if shift >= 32 {
        let v = table[0];
        out.iter_mut().zip(acc).for_each(|(o, _)| *o = O::from(v));
        return;
    }
    if avx2 {
        simd::lookup_avx2(table, acc, shift, out)
    } else {
        lookup_loop(table, acc, shift, out)
    }
}

/// The loop both builds compile: `shift < 32` (the clamp to the last entry, computed here,
/// lets the compiler drop the bounds check). Shift 0 (the presets' integer frame formats, the
/// reduced and log LUTs) has its own copy without the per-value shift.
#[inline(always)]
fn lookup_loop<T: Copy, O: From<T>>(table: &[T], acc: &[u32], shift: u32, out: &mut [O]) {
    #[inline(always)]
    fn run<T: Copy, O: From<T>>(table: &[T], acc: &[u32], shift: u32, out: &mut [O]) {
        let Some(last) = table.len().checked_sub(1) else {
            return;
        };
        for (o, &a) in out.iter_mut().zip(acc) {
            *o = O::from(table[((a >> shift) as usize).min(last)]);
        }
    }
    if shift == 0 {
        run(table, acc, 0, out)
    } else {
        run(table, acc, shift, out)
    }
}

/// The run-time AVX2 build of [`lookup_loop`].
#[cfg(target_arch = "x86_64")]
mod simd {
    /// Whether the CPU has AVX2 (the standard library caches the answer).
    #[inline]
    pub fn avx2() -> bool {
        std::arch::is_x86_feature_detected!("avx2")
    }

    /// [`super::lookup_loop`] compiled with AVX2; call only when [`avx2`] holds.
    #[inline]
    pub fn lookup_avx2<T: Copy, O: From<T>>(table: &[T], acc: &[u32], shift: u32, out: &mut [O]) {
        #[target_feature(enable = "avx2")]
        fn run<T: Copy, O: From<T>>(t: &[T], a: &[u32], s: u32, o: &mut [O]) {
            super::lookup_loop(t, a, s, o)
        }
        debug_assert!(avx2());
        // SAFETY: `run` is safe code compiled with AVX2 enabled; callers reach here only
        // after `avx2()` found the feature on this CPU (`lookup_with`'s `avx2` flag).
        unsafe { run(table, acc, shift, out) }
    }
}

/// Other targets: the portable build only.
#[cfg(not(target_arch = "x86_64"))]
mod simd {
    pub fn avx2() -> bool {
        false
    }

    pub fn lookup_avx2<T: Copy, O: From<T>>(table: &[T], acc: &[u32], shift: u32, out: &mut [O]) {
        super::lookup_loop(table, acc, shift, out)
    }
}

/// [`lookup_block`] over the whole frame, one equal chunk per rayon thread (at least
/// [`BLOCK`] pixels), the first on the calling thread ([`run_parts`]); each output depends
/// on its own input only, so the result is the same on any thread count.
pub fn lookup<T: Copy + Sync, O: From<T> + Default + Send>(
    table: &[T],
    acc: &[u32],
    shift: u32,
    out: &mut [O],
) {
    let n = out.len().min(acc.len());
    let chunk = n.div_ceil(rayon::current_num_threads().max(1)).max(BLOCK);
    if chunk >= n {
        return lookup_block(table, acc, shift, out);
    }
    let avx2 = simd::avx2();
    let parts: Vec<_> = out.chunks_mut(chunk).zip(acc.chunks(chunk)).collect();
    run_parts(parts, |(o, a)| lookup_with(table, a, shift, o, avx2));
}
