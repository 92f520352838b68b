//! The pixel loop of one span of a pixel row (the pixels of one tile column): the block ids,
//! each pixel's window sums ([`WindowSums::sum_nb`]), their rounding and frame adds, and the
//! depth and coverage of the pixel's own samples.
//!
//! The loop is compiled per sample count `n`, filter base and sum [`Word`], and a second
//! time with AVX2 enabled, chosen at run time when the CPU has it (the binary still runs
//! on any x86-64): with the window's size a constant the compiler vectorises the window's
//! dot products, and AVX2 adds 8-lane 32-bit multiplies. Every build computes the same
//! codes and statistics (`tests/accumulate.rs` compares them with the straightforward
//! model).

use super::fixed::{AccParams, FragMath, RowOut};
use super::stats::ProductStats;
use super::window::{BlockIds, WindowSums, Word};
use crate::error::Result;
use crate::stage::visibility::{BACKGROUND, Samples};

/// One span: the pixels `xa..xb` of the pixel row whose windows start at sample row `r0`
/// (buffer rows), in tile column `tc` (binned runs).
pub(super) struct Span<'a> {
    pub s: &'a Samples,
    pub p: &'a AccParams,
    pub math: &'a FragMath<'a>,
    pub r0: usize,
    pub xa: u32,
    pub xb: u32,
    pub tc: Option<usize>,
}

/// Where a span's pixels go: its slices of the frame's rows.
pub(super) struct Dst<'a> {
    pub acc: &'a mut [u32],
    pub depth: &'a mut [u32],
    pub cov: &'a mut [u16],
}

/// The scratch a task reuses for its rows' spans.
pub(super) struct Scratch {
    pub win: WindowSums,
    /// Per tile column (one slot without tiles): its span's block ids, kept for the same
    /// span on the next row.
    pub ids: Vec<BlockIds>,
    pub stats: ProductStats,
    /// Per sample column of a span: the nearest covered depth and the covered count of
    /// its pixels' own samples.
    pub own: (Vec<u32>, Vec<u32>),
}

/// How the window sums are computed: in `u32` (every sum provably fits) or `u64`, and in
/// the AVX2 build or the portable one; the results are the same.
#[derive(Clone, Copy, Debug)]
pub(super) struct Build {
    pub narrow: bool,
    pub avx2: bool,
}

/// Whether the CPU has AVX2 (the standard library caches the answer).
pub(super) fn has_avx2() -> bool {
    simd::avx2()
}

/// Computes the span's pixels into `out` (pushed in order).
pub(super) fn run(sp: &Span, sc: &mut Scratch, dst: Dst, out: &mut RowOut, b: Build) -> Result<()> {
    // A signed kernel's sums are read back as signed from the `u64` word only.
    let narrow = b.narrow && !sp.p.kernel.signed();
    macro_rules! go {
        ($n:literal, $b:literal) => {
            if narrow {
                build::<$n, $b, u32>(sp, sc, dst, out, b.avx2)
            } else {
                build::<$n, $b, u64>(sp, sc, dst, out, b.avx2)
            }
        };
    }
    let k = &sp.p.kernel;
    match (k.n, k.size / k.n as usize) {
        (1, 1) => go!(1, 1),
        (1, 2) => go!(1, 2),
        (1, 3) => go!(1, 3),
        (1, _) => go!(1, 4),
        (2, 1) => go!(2, 1),
        (2, 2) => go!(2, 2),
        (2, 3) => go!(2, 3),
        (2, _) => go!(2, 4),
        (4, 1) => go!(4, 1),
        (4, 2) => go!(4, 2),
        (4, 3) => go!(4, 3),
        (4, _) => go!(4, 4),
        (_, 1) => go!(8, 1),
        (_, 2) => go!(8, 2),
        (_, 3) => go!(8, 3),
        _ => go!(8, 4),
    }
}

#[inline(always)]
fn build<const N: usize, const B: usize, W: Word>(
    sp: &Span,
    sc: &mut Scratch,
    dst: Dst,
    out: &mut RowOut,
    avx2: bool,
) -> Result<()> {
    if avx2 {
        simd::pixels_avx2::<N, B, W>(sp, sc, dst, out)
    } else {
        pixels::<N, B, W>(sp, sc, dst, out)
    }
}

