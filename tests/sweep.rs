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
    let p = dir.join("small.toml");
    std::fs::write(&p, scene_text(0.02)).expect("write scene");
    p.to_string_lossy().into_owned()
}

/// The text of [`scene_file`] with the given background.
fn scene_text(background: f64) -> String {
    let objects = [
        common::tri(
            [[10.0, 10.0, 0.3], [150.0, 20.0, 0.5], [40.0, 110.0, 0.7]],
            [0.05, 0.9, 0.4],
        ),
        common::line([5.0, 100.0, 0.2], [155.0, 60.0, 0.2], 0.7, 1.5),
        common::point(80.0, 30.0, 0.1, 1.0, 2.0),
    ]
    .concat();
    format!(
        "[image]\nwidth = 160\nheight = 120\nbackground = {background:?}\n\n\
         [camera]\nposition = [0.0, 0.0, 10.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nfov_y_deg = 40.0\nnear = 1.0\nfar = 100.0\n\n\
         [display]\ncontrast = 100.0\ngamma = 2.4\nweber = 0.02\nb_max = 100.0\n\n{objects}"
    )
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
    let (rows, skipped) = sweep::read_rows(path).expect("read rows");
    assert_eq!(skipped, 0, "{path} has a partial line");
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
    let scene = igemu::scene::Scene::default_scene();
    let ids: std::collections::BTreeSet<String> =
        c.iter().map(|c| sweep::row_id(&scene, &c.hw)).collect();
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
    // The completed rows are reused as they were (their timing included), not recomputed.
    let (after, skipped) = sweep::read_rows(&out).unwrap();
    assert_eq!(skipped, 0);
    for r in &before {
        assert!(after.contains(r), "row {} was kept: {err}", r.index);
    }
    let resumed = rows(&out);
    let ids: std::collections::BTreeSet<&str> =
        resumed.iter().map(|r| r["id"].as_str().unwrap()).collect();
    assert_eq!(ids.len(), 40, "every configuration exactly once");
    assert_eq!(resumed, full_rows);
    // Resuming a complete file computes nothing: every row is kept as it was.
    let o = igemu(&["sweep", &scene, "--grid", &g, "--out", &out, "--resume"]);
    assert!(o.status.success());
    assert_eq!(sweep::read_rows(&out).unwrap(), (after, 0));
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
    // front red (its points, their labels, its line and a legend line).
    let svg_path = d.join("p.svg").to_string_lossy().into_owned();
    sweep::plot::write(&rows, &axes, &svg_path).unwrap();
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    let fc = pareto::front(&rows, &[pareto::Axis::Error, pareto::Axis::Cost]).len();
    let ft = pareto::front(&rows, &[pareto::Axis::Error, pareto::Axis::Throughput]).len();
    // Each front point red, and its `#index` label in red.
    assert_eq!(svg.matches("fill=\"#FF0000\"").count(), 2 * (fc + ft));
    assert_eq!(svg.matches("fill=\"#969696\"").count(), 2 * rows.len() + 2);
    assert_eq!(
        svg.matches("<polyline fill=\"none\" opacity=\"1\" stroke=\"#FF0000\"")
            .count(),
        4
    );
    assert!(svg.contains("mean Weber error") && svg.contains("Pareto front: "));
    let png_path = d.join("p.png").to_string_lossy().into_owned();
    sweep::plot::write(&rows, &axes, &png_path).unwrap();
    let png = image::open(&png_path).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), sweep::plot::SIZE);
    assert!(
        png.pixels().any(|p| p.0 == [255, 0, 0]),
        "the front is drawn"
    );
    assert!(sweep::plot::write(&rows, &axes, "p.gif").is_err());
    // Speed against error: rows carry the emulator's time per stage, and a further axis
    // gets its own panel.
    for r in &rows {
        let t = &r.timing;
        assert!(t.fixed_ms > 0.0 && t.float_ms > 0.0, "{t:?}");
        let names: Vec<&str> = t.stages.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names.first(), Some(&"input"), "{names:?}");
        let sum: f64 = t.stages.iter().map(|s| s.fixed_ms).sum();
        assert!((sum - t.fixed_ms).abs() < 1e-9 * sum.max(1.0));
        assert_eq!(pareto::Axis::EmulatorTime.key(r), t.fixed_ms);
    }
    let speed = pareto::Axis::parse_list("error,emulator_time").unwrap();
    assert_eq!(
        sweep::plot::panel_axes(&speed),
        [
            pareto::Axis::Cost,
            pareto::Axis::Throughput,
            pareto::Axis::EmulatorTime
        ]
    );
    sweep::plot::write(&rows, &speed, &png_path).unwrap();
    let png = image::open(&png_path).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), sweep::plot::size(3));
    let svg_path3 = d.join("p3.svg").to_string_lossy().into_owned();
    sweep::plot::write(&rows, &speed, &svg_path3).unwrap();
    let svg = std::fs::read_to_string(&svg_path3).unwrap();
    assert!(svg.contains("emulator fixed ms"));
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
    let scene = igemu::scene::Scene::load(&scene_file(&d)).unwrap();
    let text = "gamma.dac_bits = [6, 8, 10]\ndither.kind = [\"none\", \"bayer4\"]\n\
                accumulate.frame = [\"UQ10.0\", \"UQ12.0\"]\n";
    let cache = igemu::pipeline::Cache::new();
    let outs = cached_and_full_rows("reuse", &scene, text, &cache);
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
    let opts = common::serial_sweep(&out, Some(&cache), None);
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

