//! The `logdomain` stage: log code and encoder, potentiation LUT, Gaussian-log adder
//! (exhaustive over 8-bit code pairs), eq. 15 gamma LUT, chains of additions, hard cases,
//! ramp contours, the pipeline plan and the CLI's bad-input messages; the fixed-point
//! discipline: ROM builds through the quantiser (contents unchanged), counted overflows of
//! the log adder and the term floor, `coding.overflow = "ERROR"`.

mod common;

use common::{hw, igemu, point, scene};

use igemu::analysis::widths::*;
use igemu::compare::DisplayModel;
use igemu::config::{CodingCfg, CodingKind, DitherKind};
use igemu::fixed::{Overflow, QFormat, Quant};
use igemu::stage::gamma::GammaSpec;
use igemu::stage::logdomain::*;

const K: f64 = 100.0;

fn code(bits: u32) -> LogCode {
    LogCode { k: K, bits }
}

fn cfg(bits: u32, fa: u32, tf: u32, a: u32, interp: bool) -> CodingCfg {
    CodingCfg {
        kind: CodingKind::LogAdd,
        log_bits: bits,
        acc_frac_bits: fa,
        table_addr_bits: a,
        table_frac_bits: tf,
        interpolate: interp,
        ..CodingCfg::linear()
    }
}

/// Tent 4x4 kernel with 10 weight bits: smallest weight 1.
fn adder(c: &CodingCfg) -> LogAdder {
    LogAdder::new(code(c.log_bits), c, 10, 1)
}

/// Exact frame position of the sum of two frame codes (saturated at full scale).
fn exact_sum(add: &LogAdder, a: i64, b: i64) -> f64 {
    let v = add.value(a) + add.value(b);
    if v <= 0.0 {
        0.0
    } else {
        add.position(v).min(add.max as f64)
    }
}

/// Bound of one addition in frame LSBs: output rounding, table rounding, address rounding
/// (|sb'| <= 1/2 per frame LSB) for direct lookup.
fn bound(add: &LogAdder) -> f64 {
    let data_lsb = 1.0 / (1u64 << add.tf) as f64;
    if add.interpolate {
        // Entries and the interpolated value each round once; chord error of a function with
        // |sb''| <= ln K / (4 unit) over a step h = 2^shift is h^2 |sb''| / 8.
        let h = (1u64 << add.shift) as f64;
        0.5 + data_lsb + h * h * K.ln() / (4.0 * add.unit()) / 8.0 + 1e-9
    } else {
        let addr = if add.shift == 0 {
            0.0
        } else {
            0.5 * (1u64 << (add.shift - 1)) as f64
        };
        0.5 + 0.5 * data_lsb + addr + 1e-9
    }
}

struct PairStats {
    max: f64,
    mean: f64,
}

/// Every pair of 8-bit log codes (as frame codes of weight-1 terms) through the adder.
fn all_pairs(add: &LogAdder) -> PairStats {
    let codes: Vec<i64> = (0..=255u32).map(|c| add.term(c, 1024)).collect();
    let (mut max, mut sum) = (0f64, 0f64);
    for &a in &codes {
        assert_eq!(add.add(a, ZERO), a, "x + zero");
        assert_eq!(add.add(ZERO, a), a, "zero + x");
        for &b in &codes {
            let r = add.add(a, b);
            assert_eq!(r, add.add(b, a), "commutativity at {a}, {b}");
            let e = r as f64 - exact_sum(add, a, b);
            max = max.max(e.abs());
            sum += e;
        }
    }
    // Monotone in each operand over every frame code.
    for a in (1..=add.max).step_by(3) {
        let mut last = add.add(a, 1);
        for b in 2..=add.max {
            let r = add.add(a, b);
            assert!(r >= last, "not monotone at a={a} b={b}: {r} < {last}");
            last = r;
        }
    }
    PairStats {
        max,
        mean: sum / (codes.len() * codes.len()) as f64,
    }
}

#[test]
fn adder_every_8bit_code_pair_direct_and_interpolated() {
    for c in [
        cfg(8, 0, 0, 8, false),
        cfg(8, 0, 2, 8, false),
        cfg(8, 0, 2, 6, true),
        cfg(8, 2, 0, 10, false),
        cfg(8, 2, 0, 10, true),
        cfg(8, 2, 4, 8, true),
        CodingCfg::preset("log8-logadd").unwrap(),
    ] {
        let add = adder(&c);
        let s = all_pairs(&add);
        let b = bound(&add);
        eprintln!(
            "fa {} addr {} tf {} interp {} shift {}: max {:.3} LSB (bound {b:.3}), bias {:+.4} LSB",
            c.acc_frac_bits,
            c.table_addr_bits,
            c.table_frac_bits,
            c.interpolate,
            add.shift,
            s.max,
            s.mean
        );
        assert!(s.max <= b, "{c:?}: max error {} > bound {b}", s.max);
        assert!(s.mean.abs() < 0.25, "{c:?}: bias {}", s.mean);
    }
}

