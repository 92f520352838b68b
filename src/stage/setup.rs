//! Setup: per-primitive constants for the raster. The only stage of the geometry path
//! that multiplies and divides (once per primitive, never per span or sample).
//!
//! * An edge is always walked from its upper to its lower vertex (canonical direction),
//!   so two triangles sharing an edge compute the same crossing on every sample row.
//! * Sample row `k` lies at `y = (2k + 1) h` coordinate units, sample column `c` at
//!   `x = (2c + 1) h`, with `h` half the sample spacing. Row `k` belongs to an edge
//!   when `y_top <= y_k < y_bottom`; on a row, a span covers the columns
//!   `E_left <= c < E_right` where `E = ceil((x_cross - h) / 2h)`. This is the top-left
//!   rule: samples on a left or top edge are inside, on a right or bottom edge outside.
//! * `E` is kept as quotient and remainder (`N = q D - r`, `0 <= r < D`) and stepped per
//!   row by a precomputed quotient `a` and remainder `b`: add, compare, conditional add.
//! * Attributes are planes; the interpolator steps by gradients with
//!   `interp_guard_bits` extra fraction bits.

use super::input::{QPrim, QVertex};
use super::taps::Taps;
use super::{
    Cost, Cx, Facts, Grid, LocalError, MemImage, Need, Notes, Stage, StageId, TokenKind, Tokens,
    Unit,
};
use crate::config::HwConfig;
use crate::error::Result;
use crate::scene::Scene;
use rayon::prelude::*;
use std::sync::Arc;

/// Floor division of integers.
#[inline]
pub fn floor_div(a: i64, b: i64) -> i64 {
    a.div_euclid(b) - if b < 0 && a.rem_euclid(b) != 0 { 1 } else { 0 }
}

/// Ceiling division of integers (`b > 0`).
#[inline]
pub fn ceil_div(a: i64, b: i64) -> i64 {
    debug_assert!(b > 0);
    -floor_div(-a, b)
}

/// One edge in Bresenham quotient/remainder form.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    /// First sample row of the edge.
    pub k0: i64,
    /// One past the last sample row.
    pub k1: i64,
    /// Current crossing column `E = q` (first column right of the crossing).
    pub q: i64,
    /// Remainder, `0 <= r < d`.
    pub r: i64,
    /// Integer part of the per-row step.
    pub a: i64,
    /// Remainder part of the per-row step, `0 <= b < d`.
    pub b: i64,
    /// Denominator.
    pub d: i64,
}

impl Edge {
    /// Sets up the edge from `top` to `bottom` (`top.y < bottom.y`), positioned on row `k0`.
    pub fn new(top: (i64, i64), bottom: (i64, i64), g: &Grid) -> Self {
        let (xa, ya) = top;
        let (xb, yb) = bottom;
        let h = g.h;
        let dy = yb - ya;
        let dx = xb - xa;
        debug_assert!(dy > 0);
        let k0 = ceil_div(ya - h, 2 * h);
        let k1 = ceil_div(yb - h, 2 * h);
        let d = 2 * h * dy;
        let yk = (2 * k0 + 1) * h;
        let n0 = (xa - h) * dy + (yk - ya) * dx;
        let q = ceil_div(n0, d);
        let r = q * d - n0;
        let a = floor_div(dx, dy);
        let b = 2 * h * (dx - a * dy);
        Self {
            k0,
            k1,
            q,
            r,
            a,
            b,
            d,
        }
    }

    /// Advances one sample row: adds and compares only. Returns whether the extra
    /// column carry happened (the crossing moved by `a + 1` instead of `a`).
    #[inline]
    pub fn step(&mut self) -> bool {
        self.q += self.a;
        self.r -= self.b;
        if self.r < 0 {
            self.r += self.d;
            self.q += 1;
            true
        } else {
            false
        }
    }
}

/// An attribute plane in exact form: `A(x, y) = (num0 + nx (x - x0) + ny (y - y0)) / det`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plane {
    x0: i64,
    y0: i64,
    num0: i128,
    nx: i128,
    ny: i128,
    det: i128,
}

