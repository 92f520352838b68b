//! The visibility stage (per-sample z-buffer):
//!
//! * the z-buffer conversion rounds with `visibility.z`'s mode (against the `fixed`
//!   crate's rounding, exhaustively over a 12-bit depth) and counts clamps at the top code,
//!   in the unit and through the pipeline (`visibility.z` overflows);
//! * the sample buffer equals an independent z-buffer over the raster's fixed fragments
//!   (strict `<`: on equal depth the first primitive stays; light points are tested against
//!   the finished surface buffer and never write), over random scenes, formats and modes;
//! * named cases: equal depth keeps the first, one LSB nearer wins, a light point hidden by a
//!   surface that comes after it in the scene;
//! * the stage-local comparison (a float z-buffer fed the fixed fragments) reports no
//!   mismatched items without depth ties, and does report the ties the conversion creates;
//! * the sample buffer's memory image packs and verifies, holding the tap's words;
//! * with a log coding the sample buffer's cost moves to the logdomain stage, at the log
//!   code's width: the linear bits minus the saved bits.

mod common;

use common::{Rng, hw, point, round_with, scene, steps_through, tri};
use fixed::types::I64F64;
use igemu::config::HwConfig;
use igemu::fixed::{QFormat, Quant};
use igemu::pipeline::{Step, render};
use igemu::scene::Scene;
use igemu::stage::input::QPrim;
use igemu::stage::visibility::z_convert;
use igemu::stage::{MemKind, RunOptions, StageId};
use proptest::prelude::*;

/// The stage's z conversion by the `fixed` crate: `z / 2^shift` rounded with `q`.
fn convert(z: u32, shift: u32, q: Quant) -> i64 {
    round_with(I64F64::from_bits((z as i128) << (64 - shift)), q)
}

/// Bits of a primitive id: ids 0 (background) ..= `prims`.
fn id_width(prims: usize) -> u32 {
    let mut b = 1;
    while (1usize << b) < prims + 1 {
        b += 1;
    }
    b
}

fn visibility_step(s: &Scene, h: &HwConfig, opts: RunOptions) -> Step {
    steps_through(s, h, opts, StageId::Visibility)
        .pop()
        .unwrap()
}

#[test]
fn z_conversion_rounds_with_the_configured_mode_and_counts_clamps() {
    for vis_frac in [4, 8, 11, 12] {
        for q in Quant::ALL {
            let h = hw("linear12", |h| {
                h.input.z.format = QFormat::new(false, 0, 12);
                h.visibility.z.format = QFormat::new(false, 0, vis_frac);
                h.visibility.z.quant = q;
            });
            let zc = z_convert(&h);
            let (shift, max) = (12 - vis_frac, (1i64 << vis_frac) - 1);
            let (mut clamped, mut want_clamped) = (0u64, 0u64);
            for z in 0..4096u32 {
                let want = convert(z, shift, q);
                want_clamped += (want > max) as u64;
                assert_eq!(
                    zc.apply(z, &mut clamped) as i64,
                    want.min(max),
                    "{z} to UQ0.{vis_frac} {q}"
                );
            }
            assert_eq!(clamped, want_clamped, "UQ0.{vis_frac} {q}");
            // Only rounding up past the top code clamps: never truncation or shift 0, always
            // RND (even on the tie of shift 1).
            if shift == 0 || matches!(q, Quant::Trn | Quant::TrnZero) {
                assert_eq!(clamped, 0, "UQ0.{vis_frac} {q}");
            }
            if shift > 0 && q == Quant::Rnd {
                assert!(clamped > 0, "UQ0.{vis_frac} {q}");
            }
        }
    }
    // Through the pipeline: a surface at z = 1 (the input's top code) rounds past the top
    // of a 16-bit z-buffer with RND, and every one of its depth tests clamps.
    let far = tri(
        [[1.0, 1.0, 1.0], [30.0, 2.0, 1.0], [4.0, 28.0, 1.0]],
        [0.5; 3],
    );
    let near = tri(
        [[1.0, 1.0, 0.5], [30.0, 2.0, 0.5], [4.0, 28.0, 0.5]],
        [0.5; 3],
    );
    for (q, objects, clamps) in [
        (Quant::Rnd, far.clone(), true),
        (Quant::Trn, far, false),
        (Quant::Rnd, near, false),
    ] {
        let h = hw("linear12", |h| {
            h.visibility.z.format = QFormat::new(false, 0, 16);
            h.visibility.z.quant = q;
        });
        let step = visibility_step(&scene(32, 32, 0.0, &objects), &h, RunOptions::FAST);
        let r = &step.outcome.report;
        let st = r.signals.iter().find(|s| s.name == "visibility.z").unwrap();
        let tests = r.work["tests"];
        assert!(tests > 1000);
        assert_eq!(st.overflows, if clamps { tests } else { 0 }, "{q}");
        let s = &step.outcome.taps.fixed.samples().samples;
        let zs: Vec<u32> =
            s.z.iter()
                .zip(s.prim.iter())
                .filter(|(_, p)| **p == 1)
                .map(|(z, _)| *z)
                .collect();
        assert_eq!(zs.len() as u64, tests);
        let top = if clamps || q == Quant::Trn {
            65535
        } else {
            32768
        };
        assert!(zs.iter().all(|&z| z == top), "{q}: {:?}", &zs[..4]);
    }
}

