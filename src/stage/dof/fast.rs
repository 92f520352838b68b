//! The emulator's fast tap passes of a fixed layer, bit-identical to the per-sample
//! [`row_mac`](super::row_mac) passes of [`layered_fixed`](super::layered_fixed) with
//! `Exec::Full`: the horizontal sum of a uniform row window is `x * W_x` (no MACs), the
//! vertical pass accumulates whole rows (contiguous reads) and only over the pixels whose
//! window is not uniform, in `u64` whenever the exact sums provably fit. The work counts are
//! the caller's (they model the hardware, not this code).

use super::fixed::MacOut;

/// A tap-sum word: `u64` when every exact sum fits it, `u128` otherwise.
pub(super) trait Word:
    Copy + Default + std::ops::AddAssign + std::ops::Mul<Output = Self>
{
    fn of(v: u128) -> Self;
    fn wide(self) -> u128;
}

impl Word for u64 {
    #[inline(always)]
    fn of(v: u128) -> Self {
        v as u64
    }
    #[inline(always)]
    fn wide(self) -> u128 {
        self as u128
    }
}

impl Word for u128 {
    #[inline(always)]
    fn of(v: u128) -> Self {
        v
    }
    #[inline(always)]
    fn wide(self) -> u128 {
        self
    }
}

/// A plane word of the emulator: `u32` where every value of the run provably fits (the tap
/// multiplies are then 32 x 32 -> 64 bits, which vectorise), `u64` otherwise. The hardware's
/// widths are the configured ones either way.
pub(super) trait Plane: Copy + Default + PartialEq + Send + Sync + 'static {
    fn get(self) -> u64;
    /// `v`, which the caller has proven to fit.
    fn put(v: u64) -> Self;
    /// The planes as `u64` words (the HDL observer's), when they are.
    fn as_u64(s: &[Self]) -> Option<&[u64]>;
}

impl Plane for u32 {
    #[inline(always)]
    fn get(self) -> u64 {
        u64::from(self)
    }
    #[inline(always)]
    fn put(v: u64) -> Self {
        v as u32
    }
    fn as_u64(_: &[Self]) -> Option<&[u64]> {
        None
    }
}

impl Plane for u64 {
    #[inline(always)]
    fn get(self) -> u64 {
        self
    }
    #[inline(always)]
    fn put(v: u64) -> Self {
        v
    }
    fn as_u64(s: &[Self]) -> Option<&[u64]> {
        Some(s)
    }
}

/// Whether sums of `max * 2^f` fit a `u64` (the taps sum to `2^f`).
pub(super) fn fits_u64(max: u128, f: u32) -> bool {
    max.checked_shl(f)
        .is_some_and(|b| b >> f == max && b < 1u128 << 64)
}

/// The horizontal pass of one row (`bw` samples of the colour, alpha and behind planes,
/// taps `c`) at position `x`: the exact sums (before saturation).
#[inline]
pub(super) fn hsum<W: Word, P: Plane>(
    c: &[P],
    (rx, ra, rd): (&[P], &[P], &[P]),
    x: usize,
) -> (u128, u128, u128) {
    let m = c.len() / 2;
    let bw = rx.len();
    let t0 = m.saturating_sub(x);
    let t1 = c.len().min((bw + m).saturating_sub(x));
    let (mut sx, mut sa, mut sd) = (W::default(), W::default(), W::default());
    let base = x + t0 - m;
    let n = t1.saturating_sub(t0);
    for (((&cv, &vx), &va), &vd) in c[t0..t0 + n]
        .iter()
        .zip(&rx[base..base + n])
        .zip(&ra[base..base + n])
        .zip(&rd[base..base + n])
    {
        let cw = W::of(cv.get() as u128);
        sx += cw * W::of(vx.get() as u128);
        sa += cw * W::of(va.get() as u128);
        sd += cw * W::of(vd.get() as u128);
    }
    (sx.wide(), sa.wide(), sd.wide())
}

/// [`hsum`] of one plane (`r`, taps `c`) at position `x`.
#[inline]
pub(super) fn hsum1<W: Word, P: Plane>(c: &[P], r: &[P], x: usize) -> u128 {
    let m = c.len() / 2;
    let t0 = m.saturating_sub(x);
    let t1 = c.len().min((r.len() + m).saturating_sub(x));
    let n = t1.saturating_sub(t0);
    let base = x + t0 - m;
    let mut s = W::default();
    for (&cv, &v) in c[t0..t0 + n].iter().zip(&r[base..base + n]) {
        s += W::of(cv.get() as u128) * W::of(v.get() as u128);
    }
    s.wide()
}

/// The vertical pass of output row `y` of a `bw x bh` box over the columns `xa..xb`: the
/// exact colour, alpha and behind sums into `o` (indexed by column).
#[inline]
pub(super) fn vsum_row<W: Word, P: Plane>(
    c: &[P],
    (hx, ha, hd): (&[P], &[P], &[P]),
    (bw, bh): (usize, usize),
    y: usize,
    (xa, xb): (usize, usize),
    (ox, oa, od): (&mut [W], &mut [W], &mut [W]),
) {
    let m = c.len() / 2;
    let t0 = m.saturating_sub(y);
    let t1 = c.len().min((bh + m).saturating_sub(y));
    // Columns in groups of `L`: every tap into registers, one store per column.
    const L: usize = 8;
    let mut x = xa;
    while x + L <= xb {
        let (mut sx, mut sa, mut sd) = ([W::default(); L], [W::default(); L], [W::default(); L]);
        for (t, &cv) in c.iter().enumerate().take(t1).skip(t0) {
            let row = (y + t - m) * bw + x;
            let cw = W::of(cv.get() as u128);
            let (hr, ar, dr): (&[P; L], &[P; L], &[P; L]) = (
                hx[row..row + L].try_into().expect("L columns"),
                ha[row..row + L].try_into().expect("L columns"),
                hd[row..row + L].try_into().expect("L columns"),
            );
            for j in 0..L {
                sx[j] += cw * W::of(hr[j].get() as u128);
                sa[j] += cw * W::of(ar[j].get() as u128);
                sd[j] += cw * W::of(dr[j].get() as u128);
            }
        }
        ox[x..x + L].copy_from_slice(&sx);
        oa[x..x + L].copy_from_slice(&sa);
        od[x..x + L].copy_from_slice(&sd);
        x += L;
    }
    let xa = x;
    let (ox, oa, od) = (&mut ox[xa..xb], &mut oa[xa..xb], &mut od[xa..xb]);
    ox.fill(W::default());
    oa.fill(W::default());
    od.fill(W::default());
    for (t, &cv) in c.iter().enumerate().take(t1).skip(t0) {
        let row = (y + t - m) * bw;
        let cw = W::of(cv.get() as u128);
        let r = row + xa..row + xb;
        for (((o, &v), (p, &a)), (q, &d)) in ox
            .iter_mut()
            .zip(&hx[r.clone()])
            .zip(oa.iter_mut().zip(&ha[r.clone()]))
            .zip(od.iter_mut().zip(&hd[r]))
        {
            *o += cw * W::of(v.get() as u128);
            *p += cw * W::of(a.get() as u128);
            *q += cw * W::of(d.get() as u128);
        }
    }
}

/// A saturated [`MacOut`] of exact sums.
#[inline(always)]
pub(super) fn mac_out((sx, sa, sd): (u128, u128, u128), max: u128) -> MacOut {
    MacOut {
        x: sx.min(max),
        a: sa,
        d: sd,
        overflow: sx > max,
    }
}
