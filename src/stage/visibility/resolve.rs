//! The depth test of a surface's runs ([`crate::stage::raster::runs`]) into a part of the
//! sample buffer. A run whose values stay in range (checked at its two ends: the roundings
//! are monotonic, the values linear) takes a kernel with no clamp and no overflow check: a
//! grey run's has no branch per sample either, and the compiler vectorises it (AVX2 where
//! the CPU has it); a colour run's rounds the three intensities only where the test
//! passes. Every other run takes the raster's own per-sample codes. All give the same
//! tests, writes and codes, sample by sample (`tests::fast_runs_match_the_codes_one_by_one`,
//! `tests::colour_runs_match_the_codes_one_by_one`).

use super::{Part, VisWork, ZConvert};
use crate::fixed::RoundShift;
use crate::stage::raster::{Run, RunCodes};

/// Depth-tests the fragments of `runs`, runs of surface `prim` that fall in `part`
/// (their codes `codes`), into it (channel 0's intensity into `i`, channel `c + 1`'s into
/// `extra[c]`); counts the tests, writes and clamps.
pub fn resolve(
    runs: &[Run],
    (codes, bounds): (&RunCodes, &RunBounds),
    prim: u32,
    zc: &ZConvert,
    part: &mut Part,
    w: &mut VisWork,
) {
    let s0 = part.s0;
    let avx2 = simd::avx2();
    let (mut tests, mut writes, mut clamped) = (0, 0, 0);
    for r in runs {
        let at = r.s as usize - s0;
        let n = r.n as usize;
        tests += u64::from(r.n);
        let (z_buf, prim_buf, i_buf) = (
            &mut part.z[at..at + n],
            &mut part.prim[at..at + n],
            &mut part.i[at..at + n],
        );
        if let [e1, e2] = &mut part.extra[..]
            && let Some(k) = Kernel::of(r, bounds, zc, 3)
        {
            let more = (&mut e1[at..at + n], &mut e2[at..at + n]);
            writes += rgb(&k, prim, (z_buf, prim_buf, i_buf), more);
            continue;
        }
        if part.extra.is_empty()
            && let Some(k) = Kernel::of(r, bounds, zc, 1)
        {
            writes += grey_build(&k, prim, (z_buf, prim_buf, i_buf), avx2);
            continue;
        }
        let extra = &mut part.extra;
        let mut j = 0;
        codes.for_each(r, |f| {
            let z = zc.apply(f.z, &mut clamped);
            if z < z_buf[j] {
                z_buf[j] = z;
                prim_buf[j] = prim;
                i_buf[j] = f.i[0];
                for (c, plane) in extra.iter_mut().enumerate() {
                    plane[at + j] = f.i[c + 1];
                }
                writes += 1;
            }
            j += 1;
        });
    }
    w.tests += tests;
    w.writes += writes;
    w.clamped += clamped;
}

/// A run whose every value rounds into range with no overflow: its start values, steps
/// and the two roundings of depth (the raster's, then the z-buffer's).
struct Kernel {
    z: i64,
    dz: i64,
    i: [i64; 3],
    di: [i64; 3],
    raster: RoundShift,
    zbuf: RoundShift,
    /// Every value of the run is non-negative (its two ends are: the values are linear),
    /// so it rounds in `u64` ([`RoundShift::apply_nonneg`]).
    nonneg: bool,
}

/// The raw start and end values of a run that take the fast kernels: those of depth
/// whose raster code lies in `0..=z_max` and whose z-buffer code is in range, and those of
/// each intensity whose code lies in `0..=i_max`. The roundings are monotonic, so each is
/// one range of raw values (within [`RoundShift::is_small`]); found once per frame.
#[derive(Clone, Copy, Debug)]
pub struct RunBounds {
    z: (i64, i64),
    i: [(i64, i64); 3],
    raster: RoundShift,
}

impl RunBounds {
    /// The bounds of the raster's codes `codes` and the depth conversion `zc`.
    pub fn new(codes: &RunCodes, zc: &ZConvert) -> Self {
        const NONE: (i64, i64) = (1, 0);
        let raster = codes.rounding();
        // The largest raster depth code the z-buffer's rounding keeps in range.
        let z_top = zc
            .round
            .raw_range(i64::MIN, i64::from(zc.max))
            .map(|(_, top)| top.min(codes.z_max()));
        let z = z_top
            .and_then(|top| raster.raw_range(0, top))
            .unwrap_or(NONE);
        let i = std::array::from_fn(|c| raster.raw_range(0, codes.i_max(c)).unwrap_or(NONE));
        Self { z, i, raster }
    }
}

