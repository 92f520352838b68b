//! The fixed raster: Bresenham-style edge walking with add-only interpolation.
//!
//! Per sample row each active edge steps by quotient and remainder (see `setup`); per
//! sample the intensity and depth interpolators add their column gradient. Nothing in
//! the row or sample loops multiplies or divides. Spans that start left of the sample
//! region (off-screen, inside the guard band) are walked by additions too and counted as
//! `walked` samples; rows above the region likewise (`rows_walked`).

use super::Frag;
use super::runs::{Run, RunCodes};
use crate::fixed::Quant;
use crate::stage::setup::{Edge, PointSetup, Setup, TriSetup};
use crate::stage::{Grid, SampleRegion};

/// Work of the raster.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RasterWork {
    /// Spans with at least one sample in the region.
    pub spans: u64,
    /// Samples emitted.
    pub samples: u64,
    /// Samples stepped outside the region (guard band) to reach the region.
    pub walked: u64,
    /// Sample rows stepped above the region.
    pub rows_walked: u64,
    /// Interpolator re-seeds at a triangle's middle vertex (a setup operation).
    pub reseeds: u64,
    /// Interpolated values clamped into their format (rounding drift past a vertex value).
    pub clamped: u64,
}

impl RasterWork {
    /// Adds the counts of `o`.
    pub fn add(&mut self, o: &Self) {
        self.spans += o.spans;
        self.samples += o.samples;
        self.walked += o.walked;
        self.rows_walked += o.rows_walked;
        self.reseeds += o.reseeds;
        self.clamped += o.clamped;
    }
}

/// Fixed parameters of the raster.
#[derive(Clone, Copy, Debug)]
pub struct RasterParams {
    /// Sample grid.
    pub grid: Grid,
    /// Interpolator guard bits.
    pub guard: u32,
    /// Rounding of interpolators to sample codes.
    pub quant: Quant,
    /// Largest intensity code per channel.
    pub i_max: [i64; 3],
    /// Largest depth code.
    pub z_max: i64,
    /// Intensity channels interpolated (1 grey, 3 colour): one set of edge walkers and one
    /// intensity interpolator per channel, stepped together.
    pub channels: usize,
}

/// Where the walker puts a row's run: a list, or the part of a band its row falls in.
pub trait RunSink {
    /// Takes the run of sample row `k`.
    fn push(&mut self, k: i64, run: Run);
}

impl RunSink for Vec<Run> {
    #[inline]
    fn push(&mut self, _: i64, run: Run) {
        Vec::push(self, run);
    }
}

/// Left-edge attribute stepping: increments for a column move of `a` or `a + 1`, per
/// intensity channel and for depth.
struct EdgeInterp {
    inc_a_i: [i64; 3],
    inc_a1_i: [i64; 3],
    inc_a_z: i64,
    inc_a1_z: i64,
}

impl EdgeInterp {
    fn new(e: &Edge, di: &[(i64, i64); 3], dz: (i64, i64)) -> Self {
        // Setup-time products: the edge's integer step times the column gradient.
        let inc_a_i = di.map(|d| d.1 + e.a * d.0);
        let inc_a_z = dz.1 + e.a * dz.0;
        Self {
            inc_a_i,
            inc_a1_i: std::array::from_fn(|c| inc_a_i[c] + di[c].0),
            inc_a_z,
            inc_a1_z: inc_a_z + dz.0,
        }
    }
}

/// Rasterises one set-up triangle into `out` (fragments inside `reg`, row by row).
pub fn raster_tri(
    t: &TriSetup,
    p: &RasterParams,
    reg: &SampleRegion,
    out: &mut Vec<Frag>,
    w: &mut RasterWork,
) {
    let mut runs = Vec::new();
    raster_tri_rows(t, p, reg, (reg.k0, reg.k1), true, &mut runs, w);
    expand(&runs, p, out);
}

/// Appends the fragments of `runs` to `out`.
fn expand(runs: &[Run], p: &RasterParams, out: &mut Vec<Frag>) {
    let codes = RunCodes::new(p);
    for r in runs {
        codes.for_each(r, |f| out.push(f));
    }
}