#[test]
fn adder_hard_cases() {
    let add = adder(&CodingCfg::preset("log8-logadd").unwrap());
    let white = add.term(255, 1024);
    assert_eq!(white, add.max, "full white is full scale");
    // Full-white saturation.
    assert_eq!(add.add(white, white), add.max);
    assert_eq!(add.add(add.max, 1), add.max);
    // Equal operands: a + a = a + log_K 2.
    let a = add.term(100, 1024);
    let two = (2f64.ln() / K.ln() * add.unit()).round() as i64;
    assert_eq!(add.add(a, a), a + two);
    // Far apart (past sb's essential zero): the larger operand unchanged.
    let ez = (1i64 << add.addr_bits) << add.shift;
    assert_eq!(add.add(white, white - ez - 1), white);
    assert_eq!(add.add(1, ez + 2), ez + 2);
    assert_eq!(add.sb_lookup(ez + 1), 0);
    // Zero intensity: black samples sum to black (code `off`, L = 0) over a full tent window.
    let k = igemu::stage::accumulate::Kernel::new(igemu::config::FilterKind::Tent, 4, 10, 0.5);
    let mut w = LogWork::new(&add);
    let black = accumulate_pixel(&add, k.w.iter().map(|&w| (0, w as u32)), &mut w);
    assert!(
        (black - add.off).abs() <= 2,
        "black = {black}, off = {}",
        add.off
    );
    let white_px = accumulate_pixel(&add, k.w.iter().map(|&w| (255, w as u32)), &mut w);
    assert!((white_px - add.max).abs() <= 2, "white = {white_px}");
    // A zero weight contributes nothing.
    assert_eq!(add.term(10, 0), ZERO);
    // Intensity below the first grade encodes to the zero code (exact black).
    let enc = LogEncoder::new(code(8), 4095 * 16, 16);
    let first = enc.thresholds[0];
    assert!(first > 1);
    assert_eq!(enc.encode(first - 1), 0);
    assert_eq!(enc.encode(first), 1);
    assert_eq!(enc.encode(0), 0);
    assert_eq!(enc.encode(4095 * 16), 255);
    assert_eq!(enc.encode(u16::MAX as u64), 255, "above white saturates");
}

#[test]
fn encoder_matches_rounded_log_on_every_linear_code() {
    for bits in [7, 8] {
        let c = code(bits);
        let white = 4095u64 * 16;
        let enc = LogEncoder::new(c, white, 16);
        let g = c.grades() as f64;
        let mut last = 0;
        for i in 0..=white {
            let e = enc.encode(i);
            let exact = c.log_of_linear(i as f64 / white as f64) * g;
            assert!(
                (e as f64 - exact).abs() <= 0.5 + 1e-9,
                "bits {bits} i {i}: {e} vs {exact}"
            );
            assert!(e >= last);
            last = e;
        }
    }
}

#[test]
fn potentiation_lut_every_entry() {
    for (bits, data) in [(8, 12), (7, 12), (8, 11)] {
        let c = code(bits);
        let lut = PotentiationLut::build(c, data);
        assert_eq!(lut.table.len(), (1 << bits) as usize);
        assert_eq!(lut.table[0], 0);
        assert_eq!(*lut.table.last().unwrap(), (1 << data) - 1);
        for (i, &v) in lut.table.iter().enumerate() {
            // Independent formula: W (K^(c/G) - 1)/(K - 1).
            let g = ((1u32 << bits) - 1) as f64;
            let exact = ((1u64 << data) - 1) as f64 * (K.powf(i as f64 / g) - 1.0) / (K - 1.0);
            assert!((v as f64 - exact).abs() <= 0.5, "code {i}: {v} vs {exact}");
        }
        // Non-decreasing; two codes share an entry only where the exact step is below one
        // linear LSB (the darkest grades).
        let g = ((1u32 << bits) - 1) as f64;
        let w = ((1u64 << data) - 1) as f64;
        let mut shared = 0;
        for (i, p) in lut.table.windows(2).enumerate() {
            assert!(p[0] <= p[1]);
            if p[0] == p[1] {
                shared += 1;
                let step = w * (K.powf((i + 1) as f64 / g) - K.powf(i as f64 / g)) / (K - 1.0);
                assert!(step < 1.0, "code {i}: step {step} LSB but equal entries");
            }
        }
        eprintln!("log{bits} -> {data} bits: {shared} adjacent codes share a linear entry");
        assert_eq!(lut.cost().lut_bits, (1u64 << bits) * data as u64);
    }
}

