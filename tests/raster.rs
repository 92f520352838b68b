//! Raster (with setup): watertightness, the top-left rule, degenerate and hard cases,
//! and interpolation drift against the float reference on the same quantised input.

mod common;

use common::Rng;
use igemu::fixed::Quant;
use igemu::stage::Grid;
use igemu::stage::Pool;
use igemu::stage::input::{QPrim, QVertex};
use igemu::stage::raster::{
    self, FPrim, Frag, FragF, PART_ROWS, RasterParams, RasterWork, Run, SampleRegion,
};
use igemu::stage::setup::{self, SetupWork};
use proptest::prelude::*;

const SUB: u32 = 4;

fn params(n: u32, w: u32, h: u32) -> (RasterParams, SampleRegion) {
    let grid = Grid::new(n, SUB, w, h);
    let p = RasterParams {
        grid,
        guard: 14,
        quant: Quant::RndConv,
        i_max: [(1 << 16) - 1; 3],
        channels: 1,
        z_max: (1 << 24) - 1,
    };
    let reg = SampleRegion {
        c0: 0,
        k0: 0,
        c1: grid.sw() as i64,
        k1: grid.sh() as i64,
    };
    (p, reg)
}

fn v(x: f64, y: f64, z: i64, i: i64) -> QVertex {
    QVertex {
        x: (x * 16.0).round() as i64,
        y: (y * 16.0).round() as i64,
        z,
        i: [i, 0, 0],
    }
}

/// Coverage count of every sample of the region.
fn coverage(prims: &[QPrim], p: &RasterParams, reg: &SampleRegion) -> Vec<u32> {
    let mut count = vec![0u32; reg.len()];
    let mut frags = Vec::new();
    let (mut sw, mut rw) = (SetupWork::default(), RasterWork::default());
    for q in prims {
        frags.clear();
        raster::raster(
            &setup::setup(q, &p.grid, p.guard, &mut sw),
            p,
            reg,
            &mut frags,
            &mut rw,
        );
        for f in &frags {
            count[f.s as usize] += 1;
        }
    }
    count
}

