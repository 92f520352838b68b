//! The dof stage: the layered-DoF theorem, invariants, hard cases and bad input.
//! Figures are printed with `--nocapture` (the README's DoF section quotes them).

mod common;

use common::Rng;
use igemu::config::{DofCfg, DofKernel, HwConfig, SigmaForm};
use igemu::fixed::{Overflow, QFormat, Quant, round_shift};
use igemu::pipeline;
use igemu::scene::{Lens, Scene, depth_from_screen_z};
use igemu::stage::RunOptions;
use igemu::stage::dof::{
    DepthImage, G_FRAC, LayerPlan, LensMap, SIGMA_FRAC, additive_layered, difference_degree,
    edge_band, layered_f64, layered_fixed, per_pixel_scatter, plan_layers, region_error, taps_f64,
    taps_fixed,
};

const ZF: u32 = 16;
const FRAME: QFormat = QFormat::new(false, 12, 0);
const WHITE: u32 = 4095;

fn params() -> DofCfg {
    HwConfig::default_config().dof
}

fn lens() -> LensMap {
    common::affine_lens(ZF)
}

fn key(z: f64) -> u32 {
    (z * (1u64 << ZF) as f64).round() as u32
}

struct Img {
    w: usize,
    h: usize,
    v: Vec<u32>,
    k: Vec<u32>,
    c: Vec<u16>,
}

impl Img {
    fn new(w: usize, h: usize, v: u32, z: f64) -> Self {
        Self {
            w,
            h,
            v: vec![v; w * h],
            k: vec![key(z); w * h],
            c: vec![16; w * h],
        }
    }
    fn fixed(&self) -> DepthImage<'_, u32> {
        DepthImage {
            width: self.w,
            height: self.h,
            value: &self.v,
            key: &self.k,
            cov: &self.c,
            n2: 16,
        }
    }
    fn plan(&self, p: &DofCfg) -> LayerPlan {
        plan_layers(&self.k, &self.c, 16, &lens(), p).expect("plan")
    }
    fn run(&self, p: &DofCfg) -> Vec<u32> {
        layered_fixed(&self.fixed(), &self.plan(p), p, FRAME)
            .expect("run")
            .0
    }
    fn vf(&self) -> Vec<f64> {
        self.v.iter().map(|&v| v as f64).collect()
    }
}

fn fimg<'a>(i: &'a Img, vf: &'a [f64]) -> DepthImage<'a, f64> {
    DepthImage {
        width: i.w,
        height: i.h,
        value: vf,
        key: &i.k,
        cov: &i.c,
        n2: 16,
    }
}

/// Random blocky depth image: 6x6-pixel blocks of random depth in [0, 1], random codes.
fn random_image(rng: &mut Rng, w: usize, h: usize) -> Img {
    let mut img = Img::new(w, h, 0, 0.5);
    let bw = w.div_ceil(6);
    let zs: Vec<f64> = (0..bw * h.div_ceil(6))
        .map(|_| rng.range(0.0, 1.0))
        .collect();
    for y in 0..h {
        for x in 0..w {
            img.k[y * w + x] = key(zs[(y / 6) * bw + x / 6]);
            img.v[y * w + x] = rng.range(0.0, 4096.0) as u32;
        }
    }
    img
}

#[test]
fn theorem_additive_layered_within_p_on_random_depth_images() {
    let mut rng = Rng::new(0x05ee_dd0f);
    for &pv in &[0.05, 0.1, 0.2, 0.3] {
        let mut worst = (0.0f64, 0.0f64);
        for _ in 0..4 {
            let img = random_image(&mut rng, 40, 32);
            let p = DofCfg { p: pv, ..params() };
            let plan = img.plan(&p);
            let vf = img.vf();
            let fi = fimg(&img, &vf);
            let pp = per_pixel_scatter(&fi, &lens(), p.k, DofKernel::Gaussian);
            let s_f = difference_degree(&additive_layered(&fi, &plan, p.coef_bits, false), &pp);
            let s_q = difference_degree(&additive_layered(&fi, &plan, p.coef_bits, true), &pp);
            assert!(s_f < pv, "P = {pv}: float additive layered S = {s_f}");
            assert!(
                s_q < pv,
                "P = {pv}: fixed-coefficient additive layered S = {s_q}"
            );
            worst = (worst.0.max(s_f), worst.1.max(s_q));
        }
        eprintln!(
            "random depth images, P = {pv}: worst S(additive, per-pixel) float {:.5}, fixed coefficients {:.5}",
            worst.0, worst.1
        );
    }
}

/// The default scene's frame memory before the dof stage (the taps after accumulate).
struct Before {
    frame: igemu::stage::accumulate::Frame,
}

fn default_frame(scene: &Scene, hw: &HwConfig) -> Before {
    let (_, taps) = pipeline::run_through(
        scene,
        hw,
        RunOptions::FAST,
        igemu::stage::StageId::Accumulate,
    )
    .unwrap();
    Before {
        frame: taps.fixed.frame().frame.clone(),
    }
}