impl Plane {
    /// Plane through three vertices of attribute `f`, `det > 0` after normalisation.
    pub fn new(v: &[QVertex; 3], f: impl Fn(&QVertex) -> i64) -> Self {
        let (x0, y0) = (v[0].x as i128, v[0].y as i128);
        let (x1, y1) = (v[1].x as i128 - x0, v[1].y as i128 - y0);
        let (x2, y2) = (v[2].x as i128 - x0, v[2].y as i128 - y0);
        let (a0, a1, a2) = (
            f(&v[0]) as i128,
            f(&v[1]) as i128 - f(&v[0]) as i128,
            f(&v[2]) as i128 - f(&v[0]) as i128,
        );
        let mut det = x1 * y2 - x2 * y1;
        let mut nx = a1 * y2 - a2 * y1;
        let mut ny = a2 * x1 - a1 * x2;
        if det < 0 {
            det = -det;
            nx = -nx;
            ny = -ny;
        }
        Self {
            x0: v[0].x,
            y0: v[0].y,
            num0: a0 * det,
            nx,
            ny,
            det,
        }
    }

    /// Value at `(x, y)` units with `g` extra fraction bits, rounded to nearest (setup only: multiplies).
    pub fn eval(&self, x: i64, y: i64, g: u32) -> i64 {
        let num = self.num0 + self.nx * (x - self.x0) as i128 + self.ny * (y - self.y0) as i128;
        div_round(num << g, self.det) as i64
    }

    /// Gradient per `step` units in x, with `g` extra fraction bits.
    pub fn dx(&self, step: i64, g: u32) -> i64 {
        div_round((self.nx * step as i128) << g, self.det) as i64
    }

    /// Gradient per `step` units in y, with `g` extra fraction bits.
    pub fn dy(&self, step: i64, g: u32) -> i64 {
        div_round((self.ny * step as i128) << g, self.det) as i64
    }

    /// Exact value in f64 (reference, setup-time check).
    pub fn value_f64(&self, x: f64, y: f64) -> f64 {
        (self.num0 as f64
            + self.nx as f64 * (x - self.x0 as f64)
            + self.ny as f64 * (y - self.y0 as f64))
            / self.det as f64
    }
}

/// Round-half-up division, `d > 0` (in 64 bits when the operands fit: the same quotient,
/// without the 128-bit division routine).
#[inline]
fn div_round(n: i128, d: i128) -> i128 {
    let (num, den) = (2 * n + d, 2 * d);
    match (i64::try_from(num), i64::try_from(den)) {
        (Ok(a), Ok(b)) => a.div_euclid(b) as i128,
        _ => num.div_euclid(den),
    }
}

/// One attribute's interpolator constants, with the raster's guard bits: what the raster
/// needs of a [`Plane`] (setup evaluates and divides once per primitive; the raster only
/// adds).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Interp {
    /// Value at the first left edge's crossing on the triangle's first sample row.
    pub seed: i64,
    /// Value at the lower edge's crossing on its first row: the re-seed at the middle vertex
    /// when the long edge is the right one (0 when the raster never re-seeds).
    pub reseed: i64,
    /// Gradient per sample column.
    pub dx: i64,
    /// Gradient per sample row.
    pub dy: i64,
}

/// A set-up triangle ready for the raster.
#[derive(Clone, Copy, Debug)]
pub struct TriSetup {
    /// Long edge (top to bottom vertex).
    pub long: Edge,
    /// Upper short edge.
    pub upper: Edge,
    /// Lower short edge.
    pub lower: Edge,
    /// Whether the long edge is the left one.
    pub long_is_left: bool,
    /// Intensity interpolator per channel (intensity-format LSBs; unused channels are 0).
    pub i: [Interp; 3],
    /// Depth interpolator (input z-format LSBs).
    pub z: Interp,
}

/// A set-up light point: a square of samples with a flat value.
#[derive(Clone, Copy, Debug)]
pub struct PointSetup {
    /// First and one-past-last sample column.
    pub c: (i64, i64),
    /// First and one-past-last sample row.
    pub k: (i64, i64),
    /// Depth code.
    pub z: i64,
    /// Intensity code per channel.
    pub i: [i64; 3],
}

