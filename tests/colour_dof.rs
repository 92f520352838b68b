//! Depth of field on colour: the luminance-aware method weighs the bleed of all three
//! channels by the BT.601 luminance of R, G and B (one shared luminance unit, charged once);
//! three equal channels blur exactly as one grey channel; the fixed model against its float
//! reference on random colour frames; the wiring through the runner's lanes.
//! Figures are printed with `--nocapture`.

mod common;

use common::Rng;
use igemu::config::{DofKind, HwConfig};
use igemu::fixed::{Overflow, QFormat, Quant};
use igemu::pipeline::{self, Render};
use igemu::scene::Scene;
use igemu::stage::dof::luminance::{
    LUMA_PRE_LINES, LumParams, Luma, PRE_LINES, luminance_colour_f64, luminance_colour_fixed,
    luminance_fixed,
};
use igemu::stage::{RunOptions, StageId, Taps};
use proptest::prelude::*;

fn params(frame: QFormat, r: u32, g: u32) -> LumParams {
    let mut d = HwConfig::default_config().dof;
    d.luminance.radius = r;
    d.luminance.guard_bits = g;
    LumParams::of(&d, frame)
}

/// Channel `c` of a `w`-pixel wide colour frame blurred by the frames' luminance (fixed; no
/// pre-blur, 4 guard bits).
fn colour_fixed(
    frames: [&[u32]; 3],
    formats: [QFormat; 3],
    c: usize,
    alpha: &[u32],
    w: usize,
) -> Vec<u32> {
    let (h, r, g) = (frames[c].len() / w, 0, 4);
    let f: [Vec<f64>; 3] = std::array::from_fn(|k| frames[k].iter().map(|&v| v as f64).collect());
    let y = Luma::of(
        c,
        frames,
        Some(std::array::from_fn(|k| f[k].as_slice())),
        formats,
        g,
    );
    let p = params(formats[c], r, g);
    luminance_colour_fixed(frames[c], &y.fixed, y.format, alpha, w, h, &p)
        .expect("SAT")
        .0
}

#[test]
fn a_colour_bleeds_where_the_luminance_is_brighter_not_where_its_own_channel_is() {
    // Left half pure red (R 1000), right half pure green (G 1000): Y is 301 on the left,
    // 586 on the right. Green is the brighter colour, so it bleeds into the red half and
    // carries its colour: the red pixels at the edge lose red and gain green; the green
    // pixels have no brighter neighbour and stay as they are. Each channel on its own
    // would bleed the other way for R (red is brighter than no red).
    let (w, h) = (8usize, 3usize);
    let f = QFormat::new(false, 12, 0);
    let red: Vec<u32> = (0..w * h)
        .map(|i| if i % w < w / 2 { 1000 } else { 0 })
        .collect();
    let green: Vec<u32> = red.iter().map(|&v| 1000 - v).collect();
    let blue = vec![0u32; w * h];
    let alpha = vec![1u32 << params(f, 0, 4).alpha_bits; w * h];
    let frames = [red.as_slice(), green.as_slice(), blue.as_slice()];
    let r_out = colour_fixed(frames, [f; 3], 0, &alpha, w);
    let g_out = colour_fixed(frames, [f; 3], 1, &alpha, w);
    let b_out = colour_fixed(frames, [f; 3], 2, &alpha, w);
    for y in 0..h {
        let (edge_red, edge_green) = (y * w + w / 2 - 1, y * w + w / 2);
        assert!(r_out[edge_red] < 1000, "red edge keeps its red");
        assert!(g_out[edge_red] > 0, "green bleeds into the red edge");
        assert_eq!(r_out[edge_green], 0, "no red bleeds into green");
        assert_eq!(g_out[edge_green], 1000);
        // Hue moves, energy stays put: the red edge pixel takes its brighter neighbours'
        // colour mix exactly (three green neighbours: all green).
        assert_eq!((r_out[edge_red], g_out[edge_red]), (0, 1000));
        assert_eq!(r_out[y * w], 1000, "far from the edge nothing moves");
    }
    assert!(b_out.iter().all(|&v| v == 0));
    // Each channel by its own luminance: red would bleed into the green half.
    let p = params(f, 0, 4);
    let own = luminance_fixed(&red, &alpha, w, h, &p).unwrap().0;
    assert!(own[w / 2] > 0);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Three equal channels of one width blur exactly as one grey channel, at any radius,
    /// guard bits, widths and rounding.
    #[test]
    fn equal_channels_blur_exactly_as_grey(
        w in 1usize..10, h in 1usize..10, r in 0u32..3, g in 0u32..9, bits in 4u32..13,
        q in 0usize..7, seed in any::<u64>(),
    ) {
        let f = QFormat::new(false, bits, 0);
        let mut p = params(f, r, g);
        p.quant = Quant::ALL[q];
        p.overflow = Overflow::Sat;
        let mut rng = Rng::new(seed);
        let v: Vec<u32> = (0..w * h).map(|_| (rng.next_u64() % (1 << bits)) as u32).collect();
        let one = 1u64 << p.alpha_bits;
        let a: Vec<u32> = (0..w * h).map(|_| (rng.next_u64() % (one + 1)) as u32).collect();
        let grey = luminance_fixed(&v, &a, w, h, &p).unwrap().0;
        let vf: Vec<f64> = v.iter().map(|&x| x as f64).collect();
        let y = Luma::of(0, [&v; 3], Some([&vf; 3]), [f; 3], g);
        let colour = luminance_colour_fixed(&v, &y.fixed, y.format, &a, w, h, &p).unwrap().0;
        prop_assert_eq!(grey, colour);
    }
}