#[test]
fn theorem_on_default_scene_for_several_p_and_composited_departure() {
    let scene = Scene::default_scene();
    let hw = HwConfig::default_config();
    let a = default_frame(&scene, &hw);
    let lm = LensMap::from_camera(
        &scene.camera,
        480,
        hw.visibility.z.format.frac_bits,
        hw.dof.sigma,
        hw.dof.sigma_rom_bits,
    )
    .unwrap();
    let vf: Vec<f64> = a.frame.acc.iter().map(|&v| v as f64).collect();
    let img = DepthImage {
        width: 640,
        height: 480,
        value: &vf[..],
        key: &a.frame.depth,
        cov: &a.frame.coverage,
        n2: 16,
    };
    let pp = per_pixel_scatter(&img, &lm, hw.dof.k, DofKernel::Gaussian);
    for &pv in &[0.02, 0.05, 0.1, 0.2] {
        let p = DofCfg {
            p: pv,
            ..hw.dof.clone()
        };
        let plan = plan_layers(&a.frame.depth, &a.frame.coverage, 16, &lm, &p).unwrap();
        let s_f = difference_degree(&additive_layered(&img, &plan, p.coef_bits, false), &pp);
        let s_q = difference_degree(&additive_layered(&img, &plan, p.coef_bits, true), &pp);
        assert!(s_f < pv && s_q < pv, "P = {pv}: S float {s_f}, fixed {s_q}");
        let fimg = DepthImage {
            value: &a.frame.acc[..],
            key: &a.frame.depth,
            cov: &a.frame.coverage,
            width: 640,
            height: 480,
            n2: 16,
        };
        let (out, work) = layered_fixed(&fimg, &plan, &p, FRAME).unwrap();
        let outf: Vec<f64> = out.iter().map(|&v| v as f64).collect();
        let m_max = plan.layers.iter().map(|l| l.m).max().unwrap();
        let edge = edge_band(640, 480, &plan.index, m_max);
        let e = region_error(&outf, &pp, &edge);
        // Compositing handles occlusion, which the theorem does not cover: the departure
        // concentrates at depth edges; the interior stays within P.
        assert!(e.interior_difference_degree < pv, "{e:?}");
        assert!(e.edge_difference_degree > e.interior_difference_degree);
        eprintln!(
            "default scene, P = {pv}: {} layers, {} MACs; S(additive float) {s_f:.5}, S(additive fixed coef) {s_q:.5}; composited fixed vs per-pixel: S {:.5} (edges {:.5} over {} px, max {:.0} LSB; interior {:.5}, max {:.1} LSB)",
            plan.layers.len(),
            work.macs,
            e.difference_degree,
            e.edge_difference_degree,
            e.edge_pixels,
            e.edge_max_abs,
            e.interior_difference_degree,
            e.interior_max_abs
        );
    }
}

#[test]
fn flat_field_any_code_any_depths_is_bit_identical() {
    let mut rng = Rng::new(42);
    for code in [0u32, 1, 2, 1000, 2047, 4094, WHITE] {
        let mut img = random_image(&mut rng, 36, 30);
        img.v.iter_mut().for_each(|v| *v = code);
        // partial coverage at random pixels: the rest goes to the background layer
        for c in img.c.iter_mut() {
            if rng.range(0.0, 1.0) < 0.2 {
                *c = rng.range(0.0, 17.0) as u16;
            }
        }
        let out = img.run(&params());
        assert_eq!(out, img.v, "flat field {code}");
    }
}

/// The plan holds a background layer exactly when a pixel shows the background: its depth
/// code is the background's, or its coverage is partial. One such pixel anywhere in a frame
/// of more pixels than the plan's parallel chunks (16 384), at and around a chunk's edge.
#[test]
fn plan_has_a_background_layer_iff_a_pixel_shows_it() {
    let (w, h) = (200, 100);
    let p = params();
    assert_eq!(Img::new(w, h, 100, 0.5).plan(&p).background, None);
    for at in [0, 1, 16_383, 16_384, 16_385, w * h - 1] {
        let mut partial = Img::new(w, h, 100, 0.5);
        partial.c[at] = 15;
        assert!(partial.plan(&p).background.is_some(), "coverage 15 at {at}");
        let mut uncovered = Img::new(w, h, 100, 0.5);
        uncovered.k[at] = u32::MAX;
        assert!(
            uncovered.plan(&p).background.is_some(),
            "background at {at}"
        );
    }
}

#[test]
fn single_layer_equals_plain_2d_convolution() {
    let mut rng = Rng::new(7);
    let mut img = Img::new(33, 29, 0, 0.9); // sigma = 4.8 px
    img.v
        .iter_mut()
        .for_each(|v| *v = rng.range(0.0, 4096.0) as u32);
    let p = params();
    let plan = img.plan(&p);
    assert_eq!(plan.layers.len(), 1);
    let c = &plan.layers[0].coef;
    let m = c.len() as i64 / 2;
    let out = img.run(&p);
    let mut worst = 0.0f64;
    for y in 0..img.h as i64 {
        for x in 0..img.w as i64 {
            let (mut s, mut ws) = (0u128, 0u128);
            for j in -m..=m {
                for i in -m..=m {
                    let (xx, yy) = (x + i, y + j);
                    if xx < 0 || yy < 0 || xx >= img.w as i64 || yy >= img.h as i64 {
                        continue;
                    }
                    let wgt = c[(i + m) as usize] as u128 * c[(j + m) as usize] as u128;
                    s += wgt * img.v[(yy as usize) * img.w + xx as usize] as u128;
                    ws += wgt;
                }
            }
            let exact = s as f64 / ws as f64;
            let d = (out[y as usize * img.w + x as usize] as f64 - exact).abs();
            worst = worst.max(d);
        }
    }
    // one rounding to 2^-guard in the colour divide, one to the frame code
    let bound = 0.5 + 0.5 / (1u64 << p.guard_bits) as f64;
    assert!(worst <= bound, "worst {worst} > {bound}");
    eprintln!(
        "single layer vs plain 2-D convolution (renormalised borders): max |diff| {worst:.4} LSB"
    );
}