/// Checks the sample buffer of a run through visibility against an independent z-buffer.
fn check_buffer(s: &Scene, h: &HwConfig) -> Result<(u64, u64), TestCaseError> {
    let step = visibility_step(s, h, RunOptions::FAST);
    let taps = &step.outcome.taps;
    let (prims, frags) = (taps.fixed.prims(), taps.fixed.frags());
    let tap = taps.fixed.samples();
    let shift = h.input.z.format.frac_bits - h.visibility.z.format.frac_bits;
    let max = h.visibility.z.format.max_code();
    let conv = |z: u32| convert(z, shift, h.visibility.z.quant).min(max) as u32;
    let n = tap.samples.z.len();
    let (mut z, mut id, mut int) = (vec![u32::MAX; n], vec![0u32; n], vec![prims.bg[0]; n]);
    let (mut ties, mut wins) = (0, 0);
    for (p, q) in prims.q.iter().enumerate() {
        if matches!(q, QPrim::Point { .. }) {
            continue;
        }
        for f in frags.of(p) {
            let (s, zf) = (f.s as usize, conv(f.z));
            ties += (zf == z[s]) as u64;
            if zf < z[s] {
                (z[s], id[s], int[s]) = (zf, p as u32 + 1, f.i[0]);
                wins += 1;
            }
        }
    }
    prop_assert!(*tap.samples.z == z, "depths");
    prop_assert!(*tap.samples.prim == id, "ids");
    prop_assert!(tap.samples.i == int, "intensities");
    let points: Vec<(u32, Vec<u32>)> = prims
        .q
        .iter()
        .enumerate()
        .filter_map(|(p, q)| match q {
            QPrim::Point { v, .. } => {
                let vis = frags
                    .of(p)
                    .filter(|f| conv(f.z) < z[f.s as usize])
                    .map(|f| f.s)
                    .collect();
                Some((v.i[0] as u32, vis))
            }
            _ => None,
        })
        .collect();
    let got: Vec<(u32, Vec<u32>)> = tap
        .points
        .iter()
        .map(|p| (p.i, p.samples.clone()))
        .collect();
    prop_assert_eq!(got, points);
    prop_assert_eq!(step.outcome.report.work["writes"], wins);
    Ok((ties, wins))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// The sample buffer is the strict-`<` z-buffer of the fragments in scene order, light
    /// points tested against the finished buffer; with coplanar copies (ties) mixed in.
    #[test]
    fn the_sample_buffer_is_an_independent_z_buffer(seed in any::<u64>(), vis_frac in 8u32..25, q in 0usize..7, n_log in 0u32..4) {
        let mut rng = Rng::new(seed);
        let mut objects = String::new();
        let mut last = None;
        for _ in 0..2 + rng.next_u64() % 8 {
            if let (Some(t), 0) = (&last, rng.next_u64() % 3) {
                // A coplanar copy of the previous triangle with another intensity.
                objects += &tri(*t, [0.1, 0.2, 0.3]);
                continue;
            }
            let mut v = || [rng.range(-8.0, 40.0), rng.range(-8.0, 32.0), rng.range(0.0, 1.0)];
            let t = [v(), v(), v()];
            objects += &tri(t, [rng.range(0.0, 1.0), 0.5, 0.9]);
            last = Some(t);
        }
        for _ in 0..rng.next_u64() % 4 {
            objects += &point(rng.range(0.0, 32.0), rng.range(0.0, 24.0), rng.range(0.0, 1.0), 0.7, rng.range(0.2, 3.0));
        }
        let h = hw("linear12", |h| {
            h.visibility.z.format = QFormat::new(false, 0, vis_frac);
            h.visibility.z.quant = Quant::ALL[q];
            h.raster.samples = 1 << n_log;
        });
        check_buffer(&scene(32, 24, 0.2, &objects), &h)?;
    }
}

