//! Banded runs (raster, visibility and accumulate band by band of pixel rows,
//! `igemu::pipeline::bands`) give the same render as the whole-region run: DAC codes, float
//! reference, frame memory, float frame, and every report (work, signals, local errors,
//! tokens, cycle results, pack checks). Counts, codes, minima and maxima are compared bit
//! for bit; f64 sums (the mean errors and the signals' error sums) are added band by band
//! and then over the bands, so they are compared to 1e-9 relative.

mod common;

use common::reports::same;
use common::{Rng, hw, random_objects, scene};
use igemu::config::{FilterKind, HwConfig};
use igemu::files::TomlFile;
use igemu::pipeline::{self, Render, render};
use igemu::scene::Scene;
use igemu::stage::{Band, RunOptions, StageId};
use proptest::prelude::*;

fn opts(band_rows: Option<u32>) -> RunOptions {
    RunOptions {
        band_rows,
        ..RunOptions::default()
    }
}

fn assert_same(whole: &Render, banded: &Render, what: &str) {
    assert_eq!(whole.dac, banded.dac, "{what}: DAC codes");
    assert_eq!(
        whole.dac_ref, banded.dac_ref,
        "{what}: float reference DAC codes"
    );
    let (fa, fb) = (
        &whole.taps(StageId::Accumulate).unwrap().fixed.frame().frame,
        &banded
            .taps(StageId::Accumulate)
            .unwrap()
            .fixed
            .frame()
            .frame,
    );
    assert_eq!(fa, fb, "{what}: frame memory");
    let (ra, rb) = (
        whole.taps(StageId::Accumulate).unwrap().float.frame(),
        banded.taps(StageId::Accumulate).unwrap().float.frame(),
    );
    assert!(
        ra.iter().zip(rb).all(|(a, b)| a.to_bits() == b.to_bits()),
        "{what}: float frame"
    );
    assert_eq!(whole.frame(), banded.frame(), "{what}: frame before gamma");
    for (a, b) in whole.steps.iter().zip(&banded.steps) {
        assert_eq!(a.id, b.id);
        assert_eq!(a.key, b.key, "{what}: stage keys");
        assert_eq!(
            a.outcome.tokens, b.outcome.tokens,
            "{what}: {} tokens",
            a.id
        );
        assert_eq!(a.outcome.packs, b.outcome.packs, "{what}: {} packs", a.id);
    }
    let (ja, jb) = (
        serde_json::to_value(&whole.report).unwrap(),
        serde_json::to_value(&banded.report).unwrap(),
    );
    if let Err(e) = same(&ja, &jb, "report") {
        panic!("{what}: {e}");
    }
}

fn bands_of(r: &Render) -> usize {
    // A banded run keeps no whole-screen sample buffer after visibility.
    usize::from(r.taps(StageId::Visibility).unwrap().fixed.samples.is_none())
}

#[test]
fn the_embedded_scenes_render_the_same_in_bands() {
    for name in ["default", "default-pinhole", "cone-focus"] {
        let s = Scene::embedded(name).unwrap();
        let h = HwConfig::default_config();
        let whole = render(&s, &h, opts(None)).unwrap();
        assert_eq!(bands_of(&whole), 0, "a 640x480 screen runs in one band");
        for rows in [16, 48, 128] {
            let banded = render(&s, &h, opts(Some(rows))).unwrap();
            assert_eq!(bands_of(&banded), 1);
            assert_same(&whole, &banded, &format!("{name}, bands of {rows} rows"));
        }
    }
}

#[test]
fn other_filters_samples_tiles_and_the_depth_ramp_render_the_same_in_bands() {
    let ramp = Scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/depth-ramp.toml"
    ))
    .unwrap();
    let pin = Scene::embedded("default-pinhole").unwrap();
    let cases: Vec<(&Scene, HwConfig, &str)> = vec![
        (&ramp, HwConfig::default_config(), "depth ramp"),
        (
            &pin,
            hw("linear12", |h| {
                h.accumulate.filter = FilterKind::Box;
                h.raster.samples = 2;
                h.cycles.tile = 4;
            }),
            "box, 2x2, tile 4",
        ),
        (
            &pin,
            hw("linear8", |h| {
                h.accumulate.filter = FilterKind::Gaussian;
                h.raster.samples = 8;
                h.cycles.tile = 8;
            }),
            "gaussian, 8x8, linear8",
        ),
        (
            &pin,
            hw("linear12", |h| {
                h.raster.samples = 1;
                h.cycles.tile = 4;
            }),
            "one sample per pixel",
        ),
    ];
    for (s, h, what) in cases {
        let whole = render(s, &h, opts(None)).unwrap();
        for rows in [4, 8, 40] {
            let banded = render(s, &h, opts(Some(rows))).unwrap();
            assert_same(&whole, &banded, &format!("{what}, bands of {rows}"));
        }
    }
}

