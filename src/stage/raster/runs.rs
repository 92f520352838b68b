//! The raster's output: runs of covered samples. A run is one primitive's covered samples
//! on one sample row (a span of the edge walk), held as its first sample, its length and
//! the interpolators' values at its first sample (guard bits in) with their column steps.
//! Its fragments are the raster's per-sample adds and roundings ([`RunCodes::for_each`]),
//! done where they are read: the next stage takes each sample's codes straight from the
//! adder, as a span-fed pixel pipeline does, and no list of every fragment is written to
//! memory and read back. The fragments are those the walker emits, bit for bit.

use super::Frag;
use super::fixed::RasterParams;
use crate::fixed::RoundShift;
use crate::stage::taps::Frags;

/// One primitive's covered samples on one sample row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Run {
    /// The first sample's index in the sample region.
    pub s: u32,
    /// Samples (at least 1), at `s`, `s + 1`, ...
    pub n: u32,
    /// Depth interpolator at the first sample (guard bits in).
    pub z: i64,
    /// Its column step.
    pub dz: i64,
    /// Intensity interpolators at the first sample, per channel (guard bits in).
    pub i: [i64; 3],
    /// Their column steps.
    pub di: [i64; 3],
}

/// How an interpolator value becomes a code: the guard bits rounded off, the result
/// clamped into the code's range.
#[derive(Clone, Copy, Debug)]
pub struct RunCodes {
    rs: RoundShift,
    z_max: i64,
    i_max: [i64; 3],
    channels: usize,
}

impl RunCodes {
    /// The rounding and ranges of the raster `p`.
    pub fn new(p: &RasterParams) -> Self {
        Self {
            rs: RoundShift::new(p.guard, p.quant),
            z_max: p.z_max,
            i_max: p.i_max,
            channels: p.channels,
        }
    }

    /// The rounding of the guard bits.
    pub fn rounding(&self) -> RoundShift {
        self.rs
    }

    /// The largest depth code.
    pub fn z_max(&self) -> i64 {
        self.z_max
    }

    /// Channel `c`'s largest intensity code.
    pub fn i_max(&self, c: usize) -> i64 {
        self.i_max[c]
    }

    #[inline(always)]
    fn code(&self, v: i64, max: i64) -> u32 {
        self.rs.apply(v).clamp(0, max) as u32
    }

    fn out_of_range(&self, v: i64, max: i64) -> bool {
        let c = self.rs.apply(v);
        c < 0 || c > max
    }

    /// The last of the values `v`, `v + d`, ... (`n` of them), if no sum leaves `i64`.
    #[inline]
    pub fn end(v: i64, d: i64, n: u32) -> Option<i64> {
        d.checked_mul(i64::from(n) - 1)
            .and_then(|x| x.checked_add(v))
    }

    /// The values `v`, `v + d`, ... (`n` of them) that round out of `0..=max`.
    #[inline]
    fn lane_clamped(&self, v: i64, d: i64, n: u32, max: i64) -> u64 {
        match Self::end(v, d, n) {
            Some(e) if !self.out_of_range(v, max) && !self.out_of_range(e, max) => 0,
            _ => self.count_clamped(v, d, n, max),
        }
    }

    #[cold]
    fn count_clamped(&self, v: i64, d: i64, n: u32, max: i64) -> u64 {
        let (mut x, mut k) = (v, 0);
        for _ in 0..n {
            k += u64::from(self.out_of_range(x, max));
            x = x.wrapping_add(d);
        }
        k
    }

    /// The values of `r` that the rounding clamps (depth and every channel's intensity
    /// counted apart). The rounding is monotonic and a run's values are linear, so a run
    /// whose end values round into range clamps none; the others are counted one by one.
    #[inline]
    pub fn clamped(&self, r: &Run) -> u64 {
        let mut k = self.lane_clamped(r.z, r.dz, r.n, self.z_max);
        for c in 0..self.channels {
            k += self.lane_clamped(r.i[c], r.di[c], r.n, self.i_max[c]);
        }
        k
    }

    /// Calls `f` with each fragment of `r`, in sample order.
    #[inline(always)]
    pub fn for_each(&self, r: &Run, f: impl FnMut(Frag)) {
        self.frags(r).for_each(f);
    }

    /// The fragments of `r`, in sample order: per sample, the codes of the interpolators,
    /// then one add of each column step.
    #[inline(always)]
    pub fn frags(&self, r: &Run) -> RunFrags<'_> {
        RunFrags {
            codes: self,
            run: *r,
            j: 0,
        }
    }
}