#[test]
fn equal_depth_keeps_the_first_and_one_lsb_nearer_wins() {
    let shape = [[2.0, 2.0, 0.0], [28.0, 3.0, 0.0], [5.0, 27.0, 0.0]];
    let at = |z: f64, i: f64| tri(shape.map(|v| [v[0], v[1], z]), [i; 3]);
    let lsb = 1.0 / (1u64 << 24) as f64;
    let h = HwConfig::default_config(); // input z and z-buffer UQ0.24: one code per input LSB
    for (objects, winner) in [
        (at(0.5, 0.8) + &at(0.5, 0.2), 1),
        (at(0.5, 0.8) + &at(0.5, 0.2) + &at(0.5 - lsb, 0.4), 3),
        (at(0.5, 0.8) + &at(0.5 + lsb, 0.2), 1),
        (at(0.5 + lsb, 0.8) + &at(0.5, 0.2), 2),
    ] {
        let step = visibility_step(&scene(32, 32, 0.0, &objects), &h, RunOptions::FAST);
        let s = &step.outcome.taps.fixed.samples().samples;
        let covered: Vec<u32> = s.prim.iter().copied().filter(|&p| p != 0).collect();
        assert!(covered.len() > 1000);
        assert!(covered.iter().all(|&p| p == winner), "winner {winner}");
        check_buffer(&scene(32, 32, 0.0, &objects), &h).unwrap();
    }
}

#[test]
fn light_points_are_tested_against_the_finished_buffer_and_never_write() {
    // Point A in front of a surface, point B behind a surface that comes after it in the
    // scene, point C on the background; the points come first in the scene.
    let surfaces = tri(
        [[0.0, 0.0, 0.5], [31.0, 0.0, 0.5], [0.0, 31.0, 0.5]],
        [0.4; 3],
    ) + &tri(
        [[20.0, 20.0, 0.2], [31.0, 20.0, 0.2], [20.0, 31.0, 0.2]],
        [0.6; 3],
    );
    let points = point(6.0, 6.0, 0.3, 0.9, 2.0)
        + &point(23.0, 23.0, 0.6, 0.9, 2.0)
        + &point(29.0, 29.0, 0.9, 0.9, 2.0);
    let h = HwConfig::default_config();
    let with = visibility_step(
        &scene(32, 32, 0.0, &(points + &surfaces)),
        &h,
        RunOptions::FAST,
    );
    let without = visibility_step(&scene(32, 32, 0.0, &surfaces), &h, RunOptions::FAST);
    let (a, b) = (
        with.outcome.taps.fixed.samples(),
        without.outcome.taps.fixed.samples(),
    );
    // The points write nothing: the buffer is the surfaces' alone (ids shifted by 3).
    assert_eq!(a.samples.z, b.samples.z);
    assert_eq!(a.samples.i, b.samples.i);
    let shifted: Vec<u32> = b
        .samples
        .prim
        .iter()
        .map(|&p| if p == 0 { 0 } else { p + 3 })
        .collect();
    assert_eq!(*a.samples.prim, shifted);
    let frags = with.outcome.taps.fixed.frags();
    let counts: Vec<usize> = a.points.iter().map(|p| p.samples.len()).collect();
    let all: Vec<usize> = (0..3).map(|p| frags.count(p)).collect();
    assert!(all.iter().all(|&n| n > 0));
    assert_eq!(
        counts,
        [all[0], 0, all[2]],
        "A in front, B hidden, C on the background"
    );
    let w = &with.outcome.report.work;
    assert_eq!(w["point_tests"], all.iter().sum::<usize>() as u64);
    assert_eq!(w["point_visible"], (all[0] + all[2]) as u64);
    assert_eq!(w["writes"], without.outcome.report.work["writes"]);
}

