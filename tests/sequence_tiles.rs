//! Tile rows reused between the frames of a sequence (`igemu::pipeline::tile_rows`, the
//! stage cache of `Cache::with_tile_rows`): a frame that keeps the tile rows whose
//! primitives did not change gives the codes, the reference and every report of a full
//! emulation, and a still sequence emulates no tile row after its first frame.

mod common;

use common::reports::same;
use igemu::config::{FilterKind, HwConfig};
use igemu::files::TomlFile;
use igemu::pipeline::{self, Cache, fast};
use igemu::scene::Scene;
use igemu::stage::RunOptions;

/// The embedded flypast's text with `edit` applied.
fn flypast_with(edit: impl Fn(String) -> String) -> Scene {
    let (_, text) = igemu::scene::EMBEDDED
        .iter()
        .find(|(n, _)| *n == "flypast")
        .expect("embedded flypast");
    Scene::from_toml(&TomlFile::from_text(
        "flypast-tiles.toml",
        &edit(text.to_string()),
    ))
    .unwrap_or_else(|e| panic!("{e}"))
}

/// A sky behind everything: the plan's region is the whole screen in every frame, so only
/// the tile rows the small objects move in change.
const SKY: &str = "[[object]]\nkind = \"quad\"\nspace = \"screen\"\nvertices = [[0.0, 0.0, 0.99], [320.0, 0.0, 0.99], [320.0, 240.0, 0.99], [0.0, 240.0, 0.99]]\nintensity = [0.05, 0.05, 0.05, 0.05]\n\n[sequence]";

fn with_sky() -> Scene {
    flypast_with(|t| t.replacen("[sequence]", SKY, 1))
}

fn banded(base: RunOptions) -> RunOptions {
    RunOptions {
        band_rows: Some(16),
        ..base
    }
}

/// Renders `frames` of `scene` on one cache that keeps tile rows, each against a whole
/// render without a cache; returns the tile rows (reused, emulated) over the frames after
/// the first.
fn renders_match(scene: &Scene, hw: &HwConfig, frames: std::ops::Range<u32>) -> (u64, u64) {
    let cache = Cache::with_tile_rows();
    let first = frames.start;
    let mut after = (0, 0);
    for f in frames {
        let fs = scene.frame(f).unwrap();
        let before = cache.tile_row_stats();
        let r = pipeline::render_with(&fs, hw, banded(RunOptions::default()), Some(&cache))
            .unwrap_or_else(|e| panic!("{e}"));
        let (h, m) = cache.tile_row_stats();
        if f > first {
            after = (after.0 + h - before.0, after.1 + m - before.1);
        }
        let whole = pipeline::render(&fs, hw, RunOptions::default()).unwrap();
        assert!(r.dac == whole.dac, "frame {f}: DAC codes");
        assert!(r.dac_ref == whole.dac_ref, "frame {f}: reference codes");
        for (a, b) in whole.steps.iter().zip(&r.steps) {
            assert_eq!(
                a.outcome.tokens, b.outcome.tokens,
                "frame {f}: {} tokens",
                a.id
            );
        }
        let (ja, jb) = (
            serde_json::to_value(&whole.report).unwrap(),
            serde_json::to_value(&r.report).unwrap(),
        );
        if let Err(e) = same(&ja, &jb, "report") {
            panic!("frame {f}: {e}");
        }
    }
    after
}

#[test]
fn frames_that_reuse_tile_rows_equal_full_renders_with_the_reference() {
    let hw = HwConfig::default_config();
    let (reused, emulated) = renders_match(&with_sky(), &hw, 0..5);
    assert!(
        reused > 0 && emulated > 0,
        "reused {reused}, emulated {emulated}"
    );
    // The small objects meet a few of the 15 tile rows.
    assert!(
        emulated * 2 < reused,
        "reused {reused}, emulated {emulated}"
    );
    // The embedded flypast: its aircraft is the region's left edge, so a frame in which it
    // crosses a pixel column changes every tile row's sample region.
    let (reused, emulated) = renders_match(&Scene::embedded("flypast").unwrap(), &hw, 2..6);
    assert!(
        reused > 0 && emulated > 0,
        "reused {reused}, emulated {emulated}"
    );
}

#[test]
fn wide_filters_read_the_rows_of_reused_tile_rows_and_stay_exact() {
    // Catmull-Rom (radius 2, negative lobes) reads two pixel rows of the tile row above;
    // the box reads none.
    // The light point moves 0.2 px a frame down the last rows of tile row 0, which the
    // filter windows of tile row 1 read.
    let scene = flypast_with(|t| {
        t.replacen("[sequence]", SKY, 1)
            .replace(
                "position = [30.0, 24.0, 0.83]",
                "position = [30.0, 14.0, 0.83]",
            )
            .replace(
                "translate = [11.47, 3.41, 0.0]",
                "translate = [0.0, 6.2, 0.0]",
            )
    });
    for filter in [FilterKind::CatmullRom, FilterKind::Tent, FilterKind::Box] {
        let hw = common::hw("linear12", |h| h.accumulate.filter = filter);
        let (reused, _) = renders_match(&scene, &hw, 0..6);
        assert!(reused > 0, "{filter:?}");
    }
}

