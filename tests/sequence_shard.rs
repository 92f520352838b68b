//! A sequence run in shards (docs/sequence.md, "Sharding a long sequence"): `igemu sequence
//! --shard K/N --part FILE` and `igemu sequence merge`. The merged report equals the
//! unsharded run's in every field but the wall-clock and reuse counters (the temporal
//! figures across the shard borders too); missing, overlapping and foreign parts are refused
//! naming the frames and the files; a colour sequence (R, G, B, the temporal figures on the
//! luminance `Y`) merges as a grey one; `--shard auto` takes the shard from a Slurm array task
//! or a Kubernetes indexed Job.

mod common;

use igemu::config::{DitherKind, HwConfig};
use igemu::scene::Scene;
use igemu::sequence::{self, SequenceOptions, SequenceReport, merge, shard};
use igemu::shard::Shard;
use serde_json::Value;
use std::path::{Path, PathBuf};

use common::igemu_env as igemu;

fn tmp(name: &str) -> PathBuf {
    common::tmp_dir("seqshard", name)
}

fn path(d: &Path, name: &str) -> String {
    d.join(name).to_string_lossy().into_owned()
}

/// A report's JSON without the fields that are wall-clock or reuse counters (a shard starts
/// with its own cold stage cache).
fn without_wall_clock(mut v: Value) -> Value {
    for f in v["frames"].as_array_mut().expect("frames") {
        let f = f.as_object_mut().expect("a frame");
        for k in [
            "wall_ms",
            "reused_stages",
            "emulated_stages",
            "tile_rows_reused",
            "tile_rows_emulated",
        ] {
            assert!(f.remove(k).is_some(), "{k}");
        }
    }
    let u = v["reuse"].as_object_mut().expect("reuse");
    for k in [
        "wall_s",
        "frames_per_s",
        "stages_emulated",
        "stages_reused",
        "frames_fully_reused",
        "tile_rows_emulated",
        "tile_rows_reused",
        "first_over_later_wall",
    ] {
        assert!(u.remove(k).is_some(), "{k}");
    }
    v
}

fn json(text: &str) -> Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}: {text}"))
}

/// The colour fly-past (`docs/flypast-colour.toml`).
const COLOUR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/flypast-colour.toml");

/// `igemu sequence flypast --frames RANGE EXTRA... --json`: the report.
fn unsharded(range: &str, extra: &[&str]) -> Value {
    unsharded_of("flypast", range, extra)
}

/// `igemu sequence SCENE --frames RANGE EXTRA... --json`: the report.
fn unsharded_of(scene: &str, range: &str, extra: &[&str]) -> Value {
    let mut args = vec!["sequence", scene, "--frames", range, "--json"];
    args.extend(extra);
    let (code, out, err) = igemu(&args, &[]);
    assert_eq!(code, 0, "{err}");
    json(&out)
}

/// `igemu sequence flypast --frames RANGE --shard SPEC --part d/NAME EXTRA...` with the
/// shard variables `env`: (exit code, the part's path, stderr). An `EXTRA` of
/// `--scene PATH` runs that scene instead of `flypast`.
fn shard_run(
    d: &Path,
    range: &str,
    spec: &str,
    name: &str,
    extra: &[&str],
    env: &[(&str, &str)],
) -> (i32, String, String) {
    let part = path(d, name);
    let (scene, extra) = match extra {
        ["--scene", scene, rest @ ..] => (*scene, rest),
        _ => ("flypast", extra),
    };
    let mut args = vec!["sequence", scene, "--frames", range, "--shard", spec];
    args.extend(["--part", &part]);
    args.extend(extra);
    let (code, _, err) = igemu(&args, env);
    (code, part, err)
}

/// Shards `K/n` for each K of `ks` of `flypast --frames RANGE EXTRA...` into `d/part-K.json`.
fn shards(d: &Path, range: &str, n: usize, ks: &[usize], extra: &[&str]) -> Vec<String> {
    ks.iter()
        .map(|k| {
            let name = format!("part-{k}.json");
            let (code, part, err) = shard_run(d, range, &format!("{k}/{n}"), &name, extra, &[]);
            assert_eq!(code, 0, "{err}");
            part
        })
        .collect()
}

/// `igemu sequence merge PARTS... EXTRA...`.
fn merge_parts(parts: &[String], extra: &[&str]) -> (i32, String, String) {
    let mut args = vec!["sequence", "merge"];
    args.extend(parts.iter().map(String::as_str));
    args.extend(extra);
    igemu(&args, &[])
}

