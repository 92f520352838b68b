//! Floyd-Steinberg error diffusion: the fixed-point model (error format, rounded shares,
//! saturating error accumulation) and its float reference with exact shares.

use crate::fixed::{QFormat, Quant, SignalStats, round_shift};

/// Floyd-Steinberg parameters (fixed).
#[derive(Clone, Copy, Debug)]
pub struct FsParams {
    /// Fraction bits of the input.
    pub s: u32,
    /// Largest output code.
    pub omax: u32,
    /// Error format (output LSBs).
    pub error: QFormat,
    /// Reverse odd rows.
    pub serpentine: bool,
}

/// Floyd-Steinberg in fixed point (see the [`dither`](super) module docs); returns the error-signal stats.
pub fn floyd_steinberg(
    x: &[u32],
    width: u32,
    height: u32,
    p: &FsParams,
    out: &mut [u32],
) -> SignalStats {
    let mut st = SignalStats::new("dither.error", p.error);
    let (w, fe) = (width as usize, p.error.frac_bits);
    let up = fe - p.s;
    let (lo, hi) = (p.error.min_code(), p.error.max_code());
    let mut cur = vec![0i64; w + 2];
    let mut next = vec![0i64; w + 2];
    let mut overflows = 0u64;
    // The residuals' range, in locals (recorded once at the end, not per value).
    let (mut rmin, mut rmax) = (i64::MAX, i64::MIN);
    let mut add = |slot: &mut i64, v: i64, inside: bool| {
        let s = *slot + v;
        if inside && (s < lo || s > hi) {
            overflows += 1;
        }
        *slot = s.clamp(lo, hi);
    };
    for y in 0..height as usize {
        let rev = p.serpentine && y % 2 == 1;
        for k in 0..w {
            let xi = if rev { w - 1 - k } else { k };
            let v = ((x[y * w + xi] as i64) << up) + cur[xi + 1];
            let q = ((v + (1i64 << (fe - 1))) >> fe).clamp(0, p.omax as i64);
            out[y * w + xi] = q as u32;
            let r = v - (q << fe);
            rmin = rmin.min(r);
            rmax = rmax.max(r);
            let share = |m: i64| round_shift((m * r) as i128, 4, Quant::Rnd) as i64;
            let (e7, e3, e5) = (share(7), share(3), share(5));
            let e1 = r - e7 - e3 - e5;
            // Ahead, behind-below, below, ahead-below; slots 0 and w+1 are outside the image.
            let (ahead, behind) = if rev { (xi, xi + 2) } else { (xi + 2, xi) };
            add(&mut cur[ahead], e7, (1..=w).contains(&ahead));
            add(&mut next[behind], e3, (1..=w).contains(&behind));
            add(&mut next[xi + 1], e5, true);
            add(&mut next[ahead], e1, (1..=w).contains(&ahead));
        }
        std::mem::swap(&mut cur, &mut next);
        next.iter_mut().for_each(|e| *e = 0);
    }
    st.record_range(
        (w * height as usize) as u64,
        i128::from(rmin),
        i128::from(rmax),
    );
    st.add_overflows(overflows);
    st
}

/// Float reference of Floyd-Steinberg on real values (output LSBs), exact weights.
pub fn floyd_steinberg_f64(
    v: &[f64],
    width: u32,
    height: u32,
    omax: u32,
    serpentine: bool,
) -> Vec<u32> {
    let w = width as usize;
    let mut out = vec![0u32; v.len()];
    let mut cur = vec![0f64; w + 2];
    let mut next = vec![0f64; w + 2];
    for y in 0..height as usize {
        let rev = serpentine && y % 2 == 1;
        for k in 0..w {
            let xi = if rev { w - 1 - k } else { k };
            let a = v[y * w + xi] + cur[xi + 1];
            let q = (a + 0.5).floor().clamp(0.0, omax as f64);
            out[y * w + xi] = q as u32;
            let r = a - q;
            let (ahead, behind) = if rev { (xi, xi + 2) } else { (xi + 2, xi) };
            cur[ahead] += r * 7.0 / 16.0;
            next[behind] += r * 3.0 / 16.0;
            next[xi + 1] += r * 5.0 / 16.0;
            next[ahead] += r / 16.0;
        }
        std::mem::swap(&mut cur, &mut next);
        next.iter_mut().for_each(|e| *e = 0.0);
    }
    out
}