#[test]
fn log_gamma_lut_every_entry() {
    let spec = GammaSpec::new(2.4, true, 8, Quant::RndConv);
    for c in [
        CodingCfg::preset("log8-logadd").unwrap(),
        CodingCfg::preset("log7-logadd").unwrap(),
    ] {
        let add = adder(&c);
        let lut = log_gamma_lut(&add, &spec);
        assert_eq!(lut.len() as i64, add.max + 1);
        assert_eq!(lut[0], 0, "zero code");
        assert_eq!(lut[add.off as usize], 0, "black");
        assert_eq!(lut[add.max as usize], 255, "full white");
        for (a, &v) in lut.iter().enumerate() {
            let l = ((a as f64 - add.off as f64) / add.unit()).clamp(0.0, 1.0);
            let exact = if a == 0 {
                0.0
            } else {
                ((K.powf(l) - 1.0) / (K - 1.0)).powf(1.0 / 2.4) * 255.0
            };
            assert!(
                (v as f64 - exact).abs() <= 0.5 + 1e-9,
                "entry {a}: {v} vs {exact}"
            );
        }
        assert!(lut.windows(2).all(|w| w[0] <= w[1]));
    }
}

/// Sum `n` equal terms in a chain; error of the result against the exact sum, frame LSBs.
fn chain(add: &LogAdder, terms: &[i64]) -> f64 {
    let mut acc = ZERO;
    let mut exact = 0.0;
    for &t in terms {
        acc = add.add(acc, t);
        exact += add.value(t);
    }
    acc as f64 - add.position(exact).min(add.max as f64)
}

#[test]
fn chain_of_small_additions_bias_and_order() {
    for name in ["log8-logadd", "log7-logadd"] {
        let add = adder(&CodingCfg::preset(name).unwrap());
        // 256 equal terms of 1/256 of white each: the sum is white (full scale).
        let small = add.max - (256f64.ln() / K.ln() * add.unit()).round() as i64;
        let equal = chain(&add, &vec![small; 256]);
        // 64 terms of increasing and decreasing size (same set), below full scale.
        let mut rng = 12345u64;
        let mut t: Vec<i64> = (0..64)
            .map(|_| {
                rng = rng
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                // L in [-1, 0): 64 terms whose sum stays below full scale.
                add.off - add.unit() as i64 + ((rng >> 33) % (add.unit() as u64)) as i64
            })
            .collect();
        t.sort();
        let up = chain(&add, &t);
        t.reverse();
        let down = chain(&add, &t);
        eprintln!(
            "{name}: 256 equal terms: error {equal:+.2} LSB; 64 random terms ascending {up:+.2}, descending {down:+.2} LSB (order dependence {:.2} LSB)",
            (up - down).abs()
        );
        // One rounding per addition bounds the chain error.
        let b = bound(&add);
        assert!(equal.abs() <= 255.0 * b, "{name}: {equal}");
        assert!(up.abs() <= 63.0 * b && down.abs() <= 63.0 * b);
        // Small terms added to a large sum lose their sb (rounded towards the essential
        // zero); small-first lets them combine first: ascending is no worse than descending.
        assert!(up.abs() <= down.abs() + b, "{name}: down {down}, up {up}");
    }
}

#[test]
fn ramp_contours_count_visible_steps_only() {
    let d = DisplayModel {
        b_min: 1.0,
        b_max: 100.0,
        gamma: 2.4,
        weber: 0.02,
        max_code: 255.0,
    };
    // Every DAC code once: the dark steps of an 8-bit DAC are invisible, the bright ones too
    // (ratio ~ 1 + 2.4/255), the middle ones visible.
    let all: Vec<u16> = (0..=255).collect();
    let n = ramp_visible_contours(&all, &d);
    let expect = (1..=255u16)
        .filter(|&c| d.luminance(c) / d.luminance(c - 1) > 1.02)
        .count();
    assert_eq!(n, expect);
    assert!(n > 0);
    // Repeated codes are not steps.
    assert_eq!(ramp_visible_contours(&[5, 5, 5, 5], &d), 0);
}

