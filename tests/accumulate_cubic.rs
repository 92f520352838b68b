//! The cubic filters of accumulate (B-spline, Catmull-Rom, Mitchell-Netravali): equal
//! energy bit for bit, signed weights, the ringing at a step against the float filter, the
//! clamp to the frame word under SAT, WRAP and ERROR, and the hard cases (a one-sample-wide
//! line, a sub-pixel point across the phases, an 8x8 sample grid).

mod common;

use common::{hw, line, point, scene, tri};
use igemu::analysis::filters::{frequency_response, ripple, step};
use igemu::config::{FilterKind, HwConfig, MitchellBc};
use igemu::fixed::{Overflow, QFormat};
use igemu::pipeline::render;
use igemu::stage::RunOptions;
use igemu::stage::accumulate::{Kernel, kernel};
use proptest::prelude::*;

const CUBICS: [FilterKind; 3] = [
    FilterKind::CubicBspline,
    FilterKind::CatmullRom,
    FilterKind::Mitchell,
];

fn cubic_hw(f: FilterKind, n: u32, edit: impl FnOnce(&mut HwConfig)) -> HwConfig {
    hw("linear12", |h| {
        h.accumulate.filter = f;
        h.raster.samples = n;
        edit(h);
    })
}

/// Total of the frame memory over a 16x16 image on a grey background (so the negative
/// lobes never reach the clamp at black), frame LSBs.
fn total(objects: &str, h: &HwConfig) -> i64 {
    let s = scene(16, 16, 0.25, objects);
    let r = render(&s, h, RunOptions::FAST).expect("render");
    assert_eq!(r.report.overflows, 0);
    r.frame().acc.iter().map(|&a| a as i64).sum()
}

#[test]
fn every_sample_phase_gives_exactly_its_share_and_the_weights_are_signed_where_the_lobes_are() {
    for f in CUBICS {
        for n in [1u32, 2, 4, 8] {
            for wb in [2 * n.trailing_zeros(), 8, 10, 14] {
                let k = Kernel::new(f, n, wb, 0.5);
                assert_eq!(k.size, 4 * n as usize, "{f:?}: 4x4 pixels");
                let share = (1i64 << wb) / (n * n) as i64;
                assert!(
                    k.group_sums().iter().all(|&g| g == share),
                    "{f:?} n={n} f={wb}: {:?}",
                    k.group_sums()
                );
                assert_eq!(ripple(&k).group_spread_lsb, 0);
                assert!(ripple(&k).exact_spread < 1e-12, "partition of unity");
            }
        }
        // At 4x4 samples and 10 weight bits the lobes show as negative weights.
        let k = Kernel::new(f, 4, 10, 0.5);
        assert_eq!(k.signed(), f != FilterKind::CubicBspline, "{f:?}");
        assert_eq!(k.pos - k.neg, 1 << 10);
    }
    // The Mitchell family: B = 1, C = 0 is the B-spline, B = 0, C = 1/2 Catmull-Rom.
    let bs = Kernel::with_bc(
        FilterKind::Mitchell,
        4,
        12,
        0.5,
        MitchellBc { b: 1.0, c: 0.0 },
    );
    assert_eq!(bs.w, Kernel::new(FilterKind::CubicBspline, 4, 12, 0.5).w);
    let cr = Kernel::with_bc(
        FilterKind::Mitchell,
        4,
        12,
        0.5,
        MitchellBc { b: 0.0, c: 0.5 },
    );
    assert_eq!(cr.w, Kernel::new(FilterKind::CatmullRom, 4, 12, 0.5).w);
}

#[test]
fn rounding_each_weight_alone_would_ripple() {
    // What the per-group correction buys: 10-bit weights rounded one by one no longer give
    // every phase the same sum for Catmull-Rom (measured: 2 LSB of 2^10 at 4x4 samples).
    let k = Kernel::new(FilterKind::CatmullRom, 4, 10, 0.5);
    assert!(ripple(&k).rounded_spread_lsb > 0);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    /// Equal energy through the pipeline: a light point of one pixel and one of one sample,
    /// anywhere, adds exactly the same total to a frame wide enough to hold every product
    /// (14 fraction bits = 10 weight + 4 intensity): 0 LSB of ripple.
    #[test]
    fn equal_energy_of_the_cubics(x in 5.0f64..10.0, y in 5.0f64..10.0, f in 0usize..3, n_log in 1u32..3) {
        let n = 1 << n_log;
        let h = cubic_hw(CUBICS[f], n, |h| h.accumulate.frame.format = QFormat::new(false, 12, 14));
        for side in [1.0 / n as f64, 1.0] {
            let reference = total(&point(8.0, 8.0, 0.5, 0.4, side), &h);
            prop_assert_eq!(total(&point(x, y, 0.5, 0.4, side), &h), reference);
        }
    }
}

