//! `dof.kind = "luminance"`: the luminance-aware datapath (docs/dof-luminance.md). Flat
//! fields, a bright point, a depth edge, fixed against float, overflow, the rounded divide
//! and the alpha ROM. The whole render, cost and command line: tests/dof_luminance_run.rs.
//! Figures are printed with `--nocapture`.

mod common;

use common::Rng;
use igemu::config::{HwConfig, LuminanceCfg, SigmaForm};
use igemu::error::Error;
use igemu::fixed::{Overflow, QFormat, Quant};
use igemu::scene::{Lens, Scene};
use igemu::stage::dof::LensMap;
use igemu::stage::dof::luminance::{
    AlphaMap, LumParams, LumWork, bleed_f64, bleed_fixed, div_round, luminance_f64,
    luminance_fixed, pre_blur_f64, pre_blur_fixed,
};
use proptest::prelude::*;

const FRAME: QFormat = QFormat::new(false, 12, 0);
const Z_BITS: u32 = 24;

/// The datapath of the default configuration on a 12-bit frame, pre-blur radius `r`.
fn params(r: u32) -> LumParams {
    let mut d = HwConfig::default_config().dof;
    d.luminance.radius = r;
    LumParams::of(&d, FRAME)
}

/// The lens of a scene as the dof stage builds it (24-bit depth codes) with sigma form
/// `form` and the default sigma ROM.
fn lens_with(s: &Scene, form: SigmaForm) -> LensMap {
    let bits = HwConfig::default_config().dof.sigma_rom_bits;
    LensMap::from_camera(&s.camera, s.image.height, Z_BITS, form, bits).expect("a thin lens")
}

/// The lens of a scene with the default (paper) sigma form.
fn lens_of(s: &Scene) -> LensMap {
    lens_with(s, SigmaForm::Paper)
}

fn cone_focus() -> Scene {
    Scene::embedded("cone-focus").expect("embedded")
}

/// The depth code of screen z.
fn key(z: f64) -> u32 {
    (z * (1u64 << Z_BITS) as f64).round() as u32
}

/// A depth code in the lens's in-focus band, a twentieth of its width inside the near edge
/// (where alpha is near its largest in the band).
fn in_band_key(l: &LensMap) -> u32 {
    key(l.z_near_edge + (l.z_far_edge - l.z_near_edge) / 20.0)
}

fn run(value: &[u32], alpha: &[u32], w: usize, h: usize, p: &LumParams) -> Vec<u32> {
    luminance_fixed(value, alpha, w, h, p)
        .expect("no ERROR overflow")
        .0
}

/// Random depth codes: a third at infinity, the rest anywhere in [0, 1).
fn random_keys(rng: &mut Rng, n: usize) -> Vec<u32> {
    (0..n)
        .map(|_| {
            if rng.next_u64().is_multiple_of(3) {
                u32::MAX
            } else {
                (rng.next_u64() % (1 << Z_BITS)) as u32
            }
        })
        .collect()
}

