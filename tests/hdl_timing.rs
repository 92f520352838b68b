//! RTL-measured timing (`igemu hdl timing`): the presets' `[cycles.*]` latency and ii agree
//! with what Verilator measures on the handshake RTL; a hardware file with a wrong latency, or
//! RTL with another pipeline depth, makes it exit 1 naming the stage and field. Without
//! Verilator the simulator tests print a skip line and pass, unless `IGEMU_REQUIRE_HDL=1`.

mod common;

use common::igemu;
use common::sims::verilator;
use igemu::config::CyclesCfg;
use igemu::hdl::timing::{self, Interval, Measured, TIMED, Timed, parse_timing};
use igemu::stage_id::StageId;
use std::path::PathBuf;

fn tmp(tag: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("hdl-timing-{tag}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("dir");
    d
}

fn cache() -> String {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("hdl-cache")
        .display()
        .to_string()
}

#[test]
fn timing_lines_parse_and_bad_ones_are_refused() {
    let t = parse_timing("TESTBENCH OK 9 vectors\nTIMING items=9 first_in=0 first_out=2 last_in=12 last_out=14 stalls=4\n")
        .expect("parses");
    assert_eq!((t.items, t.first_out, t.last_in, t.stalls), (9, 2, 12, 4));
    for bad in [
        "",
        "TIMING items=9 first_in=0 first_out=2 last_in=12 last_out=14 stalls=4\nTIMING items=9",
        "TIMING items=9 first_in=0 first_out=2 last_in=12 last_out=14 stall=4",
        "TIMING items=9 first_in=0 first_out=2 last_in=3 last_out=14 stalls=4",
        "TIMING items=1 first_in=0 first_out=2 last_in=0 last_out=2 stalls=0",
    ] {
        assert_eq!(parse_timing(bad), None, "{bad}");
    }
}

#[test]
fn compare_names_each_field_that_disagrees() {
    let c = CyclesCfg::default_for(12);
    let dof = Timed::of(StageId::Dof).expect("dof has RTL");
    let m = Measured {
        timed: dof,
        latency: 8,
        ii_full: Interval {
            cycles: 99,
            inputs: 99,
        },
        ii_stall: Interval {
            cycles: 120,
            inputs: 99,
        },
        stalls: 40,
        items: 100,
    };
    let miss = timing::compare(&m, &c.dof);
    assert_eq!(miss.len(), 1, "{miss:?}");
    assert_eq!(miss[0].field, "ii under stalls");
    let mut t = c.dof;
    t.latency = 7;
    t.lanes = 3;
    let fields: Vec<_> = timing::compare(&m, &t).iter().map(|m| m.field).collect();
    assert_eq!(fields, ["latency", "ii under stalls", "lanes"]);
    let msg = timing::compare(&m, &t)[0].to_string();
    assert!(
        msg.contains("stage dof: latency") && msg.contains("measures 8") && msg.contains("says 7"),
        "{msg}"
    );
    // The measured values replace latency and ii only.
    let mut cfg = c.clone();
    cfg.dof = t;
    let from_rtl = timing::with_measured(&cfg, &[m]);
    assert_eq!(
        (from_rtl.dof.latency, from_rtl.dof.ii, from_rtl.dof.lanes),
        (8, 1, 3)
    );
    assert_eq!(TIMED.len(), 6);
}

#[test]
fn the_presets_agree_with_the_rtl() {
    if !verilator("hdl timing, presets") {
        return;
    }
    let cache = cache();
    for hw in ["linear12", "log8-logadd"] {
        let (c, out, err) = igemu(&["hdl", "timing", "--hw", hw, "--cache-dir", &cache]);
        assert_eq!(c, 0, "{hw}: {out}{err}");
        for t in TIMED {
            let line = out
                .lines()
                .find(|l| l.starts_with(t.timing.name()) && l.contains(t.module))
                .unwrap_or_else(|| panic!("{hw}: no line of {}: {out}", t.module));
            assert!(line.ends_with("agree"), "{line}");
        }
    }
}

#[test]
fn a_wrong_latency_or_ii_in_the_hardware_file_exits_1_naming_it() {
    if !verilator("hdl timing, wrong latency") {
        return;
    }
    let d = tmp("wrong");
    let f = d.join("slow.toml");
    std::fs::write(
        &f,
        "preset = \"linear12\"\n[cycles.dither]\nlatency = 3\n[cycles.gamma]\nii = 2\n",
    )
    .expect("hw");
    let fs = f.display().to_string();
    let cache = cache();
    let (c, out, err) = igemu(&["hdl", "timing", "--hw", &fs, "--cache-dir", &cache]);
    assert_eq!(c, 1, "{out}{err}");
    assert!(
        out.contains("mismatch: stage dither: latency: the RTL (dither_ordered) measures 1, [cycles.dither] says 3"),
        "{out}"
    );
    assert!(
        out.contains(
            "mismatch: stage gamma: ii: the RTL (gamma_lut) measures 1.000, [cycles.gamma] says 2"
        ),
        "{out}"
    );
    assert_eq!(out.matches("mismatch:").count(), 3, "{out}");
    // --stage limits the run to one stage: the disagreeing one alone exits 1, another 0.
    let (c, out, _) = igemu(&[
        "hdl",
        "timing",
        "--stage",
        "dither",
        "--hw",
        &fs,
        "--cache-dir",
        &cache,
    ]);
    assert_eq!(c, 1, "{out}");
    let (c, out, _) = igemu(&[
        "hdl",
        "timing",
        "--stage",
        "accumulate",
        "--hw",
        &fs,
        "--cache-dir",
        &cache,
    ]);
    assert_eq!(c, 0, "{out}");
    assert_eq!(out.matches("agree").count(), 1, "{out}");
}

/// The measurement follows the RTL: a gamma LUT with one more pipeline stage (a copy of the
/// models given with --hdl-dir) measures latency 3 against the preset's 2.
#[test]
fn deeper_rtl_is_measured_and_disagrees() {
    if !verilator("hdl timing, deeper RTL") {
        return;
    }
    let d = tmp("deeper");
    let models = d.join("models");
    for (p, text) in igemu::hdl::models::SOURCES {
        let f = models.join(p);
        std::fs::create_dir_all(f.parent().expect("parent")).expect("dir");
        let text = if *p == "rtl/gamma_lut.v" {
            assert!(text.contains("parameter LATENCY   = 2"), "{text}");
            text.replace("parameter LATENCY   = 2", "parameter LATENCY   = 3")
        } else {
            text.to_string()
        };
        std::fs::write(f, text).expect("write");
    }
    let ms = models.display().to_string();
    let cache = cache();
    let (c, out, err) = igemu(&[
        "hdl",
        "timing",
        "--stage",
        "gamma",
        "--hdl-dir",
        &ms,
        "--cache-dir",
        &cache,
    ]);
    assert_eq!(c, 1, "{out}{err}");
    assert!(
        out.contains(
            "mismatch: stage gamma: latency: the RTL (gamma_lut) measures 3, [cycles.gamma] says 2"
        ),
        "{out}"
    );
}

/// The gamma line of an `igemu cycles` table and the frame line.
fn gamma_and_frame(out: &str) -> (String, String) {
    let find = |p: &str| {
        out.lines()
            .find(|l| l.starts_with(p))
            .unwrap_or_else(|| panic!("no {p} line: {out}"))
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
    };
    (find("gamma "), find("frame: "))
}

/// `cycles --timing-from-rtl` replaces a hardware file's latency and ii by the RTL's: a
/// gamma latency of 5 becomes the measured 2 and the frame time is the preset's again.
#[test]
fn cycles_timing_from_rtl_uses_the_measured_values() {
    if !verilator("cycles --timing-from-rtl") {
        return;
    }
    let d = tmp("from-rtl");
    let f = d.join("gamma5.toml");
    std::fs::write(
        &f,
        "preset = \"linear12\"\n[cycles.gamma]\nlatency = 5\nii = 3\n",
    )
    .expect("hw");
    let fs = f.display().to_string();
    let cache = cache();
    let (c, preset, err) = igemu(&["cycles"]);
    assert_eq!(c, 0, "{err}");
    let (c, typed, err) = igemu(&["cycles", "--hw", &fs]);
    assert_eq!(c, 0, "{err}");
    let (c, rtl, err) = igemu(&[
        "cycles",
        "--hw",
        &fs,
        "--timing-from-rtl",
        "--cache-dir",
        &cache,
    ]);
    assert_eq!(c, 0, "{err}");
    let (p, t, r) = (
        gamma_and_frame(&preset),
        gamma_and_frame(&typed),
        gamma_and_frame(&rtl),
    );
    assert!(t.0.starts_with("gamma 1 5 3 "), "{}", t.0);
    assert!(r.0.starts_with("gamma 1 2 1 "), "{}", r.0);
    assert_ne!(t.1, p.1);
    assert_eq!(r, p);
    assert!(
        rtl.contains("timing from the RTL (Verilator): raster latency 4 ii 1.000"),
        "{rtl}"
    );
}

/// `hdl timing --correlate`: the RTL's cycles on the default scene's token stream (with an
/// ordered dither planned) are within the documented bound of the model's for the five stages.
#[test]
fn the_rtl_on_the_real_token_stream_correlates_with_the_model() {
    if !verilator("hdl timing --correlate") {
        return;
    }
    let d = tmp("correlate");
    let f = d.join("bayer4.toml");
    std::fs::write(&f, "preset = \"linear12\"\n[dither]\nkind = \"bayer4\"\n").expect("hw");
    let fs = f.display().to_string();
    let cache = cache();
    let (c, out, err) = igemu(&[
        "hdl",
        "timing",
        "--correlate",
        "--hw",
        &fs,
        "--cache-dir",
        &cache,
    ]);
    assert_eq!(c, 0, "{out}{err}");
    for st in ["raster", "accumulate", "dof", "gamma", "dither"] {
        let line = out
            .lines()
            .find(|l| l.starts_with(&format!("{st} ")))
            .unwrap_or_else(|| panic!("no {st} line: {out}"));
        let v: Vec<&str> = line.split_whitespace().collect();
        let (rtl, model): (f64, f64) = (v[5].parse().expect("rtl"), v[6].parse().expect("model"));
        assert!(rtl > 1000.0, "{line}");
        let e = (rtl - model) / model * 100.0;
        assert!(e.abs() <= igemu::hdl::correlate::BOUND_PCT, "{line}");
    }
    assert!(out.contains("not in the plan: logdomain"), "{out}");
}