/// [`raster_tri`] on the sample rows `rows.0..rows.1` of `reg` (a band; fragment indices
/// stay those of `reg`), as runs (one per span): the edges are stepped (adds only, no samples) through the rows
/// above the band, which count as `rows_walked`, and their re-seeds as `reseeds`, only when
/// `above` (the first band, or the whole region); a later band's walk down to its rows
/// repeats what an earlier band counted. The fragments of the band's rows are exactly those
/// of the whole-region run (same walk, same adds).
pub fn raster_tri_rows(
    t: &TriSetup,
    p: &RasterParams,
    reg: &SampleRegion,
    rows: (i64, i64),
    above: bool,
    out: &mut impl RunSink,
    w: &mut RasterWork,
) {
    let (mut long, mut upper, mut lower) = (t.long, t.upper, t.lower);
    let (k_start, k_end) = (long.k0, long.k1.min(rows.1));
    if k_start >= k_end || (!above && k_end <= rows.0) {
        return;
    }
    // Column and row gradients and the seeds come from setup (its divisions, once per
    // primitive); the raster adds.
    let nc = p.channels;
    let di: [(i64, i64); 3] = std::array::from_fn(|c| (t.i[c].dx, t.i[c].dy));
    let dz = (t.z.dx, t.z.dy);
    let mut in_upper = upper.k0 < upper.k1 && k_start < upper.k1;
    let (mut vi, mut vz) = (t.i.map(|a| a.seed), t.z.seed);
    let mut interp = EdgeInterp::new(t.first_left(), &di, dz);
    let width = reg.width();
    let codes = RunCodes::new(p);
    let mut k = k_start;
    loop {
        let short = if in_upper { &upper } else { &lower };
        let (lq, rq) = if t.long_is_left {
            (long.q, short.q)
        } else {
            (short.q, long.q)
        };
        if k >= rows.0 {
            let c_start = lq.max(reg.c0);
            let c_end = rq.min(reg.c1);
            if c_start < c_end {
                w.spans += 1;
                // The columns left of the region are walked (counted) as the hardware
                // steps them: `n` adds of the column gradient are one multiply here.
                let n = c_start - lq;
                let (mut si, sz) = (vi, vz + dz.0 * n);
                for ch in 0..nc {
                    si[ch] += di[ch].0 * n;
                }
                w.walked += n as u64;
                let row = (k - reg.k0) as usize * width;
                let run = Run {
                    s: (row + (c_start - reg.c0) as usize) as u32,
                    n: (c_end - c_start) as u32,
                    z: sz,
                    dz: dz.0,
                    i: si,
                    di: di.map(|d| d.0),
                };
                w.clamped += codes.clamped(&run);
                w.samples += u64::from(run.n);
                out.push(k, run);
            }
        } else if above {
            w.rows_walked += 1;
        }
        k += 1;
        if k >= k_end {
            break;
        }
        // Step the edges to the next row: adds and compares only.
        let long_carry = long.step();
        let switch = in_upper && k >= upper.k1;
        let short_carry = if switch {
            in_upper = false; // `lower` already sits on its first row, which is `k`
            false
        } else if in_upper {
            upper.step()
        } else {
            lower.step()
        };
        if !t.long_is_left && switch {
            // The left edge changes at the middle vertex: re-seed (setup's value).
            (vi, vz) = (t.i.map(|a| a.reseed), t.z.reseed);
            interp = EdgeInterp::new(&lower, &di, dz);
            if above || k >= rows.0 {
                w.reseeds += 1;
            }
        } else {
            let c = if t.long_is_left {
                long_carry
            } else {
                short_carry
            };
            let inc = if c { &interp.inc_a1_i } else { &interp.inc_a_i };
            for ch in 0..nc {
                vi[ch] += inc[ch];
            }
            vz += if c { interp.inc_a1_z } else { interp.inc_a_z };
        }
    }
}

/// Rasterises a light point's square (flat values) into `out`.
pub fn raster_point(
    pt: &PointSetup,
    p: &RasterParams,
    reg: &SampleRegion,
    rows: (i64, i64),
    out: &mut impl RunSink,
    w: &mut RasterWork,
) {
    let (c0, c1) = (pt.c.0.max(reg.c0), pt.c.1.min(reg.c1));
    let (k0, k1) = (pt.k.0.max(rows.0), pt.k.1.min(rows.1));
    if c0 >= c1 || k0 >= k1 {
        return;
    }
    // Flat codes, in range: with the guard bits below them every rounding gives them back.
    let z = pt.z.clamp(0, p.z_max) << p.guard;
    let i: [i64; 3] = std::array::from_fn(|c| pt.i[c].clamp(0, p.i_max[c]) << p.guard);
    for k in k0..k1 {
        w.spans += 1;
        out.push(
            k,
            Run {
                s: reg.index(c0, k) as u32,
                n: (c1 - c0) as u32,
                z,
                dz: 0,
                i,
                di: [0; 3],
            },
        );
    }
    w.samples += ((c1 - c0) * (k1 - k0)) as u64;
}

/// Rasterises any set-up primitive.
pub fn raster(
    s: &Setup,
    p: &RasterParams,
    reg: &SampleRegion,
    out: &mut Vec<Frag>,
    w: &mut RasterWork,
) {
    let mut runs = Vec::new();
    raster_rows(s, p, reg, (reg.k0, reg.k1), true, &mut runs, w);
    expand(&runs, p, out);
}

/// [`raster`] on the sample rows `rows.0..rows.1` of `reg` (see [`raster_tri_rows`] for
/// `above`), as runs; the fragment indices are those of `reg`.
pub fn raster_rows(
    s: &Setup,
    p: &RasterParams,
    reg: &SampleRegion,
    rows: (i64, i64),
    above: bool,
    out: &mut impl RunSink,
    w: &mut RasterWork,
) {
    match s {
        Setup::Tri(t) => raster_tri_rows(t, p, reg, rows, above, out, w),
        Setup::Line(pair) => {
            for t in pair.iter() {
                raster_tri_rows(t, p, reg, rows, above, out, w);
            }
        }
        Setup::Point(pt) => raster_point(pt, p, reg, rows, out, w),
        Setup::Degenerate => {}
    }
}