/// The loop every build compiles: `n = N`, windows of `B x B` blocks, sums in `W`.
#[inline(always)]
fn pixels<const N: usize, const B: usize, W: Word>(
    sp: &Span,
    sc: &mut Scratch,
    dst: Dst,
    out: &mut RowOut,
) -> Result<()> {
    let (s, p) = (sp.s, sp.p);
    let k = &p.kernel;
    let sw = s.reg.width();
    let npx = (sp.xb - sp.xa) as usize;
    let first = sp.r0 * sw + (sp.xa as i64 * N as i64 - k.off - s.reg.c0) as usize;
    let slot = sp.tc.unwrap_or(0);
    if sc.ids.len() <= slot {
        sc.ids.resize_with(slot + 1, BlockIds::default);
    }
    let ids = &mut sc.ids[slot];
    ids.find::<N, B>(&s.prim, first, sw, npx);
    let cols = npx + B - 1;
    let macs = (N * B * N * B) as u64;
    for gx in 0..npx {
        let base = first + gx * N;
        sc.win
            .sum_nb::<N, B, W>(&s.prim, &s.i, &k.w, base, sw, &ids.ids, gx, cols);
        let nf = sc.win.frags.len() as u64;
        out.work.pixels += 1;
        out.work.macs += macs;
        out.work.fragments += nf;
        if let Some(c) = sp.tc {
            out.tile_rmw[c] += nf;
        }
        dst.acc[gx] = sp.math.pixel(&sc.win.frags, &mut sc.stats, &mut out.work)?;
    }
    // Depth and coverage of each pixel's own `N x N` samples: the span's own blocks lie
    // side by side in `N` sample rows. Each sample row is folded into per-column minima
    // and counts (a straight pass over `npx * N` samples), then each pixel's `N` columns
    // are reduced.
    let own = first + k.off as usize * sw + k.off as usize;
    own_depth_coverage::<N>(&s.prim, &s.z, own, sw, npx, &mut sc.own, dst);
    Ok(())
}

/// The nearest depth and covered-sample count of each of `npx` pixels whose own `N x N`
/// samples lie side by side from buffer index `own` (row stride `sw`), into `dst`;
/// `cols` is scratch of per-column `(depth, count)` partials.
#[inline(always)]
fn own_depth_coverage<const N: usize>(
    prim: &[u32],
    z: &[u32],
    own: usize,
    sw: usize,
    npx: usize,
    cols: &mut (Vec<u32>, Vec<u32>),
    dst: Dst,
) {
    let len = npx * N;
    let (zc, cc) = cols;
    zc.clear();
    zc.resize(len, u32::MAX);
    cc.clear();
    cc.resize(len, 0);
    for sy in 0..N {
        let row = own + sy * sw;
        let (ps, zs) = (&prim[row..row + len], &z[row..row + len]);
        for (((zm, c), &p), &zv) in zc.iter_mut().zip(cc.iter_mut()).zip(ps).zip(zs) {
            let covered = p != BACKGROUND;
            *c += u32::from(covered);
            *zm = (*zm).min(if covered { zv } else { u32::MAX });
        }
    }
    let px = dst.depth.iter_mut().zip(dst.cov.iter_mut());
    for ((d, c), (zb, cb)) in px.zip(zc.chunks_exact(N).zip(cc.chunks_exact(N))) {
        let zb: &[u32; N] = zb.try_into().expect("N columns");
        let cb: &[u32; N] = cb.try_into().expect("N columns");
        *d = zb.iter().fold(u32::MAX, |a, &b| a.min(b));
        *c = cb.iter().sum::<u32>() as u16;
    }
}

/// The run-time AVX2 build of [`pixels`].
#[cfg(target_arch = "x86_64")]
mod simd {
    use super::*;

    pub fn avx2() -> bool {
        std::arch::is_x86_feature_detected!("avx2")
    }

    /// [`super::pixels`] compiled with AVX2; call only when [`avx2`] holds.
    #[inline]
    pub fn pixels_avx2<const N: usize, const B: usize, W: Word>(
        sp: &Span,
        sc: &mut Scratch,
        dst: Dst,
        out: &mut RowOut,
    ) -> Result<()> {
        #[target_feature(enable = "avx2")]
        fn run<const N: usize, const B: usize, W: Word>(
            sp: &Span,
            sc: &mut Scratch,
            dst: Dst,
            out: &mut RowOut,
        ) -> Result<()> {
            super::pixels::<N, B, W>(sp, sc, dst, out)
        }
        debug_assert!(avx2());
        // SAFETY: `run` is safe code compiled with AVX2 enabled; callers pass `avx2 = true`
        // only after `avx2()` found the feature on this CPU (`Build::avx2`).
        unsafe { run::<N, B, W>(sp, sc, dst, out) }
    }
}