/// Result of setup for one primitive. Triangles, the common case, stay unboxed (no
/// allocation per primitive); lines, which are few and twice as wide, are boxed.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum Setup {
    /// One triangle.
    Tri(TriSetup),
    /// A line expands to two triangles sharing an edge.
    Line(Box<[TriSetup; 2]>),
    /// An additive light point.
    Point(PointSetup),
    /// Zero area: nothing to draw.
    Degenerate,
}

/// Work counted by setup.
#[derive(Clone, Copy, Debug, Default)]
pub struct SetupWork {
    /// Triangles set up (lines count two).
    pub triangles: u64,
    /// Zero-area triangles dropped.
    pub degenerate: u64,
    /// Lines expanded.
    pub lines: u64,
    /// Light points.
    pub points: u64,
}

impl SetupWork {
    /// Counts primitive `p` set up as `s`, as [`setup`] does.
    pub fn tally(&mut self, p: &QPrim, s: &Setup) {
        let dead = matches!(s, Setup::Degenerate);
        match p {
            QPrim::Triangle(_) => {
                self.triangles += 1;
                self.degenerate += u64::from(dead);
            }
            QPrim::Line { .. } => {
                self.lines += 1;
                self.triangles += 2;
                self.degenerate += 2 * u64::from(dead);
            }
            QPrim::Point { .. } => self.points += 1,
        }
    }
}

/// A triangle's vertices in the order setup takes them: top to bottom, ties by `x` (a
/// canonical order, whatever order the primitive lists them in).
pub fn sorted(v: &[QVertex; 3]) -> [QVertex; 3] {
    let mut s = *v;
    s.sort_by_key(|p| (p.y, p.x));
    s
}

/// The two triangles a line of `width` units from `a` to `b` expands to (`None` for zero
/// length): a parallelogram whose minor-axis extent is exactly `width` units at every
/// position along the major axis, so the coverage per sample column / row is constant.
pub fn line_triangles(a: &QVertex, b: &QVertex, width: i64) -> Option<[[QVertex; 3]; 2]> {
    let (dx, dy) = ((b.x - a.x).abs(), (b.y - a.y).abs());
    if dx == 0 && dy == 0 {
        return None;
    }
    let lo = width / 2;
    let hi = width - lo;
    let off = |v: &QVertex, d: i64| {
        if dx >= dy {
            QVertex { y: v.y + d, ..*v }
        } else {
            QVertex { x: v.x + d, ..*v }
        }
    };
    let (a0, a1, b0, b1) = (off(a, -lo), off(a, hi), off(b, -lo), off(b, hi));
    Some([[a0, b0, b1], [a0, b1, a1]])
}

/// Sets up a triangle with `guard` interpolator guard bits; `None` for zero area.
pub fn triangle(v: &[QVertex; 3], g: &Grid, guard: u32) -> Option<TriSetup> {
    let s = sorted(v);
    let [v0, v1, v2] = s;
    let cross = (v1.x - v0.x) as i128 * (v2.y - v0.y) as i128
        - (v2.x - v0.x) as i128 * (v1.y - v0.y) as i128;
    if cross == 0 || v0.y == v2.y {
        return None;
    }
    let e = |a: QVertex, b: QVertex| {
        if b.y > a.y {
            Edge::new((a.x, a.y), (b.x, b.y), g)
        } else {
            Edge {
                k0: 0,
                k1: 0,
                q: 0,
                r: 0,
                a: 0,
                b: 0,
                d: 1,
            }
        }
    };
    let mut t = TriSetup {
        long: e(v0, v2),
        upper: e(v0, v1),
        lower: e(v1, v2),
        long_is_left: cross > 0,
        i: [Interp::default(); 3],
        z: Interp::default(),
    };
    // Where the raster seeds its interpolators: the first left edge on the first row, and
    // the lower edge on its first row when the left edge changes at the middle vertex.
    let at = |e: &Edge, k: i64| ((2 * e.q + 1) * g.h, (2 * k + 1) * g.h);
    let seed_at = at(t.first_left(), t.long.k0);
    let reseed_at = (!t.long_is_left && t.lower.k0 < t.lower.k1).then(|| at(&t.lower, t.lower.k0));
    let interp = |pl: Plane| Interp {
        seed: pl.eval(seed_at.0, seed_at.1, guard),
        reseed: reseed_at.map_or(0, |(x, y)| pl.eval(x, y, guard)),
        dx: pl.dx(2 * g.h, guard),
        dy: pl.dy(2 * g.h, guard),
    };
    for c in 0..3 {
        if s.iter().any(|p| p.i[c] != 0) {
            t.i[c] = interp(Plane::new(&s, |p| p.i[c]));
        }
    }
    t.z = interp(Plane::new(&s, |p| p.z));
    Some(t)
}

