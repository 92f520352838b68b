//! The quantised filter kernel: exact weights, their quantisation to `weight_bits` fraction
//! bits by largest remainder (per sample group for the equal-energy filters, over the whole
//! kernel for the Gaussian), and its unit tests.

use crate::config::FilterKind;

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
    /// Quantised weights, row-major.
    pub w: Vec<u32>,
    /// Exact weights (sum 1), row-major: the float reference.
    pub wf: Vec<f64>,
}

impl Kernel {
    /// Builds and quantises the kernel.
    pub fn new(kind: FilterKind, n: u32, f: u32, sigma: f64) -> Self {
        let base = kind.base();
        let size = (base * n) as usize;
        let off = ((base - 1) * n / 2) as i64;
        let nf = n as f64;
        let profile = |j: usize| {
            let u = (j as f64 - off as f64 + 0.5) / nf - 0.5;
            match kind {
                FilterKind::Box => 1.0,
                FilterKind::Tent => 1.0 - u.abs(),
                FilterKind::Gaussian => (-u * u / (2.0 * sigma * sigma)).exp(),
            }
        };
        let p: Vec<f64> = (0..size).map(profile).collect();
        let total: f64 = p.iter().sum::<f64>().powi(2);
        let wf: Vec<f64> = (0..size * size)
            .map(|e| p[e / size] * p[e % size] / total)
            .collect();
        let one = 1u64 << f;
        let mut w = vec![0u32; size * size];
        if kind.equal_energy() {
            let share = one / (n as u64 * n as u64);
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
        Self {
            kind,
            n,
            size,
            off,
            f,
            w,
            wf,
        }
    }

    /// Sum of the quantised weights one sample gives to all pixels, for each sample phase
    /// (all equal to `2^f / n^2` for an equal-energy filter).
    pub fn group_sums(&self) -> Vec<u64> {
        let n = self.n as usize;
        let mut out = vec![0u64; n * n];
        for (e, &w) in self.w.iter().enumerate() {
            out[(e / self.size % n) * n + e % self.size % n] += w as u64;
        }
        out
    }
}

/// Rounds `wf[m] * scale` for the members to integers that sum to exactly `target`:
/// floors, then +1 to the largest fractional parts (ties to the lower index).
fn largest_remainder(members: &[usize], wf: &[f64], scale: f64, target: u64, w: &mut [u32]) {
    let mut fl: Vec<(usize, u64, f64)> = members
        .iter()
        .map(|&m| {
            let v = wf[m] * scale;
            let f = v.floor();
            (m, f as u64, v - f)
        })
        .collect();
    let sum: u64 = fl.iter().map(|x| x.1).sum();
    let mut left = target.saturating_sub(sum);
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
        w[m] = v as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernels_sum_exactly_and_equal_energy_groups_are_equal() {
        for kind in [FilterKind::Box, FilterKind::Tent, FilterKind::Gaussian] {
            for n in [2u32, 4, 8] {
                for f in [2 * n.trailing_zeros(), 8, 10, 16] {
                    let k = Kernel::new(kind, n, f, 0.5);
                    assert_eq!(
                        k.w.iter().map(|&w| w as u64).sum::<u64>(),
                        1u64 << f,
                        "{kind:?} n={n} f={f}"
                    );
                    let g = k.group_sums();
                    if kind.equal_energy() {
                        assert!(
                            g.iter().all(|&s| s == (1u64 << f) / (n * n) as u64),
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
        let row: Vec<u32> = (0..8).map(|i| k.w[3 * 8 + i]).collect();
        assert_eq!(row, [7, 21, 35, 49, 49, 35, 21, 7]);
    }
}
