//! The input stage (host vertices to fixed point):
//!
//! * coordinates are the code of the configured `input.coord` format that the configured
//!   rounding mode picks, against the `fixed` crate's rounding of the exact value, for
//!   random and tie vertices, several formats and every quantisation mode;
//! * intensity: full white is `2^int_bits - 1` integer codes (and the background too), an
//!   intensity above white saturates and is counted;
//! * the stage-local error is at most half an LSB for the round-to-nearest modes (and is
//!   larger for truncation, so the check can fail);
//! * overflow mode `ERROR` stops with `Error::Overflow` naming `input.x`, `input.y`,
//!   `input.z` or `input.intensity`; the host's guard band keeps coordinates in range;
//! * line widths and point sizes are rounded to the coordinate grid, at least one unit;
//! * in chunks on the threads: the same on one thread and two, and the first overflow in
//!   scene order is the error;
//! * tokens: vertices per primitive in processing order (surfaces in scene order, then
//!   light points);
//! * `input::footprint`: its quantised triangle is the stage's, and its pixel box holds
//!   every sample the raster later covers (whose pixel then lies in a binned tile).

mod common;

use common::{Rng, hw, line, point, round_with, scene, steps_through, tri};
use fixed::types::I64F64;
use igemu::config::{FilterKind, HwConfig};
use igemu::error::Error;
use igemu::fixed::{Overflow, QFormat, Quant};
use igemu::pipeline::run_through;
use igemu::scene::{FrontEndStats, HostScene, Primitive, Scene, ScreenVertex};
use igemu::stage::input::{self, QPrim, QVertex};
use igemu::stage::{RunOptions, StageId, TokenKind};
use proptest::prelude::*;

/// The exact code of `x` in a format with `frac` fraction bits, rounded with `q`.
fn exact(x: f64, frac: u32, q: Quant) -> i64 {
    let v = I64F64::from_num(x);
    assert_eq!(v.to_num::<f64>(), x, "{x} is not exact in I64F64");
    round_with(v << frac, q)
}

/// A random coordinate in `[lo, hi)`, a multiple of 2^-40 (exact in f64 and in I64F64).
fn coord(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    (rng.range(lo, hi) * (1u64 << 40) as f64).round() / (1u64 << 40) as f64
}

/// The quantised vertices of a primitive.
fn qverts(p: &QPrim) -> Vec<QVertex> {
    match *p {
        QPrim::Triangle(v) => v.to_vec(),
        QPrim::Line { a, b, .. } => vec![a, b],
        QPrim::Point { v, .. } => vec![v],
    }
}

/// The host vertices of a primitive.
fn hverts(p: &Primitive) -> Vec<ScreenVertex> {
    match *p {
        Primitive::Triangle(v) => v.to_vec(),
        Primitive::Line { a, b, .. } => vec![a, b],
        Primitive::Point { v, .. } => vec![v],
    }
}

/// The input step of a render: its report, tokens and taps.
fn input_step(s: &Scene, h: &HwConfig, opts: RunOptions) -> igemu::pipeline::Step {
    steps_through(s, h, opts, StageId::Input).remove(0)
}

/// Random triangles inside the guard band of a 64x48 screen (64 px), plus triangles whose
/// coordinates are exact ties of a `frac`-bit grid.
fn random_triangles(rng: &mut Rng, frac: u32) -> String {
    let mut objects = String::new();
    for _ in 0..8 {
        let mut v = || [coord(rng, -60.0, 124.0), coord(rng, -60.0, 108.0), 0.5];
        objects += &tri([v(), v(), v()], [0.3, 0.6, 0.9]);
    }
    let unit = (1u64 << frac) as f64;
    for _ in 0..4 {
        let mut tie = |lo: f64, hi: f64| ((rng.range(lo, hi) * unit).floor() + 0.5) / unit;
        let mut v = || [tie(-60.0, 124.0), tie(-60.0, 108.0), 0.5];
        objects += &tri([v(), v(), v()], [0.5; 3]);
    }
    objects
}