impl TriSetup {
    /// The left edge on the triangle's first row, where the raster seeds its interpolators:
    /// the long edge when it is the left one, else the upper edge unless it owns no row,
    /// then the lower one (which starts on that row).
    pub fn first_left(&self) -> &Edge {
        if self.long_is_left {
            &self.long
        } else if self.upper.k0 < self.upper.k1 {
            &self.upper
        } else {
            &self.lower
        }
    }
}

/// Sets up one primitive with `guard` interpolator guard bits.
pub fn setup(p: &QPrim, g: &Grid, guard: u32, work: &mut SetupWork) -> Setup {
    match p {
        QPrim::Triangle(v) => {
            work.triangles += 1;
            match triangle(v, g, guard) {
                Some(t) => Setup::Tri(t),
                None => {
                    work.degenerate += 1;
                    Setup::Degenerate
                }
            }
        }
        QPrim::Line { a, b, width } => {
            work.lines += 1;
            work.triangles += 2;
            let Some([p0, p1]) = line_triangles(a, b, *width) else {
                work.degenerate += 2;
                return Setup::Degenerate;
            };
            match (triangle(&p0, g, guard), triangle(&p1, g, guard)) {
                (Some(t0), Some(t1)) => Setup::Line(Box::new([t0, t1])),
                _ => {
                    work.degenerate += 2;
                    Setup::Degenerate
                }
            }
        }
        QPrim::Point { v, size } => {
            work.points += 1;
            let lo = v.x - size / 2;
            let top = v.y - size / 2;
            let span = |a: i64| {
                (
                    ceil_div(a - g.h, 2 * g.h),
                    ceil_div(a + size - g.h, 2 * g.h),
                )
            };
            Setup::Point(PointSetup {
                c: span(lo),
                k: span(top),
                z: v.z,
                i: v.i,
            })
        }
    }
}

/// The setup stage.
pub struct SetupStage;

impl Stage for SetupStage {
    type Fixed = usize;

    fn id(&self) -> StageId {
        StageId::Setup
    }

    fn plan(&self, _: &Scene, _: &HwConfig) -> Result<Need> {
        Ok(Need::yes(
            "every primitive needs edge and plane constants (the geometry path's only divides)",
        ))
    }

    fn key(&self, cx: &Cx) -> serde_json::Value {
        serde_json::json!({"grid": cx.layout.grid, "guard": cx.hw.raster.interp_guard_bits})
    }

    fn fixed(&self, cx: &Cx, taps: &mut Taps) -> Result<(usize, Facts)> {
        let mut w = SetupWork::default();
        let prims = &taps.fixed.prims().q;
        // On every core, straight into the pooled list; the counts follow from each
        // primitive and its setup (integers, the same on any thread count).
        let mut setups: Vec<Setup> = cx.pool.take(prims.len());
        let (g, guard) = (&cx.layout.grid, cx.hw.raster.interp_guard_bits);
        setups.par_extend(
            prims
                .par_iter()
                .map(|p| setup(p, g, guard, &mut SetupWork::default())),
        );
        for (p, s) in prims.iter().zip(&setups) {
            w.tally(p, s);
        }
        let n = setups.len();
        taps.fixed.setups = Some(Arc::new(setups));
        let facts = Facts {
            work: vec![
                ("triangles", w.triangles),
                ("degenerate", w.degenerate),
                ("lines", w.lines),
                ("points", w.points),
            ],
            ..Facts::default()
        };
        Ok((n, facts))
    }

