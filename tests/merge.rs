//! `igemu sweep merge` and `--shard auto`, without a cluster: shards merge to the unsharded
//! run; a missing, duplicated or foreign row exits 1 naming it and writes nothing; rows are
//! written in job order; `--shard auto` takes the shard from a Slurm array task's or a
//! Kubernetes indexed Job's variables and refuses bad ones with exit 2. The real Slurm run
//! is tests/slurm.rs.

mod common;

use igemu::files::TomlFile;
use igemu::sweep::grid::Grid;
use igemu::sweep::merge::{Part, merge};
use igemu::sweep::{self, Row};
use std::path::{Path, PathBuf};

use common::igemu_env as igemu;

fn tmp(name: &str) -> PathBuf {
    common::tmp_dir("merge", name)
}

fn path(d: &Path, name: &str) -> String {
    d.join(name).to_string_lossy().into_owned()
}

/// A small sweep (two scenes, 8 jobs) run whole into `full.jsonl` and as 4 shards into
/// `part-1.jsonl` .. `part-4.jsonl`: (scenes, grid, full, parts).
fn sharded(d: &Path) -> (Vec<String>, String, String, Vec<String>) {
    let (scenes, grid) = common::small_sweep(d);
    let full = path(d, "full.jsonl");
    let mut args = vec!["sweep"];
    args.extend(scenes.iter().map(String::as_str));
    args.extend(["--grid", &grid, "--out", &full]);
    let (code, _, err) = igemu(&args, &[]);
    assert_eq!(code, 0, "{err}");
    let parts: Vec<String> = (1..=4)
        .map(|k| path(d, &format!("part-{k}.jsonl")))
        .collect();
    for (k, p) in parts.iter().enumerate() {
        let shard = format!("{}/4", k + 1);
        let mut a = args[..args.len() - 1].to_vec();
        a.extend([p.as_str(), "--shard", &shard]);
        let (code, _, err) = igemu(&a, &[]);
        assert_eq!(code, 0, "{shard}: {err}");
    }
    (scenes, grid, full, parts)
}

/// `igemu sweep merge PARTS --grid G --scene A --scene B --out OUT` plus `extra`.
fn merge_cli(
    parts: &[&str],
    grid: &str,
    scenes: &[String],
    out: &str,
    extra: &[&str],
) -> (i32, String, String) {
    let mut a = vec!["sweep", "merge"];
    a.extend(parts);
    a.extend(["--grid", grid, "--out", out]);
    for s in scenes {
        a.extend(["--scene", s.as_str()]);
    }
    a.extend(extra);
    igemu(&a, &[])
}

fn lines(p: &str) -> Vec<String> {
    std::fs::read_to_string(p)
        .expect("read")
        .lines()
        .map(String::from)
        .collect()
}

fn id_of(line: &str) -> String {
    serde_json::from_str::<Row>(line).expect("a row").id
}

#[test]
fn shards_given_in_any_order_merge_to_the_unsharded_run() {
    let d = tmp("shards");
    let (scenes, grid, full, parts) = sharded(&d);
    let out = path(&d, "all.jsonl");
    let plot = path(&d, "pareto.svg");
    let html = path(&d, "all.html");
    let rev: Vec<&str> = parts.iter().rev().map(String::as_str).collect();
    let (code, stdout, err) = merge_cli(
        &rev,
        &grid,
        &scenes,
        &out,
        &["--plot", &plot, "--html", &html],
    );
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("8 rows from 4 files"), "{err}");
    let merged = common::rows_without_timing(&out);
    assert_eq!(merged.len(), 8);
    assert_eq!(merged, common::rows_without_timing(&full));
    for (i, r) in merged.iter().enumerate() {
        assert_eq!(r["index"], i, "job order");
    }
    // The front of `igemu sweep`, per scene, and the plot.
    assert!(stdout.starts_with("Pareto front on mean Weber error x storage + LUT bits"));
    assert!(stdout.contains("dither.kind="), "{stdout}");
    assert!(
        std::fs::read_to_string(&plot)
            .expect("plot")
            .contains("<svg")
    );
    // The HTML page: one table row per merged row, the front highlighted, the plot inline.
    let page = std::fs::read_to_string(&html).expect("html");
    assert_eq!(page.matches("<tr").count(), 1 + 8, "heading + rows");
    assert!(page.contains("class=\"front\"") && page.contains("svg+xml;base64,"));
    assert!(page.contains("4 parts merged"));
}