impl Kernel {
    /// The kernel of `r` with `channels` intensities, if its end values show that no value
    /// of it clamps or overflows (`b`: the raw values that do not).
    fn of(r: &Run, b: &RunBounds, zc: &ZConvert, channels: usize) -> Option<Self> {
        let inside = |v: i64, (lo, hi): (i64, i64)| lo <= v && v <= hi;
        let ez = RunCodes::end(r.z, r.dz, r.n)?;
        if !(inside(r.z, b.z) && inside(ez, b.z)) {
            return None;
        }
        let mut nonneg = r.z >= 0 && ez >= 0;
        for c in 0..channels {
            let ei = RunCodes::end(r.i[c], r.di[c], r.n)?;
            if !(inside(r.i[c], b.i[c]) && inside(ei, b.i[c])) {
                return None;
            }
            nonneg &= r.i[c] >= 0 && ei >= 0;
        }
        Some(Self {
            z: r.z,
            dz: r.dz,
            i: r.i,
            di: r.di,
            raster: b.raster,
            zbuf: zc.round,
            nonneg,
        })
    }
}

/// [`grey`] in the build for `k` (non-negative or not) and the CPU (`avx2`).
#[inline]
fn grey_build(k: &Kernel, prim: u32, planes: Planes, avx2: bool) -> u64 {
    match (avx2, k.nonneg) {
        (true, true) => simd::grey_avx2::<true>(k, prim, planes),
        (true, false) => simd::grey_avx2::<false>(k, prim, planes),
        (false, true) => grey::<true>(k, prim, planes),
        (false, false) => grey::<false>(k, prim, planes),
    }
}

/// The depth test of kernel `k`'s samples into the planes `(z, prim, i)` (one per sample
/// of the run): branch-free selects; `NONNEG`: the kernel's values are non-negative
/// ([`Kernel::nonneg`]) and round in `u64`. Returns the writes.
#[inline(always)]
fn grey<const NONNEG: bool>(k: &Kernel, prim: u32, (zb, pb, ib): Planes) -> u64 {
    let (mut z, mut i) = (k.z, k.i[0]);
    let mut writes = 0;
    for ((zb, pb), ib) in zb.iter_mut().zip(pb.iter_mut()).zip(ib.iter_mut()) {
        let (zv, iv) = if NONNEG {
            let zr = k.raster.apply_nonneg(z as u64);
            (
                k.zbuf.apply_nonneg(zr) as u32,
                k.raster.apply_nonneg(i as u64) as u32,
            )
        } else {
            (
                k.zbuf.apply_small(k.raster.apply_small(z)) as u32,
                k.raster.apply_small(i) as u32,
            )
        };
        let win = zv < *zb;
        *zb = if win { zv } else { *zb };
        *pb = if win { prim } else { *pb };
        *ib = if win { iv } else { *ib };
        writes += u64::from(win);
        z = z.wrapping_add(k.dz);
        i = i.wrapping_add(k.di[0]);
    }
    writes
}

/// [`grey`] for a colour run: channel 0's intensity into `ib`, channels 1 and 2's into
/// `e1` and `e2`.
fn rgb(k: &Kernel, prim: u32, (zb, pb, ib): Planes, (e1, e2): (&mut [u32], &mut [u32])) -> u64 {
    let (mut z, mut i) = (k.z, k.i);
    let mut writes = 0;
    let planes = zb.iter_mut().zip(pb.iter_mut()).zip(ib.iter_mut());
    for (((zb, pb), ib), (a, b)) in planes.zip(e1.iter_mut().zip(e2.iter_mut())) {
        let zv = k.zbuf.apply_small(k.raster.apply_small(z)) as u32;
        let win = zv < *zb;
        if win {
            *zb = zv;
            *pb = prim;
            *ib = k.raster.apply_small(i[0]) as u32;
            *a = k.raster.apply_small(i[1]) as u32;
            *b = k.raster.apply_small(i[2]) as u32;
            writes += 1;
        }
        z = z.wrapping_add(k.dz);
        for (v, d) in i.iter_mut().zip(&k.di) {
            *v = v.wrapping_add(*d);
        }
    }
    writes
}

/// A run's slices of the depth, primitive-id and channel-0 intensity planes.
type Planes<'a> = (&'a mut [u32], &'a mut [u32], &'a mut [u32]);