#[test]
fn energy_conserved_away_from_borders() {
    let mut rng = Rng::new(9);
    let mut img = Img::new(64, 64, 0, 0.8); // sigma 3.6 px, M = 7
    for y in 20..44 {
        for x in 20..44 {
            img.v[y * 64 + x] = rng.range(0.0, 4096.0) as u32;
        }
    }
    let out = img.run(&params());
    let sin: i64 = img.v.iter().map(|&v| v as i64).sum();
    let sout: i64 = out.iter().map(|&v| v as i64).sum();
    let touched = out.iter().filter(|&&v| v > 0).count() as i64;
    // each output pixel is rounded once (RND_CONV): |error| <= 1/2 LSB per touched pixel
    assert!(
        (sout - sin).abs() * 2 <= touched,
        "in {sin}, out {sout}, {touched} px"
    );
    eprintln!(
        "energy: in {sin}, out {sout}: {} LSB over {touched} pixels ({:.2e} relative)",
        sout - sin,
        (sout - sin) as f64 / sin as f64
    );
}

#[test]
fn coefficients_sum_exactly_and_mask_half_size_follows_k() {
    for s in [0.3, 1.0, 2.5, 4.0, 9.7] {
        let t = taps_f64(s, 0.05);
        let m = t.len() / 2;
        assert!(m as f64 >= 1.731 * s - 1e-9 && (m as f64) < 1.731 * s + 1.0);
        for f in [6, 10, 12, 16] {
            assert_eq!(taps_fixed(&t, f).iter().sum::<u64>(), 1u64 << f);
        }
    }
}

#[test]
fn hard_case_sharp_object_in_front_of_blurred_background() {
    // background: vertical stripes at z = 0.9 (sigma 4.8 px); in front, a sharp (sigma 0)
    // bright square at z = 0.45.
    let (w, h) = (48, 40);
    let mut img = Img::new(w, h, 0, 0.9);
    for y in 0..h {
        for x in 0..w {
            img.v[y * w + x] = if (x / 4) % 2 == 0 { 300 } else { 900 };
        }
    }
    let bg_only = img.run(&params());
    for y in 14..26 {
        for x in 18..30 {
            img.v[y * w + x] = WHITE;
            img.k[y * w + x] = key(0.45);
        }
    }
    let out = img.run(&params());
    let mut leak = 0u32;
    for y in 0..h {
        for x in 0..w {
            let inside = (14..26).contains(&y) && (18..30).contains(&x);
            if inside {
                assert_eq!(out[y * w + x], WHITE, "sharp object passes untouched");
            } else {
                leak = leak.max(out[y * w + x].abs_diff(bg_only[y * w + x]).min(WHITE));
                // no white leaks into the background: never brighter than the stripes' blur
                assert!(out[y * w + x] <= 900);
            }
        }
    }
    let vf = img.vf();
    let pp = per_pixel_scatter(&fimg(&img, &vf), &lens(), 0.05, DofKernel::Gaussian);
    let pp_leak = (0..w * h)
        .filter(|&i| {
            let (x, y) = (i % w, i / w);
            !((14..26).contains(&y) && (18..30).contains(&x))
        })
        .map(|i| pp[i] - 900.0)
        .fold(0.0f64, f64::max);
    eprintln!(
        "sharp in front of blurred: leakage of the white square into the background: layered max {leak} LSB change vs background alone (bound: the hole-filled background blur), never above 900; per-pixel scatter reference leaks up to {pp_leak:.0} LSB above 900"
    );
}

#[test]
fn hard_case_blurred_foreground_over_sharp_background() {
    let (w, h) = (48, 40);
    let mut img = Img::new(w, h, 0, 0.45); // sharp background (inside the band)
    for y in 0..h {
        for x in 0..w {
            img.v[y * w + x] = if (x + y) % 2 == 0 { 200 } else { 1200 };
        }
    }
    let bg = img.v.clone();
    for y in 15..25 {
        for x in 19..29 {
            img.v[y * w + x] = WHITE;
            img.k[y * w + x] = key(0.15); // sigma -3 px in front of the band
        }
    }
    let out = img.run(&params());
    let m = img
        .plan(&params())
        .layers
        .iter()
        .map(|l| l.m)
        .max()
        .unwrap();
    // far from the foreground the background is untouched
    for y in 0..h {
        for x in 0..w {
            let far = y + m < 15 || y >= 25 + m || x + m < 19 || x >= 29 + m;
            if far {
                assert_eq!(out[y * w + x], bg[y * w + x]);
            }
        }
    }
    // the foreground spreads over the background: a blurred fringe just outside it
    let fringe = out[20 * w + 29 + 1] as i64 - bg[20 * w + 30] as i64;
    assert!(fringe > 200, "fringe {fringe}");
    let vf = img.vf();
    let pp = per_pixel_scatter(&fimg(&img, &vf), &lens(), 0.05, DofKernel::Gaussian);
    let outf: Vec<f64> = out.iter().map(|&v| v as f64).collect();
    eprintln!(
        "blurred foreground over sharp background: fringe +{fringe} LSB one pixel outside; background untouched beyond M = {m}; S vs per-pixel {:.4}",
        difference_degree(&outf, &pp)
    );
}

