//! `dof.kind = "downsample"`: downsample-and-blend depth of field. Flat fields, a bright
//! point, depth edges, fixed against float, the Poisson taps, the ROMs, the pack check, the
//! command line, bad fields and odd image sizes. Figures are printed with `--nocapture`
//! (docs/dof-downsample.md quotes them).

mod common;

use common::Rng;
use igemu::config::{DofCfg, DofKind, HwConfig, LeakGuard};
use igemu::fixed::{Overflow, QFormat};
use igemu::scene::Scene;
use igemu::stage::dof::SIGMA_FRAC;
use igemu::stage::dof::downsample::{
    Blur, DownPlan, Poisson, downsample_f64, downsample_fixed, plan_downsample, poisson_disc,
};
use igemu::stage::{RunOptions, StageId, TokenKind};
use proptest::prelude::*;

const ZF: u32 = 16;
const FRAME: QFormat = QFormat::new(false, 12, 0);

/// A synthetic blur: `sigma = g (z - far)` behind `far`, `g (z - near)` in front of `near`
/// (pixels, z = key / 2^16), the background at z = 1.
struct Lens {
    g: f64,
    far: f64,
    near: f64,
}

const LENS: Lens = Lens {
    g: 10.0,
    far: 0.5,
    near: 0.4,
};

impl Blur for Lens {
    fn sigma_code(&self, key: u32) -> i64 {
        (self.sigma_f64(key) * (1u64 << SIGMA_FRAC) as f64).round() as i64
    }
    fn sigma_f64(&self, key: u32) -> f64 {
        let z = if key == u32::MAX {
            1.0
        } else {
            key as f64 / (1u64 << ZF) as f64
        };
        if z > self.far {
            self.g * (z - self.far)
        } else if z < self.near {
            self.g * (z - self.near)
        } else {
            0.0
        }
    }
    fn z_frac(&self) -> u32 {
        ZF
    }
}

/// The depth code of screen z.
fn key(z: f64) -> u32 {
    (z * (1u64 << ZF) as f64).round() as u32
}

/// The depth code behind the focus with blur `sigma` px.
fn key_behind(sigma: f64) -> u32 {
    key(LENS.far + sigma / LENS.g)
}

/// In focus.
const FOCUS: f64 = 0.45;

fn params() -> DofCfg {
    let mut p = HwConfig::default_config().dof;
    p.kind = DofKind::Downsample;
    p
}

/// A frame: codes and depth codes.
#[derive(Clone, Debug)]
struct Img {
    w: usize,
    h: usize,
    v: Vec<u32>,
    k: Vec<u32>,
}

impl Img {
    fn new(w: usize, h: usize, v: u32, k: u32) -> Self {
        Self {
            w,
            h,
            v: vec![v; w * h],
            k: vec![k; w * h],
        }
    }
    fn plan(&self, p: &DofCfg) -> DownPlan {
        plan_downsample(&self.k, self.w, self.h, &LENS, p).expect("plan")
    }
    fn fixed(&self, p: &DofCfg) -> Vec<u32> {
        downsample_fixed(&self.v, &self.k, &self.plan(p), p, FRAME)
            .expect("run")
            .0
    }
    fn float(&self, p: &DofCfg) -> Vec<f64> {
        let vf: Vec<f64> = self.v.iter().map(|&v| v as f64).collect();
        downsample_f64(&vf, &self.k, &self.plan(p), &LENS, p)
    }
    fn at(&self, x: usize, y: usize) -> usize {
        y * self.w + x
    }
}

/// Random depth codes: blocks of random depth in [0, 1] and some background.
fn random_depths(rng: &mut Rng, img: &mut Img, block: usize) {
    let bw = img.w.div_ceil(block);
    let zs: Vec<u32> = (0..bw * img.h.div_ceil(block))
        .map(|_| {
            let z = rng.range(0.0, 1.05);
            if z >= 1.0 { u32::MAX } else { key(z) }
        })
        .collect();
    for y in 0..img.h {
        for x in 0..img.w {
            img.k[y * img.w + x] = zs[(y / block) * bw + x / block];
        }
    }
}

