//! The float raster: the same top-left rule and the exact attribute planes in f64 at the
//! same sample positions.

use super::FragF;
use crate::stage::input::{QPrim, QVertex};
use crate::stage::{Grid, SampleRegion};

/// A float vertex: x, y in pixels; z and i in their fixed formats' LSBs (no rounding).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FVertex {
    /// x, pixels.
    pub x: f64,
    /// y, pixels.
    pub y: f64,
    /// Depth, z-format LSBs.
    pub z: f64,
    /// Intensity per channel, intensity-format LSBs.
    pub i: [f64; 3],
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
        let v = |q: &QVertex| FVertex {
            x: q.x as f64 / s,
            y: q.y as f64 / s,
            z: q.z as f64,
            i: q.i.map(|i| i as f64),
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
    let plane = |f: &dyn Fn(&FVertex) -> f64| {
        let (a1, a2) = (f(&v1) - f(&v0), f(&v2) - f(&v0));
        let gx = (a1 * (v2.y - v0.y) - a2 * (v1.y - v0.y)) / det;
        let gy = (a2 * (v1.x - v0.x) - a1 * (v2.x - v0.x)) / det;
        (f(&v0), gx, gy)
    };
    let pi: [(f64, f64, f64); 3] = std::array::from_fn(|c| plane(&|p: &FVertex| p.i[c]));
    let pz = plane(&|p: &FVertex| p.z);
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
                i: pi.map(|pi| pi.0 + pi.1 * dx + pi.2 * dy),
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