#[test]
fn the_fixed_only_path_reuses_tile_rows_bit_exactly() {
    let scene = with_sky();
    let hw = HwConfig::default_config();
    let emulator = fast::Emulator::new();
    let cache = Cache::with_tile_rows();
    for f in 0..4 {
        let fs = scene.frame(f).unwrap();
        let e = emulator
            .emulate(&fs, &hw, banded(RunOptions::FIXED_ONLY), Some(&cache))
            .unwrap();
        let one = fast::emulate(&fs, &hw, RunOptions::FIXED_ONLY, None).unwrap();
        assert!(e.channels == one.channels, "frame {f}: codes");
        assert_eq!(
            e.report.cycles.total_cycles, one.report.cycles.total_cycles,
            "frame {f}: cycles"
        );
        emulator.recycle(e);
    }
    let (reused, emulated) = cache.tile_row_stats();
    assert!(reused > 0 && emulated >= 15, "{reused} {emulated}");
}

#[test]
fn a_still_sequence_emulates_no_tile_row_after_frame_0_and_equals_single_renders() {
    let scene = flypast_with(|t| {
        let head = &t[..t.find("[sequence]").expect("a [sequence]")];
        format!("{head}[sequence]\nframes = 3\n")
    });
    let hw = HwConfig::default_config();
    let (r, kept) = common::run_sequence(&scene, &hw, 0..3, true, true);
    assert!(r.reuse.tile_rows_off.is_none());
    assert_eq!(r.frames[0].tile_rows_emulated, u64::from(r.reuse.tile_rows));
    for f in &r.frames[1..] {
        assert_eq!(f.tile_rows_emulated, 0, "frame {}", f.frame);
        assert_eq!(f.tile_rows_reused, u64::from(r.reuse.tile_rows));
        assert_eq!(f.emulated_stages, 0, "frame {}", f.frame);
    }
    assert_eq!(r.reuse.frames_fully_reused, 2);
    let single = pipeline::render(&scene.frame(0).unwrap(), &hw, RunOptions::FAST).unwrap();
    for (k, (fixed, reference)) in kept.iter().enumerate() {
        assert!(fixed[0] == single.dac, "frame {k}");
        assert!(
            reference.as_ref().unwrap()[0] == single.dac_ref,
            "frame {k}"
        );
    }
}

#[test]
fn a_moving_sequence_reports_its_tile_rows_and_equals_the_sequence_without_reuse() {
    let scene = with_sky();
    let hw = HwConfig::default_config();
    let (a, with) = common::run_sequence(&scene, &hw, 3..8, true, true);
    let (b, without) = common::run_sequence(&scene, &hw, 3..8, true, false);
    assert!(with == without);
    for (x, y) in a.frames.iter().zip(&b.frames) {
        assert_eq!(x.cycles, y.cycles, "frame {}", x.frame);
        assert_eq!(x.identical_fraction, y.identical_fraction);
        assert_eq!(x.tile_rows_emulated + x.tile_rows_reused, 15);
        assert_eq!((y.tile_rows_emulated, y.tile_rows_reused), (0, 0));
    }
    assert!(a.reuse.tile_rows_reused > a.reuse.tile_rows_emulated);
    assert!(b.reuse.tile_rows_off.is_some());
}

#[test]
fn a_colour_sequence_reuses_tile_rows_in_every_channel() {
    let colour = Scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/flypast-colour.toml"
    ))
    .unwrap();
    let sky = flypast_with(|t| {
        t.replacen("[image]", "[image]\ncolour = true", 1)
            .replacen("[sequence]", SKY, 1)
    });
    let hw = HwConfig::default_config();
    for scene in [&colour, &sky] {
        let (a, with) = common::run_sequence(scene, &hw, 2..5, true, true);
        let (_, without) = common::run_sequence(scene, &hw, 2..5, true, false);
        assert!(with == without, "{}", scene.name);
        assert!(a.reuse.tile_rows_off.is_none());
        assert!(
            a.reuse.tile_rows_reused > 0,
            "{}: {:?}",
            scene.name,
            a.reuse
        );
    }
    let (reused, emulated) = renders_match(&sky, &hw, 0..3);
    assert!(reused > emulated, "reused {reused}, emulated {emulated}");
}

#[test]
fn a_log_coded_sequence_says_it_reuses_no_tile_row() {
    let hw = common::hw("log8-logadd", |_| {});
    let (r, _) = common::run_sequence(&with_sky(), &hw, 0..2, false, true);
    assert!(
        r.reuse
            .tile_rows_off
            .as_deref()
            .unwrap()
            .contains("one band")
    );
}

#[test]
fn a_moving_camera_reuses_no_tile_row_and_the_report_says_so() {
    // The camera pans: every primitive moves on the screen in every frame.
    let scene = flypast_with(|t| {
        t.replacen(
            "interpolation = \"linear\"\n",
            "interpolation = \"linear\"\n\n[[sequence.camera]]\nframe = 0\nlook_at = [0.0, 0.0, -1.0]\n\n[[sequence.camera]]\nframe = 31\nlook_at = [0.2, 0.05, -1.0]\n",
            1,
        )
    });
    let hw = HwConfig::default_config();
    let (r, with) = common::run_sequence(&scene, &hw, 0..4, false, true);
    let (_, without) = common::run_sequence(&scene, &hw, 0..4, false, false);
    assert!(with == without);
    assert!(r.reuse.camera_moves);
    assert_eq!(r.reuse.tile_rows_reused, 0, "{:?}", r.reuse);
    assert_eq!(r.reuse.frames_fully_reused, 0);
}
