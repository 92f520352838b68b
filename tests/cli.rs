//! The `igemu` binary: the README's commands, exit codes and error messages.

mod common;

use common::igemu;

fn tmp(name: &str) -> String {
    let d = std::env::temp_dir().join(format!("igemu-cli-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name).to_string_lossy().into_owned()
}

fn write(name: &str, text: &str) -> String {
    let p = tmp(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn render_default_scene_writes_image_and_json_report() {
    let png = tmp("out.png");
    let refp = tmp("ref.png");
    let diff = tmp("diff.png");
    let acc = tmp("acc.png");
    let rep = tmp("report.json");
    let (code, stdout, stderr) = igemu(&[
        "render",
        "-o",
        &png,
        "--reference-out",
        &refp,
        "--diff-out",
        &diff,
        "--dump",
        &format!("accumulate={acc}"),
        "--report",
        &rep,
    ]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("end to end"), "{stdout}");
    for p in [&png, &refp, &diff, &acc] {
        assert!(std::fs::metadata(p).unwrap().len() > 100, "{p}");
    }
    let img = image::open(&acc).unwrap();
    assert_eq!(img.color(), image::ColorType::L16);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&rep).unwrap()).unwrap();
    for key in [
        "igemu_version",
        "scene",
        "hardware",
        "plan",
        "stages",
        "end_to_end",
        "overflows",
        "storage_bits",
        "lut_bits",
        "timing",
    ] {
        assert!(v.get(key).is_some(), "missing key {key}");
    }
    assert!(v["end_to_end"]["codes"]["identical_fraction"].is_number());
    assert!(v["stages"][2]["fixed_ms"].is_number() && v["stages"][2]["float_ms"].is_number());
}

#[test]
fn check_exits_1_when_a_threshold_fails_and_0_otherwise() {
    let (code, out, _) = igemu(&["check", "--hw", "linear8", "--min-identical", "1.0"]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("FAILED"));
    let (code, out, err) = igemu(&["check", "--max-code-diff", "255"]);
    assert_eq!(code, 0, "{out}{err}");
}

#[test]
fn widths_and_dof_calculators_print_the_papers_numbers() {
    let (code, out, _) = igemu(&[
        "widths",
        "--contrast",
        "100",
        "--weber",
        "0.02",
        "--gamma",
        "2.4",
        "--json",
    ]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["linear"]["levels"].as_f64().unwrap().round(), 4950.0);
    assert_eq!(v["linear"]["bits"], 13);
    assert_eq!(v["dac"]["bits"], 9);
    let (code, out, _) = igemu(&[
        "dof",
        "--f-number",
        "11",
        "--coc",
        "0.035",
        "--focal",
        "200",
        "--distance",
        "2500",
    ]);
    assert_eq!(code, 0);
    assert!(out.contains("58.74") && out.contains("61.64"), "{out}");
}

fn expect_error(args: &[&str], needles: &[&str]) {
    let (code, out, err) = igemu(args);
    assert_eq!(code, 2, "args {args:?}: stdout {out} stderr {err}");
    for n in needles {
        assert!(err.contains(n), "args {args:?}: `{n}` not in: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn bad_input_gets_a_message_with_file_line_field_and_range_and_exit_2() {
    expect_error(
        &["render", "/nonexistent/scene.toml"],
        &["/nonexistent/scene.toml", "cannot read"],
    );
    let bad = write("malformed.toml", "[image\nwidth = 3\n");
    expect_error(&["render", &bad], &["malformed.toml:1"]);
    let hw = write(
        "unknown.toml",
        "[accumulate]\nfilter = \"tent\"\nbogus = 1\n",
    );
    expect_error(&["render", "--hw", &hw], &["unknown.toml:3", "bogus"]);
    let hw = write("wide.toml", "[accumulate]\nframe = \"UQ40.0\"\n");
    expect_error(&["render", "--hw", &hw], &["wide.toml:2", "1..=32"]);
    let hw = write("lut.toml", "[accumulate]\nframe = \"UQ24.0\"\n");
    expect_error(
        &["render", "--hw", &hw],
        &["lut.toml:2", "accumulate.frame", "1..=20"],
    );
    let hw = write("dac.toml", "[gamma]\ndac_bits = 0\n");
    expect_error(
        &["render", "--hw", &hw],
        &["dac.toml:2", "gamma.dac_bits", "1..=16"],
    );
    let hw = write("samples.toml", "[raster]\nsamples = 3\n");
    expect_error(
        &["render", "--hw", &hw],
        &["samples.toml:2", "raster.samples"],
    );
    let hw = write("sigma.toml", "[accumulate]\ngaussian_sigma = nan\n");
    expect_error(
        &["render", "--hw", &hw],
        &["sigma.toml:2", "gaussian_sigma"],
    );
    expect_error(&["render", "--hw", "linear99"], &["linear99", "linear12"]);
    expect_error(&["render", "--dump", "nothing"], &["TAP=PATH"]);
    // The taps derive from the stages: every stage with an image tap is offered.
    expect_error(
        &["render", "--dump", "coverage=x.png"],
        &[
            "unknown tap `coverage`",
            "accumulate.coverage",
            "dof.depth",
            "gamma.codes",
        ],
    );
    // A stage the plan does not run has no taps (the default scene has no dither).
    expect_error(
        &["render", "--dump", "dither=/tmp/igemu-cli-dither.png"],
        &["`dither` is not in the plan", "dither.kind = \"none\""],
    );
    expect_error(
        &["widths", "--contrast", "0.5", "--weber", "0.02"],
        &["contrast"],
    );
    expect_error(
        &[
            "dof",
            "--f-number",
            "11",
            "--coc",
            "0.035",
            "--focal",
            "-200",
            "--distance",
            "2500",
        ],
        &["focal"],
    );
    expect_error(
        &["check", "--min-identical", "2"],
        &["--min-identical", "0..=1"],
    );
}

#[test]
fn bad_scene_files_name_line_and_field() {
    let cam =
        "[camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nnear = 1.0\nfar = 10.0\n";
    let p = write(
        "zero.toml",
        &format!("[image]\nwidth = 0\nheight = 10\nbackground = 0.0\n{cam}"),
    );
    expect_error(&["render", &p], &["zero.toml:2", "width"]);
    let p = write(
        "nan.toml",
        &format!("[image]\nwidth = 10\nheight = 10\nbackground = nan\n{cam}"),
    );
    expect_error(&["render", &p], &["nan.toml:4", "background"]);
    let p = write(
        "huge.toml",
        &format!("[image]\nwidth = 100000\nheight = 10\nbackground = 0.0\n{cam}"),
    );
    expect_error(&["render", &p], &["huge.toml:2", "width"]);
    let p = write("camera.toml", "[image]\nwidth = 10\nheight = 10\n");
    expect_error(&["render", &p], &["camera.toml", "camera"]);
    let p = write(
        "far.toml",
        "[image]\nwidth = 10\nheight = 10\n[camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nnear = 1.0\nfar = 0.5\n",
    );
    expect_error(&["render", &p], &["far.toml:8", "far"]);
}

#[test]
fn a_bad_choice_names_the_value_and_the_choices_and_exits_2() {
    // The stages with an HDL model, in flow order (the CLI derives them from StageId::ALL).
    let stages: Vec<&str> = igemu::stage_id::StageId::ALL
        .into_iter()
        .filter(|&s| igemu::hdl::module_of(s).is_some())
        .map(|s| s.name())
        .collect();
    let stages = stages.join(", ");
    assert!(
        stages.contains("gamma") && !stages.contains("raster"),
        "{stages}"
    );
    let out = tmp("hdl-bad");
    for stage in ["raster", "nope"] {
        expect_error(
            &["hdl", "vectors", "--stage", stage, "--out", &out],
            &["--stage", stage, &stages],
        );
    }
    expect_error(
        &[
            "hdl", "vectors", "--stage", "gamma", "--out", &out, "--sim", "ghdl",
        ],
        &["--sim", "ghdl", "icarus, verilator"],
    );
    expect_error(
        &["ranges", "--export", "vhdl"],
        &["--export", "vhdl", "ac_fixed, ap_fixed, systemc, verilog"],
    );
    expect_error(
        &["flicker", "--filter", "sinc"],
        &["--filter", "sinc", "box, tent, gaussian"],
    );
}

/// Every numeric flag out of its range exits 2 naming the flag and the range, before any
/// work (`-0.1` too: clap would take it for a flag).
#[test]
fn numeric_flags_out_of_range_exit_2_naming_the_flag() {
    for v in ["2", "nan", "inf", "-0.1", "1.0000001"] {
        for flag in ["--max-visible", "--min-identical"] {
            expect_error(&["check", flag, v], &[flag, "0..=1"]);
        }
    }
    for (flag, v, range) in [
        ("--gamma", "1e308", "(1, 5]"),
        ("--gamma", "1", "(1, 5]"),
        ("--gamma", "nan", "(1, 5]"),
        ("--contrast", "nan", "> 1"),
        ("--contrast", "inf", "> 1"),
        ("--contrast", "-3", "> 1"),
        ("--weber", "1", "(0, 1)"),
        ("--weber", "0", "(0, 1)"),
        ("--weber", "-0.02", "(0, 1)"),
    ] {
        let mut args = vec!["widths"];
        for (f, ok) in [
            ("--contrast", "100"),
            ("--weber", "0.02"),
            ("--gamma", "2.4"),
        ] {
            args.extend([f, if f == flag { v } else { ok }]);
        }
        expect_error(&args, &[flag, range]);
    }
    // Finite flags whose widths are beyond any code.
    expect_error(
        &["widths", "--contrast", "1e300", "--weber", "0.02"],
        &["--contrast", "64-bit", "1e300"],
    );
    expect_error(
        &["widths", "--contrast", "100", "--weber", "1e-300"],
        &["--weber", "64-bit"],
    );
    let dof = |f: &str, c: &str, fl: &str, d: &str| {
        vec![
            "dof".to_string(),
            "--f-number".into(),
            f.into(),
            "--coc".into(),
            c.into(),
            "--focal".into(),
            fl.into(),
            "--distance".into(),
            d.into(),
        ]
    };
    for (args, flag) in [
        (dof("1e308", "0.035", "200", "2500"), "--f-number"),
        (dof("nan", "0.035", "200", "2500"), "--f-number"),
        (dof("-11", "0.035", "200", "2500"), "--f-number"),
        (dof("11", "1e308", "200", "2500"), "--coc"),
        (dof("11", "1e-308", "200", "2500"), "--coc"),
        (dof("11", "0.035", "inf", "2500"), "--focal"),
        (dof("11", "0.035", "200", "1e308"), "--distance"),
        (dof("11", "0.035", "200", "100"), "--distance"),
    ] {
        let a: Vec<&str> = args.iter().map(|s| s.as_str()).collect();
        expect_error(&a, &[flag, "got"]);
    }
    for v in ["nan", "inf", "0", "-5", "1e308"] {
        expect_error(
            &["cycles", "--clock-mhz", v],
            &["--clock-mhz", "[0.001, 10000]"],
        );
    }
}

/// A contrast whose widths round to 0 bits has no narrower width to try: no u32 underflow
/// (the tests and the binary run with overflow checks), exit 0.
#[test]
fn widths_of_a_tiny_contrast_do_not_underflow() {
    let (code, out, err) = igemu(&["widths", "--contrast", "1.01", "--weber", "0.02"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        out.contains("->  0 bits") && !err.contains("panicked"),
        "{out}{err}"
    );
    // The library directly: a recommendation of 0 and of 1 bit.
    let mut w = igemu::analysis::calc::widths(1.01, 0.02, 2.4).unwrap();
    assert_eq!((w.linear.bits, w.log_grades.bits), (0, 0));
    assert!(
        igemu::analysis::widths::validate_widths(&w)
            .iter()
            .all(|c| c.code_bits > 0 && c.dac_bits > 0)
    );
    w.linear.bits = 1;
    w.dac.bits = 1;
    let checks = igemu::analysis::widths::validate_widths(&w);
    assert_eq!(
        checks.len(),
        1,
        "only the recommended 1-bit linear row: {checks:?}"
    );
    assert!(checks[0].recommended);
}

/// A scene argument that is no file and no embedded scene names what the user meant
/// (issue 30): the nearest embedded name, or that a hardware preset was given as the scene;
/// and `--hw` given a scene name or a near miss of a preset says so.
#[test]
fn a_mistyped_scene_or_preset_names_what_was_meant() {
    let scenes = "default, default-pinhole, cone-focus, default-colour";
    expect_error(
        &["render", "cone_focus"],
        &["`cone_focus`", "did you mean `cone-focus`", scenes],
    );
    expect_error(
        &["check", "Default-Colour"],
        &["did you mean `default-colour`"],
    );
    expect_error(
        &["render", "linear8"],
        &["`linear8` is a hardware preset", "--hw linear8", scenes],
    );
    let (code, _, err) = igemu(&["render", "qqqqqqqqqq"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(scenes) && !err.contains("did you mean"),
        "{err}"
    );
    expect_error(&["render", "--hw", "linear-8"], &["did you mean `linear8`"]);
    expect_error(
        &["render", "--hw", "cone-focus"],
        &["`cone-focus` is an embedded scene"],
    );
    // A path (a `/` or `.toml`) is still read as a file.
    expect_error(&["render", "nosuch.toml"], &["nosuch.toml", "cannot read"]);
}

/// `igemu cost --json`: the table as JSON, the same numbers as the text table.
#[test]
fn cost_takes_json() {
    let (code, out, err) = igemu(&["cost", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("cost --json is JSON");
    assert_eq!(v["hardware"], "linear12");
    assert_eq!(v["scene"], "default");
    let stages = v["stages"].as_array().expect("stages");
    let (code, text, err) = igemu(&["cost"]);
    assert_eq!(code, 0, "{err}");
    let mut rows: Vec<&str> = text.lines().skip(2).collect();
    // The default scene streams its depth of field: the last line is the line buffers.
    let lb = &v["line_buffers"];
    assert_eq!(lb["schedule"], "stream");
    assert_eq!(lb["charged"], true);
    assert!(lb["bits"].as_u64().unwrap() > 0);
    assert_eq!(
        rows.pop(),
        Some(
            format!(
                "dof stream line buffers: {} bits ({} rows; dof.schedule = \"stream\")",
                lb["bits"], lb["rows"]
            )
            .as_str()
        ),
        "{text}"
    );
    assert_eq!(stages.len(), rows.len(), "{text}");
    for (s, row) in stages.iter().zip(&rows) {
        let f: Vec<&str> = row.split_whitespace().collect();
        assert_eq!(s["stage"], f[0], "{row}");
        assert_eq!(s["storage_bits"].to_string(), f[1], "{row}");
        assert_eq!(s["lut_bits"].to_string(), f[2], "{row}");
        assert!(s["synth"].is_null());
    }
    assert!(stages.iter().any(|s| s["hdl_module"] == "gamma_lut"));
}

/// `-o /dev/null` (a special file without a `.png` extension) is written as PNG in place;
/// `/dev/null` stays the device (no rename over it), and several outputs may share it.
#[cfg(unix)]
#[test]
fn dev_null_is_an_output() {
    use std::os::unix::fs::FileTypeExt;
    let (code, out, err) = igemu(&[
        "render",
        "default-pinhole",
        "-o",
        "/dev/null",
        "--diff-out",
        "/dev/null",
        "--report",
        "/dev/null",
    ]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("wrote /dev/null"), "{out}");
    let m = std::fs::metadata("/dev/null").expect("/dev/null");
    assert!(m.file_type().is_char_device(), "/dev/null was replaced");
    // A regular file without an extension is still refused by its format.
    let d = std::env::temp_dir().join(format!("igemu-cli-noext-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&d);
    let p = d.join("image");
    expect_error(
        &["render", "default-pinhole", "-o", p.to_str().unwrap()],
        &["image format", "name the file .png"],
    );
    assert!(!p.exists());
}

/// `igemu ranges` says why its overflow counters have no range (issue 30): the `-` rows are
/// listed under the table, and `--json` marks them `overflow_only`.
#[test]
fn ranges_say_which_signals_only_count_overflows() {
    let (code, out, err) = igemu(&["ranges"]);
    assert_eq!(code, 0, "{err}");
    let note = out.lines().last().expect("a last line");
    assert!(
        note.starts_with("-: ") && note.contains("count only their overflows"),
        "{out}"
    );
    for row in out
        .lines()
        .filter(|l| l.split_whitespace().nth(3) == Some("-"))
    {
        let name = row.split_whitespace().nth(1).expect("signal");
        assert!(
            note.contains(name),
            "{name} has no range and is not in: {note}"
        );
    }
    let (code, json, err) = igemu(&["ranges", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: Vec<serde_json::Value> = serde_json::from_str(&json).expect("JSON");
    for s in &v {
        let counter = s["overflow_only"].as_bool().expect("overflow_only");
        assert_eq!(counter, s["count"] == 0 && s["min"].is_null(), "{s}");
        assert_eq!(counter, note.contains(s["signal"].as_str().unwrap()), "{s}");
    }
}