#[test]
fn flat_fields_are_bit_identical() {
    let mut rng = Rng::new(0xf1a7);
    let mut checked = 0;
    for &(w, h) in &[(37, 23), (64, 48), (1, 19), (19, 1), (5, 7)] {
        for &v in &[0u32, 1, 2, 1000, 2047, 4094, 4095] {
            for factor in [2, 4, 8] {
                for guard in LeakGuard::ALL {
                    let mut img = Img::new(w, h, v, 0);
                    random_depths(&mut rng, &mut img, 3);
                    let mut p = params();
                    p.downsample.factor = factor;
                    p.downsample.leak_guard = guard;
                    p.downsample.guard_bits = (checked % 3) as u32 * 2;
                    let out = img.fixed(&p);
                    assert!(
                        out.iter().all(|&o| o == v),
                        "{w}x{h} code {v} factor {factor} {guard:?}: {:?}",
                        out.iter().find(|&&o| o != v)
                    );
                    let fl = img.float(&p);
                    assert!(fl.iter().all(|&o| (o - v as f64).abs() < 1e-9));
                    checked += 1;
                }
            }
        }
    }
    eprintln!("flat fields: {checked} frames bit-identical (fixed) and within 1e-9 (float)");
}

#[test]
fn in_focus_pixels_pass_through_and_output_stays_within_the_input_range() {
    let mut rng = Rng::new(0x1f0c);
    let p = params();
    let mut img = Img::new(48, 40, 0, 0);
    random_depths(&mut rng, &mut img, 5);
    for (i, v) in img.v.iter_mut().enumerate() {
        *v = rng.range(0.0, 4096.0) as u32;
        if i % 7 == 0 {
            img.k[i] = key(FOCUS);
        }
    }
    let out = img.fixed(&p);
    let fl = img.float(&p);
    let (lo, hi) = (*img.v.iter().min().unwrap(), *img.v.iter().max().unwrap());
    let mut sharp = 0;
    for i in 0..out.len() {
        assert!(
            (lo..=hi).contains(&out[i]),
            "pixel {i}: {} outside the input range",
            out[i]
        );
        assert!(fl[i] >= lo as f64 - 1e-9 && fl[i] <= hi as f64 + 1e-9);
        if LENS.sigma_f64(img.k[i]) == 0.0 {
            assert_eq!(out[i], img.v[i], "in-focus pixel {i} changed");
            sharp += 1;
        }
    }
    assert!(sharp > 200);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Any code, any depth image (random blocks of depth, background included), any factor,
    /// leak rule and guard bits: the output is the input code, bit for bit.
    #[test]
    fn flat_field_is_bit_identical_for_any_code_and_depth_image(
        v in 0u32..4096,
        w in 1usize..48,
        h in 1usize..48,
        seed in any::<u64>(),
        block in 1usize..9,
        fi in 0usize..3,
        gi in 0usize..3,
        guard_bits in 0u32..8,
    ) {
        let mut img = Img::new(w, h, v, 0);
        random_depths(&mut Rng::new(seed), &mut img, block);
        let mut p = params();
        p.downsample.factor = [2, 4, 8][fi];
        p.downsample.leak_guard = LeakGuard::ALL[gi];
        p.downsample.guard_bits = guard_bits;
        let out = img.fixed(&p);
        prop_assert!(out.iter().all(|&o| o == v), "{:?}", out.iter().find(|&&o| o != v));
    }
}

/// A 2x2 bright block (code 4000) over a dark (0) field, everything at one depth behind the
/// focus; the block sits symmetric about a small texel's centre (pixels 29 and 30 for
/// factor 4, centre x = y = 30.0), so the method's grids are symmetric about it.
fn bright_point(sigma: f64) -> (Img, Vec<u32>, Vec<f64>) {
    let mut img = Img::new(60, 60, 0, key_behind(sigma));
    // One far corner pixel at sigma 3 fixes sigma_max (the blend factor 1).
    img.k[0] = key_behind(3.0);
    for y in 29..31 {
        for x in 29..31 {
            let i = img.at(x, y);
            img.v[i] = 4000;
        }
    }
    let p = params();
    let out = img.fixed(&p);
    let fl = img.float(&p);
    (img, out, fl)
}

