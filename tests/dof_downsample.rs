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
    let mut rng = Rng(0xf1a7);
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
    let mut rng = Rng(0x1f0c);
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