#[test]
fn a_colour_render_runs_every_channel_in_bands() {
    // Per-channel frame words, so a lane's words reach its own accumulate in each band.
    let s = Scene::embedded("default-colour").unwrap();
    let h = HwConfig::from_toml(&TomlFile::from_text(
        "hw.toml",
        "[accumulate]\nfilter = \"catmull_rom\"\nframe = [\"UQ12.0\", \"UQ10.0\", \"UQ11.0\"]\n",
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    let whole = render(&s, &h, opts(None)).unwrap();
    for rows in [16, 40] {
        let banded = render(&s, &h, opts(Some(rows))).unwrap();
        assert_eq!(bands_of(&banded), 1);
        assert_same(&whole, &banded, &format!("default-colour, bands of {rows}"));
        let (a, b) = (
            whole.colour.as_ref().unwrap(),
            banded.colour.as_ref().unwrap(),
        );
        for (c, (x, y)) in a.channels.iter().zip(&b.channels).enumerate() {
            assert!(x.dac == y.dac && x.dac_ref == y.dac_ref, "channel {c}");
        }
        assert!(
            whole.report.colour.is_some(),
            "the report's channels are compared"
        );
    }
}

#[test]
fn a_log_coded_plan_runs_in_one_band() {
    let s = Scene::embedded("default-pinhole").unwrap();
    let h = hw("log8-logadd", |_| {});
    let r = render(&s, &h, opts(Some(16))).unwrap();
    assert_eq!(bands_of(&r), 0);
}

#[test]
fn a_banded_plan_refuses_the_whole_screen_raster_and_visibility_taps() {
    let s = Scene::embedded("default-pinhole").unwrap();
    let h = HwConfig::default_config();
    for id in [StageId::Raster, StageId::Visibility] {
        let e = pipeline::run_through(&s, &h, opts(Some(32)), id)
            .err()
            .expect("refused")
            .to_string();
        assert!(e.contains("bands of 32 pixel rows"), "{e}");
    }
    let (_, taps) = pipeline::run_through(&s, &h, opts(Some(32)), StageId::Accumulate).unwrap();
    assert_eq!(taps.fixed.frame().frame.acc.len(), 640 * 480);
}

#[test]
fn the_bands_partition_the_screen_on_tile_rows() {
    let b = pipeline::bands::bands(32, 100);
    assert_eq!(
        b,
        vec![
            Band {
                y0: 0,
                y1: 32,
                first: true
            },
            Band {
                y0: 32,
                y1: 64,
                first: false
            },
            Band {
                y0: 64,
                y1: 96,
                first: false
            },
            Band {
                y0: 96,
                y1: 100,
                first: false
            },
        ]
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Random triangles (reaching off screen), lines and light points, random samples,
    /// filters and tile sizes, bands of one tile up to the screen: the same render.
    #[test]
    fn random_scenes_render_the_same_in_bands(seed in any::<u64>(), n_log in 0u32..4, filter in 0usize..3, tile_log in 2u32..5, rows in 1u32..40) {
        let mut rng = Rng::new(seed);
        let objects = random_objects(&mut rng, 1);
        let s = scene(40, 30, rng.range(0.0, 1.0), &objects);
        let h = hw("linear12", |h| {
            h.raster.samples = 1 << n_log;
            h.accumulate.filter = [FilterKind::Box, FilterKind::Tent, FilterKind::Gaussian][filter];
            h.cycles.tile = 1 << tile_log;
        });
        let whole = render(&s, &h, opts(None)).unwrap();
        let banded = render(&s, &h, opts(Some(rows))).unwrap();
        assert_same(&whole, &banded, &format!("seed {seed}, bands of {rows}"));
    }
}

/// The banded contour metric against its whole-image reference.
fn contours_agree(
    dac: &[u16],
    dac_ref: &[u16],
    powers: Vec<f64>,
    d: &DisplayModel,
    w: u32,
    h: u32,
) {
    let whole = WholeIdeal::new(&powers, d, w, h);
    let a = perceptual::contours_whole(dac, dac_ref, &whole, d);
    let ideal = IdealImage::new(std::sync::Arc::new(powers), d, w, h);
    let b = perceptual::contours_banded(dac, dac_ref, &ideal, d);
    assert_eq!(a.report, b.report);
    assert!(a.map == b.map, "contour maps differ");
    let c = perceptual::contours(dac, dac_ref, &ideal, d);
    assert_eq!(a.report, c.report);
}

use igemu::compare::DisplayModel;
use igemu::perceptual::{self, IdealImage, WholeIdeal};

#[test]
fn the_banded_contour_metric_equals_the_whole_image_one() {
    for (name, bits) in [("default", 6), ("default-pinhole", 8), ("cone-focus", 10)] {
        let s = Scene::embedded(name).unwrap();
        let h = hw("linear12", |h| h.gamma.dac_bits = bits);
        let r = render(&s, &h, RunOptions::FAST).unwrap();
        let spec = igemu::pipeline::report::gamma_spec(&s, &h);
        let powers = igemu::stage::gamma::powers(r.frame_ref(), &h, &spec);
        let d = DisplayModel::new(&s.display, bits);
        contours_agree(&r.dac, &r.dac_ref, powers, &d, 640, 480);
        assert!(r.report.contours.smooth_steps > 0);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Random smooth ramps with noise and steps, on images of 1 to 150 rows (one to three
    /// bands of the metric): the same steps, excesses and map.
    #[test]
    fn random_images_have_the_same_contours_banded(seed in any::<u64>(), w in 1u32..90, h in 1u32..150, bits in 4u32..9) {
        let mut rng = Rng::new(seed);
        let (gx, gy) = (rng.range(-0.01, 0.01), rng.range(-0.01, 0.01));
        let noise = rng.range(0.0, 0.02);
        let max = ((1u32 << bits) - 1) as f64;
        let mut powers = Vec::new();
        let (mut dac, mut dac_ref) = (Vec::new(), Vec::new());
        for y in 0..h {
            for x in 0..w {
                let v = (0.5 + gx * x as f64 + gy * y as f64 + noise * rng.range(-1.0, 1.0)).clamp(0.0, 1.0);
                powers.push(v);
                dac.push((v * max).floor() as u16);
                dac_ref.push((v * max).round() as u16);
            }
        }
        let s = Scene::default_scene();
        let d = DisplayModel::new(&s.display, bits);
        contours_agree(&dac, &dac_ref, powers, &d, w, h);
    }
}