#[test]
fn coordinates_are_the_rounded_code_for_every_format_and_mode() {
    let formats = [
        (13, 4, 4),
        (9, 1, 1),
        (16, 2, 2),
        (12, 3, 4),
        (10, 6, 8),
        (11, 12, 8),
    ];
    let mut rng = Rng::new(0x1234_5678);
    let (mut checked, mut ties) = (0, 0);
    for (int_bits, frac, n) in formats {
        for q in Quant::ALL {
            let s = scene(64, 48, 0.0, &random_triangles(&mut rng, frac));
            let h = hw("linear12", |h| {
                h.input.coord.format = QFormat::new(true, int_bits, frac);
                h.input.coord.quant = q;
                h.raster.samples = n;
            });
            let (_, taps) = run_through(&s, &h, RunOptions::FAST, StageId::Input).unwrap();
            let (host, prims) = (taps.host(), &taps.fixed.prims().q);
            assert_eq!(host.prims.len(), prims.len());
            for (hp, qp) in host.prims.iter().zip(prims) {
                for (hv, qv) in hverts(hp).iter().zip(qverts(qp)) {
                    for (x, code) in [(hv.x, qv.x), (hv.y, qv.y)] {
                        let want = exact(x, frac, q);
                        assert_eq!(code, want, "Q{int_bits}.{frac} {q}: {x} px");
                        checked += 1;
                        ties += ((x * (1u64 << frac) as f64).fract().abs() == 0.5) as u32;
                    }
                }
            }
        }
    }
    assert!(
        checked >= 3000 && ties >= 1000,
        "{checked} values, {ties} ties"
    );
}

#[test]
fn full_white_is_the_top_integer_code() {
    for (int_bits, frac) in [(8, 0), (8, 4), (11, 4), (12, 0), (12, 4), (12, 8), (16, 6)] {
        let h = hw("linear12", |h| {
            h.input.intensity.format = QFormat::new(false, int_bits, frac);
            h.accumulate.frame.format.int_bits = int_bits;
        });
        let white = ((1i64 << int_bits) - 1) << frac;
        // Intensities that are multiples of 2^-16 times a white of <= 16 bits are exact in f64.
        let mut rng = Rng::new(int_bits as u64 * 31 + frac as u64);
        let mut objects = tri(
            [[1.0, 1.0, 0.5], [20.0, 2.0, 0.5], [5.0, 18.0, 0.5]],
            [1.0, 0.0, 0.5],
        );
        let mut is = vec![1.0, 0.0, 0.5];
        for _ in 0..10 {
            let i = [0; 3].map(|_| (rng.next_u64() % (1 << 16)) as f64 / (1u64 << 16) as f64);
            objects += &tri([[2.0, 3.0, 0.4], [30.0, 4.0, 0.4], [7.0, 25.0, 0.4]], i);
            is.extend(i);
        }
        let s = scene(32, 32, 1.0, &objects);
        let step = input_step(&s, &h, RunOptions::FAST);
        let prims = step.outcome.taps.fixed.prims();
        assert_eq!(
            prims.bg[0] as i64, white,
            "background 1.0 in UQ{int_bits}.{frac}"
        );
        let codes: Vec<i64> = prims.q.iter().flat_map(qverts).map(|v| v.i[0]).collect();
        assert_eq!(codes[0], white, "full white in UQ{int_bits}.{frac}");
        assert_eq!(codes[1], 0);
        for (&i, &c) in is.iter().zip(&codes) {
            let want = round_with(
                I64F64::from_num(i) * I64F64::from_num(white),
                Quant::RndConv,
            );
            assert_eq!(c, want, "intensity {i} in UQ{int_bits}.{frac}");
        }
        let st = &step.outcome.report.signals[3];
        assert_eq!((st.name.as_str(), st.overflows), ("input.intensity", 0));
    }
    // Above white saturates at the format's top code and is counted.
    let s = scene(32, 32, 0.0, &point(5.0, 5.0, 0.5, 1.5, 2.0));
    let step = input_step(&s, &HwConfig::default_config(), RunOptions::FAST);
    let QPrim::Point { v, .. } = step.outcome.taps.fixed.prims().q[0] else {
        panic!("a light point")
    };
    assert_eq!(v.i[0], (1 << 16) - 1);
    assert_eq!(step.outcome.report.signals[3].overflows, 1);
}