fn expand(text: &str) -> Vec<grid::Config> {
    let f = TomlFile::from_text("g.toml", text);
    grid::Grid::parse(&f).unwrap().expand(&f).unwrap()
}

fn counts(s: &sweep::SweepSummary) -> (usize, usize, usize) {
    (s.reused, s.dropped, s.computed)
}

fn json(rows: &[sweep::Row]) -> Vec<serde_json::Value> {
    rows.iter().map(sweep::without_timing).collect()
}

#[test]
fn row_ids_name_the_scene_content_the_hardware_and_not_the_spelling() {
    use igemu::scene::Scene;
    let (d1, d2) = (tmp("id-a"), tmp("id-b"));
    let a = Scene::load(&scene_file(&d1)).unwrap();
    let b_path = d2.join("small.toml");
    std::fs::write(&b_path, scene_text(0.05)).unwrap();
    let b = Scene::load(b_path.to_str().unwrap()).unwrap();
    assert_eq!(a.name, b.name, "two files, one scene name");
    let hw = igemu::config::HwConfig::preset("linear12").unwrap();
    let id = sweep::row_id(&a, &hw);
    assert_eq!(id.len(), 16);
    assert!(
        id.chars()
            .all(|c| c.is_ascii_hexdigit() && !c.is_ascii_uppercase())
    );
    assert_ne!(
        id,
        sweep::row_id(&b, &hw),
        "different content, different id"
    );
    // Comments and formatting are not content.
    let c_path = d2.join("small-reformatted.toml");
    let text = format!(
        "# the same scene\n\n{}",
        scene_text(0.02).replace(" = ", "   =  ")
    );
    std::fs::write(&c_path, text).unwrap();
    let mut c = Scene::load(c_path.to_str().unwrap()).unwrap();
    c.name = a.name.clone();
    assert_eq!(sweep::row_id(&c, &hw), id);
    // The hardware as validated, not its name or its spelling in the grid.
    let spelled = expand("preset = [\"linear12\"]\ngamma.dac_bits = [8]\n");
    assert_ne!(spelled[0].hw.name, hw.name);
    assert_eq!(sweep::row_id(&a, &spelled[0].hw), id);
    let other = expand("gamma.dac_bits = [9]\n");
    assert_ne!(sweep::row_id(&a, &other[0].hw), id);
    // Through the command line: two scene files of one name give two rows, two ids.
    let g = grid_file(&d1, "g.toml", "gamma.dac_bits = [8]\n");
    let out = d1.join("two.jsonl").to_string_lossy().into_owned();
    let s1 = d1.join("small.toml").to_string_lossy().into_owned();
    let s2 = b_path.to_string_lossy().into_owned();
    let o = igemu(&["sweep", &s1, &s2, "--grid", &g, "--out", &out]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = rows(&out);
    assert_eq!(r.len(), 2);
    assert_eq!(r[0]["scene"], r[1]["scene"]);
    assert_ne!(r[0]["id"], r[1]["id"]);
    assert_eq!(r[0]["id"], id.as_str(), "the id of the library");
}

#[test]
fn resume_after_editing_the_scene_recomputes_every_row() {
    use igemu::scene::Scene;
    let d = tmp("edit");
    let path = scene_file(&d);
    let configs = expand("gamma.dac_bits = [6, 8]\n");
    let out = d.join("o.jsonl").to_string_lossy().into_owned();
    let old = Scene::load(&path).unwrap();
    let first = common::run_sweep(&out, &configs, std::slice::from_ref(&old), false);
    assert_eq!(counts(&first), (0, 0, 2));
    // A comment and other spacing: the same scene as parsed, every row kept.
    let text = format!("# edited\n{}\n\n", scene_text(0.02).replace(" = ", "="));
    std::fs::write(&path, text).unwrap();
    let same = Scene::load(&path).unwrap();
    let s = common::run_sweep(&out, &configs, std::slice::from_ref(&same), true);
    assert_eq!(counts(&s), (2, 0, 0));
    assert_eq!(s.rows, first.rows, "kept as they were, timing included");
    // A real edit under the same name: every row recomputed, the old ones dropped.
    std::fs::write(&path, scene_text(0.1)).unwrap();
    let edited = Scene::load(&path).unwrap();
    assert_eq!(edited.name, old.name);
    let s = common::run_sweep(&out, &configs, std::slice::from_ref(&edited), true);
    assert_eq!(counts(&s), (0, 2, 2));
    let fresh_out = d.join("fresh.jsonl").to_string_lossy().into_owned();
    let fresh = common::run_sweep(&fresh_out, &configs, std::slice::from_ref(&edited), false);
    assert_eq!(json(&s.rows), json(&fresh.rows));
    assert_ne!(
        json(&s.rows),
        json(&first.rows),
        "the edit changes the rows"
    );
    assert_eq!(rows(&out), json(&fresh.rows));
}

#[test]
fn resume_after_an_equivalent_spelling_of_the_grid_keeps_the_rows() {
    let d = tmp("spelling");
    let scene = igemu::scene::Scene::load(&scene_file(&d)).unwrap();
    let scenes = std::slice::from_ref(&scene);
    let out = d.join("o.jsonl").to_string_lossy().into_owned();
    let first = common::run_sweep(&out, &expand("gamma.dac_bits = [6, 8]\n"), scenes, false);
    // The default preset named, the values in the other order: the same two machines.
    let respelled = expand("preset = [\"linear12\"]\ngamma.dac_bits = [8, 6]\n");
    let s = common::run_sweep(&out, &respelled, scenes, true);
    assert_eq!(counts(&s), (2, 0, 0));
    assert_eq!(
        s.rows[0].error, first.rows[1].error,
        "dac_bits 8 is now job 0"
    );
    assert_eq!(
        s.rows[0].timing, first.rows[1].timing,
        "reused, not recomputed"
    );
    // Relabelled with the new grid: the file equals a fresh run of the new grid.
    let fresh_out = d.join("fresh.jsonl").to_string_lossy().into_owned();
    let fresh = common::run_sweep(&fresh_out, &respelled, scenes, false);
    assert_eq!(json(&s.rows), json(&fresh.rows));
    assert_eq!(rows(&out), json(&fresh.rows));
    // Two spellings of one machine in one grid share an id; both jobs get their row.
    let twice = expand("preset = [\"linear12\"]\ngamma.dac_bits = [6, 8]\n");
    let twice = [twice[1].clone(), respelled[0].clone()];
    let twice: Vec<grid::Config> = twice
        .into_iter()
        .enumerate()
        .map(|(i, mut c)| {
            c.index = i;
            c
        })
        .collect();
    let s = common::run_sweep(&out, &twice, scenes, true);
    assert_eq!(counts(&s), (2, 1, 0), "the dac_bits 6 row is not asked for");
    assert_eq!(s.rows[0].id, s.rows[1].id);
    assert_eq!(rows(&out).len(), 2);
    let s = common::run_sweep(&out, &twice, scenes, true);
    assert_eq!(counts(&s), (2, 0, 0));
    // A changed grid: the common machine is kept, the new one computed.
    let s = common::run_sweep(&out, &expand("gamma.dac_bits = [8, 9]\n"), scenes, true);
    assert_eq!(counts(&s), (1, 1, 1));
}

#[test]
fn resume_drops_and_counts_partial_foreign_and_duplicate_lines() {
    use std::io::Write;
    let d = tmp("drops");
    let scene = igemu::scene::Scene::load(&scene_file(&d)).unwrap();
    let scenes = std::slice::from_ref(&scene);
    let configs = expand("gamma.dac_bits = [6, 8]\n");
    let out = d.join("o.jsonl").to_string_lossy().into_owned();
    let first = common::run_sweep(&out, &configs, scenes, false);
    let text = std::fs::read_to_string(&out).unwrap();
    let line0 = text.lines().next().unwrap().to_string();
    let mut foreign = first.rows[1].clone();
    foreign.id = "0123456789abcdef".into();
    {
        let mut f = std::fs::OpenOptions::new().append(true).open(&out).unwrap();
        writeln!(f, "{line0}").unwrap(); // a duplicate
        writeln!(f, "{}", serde_json::to_string(&foreign).unwrap()).unwrap(); // another sweep's
        writeln!(f, "not a row").unwrap();
        f.write_all(b"{\"id\":\"0123\",\"index\":").unwrap(); // a killed write
    }
    assert_eq!(sweep::read_rows(&out).unwrap().1, 2);
    let s = common::run_sweep(&out, &configs, scenes, true);
    assert_eq!(counts(&s), (2, 4, 0));
    assert_eq!(s.rows, first.rows);
    assert_eq!(sweep::read_rows(&out).unwrap(), (first.rows.clone(), 0));
    // A last line without its newline is partial even when it parses: dropped and recomputed.
    let text = std::fs::read_to_string(&out).unwrap();
    std::fs::write(&out, text.trim_end()).unwrap();
    let s = common::run_sweep(&out, &configs, scenes, true);
    assert_eq!(counts(&s), (1, 1, 1));
    assert_eq!(json(&s.rows), json(&first.rows));
    assert_eq!(rows(&out), json(&first.rows));
}

mod shards {
    use super::*;
    use igemu::sweep::grid::Shard;
    use proptest::prelude::*;

    fn count() -> impl Strategy<Value = usize> {
        prop_oneof![
            0usize..50,
            any::<usize>(),
            Just(usize::MAX),
            Just(usize::MAX - 1),
            Just(1usize << 62),
            (1usize << 62) - 3..(1usize << 62) + 3,
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// Neighbouring shards meet, the first starts at 0, the last ends at the total, and
        /// no shard is more than one job longer than another: concatenated in K order they
        /// are every job once.
        #[test]
        fn shards_partition_the_jobs(n in count(), k in count(), total in count()) {
            let n = n.max(1);
            let k = 1 + k % n;
            let s = Shard::parse(&format!("{k}/{n}")).unwrap();
            prop_assert_eq!(s, Shard { k, n });
            let r = s.range(total);
            prop_assert!(r.start <= r.end && r.end <= total);
            // Between floor(total / n) and ceil(total / n) jobs.
            prop_assert!(r.len() >= total / n);
            prop_assert!(r.len() <= total / n + usize::from(total % n != 0));
            if k == 1 {
                prop_assert_eq!(r.start, 0);
            } else {
                prop_assert_eq!(Shard { k: k - 1, n }.range(total).end, r.start);
            }
            if k == n {
                prop_assert_eq!(r.end, total);
            } else {
                prop_assert_eq!(Shard { k: k + 1, n }.range(total).start, r.end);
            }
        }
    }

    #[test]
    fn small_shards_concatenate_to_all_jobs() {
        for n in 1..=12 {
            for total in 0..=40 {
                let all: Vec<usize> = (1..=n).flat_map(|k| Shard { k, n }.range(total)).collect();
                assert_eq!(
                    all,
                    (0..total).collect::<Vec<_>>(),
                    "{n} shards, {total} jobs"
                );
            }
        }
    }

    #[test]
    fn huge_shards_run_from_the_command_line() {
        let d = tmp("huge-shard");
        let scene = scene_file(&d);
        // 8 jobs: K * 8 overflows 64 bits for these K.
        let g = grid_file(
            &d,
            "g.toml",
            "gamma.dac_bits = [6, 7, 8, 9, 10, 11, 12, 13]\n",
        );
        let out = d.join("o.jsonl").to_string_lossy().into_owned();
        let max = usize::MAX.to_string();
        for (shard, expect) in [
            ("4611686018427387904/4611686018427387904", 1),
            ("1/4611686018427387904", 0),
            (&format!("{max}/{max}") as &str, 1),
            (&format!("1/{max}"), 0),
        ] {
            let o = igemu(&[
                "sweep", &scene, "--grid", &g, "--out", &out, "--shard", shard,
            ]);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(0), "{shard}: {err}");
            let r = rows(&out);
            assert_eq!(r.len(), expect, "{shard}");
            if expect == 1 {
                assert_eq!(r[0]["index"], 7, "the last shard has the last job");
            }
        }
    }
}

mod files {
    use super::*;

    /// The files in `dir`, sorted.
    fn listing(dir: &std::path::Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    fn some_rows(name: &str) -> (std::path::PathBuf, Vec<sweep::Row>) {
        let d = tmp(name);
        let scene = igemu::scene::Scene::load(&scene_file(&d)).unwrap();
        let out = d.join("o.jsonl").to_string_lossy().into_owned();
        let configs = expand("gamma.dac_bits = [6, 8]\n");
        let s = common::run_sweep(&out, &configs, std::slice::from_ref(&scene), false);
        (d, s.rows)
    }

    #[test]
    fn the_plot_replaces_its_file_by_a_rename() {
        let (d, rows) = some_rows("plot-rename");
        for ext in ["svg", "png"] {
            // A second name for the old plot: a write in place would change it too.
            let p = d.join(format!("p.{ext}"));
            let keep = d.join(format!("keep.{ext}"));
            std::fs::write(&p, "old plot").unwrap();
            std::fs::hard_link(&p, &keep).unwrap();
            let before = listing(&d);
            sweep::plot::write(&rows, &[pareto::Axis::Error], p.to_str().unwrap()).unwrap();
            let kept = std::fs::read(&keep).unwrap();
            assert!(kept == b"old plot", "{ext}: written in place, not renamed");
            assert!(
                std::fs::read(&p).unwrap() != b"old plot",
                "{ext}: not written"
            );
            assert_eq!(listing(&d), before, "no temporary left ({ext})");
        }
        assert!(image::open(d.join("p.png")).is_ok());
    }

    #[test]
    fn a_failed_write_leaves_no_temporary() {
        let (d, rows) = some_rows("failed-write");
        // The output names a folder: the rename fails.
        for name in ["busy.svg", "busy.png", "busy.jsonl"] {
            let target = d.join(name);
            std::fs::create_dir_all(target.join("inside")).unwrap();
            let before = listing(&d);
            let t = target.to_str().unwrap();
            let e = if name.ends_with("jsonl") {
                sweep::rewrite_sorted(t, &rows).unwrap_err()
            } else {
                sweep::plot::write(&rows, &[pareto::Axis::Error], t).unwrap_err()
            };
            assert!(e.to_string().contains(name), "{name}: {e}");
            assert_eq!(listing(&d), before, "{name}");
            assert_eq!(listing(&target), ["inside"], "{name}");
        }
        // A folder that does not exist: nothing is created.
        let missing = d.join("missing").join("p.svg");
        assert!(
            sweep::plot::write(&rows, &[pareto::Axis::Error], missing.to_str().unwrap()).is_err()
        );
        assert!(!d.join("missing").exists());
    }
}

/// A small colour scene file: two saturated shaded triangles (orange, blue-green) on a
/// dusk-blue background, 160x120, pinhole camera.
fn colour_scene_file(dir: &std::path::Path) -> String {
    let tri = |v: [[f64; 3]; 3], i: [[f64; 3]; 3]| {
        format!(
            "[[object]]\nkind = \"triangle\"\nspace = \"screen\"\nvertices = {v:?}\nintensity = {i:?}\n\n"
        )
    };
    let objects = [
        tri(
            [[10.0, 10.0, 0.3], [150.0, 20.0, 0.5], [40.0, 110.0, 0.7]],
            [[0.9, 0.36, 0.18], [0.1, 0.04, 0.02], [0.5, 0.2, 0.1]],
        ),
        tri(
            [[100.0, 60.0, 0.2], [155.0, 115.0, 0.2], [60.0, 115.0, 0.2]],
            [[0.05, 0.5, 0.4], [0.1, 0.9, 0.7], [0.02, 0.2, 0.15]],
        ),
    ]
    .concat();
    let text = common::scene_toml(160, 120, 0.0, &objects)
        .replace("background = 0\n", "background = [0.03, 0.045, 0.08]\n");
    assert!(text.contains("[0.03, 0.045, 0.08]"), "{text}");
    let p = dir.join("colour.toml");
    std::fs::write(&p, text).expect("write scene");
    p.to_string_lossy().into_owned()
}

/// 5-6-5, 6-6-6 and 8-8-8 frame words: a grid of per-channel values (an array per value).
const FRAME_GRID: &str = "accumulate.frame = [[\"UQ5.0\", \"UQ6.0\", \"UQ5.0\"], [\"UQ6.0\", \"UQ6.0\", \"UQ6.0\"], [\"UQ8.0\", \"UQ8.0\", \"UQ8.0\"]]\n";

#[test]
fn a_colour_sweep_over_frame_widths_ranks_delta_e_against_cost() {
    let d = tmp("colour");
    let scene = colour_scene_file(&d);
    let g = grid_file(&d, "g.toml", FRAME_GRID);
    let out = d.join("o.jsonl").to_string_lossy().into_owned();
    let html = d.join("s.html").to_string_lossy().into_owned();
    let o = igemu(&[
        "sweep",
        &scene,
        "--grid",
        &g,
        "--out",
        &out,
        "--axes",
        "delta_e,cost",
        "--html",
        &html,
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (rows, _) = sweep::read_rows(&out).unwrap();
    assert_eq!(rows.len(), 3);
    // The per-channel values reach the hardware: each row's config is its array.
    assert_eq!(
        rows[0].config["accumulate.frame"],
        serde_json::json!(["UQ5.0", "UQ6.0", "UQ5.0"])
    );
    let c: Vec<&sweep::ColourMetrics> = rows
        .iter()
        .map(|r| r.colour.as_ref().expect("a colour row has colour metrics"))
        .collect();
    let cost = |r: &sweep::Row| pareto::Axis::Cost.key(r);
    for k in 0..2 {
        assert!(
            c[k].delta_e_mean > c[k + 1].delta_e_mean,
            "mean CIEDE2000 falls with the width: {c:?}"
        );
        assert!(
            c[k].hue_shift_mean_deg > c[k + 1].hue_shift_mean_deg,
            "{c:?}"
        );
        assert!(cost(&rows[k]) < cost(&rows[k + 1]), "wider words cost more");
    }
    assert!(
        c[0].delta_e_over_jnd > 0 && c[0].hue_shift_pixels > 0,
        "{c:?}"
    );
    // Narrower is cheaper and worse, wider dearer and better: all three on the front.
    let axes = pareto::Axis::parse_list("delta_e,cost").unwrap();
    assert_eq!(pareto::Axis::DeltaE.key(&rows[1]), c[1].delta_e_mean);
    assert_eq!(pareto::front(&rows, &axes), [2, 1, 0]);
    assert!(
        stdout.contains("mean CIEDE2000") && stdout.contains("(3 of 3 rows)"),
        "{stdout}"
    );
    // A row that loses on both axes leaves the front.
    let mut worse = rows[1].clone();
    worse.index = 3;
    worse.colour.as_mut().unwrap().delta_e_mean = c[0].delta_e_mean + 1.0;
    let mut four = rows.clone();
    four.push(worse);
    assert_eq!(pareto::front(&four, &axes), [2, 1, 0]);
    // The HTML table carries the colour columns.
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("mean CIEDE2000") && page.contains("mean hue shift deg"));
    // Rows of a colour render without colour metrics (written before rows had them) are
    // recomputed by --resume, the others kept.
    let text = std::fs::read_to_string(&out).unwrap();
    let lines: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(k, l)| {
            let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
            if k != 1 {
                v.as_object_mut().unwrap().remove("colour");
            }
            v.to_string() + "\n"
        })
        .collect();
    std::fs::write(&out, lines.concat()).unwrap();
    let o = igemu(&["sweep", &scene, "--grid", &g, "--out", &out, "--resume"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("kept 1, dropped 2 (stale or foreign), computed 2"),
        "{err}"
    );
    let (again, _) = sweep::read_rows(&out).unwrap();
    let json = |r: &[sweep::Row]| r.iter().map(sweep::without_timing).collect::<Vec<_>>();
    assert_eq!(json(&again), json(&rows));
}

#[test]
fn a_colour_axis_on_a_grey_sweep_is_refused_naming_the_axis() {
    let d = tmp("colour-grey");
    let scene = scene_file(&d);
    let g = grid_file(&d, "g.toml", "gamma.dac_bits = [8, 9]\n");
    let out = d.join("o.jsonl");
    let out_s = out.to_string_lossy().into_owned();
    for axes in ["delta_e,cost", "cost,hue_shift", "delta_e_p99,cost"] {
        let o = igemu(&[
            "sweep", &scene, "--grid", &g, "--out", &out_s, "--axes", axes,
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{axes}: {err}");
        let axis = axes.split(',').find(|a| *a != "cost").unwrap();
        assert!(
            err.contains("--axes") && err.contains(&format!("the {axis} axis")),
            "{err}"
        );
        assert!(
            err.contains("needs a colour scene") && err.contains("small"),
            "{err}"
        );
        assert!(!out.exists(), "no work before the error");
    }
    // A grey sweep's rows carry no colour key (their output is as before).
    let o = igemu(&["sweep", &scene, "--grid", &g, "--out", &out_s]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        !text.contains("\"colour\"") && !text.contains("delta_e"),
        "{text}"
    );
    // Per-channel widths make the grey scene a colour render: the axis is allowed.
    let g3 = grid_file(&d, "g3.toml", FRAME_GRID);
    let o = igemu(&[
        "sweep",
        &scene,
        "--grid",
        &g3,
        "--out",
        &out_s,
        "--axes",
        "delta_e,cost",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (rows, _) = sweep::read_rows(&out_s).unwrap();
    assert!(rows.iter().all(|r| r.colour.is_some()));
}

#[test]
fn a_per_channel_sweep_with_stage_reuse_gives_the_rows_of_full_renders() {
    // 5-5-5 then 5-6-5: channel R's lane is the same, G's vertex intensities are not (they
    // follow G's frame word), so the geometry stages must not be reused.
    let d = tmp("colour-reuse");
    let scene = colour_scene_file(&d);
    let g = grid_file(
        &d,
        "g.toml",
        "accumulate.frame = [[\"UQ5.0\", \"UQ5.0\", \"UQ5.0\"], [\"UQ5.0\", \"UQ6.0\", \"UQ5.0\"], [\"UQ6.0\", \"UQ6.0\", \"UQ6.0\"]]\n",
    );
    let mut outs = Vec::new();
    for reuse in [true, false] {
        let out = d
            .join(format!("{reuse}.jsonl"))
            .to_string_lossy()
            .into_owned();
        let mut args = vec!["sweep", &scene, "--grid", &g, "--out", &out];
        if !reuse {
            args.push("--no-reuse");
        }
        let o = igemu(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        outs.push(rows(&out));
    }
    assert_eq!(outs[0], outs[1]);
}

/// The rows of `grid` on `scene` with stage reuse (in `cache`) and without (full renders).
fn cached_and_full_rows(
    name: &str,
    scene: &igemu::scene::Scene,
    grid: &str,
    cache: &igemu::pipeline::Cache,
) -> [Vec<serde_json::Value>; 2] {
    let d = tmp(name);
    let f = TomlFile::from_text("g.toml", grid);
    let configs = grid::Grid::parse(&f).unwrap().expand(&f).unwrap();
    [Some(cache), None].map(|c| {
        let out = d
            .join(format!("{}.jsonl", c.is_some()))
            .to_string_lossy()
            .into_owned();
        let opts = common::serial_sweep(&out, c, None);
        sweep::run(&configs, std::slice::from_ref(scene), &opts, &|_, _| {}).unwrap();
        rows(&out)
    })
}

/// The layered depth of field's float reference is shared by the rows whose layer plans
/// agree on what it reads (the taps' support, not their values), and the gamma curve's
/// powers and the contour metric's ideal image with it: every row still equals its full
/// render. `coef_bits = 4` zeroes tail taps that 12 bits keep (another support), and
/// `p` moves the layers.
#[test]
fn a_dof_width_sweep_shares_the_float_reference_and_gives_the_rows_of_full_renders() {
    let scene = igemu::scene::Scene::default_scene();
    let grid = "dof.p = [0.1, 0.3]\ndof.coef_bits = [4, 12]\ndof.guard_bits = [2, 4]\n";
    let cache = igemu::pipeline::Cache::new();
    let [cached, full] = cached_and_full_rows("dof-float", &scene, grid, &cache);
    assert_eq!(cached.len(), 8);
    assert_eq!(cached, full);
    // The widths do change the fixed output (the test is not vacuous).
    let err = |r: &serde_json::Value| r["error"].clone();
    assert_ne!(err(&cached[0]), err(&cached[1]));
    assert_ne!(err(&cached[0]), err(&cached[2]));
}

/// Rows whose outputs are the same (`dither.frac_bits` without a dither) share one
/// end-to-end comparison, and each still equals its full render.
#[test]
fn rows_with_the_same_output_compare_once_and_equal_their_full_renders() {
    let d = tmp("same-output-scene");
    let scene = igemu::scene::Scene::load(&scene_file(&d)).unwrap();
    let grid = "gamma.dac_bits = [6, 8]\ndither.kind = [\"none\", \"bayer4\"]\n\
                dither.frac_bits = [1, 3]\n";
    let cache = igemu::pipeline::Cache::new();
    let [cached, full] = cached_and_full_rows("same-output", &scene, grid, &cache);
    assert_eq!(cached.len(), 8);
    assert_eq!(cached, full);
}