#[test]
fn hard_case_one_pixel_wire_with_large_sigma() {
    let (w, h) = (64, 24);
    // (a) over a blurred background (z = 0.9, sigma 4.8 px): the hole the wire leaves in
    // the background layer is filled by its normalised convolution.
    // (b) over a sharp background (z = 0.45, sigma 0): a sharp layer carries nothing behind
    // the wire, so the wire's own pixels keep its value (the missing-background limit of
    // layered DoF); its halo is still spread.
    for (bgz, name) in [(0.9, "blurred"), (0.45, "sharp")] {
        let mut img = Img::new(w, h, 500, bgz);
        for y in 0..h {
            img.v[y * w + 32] = WHITE;
            img.k[y * w + 32] = key(0.0); // sigma -4.8 px, in front
        }
        let out = img.run(&params());
        let frac = |x: usize| (out[12 * w + x] as f64 - 500.0) / (WHITE as f64 - 500.0);
        let halo = frac(34);
        assert!(halo > 0.05, "{name}: halo {halo}");
        if name == "blurred" {
            // centre tap of exp(-x^2/sigma^2), 4.8 px: 1/(sqrt(pi) 4.8) = 0.118
            assert!(frac(32) < 0.2, "{name}: wire keeps {}", frac(32));
            let e: f64 = (0..w).map(|x| out[12 * w + x] as f64 - 500.0).sum();
            assert!(
                (e - (WHITE - 500) as f64).abs() < 0.02 * (WHITE - 500) as f64,
                "energy {e}"
            );
        }
        eprintln!(
            "1-px wire, sigma 4.8 px, over a {name} background: wire pixel keeps {:.3} of its contrast, 2 px away {halo:.3}",
            frac(32)
        );
    }
}

#[test]
fn hard_case_depth_ramp_crossing_every_layer() {
    let (w, h) = (160, 16);
    let mut img = Img::new(w, h, 0, 0.0);
    for y in 0..h {
        for x in 0..w {
            img.k[y * w + x] = key(x as f64 / (w - 1) as f64);
            img.v[y * w + x] = if (x / 3 + y / 3) % 2 == 0 { 800 } else { 3000 };
        }
    }
    let p = params();
    let plan = img.plan(&p);
    assert!(plan.layers.len() >= 8, "{} layers", plan.layers.len());
    let vf = img.vf();
    let fi = fimg(&img, &vf);
    let pp = per_pixel_scatter(&fi, &lens(), p.k, DofKernel::Gaussian);
    let s = difference_degree(&additive_layered(&fi, &plan, p.coef_bits, false), &pp);
    assert!(s < p.p);
    let max_sigma_step = plan
        .layers
        .windows(2)
        .map(|l| (l[0].sigma.abs() - l[1].sigma.abs()).abs())
        .fold(0.0f64, f64::max);
    let out = img.run(&p);
    let lay = layered_f64(&fi, &plan);
    // step across layer boundaries: error vs the per-pixel reference in the boundary columns
    let (mut b_err, mut i_err) = (0.0f64, 0.0f64);
    for x in 0..w {
        let l = plan.index[8 * w + x];
        let boundary = (x > 0 && plan.index[8 * w + x - 1] != l)
            || (x + 1 < w && plan.index[8 * w + x + 1] != l);
        for y in 4..12 {
            let d = (out[y * w + x] as f64 - pp[y * w + x]).abs();
            if boundary {
                b_err = b_err.max(d);
            } else {
                i_err = i_err.max(d);
            }
        }
    }
    let outf: Vec<f64> = out.iter().map(|&v| v as f64).collect();
    eprintln!(
        "depth ramp: {} layers, largest sigma step between layers {max_sigma_step:.3} px; S(additive, per-pixel) {s:.4}; composited vs per-pixel: max |diff| at layer boundaries {b_err:.0} LSB, elsewhere {i_err:.0} LSB; S(fixed, float layered) {:.2e}",
        plan.layers.len(),
        difference_degree(&outf, &lay)
    );
}

#[test]
fn hard_case_accumulator_overflow_at_full_white() {
    let mut img = Img::new(40, 40, WHITE, 0.95);
    img.k[20 * 40 + 20] = key(0.0);
    let p = params();
    let (out, work) = layered_fixed(&img.fixed(), &img.plan(&p), &p, FRAME).unwrap();
    assert_eq!(work.acc_overflows + work.line_overflows, 0);
    assert!(out.iter().all(|&v| v == WHITE));
    let narrow = DofCfg {
        acc_bits: p.acc_bits - 1,
        ..p.clone()
    };
    let (out_n, work_n) = layered_fixed(&img.fixed(), &img.plan(&narrow), &narrow, FRAME).unwrap();
    assert!(work_n.acc_overflows > 0);
    let low = out_n.iter().filter(|&&v| v < WHITE).count();
    assert!(low > 0);
    let err = DofCfg {
        overflow: Overflow::Error,
        ..narrow.clone()
    };
    let e = layered_fixed(&img.fixed(), &img.plan(&err), &err, FRAME).unwrap_err();
    assert_eq!(e.0, "dof.acc");
    eprintln!(
        "full white: {}-bit accumulator holds it (0 overflows); {}-bit: {} overflows (SAT), {low} pixels below white, min {}; ERROR mode stops at dof.acc",
        p.acc_bits,
        narrow.acc_bits,
        work_n.acc_overflows,
        out_n.iter().min().unwrap()
    );
}

