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

/// Whether the CPU runs AVX2 (the tap loops then multiply four words at a time; the same
/// integers either way).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(super) fn has_avx2() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
}

/// `avx2_or_portable!([generics] (arg: Type, ...) -> Ret, body)` in a function of a module
/// beside this one: returns `body` (a call of an `inline(always)` function of the arguments
/// in scope) compiled with AVX2 where the CPU has it, else evaluates it as portable code.
/// The body is not a closure: a closure is not reliably inlined into the `#[target_feature]`
/// function, which then runs without AVX2.
macro_rules! avx2_or_portable {
    ([$($g:tt)*] ($($a:ident: $t:ty),* $(,)?) -> $r:ty, $body:expr) => {{
        #[target_feature(enable = "avx2")]
        #[cfg(target_arch = "x86_64")]
        fn avx2<$($g)*>($($a: $t),*) -> $r {
            $body
        }
        #[cfg(target_arch = "x86_64")]
        if super::fast::has_avx2() {
            // SAFETY: `avx2` is safe code compiled with AVX2, called only where the CPU has it.
            return unsafe { avx2($($a),*) };
        }
        $body
    }};
}
pub(super) use avx2_or_portable;

/// Whether sums of `max * 2^f` fit a `u64` (the taps sum to `2^f`).
pub(super) fn fits_u64(max: u128, f: u32) -> bool {
    max.checked_shl(f)
        .is_some_and(|b| b >> f == max && b < 1u128 << 64)
}

/// The horizontal pass of one row (`bw` samples of the colour, alpha and behind planes,
/// taps `c`) at position `x`: the exact sums (before saturation).
#[inline(always)]
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

/// The horizontal sums of the positions `xa..xb` of one row (the planes and taps as in
/// [`hsum`]) into `o` (indexed by position); with `zero` (no share in any row window of the
/// run) only the behind sums, the others being zero. Positions whose taps all lie in the row
/// go [`mac_run`]'s way, the `M` either end [`hsum`]'s.
#[inline(always)]
pub(super) fn hsum_run<W: Word, P: Plane>(
    c: &[P],
    (rx, ra, rd): (&[P], &[P], &[P]),
    (xa, xb): (usize, usize),
    zero: bool,
    (ox, oa, od): (&mut [W], &mut [W], &mut [W]),
) {
    let m = c.len() / 2;
    let bw = rx.len();
    // Interior positions `[ia, ib)`: `m <= x < bw - m`.
    let ia = xa.max(m).min(xb);
    let ib = xb.min(bw.saturating_sub(m)).max(ia);
    for x in (xa..ia).chain(ib..xb) {
        let (sx, sa, sd) = hsum::<W, P>(c, (rx, ra, rd), x);
        (ox[x], oa[x], od[x]) = (W::of(sx), W::of(sa), W::of(sd));
    }
    if ia == ib {
        return;
    }
    let off = |t: usize| ia + t - m;
    let (ox, oa, od) = (&mut ox[ia..ib], &mut oa[ia..ib], &mut od[ia..ib]);
    if zero {
        ox.fill(W::default());
        oa.fill(W::default());
        mac_run(c, 0..c.len(), [rd], off, [od]);
    } else {
        mac_run(c, 0..c.len(), [rx, ra, rd], off, [ox, oa, od]);
    }
}

/// The horizontal sums of the positions `xa..xb` of one row whose window is uniform and
/// full: each plane's sample times its column's in-box tap sum `bs` (the taps read one value
/// throughout).
#[inline(always)]
pub(super) fn scale_run<W: Word, P: Plane>(
    (rx, ra, rd): (&[P], &[P], &[P]),
    bs: &[u64],
    (xa, xb): (usize, usize),
    (ox, oa, od): (&mut [W], &mut [W], &mut [W]),
) {
    for x in xa..xb {
        let b = W::of(u128::from(bs[x]));
        let v = |p: &[P]| W::of(u128::from(p[x].get())) * b;
        (ox[x], oa[x], od[x]) = (v(rx), v(ra), v(rd));
    }
}

/// The vertical pass of output row `y` of a `bw x bh` box over the columns `xa..xb`: the
/// exact colour, alpha and behind sums into `o` (indexed by column).
#[inline(always)]
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
    let off = |t: usize| (y + t - m) * bw + xa;
    let out = [&mut ox[xa..xb], &mut oa[xa..xb], &mut od[xa..xb]];
    mac_run(c, t0..t1, [hx, ha, hd], off, out);
}

/// `out[k][j] = sum of c[t] src[k][off(t) + j]` over the taps `t` in `taps`, for every
/// output `j` (the `out` slices have one length): outputs in groups of eight, every tap into
/// registers, one store per output.
#[inline(always)]
fn mac_run<W: Word, P: Plane, const N: usize>(
    c: &[P],
    taps: std::ops::Range<usize>,
    src: [&[P]; N],
    off: impl Fn(usize) -> usize,
    mut out: [&mut [W]; N],
) {
    const L: usize = 8;
    let n = out[0].len();
    let mut j = 0;
    while j + L <= n {
        let mut s = [[W::default(); L]; N];
        for t in taps.clone() {
            let cw = W::of(c[t].get() as u128);
            let o = off(t) + j;
            for (sk, src) in s.iter_mut().zip(&src) {
                let r: &[P; L] = src[o..o + L].try_into().expect("L outputs");
                for (a, v) in sk.iter_mut().zip(r) {
                    *a += cw * W::of(v.get() as u128);
                }
            }
        }
        for (o, sk) in out.iter_mut().zip(&s) {
            o[j..j + L].copy_from_slice(sk);
        }
        j += L;
    }
    for o in out.iter_mut() {
        o[j..].fill(W::default());
    }
    for t in taps {
        let cw = W::of(c[t].get() as u128);
        let o = off(t);
        for (out, src) in out.iter_mut().zip(&src) {
            for (a, v) in out[j..].iter_mut().zip(&src[o + j..o + n]) {
                *a += cw * W::of(v.get() as u128);
            }
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