#[test]
fn stage_local_error_is_at_most_half_an_lsb_when_rounding_to_nearest() {
    let mut rng = Rng::new(99);
    let mut objects = String::new();
    for _ in 0..40 {
        let mut v = || {
            [
                rng.range(-60.0, 124.0),
                rng.range(-60.0, 108.0),
                rng.range(0.0, 0.99),
            ]
        };
        let (a, b, c) = (v(), v(), v());
        objects += &tri([a, b, c], [rng.range(0.0, 1.0), rng.range(0.0, 1.0), 0.7]);
    }
    let s = scene(64, 48, 0.0, &objects);
    for q in Quant::ALL {
        let h = hw("linear12", |h| {
            for x in [&mut h.input.coord, &mut h.input.z, &mut h.input.intensity] {
                x.quant = q;
            }
        });
        let step = input_step(&s, &h, RunOptions::default());
        let local = step
            .outcome
            .report
            .local
            .clone()
            .expect("input compares locally");
        assert_eq!(local.values, 40 * 3 * 4, "{q}: every x, y, z, intensity");
        if matches!(q, Quant::Trn | Quant::TrnZero) {
            // Truncation: errors up to (not including) one LSB, biased.
            assert!(
                local.max_abs_lsb > 0.5 && local.max_abs_lsb < 1.0,
                "{q}: {local:?}"
            );
            assert!(local.mean_lsb.abs() > 0.1, "{q}: {local:?}");
        } else {
            assert!(local.max_abs_lsb <= 0.5, "{q}: {local:?}");
            assert!(local.mean_lsb.abs() < 0.1, "{q}: {local:?}");
        }
    }
}

fn host(prims: Vec<Primitive>) -> HostScene {
    HostScene {
        width: 64,
        height: 48,
        background: [0.0; 3],
        channels: 1,
        prims,
        stats: FrontEndStats::default(),
    }
}

fn sv(x: f64, y: f64, z: f64, i: f64) -> ScreenVertex {
    ScreenVertex { x, y, z, i: [i; 3] }
}

#[test]
fn overflow_mode_error_names_the_signal() {
    let h = hw("linear12", |h| {
        for x in [&mut h.input.coord, &mut h.input.z, &mut h.input.intensity] {
            x.overflow = Overflow::Error;
        }
    });
    let ok = sv(10.0, 10.0, 0.5, 0.5);
    let cases = [
        (sv(5000.0, 10.0, 0.5, 0.5), "input.x", "Q13.4", 80000),
        (sv(10.0, -4097.0, 0.5, 0.5), "input.y", "Q13.4", -65552),
        (sv(10.0, 10.0, 1.0, 0.5), "input.z", "UQ0.24", 1 << 24),
        (
            sv(10.0, 10.0, 0.5, 2.0),
            "input.intensity",
            "UQ12.4",
            2 * 4095 * 16,
        ),
    ];
    for (bad, name, fmt, value) in cases {
        let e = input::quantize(&host(vec![Primitive::Triangle([ok, bad, ok])]), &h, 1)
            .err()
            .unwrap_or_else(|| panic!("{name}: no error"));
        let msg = e.to_string();
        match e {
            Error::Overflow {
                signal,
                format,
                value: v,
                ..
            } => {
                assert_eq!((signal.as_str(), format.as_str(), v), (name, fmt, value));
            }
            other => panic!("{name}: {other}"),
        }
        assert!(msg.contains(name) && msg.contains("ERROR"), "{msg}");
        // The same vertex under SAT: the top (or bottom) code, counted.
        let sat = input::quantize(
            &host(vec![Primitive::Triangle([ok, bad, ok])]),
            &HwConfig::default_config(),
            1,
        )
        .unwrap();
        let st = sat.signals.iter().find(|s| s.name == name).unwrap();
        assert_eq!(st.overflows, 1, "{name}");
    }
    // Through the pipeline: coordinates far outside the screen are clipped by the host to
    // the guard band, which the format holds, so ERROR never fires on them ...
    let far = tri(
        [[-1.0e5, -1.0e5, 0.5], [1.0e5, 5.0, 0.5], [5.0, 1.0e5, 0.5]],
        [0.5; 3],
    );
    input_step(&scene(64, 48, 0.0, &far), &h, RunOptions::FAST);
    // ... an intensity above white does.
    let bright = scene(64, 48, 0.0, &point(5.0, 5.0, 0.5, 1.5, 1.0));
    let plan = igemu::pipeline::plan::build(&bright, &h).unwrap();
    let e = igemu::pipeline::run::run(&bright, &h, &plan, RunOptions::FAST, None, None)
        .err()
        .expect("overflow");
    assert!(
        matches!(&e, Error::Overflow { signal, .. } if signal == "input.intensity"),
        "{e}"
    );
    // A format too narrow for the screen plus the guard band is refused by the plan.
    let narrow = hw("linear12", |h| {
        h.input.coord.format = QFormat::new(true, 8, 4)
    });
    let e = igemu::pipeline::plan::build(&bright, &narrow)
        .err()
        .unwrap();
    assert!(e.to_string().contains("input.coord"), "{e}");
}

