//! The fixed-only fast path (`pipeline::fast`, `render --no-reference`): the same DAC codes,
//! work, signals, overflows, cost and cycles as a full render, on grey and colour scenes,
//! every dof kind, log coding, dither and banded runs; no float tap and no memory image is
//! computed unless asked for (the pack checks are then the full render's); the command
//! line writes the same image and refuses what needs the reference, naming the flag.

mod common;

use common::igemu;
use igemu::config::{DitherKind, DofKind, HwConfig};
use igemu::pipeline::fast::{Emulation, emulate};
use igemu::pipeline::{Render, render};
use igemu::scene::Scene;
use igemu::stage::RunOptions;

fn small(name: &str) -> Scene {
    let mut s = Scene::embedded(name).expect("embedded");
    s.image.width = 160;
    s.image.height = 120;
    s
}

/// Checks that the fixed-only run `e` is the full render `r` without its reference.
fn same_as_full(e: &Emulation, r: &Render, what: &str) {
    let codes: Vec<&Vec<u16>> = match &r.colour {
        Some(c) => c.channels.iter().map(|k| &k.dac).collect(),
        None => vec![&r.dac],
    };
    assert_eq!(e.channels.len(), codes.len(), "{what}");
    for (k, (a, b)) in e.channels.iter().zip(codes).enumerate() {
        assert!(a == b, "{what}: channel {k}'s DAC codes differ");
    }
    let f = &e.report;
    assert_eq!(f.overflows, r.report.overflows, "{what}");
    assert_eq!(f.storage_bits, r.report.storage_bits, "{what}");
    assert_eq!(f.lut_bits, r.report.lut_bits, "{what}");
    assert_eq!(
        f.cycles.total_cycles, r.report.cycles.total_cycles,
        "{what}"
    );
    assert_eq!(f.stages.len(), r.report.stages.len(), "{what}");
    for (a, b) in f.stages.iter().zip(&r.report.stages) {
        assert_eq!(a.work, b.work, "{what}: {}", a.name);
        assert_eq!(
            a.cost.storage_bits, b.cost.storage_bits,
            "{what}: {}",
            a.name
        );
        let sig =
            |s: &igemu::stage::StageReport| -> Vec<(String, Option<i128>, Option<i128>, u64)> {
                s.signals
                    .iter()
                    .map(|x| (x.name.clone(), x.min, x.max, x.overflows))
                    .collect()
            };
        assert_eq!(sig(a), sig(b), "{what}: {}", a.name);
        assert_eq!(a.float_ms, 0.0, "{what}: {} ran a float reference", a.name);
        assert!(a.local.is_none());
    }
    for s in &e.steps {
        let t = &s.outcome.taps.float;
        assert!(
            t.prims.is_none() && t.samples.is_none() && t.frame.is_none() && t.pixels.is_none(),
            "{what}: {} left a float tap",
            s.id
        );
    }
}

fn check(s: &Scene, h: &HwConfig, what: &str) {
    let r = render(s, h, RunOptions::FAST).unwrap_or_else(|e| panic!("{what}: {e}"));
    let e = emulate(s, h, RunOptions::FIXED_ONLY, None).unwrap_or_else(|e| panic!("{what}: {e}"));
    same_as_full(&e, &r, what);
    assert!(
        e.report.cycles.cost.packed.is_empty(),
        "{what}: no memory images by default"
    );
    // With the memories' images (what --rom-out needs): the full render's pack checks.
    let packed = RunOptions {
        pack_check: true,
        ..RunOptions::FIXED_ONLY
    };
    let e = emulate(s, h, packed, None).unwrap();
    assert_eq!(
        e.report.cycles.cost.packed, r.report.cycles.cost.packed,
        "{what}"
    );
    assert!(!e.report.cycles.cost.packed.is_empty());
}

#[test]
fn the_default_scene_fixed_only_is_the_full_render_without_its_reference() {
    // Full size: the full render's codes are the golden ones (tests/golden.rs).
    let h = HwConfig::default_config();
    for name in ["default", "default-pinhole"] {
        check(&Scene::embedded(name).unwrap(), &h, name);
    }
}

#[test]
fn every_dof_kind_coding_and_dither_fixed_only_on_grey_and_colour() {
    for scene in ["cone-focus", "default-colour"] {
        for kind in DofKind::ALL {
            let mut h = HwConfig::default_config();
            h.dof.kind = kind;
            check(&small(scene), &h, &format!("{scene} {kind:?}"));
        }
        for preset in ["log8-potentiate", "log8-logadd"] {
            let h = HwConfig::preset(preset).unwrap();
            check(&small(scene), &h, &format!("{scene} {preset}"));
        }
        let mut h = HwConfig::default_config();
        h.dither.kind = DitherKind::FloydSteinberg;
        check(&small(scene), &h, &format!("{scene} Floyd-Steinberg"));
    }
}

#[test]
fn a_banded_fixed_only_run_is_the_whole_run() {
    let s = small("default");
    let h = HwConfig::default_config();
    let r = render(&s, &h, RunOptions::FAST).unwrap();
    let banded = RunOptions {
        band_rows: Some(16),
        ..RunOptions::FIXED_ONLY
    };
    let e = emulate(&s, &h, banded, None).unwrap();
    same_as_full(&e, &r, "16-row bands");
}

#[test]
fn the_command_line_writes_the_same_image_and_refuses_reference_outputs() {
    let dir = std::env::temp_dir().join(format!("igemu-fast-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = |n: &str| dir.join(n).display().to_string();
    for scene in ["default", "default-colour"] {
        let (full, fast) = (
            p(&format!("{scene}-full.png")),
            p(&format!("{scene}-fast.png")),
        );
        let (c, _, err) = igemu(&["render", scene, "-o", &full]);
        assert_eq!(c, 0, "{err}");
        let (c, out, err) = igemu(&["render", scene, "--no-reference", "-o", &fast]);
        assert_eq!(c, 0, "{err}");
        assert!(out.contains("fixed only (--no-reference)"), "{out}");
        assert_eq!(
            std::fs::read(&full).unwrap(),
            std::fs::read(&fast).unwrap(),
            "{scene}"
        );
    }
    let (c, out, _) = igemu(&[
        "render",
        "default",
        "--no-reference",
        "--json",
        "-o",
        &p("j.png"),
    ]);
    assert_eq!(c, 0);
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON");
    assert_eq!(v["mode"], "fixed only");
    assert!(v.get("end_to_end").is_none());
    // --rom-out builds the memories' images on the fast path too.
    let roms = p("roms");
    std::fs::create_dir_all(&roms).unwrap();
    let (c, _, err) = igemu(&[
        "render",
        "default",
        "--no-reference",
        "--rom-out",
        &roms,
        "-o",
        &p("r.png"),
    ]);
    assert_eq!(c, 0, "{err}");
    assert!(std::path::Path::new(&roms).join("manifest.json").exists());
    for flag in ["--reference-out", "--diff-out", "--banding-out", "--html"] {
        let (c, _, err) = igemu(&[
            "render",
            "default",
            "--no-reference",
            flag,
            &p("x.out"),
            "-o",
            &p("y.png"),
        ]);
        assert_eq!(c, 2, "{flag}: {err}");
        assert!(
            err.contains(flag) && err.contains("--no-reference"),
            "{err}"
        );
        assert!(
            !std::path::Path::new(&p("y.png")).exists(),
            "nothing written"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