/// The dof output is rounded and saturated to the frame format by a quantiser, and the
/// saturated pixels are counted (`DofWork::out_overflows`, signal `dof.out`).
#[test]
fn out_saturations_to_a_narrow_frame_format_are_counted() {
    const NARROW: QFormat = QFormat::new(false, 8, 0);
    // In focus (sigma = 0, passed through): the output is the input saturated to 255.
    let mut img = Img::new(12, 10, 0, 0.45);
    let vals = [0, 1, 100, 254, 255, 256, 1000, 4094, WHITE];
    for (i, v) in img.v.iter_mut().enumerate() {
        *v = vals[i % vals.len()];
    }
    let p = params();
    let plan = img.plan(&p);
    assert!(plan.layers.iter().all(|l| l.m == 0));
    let (out, work) = layered_fixed(&img.fixed(), &plan, &p, NARROW).unwrap();
    let want: Vec<u32> = img.v.iter().map(|&v| v.min(255)).collect();
    assert_eq!(out, want);
    let saturated = img.v.iter().filter(|&&v| v > 255).count() as u64;
    assert_eq!(work.out_overflows, saturated);
    assert!(saturated > 0);
    let (out12, work12) = layered_fixed(&img.fixed(), &plan, &p, FRAME).unwrap();
    assert_eq!((out12, work12.out_overflows), (img.v.clone(), 0));
    // Blurred full white: every pixel saturates.
    let img = Img::new(20, 16, WHITE, 0.95);
    let plan = img.plan(&p);
    assert!(plan.layers.iter().all(|l| l.m > 0));
    let (out, work) = layered_fixed(&img.fixed(), &plan, &p, NARROW).unwrap();
    assert!(out.iter().all(|&v| v == 255));
    assert_eq!(work.out_overflows, (img.w * img.h) as u64);
    assert_eq!(work.acc_overflows + work.line_overflows, 0);
}

#[test]
fn dof_stage_reports_the_out_signal_in_the_frame_format() {
    let hw = HwConfig::default_config();
    let r = pipeline::render(&Scene::default_scene(), &hw, RunOptions::FAST).unwrap();
    let d = r.report.stages.iter().find(|s| s.name == "dof").unwrap();
    let names: Vec<&str> = d.signals.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["dof.line", "dof.acc", "dof.out"]);
    let out = &d.signals[2];
    assert_eq!(out.format, hw.accumulate.frame.format);
    assert_eq!(out.overflows, 0);
    // The line and accumulator words in their configured widths (40 bits: wider than a
    // quantiser's format, a label only).
    assert_eq!(
        d.signals[0].format.to_string(),
        format!("UQ{}.0", hw.dof.line_bits)
    );
    assert_eq!(
        d.signals[1].format.to_string(),
        format!("UQ{}.0", hw.dof.acc_bits)
    );
    assert!(hw.dof.acc_bits > 32);
}

/// The depth code of screen z as before the quantiser: `f64::round`.
fn old_z_code(l: &LensMap, z: f64) -> i64 {
    (z * (1u64 << l.z_frac) as f64).round() as i64
}

/// The sigma code as computed before the quantiser (`f64::round` of the constants).
fn old_sigma_code(l: &LensMap, key: u32) -> i64 {
    let z = if key == u32::MAX {
        old_z_code(l, l.z_inf)
    } else {
        key as i64
    };
    let (zf, zn) = (old_z_code(l, l.z_far_edge), old_z_code(l, l.z_near_edge));
    let d = if z > zf {
        z - zf
    } else if z < zn {
        z - zn
    } else {
        return 0;
    };
    let g = (l.g * (1u64 << G_FRAC) as f64).round() as i128;
    round_shift(d as i128 * g, l.z_frac + G_FRAC - SIGMA_FRAC, Quant::Rnd) as i64
}

/// The sigma of a layer's middle depth as computed before the quantiser.
fn old_mid_sigma(l: &LensMap, far: u32, near: u32) -> f64 {
    let zm = (l.z_of(far) + l.z_of(near)) / 2.0;
    let code = (zm * (1u64 << l.z_frac) as f64).round();
    let c = if code >= u32::MAX as f64 {
        u32::MAX
    } else {
        code as u32
    };
    old_sigma_code(l, c) as f64 / (1u64 << SIGMA_FRAC) as f64
}

/// The layer plan takes the middle of two depth codes as `(far + near + 1) / 2` (exact in
/// binary, rounded as the constants are: RND_INF); the lens's z quantiser must agree on the
/// embedded lenses, for codes across the whole z buffer and at its ends.
#[test]
fn the_middle_of_two_depth_codes_is_their_mean_rounded_away_from_zero() {
    let hw = HwConfig::default_config();
    let zf = hw.visibility.z.format.frac_bits;
    let top = hw.visibility.z.format.max_code() as u32;
    let mut rng = Rng::new(0x3a1d);
    for name in ["default", "cone-focus"] {
        let scene = Scene::embedded(name).unwrap();
        for form in [SigmaForm::Affine, SigmaForm::Paper] {
            let lm = LensMap::from_camera(&scene.camera, scene.image.height, zf, form, 10)
                .expect("a thin lens");
            let zq = lm.z_quantizer();
            assert_eq!((zq.format.frac_bits, zq.quant), (zf, Quant::RndInf));
            let mut pairs: Vec<(u32, u32)> = vec![(0, 0), (1, 0), (top, 0), (top, top - 1)];
            pairs.extend((0..20_000).map(|_| {
                let (a, b) = (
                    rng.bits(32) as u32 % (top + 1),
                    rng.bits(32) as u32 % (top + 1),
                );
                (a.max(b), a.min(b))
            }));
            for (far, near) in pairs {
                let q = zq.quantize_f64((lm.z_of(far) + lm.z_of(near)) / 2.0);
                assert!(!q.overflow, "{name}: {far} {near}");
                assert_eq!(
                    q.code,
                    (i64::from(far) + i64::from(near) + 1) / 2,
                    "{name}: {far} {near}"
                );
            }
        }
    }
}