/// The fragments of a run, one by one ([`RunCodes::frags`]).
pub struct RunFrags<'a> {
    codes: &'a RunCodes,
    /// The run, its values at sample `j`.
    run: Run,
    j: u32,
}

impl Iterator for RunFrags<'_> {
    type Item = Frag;

    #[inline(always)]
    fn next(&mut self) -> Option<Frag> {
        if self.j == self.run.n {
            return None;
        }
        let (c, r) = (self.codes, &mut self.run);
        let mut codes = [0u32; 3];
        let lanes = codes
            .iter_mut()
            .zip(r.i.iter_mut().zip(&r.di).zip(&c.i_max));
        for (code, ((i, di), &max)) in lanes.take(c.channels) {
            *code = c.code(*i, max);
            *i = i.wrapping_add(*di);
        }
        let f = Frag {
            s: r.s + self.j,
            z: c.code(r.z, c.z_max),
            i: codes,
        };
        r.z = r.z.wrapping_add(r.dz);
        self.j += 1;
        Some(f)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = (self.run.n - self.j) as usize;
        (n, Some(n))
    }
}

/// The raster's fragments: every primitive's runs, in parts of sample rows (see
/// [`Frags`]), and how their values become codes.
#[derive(Clone, Debug)]
pub struct FragRuns {
    /// The runs.
    pub runs: Frags<Run>,
    /// Their codes.
    pub codes: RunCodes,
}

impl FragRuns {
    /// Primitive `p`'s fragments, part by part (rows), each part's in the order the walker
    /// emitted them.
    pub fn of(&self, p: usize) -> impl Iterator<Item = Frag> + '_ {
        self.runs
            .of(p)
            .flatten()
            .flat_map(move |r| self.codes.frags(r))
    }

    /// The number of primitive `p`'s fragments.
    pub fn count(&self, p: usize) -> usize {
        self.runs.of(p).flatten().map(|r| r.n as usize).sum()
    }

    /// Fragments of all primitives.
    pub fn len(&self) -> usize {
        self.runs.parts.iter().flatten().map(|r| r.n as usize).sum()
    }

    /// Whether no primitive has a fragment.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::{Run, RunCodes};
    use crate::fixed::Quant;
    use crate::stage::Grid;
    use crate::stage::raster::RasterParams;
    use proptest::prelude::*;

    fn codes(guard: u32, quant: Quant, z_max: i64, i_max: i64, channels: usize) -> RunCodes {
        RunCodes::new(&RasterParams {
            grid: Grid::new(4, 4, 8, 8),
            guard,
            quant,
            i_max: [i_max; 3],
            z_max,
            channels,
        })
    }

    proptest! {
        /// The run's clamp count from its end values is the count of its values, one by
        /// one, that round out of range; its fragments are the per-sample adds and
        /// roundings, clamped.
        #[test]
        fn clamps_and_codes_are_those_of_the_values_one_by_one(
            guard in 0u32..=24,
            q in 0usize..7,
            (z, dz) in (-(1i64 << 40)..(1i64 << 40), -(1i64 << 30)..(1i64 << 30)),
            i in prop::array::uniform3(-(1i64 << 36)..(1i64 << 36)),
            di in prop::array::uniform3(-(1i64 << 28)..(1i64 << 28)),
            n in 1u32..300,
            channels in 1usize..=3,
            (z_max, i_max) in (1i64..(1i64 << 32), 1i64..(1i64 << 16)),
        ) {
            let c = codes(guard, Quant::ALL[q], z_max, i_max, channels);
            let r = Run { s: 7, n, z, dz, i, di };
            let round = |v: i64| crate::fixed::RoundShift::new(guard, Quant::ALL[q]).apply(v);
            let (mut want, mut frags) = (0u64, Vec::new());
            let (mut zv, mut iv) = (z, i);
            for j in 0..n {
                let mut codes = [0u32; 3];
                for ch in 0..channels {
                    let v = round(iv[ch]);
                    want += u64::from(v < 0 || v > i_max);
                    codes[ch] = v.clamp(0, i_max) as u32;
                    iv[ch] += di[ch];
                }
                let v = round(zv);
                want += u64::from(v < 0 || v > z_max);
                frags.push((7 + j, v.clamp(0, z_max) as u32, codes));
                zv += dz;
            }
            prop_assert_eq!(c.clamped(&r), want);
            let got: Vec<_> = c.frags(&r).map(|f| (f.s, f.z, f.i)).collect();
            prop_assert_eq!(got, frags);
        }
    }
}