#[cfg(target_arch = "x86_64")]
mod simd {
    use super::{Kernel, Planes};

    pub fn avx2() -> bool {
        std::arch::is_x86_feature_detected!("avx2")
    }

    /// [`super::grey`] compiled with AVX2; call only when [`avx2`] holds.
    #[inline]
    pub fn grey_avx2<const NONNEG: bool>(k: &Kernel, prim: u32, planes: Planes) -> u64 {
        #[target_feature(enable = "avx2")]
        fn run<const NONNEG: bool>(k: &Kernel, prim: u32, planes: Planes) -> u64 {
            super::grey::<NONNEG>(k, prim, planes)
        }
        debug_assert!(avx2());
        // SAFETY: `run` is safe code compiled with AVX2 enabled; `resolve` calls this only
        // after `avx2()` found the feature on this CPU.
        unsafe { run::<NONNEG>(k, prim, planes) }
    }
}

/// Other targets: the portable build only.
#[cfg(not(target_arch = "x86_64"))]
mod simd {
    use super::{Kernel, Planes};

    pub fn avx2() -> bool {
        false
    }

    pub fn grey_avx2<const NONNEG: bool>(k: &Kernel, prim: u32, planes: Planes) -> u64 {
        super::grey::<NONNEG>(k, prim, planes)
    }
}

#[cfg(test)]
mod tests {
    use super::{Kernel, RunBounds, grey_build, resolve, simd};
    use crate::fixed::{Quant, RoundShift};
    use crate::stage::Grid;
    use crate::stage::raster::{RasterParams, Run, RunCodes};
    use crate::stage::visibility::{Part, VisWork, ZConvert};
    use proptest::prelude::*;

    fn setup(guard: u32, q: usize, zs: u32, channels: usize) -> (RunCodes, ZConvert) {
        let quant = Quant::ALL[q];
        let codes = RunCodes::new(&RasterParams {
            grid: Grid::new(4, 4, 8, 8),
            guard,
            quant,
            i_max: [4095; 3],
            z_max: (1 << 24) - 1,
            channels,
        });
        let zc = ZConvert {
            round: RoundShift::new(zs, quant),
            max: (1 << (24 - zs)) - 1,
        };
        (codes, zc)
    }

    /// Planes depth, id, intensity and channels 1 and 2 of a run at sample 3 (three samples
    /// before it), the depths from `old`.
    fn planes(old: &[u32], r: &Run) -> [Vec<u32>; 5] {
        let len = 3 + r.n as usize;
        [
            old[..len].to_vec(),
            vec![9; len],
            vec![7; len],
            vec![6; len],
            vec![5; len],
        ]
    }

    /// Resolves `r` (surface 5, `channels` intensities) and checks the planes, tests,
    /// writes and clamps against the raster's per-sample codes; returns the planes and the
    /// writes.
    fn check(
        codes: &RunCodes,
        zc: &ZConvert,
        r: &Run,
        old: &[u32],
        channels: usize,
    ) -> ([Vec<u32>; 5], u64) {
        let mut want = planes(old, r);
        let (mut writes, mut clamped) = (0u64, 0u64);
        codes.for_each(r, |f| {
            let zv = zc.apply(f.z, &mut clamped);
            let s = f.s as usize;
            if zv < want[0][s] {
                (want[0][s], want[1][s]) = (zv, 5);
                for c in 0..channels {
                    want[2 + c][s] = f.i[c];
                }
                writes += 1;
            }
        });
        let mut got = planes(old, r);
        let [gz, gp, gi, e1, e2] = &mut got;
        let extra = if channels == 3 {
            vec![&mut e1[..], &mut e2[..]]
        } else {
            Vec::new()
        };
        let mut part = Part {
            s0: 0,
            z: gz,
            prim: gp,
            i: gi,
            extra,
        };
        let mut w = VisWork::default();
        let bounds = RunBounds::new(codes, zc);
        resolve(&[*r], (codes, &bounds), 5, zc, &mut part, &mut w);
        assert_eq!(
            (w.tests, w.writes, w.clamped),
            (u64::from(r.n), writes, clamped)
        );
        assert_eq!(got, want);
        (want, writes)
    }