/// The step's ringing: no undershoot or overshoot for the B-spline; for Catmull-Rom and
/// Mitchell the fixed model's (frame LSBs, through the pipeline) within 3 LSB of the float
/// filter's at the same step, and near the continuous filter's analytic value: the area of
/// its negative lobe, of the step's height (1/24 for Catmull-Rom).
#[test]
fn step_overshoot_matches_the_float_filter() {
    let lobe_area = |bc: MitchellBc| {
        let m = 20_000;
        (0..m)
            .map(|i| bc.eval(2.0 * (i as f64 + 0.5) / m as f64).min(0.0))
            .sum::<f64>()
            * -2.0
            / m as f64
    };
    let cr = lobe_area(MitchellBc { b: 0.0, c: 0.5 });
    assert!((cr - 1.0 / 24.0).abs() < 1e-6, "{cr}");
    for (f, lobe) in [
        (FilterKind::CubicBspline, 0.0),
        (FilterKind::CatmullRom, cr),
        (FilterKind::Mitchell, lobe_area(MitchellBc::THIRD)),
    ] {
        let h = cubic_hw(f, 4, |_| {});
        let s = step(&h).expect("step");
        let height = (s.hi - s.lo) as f64;
        for (fixed, float) in [
            (s.overshoot, s.float_overshoot),
            (s.undershoot, s.float_undershoot),
        ] {
            assert!(
                (fixed as f64 - float).abs() <= 3.0,
                "{f:?}: fixed {fixed} float {float:.2}"
            );
            assert!(
                (float / height - lobe).abs() < 0.004,
                "{f:?}: {:.4} of the step, continuous {lobe:.4}",
                float / height
            );
        }
        if lobe > 0.0 {
            assert!(s.overshoot > 0 && s.undershoot > 0 && s.overshoot_dac > 0);
        } else {
            assert!(s.overshoot <= 1 && s.undershoot <= 1, "{s:?}");
        }
    }
}

/// A full-white region under Catmull-Rom: the overshoot inside the edge goes past white;
/// SAT clamps it to the largest code (counted), WRAP wraps it (counted), ERROR stops.
#[test]
fn full_white_under_catmull_rom_clamps_and_counts() {
    let quad = |i: f64| {
        tri(
            [[4.0, 4.0, 0.5], [12.0, 4.0, 0.5], [12.0, 12.0, 0.5]],
            [i; 3],
        ) + &tri(
            [[4.0, 4.0, 0.5], [12.0, 12.0, 0.5], [4.0, 12.0, 0.5]],
            [i; 3],
        )
    };
    let s = scene(16, 16, 0.0, &quad(1.0));
    let run = |o: Overflow| {
        render(
            &s,
            &cubic_hw(FilterKind::CatmullRom, 4, |h| {
                h.accumulate.frame.overflow = o
            }),
            RunOptions::default(),
        )
    };
    let sat = run(Overflow::Sat).expect("SAT renders");
    let clamps = sat
        .report
        .stages
        .iter()
        .find(|x| x.name == "accumulate")
        .unwrap()
        .work["clamps"];
    assert!(clamps > 0 && sat.report.overflows >= clamps);
    let acc = &sat.frame().acc;
    assert_eq!(*acc.iter().max().unwrap(), 4095, "clamped to white");
    // Black outside the edge: the undershoot clamps to 0, never wraps to a bright code.
    assert!(acc.iter().all(|&a| a <= 4095));
    assert_eq!(acc[8 * 16 + 1], 0);
    let wrap = run(Overflow::Wrap).expect("WRAP renders");
    assert!(wrap.report.overflows > 0, "WRAP is counted");
    assert_ne!(wrap.frame().acc, sat.frame().acc, "WRAP wraps");
    assert!(matches!(
        run(Overflow::Error),
        Err(igemu::error::Error::Overflow { ref signal, .. }) if signal == "accumulate.frame"
    ));
    // The same region at 0.9 stays inside the word: nothing clamps.
    let s = scene(16, 16, 0.05, &quad(0.9));
    let r = render(
        &s,
        &cubic_hw(FilterKind::CatmullRom, 4, |_| {}),
        RunOptions::default(),
    )
    .unwrap();
    assert_eq!(r.report.overflows, 0);
}

