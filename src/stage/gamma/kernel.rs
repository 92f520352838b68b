//! The LUT lookup over slices, the one kernel every gamma LUT (plain, extended, reduced, log)
//! runs: `out[i] = table[min(acc[i] >> shift, len - 1)]`, in blocks of [`BLOCK`] pixels
//! (rayon), the clamp hoisted so the loop has no bounds check.

use rayon::prelude::*;

/// Pixels per parallel block of [`lookup`].
pub const BLOCK: usize = 1 << 16;

/// One block of [`lookup`], serial: `out[i] = table[min(acc[i] >> shift, table.len() - 1)]`
/// for `i < min(acc.len(), out.len())`. An empty table writes the default value; a shift of
/// 32 or more addresses entry 0.
#[inline]
pub fn lookup_block<T: Copy, O: From<T> + Default>(
    table: &[T],
    acc: &[u32],
    shift: u32,
    out: &mut [O],
) {
    let Some(last) = table.len().checked_sub(1) else {
        out.iter_mut().for_each(|o| *o = O::default());
        return;
    };
    if shift >= 32 {
        let v = table[0];
        out.iter_mut().zip(acc).for_each(|(o, _)| *o = O::from(v));
        return;
    }
    for (o, &a) in out.iter_mut().zip(acc) {
        *o = O::from(table[((a >> shift) as usize).min(last)]);
    }
}

/// [`lookup_block`] over the whole frame, blocks in parallel (each output depends on its own
/// input only, so the result is the same on any thread count).
pub fn lookup<T: Copy + Sync, O: From<T> + Default + Send>(
    table: &[T],
    acc: &[u32],
    shift: u32,
    out: &mut [O],
) {
    out.par_chunks_mut(BLOCK)
        .zip(acc.par_chunks(BLOCK))
        .for_each(|(o, a)| lookup_block(table, a, shift, o));
}
