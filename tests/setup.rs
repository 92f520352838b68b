//! The setup stage (per-primitive edge and plane constants):
//!
//! * edge quotient/remainder stepping gives, on every sample row of the edge, the first
//!   sample column at or right of the exact crossing (`ceil((x_cross - h) / 2h)`), with the
//!   remainder invariant `q d - r = N` and the carry flag: exhaustively over small
//!   coordinate grids for several sample grids, and a proptest on large coordinates;
//! * the rows an edge owns are exactly those with `y_top <= y_k < y_bottom`;
//! * degenerate triangles (zero area after quantisation, zero-length lines) are dropped and
//!   counted, and draw nothing;
//! * lines become two triangles (a parallelogram of exactly the line's width along the
//!   minor axis; `triangles` counts 2 per line);
//! * an edge shared by two triangles gets identical constants in both, on opposite sides
//!   (the constants behind watertightness; tests/raster.rs checks the coverage itself);
//! * planes interpolate the vertex attributes exactly and round their gradients to nearest;
//! * light points cover the samples whose centres lie in their square;
//! * the stage's tokens are one per primitive.

mod common;

use common::{Rng, line, point, scene, steps_through, tri};
use igemu::config::HwConfig;
use igemu::pipeline::run_through;
use igemu::stage::input::{QPrim, QVertex};
use igemu::stage::setup::{self, Edge, Plane, Setup, SetupWork, TriSetup};
use igemu::stage::{Grid, RunOptions, StageId, TokenKind};
use proptest::prelude::*;

/// Sample grids `(n, sub_bits)`, including the tightest (`sub_bits = log2 n + 1`).
/// Interpolator guard bits handed to setup (edges do not depend on them).
const GUARD: u32 = 4;

const GRIDS: [(u32, u32); 7] = [(1, 1), (2, 2), (4, 3), (4, 4), (8, 4), (1, 4), (2, 5)];

/// Walks the edge over all its rows and checks every row against exact integer arithmetic.
fn check_edge(top: (i64, i64), bot: (i64, i64), g: &Grid) -> Result<u64, String> {
    let h = g.h;
    let (xa, ya, xb, yb) = (top.0 as i128, top.1 as i128, bot.0 as i128, bot.1 as i128);
    let (dx, dy) = (xb - xa, yb - ya);
    let hh = h as i128;
    let mut e = Edge::new(top, bot, g);
    // The rows: the first row centre at or below the top, the first at or below the bottom.
    let first_at_or_below = |y: i128| {
        let mut k = y.div_euclid(2 * hh) - 1;
        while (2 * k + 1) * hh < y {
            k += 1;
        }
        k as i64
    };
    if (e.k0, e.k1) != (first_at_or_below(ya), first_at_or_below(yb)) {
        return Err(format!("rows {}..{} of {top:?}-{bot:?}", e.k0, e.k1));
    }
    if e.a as i128 != dx.div_euclid(dy) || e.d as i128 != 2 * hh * dy {
        return Err(format!("step a {} d {} of {top:?}-{bot:?}", e.a, e.d));
    }
    let mut rows = 0;
    for k in e.k0..e.k1 {
        let yk = (2 * k as i128 + 1) * hh;
        // Crossing x_c = xa + (yk - ya) dx / dy; E is the first column whose centre
        // (2E + 1) h is at or right of it, so (2E - 1) h is left of it.
        let q = e.q as i128;
        let lhs = |c: i128| ((2 * c + 1) * hh - xa) * dy;
        let rhs = (yk - ya) * dx;
        if !(lhs(q) >= rhs && lhs(q - 1) < rhs) {
            return Err(format!("row {k}: E = {q} of {top:?}-{bot:?} on {g:?}"));
        }
        let n = (xa - hh) * dy + (yk - ya) * dx;
        let (r, d) = (e.r as i128, e.d as i128);
        if !(0 <= r && r < d && q * d - r == n) {
            return Err(format!("row {k}: r = {r}, d = {d}, q d - r != {n}"));
        }
        rows += 1;
        if k + 1 < e.k1 {
            let before = e.q;
            let carry = e.step();
            if carry != (e.q - before == e.a + 1) {
                return Err(format!("row {k}: carry flag {carry}"));
            }
        }
    }
    Ok(rows)
}