#[test]
fn three_shards_with_the_reference_merge_to_the_unsharded_report() {
    let d = tmp("reference");
    let full = unsharded("0..9", &[]);
    let parts = shards(&d, "0..9", 3, &[1, 2, 3], &[]);
    // Any order of the parts; the merged report also goes to --out and an HTML page.
    let (out, html) = (path(&d, "all.json"), path(&d, "all.html"));
    let reversed: Vec<String> = parts.iter().rev().cloned().collect();
    let (code, stdout, err) = merge_parts(&reversed, &["--json", "--out", &out, "--html", &html]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("9 frames (0..9) from 3 parts"), "{err}");
    let merged = json(&stdout);
    assert_eq!(json(&std::fs::read_to_string(&out).unwrap()), merged);
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(
        page.contains("<img") && page.contains("<table"),
        "the plots and the table"
    );
    // The temporal figures cross the shard borders: 8 pairs, the small objects' series.
    let t = &full["temporal"];
    assert_eq!(t["pairs"], 8);
    assert!(t["max_excess_weber"].as_f64().unwrap() > 0.0);
    assert_eq!(t["objects"].as_array().unwrap().len(), 3);
    assert!(full["frames"][0]["identical_fraction"].is_number());
    assert_eq!(without_wall_clock(merged), without_wall_clock(full));
}

#[test]
fn unequal_shards_of_a_fixed_only_run_merge_to_the_unsharded_report() {
    let d = tmp("fixed-only");
    // 7 frames in 3 shards (2, 2, 3 frames), starting at frame 2, no reference.
    let extra = ["--no-reference"];
    let full = unsharded("2..9", &extra);
    let parts = shards(&d, "2..9", 3, &[1, 2, 3], &extra);
    let p: Value = json(&std::fs::read_to_string(&parts[0]).unwrap());
    assert_eq!(p["frames"], serde_json::json!([2, 4]));
    assert_eq!(p["lead_in"], false);
    let (code, stdout, err) = merge_parts(&parts, &["--json"]);
    assert_eq!(code, 0, "{err}");
    let merged = json(&stdout);
    assert_eq!(merged["first"], 2);
    assert!(merged["temporal"]["max_excess_weber"].is_null());
    assert_eq!(without_wall_clock(merged), without_wall_clock(full));
}

/// Frames `frames` of `scene` on `linear8` with a temporal Bayer dither, through the
/// library: the unsharded report, the merge of its `n` shards (each part written to `d` and
/// read back) and whether each part has a lead-in frame.
fn dither_runs(
    scene: &Scene,
    frames: std::ops::Range<u32>,
    n: usize,
    d: &Path,
) -> (SequenceReport, SequenceReport, Vec<bool>) {
    let hw = common::hw("linear8", |h: &mut HwConfig| {
        h.dither.kind = DitherKind::Bayer4;
        h.dither.temporal = true;
    });
    let o = SequenceOptions {
        frames,
        reference: true,
        reuse: true,
    };
    let full = sequence::run(scene, &hw, &o, &mut |_| Ok(())).expect("runs");
    let parts: Vec<(String, shard::Part)> = (1..=n)
        .map(|k| {
            let p = shard::run_shard(scene, &hw, &o, Shard { k, n }, &mut |_| Ok(()))
                .expect("a shard runs");
            let file = path(d, &format!("p{k}.json"));
            std::fs::write(&file, serde_json::to_string(&p).unwrap()).unwrap();
            (file.clone(), merge::read(&file).expect("reads back"))
        })
        .collect();
    let lead_in = parts.iter().map(|(_, p)| p.lead_in).collect();
    let merged = merge::merge(parts).expect("merges");
    (full, merged, lead_in)
}

/// A report's JSON without the wall-clock and reuse counters.
fn value(r: &SequenceReport) -> Value {
    without_wall_clock(serde_json::to_value(r).unwrap())
}

#[test]
fn a_temporal_dither_merges_to_the_unsharded_figures() {
    // The library: parts written and read back as files, merged, against one run.
    let scene = Scene::embedded("flypast").expect("embedded");
    let (full, merged, lead_in) = dither_runs(&scene, 1..7, 3, &tmp("dither"));
    assert_eq!(lead_in, [false, true, true]);
    let dither = full.temporal.dither.as_ref().expect("the temporal dither");
    assert_eq!(dither.frames, 6);
    assert!(dither.static_pixels > 0);
    assert_eq!(value(&merged), value(&full));
}

