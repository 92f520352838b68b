//! The small image's two steps, shared by the fixed model and the float reference: the box
//! sum of every `factor x factor` block and one pass of the separable Gaussian, both with
//! clamped coordinates (edge pixels repeat, as a texture with clamp addressing). The caller
//! rounds (fixed) or scales (float) each output.

use super::plan::DownPlan;
use std::ops::AddAssign;

/// The sum of every `factor x factor` block of `value` (`width x height`), coordinates
/// clamped to the frame; `emit(small index, sum)` in raster order.
pub(super) fn box_sums<T: Copy, S: From<T> + AddAssign + Default, E>(
    value: &[T],
    plan: &DownPlan,
    mut emit: impl FnMut(usize, S) -> Result<(), E>,
) -> Result<(), E> {
    let (w, h, f) = (plan.width, plan.height, plan.factor);
    for sy in 0..plan.small_height {
        for sx in 0..plan.small_width {
            let mut sum = S::default();
            for dy in 0..f {
                let row = &value[(sy * f + dy).min(h - 1) * w..];
                for dx in 0..f {
                    sum += S::from(row[(sx * f + dx).min(w - 1)]);
                }
            }
            emit(sy * plan.small_width + sx, sum)?;
        }
    }
    Ok(())
}

/// One pass of the 1-D taps `coef` (centre `coef.len() / 2`) along the rows (`horizontal`)
/// or the columns of `src` (`sw x sh`), coordinates clamped: `emit(index, sum of
/// mul(tap, sample))`.
#[allow(clippy::too_many_arguments)]
pub(super) fn gauss_pass<T: Copy, C: Copy, S: AddAssign + Default, E>(
    src: &[T],
    sw: usize,
    sh: usize,
    coef: &[C],
    horizontal: bool,
    mul: impl Fn(C, T) -> S,
    mut emit: impl FnMut(usize, S) -> Result<(), E>,
) -> Result<(), E> {
    let m = (coef.len() / 2) as i64;
    let (n, lines) = if horizontal { (sw, sh) } else { (sh, sw) };
    let at = |line: usize, pos: usize| {
        if horizontal {
            line * sw + pos
        } else {
            pos * sw + line
        }
    };
    for line in 0..lines {
        for pos in 0..n {
            let mut s = S::default();
            for (t, &c) in coef.iter().enumerate() {
                let q = (pos as i64 + t as i64 - m).clamp(0, n as i64 - 1) as usize;
                s += mul(c, src[at(line, q)]);
            }
            emit(at(line, pos), s)?;
        }
    }
    Ok(())
}