    /// Both builds of the grey kernel on `r`, against the planes `want` and `writes`.
    fn check_kernel(
        codes: &RunCodes,
        zc: &ZConvert,
        r: &Run,
        old: &[u32],
        (want, writes): ([Vec<u32>; 5], u64),
    ) {
        let Some(k) = Kernel::of(r, &RunBounds::new(codes, zc), zc, 1) else {
            return;
        };
        let n = r.n as usize;
        for avx2 in [false, simd::avx2()] {
            let (mut zk, mut pk, mut ik) = (old[3..3 + n].to_vec(), vec![9u32; n], vec![7u32; n]);
            let planes = (&mut zk[..], &mut pk[..], &mut ik[..]);
            let wk = grey_build(&k, 5, planes, avx2);
            assert_eq!(wk, writes);
            assert_eq!(
                (&zk[..], &pk[..], &ik[..]),
                (&want[0][3..], &want[1][3..], &want[2][3..])
            );
        }
    }

    fn run_strategy() -> impl Strategy<Value = (u32, usize, u32, Run, Vec<u32>)> {
        (
            0u32..=24,
            0usize..7,
            0u32..8,
            (-(1i64 << 20)..(1i64 << 50), -(1i64 << 36)..(1i64 << 36)),
            prop::array::uniform3(-(1i64 << 20)..(1i64 << 40)),
            prop::array::uniform3(-(1i64 << 30)..(1i64 << 30)),
            1u32..40,
            prop::collection::vec(0u32..(1 << 20), 43),
        )
            .prop_map(|(guard, q, zs, (z, dz), i, di, n, old)| {
                (
                    guard,
                    q,
                    zs,
                    Run {
                        s: 3,
                        n,
                        z,
                        dz,
                        i,
                        di,
                    },
                    old,
                )
            })
    }

    proptest! {
        /// Every grey run, fast kernel (portable and AVX2) or not, depth-tests its samples
        /// as the raster's per-sample codes do: the same planes, writes and clamps.
        #[test]
        fn fast_runs_match_the_codes_one_by_one((guard, q, zs, r, old) in run_strategy()) {
            let (codes, zc) = setup(guard, q, zs, 1);
            let got = check(&codes, &zc, &r, &old, 1);
            check_kernel(&codes, &zc, &r, &old, got);
        }

        /// Every colour run, fast kernel or not, writes the three channels' codes of the
        /// samples whose depth test passes, as the raster's per-sample codes do.
        #[test]
        fn colour_runs_match_the_codes_one_by_one((guard, q, zs, r, old) in run_strategy()) {
            let (codes, zc) = setup(guard, q, zs, 3);
            check(&codes, &zc, &r, &old, 3);
        }
    }

    /// Runs in range take the kernels, and give the per-sample codes there (the
    /// properties above need not draw such runs); a run out of range does not.
    #[test]
    fn in_range_runs_take_the_kernel() {
        let (codes, zc) = setup(14, 2, 4, 1);
        let r = Run {
            s: 3,
            n: 16,
            z: 1000 << 14,
            dz: 3 << 10,
            i: [200 << 14, 0, 0],
            di: [1 << 12, 0, 0],
        };
        // The samples already hold a nearer depth, the same depth (the earlier surface
        // stays) or a farther one, in turn.
        let mut old = vec![0u32; 43];
        let mut ignored = 0;
        for (j, f) in codes.frags(&r).enumerate() {
            let zv = zc.apply(f.z, &mut ignored);
            old[f.s as usize] = [0, zv, 1 << 20][j % 3];
        }
        assert!(Kernel::of(&r, &RunBounds::new(&codes, &zc), &zc, 1).is_some());
        let got = check(&codes, &zc, &r, &old, 1);
        assert_eq!(
            got.1, 5,
            "the farther samples 2, 5, 8, 11 and 14 are written"
        );
        check_kernel(&codes, &zc, &r, &old, got);
        let out = Run { z: -(1 << 20), ..r };
        assert!(Kernel::of(&out, &RunBounds::new(&codes, &zc), &zc, 1).is_none());
        let (codes, zc) = setup(14, 2, 4, 3);
        let rgb = Run {
            i: [200 << 14, 100 << 14, 50 << 14],
            di: [1 << 12; 3],
            ..r
        };
        assert!(Kernel::of(&rgb, &RunBounds::new(&codes, &zc), &zc, 3).is_some());
        check(&codes, &zc, &rgb, &old, 3);
        let dark = Run {
            i: [200 << 14, -(1 << 20), 50 << 14],
            ..rgb
        };
        assert!(Kernel::of(&dark, &RunBounds::new(&codes, &zc), &zc, 3).is_none());
    }
}