#[test]
fn line_widths_and_point_sizes_are_at_least_one_unit() {
    for frac in [1u32, 2, 4, 6] {
        let n = if frac == 1 { 1 } else { 2 };
        let h = hw("linear12", |h| {
            h.input.coord.format = QFormat::new(true, 13, frac);
            h.raster.samples = n;
        });
        let sizes = [0.001, 0.03, 0.0625, 0.09, 0.1, 0.53, 2.0, 7.3];
        let mut objects = String::new();
        for (k, &w) in sizes.iter().enumerate() {
            let y = 2.0 + 4.0 * k as f64;
            objects += &line([2.0, y, 0.5], [40.0, y + 1.0, 0.5], 0.5, w);
            objects += &point(50.0, y, 0.5, 0.5, w);
        }
        let step = input_step(&scene(64, 48, 0.0, &objects), &h, RunOptions::FAST);
        let prims = &step.outcome.taps.fixed.prims().q;
        let unit = (1u64 << frac) as f64;
        for (k, &w) in sizes.iter().enumerate() {
            let want = ((w * unit).round() as i64).max(1);
            match (prims[2 * k], prims[2 * k + 1]) {
                (QPrim::Line { width, .. }, QPrim::Point { size, .. }) => {
                    assert_eq!((width, size), (want, want), "{w} px at {frac} bits");
                }
                other => panic!("{other:?}"),
            }
        }
    }
}

#[test]
fn tokens_are_vertices_per_primitive_surfaces_first_then_light_points() {
    let t = tri(
        [[1.0, 1.0, 0.5], [20.0, 2.0, 0.5], [5.0, 18.0, 0.5]],
        [0.5; 3],
    );
    let l = line([2.0, 30.0, 0.5], [30.0, 35.0, 0.5], 0.5, 1.0);
    let p = point(40.0, 10.0, 0.5, 0.5, 1.0);
    let mut rng = Rng::new(5);
    for round in 0..20 {
        let kinds: Vec<u64> = if round == 0 {
            vec![1, 3, 2, 1, 3, 2]
        } else {
            (0..1 + rng.next_u64() % 9)
                .map(|_| 1 + rng.next_u64() % 3)
                .collect()
        };
        let objects: String = kinds
            .iter()
            .map(|k| match k {
                3 => t.as_str(),
                2 => l.as_str(),
                _ => p.as_str(),
            })
            .collect();
        let step = input_step(
            &scene(64, 48, 0.0, &objects),
            &HwConfig::default_config(),
            RunOptions::FAST,
        );
        let tok = step.outcome.tokens.clone().expect("input has tokens");
        assert_eq!((tok.kind, tok.item), (TokenKind::Primitive, "vertices"));
        let mut want: Vec<u64> = kinds.iter().copied().filter(|&k| k > 1).collect();
        want.extend(kinds.iter().copied().filter(|&k| k == 1));
        assert_eq!(tok.items, want, "scene order {kinds:?}");
        if round == 0 {
            assert_eq!(want, [3, 2, 3, 2, 1, 1]);
        }
        let work = &step.outcome.report.work;
        assert_eq!(work["vertices"], kinds.iter().sum::<u64>());
        assert_eq!(work["primitives"], kinds.len() as u64);
    }
}

