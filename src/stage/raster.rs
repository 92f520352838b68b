//! Raster: Bresenham-style edge walking with add-only interpolation.
//!
//! Per sample row each active edge steps by quotient and remainder (see `setup`); per
//! sample the intensity and depth interpolators add their column gradient. Nothing in
//! the row or sample loops multiplies or divides. Spans that start left of the sample
//! region (off-screen, inside the guard band) are walked by additions too and counted as
//! `walked` samples; rows above the region likewise (`rows_walked`).
//!
//! The float reference (`raster_f64`) evaluates the same top-left rule and the exact
//! attribute planes in f64 at the same sample positions.

use super::Grid;
use super::input::QPrim;
use super::setup::{Edge, PointSetup, Setup, TriSetup};
use crate::fixed::{Quant, round_shift_i64};

/// The rectangle of samples a render keeps, half-open, in global sample coordinates
/// (may extend past the screen by the filter's apron).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampleRegion {
    /// First column.
    pub c0: i64,
    /// First row.
    pub k0: i64,
    /// One past the last column.
    pub c1: i64,
    /// One past the last row.
    pub k1: i64,
}

impl SampleRegion {
    /// Columns.
    pub fn width(&self) -> usize {
        (self.c1 - self.c0).max(0) as usize
    }
    /// Rows.
    pub fn height(&self) -> usize {
        (self.k1 - self.k0).max(0) as usize
    }
    /// Samples.
    pub fn len(&self) -> usize {
        self.width() * self.height()
    }
    /// Whether empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Buffer index of a sample inside the region.
    #[inline]
    pub fn index(&self, c: i64, k: i64) -> usize {
        (k - self.k0) as usize * self.width() + (c - self.c0) as usize
    }
}

/// One covered sample of one primitive: buffer index, depth and intensity codes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frag {
    /// Index in the sample region.
    pub s: u32,
    /// Depth, input z-format code.
    pub z: u32,
    /// Intensity, intensity-format code.
    pub i: u32,
}

/// Float fragment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FragF {
    /// Index in the sample region.
    pub s: u32,
    /// Depth in input z-format LSBs.
    pub z: f64,
    /// Intensity in intensity-format LSBs.
    pub i: f64,
}

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

/// Fixed parameters of the raster.
#[derive(Clone, Copy, Debug)]
pub struct RasterParams {
    /// Sample grid.
    pub grid: Grid,
    /// Interpolator guard bits.
    pub guard: u32,
    /// Rounding of interpolators to sample codes.
    pub quant: Quant,
    /// Largest intensity code.
    pub i_max: i64,
    /// Largest depth code.
    pub z_max: i64,
}

#[inline]
fn out_code(v: i64, p: &RasterParams, max: i64, clamped: &mut u64) -> u32 {
    let c = round_shift_i64(v, p.guard, p.quant);
    if c < 0 || c > max {
        *clamped += 1;
        c.clamp(0, max) as u32
    } else {
        c as u32
    }
}

/// Left-edge attribute stepping: increments for a column move of `a` or `a + 1`.
struct EdgeInterp {
    inc_a_i: i64,
    inc_a1_i: i64,
    inc_a_z: i64,
    inc_a1_z: i64,
}

