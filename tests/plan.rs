//! The plan: built before anything runs; its memory estimate refuses what would not fit
//! (before any stage allocates) and covers the measured peak; its notes; hard cases of the
//! layout (one sample per pixel with every filter); the dof stage's advice on the mask
//! half-size is enough to follow; `--dump accumulate` is the frame before depth of field.

mod common;

use common::{hw, igemu, scene, tri};
use igemu::config::{FilterKind, HwConfig};
use igemu::pipeline::{self, render};
use igemu::scene::Scene;
use igemu::stage::{RunOptions, StageId};

#[test]
fn one_sample_per_pixel_runs_with_every_filter_and_coding() {
    // A tent over one sample per pixel reaches one sample further on one side than the
    // other: its sample region must hold that (it once indexed past the buffer).
    let pin = Scene::embedded("default-pinhole").unwrap();
    let thin = Scene::default_scene();
    for filter in [FilterKind::Box, FilterKind::Tent, FilterKind::Gaussian] {
        for (s, preset) in [
            (&pin, "linear12"),
            (&thin, "linear12"),
            (&pin, "log8-logadd"),
            (&pin, "log8-potentiate"),
        ] {
            let h = hw(preset, |h| {
                h.raster.samples = 1;
                h.accumulate.filter = filter;
                h.accumulate.weight_bits = 8;
            });
            let r = render(s, &h, RunOptions::FAST)
                .unwrap_or_else(|e| panic!("{filter:?} {preset}: {e}"));
            let k = &r.report.cycles.cost;
            assert!(
                k.packed.iter().all(|p| p.verified),
                "{filter:?} {preset}: {:?}",
                k.packed
            );
            assert!(r.report.end_to_end.codes.identical_fraction > 0.9);
        }
    }
}

#[test]
fn the_memory_estimate_covers_the_measured_peak() {
    let png = std::env::temp_dir().join(format!("igemu-plan-{}.png", std::process::id()));
    let png = png.to_str().unwrap();
    for s in ["default", "default-pinhole", "cone-focus"] {
        let (code, out, err) = igemu(&["render", s, "-o", png, "--json"]);
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        let est = v["plan"]["memory"]["bytes"].as_u64().unwrap();
        let parts: u64 = v["plan"]["memory"]["parts"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p["bytes"].as_u64().unwrap())
            .sum();
        assert_eq!(est, parts);
        // The peak of the whole process (the binary, the libraries, the report) stays under
        // the estimate, and the estimate is not wildly conservative.
        if let Some(peak) = v["timing"]["peak_memory_bytes"].as_u64() {
            assert!(peak <= est, "{s}: peak {peak} > estimate {est}");
            assert!(
                est <= 3 * peak,
                "{s}: estimate {est} over 3x the peak {peak}"
            );
        }
    }
}

#[test]
fn a_plan_over_the_memory_limit_is_refused_before_anything_runs() {
    let s = Scene::default_scene();
    let h = HwConfig::default_config();
    let opts = RunOptions {
        max_memory: Some(64 << 20),
        ..RunOptions::FAST
    };
    let t = std::time::Instant::now();
    let e = match render(&s, &h, opts) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("a 64 MiB limit must refuse the default scene"),
    };
    assert!(
        t.elapsed().as_secs_f64() < 1.0,
        "refused before the stages ran"
    );
    for needle in [
        "image.width",
        "raster.samples",
        "--max-memory",
        "64.0 MiB",
        "sample buffers",
    ] {
        assert!(e.contains(needle), "`{needle}` not in: {e}");
    }
    // The same plan under a sufficient limit runs.
    let ok = RunOptions {
        max_memory: Some(4 << 30),
        ..RunOptions::FAST
    };
    assert!(render(&s, &h, ok).is_ok());
    // The stage-level entry point checks too.
    assert!(pipeline::run_through(&s, &h, opts, StageId::Input).is_err());
}

#[test]
fn an_8192_square_screen_is_accepted_in_bands_and_a_small_limit_still_refuses_it() {
    // The documented maximum resolution with the default scene and a pinhole camera runs
    // raster, visibility and accumulate in bands (docs/reliability.md: measured under
    // 4 GiB): its estimate counts one band's sample buffers and fragments.
    let s = Scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/default-8k.toml"
    ))
    .unwrap();
    let hp = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/q15-4.toml");
    let h = HwConfig::from_toml(&igemu::files::TomlFile::read(hp).unwrap()).unwrap();
    assert_eq!((s.image.width, s.image.height), (8192, 8192));
    let plan = pipeline::plan::build(&s, &h).unwrap();
    assert!(pipeline::bands::rows(&plan, RunOptions::default()).is_some());
    let e = plan.memory(RunOptions::default());
    assert!(e.bytes < 5 << 30, "{e:?}");
    assert!(
        e.parts
            .iter()
            .any(|p| p.what == "sample buffers (one band)")
    );
    // The same screen with the whole region at once would need tens of GiB.
    let (buffers, frags) = pipeline::estimate::sample_side(&plan, RunOptions::default());
    assert!(buffers + frags > (30u64 << 30) as f64);
    // A 1 GiB limit stands in for a small machine: refused before anything runs.
    let t = std::time::Instant::now();
    let opts = RunOptions {
        max_memory: Some(1 << 30),
        ..RunOptions::FAST
    };
    let e = render(&s, &h, opts).err().expect("refused");
    // Before anything runs: no stage's seconds (a hang guard, not a speed target).
    assert!(t.elapsed().as_secs_f64() < 10.0);
    assert!(e.to_string().contains("GiB"), "{e}");
    assert!(e.to_string().contains("one band"), "{e}");
}