/// Checks the footprint of every primitive of a render against the raster's fragments.
fn footprints_hold_the_fragments(s: &Scene, h: &HwConfig) -> Result<u64, TestCaseError> {
    let (plan, taps) = run_through(s, h, RunOptions::FAST, StageId::Raster).unwrap();
    let l = &plan.layout;
    let (reg, n) = (l.samples, l.grid.n as i64);
    let host = taps.host();
    let frags = taps.fixed.frags();
    let mut seen = 0u64;
    for (p, hp) in host.prims.iter().enumerate() {
        let fp = input::footprint(hp, h, 0);
        if let QPrim::Triangle(v) = taps.fixed.prims().q[p] {
            prop_assert_eq!(fp.triangle, Some(v.map(|v| (v.x, v.y))));
        }
        let [x0, y0, x1, y1] = fp.pixels;
        for f in frags.of(p) {
            let (c, k) = (
                reg.c0 + f.s as i64 % reg.width() as i64,
                reg.k0 + f.s as i64 / reg.width() as i64,
            );
            let (px, py) = (c.div_euclid(n), k.div_euclid(n));
            prop_assert!(
                (x0..x1).contains(&px) && (y0..y1).contains(&py),
                "primitive {} sample ({}, {}) in pixel ({}, {}) outside {:?}",
                p,
                c,
                k,
                px,
                py,
                fp.pixels
            );
            let on_screen =
                px >= 0 && py >= 0 && px < l.grid.width as i64 && py < l.grid.height as i64;
            if on_screen {
                let (ux, uy) = (px as u32, py as u32);
                let r = &l.region;
                prop_assert!(ux >= r.x0 && ux < r.x1 && uy >= r.y0 && uy < r.y1);
                prop_assert!(
                    l.tiles.is_touched(ux, uy),
                    "pixel ({}, {}) not binned",
                    ux,
                    uy
                );
            }
            seen += 1;
        }
    }
    Ok(seen)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// Every sample the raster covers lies in its primitive's footprint (and a binned tile).
    #[test]
    fn footprints_contain_every_covered_sample(seed in any::<u64>(), n_log in 0u32..4, filter in 0usize..3, sub in 0u32..3) {
        let mut rng = Rng::new(seed);
        let mut objects = String::new();
        for k in 0..1 + rng.next_u64() % 6 {
            // Large, small and sliver triangles, on and off the screen (inside the guard band).
            let size = [2.0, 12.0, 80.0][(k % 3) as usize];
            let (cx, cy) = (rng.range(-20.0, 70.0), rng.range(-20.0, 60.0));
            let mut v = || [cx + rng.range(-size, size), cy + rng.range(-size, size), rng.range(0.0, 1.0)];
            let (a, b, mut c) = (v(), v(), v());
            if k % 4 == 3 {
                // A sliver: the third vertex near the first edge.
                c = [(a[0] + b[0]) / 2.0 + 0.03, (a[1] + b[1]) / 2.0, 0.5];
            }
            objects += &tri([a, b, c], [0.5; 3]);
        }
        for _ in 0..rng.next_u64() % 3 {
            let mut v = || [rng.range(-10.0, 60.0), rng.range(-10.0, 50.0), 0.3];
            let (a, b) = (v(), v());
            objects += &line(a, b, 0.6, rng.range(0.05, 3.0));
            objects += &point(rng.range(-3.0, 52.0), rng.range(-3.0, 44.0), 0.2, 0.8, rng.range(0.05, 4.0));
        }
        let s = scene(48, 40, 0.0, &objects);
        let n = 1u32 << n_log;
        let h = hw("linear12", |h| {
            h.raster.samples = n;
            h.input.coord.format.frac_bits = n_log + 1 + sub;
            h.accumulate.filter = [FilterKind::Box, FilterKind::Tent, FilterKind::Gaussian][filter];
            h.cycles.tile = 8;
        });
        footprints_hold_the_fragments(&s, &h)?;
    }
}

#[test]
fn footprints_hold_the_default_scene() {
    let s = Scene::default_scene();
    let seen = footprints_hold_the_fragments(&s, &HwConfig::default_config()).unwrap();
    assert!(seen > 1_000_000, "{seen} fragments");
}