#[test]
fn a_bright_point_spreads_keeps_its_energy_and_is_symmetric() {
    for sigma in [3.0, 1.5] {
        let (img, out, fl) = bright_point(sigma);
        let e_in: u64 = img.v.iter().map(|&v| v as u64).sum();
        let e_out: u64 = out.iter().map(|&v| v as u64).sum();
        let e_fl: f64 = fl.iter().sum();
        let lit = out.iter().filter(|&&v| v > 0).count();
        let peak = *out.iter().max().unwrap();
        // Point symmetry about (30, 30): pixel (x, y) against (59 - x, 59 - y).
        let (mut asym, mut asym_f) = (0i64, 0.0f64);
        for y in 0..60 {
            for x in 0..60 {
                let (a, b) = (img.at(x, y), img.at(59 - x, 59 - y));
                asym = asym.max((out[a] as i64 - out[b] as i64).abs());
                asym_f = asym_f.max((fl[a] - fl[b]).abs());
            }
        }
        let ratio = e_out as f64 / e_in as f64;
        eprintln!(
            "bright point sigma {sigma}: energy out/in fixed {ratio:.5}, float {:.5}; {lit} pixels lit; peak {peak} of 4000; asymmetry fixed {asym} codes, float {asym_f:.2e}",
            e_fl / e_in as f64
        );
        assert!(
            lit > 16 * (sigma * sigma) as usize,
            "did not spread: {lit} pixels"
        );
        assert!(peak < 4000, "peak kept: {peak}");
        assert!((ratio - 1.0).abs() < 0.02, "energy {ratio}");
        assert!((e_fl / e_in as f64 - 1.0).abs() < 0.02);
        assert!(asym_f < 1e-6, "float asymmetry {asym_f}");
        assert!(asym <= 2, "fixed asymmetry {asym}");
    }
}

#[test]
fn at_a_depth_edge_in_focus_pixels_stay_sharp_and_the_guard_limits_leaks() {
    let mut rng = Rng::new(0xed6e);
    // Left: in focus, textured; right: background blurred at sigma 3, textured.
    let (w, h) = (64, 40);
    let mut img = Img::new(w, h, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let i = img.at(x, y);
            img.k[i] = if x < 32 { key(FOCUS) } else { key_behind(3.0) };
            img.v[i] = rng.range(0.0, 4096.0) as u32;
        }
    }
    let p = params();
    let plan = img.plan(&p);
    let out = img.fixed(&p);
    let mut sharp = 0;
    for (i, &o) in out.iter().enumerate() {
        if plan.blend_fixed(img.k[i], p.quant) == 0 {
            assert_eq!(o, img.v[i], "pixel {i} with blend factor 0 changed");
            sharp += 1;
        }
    }
    assert_eq!(sharp, 32 * h, "the in-focus half has blend factor 0");
    // The same edge with a bright sharp foreground over a dark background: the light that
    // leaks into the background strip next to it, per leak rule.
    let mut leak = Vec::new();
    for g in LeakGuard::ALL {
        let mut img = img.clone();
        for y in 0..h {
            for x in 0..w {
                let i = img.at(x, y);
                img.v[i] = if x < 32 { 4000 } else { 0 };
            }
        }
        let mut p = params();
        p.downsample.leak_guard = g;
        let out = img.fixed(&p);
        let e: u64 = (0..h)
            .flat_map(|y| (32..w).map(move |x| (x, y)))
            .map(|(x, y)| out[img.at(x, y)] as u64)
            .sum();
        for y in 0..h {
            for x in 0..32 {
                assert_eq!(out[img.at(x, y)], 4000, "{g:?}: foreground changed");
            }
        }
        leak.push(e as f64 / (4000.0 * h as f64));
    }
    eprintln!(
        "depth edge: {sharp} in-focus pixels bit-identical; light leaked into the background, in foreground columns: difference {:.3}, tap_blur {:.3}, none {:.3}",
        leak[0], leak[1], leak[2]
    );
    assert!(leak[0] < leak[2] && leak[1] < leak[2], "{leak:?}");
}