#[test]
fn a_colour_sequence_in_shards_merges_to_the_unsharded_report() {
    // R, G, B of every frame; the temporal figures on the luminance Y across the borders.
    let d = tmp("colour");
    let full = unsharded_of(COLOUR, "4..10", &[]);
    let parts = shards(&d, "4..10", 3, &[1, 2, 3], &["--scene", COLOUR]);
    let p: Value = json(&std::fs::read_to_string(&parts[2]).unwrap());
    assert_eq!(p["lead_in"], true);
    let (code, stdout, err) = merge_parts(&parts, &["--json"]);
    assert_eq!(code, 0, "{err}");
    let merged = json(&stdout);
    let t = &full["temporal"];
    assert_eq!(t["pairs"], 5);
    assert!(t["max_excess_weber"].as_f64().unwrap() > 0.0);
    assert!(!t["objects"].as_array().unwrap().is_empty());
    assert!(full["frames"][0]["delta_e_max"].is_number());
    assert_eq!(without_wall_clock(merged), without_wall_clock(full));
}

#[test]
fn a_colour_temporal_dither_merges_to_the_unsharded_figures() {
    // Channel R's temporal dither, the pairs and the objects on Y, through the library.
    let scene = Scene::load(COLOUR).unwrap_or_else(|e| panic!("{e}"));
    let (full, merged, lead_in) = dither_runs(&scene, 2..6, 2, &tmp("colour-dither"));
    assert_eq!(lead_in, [false, true]);
    let dither = full.temporal.dither.as_ref().expect("the temporal dither");
    assert_eq!(dither.frames, 4);
    assert!(dither.static_pixels > 0);
    assert_eq!(full.temporal.pairs, 3);
    assert_eq!(value(&merged), value(&full));
}