#[test]
fn local_comparison_has_no_mismatch_without_depth_ties() {
    let mut rng = Rng::new(4242);
    let h = HwConfig::default_config();
    for round in 0..12 {
        // Overlapping triangles, each sloped within its own depth band: no two primitives
        // meet at one depth, so fixed and float must pick the same primitive everywhere.
        let mut objects = String::new();
        let count = 2 + round % 6;
        for k in 0..count {
            let band = 0.1 * (count - k) as f64;
            let mut v = || {
                [
                    rng.range(-6.0, 38.0),
                    rng.range(-6.0, 30.0),
                    band + rng.range(0.0, 0.05),
                ]
            };
            objects += &tri([v(), v(), v()], [0.5; 3]);
        }
        let step = visibility_step(&scene(32, 24, 0.0, &objects), &h, RunOptions::default());
        let local = step
            .outcome
            .report
            .local
            .clone()
            .expect("visibility compares locally");
        let samples = step.outcome.taps.fixed.samples().samples.z.len() as u64;
        assert_eq!(
            (local.values, local.identical),
            (samples, samples),
            "round {round}"
        );
        assert_eq!(local.mismatched_items, 0, "round {round}");
    }
    // A tie made by the conversion: distinct input depths, one 16-bit z-buffer code. The
    // fixed buffer keeps the first, the float one takes the nearer second: mismatches.
    let shape = [[2.0, 2.0, 0.0], [28.0, 3.0, 0.0], [5.0, 27.0, 0.0]];
    let at = |z: f64| tri(shape.map(|v| [v[0], v[1], z]), [0.5; 3]);
    let h16 = hw("linear12", |h| {
        h.visibility.z.format = QFormat::new(false, 0, 16)
    });
    let objects = at(0.5 + 1.0 / (1u64 << 20) as f64) + &at(0.5);
    let step = visibility_step(&scene(32, 32, 0.0, &objects), &h16, RunOptions::default());
    let local = step.outcome.report.local.clone().unwrap();
    let covered = step
        .outcome
        .taps
        .fixed
        .samples()
        .samples
        .prim
        .iter()
        .filter(|&&p| p == 1)
        .count();
    assert!(covered > 1000);
    assert_eq!(local.mismatched_items, covered as u64);
}

/// Two triangles inside a 48x40 screen, clear of its edges by more than the filter's apron
/// (see `sample_buffer_pack_verifies_when_the_region_reaches_the_screen_edge`).
fn inner_scene(background: f64) -> Scene {
    let objects = tri(
        [[6.0, 6.0, 0.3], [40.0, 7.0, 0.7], [9.0, 30.0, 0.5]],
        [0.2, 0.9, 0.5],
    ) + &tri(
        [[15.0, 10.0, 0.4], [38.0, 32.0, 0.4], [8.0, 33.0, 0.4]],
        [0.7; 3],
    );
    scene(48, 40, background, &objects)
}

#[test]
fn the_sample_buffer_image_packs_and_verifies() {
    let h = hw("linear12", |h| {
        h.visibility.z.format = QFormat::new(false, 0, 16)
    });
    let step = visibility_step(&inner_scene(0.25), &h, RunOptions::FAST);
    let o = &step.outcome;
    let tap = o.taps.fixed.samples();
    let words = tap.samples.z.len();
    assert_eq!(o.packs.len(), 1);
    let p = &o.packs[0];
    assert_eq!(p.name, "sample buffer");
    assert!(p.verified, "{p:?}");
    assert_eq!(p.fields, [16, 16, id_width(2)]);
    let bits = words as u64 * 34;
    assert_eq!((p.words, p.bits, p.cost_bits), (words as u64, bits, bits));
    let mem = &o.report.cost.memories[0];
    assert_eq!(
        (mem.name.as_str(), mem.kind, mem.width),
        ("sample buffer", MemKind::Ram, 34)
    );
    // The screen's samples plus the tent filter's apron of 2 samples beyond each edge.
    assert_eq!(mem.depth, (48 * 4 + 4) * (40 * 4 + 4));
    assert_eq!(o.report.cost.storage_bits, mem.depth * 34);
    // The image holds the tap; an empty sample is the far code with the background id.
    let im = &o.images[0];
    let (mut empty, mut covered) = (0, 0);
    for w in 0..words {
        let got = [(im.get)(w, 0), (im.get)(w, 1), (im.get)(w, 2)];
        if tap.samples.prim[w] == 0 {
            assert_eq!(got, [65535, tap.bg as u64, 0]);
            empty += 1;
        } else {
            let want = [
                tap.samples.z[w] as u64,
                tap.samples.i[w] as u64,
                tap.samples.prim[w] as u64,
            ];
            assert_eq!(got, want);
            covered += 1;
        }
    }
    assert!(empty > 100 && covered > 100, "{empty} {covered}");
    assert_eq!(tap.bg, (0.25f64 * 4095.0 * 16.0).round() as u32);
}