#[test]
fn plan_notes_name_options_without_effect_and_a_narrow_guard_band() {
    let pin = Scene::embedded("default-pinhole").unwrap();
    let opts = RunOptions {
        dof_reference: true,
        ..RunOptions::FAST
    };
    let r = render(&pin, &HwConfig::default_config(), opts).unwrap();
    assert!(
        r.report
            .plan
            .notes
            .iter()
            .any(|n| n.contains("--dof-reference")),
        "{:?}",
        r.report.plan.notes
    );
    let thin = render(&Scene::default_scene(), &HwConfig::default_config(), opts).unwrap();
    assert!(
        thin.report.plan.notes.is_empty(),
        "{:?}",
        thin.report.plan.notes
    );
    // With no guard band, the tent filter's edge pixels read background samples beyond the
    // screen: the report says so, and the edge really is darker than its neighbour.
    let objects = tri(
        [[-20.0, -20.0, 0.5], [80.0, -20.0, 0.5], [-20.0, 80.0, 0.5]],
        [1.0; 3],
    );
    let s = scene(32, 24, 0.0, &objects);
    let g0 = hw("linear12", |h| h.raster.guard_band = 0);
    let r = render(&s, &g0, RunOptions::FAST).unwrap();
    let note = r.report.plan.notes.join(" ");
    assert!(note.contains("raster.guard_band = 0"), "{note}");
    assert!(r.dac[5 * 32] < r.dac[5 * 32 + 2], "the edge column fades");
    let wide = render(&s, &HwConfig::default_config(), RunOptions::FAST).unwrap();
    assert!(wide.report.plan.notes.is_empty());
    assert_eq!(wide.dac[5 * 32], wide.dac[5 * 32 + 2]);
}

#[test]
fn the_mask_half_size_advice_is_enough_to_follow() {
    for radius in ["0.3", "0.35"] {
        let text = include_str!("../src/scene/default.toml")
            .replace("lens_radius = 0.06 ", &format!("lens_radius = {radius} "));
        let s = Scene::from_toml(&igemu::files::TomlFile::from_text("lens.toml", &text)).unwrap();
        let e = render(&s, &HwConfig::default_config(), RunOptions::FAST)
            .err()
            .expect("a wide lens exceeds the default half-size")
            .to_string();
        let m: u32 = e
            .split("raise dof.max_half_size to ")
            .nth(1)
            .and_then(|t| t.split_whitespace().next())
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("no advice in: {e}"));
        let h = hw("linear12", |h| h.dof.max_half_size = m);
        render(&s, &h, RunOptions::FAST)
            .unwrap_or_else(|e| panic!("following the advice ({m}) fails: {e}"));
        // One less is not enough.
        let h = hw("linear12", |h| h.dof.max_half_size = m - 1);
        assert!(render(&s, &h, RunOptions::FAST).is_err());
    }
    // Beyond the largest configurable half-size the advice is to narrow the lens.
    let text = include_str!("../src/scene/default.toml")
        .replace("lens_radius = 0.06 ", "lens_radius = 2.0 ");
    let s = Scene::from_toml(&igemu::files::TomlFile::from_text("lens.toml", &text)).unwrap();
    let e = render(&s, &HwConfig::default_config(), RunOptions::FAST)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("lens_radius") && e.contains("64"), "{e}");
}

#[test]
fn the_accumulate_tap_is_the_frame_before_depth_of_field() {
    let r = render(
        &Scene::default_scene(),
        &HwConfig::default_config(),
        RunOptions::FAST,
    )
    .unwrap();
    let acc = r.taps(StageId::Accumulate).unwrap().image("frame").unwrap();
    let dof = r.taps(StageId::Dof).unwrap().image("frame").unwrap();
    assert_ne!(acc, dof, "depth of field changes the frame");
    assert_eq!(
        &dof,
        &r.frame().acc,
        "the gamma LUT reads the blurred frame"
    );
    let (_, taps) = pipeline::run_through(
        &Scene::default_scene(),
        &HwConfig::default_config(),
        RunOptions::FAST,
        StageId::Accumulate,
    )
    .unwrap();
    assert_eq!(taps.fixed.frame().frame.acc, acc);
}
