//! A log-add frame with a dither: the eq. 15 gamma LUT emits `f` extra output fraction
//! bits (`UQd.f`) and the dither after it removes them, with a float reference and a cycle
//! model for every planned stage (logdomain and dither included). Before the LUT a dither
//! would drop bits of the log code: that placement is refused, naming the field.

mod common;

use igemu::config::{DitherKind, HwConfig, Placement};
use igemu::pipeline::{Render, render};
use igemu::scene::Scene;
use igemu::stage::gamma::GammaSpec;
use igemu::stage::logdomain::{LogAdder, log_gamma_linear, log_gamma_lut, log_gamma_lut_extended};
use igemu::stage::taps::FrameCoding;
use igemu::stage::{RunOptions, StageId};

fn logadd(kind: DitherKind) -> HwConfig {
    let mut h = HwConfig::resolve(Some("log8-logadd")).unwrap();
    h.dither.kind = kind;
    h.validate().unwrap_or_else(|(f, m)| panic!("{f}: {m}"));
    h
}

fn run(scene: &str, h: &HwConfig) -> Render {
    let s = Scene::embedded(scene).expect("embedded");
    render(&s, h, RunOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn stage<'a>(r: &'a Render, name: &str) -> &'a igemu::stage::StageReport {
    r.report
        .stages
        .iter()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("{name} in the report"))
}

/// The done-when line of the cycle-model issue: log8-logadd + Floyd-Steinberg reports
/// cycles for every planned stage, on the thin-lens default scene (streamed DoF) and on the
/// pinhole one.
#[test]
fn log8_logadd_with_floyd_steinberg_times_every_stage() {
    let h = logadd(DitherKind::FloydSteinberg);
    for scene in ["default", "default-pinhole"] {
        let r = run(scene, &h);
        let c = &r.report.cycles;
        assert!(
            c.plan.unmodelled.is_empty(),
            "{scene}: {:?}",
            c.plan.unmodelled
        );
        for name in &r.report.plan.stages {
            let line = c.stages.iter().find(|s| &s.name == name);
            let line = line.unwrap_or_else(|| panic!("{scene}: no cycles for {name}"));
            assert!(line.busy > 0, "{scene}: {name} {line:?}");
        }
        for id in [StageId::Logdomain, StageId::Gamma, StageId::Dither] {
            assert!(r.plan.layout.has(id), "{scene}: {id:?} planned");
        }
        // Error diffusion runs one row per token, each pixel after its left neighbour.
        let d = c.stages.iter().find(|s| s.name == "dither").unwrap();
        assert_eq!(d.busy, 640 * 480, "{scene}");
        assert!(c.total_cycles >= d.busy);
    }
}

/// The eq. 15 LUT with `f` fraction bits: within half an output LSB of the ideal curve for
/// every log code (stage-local error), monotone, and at `f = 0` the plain eq. 15 LUT.
#[test]
fn the_extended_log_lut_is_the_eq15_curve_to_half_an_lsb() {
    let h = logadd(DitherKind::Bayer8);
    let r = run("default-pinhole", &h);
    let g = stage(&r, "gamma");
    assert_eq!(g.notes["output_format"], "UQ8.4", "{:?}", g.notes);
    assert_eq!(g.notes["log_input_eq15"], true);
    assert_eq!(g.notes["monotone"], true);
    let local = g.local.as_ref().expect("a stage-local error");
    assert!(local.values > 0);
    assert!(local.max_abs_lsb <= 0.5 + 1e-9, "{local:?}");
    // The ROM is 8 + f bits wide, one entry per log frame code.
    let rom = g
        .cost
        .memories
        .iter()
        .find(|m| m.name.contains("eq. 15") && m.name.contains("extended"))
        .expect("the extended eq. 15 ROM");
    assert_eq!(rom.width, 8 + h.dither.frac_bits, "{rom:?}");

    let frame = r
        .taps(StageId::Accumulate)
        .expect("accumulate ran")
        .fixed
        .frame();
    let FrameCoding::Log(add) = &frame.coding else {
        panic!("a log-add frame is log-coded")
    };
    let add: &LogAdder = add;
    let spec = GammaSpec::of(&Scene::embedded("default-pinhole").unwrap(), &h);
    let plain = log_gamma_lut(add, &spec);
    assert_eq!(
        log_gamma_lut_extended(add, &spec, 0),
        plain.iter().map(|&c| u32::from(c)).collect::<Vec<_>>()
    );
    let f = 4;
    let ext = log_gamma_lut_extended(add, &spec, f);
    assert!(ext.windows(2).all(|w| w[0] <= w[1]));
    for (a, &e) in ext.iter().enumerate() {
        let ideal = spec.ideal(log_gamma_linear(add, a as i64)) * (1u64 << f) as f64;
        assert!(
            (e as f64 - ideal).abs() <= 0.5 + 1e-9,
            "code {a}: {e} vs {ideal}"
        );
    }
}