#[test]
fn quantised_lens_constants_agree_with_f64_round_on_the_embedded_scenes() {
    let hw = HwConfig::default_config();
    let zf = hw.visibility.z.format.frac_bits;
    let mut lenses = 0;
    for name in ["default", "default-pinhole", "cone-focus"] {
        let scene = Scene::embedded(name).unwrap();
        let Some(lm) =
            LensMap::from_camera(&scene.camera, scene.image.height, zf, SigmaForm::Affine, 10)
        else {
            assert_eq!(name, "default-pinhole");
            continue;
        };
        lenses += 1;
        // Named formats: G in UQ5.16 (G = 18.99, 25.32 px per unit z), z codes in UQ1.24
        // (z_inf = 1/(1 - 2/50) = 1.0417).
        assert_eq!(lm.g_quantizer().format.to_string(), "UQ5.16", "{name}");
        assert_eq!(lm.z_quantizer().format.to_string(), "UQ1.24", "{name}");
        assert_eq!(lm.g_bits(), 21);
        assert_eq!(
            lm.g_code(),
            (lm.g * 65536.0).round() as i64,
            "{name}: G code"
        );
        for z in [lm.z_inf, lm.z_far_edge, lm.z_near_edge] {
            assert_eq!(lm.z_code(z), old_z_code(&lm, z), "{name}: z {z}");
        }
        let a = default_frame(&scene, &hw);
        let mut keys = a.frame.depth.clone();
        keys.push(u32::MAX);
        keys.sort_unstable();
        keys.dedup();
        assert!(keys.len() > 100, "{name}: {} depth codes", keys.len());
        let mut blurred = 0;
        for &k in &keys {
            let c = lm.sigma_code(k);
            assert_eq!(c, old_sigma_code(&lm, k), "{name}: depth code {k}");
            blurred += usize::from(c != 0);
        }
        assert!(blurred > 0 && blurred < keys.len(), "{name}: {blurred}");
        let plan = plan_layers(&a.frame.depth, &a.frame.coverage, 16, &lm, &hw.dof).unwrap();
        for l in &plan.layers {
            assert_eq!(
                l.sigma,
                old_mid_sigma(&lm, l.key_far, l.key_near),
                "{name}: layer {l:?}"
            );
        }
    }
    assert_eq!(lenses, 2);
}

/// The paper's blur (`dof.sigma = "paper"`, the default): the sigma ROM holds
/// `K (1/U - 1/(D - deep))` beyond the in-focus band and `K (1/U - 1/(D + deep))` before it,
/// rounded to 1/256 px; the background reads `K/U` (3.956 px on the default scene); the
/// interpolated code of every depth code in the frame is within a small bound of the exact
/// formula and monotone in depth.
#[test]
fn paper_sigma_rom_holds_the_papers_blur_and_the_background_at_k_over_u() {
    let hw = HwConfig::default_config();
    assert_eq!(hw.dof.sigma, SigmaForm::Paper);
    let zf = hw.visibility.z.format.frac_bits;
    for name in ["default", "cone-focus"] {
        let scene = Scene::embedded(name).unwrap();
        let cam = &scene.camera;
        let Lens::ThinLens {
            lens_radius: r,
            focus_distance: u,
            deep,
            ..
        } = cam.lens
        else {
            panic!("{name} has a thin lens")
        };
        let h = scene.image.height as f64;
        let k = r * h / (2.0 * (cam.fov_y_deg.to_radians() / 2.0).tan());
        let lm = LensMap::from_camera(cam, scene.image.height, zf, SigmaForm::Paper, 10).unwrap();
        let paper = |d: f64| {
            if d > u + deep {
                k * (1.0 / u - 1.0 / (d - deep))
            } else if d < u - deep {
                k * (1.0 / u - 1.0 / (d + deep))
            } else {
                0.0
            }
        };
        let rom = lm.sigma_rom();
        assert_eq!(rom.len(), 1024 + 2, "{name}");
        let mut exact = 0;
        for (j, &e) in rom[..=1024].iter().enumerate() {
            let want = paper(depth_from_screen_z(cam, j as f64 / 1024.0)) * 256.0;
            assert!(
                (e as f64 - want).abs() <= 0.5 + 1e-9,
                "{name} entry {j}: {e} vs {want}"
            );
            exact += usize::from(e == want.round() as i64);
        }
        assert!(
            exact >= 1020,
            "{name}: {exact} entries are the rounded formula"
        );
        let bg = lm.sigma_code(u32::MAX) as f64 / 256.0;
        assert!(
            (bg - k / u).abs() <= 0.5 / 256.0,
            "{name}: background {bg} vs K/U {}",
            k / u
        );
        if name == "default" {
            assert!((bg - 3.956).abs() < 0.03, "background sigma {bg}");
        }
        let a = default_frame(&scene, &hw);
        let mut keys = a.frame.depth.clone();
        keys.sort_unstable();
        keys.dedup();
        let (mut worst, mut last) = (0.0f64, i64::MIN);
        for &key in &keys {
            let c = lm.sigma_code(key);
            assert!(c >= last, "{name}: sigma not monotone at depth code {key}");
            last = c;
            if key != u32::MAX {
                let want = paper(depth_from_screen_z(cam, lm.z_of(key)));
                worst = worst.max((c as f64 / 256.0 - want).abs());
            }
        }
        eprintln!(
            "{name}: sigma ROM 1026 x {} bits, worst interpolation error over {} depth codes {worst:.4} px",
            lm.sigma_rom_bits_wide(),
            keys.len()
        );
        assert!(worst < 0.02, "{name}: {worst} px");
    }
}

