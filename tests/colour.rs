//! The colour error metrics (`igemu::colour`): identical images, greys, a pair of reds
//! checked by hand, a saturated ramp at 5-6-5 against 8-8-8, per-channel DAC widths and a
//! proptest of the CIEDE2000 difference over any codes.

use igemu::colour::{ColourDisplay, RgbCodes, delta_e, delta_e_image, heat_colour, hue_shift};
use igemu::scene::Display;
use palette::Lab;
use palette::color_difference::Ciede2000;
use proptest::prelude::*;

/// An image of the owned planes `p`.
fn img(p: &[Vec<u16>; 3], bits: [u32; 3], width: u32, height: u32) -> RgbCodes<'_> {
    RgbCodes {
        planes: [&p[0], &p[1], &p[2]],
        bits,
        width,
        height,
    }
}

/// A `width x height` image whose ideal values (in `[0, 1]` of full scale) are `v(x, y)`,
/// quantised to `bits` by `q` (`f64::floor` truncates, `f64::round` rounds).
fn quantised(
    v: impl Fn(usize, usize) -> [f64; 3],
    bits: [u32; 3],
    (width, height): (usize, usize),
    q: fn(f64) -> f64,
) -> [Vec<u16>; 3] {
    [0, 1, 2].map(|c| {
        let max = ((1u32 << bits[c]) - 1) as f64;
        (0..width * height)
            .map(|i| q(v(i % width, i / width)[c] * max) as u16)
            .collect()
    })
}

/// The saturated red-orange ramp along x used by the width comparisons, `[0, 1]` of full
/// scale per channel.
fn ramp(x: usize, _y: usize) -> [f64; 3] {
    let t = x as f64 / 511.0;
    [0.35 + 0.35 * t, 0.10 + 0.12 * t, 0.06 + 0.03 * t]
}