/// The ordered dither after the eq. 15 LUT is exact stage-locally (the float dither fed the
/// same input gives the same codes), and end to end the fixed image stays within the log
/// adders' error of its float reference: the mean DAC code agrees to a tenth of a code.
#[test]
fn the_dithered_log_frame_follows_its_float_reference() {
    for kind in [DitherKind::Bayer8, DitherKind::FloydSteinberg] {
        let h = logadd(kind);
        let r = run("default-pinhole", &h);
        let d = stage(&r, "dither");
        let local = d.local.as_ref().expect("a stage-local error");
        if kind == DitherKind::Bayer8 {
            assert_eq!(local.identical, local.values, "{kind:?}: {local:?}");
        }
        let mean = |v: &[u16]| v.iter().map(|&c| c as f64).sum::<f64>() / v.len() as f64;
        let (m, mr) = (mean(&r.dac), mean(&r.dac_ref));
        // Without the dither the same frame's means differ by the LUT's rounding as well.
        let plain = run("default-pinhole", &logadd(DitherKind::None));
        let mp = mean(&plain.dac);
        assert!(
            (m - mr).abs() <= (mp - mean(&plain.dac_ref)).abs() + 0.1,
            "{kind:?}: dithered mean {m} vs reference {mr}; undithered {mp}"
        );
        assert!(r.dac.iter().all(|&c| c <= 255));
    }
}

/// `before_lut` with a log-add frame is refused naming `dither.placement`; on the command
/// line a hardware file with it exits 2 naming the file and the field, and `after_lut`
/// renders (exit 0) with every stage timed in the JSON report.
#[test]
fn before_lut_is_refused_and_after_lut_renders_from_the_command_line() {
    let mut h = logadd(DitherKind::Bayer4);
    h.dither.placement = Placement::BeforeLut;
    let (field, msg) = h.validate().unwrap_err();
    assert_eq!(field, "dither.placement");
    assert!(msg.contains("after_lut"), "{msg}");

    let dir = std::env::temp_dir().join(format!("igemu-logdither-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_string_lossy().into_owned()
    };
    let bad = write(
        "before.toml",
        "preset = \"log8-logadd\"\n[dither]\nkind = \"bayer4\"\nplacement = \"before_lut\"\n",
    );
    let (code, _, err) = common::igemu(&["render", "default-pinhole", "--hw", &bad]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("before.toml") && err.contains("dither.placement"),
        "{err}"
    );

    let good = write(
        "fs.toml",
        "preset = \"log8-logadd\"\n[dither]\nkind = \"floyd_steinberg\"\n",
    );
    let png = dir.join("out.png").to_string_lossy().into_owned();
    let (code, out, err) = common::igemu(&[
        "render",
        "default-pinhole",
        "--hw",
        &good,
        "-o",
        &png,
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).expect("JSON report");
    assert_eq!(j["cycles"]["plan"]["unmodelled"], serde_json::json!([]));
    let timed: Vec<&str> = j["cycles"]["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    for s in j["plan"]["stages"].as_array().unwrap() {
        assert!(timed.contains(&s.as_str().unwrap()), "{s} in {timed:?}");
    }
    assert!(
        timed.contains(&"logdomain") && timed.contains(&"dither"),
        "{timed:?}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