/// Other targets: the portable build only.
#[cfg(not(target_arch = "x86_64"))]
mod simd {
    use super::*;

    pub fn avx2() -> bool {
        false
    }

    pub fn pixels_avx2<const N: usize, const B: usize, W: Word>(
        sp: &Span,
        sc: &mut Scratch,
        dst: Dst,
        out: &mut RowOut,
    ) -> Result<()> {
        super::pixels::<N, B, W>(sp, sc, dst, out)
    }
}

#[cfg(test)]
mod tests {
    use super::Build;
    use crate::config::{FilterKind, HwConfig};
    use crate::stage::Region;
    use crate::stage::accumulate::fixed::{AccParams, accumulate_build};
    use crate::stage::accumulate::{kernel, sample_region};
    use crate::stage::visibility::Samples;

    /// Every build of the window kernel (u32 and u64 sums, portable and AVX2 when the CPU
    /// has it) gives the same frame, work and statistics, for each filter and sample count,
    /// on a sample buffer of patches of one to four primitives (ids and intensities from a
    /// fixed-seed generator, some patches background).
    #[test]
    fn every_build_computes_the_same_frame() {
        let builds: Vec<Build> = [(true, false), (false, false), (true, true), (false, true)]
            .into_iter()
            .filter(|&(_, avx2)| !avx2 || super::has_avx2())
            .map(|(narrow, avx2)| Build { narrow, avx2 })
            .collect();
        let region = Region {
            x0: 3,
            y0: 2,
            x1: 45,
            y1: 30,
        };
        for (filter, n) in [
            (FilterKind::Tent, 4),
            (FilterKind::Box, 2),
            (FilterKind::Gaussian, 1),
            (FilterKind::Gaussian, 2),
            (FilterKind::Tent, 8),
            (FilterKind::CatmullRom, 4),
            (FilterKind::Mitchell, 2),
            (FilterKind::CubicBspline, 1),
        ] {
            let mut hw = HwConfig::default_config();
            hw.accumulate.filter = filter;
            hw.raster.samples = n;
            let k = kernel(&hw);
            let mut s = Samples::new(sample_region(&region, &k), 0);
            let mut x = 0x9e37_79b9_7f4a_7c15u64;
            let mut next = move || {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                x
            };
            // Patches of 3x3 samples share one primitive, so windows hold one to a few.
            let sw = s.reg.width();
            let prim = std::sync::Arc::make_mut(&mut s.prim);
            for (e, (p, i)) in prim.iter_mut().zip(s.i.iter_mut()).enumerate() {
                let (r, c) = (e / sw / 3, e % sw / 3);
                let h = (r as u64 * 7919 + c as u64 * 104_729) ^ 0x5bd1;
                *p = (h % 5) as u32;
                *i = (next() % 65_536) as u32;
            }
            for (z, &p) in std::sync::Arc::make_mut(&mut s.z)
                .iter_mut()
                .zip(s.prim.iter())
            {
                *z = if p == 0 {
                    u32::MAX
                } else {
                    (next() % 1000) as u32
                };
            }
            let p = AccParams {
                kernel: k,
                i_frac: 4,
                i_max: u32::MAX,
                frame: hw.accumulate.frame,
            };
            let run = |b: Build| {
                accumulate_build(
                    &s,
                    &region,
                    None,
                    &[],
                    &p,
                    7,
                    ((48, 32), &crate::stage::Pool::new()),
                    Some(b),
                )
                .expect("accumulates")
            };
            let first = run(builds[0]);
            assert!(
                first.1.fragments > first.1.pixels,
                "{filter:?} n={n}: mixed windows"
            );
            for &b in &builds[1..] {
                let r = run(b);
                assert_eq!(r.0, first.0, "{filter:?} n={n} {b:?}: frame");
                assert_eq!(r.1, first.1, "{filter:?} n={n} {b:?}: work");
                assert_eq!(
                    format!("{:?}", r.2),
                    format!("{:?}", first.2),
                    "{filter:?} n={n} {b:?}: statistics"
                );
            }
        }
    }
}