/// The sample buffer holds the screen's samples plus the filter's apron beyond each edge
/// (the raster writes them; the edge pixels' windows read them): a region reaching the
/// screen's edges still fits (it did not when the memory was screen-sized: "12672 words but
/// the cost charges 12288" for this 32x24 screen at 4x4 samples).
#[test]
fn sample_buffer_pack_verifies_when_the_region_reaches_the_screen_edge() {
    let objects = tri(
        [[1.0, 1.0, 0.3], [30.0, 2.0, 0.7], [4.0, 20.0, 0.5]],
        [0.5; 3],
    );
    for preset in ["linear12", "log8-logadd"] {
        let r = render(
            &scene(32, 24, 0.0, &objects),
            &HwConfig::preset(preset).unwrap(),
            RunOptions::FAST,
        )
        .unwrap();
        for p in r.steps.iter().flat_map(|s| &s.outcome.packs) {
            assert!(p.verified, "{preset}: {p:?}");
        }
    }
}

#[test]
fn log_coding_moves_the_sample_buffer_to_logdomain() {
    let s = inner_scene(0.1);
    // The screen's samples plus the tent filter's apron of 2 samples beyond each edge.
    let samples = (48 * 4 + 4) * (40 * 4 + 4u64);
    let id = id_width(2);
    let lin = render(&s, &HwConfig::default_config(), RunOptions::FAST).unwrap();
    let lin_vis = &lin.report.stages[3];
    assert_eq!(lin_vis.name, "visibility");
    let lin_bits = samples * (24 + 16 + id) as u64;
    assert_eq!(lin_vis.cost.storage_bits, lin_bits);
    assert_eq!(lin.report.cycles.cost.storage_bits["visibility"], lin_bits);
    for (preset, log_bits) in [
        ("log8-logadd", 8),
        ("log8-potentiate", 8),
        ("log7-logadd", 7),
    ] {
        let r = render(&s, &HwConfig::preset(preset).unwrap(), RunOptions::FAST).unwrap();
        let step = |id: StageId| r.steps.iter().find(|s| s.id == id).unwrap();
        let (vis, log) = (step(StageId::Visibility), step(StageId::Logdomain));
        let vc = &vis.outcome.report.cost;
        assert_eq!((vc.storage_bits, vc.memories.len()), (0, 0), "{preset}");
        assert!(vis.outcome.images.is_empty() && vis.outcome.packs.is_empty());
        let lc = &log.outcome.report.cost;
        let sb = lc
            .memories
            .iter()
            .find(|m| m.name == "sample buffer")
            .expect(preset);
        assert_eq!(
            (sb.kind, sb.depth, sb.width),
            (MemKind::Ram, samples, 24 + log_bits + id)
        );
        assert_eq!(
            lc.storage_bits,
            sb.bits(),
            "{preset}: the only RAM of logdomain"
        );
        let saved = log.outcome.report.notes["sample_buffer_bits_saved"]
            .as_u64()
            .unwrap();
        assert_eq!(saved, samples * (16 - log_bits) as u64);
        assert_eq!(sb.bits(), lin_bits - saved, "{preset}");
        let k = &r.report.cycles.cost;
        assert!(!k.storage_bits.contains_key("visibility"), "{preset}");
        assert_eq!(k.storage_bits["logdomain"], lin_bits - saved);
        let p = log
            .outcome
            .packs
            .iter()
            .find(|p| p.name == "sample buffer")
            .unwrap();
        assert!(p.verified, "{p:?}");
        assert_eq!(p.fields, [24, log_bits, id]);
    }
}