/// A one-sample-wide vertical line on grey: every filter keeps the line's energy per row
/// (the per-row totals equal), and the cubics with lobes dip on both sides of it.
#[test]
fn one_sample_wide_line() {
    for f in CUBICS {
        let h = cubic_hw(f, 4, |_| {});
        let s = scene(
            16,
            16,
            0.25,
            &line([8.1, 1.0, 0.5], [8.1, 15.0, 0.5], 0.75, 0.25),
        );
        let r = render(&s, &h, RunOptions::default()).expect("render");
        let acc = &r.frame().acc;
        let row = |y: usize| &acc[y * 16..y * 16 + 16];
        let sums: Vec<i64> = (6..10)
            .map(|y| row(y).iter().map(|&a| a as i64).sum())
            .collect();
        assert!(
            sums.windows(2).all(|w| (w[0] - w[1]).abs() <= 4),
            "{f:?}: {sums:?}"
        );
        let bg = row(8)[1];
        let dips = row(8).iter().filter(|&&a| a < bg).count();
        assert_eq!(
            dips > 0,
            f != FilterKind::CubicBspline,
            "{f:?}: {:?}",
            row(8)
        );
        assert_eq!(r.report.overflows, 0);
    }
}

/// A one-sample light point moved across the 4x4 sample phases of a pixel and beyond:
/// the frame total is the same at every phase (exact frame), while the peak pixel varies.
#[test]
fn sub_pixel_point_across_phases() {
    for f in CUBICS {
        let h = cubic_hw(f, 4, |h| {
            h.accumulate.frame.format = QFormat::new(false, 12, 14)
        });
        let totals: std::collections::BTreeSet<i64> = (0..8)
            .map(|k| {
                total(
                    &point(7.0 + k as f64 / 4.0, 8.0 + k as f64 / 8.0, 0.5, 0.6, 0.25),
                    &h,
                )
            })
            .collect();
        assert_eq!(totals.len(), 1, "{f:?}: {totals:?}");
    }
}

/// An 8x8 sample grid: 32x32-sample windows, every build of the window loop, fixed
/// against float within the rounding of the weights.
#[test]
fn eight_by_eight_sample_grid() {
    for f in CUBICS {
        let h = cubic_hw(f, 8, |h| h.accumulate.weight_bits = 14);
        let k = kernel(&h);
        assert_eq!(k.size, 32);
        let s = scene(
            16,
            16,
            0.2,
            &(tri(
                [[2.3, 2.1, 0.5], [13.7, 4.2, 0.5], [6.1, 13.9, 0.5]],
                [0.9, 0.3, 0.6],
            ) + &point(11.0, 11.0, 0.4, 0.5, 0.5)),
        );
        let r = render(&s, &h, RunOptions::default()).expect("render");
        let st = r
            .report
            .stages
            .iter()
            .find(|x| x.name == "accumulate")
            .unwrap();
        let local = st.local.clone().unwrap();
        assert!(local.max_abs_lsb < 4.0, "{f:?}: {local:?}");
        assert_eq!(st.work["macs"], st.work["pixels"] * 32 * 32);
    }
}

/// The 1-D frequency response of the quantised box, tent and B-spline weights against the
/// seed's transforms sinc, sinc², sinc⁴: within the difference the sample grid makes (the
/// sampled box is a Dirichlet kernel, 0.017 above sinc at half the sampling rate of pixels).
#[test]
fn frequency_response_against_sinc_powers() {
    for f in [FilterKind::Box, FilterKind::Tent, FilterKind::CubicBspline] {
        let k = Kernel::new(f, 8, 16, 0.5);
        for r in frequency_response(&k) {
            let a = r.analytic.expect("analytic transform");
            assert!(
                (r.quantised - a).abs() < 0.02,
                "{f:?} u={}: {} vs {a}",
                r.u,
                r.quantised
            );
            assert!((r.quantised - r.exact).abs() < 1e-3);
        }
    }
}