#[test]
fn edge_stepping_is_the_exact_ceiling_on_every_row_exhaustively() {
    let mut rows = 0;
    for (n, sub) in GRIDS {
        let g = Grid::new(n, sub, 16, 16);
        for ya in -6..=18i64 {
            for yb in ya + 1..=18 {
                for xa in -12..=12i64 {
                    for xb in -12..=12i64 {
                        rows += check_edge((xa, ya), (xb, yb), &g).unwrap();
                    }
                }
            }
        }
    }
    assert!(rows > 3_000_000, "{rows} rows");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Long and steep edges with large coordinates.
    #[test]
    fn edge_stepping_is_exact_on_large_coordinates(
        xa in -65536i64..65536, xb in -65536i64..65536,
        ya in -4096i64..4096, dy in 1i64..8192, grid in 0usize..7,
    ) {
        let (n, sub) = GRIDS[grid];
        let g = Grid::new(n, sub, 16, 16);
        prop_assert!(check_edge((xa, ya), (xb, ya + dy), &g).is_ok(), "{:?}", check_edge((xa, ya), (xb, ya + dy), &g));
    }
}

fn qv(x: i64, y: i64, z: i64, i: i64) -> QVertex {
    QVertex {
        x,
        y,
        z,
        i: [i, 0, 0],
    }
}

/// An edge of a set-up triangle: (top, bottom, constants, whether it is a left edge).
type SideEdge = ((i64, i64), (i64, i64), Edge, bool);

/// The three edges of triangle `v` as set up in `t`, leaving out horizontal edges (they
/// own no row).
fn edges(v: &[QVertex; 3], t: &TriSetup) -> Vec<SideEdge> {
    let [v0, v1, v2] = setup::sorted(v).map(|p| (p.x, p.y));
    [
        (v0, v2, t.long, t.long_is_left),
        (v0, v1, t.upper, !t.long_is_left),
        (v1, v2, t.lower, !t.long_is_left),
    ]
    .into_iter()
    .filter(|(a, b, _, _)| a.1 < b.1)
    .collect()
}

#[test]
fn shared_edges_have_identical_constants_on_opposite_sides() {
    let mut rng = Rng::new(21);
    let mut shared = 0;
    for round in 0..20_000 {
        let (n, sub) = GRIDS[round % GRIDS.len()];
        let g = Grid::new(n, sub, 64, 64);
        let span = 40 << sub;
        let mut pt = || {
            (
                (rng.next_u64() % span) as i64 - 8,
                (rng.next_u64() % span) as i64 - 8,
            )
        };
        let (p, q, r1, r2) = (pt(), pt(), pt(), pt());
        let side = |r: (i64, i64)| (q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0);
        if p.1 == q.1 || side(r1) == 0 || side(r2) == 0 || (side(r1) > 0) == (side(r2) > 0) {
            continue;
        }
        let v = |a: (i64, i64)| qv(a.0, a.1, 0, 0);
        // Each triangle lists its vertices in a different order.
        let (v1, v2) = ([v(p), v(q), v(r1)], [v(r2), v(q), v(p)]);
        let t1 = setup::triangle(&v1, &g, GUARD).expect("non-degenerate");
        let t2 = setup::triangle(&v2, &g, GUARD).expect("non-degenerate");
        let (top, bot) = if p.1 < q.1 { (p, q) } else { (q, p) };
        let find = |v: &[QVertex; 3], t: &TriSetup| {
            edges(v, t)
                .into_iter()
                .find(|e| (e.0, e.1) == (top, bot))
                .map(|e| (e.2, e.3))
        };
        let (e1, left1) = find(&v1, &t1).expect("the shared edge in the first");
        let (e2, left2) = find(&v2, &t2).expect("the shared edge in the second");
        assert_eq!(e1, e2, "{p:?}-{q:?} with {r1:?} / {r2:?}");
        assert_ne!(
            left1, left2,
            "the shared edge is left of one, right of the other"
        );
        shared += 1;
    }
    assert!(shared > 5000, "{shared}");
}

