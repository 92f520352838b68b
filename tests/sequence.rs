//! Sequences (docs/sequence.md): keyframes and their interpolation, the reuse between frames
//! (bit-identical to single renders), the temporal figures, the command line and its APNG.

mod common;

use igemu::config::{FilterKind, HwConfig};
use igemu::files::TomlFile;
use igemu::pipeline::{self, fast};
use igemu::scene::{Interpolation, Object, Scene};
use igemu::sequence::SequenceReport;
use igemu::stage::RunOptions;
use std::process::Command;

/// The embedded flypast's text with `edit` applied.
fn flypast_with(edit: impl Fn(String) -> String) -> Scene {
    let (_, text) = igemu::scene::EMBEDDED
        .iter()
        .find(|(n, _)| *n == "flypast")
        .expect("embedded flypast");
    let text = edit(text.to_string());
    Scene::from_toml(&TomlFile::from_text("flypast-test.toml", &text))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Runs `frames` of `scene` and returns the report and each frame's fixed codes.
fn run(
    scene: &Scene,
    hw: &HwConfig,
    frames: std::ops::Range<u32>,
    reference: bool,
    reuse: bool,
) -> (SequenceReport, Vec<Vec<u16>>) {
    let (r, kept) = common::run_sequence(scene, hw, frames, reference, reuse);
    (
        r,
        kept.into_iter()
            .map(|(mut f, _)| f.swap_remove(0))
            .collect(),
    )
}

fn still_flypast(frames: u32) -> Scene {
    flypast_with(|t| {
        let head = &t[..t.find("[sequence]").expect("a [sequence]")];
        format!("{head}[sequence]\nframes = {frames}\n")
    })
}

#[test]
fn a_still_sequence_reuses_every_stage_after_frame_0_and_equals_single_renders() {
    let scene = still_flypast(3);
    let hw = HwConfig::default_config();
    assert!(scene.sequence.as_ref().unwrap().is_still(&scene));
    let (r, codes) = run(&scene, &hw, 0..3, true, true);
    assert_eq!(r.reuse.frames_fully_reused, 2, "{:?}", r.reuse);
    assert!(r.frames[0].emulated_stages > 0);
    for f in &r.frames[1..] {
        assert_eq!(f.emulated_stages, 0, "frame {}", f.frame);
        assert_eq!(f.reused_stages, r.frames[0].emulated_stages);
    }
    let single = pipeline::render(&scene.frame(0).unwrap(), &hw, RunOptions::FAST).unwrap();
    for (k, c) in codes.iter().enumerate() {
        assert!(*c == single.dac, "frame {k} against a single render");
    }
    // Nothing moves: no excess flicker, every frame the same cycles.
    assert_eq!(r.temporal.max_excess_weber, Some(0.0));
    assert!(r.frames.iter().all(|f| f.cycles == r.frames[0].cycles));
    assert!(!r.reuse.camera_moves);
}

#[test]
fn a_moving_sequence_is_bit_identical_with_and_without_reuse_and_to_single_renders() {
    let scene = Scene::embedded("flypast").expect("embedded");
    let hw = HwConfig::default_config();
    let (a, with) = run(&scene, &hw, 2..6, false, true);
    let (b, without) = run(&scene, &hw, 2..6, false, false);
    assert!(with == without);
    assert_eq!(
        a.reuse.frames_fully_reused, 0,
        "objects move in every frame"
    );
    assert!(!b.reuse.enabled);
    for (k, c) in (2..6).zip(&with) {
        let one =
            fast::emulate(&scene.frame(k).unwrap(), &hw, RunOptions::FIXED_ONLY, None).unwrap();
        assert!(
            *c == one.channels[0],
            "frame {k} against a single emulation"
        );
    }
    // Consecutive frames differ (the objects move across sub-pixel phases).
    assert!(with.windows(2).all(|w| w[0] != w[1]));
    let cycles: Vec<u64> = a.frames.iter().map(|f| f.cycles).collect();
    assert_eq!(a.summary.worst_cycles, *cycles.iter().max().unwrap());
    assert_eq!(
        a.summary.worst_frame,
        2 + cycles
            .iter()
            .position(|&c| c == a.summary.worst_cycles)
            .unwrap() as u32
    );
}

#[test]
fn keys_move_the_objects_linearly_or_through_a_spline() {
    let scene = Scene::embedded("flypast").expect("embedded");
    let pos = |s: &Scene| match &s.objects[3] {
        Object::LightPoint { position, .. } => *position,
        o => panic!("object 3 is the light point, got {o:?}"),
    };
    let p0 = pos(&scene);
    let p31 = pos(&scene.frame(31).unwrap());
    assert!((p31[0] - p0[0] - 11.47).abs() < 1e-9 && (p31[1] - p0[1] - 3.41).abs() < 1e-9);
    let p10 = pos(&scene.frame(10).unwrap());
    assert!((p10[0] - p0[0] - 11.47 * 10.0 / 31.0).abs() < 1e-9);
    // After the last key the pose holds.
    let mut s = scene.clone();
    s.sequence.as_mut().unwrap().frames = 40;
    assert_eq!(pos(&s.frame(39).unwrap()), p31);
    // A spline through three keys passes through them and bends between.
    let spline = flypast_with(|t| {
        t.replace("interpolation = \"linear\"", "interpolation = \"spline\"")
            .replace(
                "[[sequence.object]]        # 0.37 px per frame",
                "[[sequence.object]]\nobject = 3\nframe = 15\ntranslate = [0.0, 6.0, 0.0]\n\n[[sequence.object]]        # 0.37 px per frame",
            )
    });
    assert_eq!(
        spline.sequence.as_ref().unwrap().interpolation,
        Interpolation::Spline
    );
    let y = |f| pos(&spline.frame(f).unwrap())[1] - p0[1];
    assert!((y(15) - 6.0).abs() < 1e-9 && (y(31) - 3.41).abs() < 1e-9);
    assert!(
        y(8) > 6.0 * 8.0 / 15.0,
        "the spline is not the straight line"
    );
}

#[test]
fn bad_sequence_fields_are_refused_naming_the_field() {
    let cases: [(&str, &str, &str); 7] = [
        ("frames = 32", "frames = 0", "sequence.frames"),
        (
            "interpolation = \"linear\"",
            "interpolation = \"cubic\"",
            "sequence.interpolation",
        ),
        (
            "object = 3\nframe = 31",
            "object = 3\nframe = 32",
            "sequence.object[1].frame",
        ),
        (
            "object = 3\nframe = 31",
            "object = 3\nframe = 0",
            "sequence.object[1].frame",
        ),
        (
            "object = 4\nframe = 0",
            "object = 9\nframe = 0",
            "sequence.object[2].object",
        ),
        (
            "object = 5\nframe = 0\ntranslate = [0.0, 0.0, 0.0]",
            "object = 5\nframe = 0\nscale = 2.0",
            "sequence.object[4]",
        ),
        ("[sequence]\n", "[sequence]\nspeed = 2\n", "speed"),
    ];
    for (from, to, field) in cases {
        let (_, text) = igemu::scene::EMBEDDED
            .iter()
            .find(|(n, _)| *n == "flypast")
            .unwrap();
        assert!(text.contains(from), "{from}");
        let bad = text.replacen(from, to, 1);
        let e = Scene::from_toml(&TomlFile::from_text("bad.toml", &bad))
            .expect_err(&format!("{to} must be refused"));
        let msg = e.to_string();
        assert!(
            msg.contains(field) && msg.contains("bad.toml"),
            "{to}: {msg}"
        );
    }
    // A focus pull needs a thin lens.
    let pin = common::scene_toml(
        32,
        32,
        0.0,
        "[sequence]\nframes = 2\n[[sequence.camera]]\nframe = 0\nfocus_distance = 5.0\n",
    );
    let e = Scene::from_toml(&TomlFile::from_text("pin.toml", &pin)).unwrap_err();
    assert!(
        e.to_string().contains("sequence.camera[0].focus_distance"),
        "{e}"
    );
}

#[test]
fn the_tent_filter_flickers_less_than_the_box_on_the_moving_light_point() {
    let scene = Scene::embedded("flypast").expect("embedded");
    let modulation = |filter| {
        let mut hw = HwConfig::default_config();
        hw.accumulate.filter = filter;
        let (r, _) = run(&scene, &hw, 0..32, false, true);
        let o = r
            .temporal
            .objects
            .iter()
            .find(|o| o.kind == "light_point")
            .expect("the point");
        o.peak_modulation_fixed_pct
    };
    let (tent, boxed) = (modulation(FilterKind::Tent), modulation(FilterKind::Box));
    assert!(tent < boxed, "tent {tent}% against box {boxed}%");
}

fn igemu(args: &[&str]) -> (i32, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_igemu"))
        .args(args)
        .output()
        .expect("runs");
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn the_command_reports_json_and_writes_an_animated_png() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("sequence-cli");
    std::fs::create_dir_all(&dir).unwrap();
    let apng = dir.join("seq.png");
    let (code, out, err) = igemu(&[
        "sequence",
        "flypast",
        "--frames",
        "3..6",
        "--apng",
        apng.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(j["frames"].as_array().unwrap().len(), 3);
    assert_eq!(j["first"], 3);
    assert!(j["summary"]["worst_cycles"].as_u64().unwrap() > 0);
    assert!(j["temporal"]["max_excess_weber"].is_number());
    assert_eq!(j["temporal"]["objects"].as_array().unwrap().len(), 3);
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&apng).unwrap()));
    let reader = dec.read_info().unwrap();
    let info = reader.info();
    assert_eq!(info.animation_control.expect("animated").num_frames, 3);
    assert_eq!((info.width, info.height), (640, 240), "fixed | difference");
    // Bad ranges and a still scene without [sequence] are refused with exit 2.
    let (code, _, err) = igemu(&["sequence", "flypast", "--frames", "30..40"]);
    assert_eq!(code, 2);
    assert!(err.contains("--frames") && err.contains("0..32"), "{err}");
    let (code, _, err) = igemu(&["sequence", "default"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("sequence") && err.contains("[sequence]"),
        "{err}"
    );
}