impl EdgeInterp {
    fn new(e: &Edge, di: (i64, i64), dz: (i64, i64)) -> Self {
        // Setup-time products: the edge's integer step times the column gradient.
        let inc_a_i = di.1 + e.a * di.0;
        let inc_a_z = dz.1 + e.a * dz.0;
        Self {
            inc_a_i,
            inc_a1_i: inc_a_i + di.0,
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
    let g = &p.grid;
    let h2 = 2 * g.h;
    let (mut long, mut upper, mut lower) = (t.long, t.upper, t.lower);
    let (k_start, k_end) = (long.k0, long.k1.min(reg.k1));
    if k_start >= k_end {
        return;
    }
    // Column and row gradients with guard bits (setup-time divisions).
    let di = (t.i.dx(h2, p.guard), t.i.dy(h2, p.guard));
    let dz = (t.z.dx(h2, p.guard), t.z.dy(h2, p.guard));
    let x_of = |c: i64| (2 * c + 1) * g.h;
    let y_of = |k: i64| (2 * k + 1) * g.h;
    let mut in_upper = upper.k0 < upper.k1 && k_start < upper.k1;
    let seed = |e: &Edge, k: i64| {
        (
            t.i.eval(x_of(e.q), y_of(k), p.guard),
            t.z.eval(x_of(e.q), y_of(k), p.guard),
        )
    };
    let first_left = if t.long_is_left {
        long
    } else if in_upper {
        upper
    } else {
        lower
    };
    let (mut vi, mut vz) = seed(&first_left, k_start);
    let mut interp = EdgeInterp::new(&first_left, di, dz);
    let width = reg.width();
    let mut k = k_start;
    loop {
        let short = if in_upper { &upper } else { &lower };
        let (lq, rq) = if t.long_is_left {
            (long.q, short.q)
        } else {
            (short.q, long.q)
        };
        if k >= reg.k0 {
            let c_start = lq.max(reg.c0);
            let c_end = rq.min(reg.c1);
            if c_start < c_end {
                w.spans += 1;
                let (mut si, mut sz) = (vi, vz);
                for _ in lq..c_start {
                    si += di.0;
                    sz += dz.0;
                }
                w.walked += (c_start - lq) as u64;
                let row = (k - reg.k0) as usize * width;
                for c in c_start..c_end {
                    out.push(Frag {
                        s: (row + (c - reg.c0) as usize) as u32,
                        z: out_code(sz, p, p.z_max, &mut w.clamped),
                        i: out_code(si, p, p.i_max, &mut w.clamped),
                    });
                    si += di.0;
                    sz += dz.0;
                }
                w.samples += (c_end - c_start) as u64;
            }
        } else {
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
            // The left edge changes at the middle vertex: re-seed (a setup operation).
            (vi, vz) = seed(&lower, k);
            interp = EdgeInterp::new(&lower, di, dz);
            w.reseeds += 1;
        } else {
            let c = if t.long_is_left {
                long_carry
            } else {
                short_carry
            };
            vi += if c { interp.inc_a1_i } else { interp.inc_a_i };
            vz += if c { interp.inc_a1_z } else { interp.inc_a_z };
        }
    }
}

/// Rasterises a light point's square (flat values) into `out`.
pub fn raster_point(
    pt: &PointSetup,
    p: &RasterParams,
    reg: &SampleRegion,
    out: &mut Vec<Frag>,
    w: &mut RasterWork,
) {
    let (c0, c1) = (pt.c.0.max(reg.c0), pt.c.1.min(reg.c1));
    let (k0, k1) = (pt.k.0.max(reg.k0), pt.k.1.min(reg.k1));
    if c0 >= c1 || k0 >= k1 {
        return;
    }
    let z = pt.z.clamp(0, p.z_max) as u32;
    let i = pt.i.clamp(0, p.i_max) as u32;
    for k in k0..k1 {
        w.spans += 1;
        for c in c0..c1 {
            out.push(Frag {
                s: reg.index(c, k) as u32,
                z,
                i,
            });
        }
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
    match s {
        Setup::Tri(t) => raster_tri(t, p, reg, out, w),
        Setup::Line(a, b) => {
            raster_tri(a, p, reg, out, w);
            raster_tri(b, p, reg, out, w);
        }
        Setup::Point(pt) => raster_point(pt, p, reg, out, w),
        Setup::Degenerate => {}
    }
}

// ---------------------------------------------------------------------------------------
// Float reference
// ---------------------------------------------------------------------------------------

/// A float vertex: x, y in pixels; z and i in their fixed formats' LSBs (no rounding).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FVertex {
    /// x, pixels.
    pub x: f64,
    /// y, pixels.
    pub y: f64,
    /// Depth, z-format LSBs.
    pub z: f64,
    /// Intensity, intensity-format LSBs.
    pub i: f64,
}

/// A float primitive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FPrim {
    /// Triangle.
    Triangle([FVertex; 3]),
    /// Line with width in pixels.
    Line {
        /// Start.
        a: FVertex,
        /// End.
        b: FVertex,
        /// Width, pixels.
        width: f64,
    },
    /// Light point with side in pixels.
    Point {
        /// Centre.
        v: FVertex,
        /// Side, pixels.
        size: f64,
    },
}

impl FPrim {
    /// The quantised primitive seen as exact reals (for stage-local comparison).
    pub fn from_q(p: &QPrim, sub_bits: u32) -> Self {
        let s = (1u64 << sub_bits) as f64;
        let v = |q: &super::input::QVertex| FVertex {
            x: q.x as f64 / s,
            y: q.y as f64 / s,
            z: q.z as f64,
            i: q.i as f64,
        };
        match p {
            QPrim::Triangle(t) => FPrim::Triangle([v(&t[0]), v(&t[1]), v(&t[2])]),
            QPrim::Line { a, b, width } => FPrim::Line {
                a: v(a),
                b: v(b),
                width: *width as f64 / s,
            },
            QPrim::Point { v: c, size } => FPrim::Point {
                v: v(c),
                size: *size as f64 / s,
            },
        }
    }