/// CIELAB of linear sRGB by hand: the IEC 61966-2-1 matrix and the CIE 1976 formulas,
/// against the D65 white.
fn lab_by_hand([r, g, b]: [f64; 3]) -> [f64; 3] {
    let x = 0.4124564 * r + 0.3575761 * g + 0.1804375 * b;
    let y = 0.2126729 * r + 0.7151522 * g + 0.0721750 * b;
    let z = 0.0193339 * r + 0.1191920 * g + 0.9503041 * b;
    let f = |t: f64| {
        let e = 6.0f64 / 29.0;
        if t > e * e * e {
            t.cbrt()
        } else {
            t / (3.0 * e * e) + 4.0 / 29.0
        }
    };
    let (fx, fy, fz) = (f(x / 0.95047), f(y), f(z / 1.08883));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

#[test]
fn identical_images_give_zero() {
    let bits = [8, 8, 8];
    let p = quantised(ramp, bits, (512, 8), f64::round);
    let a = img(&p, bits, 512, 8);
    let d = ColourDisplay::new(&Display::default(), bits);
    let e = delta_e(&a, &a, &d);
    assert_eq!(e.pixels, 512 * 8);
    assert_eq!((e.mean, e.p99, e.max), (0.0, 0.0, 0.0));
    assert_eq!((e.over_1, e.over_jnd, e.over_jnd_ab), (0, 0, 0));
    assert!(e.map.iter().all(|&v| v == 0.0));
    let h = hue_shift(&a, &a, &d);
    // The ramp is smooth and chromatic, so its pixels are counted, each with no shift.
    assert_eq!(h.pixels, 512 * 8);
    assert_eq!((h.mean_deg, h.p99_deg, h.max_deg), (0.0, 0.0, 0.0));
}

#[test]
fn greys_have_no_hue() {
    let bits = [8, 8, 8];
    let grey = |x: usize, _: usize| [0.2 + 0.5 * x as f64 / 511.0; 3];
    let r = quantised(grey, bits, (512, 4), f64::round);
    let f = quantised(grey, bits, (512, 4), f64::floor);
    assert_ne!(r, f);
    let d = ColourDisplay::new(&Display::default(), bits);
    let (fi, ri) = (img(&f, bits, 512, 4), img(&r, bits, 512, 4));
    let h = hue_shift(&fi, &ri, &d);
    assert_eq!(h.smooth_pixels, 512 * 4, "the grey ramp is smooth");
    assert_eq!(h.pixels, 0, "a grey has no hue");
    assert_eq!(h.mean_deg, 0.0);
    assert!(
        delta_e(&fi, &ri, &d).mean > 0.0,
        "the lightness still differs"
    );
}

#[test]
fn a_pair_of_reds_checked_by_hand() {
    let bits = [8, 8, 8];
    let disp = Display::default();
    let d = ColourDisplay::new(&disp, bits);
    let (reference, fixed) = ([255u16, 0, 0], [255u16, 40, 0]);
    // Code to linear by hand: (B_min + (B_max - B_min) (c / 255)^gamma) / B_max.
    let k = disp.contrast;
    let lin = |c: [u16; 3]| c.map(|c| 1.0 / k + (1.0 - 1.0 / k) * (c as f64 / 255.0).powf(2.4));
    assert!(
        d.linear(fixed)
            .iter()
            .zip(lin(fixed))
            .all(|(a, b)| (a - b).abs() < 1e-12)
    );
    let (lr, lf) = (lab_by_hand(lin(reference)), lab_by_hand(lin(fixed)));
    let pl = d.lab(reference);
    assert!(
        (pl.l - lr[0]).abs() < 1e-3 && (pl.a - lr[1]).abs() < 1e-3 && (pl.b - lr[2]).abs() < 1e-3,
        "{pl:?} against {lr:?}"
    );
    // Pure red over a 1 % stray-light floor (K = 100): L* about 54, a* about 78, b* about 60
    // (less chroma than the ideal sRGB red's 53, 80, 67).
    assert!((lr[0] - 54.0).abs() < 1.0, "{lr:?}");
    assert!(
        (75.0..82.0).contains(&lr[1]) && (55.0..65.0).contains(&lr[2]),
        "{lr:?}"
    );
    let one = |c: [u16; 3]| [vec![c[0]], vec![c[1]], vec![c[2]]];
    let (pr, pf) = (one(reference), one(fixed));
    let (ri, fi) = (img(&pr, bits, 1, 1), img(&pf, bits, 1, 1));
    // The CIEDE2000 of the hand-made CIELAB values, as palette computes it.
    let expect = Lab::<palette::white_point::D65, f64>::new(lf[0], lf[1], lf[2])
        .difference(Lab::new(lr[0], lr[1], lr[2]));
    let e = delta_e(&fi, &ri, &d);
    assert!(
        (e.mean - expect).abs() < 1e-3,
        "{} against {expect}",
        e.mean
    );
    assert!((e.max - e.mean).abs() < 1e-5);
    assert!(e.mean > 0.1 && e.mean < 5.0, "{}", e.mean);
    // The hue angles by hand: atan2(b*, a*); green moves red towards yellow.
    let hue = |l: [f64; 3]| l[2].atan2(l[1]).to_degrees();
    let shift = (hue(lf) - hue(lr)).abs();
    assert!(hue(lf) > hue(lr));
    let h = hue_shift(&fi, &ri, &d);
    assert_eq!(h.pixels, 1);
    assert!(
        (h.mean_deg - shift).abs() < 0.01,
        "{} against {shift}",
        h.mean_deg
    );
    assert_eq!(h.max_deg, h.mean_deg);
    assert_eq!(h.p99_deg, h.mean_deg);
    // And the other way round: the same angle, the difference symmetric.
    let back = hue_shift(&ri, &fi, &d);
    assert!((back.mean_deg - h.mean_deg).abs() < 1e-4);
    assert!((delta_e(&ri, &fi, &d).mean - e.mean).abs() < 1e-9);
}

#[test]
fn a_565_ramp_shifts_hue_more_than_888() {
    let disp = Display::default();
    let measure = |bits: [u32; 3]| {
        let f = quantised(ramp, bits, (512, 8), f64::floor);
        let r = quantised(ramp, bits, (512, 8), f64::round);
        let d = ColourDisplay::new(&disp, bits);
        let (fi, ri) = (img(&f, bits, 512, 8), img(&r, bits, 512, 8));
        (delta_e(&fi, &ri, &d), hue_shift(&fi, &ri, &d))
    };
    let (e565, h565) = measure([5, 6, 5]);
    let (e888, h888) = measure([8, 8, 8]);
    // The ramp is smooth and chromatic at both widths.
    assert_eq!(h565.pixels, 512 * 8);
    assert_eq!(h888.pixels, 512 * 8);
    assert!(h565.mean_deg > 0.0 && e565.mean > 0.0);
    // Mean, 99th percentile and maximum: the narrow words at least double the mean.
    for (what, narrow, wide) in [
        (
            "hue shift, deg",
            [h565.mean_deg, h565.p99_deg, h565.max_deg],
            [h888.mean_deg, h888.p99_deg, h888.max_deg],
        ),
        (
            "Delta E_00",
            [e565.mean, e565.p99, e565.max],
            [e888.mean, e888.p99, e888.max],
        ),
    ] {
        assert!(
            narrow[0] > 2.0 * wide[0],
            "{what}: 5-6-5 {narrow:?}, 8-8-8 {wide:?}"
        );
        assert!(
            narrow[1] > wide[1] && narrow[2] > wide[2],
            "{what}: {narrow:?} {wide:?}"
        );
        assert!(
            narrow[0] <= narrow[1] && narrow[1] <= narrow[2],
            "{what}: {narrow:?}"
        );
    }
    assert!(e565.over_1 > e888.over_1);
    // The heat map paints it: 3 bytes a pixel, black where the codes agree.
    let heat = delta_e_image(&e565.map, 512, 8);
    assert_eq!(heat.len(), 3 * 512 * 8);
    let zero = e565
        .map
        .iter()
        .position(|&v| v == 0.0)
        .expect("a pixel that agrees");
    assert_eq!(heat[3 * zero..3 * zero + 3], [0, 0, 0]);
    let top = e565
        .map
        .iter()
        .position(|&v| f64::from(v) == e565.max)
        .unwrap();
    assert_eq!(heat[3 * top..3 * top + 3], heat_colour(e565.max as f32));
    assert_ne!(heat_colour(e565.max as f32), [0, 0, 0]);
}

#[test]
fn per_channel_dac_widths() {
    let disp = Display::default();
    let d = ColourDisplay::new(&disp, [5, 6, 5]);
    assert_eq!(d.bits(), [5, 6, 5]);
    assert_eq!([0, 1, 2].map(|c| d.channel(c).max_code), [31.0, 63.0, 31.0]);
    for v in d.linear([31, 63, 31]) {
        assert!((v - 1.0).abs() < 1e-12, "{v}");
    }
    let w = d.lab([31, 63, 31]);
    assert!((w.l - 100.0).abs() < 1e-9 && w.a.abs() < 1e-9 && w.b.abs() < 1e-9);
    // Code 31 of the 6-bit green is about half scale, not full.
    let g = d.linear([31, 31, 31]);
    assert_eq!(g[0], 1.0f64.min(g[0]));
    assert!(g[1] < 0.25 && g[1] > 0.15, "{g:?}");
    assert_eq!(g[0], g[2]);
    // One green code below white is a small, non-zero difference.
    let (r, f) = (
        [vec![31u16], vec![63], vec![31]],
        [vec![31u16], vec![62], vec![31]],
    );
    let e = delta_e(&img(&f, [5, 6, 5], 1, 1), &img(&r, [5, 6, 5], 1, 1), &d);
    let expect = d.lab([31, 62, 31]).difference(d.lab([31, 63, 31]));
    assert!(e.mean > 0.0 && (e.mean - expect).abs() < 1e-12);
}

#[test]
#[should_panic(expected = "DAC widths")]
fn codes_of_another_width_are_refused() {
    let d = ColourDisplay::new(&Display::default(), [5, 6, 5]);
    let p = [vec![1u16], vec![1], vec![1]];
    let a = img(&p, [8, 8, 8], 1, 1);
    delta_e(&a, &a, &d);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn delta_e_is_finite_symmetric_and_zero_only_for_equal_codes(
        bits in prop::array::uniform3(1u32..=16),
        a in prop::collection::vec(prop::array::uniform3(any::<u16>()), 6),
        b in prop::collection::vec(prop::array::uniform3(any::<u16>()), 6),
        same in prop::collection::vec(any::<bool>(), 6),
    ) {
        let mask = |p: [u16; 3]| [0, 1, 2].map(|c| p[c] & ((1u32 << bits[c]) - 1) as u16);
        let pa: Vec<[u16; 3]> = a.into_iter().map(mask).collect();
        let pb: Vec<[u16; 3]> = b
            .into_iter()
            .zip(&pa)
            .zip(&same)
            .map(|((b, &a), &s)| if s { a } else { mask(b) })
            .collect();
        let planes = |p: &[[u16; 3]]| [0, 1, 2].map(|c| p.iter().map(|v| v[c]).collect::<Vec<_>>());
        let (qa, qb) = (planes(&pa), planes(&pb));
        let (ia, ib) = (img(&qa, bits, 3, 2), img(&qb, bits, 3, 2));
        let d = ColourDisplay::new(&Display::default(), bits);
        let ab = delta_e(&ia, &ib, &d);
        let ba = delta_e(&ib, &ia, &d);
        for i in 0..6 {
            let (x, y) = (ab.map[i], ba.map[i]);
            prop_assert!(x.is_finite() && x >= 0.0, "{x}");
            prop_assert_eq!(x == 0.0, pa[i] == pb[i], "pixel {} {:?} {:?}: {}", i, pa[i], pb[i], x);
            prop_assert!((x - y).abs() <= 1e-4 * x.max(1.0), "{} against {}", x, y);
        }
        prop_assert!(ab.mean.is_finite() && ab.max.is_finite() && ab.p99 <= ab.max);
        let h = hue_shift(&ia, &ib, &d);
        prop_assert!(h.mean_deg.is_finite() && (0.0..=180.0).contains(&h.max_deg));
    }
}