fn write(name: &str, text: &str) -> String {
    let d = std::env::temp_dir().join(format!("igemu-log-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

#[test]
fn cli_bad_input_exits_2_with_field_and_range() {
    for (toml, field, range) in [
        (
            "[coding]\nkind = \"log-add\"\ntable_addr_bits = 20\n",
            "coding.table_addr_bits",
            "4..=16",
        ),
        (
            "[coding]\nkind = \"log-add\"\ntable_addr_bits = 3\n",
            "coding.table_addr_bits",
            "4..=16",
        ),
        (
            "[coding]\ntable_frac_bits = 13\n",
            "coding.table_frac_bits",
            "0..=12",
        ),
        ("[coding]\nlog_bits = 2\n", "coding.log_bits", "3..=12"),
        (
            "[coding]\nacc_frac_bits = 9\n",
            "coding.acc_frac_bits",
            "0..=8",
        ),
        (
            "[coding]\nkind = \"log-add\"\noverflow = \"WRAP\"\n",
            "coding.overflow",
            "SAT or ERROR",
        ),
    ] {
        let p = write("hw.toml", toml);
        let (code, _, err) = igemu(&["render", "--hw", &p, "-o", "/dev/null"]);
        assert_eq!(code, 2, "{toml}: {err}");
        assert!(err.contains(field) && err.contains(range), "{toml}: {err}");
    }
    let p = write("hw.toml", "[coding]\nkind = \"log-multiply\"\n");
    let (code, _, err) = igemu(&["render", "--hw", &p, "-o", "/dev/null"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("log-multiply") && err.contains("log-add"),
        "{err}"
    );
    for (args, what) in [
        (vec!["--contrast", "1", "--weber", "0.02"], "contrast"),
        (vec!["--contrast", "0.5", "--weber", "0.02"], "contrast"),
        (vec!["--contrast", "100", "--weber", "0"], "weber"),
        (vec!["--contrast", "100", "--weber", "1.5"], "weber"),
        (
            vec!["--contrast", "100", "--weber", "0.02", "--gamma", "0"],
            "gamma",
        ),
        (
            vec!["--contrast", "100", "--weber", "0.02", "--gamma=-1"],
            "gamma",
        ),
    ] {
        let mut a = vec!["widths"];
        a.extend(args.iter());
        let (code, _, err) = igemu(&a);
        assert_eq!(code, 2, "{a:?}: {err}");
        assert!(err.contains(what), "{a:?}: {err}");
    }
}

#[test]
fn plan_lists_the_log_stage_only_for_log_coding() {
    // A pinhole camera: the log-add frame memory is log-coded and plans no dof stage.
    let scene = igemu::scene::Scene::embedded("default-pinhole").unwrap();
    let opts = igemu::stage::RunOptions::FAST;
    for (preset, stages) in [
        ("linear12", "input setup raster visibility accumulate gamma"),
        (
            "log8-potentiate",
            "input setup raster visibility logdomain accumulate gamma",
        ),
        (
            "log8-logadd",
            "input setup raster visibility logdomain accumulate gamma",
        ),
    ] {
        let hw = igemu::config::HwConfig::preset(preset).unwrap();
        let r = igemu::pipeline::render(&scene, &hw, opts).unwrap();
        assert_eq!(r.report.plan.stages.join(" "), stages, "{preset}");
        if preset == "log8-logadd" {
            // The accumulate stage sums in the log domain: structure (b) has no multiplier.
            let acc = &r.report.stages[5];
            assert_eq!(acc.name, "accumulate");
            assert!(
                acc.cost.multipliers.is_empty(),
                "structure (b) has no multiplier"
            );
            assert!(acc.work.contains_key("log_adds"), "{:?}", acc.work);
            // Most DAC codes within one code of the float reference.
            let c = &r.report.end_to_end.codes;
            let near = c
                .histogram
                .iter()
                .filter(|(d, _)| d.abs() <= 1)
                .map(|(_, n)| n)
                .sum::<u64>();
            assert!(near as f64 / c.count as f64 > 0.99, "{:?}", c.histogram);
        }
    }
}

#[test]
fn ramp_contours_of_the_preset_codes() {
    // Default scene display: K = 100, delta = 0.02, gamma = 2.4.
    let x = ramp(K);
    let count = |dac: u32, codes: Vec<u16>| {
        let d = DisplayModel {
            b_min: 1.0,
            b_max: K,
            gamma: 2.4,
            weber: 0.02,
            max_code: ((1u64 << dac) - 1) as f64,
        };
        ramp_visible_contours(&codes, &d)
    };
    for dac in [8, 16] {
        let lin = |bits| count(dac, ramp_linear(&x, bits, dac, 2.4));
        let log = |bits| count(dac, ramp_log(&x, K, bits, dac, 2.4));
        let (l8, l11, l12, l13, g7, g8) = (lin(8), lin(11), lin(12), lin(13), log(7), log(8));
        eprintln!(
            "ramp contours, {dac}-bit DAC: linear8 {l8}, linear11 {l11}, linear12 {l12}, linear13 {l13}, log7 {g7}, log8 {g8}"
        );
        if dac == 16 {
            // With a DAC that adds no steps of its own, the code alone decides (eq. 9, 11):
            // 13 linear bits and 8 log bits (K^(1/255) = 1.0182 < 1.02) show none, 12 linear
            // bits and 7 log bits (K^(1/127) = 1.037) do.
            assert_eq!(l13, 0);
            assert!(l12 > 0 && l11 > l12 && l8 > l11);
            assert_eq!(g8, 0);
            assert_eq!(g7, 127, "every step of a 7-bit log code is visible");
        }
    }
}

#[test]
fn cli_widths_scene_validates_by_emulation() {
    let (code, out, err) = igemu(&["widths", "--scene", "default", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["contrast"], 100.0);
    assert_eq!(v["linear"]["bits"], 13);
    let checks = v["validation"].as_array().unwrap();
    assert_eq!(checks.len(), 6);
    for c in checks {
        let contours = c["contours"].as_u64().unwrap();
        let rec = c["recommended"].as_bool().unwrap();
        assert_eq!(
            c["disagrees"].as_bool().unwrap(),
            (contours > 0) == rec,
            "{c}"
        );
    }
    // The linear recommendation (13 bits, 9-bit DAC) emulates clean; one bit less does not.
    assert_eq!(checks[0]["coding"], "linear");
    assert_eq!(checks[0]["contours"], 0);
    assert!(checks[1]["contours"].as_u64().unwrap() > 0);
    // Text form states disagreements plainly.
    let (code, out, _) = igemu(&["widths", "--scene", "default"]);
    assert_eq!(code, 0);
    let any = checks.iter().any(|c| c["disagrees"].as_bool().unwrap());
    assert_eq!(out.contains("DISAGREES"), any, "{out}");
    // Flags override the scene; neither given is bad input.
    let (code, out, _) = igemu(&["widths", "--scene", "default", "--weber", "0.05", "--json"]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["linear"]["bits"], 11);
    let (code, _, err) = igemu(&["widths", "--weber", "0.05"]);
    assert_eq!(code, 2);
    assert!(err.contains("--contrast"), "{err}");
    let scene =
        include_str!("../src/scene/default.toml").replace("contrast = 100.0", "contrast = 1.0");
    let p = write("bad-scene.toml", &scene);
    let (code, _, err) = igemu(&["widths", "--scene", &p]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("display.contrast"), "{err}");
}

/// A thin lens after a log-coded frame: the DoF stage potentiates the frame through a LUT of
/// `round(W * log_gamma_linear(a))` entries into the linear frame format, blurs it, and the
/// gamma stage then reads a linear frame (its linear LUT, not eq. 15). On both Fig. 3 scenes
/// over 85 % of the codes equal the float reference's and 99.9 % are within one code. A dither after the
/// LUT reads that linear frame; before the LUT it is refused.
#[test]
fn log_add_with_depth_of_field_potentiates_the_frame_and_refuses_a_dither_before_the_lut() {
    use igemu::stage::StageId;
    let hw = igemu::config::HwConfig::preset("log8-logadd").unwrap();
    let opts = igemu::stage::RunOptions::FAST;
    for name in ["default", "cone-focus"] {
        let sc = igemu::scene::Scene::embedded(name).unwrap();
        let r = igemu::pipeline::render(&sc, &hw, opts).unwrap_or_else(|e| panic!("{name}: {e}"));
        let dof = r
            .steps
            .iter()
            .find(|s| s.id == StageId::Dof)
            .expect("dof ran");
        let pot = dof
            .outcome
            .images
            .iter()
            .find(|i| i.name == "dof potentiation LUT")
            .expect("potentiation LUT image");
        let acc = r
            .taps(StageId::Accumulate)
            .unwrap()
            .fixed
            .frame
            .clone()
            .unwrap();
        let igemu::stage::taps::FrameCoding::Log(add) = &acc.coding else {
            panic!("{name}: log-add leaves a log-coded frame")
        };
        let f = hw.accumulate.frame.format;
        let white = f.max_code() as f64 / (1u64 << f.frac_bits) as f64;
        assert_eq!(pot.words as i64, add.max + 1, "{name}");
        for a in 0..=add.max {
            let want = (log_gamma_linear(add, a) * white).round() as u64;
            assert_eq!((pot.get)(a as usize, 0), want, "{name}: entry {a}");
        }
        // Monotone: more light never potentiates to less.
        assert!((1..pot.words).all(|a| (pot.get)(a, 0) >= (pot.get)(a - 1, 0)));
        let gamma = r.steps.iter().find(|s| s.id == StageId::Gamma).unwrap();
        let names: Vec<&str> = gamma
            .outcome
            .images
            .iter()
            .map(|i| i.name.as_str())
            .collect();
        assert_eq!(
            names,
            ["gamma ROM"],
            "{name}: the gamma stage reads a linear frame"
        );
        let c = &r.report.end_to_end.codes;
        let near: u64 = (-1..=1)
            .map(|d| c.histogram.get(&d).copied().unwrap_or(0))
            .sum();
        assert!(c.identical_fraction > 0.85, "{name}: {c:?}");
        assert!(near as f64 > 0.999 * c.count as f64, "{name}: {c:?}");
    }
    // A dither after the LUT is valid (the frame is potentiated, so the LUT is linear);
    // before the LUT it is refused for log-add, naming the placement.
    let mut hw = hw;
    hw.dither.kind = DitherKind::Bayer4;
    assert!(hw.validate().is_ok());
    hw.dither.placement = igemu::config::Placement::BeforeLut;
    let (field, _) = hw.validate().unwrap_err();
    assert_eq!(field, "dither.placement");
}

/// The old (pre-quantiser) ROM formulas, written out: `f64::round` / `f64::ceil` casts.
mod old {
    use super::*;

    pub fn thresholds(code: LogCode, white: u64) -> Vec<u64> {
        let g = code.grades() as f64;
        (1..=code.grades())
            .map(|c| {
                let x = code.linear_of_log((c as f64 - 0.5) / g) * white as f64;
                x.ceil().max(0.0) as u64
            })
            .collect()
    }

    pub fn potentiation(code: LogCode, data_bits: u32) -> Vec<u32> {
        let w = ((1u64 << data_bits) - 1) as f64;
        let g = code.grades() as f64;
        (0..=code.grades())
            .map(|c| (code.linear_of_log(c as f64 / g) * w).round() as u32)
            .collect()
    }

    /// sb table and weight ROM for the adder's own `shift` (the address search is unchanged).
    pub fn sb_and_log_w(add: &LogAdder) -> (Vec<i64>, Vec<i64>) {
        let unit = add.unit();
        let lnk = add.code.k.ln();
        let data_unit = unit * (1u64 << add.tf) as f64;
        let sbf = |d: f64| (1.0 + (-d / unit * lnk).exp()).ln() / lnk * data_unit;
        let n = (1usize << add.addr_bits) + usize::from(add.interpolate);
        let sb = (0..n)
            .map(|j| sbf((j as i64 * (1 << add.shift)) as f64).round() as i64)
            .collect();
        let log_w = (0..=(1u64 << add.wf))
            .map(|w| {
                if w == 0 {
                    0
                } else {
                    ((w as f64 / (1u64 << add.wf) as f64).ln() / lnk * unit).round() as i64
                }
            })
            .collect();
        (sb, log_w)
    }

    /// The hand-coded adder: half-up shifts, silent `min`.
    pub fn add(add: &LogAdder, a: i64, b: i64) -> i64 {
        if a == ZERO {
            return b;
        }
        if b == ZERO {
            return a;
        }
        let (m, d) = if a >= b { (a, a - b) } else { (b, b - a) };
        let n = 1i64 << add.addr_bits;
        let s = add.shift;
        let sb = if add.interpolate {
            let j = d >> s;
            if j >= n {
                0
            } else {
                let fr = d & ((1 << s) - 1);
                let (x, y) = (add.sb[j as usize], add.sb[j as usize + 1]);
                if s == 0 {
                    x
                } else {
                    x + (((y - x) * fr + (1 << (s - 1))) >> s)
                }
            }
        } else {
            let j = if s == 0 { d } else { (d + (1 << (s - 1))) >> s };
            if j >= n { 0 } else { add.sb[j as usize] }
        };
        let v = (m << add.tf) + sb;
        let r = if add.tf == 0 {
            v
        } else {
            (v + (1 << (add.tf - 1))) >> add.tf
        };
        r.min(add.max)
    }
}

#[test]
fn rom_builds_through_the_quantiser_are_unchanged() {
    let mut adders = 0;
    for k in [3.0, 100.0, 1000.0] {
        for bits in 3..=8 {
            let c = LogCode { k, bits };
            // Encoder thresholds and potentiation LUT over input / data widths.
            for (in_bits, int_bits) in [(8, 8), (12, 12), (16, 12), (16, 8)] {
                let white = ((1u64 << int_bits) - 1) << (in_bits - int_bits);
                let enc = LogEncoder::new(c, white, in_bits);
                assert_eq!(enc.thresholds, old::thresholds(c, white), "K {k} b {bits}");
                assert_eq!(enc.stats.name, "logdomain.threshold");
                assert_eq!(enc.stats.format, QFormat::new(false, in_bits, 0));
                assert_eq!(enc.stats.count, c.grades() as u64);
                assert_eq!(enc.stats.overflows, 0);
                // A ceiling: every error in [0, 1) LSB, so the mean is in [0, 1).
                assert!((0.0..1.0).contains(&enc.stats.mean_error()));
            }
            for data in 1..=16 {
                let lut = PotentiationLut::build(c, data);
                assert_eq!(
                    lut.table,
                    old::potentiation(c, data),
                    "K {k} b {bits} d {data}"
                );
                assert_eq!(lut.stats.name, "logdomain.potentiation");
                assert_eq!(lut.stats.format, QFormat::new(false, data, 0));
                assert_eq!(lut.stats.max, Some(((1i128) << data) - 1));
                assert!(lut.stats.rms_error() <= 0.5);
            }
            // sb table and weight ROM over the frame / table widths.
            for fa in 0..=3 {
                for tf in [0, 1, 2, 4] {
                    for a in [4, 6, 8] {
                        for interp in [false, true] {
                            for (wf, w_min) in [(10, 1), (6, 3), (0, 1)] {
                                let add =
                                    LogAdder::new(c, &cfg(bits, fa, tf, a, interp), wf, w_min);
                                let (sb, log_w) = old::sb_and_log_w(&add);
                                let at = format!(
                                    "K {k} b {bits} fa {fa} tf {tf} a {a} {interp} wf {wf}"
                                );
                                assert_eq!(add.sb, sb, "{at}");
                                assert_eq!(add.log_w, log_w, "{at}");
                                assert_eq!(add.sb_stats.max, Some(sb[0] as i128), "{at}");
                                assert_eq!(add.sb_stats.format.frac_bits, tf);
                                assert!(
                                    add.sb_stats.format.total_bits() >= add.table_data_bits(),
                                    "{at}"
                                );
                                assert_eq!(add.sb_stats.overflows, 0);
                                assert_eq!(add.log_w_stats.min, Some(log_w[1] as i128), "{at}");
                                assert_eq!(add.log_w_stats.count, 1 << wf);
                                assert!(add.log_w_stats.format.signed);
                                assert_eq!(add.log_w_stats.overflows, 0);
                                adders += 1;
                            }
                        }
                    }
                }
            }
        }
    }
    assert_eq!(adders, 3 * 6 * 4 * 4 * 3 * 2 * 3);
}

#[test]
fn adder_rounding_is_the_configured_mode() {
    // RND (the default) is the old hand-coded adder on every pair of small codes.
    for c in [
        cfg(8, 2, 2, 6, false),
        cfg(8, 2, 3, 6, true),
        cfg(7, 3, 1, 8, false),
        cfg(8, 0, 0, 8, true),
    ] {
        let add = adder(&c);
        let top = add.max.min(700);
        for a in 0..=top {
            for b in 0..=top {
                assert_eq!(add.add(a, b), old::add(&add, a, b), "{c:?}: {a} + {b}");
            }
        }
    }
    // TRN (floor) is what the coding asks for: below RND by at most one LSB, and below it
    // somewhere.
    let rnd = adder(&cfg(8, 2, 3, 8, false));
    let trn = adder(&CodingCfg {
        quant: Quant::Trn,
        ..cfg(8, 2, 3, 8, false)
    });
    let mut below = 0;
    for a in (1..=rnd.max).step_by(7) {
        for b in (1..=rnd.max).step_by(5) {
            let (r, t) = (rnd.add(a, b), trn.add(a, b));
            assert!(t == r || t + 1 == r, "{a} + {b}: TRN {t}, RND {r}");
            below += usize::from(t < r);
        }
    }
    assert!(below > 0, "TRN never rounded differently from RND");
}

#[test]
fn log_adder_overflow_and_term_floor_are_counted() {
    let add = adder(&CodingCfg::preset("log8-logadd").unwrap());
    let white = add.term(255, 1024);
    assert_eq!(white, add.max);
    // Four full-white terms on one pixel: the first is the identity, the three sums above
    // full white overflow and saturate.
    let mut w = LogWork::new(&add);
    let r = accumulate_pixel(&add, (0..4).map(|_| (255, 1024)), &mut w);
    assert_eq!(r, add.max);
    assert_eq!(w.frame.name, "logdomain.frame");
    assert_eq!(w.frame.overflows, 3);
    assert_eq!(w.frame.count, 4);
    assert!(w.frame.max.unwrap() > add.max as i128, "{:?}", w.frame.max);
    assert_eq!(w.saturations, 1, "hit full scale once");
    assert_eq!(w.term.overflows, 0);
    let (rounded, q) = add.add_checked(white, white);
    assert!(q.overflow && q.code == add.max && rounded > add.max);
    assert!(!add.add_checked(white, ZERO).1.overflow);
    // A sum landing at most on full white is no overflow.
    let mut w = LogWork::new(&add);
    accumulate_pixel(&add, [(255, 512), (255, 512)].into_iter(), &mut w);
    assert_eq!(w.frame.overflows, 0, "{:?}", w.frame);
    // The term floor: an adder sized for full weights only (w_min = 2^f) sees a tiny
    // weight on black, whose term is below code 1.
    let c = CodingCfg::preset("log8-logadd").unwrap();
    let add = LogAdder::new(code(8), &c, 10, 1024);
    assert!(add.term(0, 1) < 1);
    let mut w = LogWork::new(&add);
    let r = accumulate_pixel(&add, [(0, 1), (0, 2), (200, 1024)].into_iter(), &mut w);
    assert_eq!(w.term.name, "logdomain.term");
    assert_eq!(w.term.overflows, 2, "{:?}", w.term);
    assert!(w.term.min.unwrap() < 1);
    assert_eq!(w.term.count, 3);
    assert!(r >= add.term(200, 1024));
}

/// Twelve full-white light points on one pixel of a small pinhole scene.
fn bright_points() -> igemu::scene::Scene {
    let objects: String = (0..12).map(|_| point(8.0, 8.0, 0.3, 1.0, 2.0)).collect();
    scene(16, 16, 0.1, &objects)
}

/// A signal of the log arithmetic: the encoder's on the logdomain stage, the log adder's on
/// the accumulate stage (which sums in the log domain).
fn log_signal<'a>(r: &'a igemu::pipeline::Render, name: &str) -> &'a igemu::fixed::SignalStats {
    r.report
        .stages
        .iter()
        .filter(|s| s.name == "logdomain" || s.name == "accumulate")
        .flat_map(|s| &s.signals)
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no signal {name}"))
}

#[test]
fn log_adder_saturation_is_reported_and_error_mode_stops() {
    let opts = igemu::stage::RunOptions::FAST;
    let sat = hw("log8-logadd", |_| {});
    assert_eq!(sat.coding.overflow, Overflow::Sat);
    let r = igemu::pipeline::render(&bright_points(), &sat, opts).unwrap();
    let frame = log_signal(&r, "logdomain.frame");
    assert!(frame.overflows > 0, "{frame:?}");
    assert!(r.report.overflows >= frame.overflows);
    for name in [
        "logdomain.threshold",
        "logdomain.log_w",
        "logdomain.sb",
        "logdomain.term",
    ] {
        let s = log_signal(&r, name);
        assert!(s.count > 0, "{s:?}");
    }
    // ERROR stops the render and names the signal.
    let err = hw("log8-logadd", |h| h.coding.overflow = Overflow::Error);
    match igemu::pipeline::render(&bright_points(), &err, opts) {
        Err(e) => {
            let m = e.to_string();
            assert!(m.contains("logdomain.frame") && m.contains("ERROR"), "{m}");
        }
        Ok(_) => panic!("coding.overflow = ERROR must stop an overflowing log render"),
    }
    // Without the points nothing overflows, and ERROR renders.
    let plain = scene(16, 16, 0.1, "");
    let r = igemu::pipeline::render(&plain, &err, opts).unwrap();
    assert_eq!(log_signal(&r, "logdomain.frame").overflows, 0);
    // The two new fields are in the report's hardware section.
    let j = serde_json::to_value(&r.report.hardware.coding).unwrap();
    assert_eq!(j["quant"], "RND");
    assert_eq!(j["overflow"], "ERROR");
}
