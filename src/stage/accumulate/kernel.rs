//! The quantised filter kernel: exact weights, their quantisation to `weight_bits` fraction
//! bits by largest remainder (per sample group for the equal-energy filters, over the whole
//! kernel for the Gaussian), signed where the filter has negative lobes (Catmull-Rom,
//! Mitchell), and its unit tests.

use crate::config::{FilterKind, MitchellBc};
use crate::fixed::{QFormat, Quantizer};

/// A quantised filter kernel over the `size x size` samples of one pixel's window.
#[derive(Clone, Debug, PartialEq)]
pub struct Kernel {
    /// Filter.
    pub kind: FilterKind,
    /// Samples per pixel per axis.
    pub n: u32,
    /// Window size in samples per axis (`base * n`).
    pub size: usize,
    /// Offset of the window's first sample left of / above the pixel's first sample.
    pub off: i64,
    /// Weight fraction bits: the weights sum to `2^f`.
    pub f: u32,
    /// Quantised weights, row-major (negative only where the filter has negative lobes).
    pub w: Vec<i32>,
    /// Exact weights (sum 1), row-major: the float reference.
    pub wf: Vec<f64>,
    /// Sum of the positive quantised weights (`2^f` for a kernel without negative weights).
    pub pos: i64,
    /// Sum of the magnitudes of the negative quantised weights (0 without).
    pub neg: i64,
}

impl Kernel {
    /// Builds and quantises the kernel (`sigma` for the Gaussian; the Mitchell-Netravali
    /// (B, C) for `filter = "mitchell"` are [`MitchellBc::THIRD`], see [`Kernel::with_bc`]).
    pub fn new(kind: FilterKind, n: u32, f: u32, sigma: f64) -> Self {
        Self::with_bc(kind, n, f, sigma, MitchellBc::THIRD)
    }

    /// [`Kernel::new`] with the (B, C) of `filter = "mitchell"`.
    pub fn with_bc(kind: FilterKind, n: u32, f: u32, sigma: f64, bc: MitchellBc) -> Self {
        let base = kind.base();
        let cubic = kind.cubic(bc);
        let size = (base * n) as usize;
        let off = ((base - 1) * n / 2) as i64;
        let nf = n as f64;
        let profile = |j: usize| {
            let u = (j as f64 - off as f64 + 0.5) / nf - 0.5;
            match (kind, cubic) {
                (_, Some(bc)) => bc.eval(u),
                (FilterKind::Box, _) => 1.0,
                (FilterKind::Tent, _) => 1.0 - u.abs(),
                _ => (-u * u / (2.0 * sigma * sigma)).exp(),
            }
        };
        let p: Vec<f64> = (0..size).map(profile).collect();
        let total: f64 = p.iter().sum::<f64>().powi(2);
        let wf: Vec<f64> = (0..size * size)
            .map(|e| p[e / size] * p[e % size] / total)
            .collect();
        let one = 1i64 << f;
        let mut w = vec![0i32; size * size];
        if kind.equal_energy() {
            let share = one / (n as i64 * n as i64);
            for gj in 0..n as usize {
                for gi in 0..n as usize {
                    let members: Vec<usize> = (0..base as usize)
                        .flat_map(|a| {
                            (0..base as usize)
                                .map(move |b| (gj + a * n as usize) * size + gi + b * n as usize)
                        })
                        .collect();
                    largest_remainder(&members, &wf, one as f64, share, &mut w);
                }
            }
        } else {
            let all: Vec<usize> = (0..size * size).collect();
            largest_remainder(&all, &wf, one as f64, one, &mut w);
        }
        let pos = w.iter().filter(|&&v| v > 0).map(|&v| i64::from(v)).sum();
        let neg = w.iter().filter(|&&v| v < 0).map(|&v| -i64::from(v)).sum();
        Self {
            kind,
            n,
            size,
            off,
            f,
            w,
            wf,
            pos,
            neg,
        }
    }

    /// Whether some weight is negative (the multipliers and the accumulator are signed).
    pub fn signed(&self) -> bool {
        self.neg > 0
    }

    /// Sum of the quantised weights one sample gives to all pixels, for each sample phase
    /// (all equal to `2^f / n^2` for an equal-energy filter).
    pub fn group_sums(&self) -> Vec<i64> {
        let n = self.n as usize;
        let mut out = vec![0i64; n * n];
        for (e, &w) in self.w.iter().enumerate() {
            out[(e / self.size % n) * n + e % self.size % n] += i64::from(w);
        }
        out
    }