#[test]
fn a_missing_shard_is_named_by_its_frames() {
    let d = tmp("missing");
    let parts = shards(&d, "0..9", 3, &[1, 3], &["--no-reference"]);
    let (code, out, err) = merge_parts(&parts, &[]);
    assert_eq!(code, 2, "{out}{err}");
    assert!(err.contains("frames 3..6 are in no part"), "{err}");
    assert!(
        err.contains("--shard 2/3") && err.contains("part-3.json"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    // The last shard missing: the frames up to the run's end.
    let (code, _, err) = merge_parts(&parts[..1], &[]);
    assert_eq!(code, 2);
    assert!(err.contains("frames 3..9 are in no part"), "{err}");
}

#[test]
fn overlapping_parts_and_a_part_given_twice_are_refused() {
    let d = tmp("overlap");
    let thirds = shards(&d, "0..9", 3, &[1, 2, 3], &["--no-reference"]);
    let (code, half, err) = shard_run(&d, "0..9", "1/2", "half.json", &["--no-reference"], &[]);
    assert_eq!(code, 0, "{err}");
    // 1/2 is frames 0..4, 2/3 frames 3..6: frame 3 is in both.
    let parts = [half.clone(), thirds[1].clone(), thirds[2].clone()];
    let (code, _, err) = merge_parts(&parts, &[]);
    assert_eq!(code, 2);
    assert!(err.contains("frames 3..4 are in both"), "{err}");
    assert!(
        err.contains("half.json") && err.contains("part-2.json"),
        "{err}"
    );
    let mut twice = thirds.clone();
    twice.push(thirds[0].clone());
    let (code, _, err) = merge_parts(&twice, &[]);
    assert_eq!(code, 2);
    assert!(err.contains("frames 0..3 are in both"), "{err}");
}

#[test]
fn parts_of_different_runs_are_refused_naming_the_field() {
    let d = tmp("foreign");
    let a = shards(&d, "0..6", 2, &[1], &["--no-reference"]);
    let other = |name: &str, extra: &[&str]| {
        let (code, p, err) = shard_run(&d, "0..6", "2/2", name, extra, &[]);
        assert_eq!(code, 0, "{err}");
        p
    };
    let cases = [
        (
            other("hw.json", &["--no-reference", "--hw", "linear8"]),
            "report.hardware",
        ),
        (
            other("filter.json", &["--no-reference", "--filter", "box"]),
            "report.filter",
        ),
        (other("ref.json", &[]), "report.reference"),
    ];
    for (p, field) in cases {
        let (code, _, err) = merge_parts(&[a[0].clone(), p.clone()], &[]);
        assert_eq!(code, 2, "{field}");
        assert!(err.contains(&p) && err.contains(field), "{field}: {err}");
    }
    // The same hardware file edited between two shards: the names agree, the contents not.
    let hw = path(&d, "hw.toml");
    let shard_on = |bits: u32, spec: &str, name: &str| {
        std::fs::write(
            &hw,
            format!("preset = \"linear12\"\n[gamma]\ndac_bits = {bits}\n"),
        )
        .unwrap();
        let (code, p, err) = shard_run(
            &d,
            "0..6",
            spec,
            name,
            &["--no-reference", "--hw", &hw],
            &[],
        );
        assert_eq!(code, 0, "{err}");
        p
    };
    let edited = [
        shard_on(9, "1/2", "file-1.json"),
        shard_on(10, "2/2", "file-2.json"),
    ];
    let (code, _, err) = merge_parts(&edited, &[]);
    assert_eq!(code, 2);
    assert!(
        err.contains("hardware_key") && err.contains("file-2.json"),
        "{err}"
    );
    // Not a part file, a part cut short: refused naming the file.
    let cut = path(&d, "cut.json");
    let text = std::fs::read_to_string(&a[0]).unwrap();
    std::fs::write(&cut, &text[..text.len() / 2]).unwrap();
    let (code, _, err) = merge_parts(std::slice::from_ref(&cut), &[]);
    assert_eq!(code, 2);
    assert!(
        err.contains(&cut) && err.contains("is not a part file"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    // An output naming a part is refused before anything is written.
    let (code, _, err) = merge_parts(&a, &["--out", &a[0]]);
    assert_eq!(code, 2);
    assert!(
        err.contains("--out") && err.contains("never overwrites"),
        "{err}"
    );
}

#[test]
fn shard_auto_takes_the_slurm_array_task_or_the_kubernetes_index() {
    let d = tmp("auto");
    let run = |env: &[(&str, &str)], spec: &str, name: &str| {
        shard_run(&d, "0..9", spec, name, &["--no-reference"], env)
    };
    // Task 6 of --array=4-7 is shard 3/4: frames 4..6 of 0..9.
    let slurm = [
        ("SLURM_ARRAY_TASK_ID", "6"),
        ("SLURM_ARRAY_TASK_MIN", "4"),
        ("SLURM_ARRAY_TASK_MAX", "7"),
        ("SLURM_ARRAY_TASK_COUNT", "4"),
        ("SLURM_ARRAY_TASK_STEP", "1"),
    ];
    let (code, p, err) = run(&slurm, "auto", "slurm.json");
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("shard 3/4 from SLURM_ARRAY_TASK_ID=6"),
        "{err}"
    );
    let part = json(&std::fs::read_to_string(&p).unwrap());
    assert_eq!(part["frames"], serde_json::json!([4, 6]));
    assert_eq!(
        (part["shard"].clone(), part["shards"].clone()),
        (3.into(), 4.into())
    );
    let k8s = [("JOB_COMPLETION_INDEX", "0")];
    let (code, p, err) = run(&k8s, "auto/3", "k8s.json");
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        json(&std::fs::read_to_string(&p).unwrap())["frames"],
        serde_json::json!([0, 3])
    );
    // Outside an array task, `auto` says what to give instead; nothing is written.
    let (code, p, err) = run(&[], "auto", "none.json");
    assert_eq!(code, 2);
    assert!(
        err.contains("--shard") && err.contains("SLURM_ARRAY_TASK_ID"),
        "{err}"
    );
    assert!(!Path::new(&p).exists());
}

#[test]
fn bad_shards_and_ranges_are_refused_naming_the_flag() {
    let d = tmp("bad");
    let (code, p, err) = shard_run(&d, "0..9", "4/3", "p.json", &[], &[]);
    assert_eq!(code, 2);
    assert!(err.contains("--shard") && err.contains("4/3"), "{err}");
    assert!(!Path::new(&p).exists());
    // More shards than frames leaves a shard without a frame.
    let (code, _, err) = shard_run(&d, "0..2", "1/3", "p.json", &[], &[]);
    assert_eq!(code, 2);
    assert!(
        err.contains("--shard") && err.contains("without a frame"),
        "{err}"
    );
    // --shard needs --part.
    let (code, _, err) = igemu(&["sequence", "flypast", "--shard", "1/2"], &[]);
    assert_eq!(code, 2);
    assert!(err.contains("--part"), "{err}");
    // One check of --frames, the library's: it names the scene and `sequence.frames`.
    let (code, _, err) = igemu(&["sequence", "flypast", "--frames", "5..40"], &[]);
    assert_eq!(code, 2);
    assert!(
        err.contains("flypast") && err.contains("sequence.frames") && err.contains("0..32"),
        "{err}"
    );
}