/// A jittered grid mesh whose outer vertices lie outside the screen: it must cover every
/// on-screen sample exactly once, whatever the diagonals.
fn mesh(rng: &mut Rng, m: usize, w: f64, h: f64) -> Vec<QPrim> {
    let mut pts = vec![vec![(0.0, 0.0); m + 1]; m + 1];
    for (j, row) in pts.iter_mut().enumerate() {
        for (i, p) in row.iter_mut().enumerate() {
            let edge = i == 0 || j == 0 || i == m || j == m;
            let (fx, fy) = (i as f64 / m as f64, j as f64 / m as f64);
            let jit = if edge { 0.0 } else { 0.3 };
            *p = (
                -3.0 + (w + 6.0) * (fx + jit * rng.range(-0.5, 0.5) / m as f64),
                -3.0 + (h + 6.0) * (fy + jit * rng.range(-0.5, 0.5) / m as f64),
            );
        }
    }
    let mut out = Vec::new();
    for j in 0..m {
        for i in 0..m {
            let a = v(pts[j][i].0, pts[j][i].1, 5, 100);
            let b = v(pts[j][i + 1].0, pts[j][i + 1].1, 5, 100);
            let c = v(pts[j + 1][i].0, pts[j + 1][i].1, 5, 100);
            let d = v(pts[j + 1][i + 1].0, pts[j + 1][i + 1].1, 5, 100);
            if rng.next_u64() & 1 == 0 {
                out.push(QPrim::Triangle([a, b, d]));
                out.push(QPrim::Triangle([a, d, c]));
            } else {
                out.push(QPrim::Triangle([a, b, c]));
                out.push(QPrim::Triangle([b, d, c]));
            }
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// (a) Watertight: random meshes cover every sample exactly once (no hole, no double hit).
    #[test]
    fn watertight_random_meshes(seed in any::<u64>(), m in 1usize..9, n_log in 0u32..4) {
        let n = 1 << n_log;
        let (p, reg) = params(n, 24, 18);
        let mut rng = Rng::new(seed);
        let c = coverage(&mesh(&mut rng, m, 24.0, 18.0), &p, &reg);
        prop_assert!(c.iter().all(|&x| x == 1), "holes {} double hits {}", c.iter().filter(|&&x| x == 0).count(), c.iter().filter(|&&x| x > 1).count());
    }

    /// (a) Watertight: random fans around a centre, ring outside the screen.
    #[test]
    fn watertight_random_fans(seed in any::<u64>(), spokes in 3usize..40) {
        let (p, reg) = params(4, 20, 20);
        let mut rng = Rng::new(seed);
        let (cx, cy) = (rng.range(2.0, 18.0), rng.range(2.0, 18.0));
        let mut angles: Vec<f64> = (0..spokes).map(|_| rng.range(0.0, std::f64::consts::TAU)).collect();
        angles.sort_by(|a, b| a.partial_cmp(b).unwrap());
        // Keep consecutive spokes under pi apart so the ring encloses the screen.
        let ok = angles.windows(2).all(|w| w[1] - w[0] < 2.5) && angles[0] + std::f64::consts::TAU - angles[spokes - 1] < 2.5;
        prop_assume!(ok);
        let ring: Vec<QVertex> = angles.iter().map(|a| v(cx + 80.0 * a.cos(), cy + 80.0 * a.sin(), 1, 7)).collect();
        let centre = v(cx, cy, 1, 7);
        let prims: Vec<QPrim> = (0..spokes).map(|i| QPrim::Triangle([centre, ring[i], ring[(i + 1) % spokes]])).collect();
        let c = coverage(&prims, &p, &reg);
        prop_assert!(c.iter().all(|&x| x == 1));
    }
}

/// Random triangles, lines and light points over a `w` x `h` pixel screen, some reaching
/// past its edges.
fn random_prims(rng: &mut Rng, n: usize, w: f64, h: f64) -> Vec<QPrim> {
    let pt = |rng: &mut Rng| {
        v(
            rng.range(-0.2 * w, 1.2 * w),
            rng.range(-0.2 * h, 1.2 * h),
            rng.bits(20) as i64,
            rng.bits(12) as i64,
        )
    };
    (0..n)
        .map(|k| match k % 5 {
            3 => QPrim::Line {
                a: pt(rng),
                b: pt(rng),
                width: 1 + rng.bits(6) as i64,
            },
            4 => QPrim::Point {
                v: pt(rng),
                size: 1 + rng.bits(7) as i64,
            },
            _ => QPrim::Triangle([pt(rng), pt(rng), pt(rng)]),
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// The frame's walk on the threads (bands, their runs in parts of PART_ROWS rows) holds
    /// exactly the whole-region walk's runs: each part's runs of a primitive are that
    /// primitive's runs in the part's rows, in the walker's order; the parts tile the
    /// region in order; the samples stepped per primitive and the work are the same; a
    /// second frame on the recycled lists gives the same parts.
    #[test]
    fn parts_hold_the_whole_region_walk(seed in any::<u64>(), n in 1usize..40, h in 40u32..160) {
        let (p, reg) = params(4, 48, h);
        let mut rng = Rng::new(seed);
        let prims = random_prims(&mut rng, n, 48.0, f64::from(h));
        let mut sw = SetupWork::default();
        let setups: Vec<_> = prims.iter().map(|q| setup::setup(q, &p.grid, p.guard, &mut sw)).collect();
        let pool = Pool::new();
        let (frags, stepped, work) = raster::walk(&setups, &p, &reg, true, &pool);
        let mut whole_work = RasterWork::default();
        let whole: Vec<Vec<Run>> = setups.iter().enumerate().map(|(q, s)| {
            let (mut runs, before) = (Vec::new(), whole_work.samples + whole_work.walked);
            raster::raster_rows(s, &p, &reg, (reg.k0, reg.k1), true, &mut runs, &mut whole_work);
            prop_assert_eq!(stepped[q], whole_work.samples + whole_work.walked - before);
            Ok(runs)
        }).collect::<Result<_, _>>()?;
        prop_assert_eq!(work, whole_work);
        let width = reg.width();
        let mut end = 0;
        for ((&(a, b), data), spans) in frags.bounds.iter().zip(&frags.parts).zip(&frags.spans) {
            prop_assert_eq!(a, end);
            prop_assert!(b > a && b - a <= PART_ROWS as usize * width);
            end = b;
            prop_assert!(spans.windows(2).all(|s| s[0].prim < s[1].prim && s[0].b == s[1].a));
            for sp in spans {
                let want: Vec<Run> = whole[sp.prim as usize]
                    .iter()
                    .filter(|r| (a..b).contains(&(r.s as usize)))
                    .copied()
                    .collect();
                prop_assert_eq!(&data[sp.a..sp.b], &want[..]);
            }
        }
        prop_assert_eq!(end, reg.len());
        for (q, runs) in whole.iter().enumerate() {
            let n: usize = frags.of(q).map(<[Run]>::len).sum();
            prop_assert_eq!(n, runs.len());
        }
        pool.give(frags.parts.clone());
        pool.give(frags.spans.clone());
        let (again, ..) = raster::walk(&setups, &p, &reg, true, &pool);
        prop_assert_eq!(&again.parts, &frags.parts);
        prop_assert_eq!(&again.spans, &frags.spans);
    }
}

#[test]
fn top_left_rule_on_sample_aligned_edges() {
    // A 2x2-pixel square whose edges pass exactly through sample centres (n = 4: centres
    // at 1/8 + k/4 px). Left and top edges are inside, right and bottom outside: the
    // square [1.125, 3.125) covers exactly 8 columns and 8 rows.
    let (p, reg) = params(4, 8, 8);
    let (a, b, c, d) = (
        v(1.125, 1.125, 0, 0),
        v(3.125, 1.125, 0, 0),
        v(3.125, 3.125, 0, 0),
        v(1.125, 3.125, 0, 0),
    );
    let cov = coverage(
        &[QPrim::Triangle([a, b, c]), QPrim::Triangle([a, c, d])],
        &p,
        &reg,
    );
    assert_eq!(cov.iter().filter(|&&x| x == 1).count(), 64);
    assert!(cov.iter().all(|&x| x <= 1));
    let sw = reg.width();
    // Column 4 (x = 1.125) is in, column 12 (x = 3.125) is out; same for rows.
    assert_eq!(cov[4 * sw + 4], 1);
    assert_eq!(cov[4 * sw + 12], 0);
    assert_eq!(cov[12 * sw + 4], 0);
}

#[test]
fn zero_area_and_degenerate_triangles_draw_nothing() {
    let (p, reg) = params(4, 16, 16);
    let cases = [
        [v(1.0, 1.0, 0, 0), v(1.0, 1.0, 0, 0), v(1.0, 1.0, 0, 0)], // a point
        [v(1.0, 1.0, 0, 0), v(5.0, 5.0, 0, 0), v(9.0, 9.0, 0, 0)], // collinear
        [v(1.0, 3.0, 0, 0), v(5.0, 3.0, 0, 0), v(12.0, 3.0, 0, 0)], // horizontal
        [v(-5.0, -5.0, 0, 0), v(-5.0, 30.0, 0, 0), v(-5.0, 2.0, 0, 0)], // vertical, off-screen
    ];
    let mut work = SetupWork::default();
    for t in cases {
        assert!(matches!(
            setup::setup(&QPrim::Triangle(t), &p.grid, p.guard, &mut work),
            setup::Setup::Degenerate
        ));
        assert!(
            coverage(&[QPrim::Triangle(t)], &p, &reg)
                .iter()
                .all(|&x| x == 0)
        );
    }
    assert_eq!(work.degenerate, 4);
}

#[test]
fn sliver_1000_px_long_under_one_sample_wide() {
    // Width 0.1 px at n = 4 (sample spacing 0.25 px): covers a sample on some rows only.
    let (p, reg) = params(4, 1100, 8);
    let a = v(20.0, 2.0, 0, 0);
    let b = v(1020.0, 2.0 + 0.5, 0, 0);
    let c = v(1020.0, 2.6, 0, 0);
    let d = v(20.0, 2.1, 0, 0);
    let prims = [QPrim::Triangle([a, b, c]), QPrim::Triangle([a, c, d])];
    let cov = coverage(&prims, &p, &reg);
    let hits = cov.iter().filter(|&&x| x == 1).count();
    assert!(cov.iter().all(|&x| x <= 1), "shared edge hit twice");
    // Area 1000 px * 0.1 px = 100 px^2 = 1600 samples on average; a sampling estimate.
    assert!((1200..=2000).contains(&hits), "{hits} samples");
}

/// Fixed raster vs float raster fed the same quantised triangle.
fn drift(t: [QVertex; 3], n: u32, w: u32, h: u32, guard: u32) -> (f64, u64, u64) {
    let (mut p, reg) = params(n, w, h);
    p.guard = guard;
    let mut sw = SetupWork::default();
    let mut rw = RasterWork::default();
    let mut fx: Vec<Frag> = Vec::new();
    raster::raster(
        &setup::setup(&QPrim::Triangle(t), &p.grid, p.guard, &mut sw),
        &p,
        &reg,
        &mut fx,
        &mut rw,
    );
    let mut fl: Vec<FragF> = Vec::new();
    raster::raster_f64(
        &FPrim::from_q(&QPrim::Triangle(t), SUB),
        &p.grid,
        &reg,
        &mut fl,
    );
    let mut max = 0.0f64;
    let mut mismatch = 0;
    let mut it = fl.iter().peekable();
    for f in &fx {
        while it.peek().is_some_and(|g| g.s < f.s) {
            it.next();
            mismatch += 1;
        }
        match it.peek() {
            Some(g) if g.s == f.s => {
                max = max.max((f.i[0] as f64 - g.i[0]).abs());
                it.next();
            }
            _ => mismatch += 1,
        }
    }
    (max, mismatch, fx.len() as u64)
}

#[test]
fn long_thin_triangle_interpolation_drift_is_bounded() {
    // 2000 px long, intensity ramps over the full 16-bit range: the add-only interpolator
    // walks ~8000 sample rows and ~8000 columns.
    let t = [
        v(3.0, 1.0, 0, 0),
        v(2003.0, 9.0, 1 << 20, 65535),
        v(3.0, 11.0, 1 << 20, 30000),
    ];
    let (max, mismatch, n) = drift(t, 4, 2010, 12, 14);
    assert_eq!(mismatch, 0, "coverage differs from the exact rule");
    assert!(n > 10_000);
    // Bound: 1/2 LSB output rounding + steps * 2^-(guard+1) per gradient rounding
    // (< 16000 steps * 2^-15 ~ 0.49 LSB), so < 1 LSB.
    assert!(max < 1.0, "drift {max} LSB with 14 guard bits");
    // With too few guard bits the drift is visible: the test would catch a regression in
    // gradient rounding.
    let (max_small, _, _) = drift(t, 4, 2010, 12, 2);
    assert!(max_small > max, "{max_small} vs {max}");
    eprintln!(
        "drift over a 2000 px triangle: {max:.3} LSB (14 guard bits), {max_small:.1} LSB (2 guard bits)"
    );
}

#[test]
fn fixed_coverage_equals_exact_rule_on_random_triangles() {
    let mut rng = Rng::new(7);
    let mut total = 0;
    for _ in 0..300 {
        let mut p = || v(rng.range(-20.0, 84.0), rng.range(-20.0, 84.0), 0, 1000);
        let t = [p(), p(), p()];
        let (max, mismatch, n) = drift(t, 4, 64, 64, 14);
        assert_eq!(mismatch, 0);
        assert!(max <= 1.0, "{max}");
        total += n;
    }
    assert!(total > 10_000);
}