#[test]
fn degenerate_triangles_and_lines_are_dropped_and_counted() {
    // Non-degenerate for the host, zero area after quantisation to 1/16 px.
    let objects = [
        tri(
            [[1.0, 1.0, 0.5], [20.0, 1.01, 0.5], [40.0, 1.0, 0.5]],
            [0.5; 3],
        ), // flat
        tri(
            [[0.0, 0.0, 0.5], [10.0, 10.01, 0.5], [20.0, 20.0, 0.5]],
            [0.5; 3],
        ), // collinear
        tri(
            [[5.0, 5.0, 0.5], [5.01, 5.0, 0.5], [5.0, 5.01, 0.5]],
            [0.5; 3],
        ), // one point
        tri(
            [[2.0, 2.0, 0.5], [30.0, 4.0, 0.5], [8.0, 28.0, 0.5]],
            [0.5; 3],
        ), // drawn
        line([3.0, 3.0, 0.5], [3.01, 3.0, 0.5], 0.5, 1.0), // zero length
        line([3.0, 40.0, 0.5], [50.0, 44.0, 0.5], 0.5, 1.0), // drawn
        point(10.0, 10.0, 0.5, 0.5, 1.0),
    ]
    .concat();
    let s = scene(64, 48, 0.0, &objects);
    let h = HwConfig::default_config();
    let steps = steps_through(&s, &h, RunOptions::FAST, StageId::Raster);
    let (setup_step, raster_step) = (&steps[1], &steps[2]);
    let w = &setup_step.outcome.report.work;
    assert_eq!(w["triangles"], 4 + 2 * 2);
    assert_eq!(w["degenerate"], 3 + 2);
    assert_eq!((w["lines"], w["points"]), (2, 1));
    let setups = setup_step.outcome.taps.fixed.setups();
    let frags = raster_step.outcome.taps.fixed.frags();
    for (p, want_dropped) in [true, true, true, false, true, false, false]
        .iter()
        .enumerate()
    {
        let dropped = matches!(setups[p], Setup::Degenerate);
        assert_eq!(dropped, *want_dropped, "primitive {p}: {:?}", setups[p]);
        assert_eq!((frags.count(p) == 0), *want_dropped, "primitive {p}");
    }
    // One token per primitive, dropped or not, light points included.
    let tok = setup_step.outcome.tokens.clone().expect("setup has tokens");
    assert_eq!((tok.kind, tok.item), (TokenKind::Primitive, "primitives"));
    assert_eq!(tok.items, vec![1; 7]);
}

/// Twice the signed area of a triangle.
fn area2(v: &[QVertex; 3]) -> i64 {
    (v[1].x - v[0].x) * (v[2].y - v[0].y) - (v[2].x - v[0].x) * (v[1].y - v[0].y)
}

#[test]
fn lines_become_two_triangles_of_the_lines_width() {
    let mut rng = Rng::new(3);
    for round in 0..5000 {
        let (n, sub) = GRIDS[round % GRIDS.len()];
        let g = Grid::new(n, sub, 64, 64);
        let mut c = || (rng.next_u64() % 2000) as i64 - 500;
        let (a, b) = (qv(c(), c(), 7, 100), qv(c(), c(), 9, 300));
        let width = 1 + (rng.next_u64() % 64) as i64;
        let mut w = SetupWork::default();
        let s = setup::setup(&QPrim::Line { a, b, width }, &g, GUARD, &mut w);
        assert_eq!((w.triangles, w.lines), (2, 1));
        if a.x == b.x && a.y == b.y {
            assert!(matches!(s, Setup::Degenerate));
            assert_eq!(w.degenerate, 2);
            continue;
        }
        let Setup::Line(pair) = s else {
            panic!("{s:?}")
        };
        let [t0, t1] = *pair;
        // The set-up triangles are those of the line's two triangles.
        let [p0, p1] = setup::line_triangles(&a, &b, width).expect("not zero length");
        let set = |v: &[QVertex; 3]| setup::triangle(v, &g, GUARD).expect("non-degenerate");
        assert_eq!(
            format!("{:?}", (t0, t1)),
            format!("{:?}", (set(&p0), set(&p1)))
        );
        // The parallelogram's area is the major extent times the width.
        let major = (b.x - a.x).abs().max((b.y - a.y).abs());
        let (s0, s1) = (area2(&p0), area2(&p1));
        assert_eq!(
            s0.abs() + s1.abs(),
            2 * major * width,
            "{a:?} {b:?} {width}"
        );
        // Its corners: both end points moved along the minor axis by -w/2 and +w - w/2.
        let x_major = (b.x - a.x).abs() >= (b.y - a.y).abs();
        let mut corners: Vec<(i64, i64)> = p0.iter().chain(&p1).map(|p| (p.x, p.y)).collect();
        corners.sort();
        corners.dedup();
        let mut want = Vec::new();
        for e in [a, b] {
            for d in [-(width / 2), width - width / 2] {
                want.push(if x_major {
                    (e.x, e.y + d)
                } else {
                    (e.x + d, e.y)
                });
            }
        }
        want.sort();
        assert_eq!(corners, want);
        // The diagonal is an edge of both triangles with the same constants.
        let common: Vec<_> = edges(&p0, &t0)
            .into_iter()
            .filter_map(|e0| {
                edges(&p1, &t1)
                    .into_iter()
                    .find(|e1| (e1.0, e1.1) == (e0.0, e0.1))
                    .map(|e1| (e0, e1))
            })
            .collect();
        for (e0, e1) in &common {
            assert_eq!(e0.2, e1.2);
            assert_ne!(e0.3, e1.3);
        }
    }
    // Through the pipeline: `triangles` counts two per line.
    let objects: String = (0..5)
        .map(|k| {
            line(
                [2.0, 4.0 + 8.0 * k as f64, 0.5],
                [60.0, 7.0 + 8.0 * k as f64, 0.5],
                0.5,
                1.5,
            )
        })
        .collect();
    let (_, taps) = run_through(
        &scene(64, 48, 0.0, &objects),
        &HwConfig::default_config(),
        RunOptions::FAST,
        StageId::Setup,
    )
    .unwrap();
    assert!(
        taps.fixed
            .setups()
            .iter()
            .all(|s| matches!(s, Setup::Line(..)))
    );
    let steps = steps_through(
        &scene(64, 48, 0.0, &objects),
        &HwConfig::default_config(),
        RunOptions::FAST,
        StageId::Setup,
    );
    let w = &steps[1].outcome.report.work;
    assert_eq!((w["triangles"], w["lines"], w["degenerate"]), (10, 5, 0));
}