#[test]
fn rows_out_of_order_are_written_in_job_order() {
    let d = tmp("order");
    let (scenes, grid, full, _) = sharded(&d);
    // Two parts holding the full run's rows backwards, interleaved.
    let rows = lines(&full);
    let (mut odd, mut even) = (String::new(), String::new());
    for (i, l) in rows.iter().enumerate().rev() {
        let part = if i % 2 == 1 { &mut odd } else { &mut even };
        part.push_str(l);
        part.push('\n');
    }
    let (p1, p2) = (path(&d, "odd.jsonl"), path(&d, "even.jsonl"));
    std::fs::write(&p1, odd).expect("write");
    std::fs::write(&p2, even).expect("write");
    let out = path(&d, "all.jsonl");
    let (code, _, err) = merge_cli(&[&p1, &p2], &grid, &scenes, &out, &[]);
    assert_eq!(code, 0, "{err}");
    // The same rows, timing included, in the order of the unsharded run.
    let parse = |p: &str| -> Vec<Row> { sweep::read_rows(p).expect("rows").0 };
    assert_eq!(parse(&out), parse(&full));
}

#[test]
fn a_missing_row_exits_1_naming_it_and_a_rerun_with_resume_completes_the_set() {
    let d = tmp("missing");
    let (scenes, grid, _, parts) = sharded(&d);
    // Task 2 was killed after its first row, in the middle of writing the second.
    let rows = lines(&parts[1]);
    assert_eq!(rows.len(), 2);
    let lost = id_of(&rows[1]);
    std::fs::write(&parts[1], format!("{}\n{}", rows[0], &rows[1][..40])).expect("write");
    let out = path(&d, "all.jsonl");
    let p: Vec<&str> = parts.iter().map(String::as_str).collect();
    let (code, _, err) = merge_cli(&p, &grid, &scenes, &out, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("missing 1 of 8 rows (job indices 3)"), "{err}");
    assert!(
        err.contains(&format!("index 3 id {lost} scene `b`")),
        "{err}"
    );
    assert!(
        err.contains("dither.kind=\"none\";gamma.dac_bits=8"),
        "{err}"
    );
    assert!(
        err.contains(&format!("{}:2", parts[1])),
        "the partial line is named: {err}"
    );
    assert!(
        !Path::new(&out).exists(),
        "an incomplete merge writes nothing"
    );
    // Rerunning the task's shard with --resume computes only the lost row.
    let mut a = vec!["sweep"];
    a.extend(scenes.iter().map(String::as_str));
    a.extend([
        "--grid", &grid, "--out", &parts[1], "--shard", "2/4", "--resume",
    ]);
    let (code, _, err) = igemu(&a, &[]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("kept 1, dropped 1 (stale or foreign), computed 1"),
        "{err}"
    );
    let (code, _, err) = merge_cli(&p, &grid, &scenes, &out, &[]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(common::rows_without_timing(&out).len(), 8);
}

#[test]
fn a_duplicated_row_exits_1_naming_it_and_every_place() {
    let d = tmp("duplicate");
    let (scenes, grid, _, parts) = sharded(&d);
    let first = lines(&parts[0]).remove(0);
    let mut text = std::fs::read_to_string(&parts[2]).expect("read");
    text.push_str(&first);
    text.push('\n');
    std::fs::write(&parts[2], text).expect("write");
    let out = path(&d, "all.jsonl");
    let p: Vec<&str> = parts.iter().map(String::as_str).collect();
    let (code, _, err) = merge_cli(&p, &grid, &scenes, &out, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("1 rows duplicated"), "{err}");
    assert!(
        err.contains(&format!(
            "index 0 id {} at {}:1, {}:3",
            id_of(&first),
            parts[0],
            parts[2]
        )),
        "{err}"
    );
    assert!(!err.contains("missing"), "{err}");
    assert!(!Path::new(&out).exists());
}

#[test]
fn rows_of_another_grid_or_scene_exit_1_as_foreign() {
    let d = tmp("foreign");
    let (scenes, grid, _, parts) = sharded(&d);
    let p: Vec<&str> = parts.iter().map(String::as_str).collect();
    let out = path(&d, "all.jsonl");
    // Merged against scene `a` alone, the rows of `b` are no job of the sweep.
    let (code, _, err) = merge_cli(&p, &grid, &scenes[..1], &out, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("4 rows not in the grid on these scenes"),
        "{err}"
    );
    let b_row = lines(&parts[0])[1].clone();
    assert!(
        err.contains(&format!("id {} (index 1)", id_of(&b_row))),
        "{err}"
    );
    assert!(
        !err.contains("missing"),
        "every job of `a` has its row: {err}"
    );
    // An edited scene changes every id: all rows are stale and all jobs missing.
    std::fs::write(
        &scenes[1],
        std::fs::read_to_string(&scenes[1])
            .expect("read")
            .replace("background = 0.1", "background = 0.2"),
    )
    .expect("write");
    let (code, _, err) = merge_cli(&p, &grid, &scenes, &out, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("missing 4 of 8 rows (job indices 1, 3, 5, 7)"),
        "{err}"
    );
    assert!(!Path::new(&out).exists());
}

#[test]
fn merge_never_overwrites_an_input_and_checks_its_arguments() {
    let d = tmp("guard");
    let (scenes, grid, _, parts) = sharded(&d);
    let p: Vec<&str> = parts.iter().map(String::as_str).collect();
    let before = std::fs::read(&parts[0]).expect("read");
    let (code, _, err) = merge_cli(&p, &grid, &scenes, &parts[0], &[]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--out") && err.contains("a part file"),
        "{err}"
    );
    assert_eq!(std::fs::read(&parts[0]).expect("read"), before);
    let out = path(&d, "all.jsonl");
    for (extra, flag) in [
        (&["--plot", "p.pdf"][..], "--plot"),
        (&["--html", &out][..], "--html"),
        (&["--axes", "error,truth_total"][..], "--axes"),
        (&["--axes", "flicker,cost"][..], "--axes"),
    ] {
        let (code, _, err) = merge_cli(&p, &grid, &scenes, &out, extra);
        assert_eq!(code, 2, "{extra:?}: {err}");
        assert!(err.contains(flag), "{extra:?}: {err}");
        assert!(!Path::new(&out).exists(), "{extra:?}");
    }
    let (code, _, err) = merge_cli(&[&path(&d, "nope.jsonl")], &grid, &scenes, &out, &[]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("nope.jsonl"), "{err}");
}

/// Runs the 4 tasks of a job array with `env(task)` as their variables and `shard` as the
/// `--shard` value; returns their part files concatenated, without timing.
fn array_run(
    d: &Path,
    scenes: &[String],
    grid: &str,
    shard: &str,
    tasks: &[usize],
    env: impl Fn(usize) -> Vec<(&'static str, String)>,
) -> Vec<serde_json::Value> {
    let mut cat = Vec::new();
    for &t in tasks {
        let out = path(d, &format!("task-{t}.jsonl"));
        let mut a = vec!["sweep"];
        a.extend(scenes.iter().map(String::as_str));
        a.extend(["--grid", grid, "--out", &out, "--shard", shard]);
        let vars = env(t);
        let e: Vec<(&str, &str)> = vars.iter().map(|(k, v)| (*k, v.as_str())).collect();
        let (code, _, err) = igemu(&a, &e);
        assert_eq!(code, 0, "task {t}: {err}");
        assert!(
            err.contains("igemu sweep: --shard"),
            "the shard is said: {err}"
        );
        cat.extend(common::rows_without_timing(&out));
    }
    cat
}

#[test]
fn shard_auto_takes_the_slurm_array_task_or_the_kubernetes_index() {
    let d = tmp("auto");
    let (scenes, grid, full, _) = sharded(&d);
    let full = common::rows_without_timing(&full);
    // --array=1-4 (any first index).
    let slurm = |t: usize| {
        vec![
            ("SLURM_ARRAY_TASK_ID", t.to_string()),
            ("SLURM_ARRAY_TASK_MIN", "1".into()),
            ("SLURM_ARRAY_TASK_MAX", "4".into()),
            ("SLURM_ARRAY_TASK_COUNT", "4".into()),
            ("SLURM_ARRAY_TASK_STEP", "1".into()),
        ]
    };
    assert_eq!(
        array_run(&d, &scenes, &grid, "auto", &[1, 2, 3, 4], slurm),
        full
    );
    // A Kubernetes indexed Job of 4 completions.
    let k8s = |t: usize| vec![("JOB_COMPLETION_INDEX", t.to_string())];
    assert_eq!(
        array_run(&d, &scenes, &grid, "auto/4", &[0, 1, 2, 3], k8s),
        full
    );
}

#[test]
fn bad_shard_environments_exit_2_naming_the_variable_and_the_range() {
    let d = tmp("auto-bad");
    let (scenes, grid) = common::small_sweep(&d);
    let out = path(&d, "o.jsonl");
    let slurm = |id: &'static str| {
        vec![
            ("SLURM_ARRAY_TASK_ID", id),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_MAX", "3"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("SLURM_ARRAY_TASK_STEP", "1"),
        ]
    };
    type Vars = Vec<(&'static str, &'static str)>;
    let cases: Vec<(&str, Vars, &str)> = vec![
        ("auto", vec![], "neither SLURM_ARRAY_TASK_ID"),
        (
            "auto",
            slurm("x"),
            "SLURM_ARRAY_TASK_ID=`x` is not a non-negative integer",
        ),
        (
            "auto",
            slurm("4"),
            "SLURM_ARRAY_TASK_ID must be one of 0, 1, ..., 3",
        ),
        ("auto/8", slurm("1"), "the array has 4 tasks, not 8"),
        (
            "auto",
            vec![("JOB_COMPLETION_INDEX", "2")],
            "--shard auto/N",
        ),
        (
            "auto/4",
            vec![("JOB_COMPLETION_INDEX", "4")],
            "JOB_COMPLETION_INDEX=4 must be in 0..=3",
        ),
        (
            "auto/4",
            vec![("JOB_COMPLETION_INDEX", "-1")],
            "JOB_COMPLETION_INDEX=`-1`",
        ),
        (
            "auto/0",
            vec![("JOB_COMPLETION_INDEX", "0")],
            "N a positive integer",
        ),
    ];
    for (shard, env, expect) in cases {
        let (code, _, err) = igemu(
            &[
                "sweep", &scenes[0], "--grid", &grid, "--out", &out, "--shard", shard,
            ],
            &env,
        );
        assert_eq!(code, 2, "{shard} {env:?}: {err}");
        assert!(
            err.contains("--shard") && err.contains(expect),
            "{shard} {env:?}: {err}"
        );
        assert!(!Path::new(&out).exists(), "{shard} {env:?}: no output");
    }
}

/// The configurations and scene of a grid text on the small scene `a`, and the rows of its
/// unsharded sweep.
fn lib_sweep(
    d: &Path,
    grid_text: &str,
) -> (Vec<sweep::grid::Config>, Vec<igemu::scene::Scene>, Vec<Row>) {
    let (scenes, _) = common::small_sweep(d);
    let scene = igemu::scene::Scene::load(&scenes[0]).expect("scene");
    let file = TomlFile::from_text("g.toml", grid_text);
    let configs = Grid::parse(&file)
        .expect("grid")
        .expand(&file)
        .expect("expand");
    let out = path(d, "lib.jsonl");
    let s = common::run_sweep(&out, &configs, std::slice::from_ref(&scene), false);
    (configs, vec![scene], s.rows)
}

fn part(name: &str, rows: &[Row]) -> Part {
    Part {
        path: name.into(),
        rows: rows
            .iter()
            .cloned()
            .enumerate()
            .map(|(i, r)| (i + 1, r))
            .collect(),
        skipped: Vec::new(),
    }
}

#[test]
fn a_grid_that_spells_one_hardware_twice_expects_its_id_twice() {
    let d = tmp("twice");
    // Configurations 0 and 1 are the same hardware: one id, two jobs.
    let (configs, scenes, rows) = lib_sweep(&d, "gamma.dac_bits = [8, 8, 9]\n");
    assert_eq!(rows[0].id, rows[1].id);
    let mut back = rows.clone();
    back.reverse();
    let m = merge(&configs, &scenes, None, &[part("back", &back)]);
    assert!(m.complete(), "{}", m.problems());
    assert_eq!(m.rows, rows);
    // Two rows of the id fill its two jobs; a third is a duplicate.
    let m = merge(
        &configs,
        &scenes,
        None,
        &[part("p", &rows), part("q", &rows[..1])],
    );
    assert_eq!(m.duplicated.len(), 1);
    assert_eq!(m.duplicated[0].places.len(), 2);
    assert!(m.missing.is_empty() && m.foreign.is_empty());
}

#[test]
fn truth_and_flicker_settings_must_match_the_sweep() {
    let d = tmp("settings");
    let (configs, scenes, rows) = lib_sweep(&d, "gamma.dac_bits = [8, 9]\n");
    // --dof-truth is part of the ids: rows without it are foreign to a truth merge.
    let m = merge(&configs, &scenes, Some(256), &[part("p", &rows)]);
    assert_eq!((m.missing.len(), m.foreign.len()), (2, 2));
    // --flicker is not: rows with and without it are a mixed set.
    let mut mixed = rows.clone();
    mixed[1].flicker = Some(sweep::FlickerMetrics {
        phases: 8,
        displayed_ripple_pct: 1.0,
        peak_pixel_modulation_pct: 1.0,
        half_pixel_brightness_error_pct: 1.0,
        worst_object: "point".into(),
    });
    let m = merge(&configs, &scenes, None, &[part("p", &mixed)]);
    assert!(!m.complete());
    let text = m.problems().to_string();
    assert!(
        text.contains("no --flicker (first at p:1), --flicker 8 (first at p:2)"),
        "{text}"
    );
    let m = merge(&configs, &scenes, None, &[part("p", &rows)]);
    assert!(m.complete() && m.problems().to_string().is_empty());
}