    fn float(&self, _: &Cx, _: &usize, _: &mut Taps, _: &mut Notes) -> Result<()> {
        // The float raster works from the primitives directly: no float setup.
        Ok(())
    }

    fn local(&self, _: &Cx, _: &usize, _: &Taps, _: &Taps, _: &mut Notes) -> Option<LocalError> {
        None
    }

    fn tokens(&self, _: &Cx, n: &usize) -> Option<Tokens> {
        Some(Tokens {
            kind: TokenKind::Primitive,
            item: "primitives",
            items: vec![1; *n],
            port_bits: vec![],
            rows: vec![],
            stream: None,
        })
    }

    fn cost(&self, cx: &Cx, _: &usize) -> Cost {
        let cb = cx.hw.input.coord.format.total_bits();
        let ib = cx.hw.input.intensity.format.total_bits();
        Cost::new(
            vec![],
            vec![],
            vec![
                Unit::mul("edge start (x * dy)", 1, cb + 1, cb + 1),
                Unit::mul("edge step quotient (dx / dy)", 1, cb + 1, cb + 1),
                Unit::mul("plane gradient (divide)", 2, 2 * cb + ib, 2 * cb + 2),
            ],
        )
    }

    fn memories(&self, _: &Cx, _: &usize, _: &Taps) -> Vec<MemImage> {
        vec![]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tally_counts_as_setup_does() {
        let g = Grid::new(4, 4, 64, 64);
        let v = |x: i64, y: i64| QVertex {
            x,
            y,
            z: 5,
            i: [3, 0, 0],
        };
        let prims = [
            QPrim::Triangle([v(0, 0), v(300, 20), v(40, 500)]),
            QPrim::Triangle([v(0, 0), v(100, 100), v(200, 200)]),
            QPrim::Line {
                a: v(10, 10),
                b: v(400, 90),
                width: 16,
            },
            QPrim::Line {
                a: v(10, 10),
                b: v(10, 10),
                width: 16,
            },
            QPrim::Point {
                v: v(99, 99),
                size: 8,
            },
        ];
        let (mut by_setup, mut by_tally) = (SetupWork::default(), SetupWork::default());
        for p in &prims {
            let s = setup(p, &g, 2, &mut by_setup);
            by_tally.tally(p, &s);
        }
        let c = |w: SetupWork| (w.triangles, w.degenerate, w.lines, w.points);
        assert_eq!(c(by_setup), (6, 3, 2, 1));
        assert_eq!(c(by_tally), c(by_setup));
    }

    #[test]
    fn edge_walk_matches_exact_ceiling_on_every_row() {
        let g = Grid::new(4, 4, 64, 64);
        for &(top, bot) in &[
            ((3, 5), (200, 517)),
            ((400, 1), (-37, 999)),
            ((0, 0), (0, 100)),
            ((17, 2), (18, 900)),
        ] {
            let mut e = Edge::new(top, bot, &g);
            for k in e.k0..e.k1 {
                let yk = (2 * k + 1) * g.h;
                let num = (top.0 - g.h) * (bot.1 - top.1) + (yk - top.1) * (bot.0 - top.0);
                assert_eq!(e.q, ceil_div(num, 2 * g.h * (bot.1 - top.1)), "row {k}");
                assert!(0 <= e.r && e.r < e.d);
                e.step();
            }
        }
    }

    #[test]
    fn divisions_round_toward_the_right_side() {
        assert_eq!(floor_div(-7, 2), -4);
        assert_eq!(ceil_div(-7, 2), -3);
        assert_eq!(ceil_div(7, 2), 4);
        assert_eq!(div_round(5, 2), 3);
        assert_eq!(div_round(-5, 2), -2);
    }
}