/// `num / den` rounded to nearest, ties up (`den > 0`).
fn nearest(num: i128, den: i128) -> i128 {
    (2 * num + den).div_euclid(2 * den)
}

#[test]
fn planes_interpolate_exactly_and_round_gradients_to_nearest() {
    let mut rng = Rng::new(77);
    let mut c = move || (rng.next_u64() % 4000) as i64 - 1000;
    let mut checked = 0;
    while checked < 3000 {
        let attr = [0; 3].map(|_| c().rem_euclid(1000) * 16_000 + c().rem_euclid(1000));
        let vs = [0, 1, 2].map(|k| qv(c(), c(), 0, attr[k]));
        let a = area2(&vs) as i128;
        if a == 0 {
            continue;
        }
        let pl = Plane::new(&vs, |p| p.i[0]);
        let g = (c().rem_euclid(16)) as u32;
        for k in 0..3 {
            assert_eq!(pl.eval(vs[k].x, vs[k].y, g), attr[k] << g, "vertex {k}");
        }
        // The exact value by barycentric weights (numerator over |2 area|), independent of
        // the plane's own form.
        let (x0, y0) = (vs[0].x as i128, vs[0].y as i128);
        let (x1, y1) = (vs[1].x as i128 - x0, vs[1].y as i128 - y0);
        let (x2, y2) = (vs[2].x as i128 - x0, vs[2].y as i128 - y0);
        let (a0, a1, a2) = (attr[0] as i128, attr[1] as i128, attr[2] as i128);
        let num = |x: i128, y: i128| {
            let (px, py) = (x - x0, y - y0);
            let l1 = px * y2 - py * x2;
            let l2 = x1 * py - y1 * px;
            (a0 * a + (a1 - a0) * l1 + (a2 - a0) * l2) * a.signum()
        };
        let det = a.abs();
        for _ in 0..5 {
            let (x, y) = (c(), c());
            let want = nearest(num(x as i128, y as i128) << g, det);
            assert_eq!(pl.eval(x, y, g) as i128, want);
        }
        let step = 1 + c().rem_euclid(16) as i128;
        let (n00, n10, n01) = (num(0, 0), num(1, 0), num(0, 1));
        assert_eq!(
            pl.dx(step as i64, g) as i128,
            nearest(((n10 - n00) * step) << g, det)
        );
        assert_eq!(
            pl.dy(step as i64, g) as i128,
            nearest(((n01 - n00) * step) << g, det)
        );
        checked += 1;
    }
}

#[test]
fn light_points_cover_the_samples_whose_centres_are_in_their_square() {
    let mut rng = Rng::new(8);
    for round in 0..20_000 {
        let (n, sub) = GRIDS[round % GRIDS.len()];
        let g = Grid::new(n, sub, 64, 64);
        let v = qv(
            (rng.next_u64() % 400) as i64 - 100,
            (rng.next_u64() % 400) as i64 - 100,
            3,
            40,
        );
        let size = 1 + (rng.next_u64() % 48) as i64;
        let mut w = SetupWork::default();
        let Setup::Point(p) = setup::setup(&QPrim::Point { v, size }, &g, GUARD, &mut w) else {
            panic!("a point")
        };
        assert_eq!((w.points, w.triangles, p.z, p.i[0]), (1, 0, 3, 40));
        // The square [centre - size/2, centre - size/2 + size) in coordinate units.
        for (span, centre) in [(p.c, v.x), (p.k, v.y)] {
            let lo = centre - size / 2;
            for c in span.0 - 3..span.1 + 3 {
                let x = (2 * c + 1) * g.h;
                let inside = lo <= x && x < lo + size;
                assert_eq!(
                    inside,
                    (span.0..span.1).contains(&c),
                    "{v:?} size {size} column {c} on {g:?}"
                );
            }
        }
    }
}