    /// Whether the primitive is a light point (additive, not z-written).
    pub fn is_point(&self) -> bool {
        matches!(self, FPrim::Point { .. })
    }
}

/// Float raster of one triangle: same rule, exact planes.
pub fn raster_tri_f64(v: &[FVertex; 3], g: &Grid, reg: &SampleRegion, out: &mut Vec<FragF>) {
    let mut s = *v;
    s.sort_by(|a, b| {
        (a.y, a.x)
            .partial_cmp(&(b.y, b.x))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let [v0, v1, v2] = s;
    let cross = (v1.x - v0.x) * (v2.y - v0.y) - (v2.x - v0.x) * (v1.y - v0.y);
    if cross == 0.0 || !cross.is_finite() || v0.y == v2.y {
        return;
    }
    let n = g.n as f64;
    let det = cross;
    let plane = |f: fn(&FVertex) -> f64| {
        let (a1, a2) = (f(&v1) - f(&v0), f(&v2) - f(&v0));
        let gx = (a1 * (v2.y - v0.y) - a2 * (v1.y - v0.y)) / det;
        let gy = (a2 * (v1.x - v0.x) - a1 * (v2.x - v0.x)) / det;
        (f(&v0), gx, gy)
    };
    let pi = plane(|p| p.i);
    let pz = plane(|p| p.z);
    let row_of = |y: f64| (y * n - 0.5).ceil() as i64;
    let cross_col = |a: &FVertex, b: &FVertex, y: f64| {
        let x = a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y);
        (x * n - 0.5).ceil() as i64
    };
    let k_start = row_of(v0.y).max(reg.k0);
    let k_end = row_of(v2.y).min(reg.k1);
    let k_mid = row_of(v1.y);
    let long_is_left = cross > 0.0;
    let width = reg.width();
    for k in k_start..k_end {
        let y = (k as f64 + 0.5) / n;
        let el = cross_col(&v0, &v2, y);
        let es = if k < k_mid {
            cross_col(&v0, &v1, y)
        } else {
            cross_col(&v1, &v2, y)
        };
        let (l, r) = if long_is_left { (el, es) } else { (es, el) };
        let row = (k - reg.k0) as usize * width;
        for c in l.max(reg.c0)..r.min(reg.c1) {
            let x = (c as f64 + 0.5) / n;
            let (dx, dy) = (x - v0.x, y - v0.y);
            out.push(FragF {
                s: (row + (c - reg.c0) as usize) as u32,
                z: pz.0 + pz.1 * dx + pz.2 * dy,
                i: pi.0 + pi.1 * dx + pi.2 * dy,
            });
        }
    }
}

/// Float raster of any primitive (lines as the same parallelogram, points as squares).
pub fn raster_f64(p: &FPrim, g: &Grid, reg: &SampleRegion, out: &mut Vec<FragF>) {
    match p {
        FPrim::Triangle(v) => raster_tri_f64(v, g, reg, out),
        FPrim::Line { a, b, width } => {
            let (dx, dy) = ((b.x - a.x).abs(), (b.y - a.y).abs());
            if dx == 0.0 && dy == 0.0 {
                return;
            }
            let off = |v: &FVertex, d: f64| {
                if dx >= dy {
                    FVertex { y: v.y + d, ..*v }
                } else {
                    FVertex { x: v.x + d, ..*v }
                }
            };
            let (a0, a1, b0, b1) = (
                off(a, -width / 2.0),
                off(a, width / 2.0),
                off(b, -width / 2.0),
                off(b, width / 2.0),
            );
            raster_tri_f64(&[a0, b0, b1], g, reg, out);
            raster_tri_f64(&[a0, b1, a1], g, reg, out);
        }
        FPrim::Point { v, size } => {
            let n = g.n as f64;
            let span = |lo: f64| {
                (
                    ((lo * n) - 0.5).ceil() as i64,
                    (((lo + size) * n) - 0.5).ceil() as i64,
                )
            };
            let (c0, c1) = span(v.x - size / 2.0);
            let (k0, k1) = span(v.y - size / 2.0);
            for k in k0.max(reg.k0)..k1.min(reg.k1) {
                for c in c0.max(reg.c0)..c1.min(reg.c1) {
                    out.push(FragF {
                        s: reg.index(c, k) as u32,
                        z: v.z,
                        i: v.i,
                    });
                }
            }
        }
    }
}