/// The stage quantises in chunks of primitives on the threads: the primitives, every
/// signal's statistics (float error sums to the bit) and the local error are the same on
/// one thread and two, equal to the serial quantisation's in codes, counts and ranges; the
/// sums agree with the serial ones to rounding. With overflow mode ERROR the error is the
/// first overflowing vertex in scene order, thousands of primitives apart.
#[test]
fn chunked_quantisation_is_deterministic_and_keeps_scene_order() {
    let mut rng = Rng::new(11);
    let mut v = || {
        sv(
            rng.range(0.0, 64.0),
            rng.range(0.0, 48.0),
            rng.range(0.0, 1.0),
            rng.range(0.0, 1.0),
        )
    };
    let prims: Vec<Primitive> = (0..5000)
        .map(|_| Primitive::Triangle([v(), v(), v()]))
        .collect();
    let h = HwConfig::default_config();
    let on = |threads: usize, prims: &[Primitive], h: &HwConfig| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| input::quantize(&host(prims.to_vec()), h, 1))
    };
    let (one, two) = (on(1, &prims, &h).unwrap(), on(2, &prims, &h).unwrap());
    assert_eq!(one.prims, two.prims);
    assert_eq!(one.local, two.local);
    assert_eq!(one.vertices, 15000);
    let serial: Vec<_> = prims
        .iter()
        .map(|p| input::quantize(&host(vec![*p]), &h, 1).unwrap())
        .collect();
    assert_eq!(
        one.prims,
        serial.iter().map(|q| q.prims[0]).collect::<Vec<_>>()
    );
    for (k, (a, b)) in one.signals.iter().zip(&two.signals).enumerate() {
        assert_eq!(
            serde_json::to_value(a).unwrap(),
            serde_json::to_value(b).unwrap()
        );
        let count: u64 = serial.iter().map(|q| q.signals[k].count).sum();
        let err: f64 = serial.iter().map(|q| q.signals[k].err_sum).sum();
        assert_eq!(a.count, count, "{}", a.name);
        assert_eq!(a.min, serial.iter().filter_map(|q| q.signals[k].min).min());
        assert_eq!(a.max, serial.iter().filter_map(|q| q.signals[k].max).max());
        assert!((a.err_sum - err).abs() < 1e-9 * count as f64, "{}", a.name);
    }
    // Two bad vertices far apart: the first one in scene order is named.
    let mut h = HwConfig::default_config();
    h.input.coord.overflow = Overflow::Error;
    let mut bad = prims.clone();
    bad[1500] = Primitive::Triangle([
        sv(10.0, 10.0, 0.5, 0.5),
        sv(5000.0, 10.0, 0.5, 0.5),
        sv(10.0, 10.0, 0.5, 0.5),
    ]);
    bad[4200] = Primitive::Triangle([sv(6000.0, 10.0, 0.5, 0.5); 3]);
    for threads in [1, 2] {
        match on(threads, &bad, &h) {
            Err(Error::Overflow { signal, value, .. }) => {
                assert_eq!(
                    (signal.as_str(), value),
                    ("input.x", 80000),
                    "{threads} threads"
                );
            }
            other => panic!("{threads} threads: {:?}", other.err()),
        }
    }
}

/// `input::footprints` of a scene of more primitives than a part (run on the threads)
/// are each primitive's `input::footprint`, in scene order, on one thread and on two.
#[test]
fn footprints_of_many_primitives_keep_the_scene_order() {
    let mut rng = Rng::new(0x5eed_f00d);
    let mut prims = Vec::new();
    for k in 0..9000 {
        let v = |rng: &mut Rng| sv(rng.range(-8.0, 72.0), rng.range(-8.0, 56.0), 0.5, 0.5);
        prims.push(match k % 50 {
            0 => Primitive::Point {
                v: v(&mut rng),
                size: 3.0,
            },
            1 => Primitive::Line {
                a: v(&mut rng),
                b: v(&mut rng),
                width: 1.5,
            },
            _ => Primitive::Triangle([v(&mut rng), v(&mut rng), v(&mut rng)]),
        });
    }
    let h = HwConfig::default_config();
    let apron = h.accumulate.filter.base() as i64 / 2 + 1;
    let serial: Vec<_> = prims
        .iter()
        .map(|p| input::footprint(p, &h, apron))
        .collect();
    let hs = host(prims);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        assert_eq!(
            pool.install(|| input::footprints(&hs, &h)),
            serial,
            "{threads} threads"
        );
    }
}