#[test]
fn log_add_refuses_negative_lobes() {
    let mut h = HwConfig::resolve(Some("log8-logadd")).unwrap();
    h.accumulate.filter = FilterKind::CatmullRom;
    let (field, msg) = h.validate().unwrap_err();
    assert_eq!(field, "accumulate.filter");
    assert!(msg.contains("negative lobes"), "{msg}");
    h.accumulate.filter = FilterKind::CubicBspline;
    assert!(h.validate().is_ok());
}

/// `igemu render --hw <file with a cubic filter>` on every embedded scene: exit 0, the
/// accumulate stage's error, cost and cycles in the report; bad values exit 2 naming the field.
#[test]
fn render_runs_on_the_embedded_scenes_and_bad_values_are_named() {
    let dir = std::env::temp_dir().join(format!("igemu-cubic-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_string_lossy().into_owned()
    };
    let hw = file(
        "mitchell.toml",
        "preset = \"linear12\"\n[accumulate]\nfilter = \"mitchell\"\nmitchell = { b = 0.5, c = 0.25 }\n",
    );
    let png = dir.join("out.png").to_string_lossy().into_owned();
    for scene in ["default", "cone-focus", "default-colour"] {
        let (code, out, err) = common::igemu(&["render", scene, "--hw", &hw, "-o", &png, "--json"]);
        assert_eq!(code, 0, "{scene}: {err}");
        let r: serde_json::Value = serde_json::from_str(&out).unwrap();
        let st = r["stages"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["name"] == "accumulate")
            .unwrap()
            .clone();
        assert!(
            st["local"]["max_abs_lsb"].as_f64().unwrap() > 0.0,
            "{scene}"
        );
        assert!(st["cost"]["storage_bits"].as_u64().unwrap() > 0, "{scene}");
        assert!(st["work"]["macs"].as_u64().unwrap() > 0, "{scene}");
        assert!(r["cycles"]["total_cycles"].as_u64().unwrap() > 0, "{scene}");
    }
    for (text, field) in [
        (
            "[accumulate]\nfilter = \"mitchell\"\nmitchell = { b = 1.5, c = 0.2 }\n",
            "accumulate.mitchell.b",
        ),
        ("[accumulate]\nfilter = \"lanczos2\"\n", "accumulate.filter"),
        (
            "preset = \"log8-logadd\"\n[accumulate]\nfilter = \"catmull_rom\"\n",
            "accumulate.filter",
        ),
    ] {
        let bad = file("bad.toml", text);
        let (code, _, err) = common::igemu(&["render", "--hw", &bad, "-o", &png]);
        assert_eq!(code, 2, "{text}");
        assert!(err.contains(field) && err.contains("bad.toml:"), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The signed weight ROM (two's complement in `rom_bits`) and the frame memory at the
/// accumulator's width pack into the bits the cost model charges.
#[test]
fn signed_weight_rom_and_frame_memory_pack() {
    let s = scene(16, 16, 0.2, &point(8.0, 8.0, 0.5, 0.5, 1.0));
    for f in CUBICS {
        let h = cubic_hw(f, 4, |_| {});
        let r = render(&s, &h, RunOptions::default()).expect("render");
        let st = r
            .steps
            .iter()
            .find(|s| s.id == igemu::stage::StageId::Accumulate)
            .unwrap();
        let packs = &st.outcome.packs;
        assert!(packs.iter().any(|p| p.name == "filter weight ROM"), "{f:?}");
        assert!(packs.iter().all(|p| p.verified), "{f:?}: {packs:?}");
        let rom = st
            .outcome
            .report
            .cost
            .memories
            .iter()
            .find(|m| m.name == "filter weight ROM")
            .unwrap();
        assert_eq!(rom.width, kernel(&h).rom_bits(), "{f:?}");
    }
}