#[test]
fn quantised_lens_constants_agree_with_f64_round_at_the_format_edges() {
    let z24 = |z: f64| LensMap {
        g: 12.0,
        z_far_edge: z,
        z_near_edge: 0.0,
        z_inf: 1.0 / (1.0 - 2.0 / 50.0),
        z_frac: 24,
        coc_px: 1.0,
        ..lens()
    };
    let cases = [
        // G = 2 - 2^-20 rounds up to 2.0 (code 131072): one integer bit more than G's floor.
        (
            LensMap {
                g: 2.0 - 2f64.powi(-20),
                ..lens()
            },
            "UQ2.16",
            "UQ1.16",
        ),
        // G = 100000.3 px per unit z: wider than the 32-bit configurable formats.
        (
            LensMap {
                g: 100_000.3,
                ..lens()
            },
            "UQ17.16",
            "UQ1.16",
        ),
        // The band's far edge before the near plane (z = -0.75): signed z codes.
        (z24(-0.75), "UQ4.16", "Q2.24"),
        // Ties: -1.5 z LSBs rounds away from zero to -2 LSBs, as f64::round.
        (z24(-1.5 * 2f64.powi(-24)), "UQ4.16", "Q2.24"),
        // 2.5 LSBs rounds to 3.
        (z24(2.5 * 2f64.powi(-24)), "UQ4.16", "UQ1.24"),
    ];
    for (lm, g_fmt, z_fmt) in cases {
        assert_eq!(lm.g_quantizer().format.to_string(), g_fmt, "{lm:?}");
        assert_eq!(lm.z_quantizer().format.to_string(), z_fmt, "{lm:?}");
        assert_eq!(lm.g_code(), (lm.g * 65536.0).round() as i64, "{lm:?}");
        for z in [lm.z_inf, lm.z_far_edge, lm.z_near_edge] {
            assert_eq!(lm.z_code(z), old_z_code(&lm, z), "{lm:?}: z {z}");
        }
        let one = 1u32 << lm.z_frac;
        let zf = old_z_code(&lm, lm.z_far_edge).max(0) as u32;
        let keys = (0..=one)
            .step_by(one as usize / 997)
            .chain(zf.saturating_sub(3)..zf + 4)
            .chain([one, u32::MAX]);
        for k in keys {
            assert_eq!(lm.sigma_code(k), old_sigma_code(&lm, k), "{lm:?}: key {k}");
        }
    }
    // The tie cases really are ties of the old rounding.
    assert_eq!(
        old_z_code(&z24(-1.5 * 2f64.powi(-24)), -1.5 * 2f64.powi(-24)),
        -2
    );
    assert_eq!(
        old_z_code(&z24(2.5 * 2f64.powi(-24)), 2.5 * 2f64.powi(-24)),
        3
    );
}

#[test]
fn pinhole_plans_no_dof_stage_thin_lens_does() {
    let hw = HwConfig::default_config();
    let r = pipeline::render(&Scene::default_scene(), &hw, RunOptions::FAST).unwrap();
    assert!(r.report.plan.stages.iter().any(|s| s == "dof"));
    let mut s = Scene::default_scene();
    s.camera.lens = igemu::scene::Lens::Pinhole;
    let r = pipeline::render(&s, &hw, RunOptions::FAST).unwrap();
    assert!(!r.report.plan.stages.iter().any(|s| s == "dof"));
    let c = Scene::embedded("cone-focus").expect("embedded cone-focus scene");
    let r = pipeline::render(&c, &hw, RunOptions::FAST).unwrap();
    let d = r.report.stages.iter().find(|s| s.name == "dof").unwrap();
    assert!(d.work["layers"] >= 3);
}

/// (exit code, stderr) of the binary.
fn igemu(args: &[&str]) -> (i32, String) {
    let (code, _, err) = common::igemu(args);
    (code, err)
}