#[test]
fn fixed_vs_float_on_random_colour_frames() {
    // 5-6-5 and 8-8-8 frames of random smooth-ish colour (a random walk per channel), alpha
    // exact: the fixed model against the float reference on the same codes (the luminance
    // of the fixed codes as reals). Most pixels stay within the grey bound (0.5 + 22 x 0.5
    // / 2^g LSB); a near tie of luminance that the fixed rounding flips moves a pixel by
    // the colour difference of its neighbours. Print what is reached.
    let mut rng = Rng::new(0xc010_u64);
    for formats in [
        [5, 6, 5].map(|b| QFormat::new(false, b, 0)),
        [8, 8, 8].map(|b| QFormat::new(false, b, 0)),
    ] {
        let (w, h) = (32usize, 24usize);
        let (mut worst, mut over, mut n) = (0.0f64, 0usize, 0usize);
        let mut sum = 0.0;
        for _ in 0..20 {
            let frames: [Vec<u32>; 3] = std::array::from_fn(|c| {
                let max = (1i64 << formats[c].total_bits()) - 1;
                let mut v = (rng.next_u64() % (max as u64 + 1)) as i64;
                (0..w * h)
                    .map(|_| {
                        v = (v + (rng.next_u64() % 7) as i64 - 3).clamp(0, max);
                        v as u32
                    })
                    .collect()
            });
            let ff: [Vec<f64>; 3] =
                std::array::from_fn(|c| frames[c].iter().map(|&v| v as f64).collect());
            let p0 = params(formats[0], 1, 4);
            let one = 1u64 << p0.alpha_bits;
            let a: Vec<u32> = (0..w * h)
                .map(|_| (rng.next_u64() % (one + 1)) as u32)
                .collect();
            let af: Vec<f64> = a.iter().map(|&x| x as f64 / one as f64).collect();
            let codes = std::array::from_fn(|k| frames[k].as_slice());
            let vals = std::array::from_fn(|k| ff[k].as_slice());
            for c in 0..3 {
                let y = Luma::of(c, codes, Some(vals), formats, 4);
                let p = params(formats[c], 1, 4);
                let out = luminance_colour_fixed(&frames[c], &y.fixed, y.format, &a, w, h, &p)
                    .unwrap()
                    .0;
                let f = luminance_colour_f64(&ff[c], &y.local, &af, w, h, 1);
                for i in 0..w * h {
                    let e = (out[i] as f64 - f[i]).abs();
                    worst = worst.max(e);
                    sum += e;
                    over += usize::from(e > 0.5 + 11.0 / 16.0);
                    n += 1;
                }
            }
        }
        let mean = sum / n as f64;
        println!(
            "random 32x24 colour frames {:?}: mean |fixed - float| {mean:.3} LSB, max {worst:.2}, \
             {over} of {n} samples over the grey bound",
            formats.map(|f| f.total_bits())
        );
        assert!(mean < 0.5, "mean {mean}");
        assert!((over as f64) < 0.02 * n as f64, "{over} of {n}");
    }
}

fn small_colour() -> Scene {
    let mut s = Scene::embedded("default-colour").expect("embedded");
    s.image.width = 160;
    s.image.height = 120;
    s
}

fn render(s: &Scene, h: &HwConfig) -> Render {
    pipeline::render(s, h, RunOptions::FAST).unwrap_or_else(|e| panic!("{e}"))
}

/// Channel `c`'s taps after stage `id`.
fn lane_taps(r: &Render, c: usize, id: StageId) -> &Taps {
    let steps = match c {
        0 => &r.steps,
        _ => &r.colour.as_ref().expect("colour").lanes[c - 1],
    };
    &steps
        .iter()
        .find(|s| s.id == id)
        .expect("the stage ran")
        .outcome
        .taps
}

