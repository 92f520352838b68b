//! Sweeps: grid expansion and validation, resume after a real kill, shards, parallel = serial.

mod common;

use igemu::files::TomlFile;
use igemu::sweep::{self, grid, pareto};
use std::path::PathBuf;
use std::process::{Command, Output};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("igemu-sweep-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// A small scene file: a shaded triangle, a line and a light point on 160x120.
fn scene_file(dir: &std::path::Path) -> String {
    let objects = [
        common::tri(
            [[10.0, 10.0, 0.3], [150.0, 20.0, 0.5], [40.0, 110.0, 0.7]],
            [0.05, 0.9, 0.4],
        ),
        common::line([5.0, 100.0, 0.2], [155.0, 60.0, 0.2], 0.7, 1.5),
        common::point(80.0, 30.0, 0.1, 1.0, 2.0),
    ]
    .concat();
    let text = format!(
        "[image]\nwidth = 160\nheight = 120\nbackground = 0.02\n\n\
         [camera]\nposition = [0.0, 0.0, 10.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nfov_y_deg = 40.0\nnear = 1.0\nfar = 100.0\n\n\
         [display]\ncontrast = 100.0\ngamma = 2.4\nweber = 0.02\nb_max = 100.0\n\n{objects}"
    );
    let p = dir.join("small.toml");
    std::fs::write(&p, text).expect("write scene");
    p.to_string_lossy().into_owned()
}

fn grid_file(dir: &std::path::Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write grid");
    p.to_string_lossy().into_owned()
}

fn igemu(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_igemu"))
        .args(args)
        .output()
        .expect("run igemu")
}

fn rows(path: &str) -> Vec<serde_json::Value> {
    let (rows, dropped) = sweep::read_rows(path).expect("read rows");
    assert!(!dropped, "{path} has a partial line");
    rows.iter().map(sweep::without_timing).collect()
}

const GRID: &str = "accumulate.frame = [\"UQ10.0\", \"UQ11.0\", \"UQ12.0\"]\n\
                    gamma.dac_bits = [6, 8]\npreset = [\"linear12\"]\n";

#[test]
fn expansion_is_ordered_last_field_fastest_and_validated() {
    let f = TomlFile::from_text("g.toml", GRID);
    let g = grid::Grid::parse(&f).unwrap();
    assert_eq!(g.len(), 6);
    let c = g.expand(&f).unwrap();
    let keys: Vec<&str> = c.iter().map(|c| c.canonical.as_str()).collect();
    assert_eq!(
        keys[0],
        "accumulate.frame=\"UQ10.0\";gamma.dac_bits=6;preset=\"linear12\""
    );
    assert_eq!(
        keys[1],
        "accumulate.frame=\"UQ10.0\";gamma.dac_bits=8;preset=\"linear12\""
    );
    assert_eq!(c[5].hw.accumulate.frame.format.int_bits, 12);
    assert_eq!(c[5].hw.gamma.dac_bits, 8);
    // The vertex intensity follows the accumulator, as in a hardware file.
    assert_eq!(c[0].hw.input.intensity.format.int_bits, 10);
    // Ids are stable (FNV-1a) and distinct.
    let ids: std::collections::BTreeSet<String> =
        c.iter().map(|c| sweep::row_id("s", &c.canonical)).collect();
    assert_eq!(ids.len(), 6);
    assert_eq!(igemu::fnv::fnv1a(b""), 0xcbf2_9ce4_8422_2325);
    assert_eq!(igemu::fnv::fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
}

#[test]
fn bad_grids_and_shards_exit_2_before_any_work() {
    let d = tmp("bad");
    let out = d.join("out.jsonl");
    let out_s = out.to_string_lossy().into_owned();
    let cases = [
        ("unknown.toml", "gamma.dac_bitz = [8, 9]\n", "dac_bitz"),
        ("empty.toml", "gamma.dac_bits = []\n", "empty"),
        ("range.toml", "gamma.dac_bits = [8, 17]\n", "1..=16"),
        ("scalar.toml", "gamma.dac_bits = 8\n", "list"),
        ("preset.toml", "preset = [\"linear99\"]\n", "linear99"),
    ];
    for (name, text, expect) in cases {
        let g = grid_file(&d, name, text);
        let o = igemu(&["sweep", "--grid", &g, "--out", &out_s]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(expect), "{name}: {err}");
        assert!(err.contains(name), "{name} names the file: {err}");
        assert!(!out.exists(), "{name}: no work before the error");
    }
    let g = grid_file(&d, "ok.toml", "gamma.dac_bits = [8]\n");
    for (flag, value) in [
        ("--plot", "pareto.gif"),
        ("--flicker", "1"),
        ("--flicker", "65"),
        ("--axes", "flicker,cost"),
        ("--jobs", "0"),
    ] {
        let o = igemu(&["sweep", "--grid", &g, "--out", &out_s, flag, value]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flag} {value}: {err}");
        assert!(err.contains(flag), "{flag} {value}: {err}");
        assert!(!out.exists());
    }
    for shard in ["3/2", "0/2", "1/0", "x"] {
        let o = igemu(&["sweep", "--grid", &g, "--out", &out_s, "--shard", shard]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{shard}: {err}");
        assert!(err.contains("--shard"), "{err}");
        assert!(!out.exists());
    }
}

#[test]
fn shards_concatenate_to_the_full_run_and_parallel_equals_serial() {
    let d = tmp("shards");
    let scene = scene_file(&d);
    let g = grid_file(&d, "g.toml", GRID);
    let full = d.join("full.jsonl").to_string_lossy().into_owned();
    let o = igemu(&["sweep", &scene, "--grid", &g, "--out", &full]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let full_rows = rows(&full);
    assert_eq!(full_rows.len(), 6);
    for (i, r) in full_rows.iter().enumerate() {
        assert_eq!(r["index"], i);
    }
    let mut cat = Vec::new();
    for k in 1..=4 {
        let p = d.join(format!("s{k}.jsonl")).to_string_lossy().into_owned();
        let o = igemu(&[
            "sweep",
            &scene,
            "--grid",
            &g,
            "--out",
            &p,
            "--shard",
            &format!("{k}/4"),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        cat.extend(rows(&p));
    }
    assert_eq!(cat, full_rows);
    let par = d.join("par.jsonl").to_string_lossy().into_owned();
    let o = igemu(&["sweep", &scene, "--grid", &g, "--out", &par, "--jobs", "3"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(rows(&par), full_rows);
    // The Pareto table is printed.
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("Pareto front"), "{stdout}");
}

#[test]
fn a_killed_sweep_resumes_to_the_uninterrupted_result() {
    let d = tmp("kill");
    let scene = scene_file(&d);
    let g = grid_file(
        &d,
        "g.toml",
        "accumulate.frame = [\"UQ9.0\", \"UQ10.0\", \"UQ11.0\", \"UQ12.0\"]\n\
         gamma.dac_bits = [6, 7, 8, 9, 10]\nraster.samples = [4, 8]\n",
    );
    let full = d.join("full.jsonl").to_string_lossy().into_owned();
    let o = igemu(&["sweep", &scene, "--grid", &g, "--out", &full]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let full_rows = rows(&full);
    assert_eq!(full_rows.len(), 40);

    let out = d.join("killed.jsonl").to_string_lossy().into_owned();
    let mut child = Command::new(env!("CARGO_BIN_EXE_igemu"))
        .args(["sweep", &scene, "--grid", &g, "--out", &out])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("spawn");
    // Wait for a few completed rows, then SIGKILL.
    let t = std::time::Instant::now();
    loop {
        let n = std::fs::read_to_string(&out)
            .map(|s| s.matches('\n').count())
            .unwrap_or(0);
        if n >= 3 || t.elapsed().as_secs() > 60 {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    child.kill().expect("kill");
    let status = child.wait().expect("wait");
    assert!(!status.success(), "the sweep was killed, not finished");
    let (before, _) = sweep::read_rows(&out).unwrap();
    assert!(
        !before.is_empty() && before.len() < 40,
        "killed mid-run: {} rows",
        before.len()
    );
    // Simulate a partial last line as a kill inside a write would leave it.
    {
        use std::io::Write;
        let mut f = std::fs::OpenOptions::new().append(true).open(&out).unwrap();
        f.write_all(b"{\"id\":\"0123\",\"index\":").unwrap();
    }
    let o = igemu(&["sweep", &scene, "--grid", &g, "--out", &out, "--resume"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains(&format!("{} kept", before.len())),
        "reuses the completed rows: {err}"
    );
    let resumed = rows(&out);
    let ids: std::collections::BTreeSet<&str> =
        resumed.iter().map(|r| r["id"].as_str().unwrap()).collect();
    assert_eq!(ids.len(), 40, "every configuration exactly once");
    assert_eq!(resumed, full_rows);
    // Resuming a complete file computes nothing.
    let o = igemu(&["sweep", &scene, "--grid", &g, "--out", &out, "--resume"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("40 kept"));
    assert_eq!(rows(&out), full_rows);
}

#[test]
fn pareto_front_keeps_exactly_the_non_dominated_rows() {
    let d = tmp("pareto");
    let scene = scene_file(&d);
    let g = grid_file(&d, "g.toml", GRID);
    let out = d.join("o.jsonl").to_string_lossy().into_owned();
    let o = igemu(&["sweep", &scene, "--grid", &g, "--out", &out]);
    assert!(o.status.success());
    let (rows, _) = sweep::read_rows(&out).unwrap();
    let axes = pareto::Axis::parse_list("error,cost").unwrap();
    let front = pareto::front(&rows, &axes);
    assert!(!front.is_empty());
    for (i, r) in rows.iter().enumerate() {
        let dominated = rows.iter().any(|o| pareto::dominates(o, r, &axes));
        assert_eq!(front.contains(&i), !dominated, "row {i}");
    }
    // The plotters plot: every row grey in both panels (+ a legend dot each), each panel's
    // front red (its points, its line and a legend line).
    let svg_path = d.join("p.svg").to_string_lossy().into_owned();
    sweep::plot::write(&rows, pareto::Axis::Error, &svg_path).unwrap();
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    let fc = pareto::front(&rows, &[pareto::Axis::Error, pareto::Axis::Cost]).len();
    let ft = pareto::front(&rows, &[pareto::Axis::Error, pareto::Axis::Throughput]).len();
    assert_eq!(svg.matches("fill=\"#FF0000\"").count(), fc + ft);
    assert_eq!(svg.matches("fill=\"#969696\"").count(), 2 * rows.len() + 2);
    assert_eq!(
        svg.matches("<polyline fill=\"none\" opacity=\"1\" stroke=\"#FF0000\"")
            .count(),
        4
    );
    assert!(svg.contains("mean Weber error") && svg.contains("Pareto front: "));
    let png_path = d.join("p.png").to_string_lossy().into_owned();
    sweep::plot::write(&rows, pareto::Axis::Error, &png_path).unwrap();
    let png = image::open(&png_path).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), sweep::plot::SIZE);
    assert!(
        png.pixels().any(|p| p.0 == [255, 0, 0]),
        "the front is drawn"
    );
    assert!(sweep::plot::write(&rows, pareto::Axis::Error, "p.gif").is_err());
    assert!(pareto::Axis::parse_list("error").is_err());
    assert!(pareto::Axis::parse_list("error,bogus").is_err());
}

#[test]
fn flicker_metrics_are_the_flicker_sweeps_worst_object_and_only_when_asked() {
    let d = tmp("flicker");
    let scene = scene_file(&d);
    let text = "gamma.dac_bits = [6, 10]\naccumulate.filter = [\"box\", \"tent\"]\n";
    let g = grid_file(&d, "g.toml", text);
    let out = d.join("o.jsonl").to_string_lossy().into_owned();
    let o = igemu(&[
        "sweep",
        &scene,
        "--grid",
        &g,
        "--out",
        &out,
        "--flicker",
        "4",
        "--axes",
        "flicker,cost",
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("displayed flicker ripple %"), "{stdout}");
    let (rows, _) = sweep::read_rows(&out).unwrap();
    let f = TomlFile::from_text("g.toml", text);
    let configs = grid::Grid::parse(&f).unwrap().expand(&f).unwrap();
    assert_eq!(rows.len(), 4);
    for (r, c) in rows.iter().zip(&configs) {
        let m = r.flicker.as_ref().expect("flicker metrics in the row");
        let direct = igemu::analysis::flicker::flicker(&c.hw, 4).unwrap();
        let worst = direct
            .objects
            .iter()
            .map(|o| o.displayed_ripple_pct)
            .fold(0.0, f64::max);
        assert_eq!(m.phases, 4);
        assert_eq!(m.displayed_ripple_pct, worst);
        assert!(direct.objects.iter().any(|o| o.object == m.worst_object));
    }
    // The box filter flickers more than the tent filter (docs/reference.md §1: equal-energy filtering).
    assert!(
        rows[0].flicker.as_ref().unwrap().displayed_ripple_pct
            > rows[1].flicker.as_ref().unwrap().displayed_ripple_pct
    );
    // Without --flicker the rows have no flicker key.
    let o = igemu(&["sweep", &scene, "--grid", &g, "--out", &out]);
    assert!(o.status.success());
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(!text.contains("flicker"), "{text}");
}

#[test]
fn stage_reuse_gives_the_rows_of_full_renders() {
    let d = tmp("reuse");
    let scene_path = scene_file(&d);
    let scene = igemu::scene::Scene::load(&scene_path).unwrap();
    let text = "gamma.dac_bits = [6, 8, 10]\ndither.kind = [\"none\", \"bayer4\"]\n\
                accumulate.frame = [\"UQ10.0\", \"UQ12.0\"]\n";
    let f = TomlFile::from_text("g.toml", text);
    let configs = grid::Grid::parse(&f).unwrap().expand(&f).unwrap();
    let cache = igemu::pipeline::Cache::new();
    let mut outs = Vec::new();
    for (name, c) in [("cached", Some(&cache)), ("full", None)] {
        let out = d
            .join(format!("{name}.jsonl"))
            .to_string_lossy()
            .into_owned();
        let opts = sweep::SweepOptions {
            out: &out,
            resume: false,
            shard: None,
            jobs: 1,
            cache: c,
            flicker: None,
        };
        sweep::run(&configs, std::slice::from_ref(&scene), &opts, &|_, _| {}).unwrap();
        outs.push(rows(&out));
    }
    assert_eq!(outs[0].len(), 12);
    assert_eq!(outs[0], outs[1]);
    // accumulate.frame varies slowest (the vertex intensity follows it, so every stage
    // depends on it); within each of its two blocks of 6 rows the first computes input,
    // setup, raster, visibility, accumulate and gamma, the other 5 reuse the first five
    // stages and compute gamma (and the dither for the 3 bayer4 rows).
    assert_eq!(cache.stats(), (2 * 5 * 5, 2 * (6 + 5 + 3)));
}

#[test]
fn narrowest_formats_hold_the_observed_range_and_no_narrower_does() {
    use igemu::analysis::ranges::narrowest;
    for (min, max, frac) in [
        (0i128, 0i128, 0u32),
        (0, 255, 0),
        (0, 256, 0),
        (3, 57438, 4),
        (-1, 0, 2),
        (-128, 127, 0),
        (-129, 5, 3),
        (-5, 1000, 4),
    ] {
        let f = narrowest(min, max, frac);
        assert_eq!(f.frac_bits, frac);
        let holds =
            |f: &igemu::fixed::QFormat| f.min_code() as i128 <= min && max <= f.max_code() as i128;
        assert!(holds(&f), "{f} holds [{min}, {max}]");
        if f.int_bits > 0 {
            let smaller = igemu::fixed::QFormat::new(f.signed, f.int_bits - 1, frac);
            if smaller.total_bits() > 0 {
                assert!(!holds(&smaller), "{smaller} would do for [{min}, {max}]");
            }
        }
    }
}

#[test]
fn ranges_cli_reports_signals_and_exports_typedefs() {
    let d = tmp("ranges");
    let scene = scene_file(&d);
    let o = igemu(&["ranges", &scene, "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let frame = v
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["signal"] == "accumulate.frame")
        .expect("accumulate.frame is instrumented");
    assert!(frame["max"].as_i64().unwrap() <= 4095);
    assert!(frame["narrowest"].as_str().unwrap().starts_with("UQ"));
    for (lang, expect) in [
        (
            "ac_fixed",
            "typedef ac_fixed<12, 12, false, AC_RND_CONV, AC_SAT> accumulate_frame_t;",
        ),
        (
            "ap_fixed",
            "typedef ap_fixed<17, 13, AP_RND_CONV, AP_SAT> input_coord_t;",
        ),
        (
            "systemc",
            "sc_dt::sc_ufixed<8, 8, sc_dt::SC_RND_CONV, sc_dt::SC_SAT> gamma_dac_t;",
        ),
        ("verilog", "localparam integer ACCUMULATE_FRAME_W = 12;"),
    ] {
        let o = igemu(&["ranges", "--export", lang]);
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success());
        assert!(out.contains(expect), "{lang}: {out}");
    }
    assert_eq!(
        igemu(&["ranges", "--export", "vhdl"]).status.code(),
        Some(2)
    );
}

/// Runs a grid on one scene through `sweep::run` with a fresh cache; returns the rows.
fn reuse_rows(name: &str, scene: &igemu::scene::Scene, grid: &str) -> Vec<sweep::Row> {
    let d = tmp(name);
    let f = TomlFile::from_text("g.toml", grid);
    let configs = grid::Grid::parse(&f).unwrap().expand(&f).unwrap();
    let cache = igemu::pipeline::Cache::new();
    let out = d.join("out.jsonl").to_string_lossy().into_owned();
    let opts = sweep::SweepOptions {
        out: &out,
        resume: false,
        shard: None,
        jobs: 1,
        cache: Some(&cache),
        flicker: None,
    };
    sweep::run(&configs, std::slice::from_ref(scene), &opts, &|_, _| {})
        .unwrap()
        .rows
}

#[test]
fn a_dof_sweep_reuses_every_stage_before_dof() {
    let scene = igemu::scene::Scene::default_scene();
    let rows = reuse_rows("dof", &scene, "dof.guard_bits = [2, 3, 4]\n");
    assert_eq!(rows.len(), 3);
    assert!(rows[0].reused.is_empty(), "{:?}", rows[0].reused);
    let before: Vec<String> = igemu::stage::StageId::ALL
        .iter()
        .take_while(|&&s| s != igemu::stage::StageId::Dof)
        .filter(|&&s| s != igemu::stage::StageId::Logdomain)
        .map(|s| s.name().to_string())
        .collect();
    for r in &rows[1..] {
        assert_eq!(r.reused, before, "row {}", r.index);
    }
    // The guard bits change the blurred frame, so dof really ran on every row.
    assert_ne!(rows[0].error, rows[2].error);
}

#[test]
fn a_timing_sweep_reuses_every_stage_and_reruns_only_the_cycle_model() {
    let d = tmp("timing-scene");
    let scene = igemu::scene::Scene::load(&scene_file(&d)).unwrap();
    let rows = reuse_rows(
        "timing",
        &scene,
        "cycles.accumulate.lanes = [4, 16]\ncycles.raster.fifo = [1, 64]\n",
    );
    assert_eq!(rows.len(), 4);
    let planned = [
        "input",
        "setup",
        "raster",
        "visibility",
        "accumulate",
        "gamma",
    ];
    assert!(rows[0].reused.is_empty());
    for r in &rows[1..] {
        assert_eq!(r.reused, planned, "row {}", r.index);
        // Same images: the timing never changes a code.
        assert_eq!(r.error, rows[0].error);
    }
    // The cycle model ran for each timing: four lanes are slower than sixteen.
    assert!(rows[0].cycles.total_cycles > rows[2].cycles.total_cycles);
}