/// A flat field through the fixed model and the float reference at the given frame width,
/// pre-blur radius, guard bits, rounding, depths (with the lens of `form`) and alpha widths:
/// both return the field unchanged. The pre-blur sum is given the bits it needs.
#[allow(clippy::too_many_arguments)]
fn check_flat(
    form: SigmaForm,
    scene: &Scene,
    bits: u32,
    code: u32,
    r: u32,
    g: u32,
    q: Quant,
    (alpha_bits, rom_bits): (u32, u32),
    keys: &[u32],
    (w, h): (usize, usize),
) -> Result<(), TestCaseError> {
    let lens = lens_with(scene, form);
    let cfg = LuminanceCfg {
        radius: r,
        alpha_bits,
        alpha_rom_bits: rom_bits,
        ..LuminanceCfg::default()
    };
    let alpha = AlphaMap::new(&lens, &cfg);
    let a: Vec<u32> = keys.iter().map(|&k| alpha.code(k)).collect();
    let count = (2 * r + 1) * (2 * r + 1);
    let p = LumParams {
        radius: r,
        pre_bits: bits + (32 - count.leading_zeros()),
        guard_bits: g,
        alpha_bits,
        quant: q,
        overflow: Overflow::Error,
        frame: QFormat::new(false, bits, 0),
    };
    let v = vec![code; w * h];
    let (out, work) = luminance_fixed(&v, &a, w, h, &p).expect("the sum fits");
    prop_assert_eq!(&out, &v, "{:?} r={} g={} {:?} {}x{}", form, r, g, q, w, h);
    prop_assert_eq!(work.bleeding, 0);
    prop_assert_eq!(work.pre.overflows + work.out.overflows, 0);
    let vf = vec![f64::from(code); w * h];
    let af: Vec<f64> = keys.iter().map(|&k| alpha.alpha_f64(&lens, k)).collect();
    let f = luminance_f64(&vf, &af, w, h, r as usize);
    prop_assert!(f.iter().all(|&o| o == f64::from(code)));
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Flat fields are bit-identical for any code of any frame width, any depth image (a
    /// third of the pixels at infinity: the method reads no coverage, so partly covered
    /// pixels are codes like any other), both sigma forms, both Fig. 3 lenses, any radius,
    /// guard bits, rounding and alpha widths, any frame shape (1 x 1 and thin lines too).
    #[test]
    fn flat_field_is_bit_identical(
        paper in any::<bool>(), cone in any::<bool>(), bits in 1u32..17, code_seed in any::<u64>(),
        r in 0u32..5, g in 0u32..17, q in 0usize..7, ab in 2u32..17, rb in 2u32..17,
        w in 1usize..14, h in 1usize..14, seed in any::<u64>(),
    ) {
        let form = if paper { SigmaForm::Paper } else { SigmaForm::Affine };
        let scene = if cone { cone_focus() } else { Scene::default_scene() };
        // The extremes as often as the rest.
        let max = (1u64 << bits) - 1;
        let code = match code_seed % 4 { 0 => 0, 1 => max, _ => code_seed % (max + 1) } as u32;
        let keys = random_keys(&mut Rng::new(seed), w * h);
        check_flat(form, &scene, bits, code, r, g, Quant::ALL[q], (ab, rb), &keys, (w, h))?;
    }
}

#[test]
fn flat_field_corner_cases_are_bit_identical() {
    // The largest 16-bit code, with a pre-blur window larger than the frame, at every
    // rounding, both forms, with all pixels at infinity and all in the focus band.
    let scene = cone_focus();
    let lens = lens_of(&scene);
    for form in [SigmaForm::Paper, SigmaForm::Affine] {
        for q in Quant::ALL {
            for keys in [vec![u32::MAX; 15], vec![in_band_key(&lens); 15]] {
                for (w, h) in [(15, 1), (1, 15), (5, 3)] {
                    check_flat(form, &scene, 16, 65535, 8, 16, q, (16, 16), &keys, (w, h)).unwrap();
                }
            }
        }
    }
}

/// The 8 symmetries of the square applied to `(x, y)` in an `n x n` image.
fn d4(k: usize, x: usize, y: usize, n: usize) -> (usize, usize) {
    let (x, y) = if k & 4 != 0 { (y, x) } else { (x, y) };
    let x = if k & 1 != 0 { n - 1 - x } else { x };
    let y = if k & 2 != 0 { n - 1 - y } else { y };
    (x, y)
}

#[test]
fn bright_point_bleeds_only_into_darker_neighbours() {
    const N: usize = 15;
    let (dark, bright, c) = (200u32, 4000u32, N / 2);
    let mut v = vec![dark; N * N];
    v[c * N + c] = bright;
    let one = 1u32 << params(1).alpha_bits;
    for r in 0..=2u32 {
        let p = params(r);
        let out = run(&v, &vec![one; N * N], N, N, &p);
        // Symmetric, bounded by the point and the background.
        for k in 0..8 {
            for y in 0..N {
                for x in 0..N {
                    let (xx, yy) = d4(k, x, y, N);
                    assert_eq!(out[y * N + x], out[yy * N + xx]);
                }
            }
        }
        assert!(out.iter().all(|&o| (dark..=bright).contains(&o)));
        // The bleed only takes from brighter neighbours: it never darkens the pre-blurred
        // image and never goes above the brightest neighbour.
        let mut work = LumWork::new(&p);
        let pre = pre_blur_fixed(&v, N, N, &p, &mut work).unwrap();
        let blur = bleed_fixed(&pre, N, N, &p, &mut work);
        for y in 0..N {
            for x in 0..N {
                let i = y * N + x;
                let hi = (0..9)
                    .filter_map(|k| {
                        let (xx, yy) = ((x + k % 3).checked_sub(1)?, (y + k / 3).checked_sub(1)?);
                        (xx < N && yy < N).then(|| pre[yy * N + xx])
                    })
                    .max()
                    .unwrap();
                assert!(blur[i] >= pre[i] && blur[i] <= hi, "r={r} ({x},{y})");
            }
        }
        // Changed pixels: exactly those within r + 1 of the point.
        let reach = r as usize + 1;
        let mut extra = 0i64;
        for y in 0..N {
            for x in 0..N {
                let d = x.abs_diff(c).max(y.abs_diff(c));
                let o = out[y * N + x];
                assert_eq!(o != dark, d <= reach, "r={r} ({x},{y}) = {o}");
                extra += o as i64 - dark as i64;
            }
        }
        let side = 2 * reach + 1;
        println!(
            "bright point (r = {r}): a {side}x{side} square of {}, the point's excess light x {:.2}",
            out[c * N + c],
            extra as f64 / (bright - dark) as f64
        );
        // r = 1: the point's window mean (4000 + 8 x 200) / 9 = 622.2 spreads over 5x5.
        if r == 1 {
            assert!(out.iter().all(|&o| o == dark || o == 622));
        }
    }
    // In focus (alpha = 0) nothing changes.
    assert_eq!(run(&v, &vec![0; N * N], N, N, &params(1)), v);
    // The point in focus over a blurred background: it keeps its value, the background
    // takes its light.
    let mut a = vec![one; N * N];
    a[c * N + c] = 0;
    let out = run(&v, &a, N, N, &params(1));
    assert_eq!(out[c * N + c], bright);
    assert_eq!(out[c * N + c + 1], 622);
    assert_eq!(out[c * N + c + 3], dark);
}

#[test]
fn depth_edge_in_focus_object_changes_by_at_most_its_scaled_alpha_share() {
    // A sharp object (left, in the band near its edge) next to a background at infinity,
    // brighter than the background and darker than it.
    let lens = lens_of(&cone_focus());
    let cfg = LuminanceCfg::default();
    let alpha = AlphaMap::new(&lens, &cfg);
    let (w, h, edge) = (32usize, 12usize, 16usize);
    let ko = in_band_key(&lens);
    let keys: Vec<u32> = (0..w * h)
        .map(|i| if i % w < edge { ko } else { u32::MAX })
        .collect();
    let a: Vec<u32> = keys.iter().map(|&k| alpha.code(k)).collect();
    let p = params(cfg.radius);
    let one = f64::from(alpha.one());
    let (a_obj, a_bg) = (
        f64::from(alpha.code(ko)) / one,
        f64::from(alpha.code(u32::MAX)) / one,
    );
    // The object's alpha is the band's: at most focus_scale x the edge's C / C_max.
    let band_max = cfg.focus_scale * alpha.c_far_edge.max(alpha.c_near_edge) / alpha.c_max;
    assert!(
        a_obj > 0.0 && a_obj <= band_max + 0.5 / one,
        "{a_obj} > {band_max}"
    );
    let g = f64::from(1u32 << p.guard_bits);
    let reach = cfg.radius as usize + 1;
    for (obj, bg) in [(3000u32, 500u32), (500, 3000)] {
        let v: Vec<u32> = keys
            .iter()
            .map(|&k| if k == u32::MAX { bg } else { obj })
            .collect();
        let out = run(&v, &a, w, h, &p);
        let mut work = LumWork::new(&p);
        let pre = pre_blur_fixed(&v, w, h, &p, &mut work).unwrap();
        let blur = bleed_fixed(&pre, w, h, &p, &mut work);
        let (mut obj_max, mut bg_max) = (0i64, 0i64);
        for i in 0..w * h {
            let x = i % w;
            let d = out[i] as i64 - v[i] as i64;
            if x < edge {
                let share = a_obj * (blur[i] as f64 / g - v[i] as f64).abs();
                assert!(
                    d.abs() as f64 <= share + 0.5,
                    "pixel {x}: {d} > {share} + 0.5"
                );
                obj_max = if d.abs() > obj_max.abs() { d } else { obj_max };
            } else {
                assert!(d.abs() as f64 <= a_bg * obj.abs_diff(bg) as f64 + 0.5);
                bg_max = if d.abs() > bg_max.abs() { d } else { bg_max };
            }
            // Beyond the method's reach of the edge nothing changes.
            if x + reach < edge || x >= edge + reach {
                assert_eq!(out[i], v[i], "pixel {x}");
            }
        }
        if obj > bg {
            // The bright object's edge pixels have brighter neighbours inside the object:
            // the bleed gives them back the object's value, so the object does not change;
            // the method does not look at depth, so the in-focus object's light leaks into
            // the blurred background by the background's alpha.
            assert_eq!(obj_max, 0);
            assert!(bg_max > 0);
        } else {
            // The dark object's edge takes the bright background's light by its own (band)
            // alpha; the bright side never changes: its edge pixels take their brighter
            // neighbours' value back.
            assert!(obj_max > 0);
            assert_eq!(bg_max, 0);
        }
        println!(
            "depth edge, object {obj} in the band (alpha {a_obj:.4}, band limit {band_max:.4}) \
             beside background {bg} (alpha {a_bg:.4}): object pixels change by at most {obj_max:+} \
             LSB, background pixels by {bg_max:+} LSB"
        );
    }
}

/// Rounding error bound of one rounding with mode `q`, in units of the result's LSB.
fn unit(q: Quant) -> f64 {
    if matches!(q, Quant::Trn | Quant::TrnZero) {
        1.0
    } else {
        0.5
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// The stated bound (docs/dof-luminance.md): with `u` the rounding unit of `quant`,
    /// `|fixed - float| <= u + |a - alpha| |blur - x| + a 22 u 2^-g` per pixel, `a` the ROM
    /// alpha, `alpha` the exact one, `blur` the float bleed (the pre-blur mean and the bleed
    /// divide each round once, and the bleed is 21-Lipschitz in the pre-blurred values).
    #[test]
    fn fixed_matches_float_within_the_stated_bound(
        w in 1usize..12, h in 1usize..12, r in 0u32..4, g in 0u32..7, b in 2u32..13,
        rom in 2u32..14, q in 0usize..7, bits in 4u32..13, seed in any::<u64>(),
    ) {
        let lens = lens_of(&Scene::default_scene());
        let cfg = LuminanceCfg { alpha_bits: b, alpha_rom_bits: rom, ..LuminanceCfg::default() };
        let alpha = AlphaMap::new(&lens, &cfg);
        let frame = QFormat::new(false, bits, 0);
        let quant = Quant::ALL[q];
        let p = LumParams { radius: r, pre_bits: 48, guard_bits: g, alpha_bits: b, quant,
            overflow: Overflow::Error, frame };
        let mut rng = Rng::new(seed);
        let v: Vec<u32> = (0..w * h).map(|_| (rng.next_u64() % (1 << bits)) as u32).collect();
        let keys = random_keys(&mut rng, w * h);
        let a: Vec<u32> = keys.iter().map(|&k| alpha.code(k)).collect();
        let (out, work) = luminance_fixed(&v, &a, w, h, &p).unwrap();
        prop_assert_eq!(&luminance_fixed(&v, &a, w, h, &p).unwrap().0, &out);
        prop_assert_eq!(work.out.overflows, 0);
        let vf: Vec<f64> = v.iter().map(|&x| x as f64).collect();
        let af: Vec<f64> = keys.iter().map(|&k| alpha.alpha_f64(&lens, k)).collect();
        let f = luminance_f64(&vf, &af, w, h, r as usize);
        let blur = bleed_f64(&pre_blur_f64(&vf, w, h, r as usize), w, h);
        let u = unit(quant);
        let one = (1u64 << b) as f64;
        for i in 0..w * h {
            let aq = a[i] as f64 / one;
            let bound = u + (aq - af[i]).abs() * (blur[i] - vf[i]).abs()
                + aq * 22.0 * u / (1u64 << g) as f64 + 1e-9;
            prop_assert!((out[i] as f64 - f[i]).abs() <= bound,
                "pixel {}: fixed {} float {} bound {}", i, out[i], f[i], bound);
            prop_assert!(out[i] < 1 << bits);
        }
    }
}

#[test]
fn fixed_vs_float_measured_on_random_frames() {
    // The default configuration (RND_CONV, g = 4) with alpha given exactly: the stated bound
    // is 0.5 + a 22 x 0.5 / 16 LSB; print what is reached.
    let mut rng = Rng::new(0xf1_0a7);
    let p = params(1);
    let one = f64::from(1u32 << p.alpha_bits);
    let (mut worst, mut worst_bleed) = (0.0f64, 0.0f64);
    for _ in 0..40 {
        let (w, h) = (24, 16);
        let v: Vec<u32> = (0..w * h).map(|_| (rng.next_u64() % 4096) as u32).collect();
        let a: Vec<u32> = (0..w * h)
            .map(|_| (rng.next_u64() % (one as u64 + 1)) as u32)
            .collect();
        let out = run(&v, &a, w, h, &p);
        let vf: Vec<f64> = v.iter().map(|&x| x as f64).collect();
        let af: Vec<f64> = a.iter().map(|&x| x as f64 / one).collect();
        let f = luminance_f64(&vf, &af, w, h, 1);
        let mut work = LumWork::new(&p);
        let pre = pre_blur_fixed(&v, w, h, &p, &mut work).unwrap();
        let bq = bleed_fixed(&pre, w, h, &p, &mut work);
        let bf = bleed_f64(&pre_blur_f64(&vf, w, h, 1), w, h);
        for i in 0..w * h {
            worst = worst.max((out[i] as f64 - f[i]).abs());
            worst_bleed = worst_bleed.max((bq[i] as f64 / 16.0 - bf[i]).abs());
        }
    }
    let bound = 0.5 + 22.0 * 0.5 / 16.0;
    assert!(worst <= bound, "{worst}");
    println!(
        "random 24x16 frames, default widths: max |fixed - float| {worst:.3} LSB (bound \
         {bound:.3}); bleed result max error {worst_bleed:.4} LSB (bound {:.4})",
        22.0 * 0.5 / 16.0
    );
}

#[test]
fn rounded_divide_matches_every_mode() {
    for q in Quant::ALL {
        for d in 1u128..40 {
            for n in 0u128..200 {
                let fl = n / d;
                // Compare n/d with fl + 1/2 exactly: 2n vs (2 fl + 1) d.
                let (two_n, mid) = (2 * n, (2 * fl + 1) * d);
                let want = match q {
                    _ if n % d == 0 => fl,
                    Quant::Trn | Quant::TrnZero => fl,
                    _ if two_n < mid => fl,
                    _ if two_n > mid => fl + 1,
                    Quant::Rnd | Quant::RndInf => fl + 1,
                    Quant::RndZero | Quant::RndMinInf => fl,
                    Quant::RndConv => fl + (fl & 1),
                };
                assert_eq!(div_round(n, d, q), want, "{n}/{d} {q:?}");
            }
        }
    }
}

#[test]
fn pre_blur_sum_overflow_saturates_and_counts_or_stops() {
    let (w, h) = (8, 6);
    let v = vec![4095u32; w * h];
    let a = vec![1u32 << 10; w * h];
    // A full 3x3 window of 4095 sums to 36855 > 2^15 - 1.
    let p = LumParams {
        pre_bits: 15,
        ..params(1)
    };
    let (out, work) = luminance_fixed(&v, &a, w, h, &p).unwrap();
    let interior = (w - 2) * (h - 2);
    assert_eq!(work.pre.overflows, interior as u64);
    assert!(out.iter().all(|&o| o <= 4095));
    assert!(out.iter().any(|&o| o < 4095));
    let p = LumParams {
        overflow: Overflow::Error,
        ..p
    };
    match luminance_fixed(&v, &a, w, h, &p) {
        Err(Error::Overflow { signal, format, .. }) => {
            assert_eq!(signal, "dof.lum.pre");
            assert_eq!(format, "UQ15.0");
        }
        other => panic!("{:?}", other.map(|x| x.0)),
    }
    // 16 bits hold it.
    let p = LumParams {
        pre_bits: 16,
        ..params(1)
    };
    let (out, work) = luminance_fixed(&v, &a, w, h, &p).unwrap();
    assert_eq!(work.pre.overflows, 0);
    assert!(out.iter().all(|&o| o == 4095));
}

/// The ROM entry of `i` computed here from the lens's circles of confusion (independently
/// of `AlphaMap`'s own formula code).
fn entry_by_formula(l: &LensMap, cfg: &LuminanceCfg, index_bits: u32, i: usize) -> u32 {
    let k = if i == 1 << index_bits {
        u32::MAX
    } else {
        let s = l.z_frac - index_bits;
        ((i as u64) << s | if s == 0 { 0 } else { 1 << (s - 1) }) as u32
    };
    let c_max = l.coc_f64(0).max(l.coc_f64(1 << l.z_frac));
    let z = l.z_of(k);
    let factor = if z >= l.z_near_edge && z <= l.z_far_edge {
        cfg.focus_scale
    } else {
        let ze = if z > l.z_far_edge {
            l.z_far_edge
        } else {
            l.z_near_edge
        };
        let ce = l.coc_f64(key(ze));
        let t = if cfg.ramp > 0.0 {
            ((l.coc_f64(k) - ce) / cfg.ramp).clamp(0.0, 1.0)
        } else {
            1.0
        };
        cfg.focus_scale + (1.0 - cfg.focus_scale) * t
    };
    let a = (l.coc_f64(k) / c_max).min(1.0) * factor;
    (a * (1u64 << cfg.alpha_bits) as f64 + 0.5).floor() as u32
}

#[test]
fn alpha_rom_entries_follow_the_formula() {
    for scene in [Scene::default_scene(), cone_focus()] {
        let l = lens_of(&scene);
        for cfg in [
            LuminanceCfg::default(),
            LuminanceCfg {
                ramp: 0.0,
                alpha_rom_bits: 6,
                alpha_bits: 6,
                ..LuminanceCfg::default()
            },
        ] {
            let a = AlphaMap::new(&l, &cfg);
            assert_eq!(a.rom.len(), (1 << cfg.alpha_rom_bits) + 1);
            for (i, &e) in a.rom.iter().enumerate() {
                assert_eq!(e, entry_by_formula(&l, &cfg, a.index_bits, i), "{i}");
                assert!(e <= a.one());
            }
            assert_eq!(a.index(u32::MAX), a.rom.len() - 1);
            assert_eq!(a.index((1 << Z_BITS) - 1), a.rom.len() - 2);
            // Non-decreasing away from the focus (screen z where 1/D = 1/U) on both sides.
            let z_focus = (l.inv_near - l.inv_focus) / (l.inv_near - l.inv_far);
            let focus = a.index(key(z_focus));
            let finite = &a.rom[..a.rom.len() - 1];
            assert!(finite[focus..].windows(2).all(|p| p[0] <= p[1]));
            assert!(finite[..=focus].windows(2).all(|p| p[0] >= p[1]));
            // The largest step: small with the ramp; at the band edge without it.
            let step = finite.windows(2).map(|p| p[0].abs_diff(p[1])).max();
            println!(
                "{}: C_max {:.2} px, alpha of infinity {:.4}, band edge C {:.3}/{:.3} px, \
                 ramp {} px: largest step between entries {} of {}",
                scene.name,
                a.c_max,
                f64::from(a.rom[a.rom.len() - 1]) / f64::from(a.one()),
                a.c_near_edge,
                a.c_far_edge,
                cfg.ramp,
                step.unwrap(),
                a.one()
            );
        }
    }
    // A focus close to the near plane: the background's C exceeds C_max, alpha = 1 exactly.
    let mut s = Scene::default_scene();
    s.camera.lens = Lens::ThinLens {
        focal_length: 0.02,
        lens_radius: 0.06,
        focus_distance: 3.0,
        deep: 0.2,
        coc: 0.000035,
    };
    let a = AlphaMap::new(&lens_of(&s), &LuminanceCfg::default());
    assert_eq!(a.code(u32::MAX), a.one());
    // A depth code narrower than the ROM's index: every code has its own entry.
    let mut l = lens_of(&Scene::default_scene());
    l.z_frac = 8;
    let a = AlphaMap::new(&l, &LuminanceCfg::default());
    assert_eq!((a.index_bits, a.rom.len()), (8, 257));
    assert_eq!(a.index(200), 200);
}
