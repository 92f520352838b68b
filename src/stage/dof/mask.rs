//! The Gaussian mask of a sigma (docs/reference.md §2a eq. 4): its half-size, float and
//! quantised 1-D taps, and the difference degree of masks and images (docs/reference.md §3
//! eq. 6).

/// Half-size M of the mask for |sigma| (pixels): `ceil(sqrt(-ln k) |sigma|)`.
pub fn half_size(sigma: f64, k: f64) -> usize {
    ((-k.ln()).sqrt() * sigma.abs() - 1e-9).ceil().max(0.0) as usize
}

/// Normalised 1-D taps `exp(-x^2 / sigma^2)`, `|x| <= M` (sum 1); `[1]` for sigma = 0.
pub fn taps_f64(sigma: f64, k: f64) -> Vec<f64> {
    let m = half_size(sigma, k);
    if m == 0 {
        return vec![1.0];
    }
    let s2 = sigma * sigma;
    let t: Vec<f64> = (-(m as i64)..=m as i64)
        .map(|x| (-(x * x) as f64 / s2).exp())
        .collect();
    let sum: f64 = t.iter().sum();
    t.into_iter().map(|v| v / sum).collect()
}

/// Taps quantised to `f` fraction bits with their sum exactly `2^f` (largest remainder,
/// ties to the centre-most tap: symmetric masks stay symmetric when the leftover is even).
pub fn taps_fixed(tf: &[f64], f: u32) -> Vec<u64> {
    let one = (1u64 << f) as f64;
    let mut fl: Vec<(usize, u64, f64)> = tf
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            let s = v * one;
            (i, s.floor() as u64, s - s.floor())
        })
        .collect();
    let sum: u64 = fl.iter().map(|x| x.1).sum();
    let mut left = (1u64 << f).saturating_sub(sum);
    let c = tf.len() / 2;
    let mut order: Vec<usize> = (0..fl.len()).collect();
    order.sort_by(|&a, &b| {
        fl[b]
            .2
            .partial_cmp(&fl[a].2)
            .unwrap_or(std::cmp::Ordering::Equal)
            .then(a.abs_diff(c).cmp(&b.abs_diff(c)))
            .then(a.cmp(&b))
    });
    for i in order {
        if left == 0 {
            break;
        }
        fl[i].1 += 1;
        left -= 1;
    }
    fl.into_iter().map(|x| x.1).collect()
}

/// Difference degree of the 2-D separable masks of two sigmas (docs/reference.md §3, eq. 6).
pub fn mask_difference(s1: f64, s2: f64, k: f64) -> f64 {
    taps_difference(&taps_f64(s1, k), &taps_f64(s2, k))
}

/// [`mask_difference`] remembering its results and taps: the layer plan asks for the same
/// few sigmas (sigma codes are quantised) once per depth code pair. Bit-identical.
#[derive(Default)]
pub(super) struct MaskDifferences {
    taps: std::collections::HashMap<u64, std::rc::Rc<Vec<f64>>>,
    diff: std::collections::HashMap<(u64, u64), f64>,
}

impl MaskDifferences {
    /// `mask_difference(s1, s2, k)` (`k` must be the same on every call).
    pub(super) fn get(&mut self, s1: f64, s2: f64, k: f64) -> f64 {
        let key = (s1.to_bits(), s2.to_bits());
        if let Some(&d) = self.diff.get(&key) {
            return d;
        }
        let mut taps = |s: f64| {
            self.taps
                .entry(s.to_bits())
                .or_insert_with(|| std::rc::Rc::new(taps_f64(s, k)))
                .clone()
        };
        let (a, b) = (taps(s1), taps(s2));
        let d = taps_difference(&a, &b);
        self.diff.insert(key, d);
        d
    }
}

/// Difference degree of the 2-D separable masks with 1-D taps `a` and `b`.
fn taps_difference(a: &[f64], b: &[f64]) -> f64 {
    let m = a.len().max(b.len()) / 2;
    let get = |t: &[f64], i: usize| {
        let h = t.len() / 2;
        let off = i as i64 - m as i64 + h as i64;
        if off < 0 || off >= t.len() as i64 {
            0.0
        } else {
            t[off as usize]
        }
    };
    let n = 2 * m + 1;
    // Both masks' taps on the common support, zero outside their own (read once, not per
    // product; the same sum in the same order).
    let (pa, pb): (Vec<f64>, Vec<f64>) = (0..n).map(|i| (get(a, i), get(b, i))).unzip();
    let mut d = 0.0;
    for (&ay, &by) in pa.iter().zip(&pb) {
        for (&ax, &bx) in pa.iter().zip(&pb) {
            d += (ay * ax - by * bx).abs();
        }
    }
    d / 2.0
}

/// Difference degree of two images, `sum|A - B| / sum(|A| + |B|)`.
pub fn difference_degree(a: &[f64], b: &[f64]) -> f64 {
    let (mut d, mut s) = (0.0, 0.0);
    for (&x, &y) in a.iter().zip(b) {
        d += (x - y).abs();
        s += x.abs() + y.abs();
    }
    if s == 0.0 { 0.0 } else { d / s }
}