fn write(name: &str, text: &str) -> String {
    let d = std::env::temp_dir().join(format!("igemu-dof-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

fn lens_scene(lens: &str) -> String {
    let s = include_str!("../src/scene/default.toml");
    let a = s.find("[camera.lens]").unwrap();
    let b = s.find("[display]").unwrap();
    format!("{}{lens}\n\n{}", &s[..a], &s[b..])
}

#[test]
fn bad_input_exits_2_with_a_clear_message() {
    let out = write("o.png", "");
    for (name, lens, want) in [
        (
            "f0.toml",
            "[camera.lens]\nkind = \"thin_lens\"\nfocal_length = 0.0\nlens_radius = 0.06\nfocus_distance = 10.0",
            "focal_length",
        ),
        (
            "fneg.toml",
            "[camera.lens]\nkind = \"thin_lens\"\nfocal_length = -1.0\nlens_radius = 0.06\nfocus_distance = 10.0",
            "focal_length",
        ),
        (
            "close.toml",
            "[camera.lens]\nkind = \"thin_lens\"\nfocal_length = 0.5\nlens_radius = 0.06\nfocus_distance = 0.4",
            "focus_distance",
        ),
    ] {
        let sc = write(name, &lens_scene(lens));
        let (code, err) = igemu(&["render", &sc, "-o", &out]);
        assert_eq!(code, 2, "{name}: {err}");
        assert!(err.contains(want), "{name}: {err}");
    }
    for (name, hw, want) in [
        ("p0.toml", "[dof]\np = 0.0", "dof.p"),
        ("p1.toml", "[dof]\np = 1.0", "dof.p"),
        ("m.toml", "[dof]\nmax_half_size = 65", "dof.max_half_size"),
        (
            "small.toml",
            "[dof]\nmax_half_size = 3",
            "dof.max_half_size",
        ),
    ] {
        let h = write(name, hw);
        let (code, err) = igemu(&["render", "--hw", &h, "-o", &out]);
        assert_eq!(code, 2, "{name}: {err}");
        assert!(err.contains(want), "{name}: {err}");
    }
}

/// The float layered reference convolves with the float taps on the fixed mask's support:
/// which layers reach a pixel decides which one fills it first, so a float tail tap of
/// 1e-5 where the fixed tap is 0 (sigma 0.59 px, M = 2) picked another back layer and put
/// the two 224.8 LSB apart on the depth-ramp example. Now they agree within the
/// arithmetic's rounding.
#[test]
fn float_layers_use_the_fixed_mask_support_on_a_depth_ramp() {
    // The example with a smaller lens (0.05): a layer of sigma 0.59 px lands on a ground
    // stripe one pixel high.
    let text = include_str!("../examples/depth-ramp.toml")
        .replace("lens_radius = 0.07", "lens_radius = 0.05");
    let scene = Scene::from_toml(&igemu::files::TomlFile::from_text("depth-ramp", &text)).unwrap();
    let r = pipeline::render(&scene, &HwConfig::default_config(), RunOptions::default()).unwrap();
    let dof = r.report.stages.iter().find(|s| s.name == "dof").unwrap();
    let layers = dof.notes["layers"].as_array().unwrap();
    assert!(layers.len() > 30, "{}", layers.len());
    let local = dof.local.as_ref().unwrap();
    assert!(local.max_abs_lsb < 2.0, "{local:?}");
    // The case is present: a blurred layer whose outer fixed taps are 0.
    let p = HwConfig::default_config().dof;
    let tail_zero = layers.iter().any(|l| {
        let s = l["sigma"].as_f64().unwrap().abs();
        let t = taps_fixed(&taps_f64(s, p.k), p.coef_bits);
        s > 0.0 && t[0] == 0
    });
    assert!(tail_zero);
}

/// The preset widths are exactly the sums the layered passes reach at 4x4 samples; with 8x8
/// samples the line sum needs 2 more bits: the plan says so (with the widths that hold every
/// sum), the render counts the saturated sums, and with those widths both go away.
#[test]
fn a_line_word_too_narrow_for_the_samples_is_named_in_the_plan() {
    for preset in ["linear12", "linear11", "linear8", "log8-logadd"] {
        let hw = HwConfig::preset(preset).unwrap();
        let n2 = hw.raster.samples * hw.raster.samples;
        assert_eq!(
            igemu::stage::dof::reachable_bits(hw.accumulate.frame.format, n2, &hw.dof),
            (hw.dof.line_bits, hw.dof.acc_bits),
            "{preset}"
        );
    }
    let scene = Scene::default_scene();
    let dof_overflows = |hw: &HwConfig| {
        let r = pipeline::render(&scene, hw, RunOptions::FAST).unwrap();
        let d = r.report.stages.iter().find(|s| s.name == "dof").unwrap();
        let n: u64 = d.signals.iter().map(|s| s.overflows).sum();
        (r.report.plan.notes, n)
    };
    let (notes, n) = dof_overflows(&HwConfig::default_config());
    assert!(
        notes.iter().all(|t| !t.contains("dof.line_bits")),
        "{notes:?}"
    );
    assert_eq!(n, 0);
    let mut hw = HwConfig::default_config();
    hw.raster.samples = 8;
    let (notes, n) = dof_overflows(&hw);
    let note = notes.iter().find(|t| t.contains("dof.line_bits = 28 < 30"));
    assert!(
        note.is_some_and(|t| t.contains("every sum fits dof.line_bits = 30, dof.acc_bits = 42")),
        "{notes:?}"
    );
    assert!(n > 0, "the narrow line word saturates");
    hw.dof.line_bits = 30;
    hw.dof.acc_bits = 42;
    let (notes, n) = dof_overflows(&hw);
    assert!(
        notes.iter().all(|t| !t.contains("dof.line_bits")),
        "{notes:?}"
    );
    assert_eq!(n, 0, "the widths of the note hold every sum");
}
