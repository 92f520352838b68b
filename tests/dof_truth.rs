//! The depth-of-field truth (src/truth, docs/dof-truth.md): the shear geometry of a lens
//! point, the pinhole limit, the noise estimate, the three-way split of the errors,
//! determinism, the `render --dof-truth` report and flags, and the sweep's truth axis.

mod common;

use common::igemu;
use igemu::config::HwConfig;
use igemu::pipeline;
use igemu::scene::{GuardBand, Lens, LensPoint, Primitive, Scene, front_end, front_end_through};
use igemu::stage::{RunOptions, StageId};
use igemu::truth::{self, Images, TruthFrame, TruthSetup};

/// The default scene at 160x120 (its objects are in world space; the blur scales with H).
fn small_default() -> Scene {
    let mut s = Scene::default_scene();
    s.image.width = 160;
    s.image.height = 120;
    s
}

fn hw() -> HwConfig {
    HwConfig::preset("linear12").expect("preset")
}

fn truth_of(scene: &Scene, n: u32) -> TruthFrame {
    TruthSetup::new(scene, n).expect("thin lens").run()
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

/// World-space light points at several depths on a camera at z = 10 looking at the origin.
fn points_scene(depths: &[f64]) -> Scene {
    let objects: String = depths
        .iter()
        .enumerate()
        .map(|(k, d)| {
            let x = -1.0 + 0.5 * k as f64;
            format!(
                "[[object]]\nkind = \"light_point\"\nspace = \"world\"\nposition = [{x}, 0.3, {}]\nintensity = 1.0\nsize = 1.0\n\n",
                10.0 - d
            )
        })
        .collect();
    common::scene(320, 240, 0.0, &objects)
}

fn point_centres(prims: &[Primitive]) -> Vec<(f64, f64)> {
    prims
        .iter()
        .map(|p| match p {
            Primitive::Point { v, .. } => (v.x, v.y),
            other => panic!("not a point: {other:?}"),
        })
        .collect()
}

#[test]
fn a_lens_point_shears_a_point_at_depth_d_by_f_px_a_b_times_1_over_u_minus_1_over_d() {
    let depths = [3.0, 6.0, 10.0, 25.0, 60.0];
    let scene = points_scene(&depths);
    let guard = GuardBand::around(320, 240, 4096.0);
    let pin = point_centres(&front_end(&scene, &guard).prims);
    assert_eq!(pin.len(), depths.len());
    let f_px = 240.0 * 0.5 / (20.0f64.to_radians()).tan();
    let u = 10.0;
    for (a, b, jitter) in [
        (0.05, 0.0, (0.0, 0.0)),
        (0.0, 0.05, (0.0, 0.0)),
        (-0.03, 0.02, (0.0, 0.0)),
        (0.2, -0.1, (0.0, 0.0)),
        (0.05, -0.02, (0.1, -0.0625)),
    ] {
        let lens = LensPoint {
            a,
            b,
            focus: u,
            jitter,
        };
        let moved = point_centres(&front_end_through(&scene, &guard, Some(lens)).prims);
        for ((p, m), d) in pin.iter().zip(&moved).zip(depths) {
            let k = f_px * (1.0 / u - 1.0 / d);
            // The jitter moves every point by the same sub-pixel offset.
            let (dx, dy) = (m.0 - p.0 - jitter.0, m.1 - p.1 - jitter.1);
            assert!(
                (dx - k * a).abs() < 1e-9,
                "a {a} b {b} D {d}: dx {dx} want {}",
                k * a
            );
            assert!(
                (dy + k * b).abs() < 1e-9,
                "a {a} b {b} D {d}: dy {dy} want {}",
                -k * b
            );
            if d == u {
                assert!(dx.abs() < 1e-9 && dy.abs() < 1e-9, "the focus plane moved");
            } else {
                assert!(dx.hypot(dy) > 1e-3, "D {d} did not move");
            }
        }
    }
    // `None` is exactly the pinhole.
    assert_eq!(
        front_end_through(&scene, &guard, None).prims,
        front_end(&scene, &guard).prims
    );
}

#[test]
fn with_a_tiny_aperture_the_truth_is_the_pinhole_float_frame() {
    let mut scene = small_default();
    let Lens::ThinLens {
        ref mut lens_radius,
        ..
    } = scene.camera.lens
    else {
        panic!("the default scene has a thin lens")
    };
    *lens_radius = 1e-9;
    let t = truth_of(&scene, 64);
    // The truth's own sampling (4x4 grid, box filter) through the pipeline, pinhole camera.
    let h = truth::truth_hw();
    let mut pinhole = scene.clone();
    pinhole.camera.lens = Lens::Pinhole;
    let r = pipeline::render(&pinhole, &h, RunOptions::FAST).expect("render");
    let float = r
        .taps(StageId::Accumulate)
        .and_then(|t| t.float.frame.clone())
        .expect("the float frame after accumulate");
    assert_eq!(float.len(), t.mean.len());
    let white = truth::frame_white(&h);
    let peak = t.mean.iter().fold(0.0f64, |m, &v| m.max(v));
    assert!(peak > 0.25, "a lit scene: {peak}");
    // The jitter moves the grid over the pixel: away from silhouettes (no spread between
    // the groups) the area average differs from the grid's average only by the grid's own
    // error on curved shading (the specular highlight: 0.0021 of white measured); at a
    // silhouette it is the exact covered area, within one sample's share (1/16) of the
    // grid's count.
    let (mut flat, mut worst_flat, mut worst_edge) = (0, 0.0f64, 0.0f64);
    for ((m, f), se) in t.mean.iter().zip(float.iter()).zip(&t.se) {
        let d = (m - f / white).abs();
        if *se < 1e-4 {
            flat += 1;
            worst_flat = worst_flat.max(d);
        } else {
            worst_edge = worst_edge.max(d);
        }
    }
    assert!(flat > 160 * 120 / 2, "{flat}");
    assert!(
        worst_flat < 4e-3,
        "largest difference off silhouettes {worst_flat}"
    );
    assert!(
        worst_edge < 1.0 / 16.0 + 4e-3,
        "largest difference at a silhouette {worst_edge}"
    );
}

#[test]
fn the_standard_error_falls_at_least_as_1_over_sqrt_n_and_predicts_the_actual_error() {
    let scene = small_default();
    let t16 = truth_of(&scene, 16);
    let t64 = truth_of(&scene, 64);
    let t512 = truth_of(&scene, 512);
    let (s16, s64, s512) = (rms(&t16.se), rms(&t64.se), rms(&t512.se));
    assert!(s64 > 0.0 && s512 > 0.0, "a blurred scene has lens noise");
    // 1/sqrt(N) would give a ratio of 2 from N = 16 to 64; the stratified groups do better.
    assert!(s16 / s64 > 1.7, "se 16: {s16}, se 64: {s64}");
    assert!(
        s64 / s512 > 1.7 * 2f64.sqrt(),
        "se 64: {s64}, se 512: {s512}"
    );
    // The estimate is honest: the actual RMS distance from the N = 512 truth (much less
    // noisy) is of the size the estimate claims.
    for (t, s) in [(&t16, s16), (&t64, s64)] {
        let d: Vec<f64> = t.mean.iter().zip(&t512.mean).map(|(a, b)| a - b).collect();
        let actual = rms(&d);
        assert!(
            actual > s / 3.0 && actual < 3.0 * s,
            "N {}: actual RMS error {actual}, estimated {s}",
            t.lens_samples
        );
    }
}

#[test]
fn the_split_is_consistent_total_is_algorithm_plus_quantisation() {
    let scene = small_default();
    let h = hw();
    let t = truth_of(&scene, 16);
    let r = pipeline::render(&scene, &h, RunOptions::FAST).expect("render");
    let frame = &r.taps(StageId::Accumulate).unwrap().fixed.frame().frame;
    // Identical fixed and float images: no quantisation error, total == algorithm.
    let same = truth::assess(
        &scene,
        &h,
        &t,
        false,
        &Images {
            fixed: &r.dac_ref,
            float: &r.dac_ref,
            frame,
        },
    );
    for (q, (tot, alg)) in [
        (
            &same.quantisation.whole,
            (&same.total.whole, &same.algorithm.whole),
        ),
        (
            &same.quantisation.edge,
            (&same.total.edge, &same.algorithm.edge),
        ),
        (
            &same.quantisation.interior,
            (&same.total.interior, &same.algorithm.interior),
        ),
    ] {
        assert_eq!(q.max_abs, 0);
        assert_eq!(q.mean_abs, 0.0);
        assert_eq!(q.identical_fraction, 1.0);
        assert_eq!(tot, alg);
    }
    assert!(
        same.algorithm.whole.mean_abs > 0.0,
        "the method differs from the truth"
    );
    // The real images: the signed means add up exactly, the regions partition the image.
    let rep = truth::assess(
        &scene,
        &h,
        &t,
        false,
        &Images {
            fixed: &r.dac,
            float: &r.dac_ref,
            frame,
        },
    );
    for (tot, alg, q) in [
        (
            &rep.total.whole,
            &rep.algorithm.whole,
            &rep.quantisation.whole,
        ),
        (&rep.total.edge, &rep.algorithm.edge, &rep.quantisation.edge),
        (
            &rep.total.interior,
            &rep.algorithm.interior,
            &rep.quantisation.interior,
        ),
    ] {
        assert!(
            (tot.mean_signed - alg.mean_signed - q.mean_signed).abs() < 1e-9,
            "{tot:?} {alg:?} {q:?}"
        );
        assert!(tot.mean_abs <= alg.mean_abs + q.mean_abs + 1e-12);
    }
    assert!(rep.edge_pixels > 0 && rep.edge_pixels < 160 * 120);
    assert_eq!(rep.total.edge.pixels, rep.edge_pixels);
    assert_eq!(
        rep.total.edge.pixels + rep.total.interior.pixels,
        rep.total.whole.pixels
    );
    assert!(
        rep.quantisation.whole.mean_abs > 0.0,
        "linear12 is not exact"
    );
    // The depth-edge band is the DoF stage's (the same for every method): the errors
    // concentrate there.
    assert!(rep.algorithm.edge.mean_abs > 5.0 * rep.algorithm.interior.mean_abs);
}

#[test]
fn the_truth_is_bit_identical_on_one_and_two_threads() {
    let scene = small_default();
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| truth_of(&scene, 24))
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.mean, b.mean);
    assert_eq!(a.se, b.se);
    assert_eq!(a.lens_samples, 24);
}

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("igemu-dof-truth-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn render_dof_truth_json_reports_the_split_and_the_noise() {
    let d = tmp("json");
    let out = d.join("o.png").to_string_lossy().into_owned();
    let (code, stdout, stderr) = igemu(&[
        "render",
        "default",
        "--dof-truth",
        "--lens-samples",
        "16",
        "--json",
        "-o",
        &out,
    ]);
    assert_eq!(code, 0, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let t = &v["dof_truth"];
    assert_eq!(t["lens_samples"], 16);
    assert!(t["ms"].as_f64().unwrap() > 0.0);
    assert!(t["edge_band_px"].as_u64().unwrap() > 0);
    for part in ["total", "algorithm", "quantisation"] {
        for region in ["whole", "edge", "interior"] {
            let x = &t[part][region];
            for field in ["mean_abs", "rms", "mean_signed", "weber_mean", "weber_max"] {
                assert!(x[field].as_f64().is_some(), "{part}.{region}.{field}: {x}");
            }
            assert!(x["max_abs"].as_u64().is_some());
        }
    }
    for unit in ["frame_lsb", "dac"] {
        for region in ["whole", "edge", "interior"] {
            assert!(t["noise"][unit][region]["rms"].as_f64().unwrap() > 0.0);
        }
    }
    assert_eq!(t["noise"]["groups"], truth::GROUPS);
    // The text report has the block; without the flag there is no `dof_truth`.
    let (code, stdout, _) = igemu(&[
        "render",
        "default",
        "--dof-truth",
        "--lens-samples",
        "8",
        "-o",
        &out,
    ]);
    assert_eq!(code, 0);
    assert!(
        stdout.contains("depth-of-field truth: 8 lens points"),
        "{stdout}"
    );
    assert!(stdout.contains("algorithm (float)"));
    let (_, stdout, _) = igemu(&["render", "default", "--json", "--no-local", "-o", &out]);
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert!(v.get("dof_truth").is_none());
    // A pinhole gets a plan note, not an error.
    let (code, stdout, stderr) = igemu(&[
        "render",
        "default-pinhole",
        "--dof-truth",
        "--lens-samples",
        "8",
        "--json",
        "-o",
        &out,
    ]);
    assert_eq!(code, 0, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert!(v.get("dof_truth").is_none());
    let notes = v["plan"]["notes"].to_string();
    assert!(notes.contains("--dof-truth has no effect"), "{notes}");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_bad_lens_sample_count_exits_2_naming_the_flag_and_the_range() {
    let d = tmp("bad");
    let out = d.join("o.png").to_string_lossy().into_owned();
    for n in ["0", "7", "12", "4104", "-8", "many"] {
        let flag = format!("--lens-samples={n}");
        let (code, _, stderr) = igemu(&["render", "default", "--dof-truth", &flag, "-o", &out]);
        assert_eq!(code, 2, "{n}: {stderr}");
        assert!(stderr.contains("--lens-samples"), "{n}: {stderr}");
        assert!(stderr.contains("8..=4096"), "{n}: {stderr}");
    }
    // --lens-samples alone asks for nothing: refused.
    let (code, _, stderr) = igemu(&["render", "default", "--lens-samples", "16", "-o", &out]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("--dof-truth"), "{stderr}");
    assert!(!std::path::Path::new(&out).exists(), "nothing written");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_sweep_row_carries_the_truth_errors_and_the_truth_is_computed_once_per_scene() {
    use igemu::files::TomlFile;
    use igemu::sweep::{self, grid, pareto::Axis};
    let d = tmp("sweep");
    let scene = small_default();
    // The truth's sampling does not depend on the hardware: one truth for every filter and
    // sample count.
    let text = "accumulate.filter = [\"box\", \"tent\"]\nraster.samples = [2, 4]\n";
    let f = TomlFile::from_text("g.toml", text);
    let configs = grid::Grid::parse(&f).unwrap().expand(&f).unwrap();
    let cache = pipeline::Cache::new();
    let mut runs = Vec::new();
    for (name, c) in [("cached", Some(&cache)), ("full", None)] {
        let out = d
            .join(format!("{name}.jsonl"))
            .to_string_lossy()
            .into_owned();
        let opts = common::serial_sweep(&out, c, Some(16));
        let s = sweep::run(&configs, std::slice::from_ref(&scene), &opts, &|_, _| {}).unwrap();
        runs.push(s.rows);
    }
    let rows = &runs[0];
    assert_eq!(rows.len(), 4);
    for (i, r) in rows.iter().enumerate() {
        let t = r.truth.as_ref().expect("every row has the truth");
        assert_eq!(t.lens_samples, 16);
        assert!(t.noise_dac_rms > 0.0);
        assert!(t.algorithm.whole.mean_code_diff > 0.0);
        assert!(Axis::TruthTotal.key(r).is_finite());
        assert_eq!(Axis::TruthAlgorithm.key(r), t.algorithm.whole.weber_mean);
        // The truth frame is computed by the first row and reused by the others.
        let reused = r.reused.iter().any(|s| s == sweep::TRUTH_REUSED);
        assert_eq!(reused, i > 0, "row {i}: {:?}", r.reused);
    }
    // Without the cache every row computes it: the same rows.
    assert!(runs[1].iter().all(|r| r.reused.is_empty()));
    let strip = |rs: &[sweep::Row]| rs.iter().map(sweep::without_timing).collect::<Vec<_>>();
    assert_eq!(strip(&runs[0]), strip(&runs[1]));
    // The lens-sample count is part of the row id.
    let plain = sweep::row_id(&scene, &configs[0].hw);
    assert_ne!(rows[0].id, plain);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn truth_out_writes_the_truths_dac_codes_and_is_refused_without_a_truth() {
    let d = tmp("out");
    let (out, truth_png) = (d.join("o.png"), d.join("truth.png"));
    let (out, truth_png) = (out.to_str().unwrap(), truth_png.to_str().unwrap());
    let args = ["render", "default", "--dof-truth", "--lens-samples", "8"];
    let (code, _, stderr) = igemu(&[&args[..], &["-o", out, "--truth-out", truth_png]].concat());
    assert_eq!(code, 0, "{stderr}");
    let opts = RunOptions {
        dof_truth_samples: 8,
        ..RunOptions::FAST
    };
    let r = pipeline::render(&Scene::default_scene(), &hw(), opts).unwrap();
    let want = r.truth_dac.expect("a thin lens has a truth");
    let got = image::open(truth_png).unwrap().into_luma8().into_raw();
    assert_eq!(got.len(), want.len());
    assert!(got.iter().zip(&want).all(|(&g, &w)| u16::from(g) == w));
    // The truth is not the fixed image (the method differs from the lens).
    assert_ne!(want, r.dac);
    // Without --dof-truth, or on a pinhole scene: exit 2, nothing written.
    std::fs::remove_file(truth_png).unwrap();
    let (code, _, stderr) = igemu(&["render", "default", "-o", out, "--truth-out", truth_png]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("--dof-truth"), "{stderr}");
    let pinhole = [
        "render",
        "default-pinhole",
        "--dof-truth",
        "--lens-samples",
        "8",
    ];
    let (code, _, stderr) = igemu(&[&pinhole[..], &["-o", out, "--truth-out", truth_png]].concat());
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("--truth-out") && stderr.contains("pinhole"),
        "{stderr}"
    );
    assert!(!std::path::Path::new(truth_png).exists());
    std::fs::remove_dir_all(&d).ok();
}