#[test]
fn the_luminance_method_on_a_colour_render_blurs_each_channel_by_the_frames_luminance() {
    let mut h = HwConfig::default_config();
    h.dof.kind = DofKind::Luminance;
    let s = small_colour();
    let r = render(&s, &h);
    let c = r.colour.as_ref().expect("colour");
    let (w, ht) = (s.image.width as usize, s.image.height as usize);
    // Every channel's frame before the blur and after it.
    let frames = |id: StageId| -> Vec<_> {
        (0..3)
            .map(|k| lane_taps(&r, k, id).fixed.frame().frame.clone())
            .collect()
    };
    let (before, after) = (frames(StageId::Accumulate), frames(StageId::Dof));
    let f = h.accumulate.frame.format;
    let g = h.dof.luminance.guard_bits;
    let p = LumParams::of(&h.dof, f);
    // Each channel's output is the colour kernel on the three frames (the luminance of all
    // three), with the alpha ROM read at each pixel's depth.
    let codes: [&[u32]; 3] = std::array::from_fn(|k| before[k].acc.as_slice());
    let vals: [Vec<f64>; 3] =
        std::array::from_fn(|k| before[k].acc.iter().map(|&v| v as f64).collect());
    let y = Luma::of(
        0,
        codes,
        Some(std::array::from_fn(|k| vals[k].as_slice())),
        [f; 3],
        g,
    );
    let mut differs_from_own = false;
    for k in 0..3 {
        let alpha = alpha_codes(&h, &s, &before[k].depth);
        let want = luminance_colour_fixed(codes[k], &y.fixed, y.format, &alpha, w, ht, &p)
            .unwrap()
            .0;
        assert!(after[k].acc == want, "channel {k}: not the colour kernel");
        let own = luminance_fixed(codes[k], &alpha, w, ht, &p).unwrap().0;
        differs_from_own |= own != after[k].acc;
    }
    assert!(
        differs_from_own,
        "some channel's blur differs from a blur by its own intensity"
    );
    // One luminance unit: lane 0 charges it and reports its signals, the others do not.
    for k in 0..3 {
        let steps = match k {
            0 => &r.steps,
            _ => &c.lanes[k - 1],
        };
        let dof = steps.iter().find(|s| s.id == StageId::Dof).unwrap();
        let rep = &dof.outcome.report;
        let has = |name: &str| rep.cost.memories.iter().any(|m| m.name == name);
        assert_eq!(has(LUMA_PRE_LINES), k == 0, "lane {k}");
        assert!(has(PRE_LINES), "lane {k} pre-blurs its own channel");
        let luma_signal = rep.signals.iter().any(|sg| sg.name == "dof.lum.luma");
        assert_eq!(luma_signal, k == 0, "lane {k}");
    }
    // The report measures it: CIEDE2000 of fixed against float is small.
    let de = &r.report.colour.as_ref().expect("colour report").delta_e;
    println!("default-colour 160x120, luminance DoF: {de:?}");
    assert!(de.mean < 0.5, "{de:?}");
}

/// The alpha ROM codes of each depth code, as the dof stage reads them.
fn alpha_codes(h: &HwConfig, s: &Scene, depth: &[u32]) -> Vec<u32> {
    use igemu::stage::dof::LensMap;
    use igemu::stage::dof::luminance::AlphaMap;
    let lens = LensMap::of(s, h, s.image.height).expect("a thin lens");
    let alpha = AlphaMap::new(&lens, &h.dof.luminance);
    depth.iter().map(|&k| alpha.code(k)).collect()
}

#[test]
fn a_cached_colour_run_reuses_nothing_across_lanes_and_repeats_bit_exactly() {
    let mut h = HwConfig::default_config();
    h.dof.kind = DofKind::Luminance;
    let s = small_colour();
    let cache = pipeline::Cache::new();
    let a = pipeline::render_with(&s, &h, RunOptions::FAST, Some(&cache)).unwrap();
    let b = pipeline::render_with(&s, &h, RunOptions::FAST, Some(&cache)).unwrap();
    let ca = a.colour.as_ref().unwrap();
    let cb = b.colour.as_ref().unwrap();
    for k in 0..3 {
        assert!(ca.channels[k].dac == cb.channels[k].dac, "channel {k}");
    }
    assert!(
        b.steps.iter().all(|s| s.reused),
        "the second run reuses every step"
    );
    let dof_keys: Vec<u64> = std::iter::once(&a.steps)
        .chain(&ca.lanes)
        .map(|l| l.iter().find(|s| s.id == StageId::Dof).unwrap().key)
        .collect();
    assert!(dof_keys[0] != dof_keys[1] && dof_keys[1] != dof_keys[2]);
    let uncached = render(&s, &h);
    assert!(uncached.dac == a.dac);
}