    /// Bits of a weight in the ROM: magnitude bits of the largest weight, plus a sign bit
    /// for a signed kernel (the unsigned kernels keep their `f + 1` bits: `2^f` fits).
    pub fn rom_bits(&self) -> u32 {
        if self.signed() {
            let m = self.w.iter().map(|&v| v.unsigned_abs()).max().unwrap_or(1);
            (32 - m.leading_zeros()) + 1
        } else {
            self.f + 1
        }
    }

    /// The accumulator of a pixel's signed sum, for a signed kernel (`None` otherwise: the
    /// frame memory accumulates directly). In frame LSBs every partial sum over a pixel's
    /// fragments lies in `[-(max + 1) neg / 2^f - r, (max + 1) pos / 2^f + r]`, `max` the
    /// frame's largest code (full white) and `r` one rounding per sample of the window at
    /// most; the accumulator is the narrowest signed format with the frame's fraction bits
    /// that holds it, so it cannot overflow: its sign bit and the headroom bits above the
    /// frame word are derived here, and the clamp to the frame word at the pixel's end
    /// follows the frame's overflow mode.
    pub fn accumulator(&self, frame: &Quantizer) -> Option<Quantizer> {
        if !self.signed() {
            return None;
        }
        let top = i128::from(frame.format.max_code()) + 1;
        let r = (self.size * self.size) as i128;
        let hi = (top * i128::from(self.pos)) >> self.f;
        let lo = (top * i128::from(self.neg)) >> self.f;
        let bound = (hi.max(lo) + 1 + r) as u128;
        let bits = 128 - bound.leading_zeros() + 1;
        let fr = frame.format.frac_bits;
        Some(Quantizer {
            format: QFormat::new(true, bits.saturating_sub(fr).max(1), fr),
            ..*frame
        })
    }
}

/// Rounds `wf[m] * scale` for the members to integers that sum to exactly `target`:
/// floors, then +1 to the largest fractional parts (ties to the lower index).
fn largest_remainder(members: &[usize], wf: &[f64], scale: f64, target: i64, w: &mut [i32]) {
    let mut fl: Vec<(usize, i64, f64)> = members
        .iter()
        .map(|&m| {
            let v = wf[m] * scale;
            let f = v.floor();
            (m, f as i64, v - f)
        })
        .collect();
    let sum: i64 = fl.iter().map(|x| x.1).sum();
    let mut left = (target - sum).max(0);
    fl.sort_by(|a, b| {
        b.2.partial_cmp(&a.2)
            .unwrap_or(std::cmp::Ordering::Equal)
            .then(a.0.cmp(&b.0))
    });
    for x in fl.iter_mut() {
        if left == 0 {
            break;
        }
        x.1 += 1;
        left -= 1;
    }
    for (m, v, _) in fl {
        w[m] = v as i32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernels_sum_exactly_and_equal_energy_groups_are_equal() {
        for kind in FilterKind::ALL {
            for n in [2u32, 4, 8] {
                for f in [2 * n.trailing_zeros(), 8, 10, 16] {
                    let k = Kernel::new(kind, n, f, 0.5);
                    assert_eq!(
                        k.w.iter().map(|&w| i64::from(w)).sum::<i64>(),
                        1i64 << f,
                        "{kind:?} n={n} f={f}"
                    );
                    let g = k.group_sums();
                    if kind.equal_energy() {
                        assert!(
                            g.iter().all(|&s| s == (1i64 << f) / (n * n) as i64),
                            "{kind:?} n={n} f={f}: {g:?}"
                        );
                    }
                }
            }
        }
        // The Gaussian is not equal energy: its groups differ.
        let g = Kernel::new(FilterKind::Gaussian, 4, 12, 0.5).group_sums();
        assert!(g.iter().min() != g.iter().max());
    }

    #[test]
    fn tent_4x4_weights_are_the_bed_of_nails() {
        // 1-D tent weights at the 8 sample positions: 1,3,5,7,7,5,3,1 (/32).
        let k = Kernel::new(FilterKind::Tent, 4, 10, 0.5);
        let row: Vec<i32> = (0..8).map(|i| k.w[3 * 8 + i]).collect();
        assert_eq!(row, [7, 21, 35, 49, 49, 35, 21, 7]);
    }
}