/// A smooth frame (sinusoidal codes, at most 108 LSB per pixel) over a smooth depth ramp
/// through the focus.
fn smooth(w: usize, h: usize) -> Img {
    let mut img = Img::new(w, h, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let i = img.at(x, y);
            let t = (x as f64 * 0.06).sin() * (y as f64 * 0.045).cos();
            img.v[i] = (2048.0 + 1800.0 * t).round() as u32;
            img.k[i] = key(0.2 + 0.75 * (x + y) as f64 / (w + h) as f64);
        }
    }
    img
}

#[test]
fn fixed_is_within_a_stated_bound_of_float() {
    let p = params();
    // Smooth frame and depth: every tap's pixel and texel agree, the rest is rounding.
    let img = smooth(96, 64);
    let out = img.fixed(&p);
    let fl = img.float(&p);
    let d: Vec<f64> = out.iter().zip(&fl).map(|(&o, &f)| o as f64 - f).collect();
    let max = d.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let within = d.iter().filter(|x| x.abs() <= 0.5).count() as f64 / d.len() as f64;
    // The largest step between neighbouring pixels: a tap whose quantised position falls
    // on the other side of a pixel boundary than the exact one reads the neighbour, which
    // moves the mean of the 13 taps by at most step / 13.
    let step = (0..img.h)
        .flat_map(|y| (0..img.w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let v = img.v[img.at(x, y)] as f64;
            let r = img.v[img.at((x + 1).min(img.w - 1), y)] as f64;
            let b = img.v[img.at(x, (y + 1).min(img.h - 1))] as f64;
            (v - r).abs().max((v - b).abs())
        })
        .fold(0.0f64, f64::max);
    let bound = 2.0 * step / (p.downsample.taps + 1) as f64 + 1.0;
    // Random textured blocks: a tap on a pixel boundary may read the neighbour.
    let mut rng = Rng::new(0x7e57);
    let mut img = Img::new(96, 64, 0, 0);
    random_depths(&mut rng, &mut img, 6);
    for v in img.v.iter_mut() {
        *v = rng.range(0.0, 4096.0) as u32;
    }
    let out = img.fixed(&p);
    let fl = img.float(&p);
    let dr: Vec<f64> = out.iter().zip(&fl).map(|(&o, &f)| o as f64 - f).collect();
    let max_r = dr.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mean_r = dr.iter().map(|x| x.abs()).sum::<f64>() / dr.len() as f64;
    eprintln!(
        "fixed vs float: smooth max |d| {max:.3} LSB, {:.2} % within 0.5; random blocks max |d| {max_r:.1}, mean |d| {mean_r:.3}",
        100.0 * within
    );
    eprintln!("smooth: largest neighbour step {step} LSB, bound 2 step / 13 + 1 = {bound:.2}");
    assert!(max <= bound, "smooth: {max} > {bound}");
    assert!(within > 0.9, "smooth: {within}");
    assert!(mean_r < 4.0, "random: {mean_r}");
}

#[test]
fn a_frame_format_too_narrow_for_the_codes_overflows_counted_or_stops() {
    // Codes up to 4095 into a UQ8.0 frame: the small image's UQ8.<g> word cannot hold the
    // block averages. SAT counts and clamps; ERROR stops naming the signal.
    let narrow = QFormat::new(false, 8, 0);
    let mut img = Img::new(32, 24, 0, key_behind(2.0));
    for (i, v) in img.v.iter_mut().enumerate() {
        *v = if i % 3 == 0 { 4095 } else { 100 };
    }
    let mut p = params();
    p.overflow = Overflow::Sat;
    let plan = img.plan(&p);
    let (out, work) = downsample_fixed(&img.v, &img.k, &plan, &p, narrow).expect("SAT runs");
    eprintln!(
        "too narrow: dof.down.small {} overflows of {}, dof.down.out {}",
        work.small.overflows, work.small.count, work.out.overflows
    );
    assert!(work.small.overflows > 0);
    assert!(out.iter().all(|&o| o <= 255));
    // The same frame in its own format: none.
    let (_, ok) = downsample_fixed(&img.v, &img.k, &plan, &p, FRAME).unwrap();
    assert_eq!(ok.small.overflows + ok.blur.overflows + ok.out.overflows, 0);
    assert_eq!(ok.tap_overflows, 0);
    p.overflow = Overflow::Error;
    let e = downsample_fixed(&img.v, &img.k, &plan, &p, narrow).unwrap_err();
    assert_eq!(e.0, "dof.down.small");
    assert_eq!(e.1, QFormat::new(false, 8, p.downsample.guard_bits));
}

#[test]
fn poisson_taps_are_point_symmetric_inside_the_disc_and_spread() {
    for n in [2usize, 12, 32, 64] {
        let t = Poisson::new(n, 8);
        assert_eq!(t.points.len(), n + 1);
        assert_eq!(t.points[0], (0.0, 0.0));
        for k in 0..n / 2 {
            let (a, b) = (t.points[1 + 2 * k], t.points[2 + 2 * k]);
            assert_eq!((a.0, a.1), (-b.0, -b.1));
            let (ca, cb) = (t.codes[1 + 2 * k], t.codes[2 + 2 * k]);
            assert_eq!((ca.0, ca.1), (-cb.0, -cb.1));
            assert!(a.0.hypot(a.1) < 1.0);
        }
        // A deterministic design: the same set every time.
        assert_eq!(poisson_disc(n), t.points);
        assert!(
            t.min_distance > 0.8 / (n as f64 + 1.0).sqrt(),
            "{n}: {}",
            t.min_distance
        );
    }
}

fn hw_file(name: &str, body: &str) -> String {
    let dir = std::env::temp_dir().join(format!("igemu-down-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, body).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn render_default_and_cone_focus_on_the_command_line() {
    let hw = hw_file("down.toml", "[dof]\nkind = \"downsample\"\n");
    for scene in ["default", "cone-focus"] {
        let out = hw_file(&format!("{scene}.png"), "");
        let (code, stdout, stderr) =
            common::igemu(&["render", scene, "--hw", &hw, "-o", &out, "--no-local"]);
        assert_eq!(code, 0, "{scene}: {stderr}");
        assert!(
            stdout.contains("downsample by 4x4, Gaussian, blend by 12 Poisson-disc taps"),
            "{scene}: {stdout}"
        );
        assert!(stdout.contains("dof down blurred image"), "{stdout}");
    }
}

#[test]
fn both_scenes_through_the_library_compare_and_image_every_memory() {
    let mut hw = HwConfig::default_config();
    hw.dof.kind = DofKind::Downsample;
    let transient = [
        "dof down box accumulators",
        "dof down line buffers",
        "dof down blend window",
    ];
    for scene in ["default", "cone-focus"] {
        let s = Scene::embedded(scene).unwrap();
        let r = igemu::pipeline::render(&s, &hw, RunOptions::default()).unwrap();
        let step = r.steps.iter().find(|s| s.id == StageId::Dof).unwrap();
        let o = &step.outcome;
        let local = o.report.local.as_ref().expect("stage-local comparison");
        let ident = local.identical as f64 / local.values as f64;
        eprintln!(
            "{scene}: dof local identical {:.4} %, max {:.2} LSB, mean {:.4}; e2e identical {:.4} %",
            100.0 * ident,
            local.max_abs_lsb,
            local.mean_lsb,
            100.0 * r.dac.iter().zip(&r.dac_ref).filter(|(a, b)| a == b).count() as f64
                / r.dac.len() as f64
        );
        assert!(ident > 0.9, "{scene}: {ident}");
        assert!(local.mean_lsb.abs() < 0.05, "{scene}: {}", local.mean_lsb);
        let held: std::collections::BTreeSet<&str> = o
            .report
            .cost
            .memories
            .iter()
            .map(|m| m.name.as_str())
            .filter(|n| !transient.contains(n))
            .collect();
        let imaged: std::collections::BTreeSet<&str> =
            o.images.iter().map(|i| i.name.as_str()).collect();
        assert_eq!(held, imaged, "{scene}");
        assert!(o.packs.iter().all(|p| p.verified), "{scene}");
        let tokens = o.tokens.as_ref().expect("tokens");
        assert_eq!(tokens.kind, TokenKind::Row);
        assert_eq!(tokens.items.len(), 480);
        // No overflow on a real scene.
        assert!(o.report.signals.iter().all(|s| s.overflows == 0));
    }
}

#[test]
fn bad_downsample_fields_name_file_field_and_range() {
    use igemu::files::TomlFile;
    for (line, field, range) in [
        ("factor = 3", "dof.downsample.factor", "2, 4 or 8"),
        ("taps = 13", "dof.downsample.taps", "2..=64"),
        ("taps = 80", "dof.downsample.taps", "2..=64"),
        ("blend_bits = 40", "dof.downsample.blend_bits", "2..=16"),
        ("offset_bits = 1", "dof.downsample.offset_bits", "2..=16"),
        ("guard_bits = 17", "dof.downsample.guard_bits", "0..=16"),
        (
            "leak_guard = \"some\"",
            "dof.downsample.leak_guard",
            "`difference`, `tap_blur`, `none`",
        ),
    ] {
        let text = format!("[dof]\nkind = \"downsample\"\n[dof.downsample]\n{line}\n");
        let e = HwConfig::from_toml(&TomlFile::from_text("bad.toml", &text))
            .err()
            .unwrap_or_else(|| panic!("accepted: {line}"));
        assert_eq!(e.field, field, "{e}");
        let msg = e.to_string();
        assert!(msg.contains("bad.toml"), "{msg}");
        assert!(msg.contains(range), "{line}: {msg}");
    }
}

/// The cubic reconstructions (`dof.downsample.reconstruction`): flat fields stay bit
/// identical (each axis's four weights sum to exactly `2^bilinear_bits`), fixed against
/// float within the bilinear read's bound on the smooth frame, 16 texels per blurred sample
/// in the MACs, and on both scenes the local comparison, the weight ROM image and its pack
/// check; bilinear stays the default.
#[test]
fn cubic_reconstructions() {
    use igemu::config::Reconstruction;
    assert_eq!(params().downsample.reconstruction, Reconstruction::Bilinear);
    let mut rng = Rng::new(0xc0b1c);
    let smooth_img = smooth(96, 64);
    // The largest |fixed - float| on the smooth frame and the MACs.
    let smooth_run = |p: &DofCfg| {
        let plan = smooth_img.plan(p);
        let (out, work) = downsample_fixed(&smooth_img.v, &smooth_img.k, &plan, p, FRAME).unwrap();
        let fl = smooth_img.float(p);
        let max = out
            .iter()
            .zip(&fl)
            .fold(0.0f64, |m, (&o, &f)| m.max((o as f64 - f).abs()));
        (max, work.macs)
    };
    let bilinear = smooth_run(&params());
    for r in [
        Reconstruction::CubicBspline,
        Reconstruction::CatmullRom,
        Reconstruction::Mitchell,
    ] {
        let mut p = params();
        p.downsample.reconstruction = r;
        for &v in &[0u32, 1, 2047, 4095] {
            let mut img = Img::new(37, 23, v, 0);
            random_depths(&mut rng, &mut img, 3);
            assert!(img.fixed(&p).iter().all(|&o| o == v), "{r:?} code {v}");
            assert!(img.float(&p).iter().all(|&o| (o - v as f64).abs() < 1e-9));
        }
        let (max, macs) = smooth_run(&p);
        eprintln!(
            "{r:?}: smooth frame fixed vs float max {max:.3} LSB (bilinear {:.3}); MACs {macs} (bilinear {})",
            bilinear.0, bilinear.1
        );
        assert!(max <= bilinear.0 + 1.0, "{r:?}: {max}");
        assert!(macs > bilinear.1, "{r:?}: 16 texels");
        // Through the pipeline: the ROM is charged, imaged and packs.
        let mut hw = HwConfig::default_config();
        hw.dof = p.clone();
        let s = Scene::embedded("cone-focus").unwrap();
        let rr = igemu::pipeline::render(&s, &hw, RunOptions::default()).unwrap();
        let step = rr.steps.iter().find(|s| s.id == StageId::Dof).unwrap();
        let o = &step.outcome;
        assert!(
            o.images
                .iter()
                .any(|i| i.name == "dof down reconstruction ROM")
        );
        assert!(o.packs.iter().all(|p| p.verified), "{r:?}");
        let local = o.report.local.as_ref().unwrap();
        assert!(local.identical as f64 / local.values as f64 > 0.9, "{r:?}");
    }
}
