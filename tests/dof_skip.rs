//! The layered DoF's uniform-window skip (docs/dof.md, "Uniform windows"): the fast
//! computation (`Exec::SkipUniform`, and in strips of rows `Exec::Strips`, the default)
//! against every tap computed (`Exec::Full`),
//! fixed and float, bit for bit with the same work counts, on the embedded scenes, the depth
//! ramp and random depth images; and the hardware option `dof.skip_uniform_tiles`.

mod common;

use igemu::config::{DofCfg, HwConfig};
use igemu::fixed::{Overflow, QFormat};
use igemu::pipeline;
use igemu::scene::Scene;
use igemu::stage::dof::{
    DepthImage, Exec, LayerPlan, LensMap, STRIP_ROWS, layered_f64_exec, layered_fixed_exec,
    plan_layers,
};
use igemu::stage::{RunOptions, StageId};
use proptest::prelude::*;

const FRAME: QFormat = QFormat::new(false, 12, 0);

/// Both executions of the fixed and float layered DoF agree bit for bit (outputs, work
/// counts, skipped tiles, overflow errors). Returns the fast run's work and skipped tiles.
fn check(img: &DepthImage<u32>, plan: &LayerPlan, p: &DofCfg, fmt: QFormat) -> Option<u64> {
    let full = layered_fixed_exec(
        img,
        plan,
        p,
        fmt,
        Exec::Full,
        |_| {},
        &igemu::stage::Pool::new(),
    );
    let fast = layered_fixed_exec(
        img,
        plan,
        p,
        fmt,
        Exec::SkipUniform,
        |_| {},
        &igemu::stage::Pool::new(),
    );
    assert_eq!(full, fast, "fixed layered: skip vs full");
    for rows in [16, STRIP_ROWS] {
        let strips = layered_fixed_exec(
            img,
            plan,
            p,
            fmt,
            Exec::Strips(rows),
            |_| {},
            &igemu::stage::Pool::new(),
        );
        assert_eq!(full, strips, "fixed layered: strips of {rows} rows vs full");
    }
    let vf: Vec<f64> = img.value.iter().map(|&v| v as f64 * 0.37).collect();
    let fi = DepthImage {
        value: &vf[..],
        width: img.width,
        height: img.height,
        key: img.key,
        cov: img.cov,
        n2: img.n2,
    };
    let a = layered_f64_exec(&fi, plan, Exec::Full);
    let b = layered_f64_exec(&fi, plan, Exec::SkipUniform);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&a), bits(&b), "float layered: skip vs full");
    fast.ok().map(|r| r.1.skipped_tiles)
}

/// The fixed frame of a scene (after accumulate) and its lens.
fn scene_frame(scene: &Scene, hw: &HwConfig) -> (igemu::stage::accumulate::Frame, LensMap) {
    let (_, taps) =
        pipeline::run_through(scene, hw, RunOptions::FAST, StageId::Accumulate).unwrap();
    let fr = taps.fixed.frame().frame.clone();
    let lens = LensMap::from_camera(
        &scene.camera,
        fr.height,
        hw.visibility.z.format.frac_bits,
        hw.dof.sigma,
        hw.dof.sigma_rom_bits,
    )
    .unwrap();
    (fr, lens)
}

fn check_scene(scene: &Scene) {
    let hw = HwConfig::default_config();
    let (fr, lens) = scene_frame(scene, &hw);
    let plan = plan_layers(&fr.depth, &fr.coverage, 16, &lens, &hw.dof).unwrap();
    let img = DepthImage::of_frame(&fr, &fr.acc, 16);
    let fmt = hw.accumulate.frame.format;
    check(&img, &plan, &hw.dof, fmt);
    let mut on = hw.dof.clone();
    on.skip_uniform_tiles = true;
    let tiles = check(&img, &plan, &on, fmt).unwrap();
    // The option changes the counts only: fewer MACs and divides, the same codes.
    let (o0, w0) = layered_fixed_exec(
        &img,
        &plan,
        &hw.dof,
        fmt,
        Exec::SkipUniform,
        |_| {},
        &igemu::stage::Pool::new(),
    )
    .map(|r| (r.0, r.1))
    .unwrap();
    let (o1, w1, skipped) = layered_fixed_exec(
        &img,
        &plan,
        &on,
        fmt,
        Exec::SkipUniform,
        |_| {},
        &igemu::stage::Pool::new(),
    )
    .unwrap();
    assert_eq!(o0, o1);
    assert!(tiles > 0 && skipped.iter().sum::<u64>() > 0);
    assert!(
        w1.macs < w0.macs && w1.divides < w0.divides,
        "{w0:?} {w1:?}"
    );
    assert_eq!(
        (w1.composites, w1.passthrough),
        (w0.composites, w0.passthrough)
    );
}

#[test]
fn embedded_scenes_skip_is_exact() {
    check_scene(&Scene::default_scene());
    check_scene(&Scene::embedded("cone-focus").unwrap());
}

#[test]
fn depth_ramp_skip_is_exact() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/depth-ramp.toml");
    check_scene(&Scene::load(path).unwrap());
}

fn lens() -> LensMap {
    common::affine_lens(16)
}

/// A random depth image of flat blocks (so that uniform windows occur), with background,
/// partial coverage and a few values.
fn blocks(w: usize, h: usize, seed: u64, b: usize) -> (Vec<u32>, Vec<u32>, Vec<u16>) {
    let mut s = seed | 1;
    let mut next = |n: u64| {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s % n
    };
    let (bx, by) = (w.div_ceil(b), h.div_ceil(b));
    let cells: Vec<(u32, u32, u16)> = (0..bx * by)
        .map(|_| {
            let v = [0, 1, 700, 4095][next(4) as usize];
            let z = [0.2, 0.45, 0.6, 0.8, 0.95][next(5) as usize];
            let k = if next(5) == 0 {
                u32::MAX
            } else {
                (z * 65536.0) as u32
            };
            let c = if k == u32::MAX {
                0
            } else if next(4) == 0 {
                next(16) as u16
            } else {
                16
            };
            (v, k, c)
        })
        .collect();
    let (mut v, mut k, mut c) = (vec![0; w * h], vec![0; w * h], vec![0; w * h]);
    for y in 0..h {
        for x in 0..w {
            let (cv, ck, cc) = cells[(y / b) * bx + x / b];
            v[y * w + x] = cv;
            k[y * w + x] = ck;
            c[y * w + x] = cc;
        }
    }
    (v, k, c)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Random block images, tiny to medium, with masks larger than the image, narrow words
    /// (saturation, ERROR), a line word wider than 32 bits and the hardware option: the skip
    /// is exact.
    #[test]
    fn random_depth_images_skip_is_exact(
        w in 1usize..70, h in 1usize..100, seed in any::<u64>(), b in 1usize..24,
        narrow in 0u32..4, tiles in any::<bool>(),
    ) {
        let (v, k, c) = blocks(w, h, seed, b);
        let mut p = HwConfig::default_config().dof;
        p.skip_uniform_tiles = tiles;
        match narrow {
            1 => { p.line_bits = 24; p.acc_bits = 30; }
            2 => { p.line_bits = 24; p.acc_bits = 30; p.overflow = Overflow::Error; }
            // A line word wider than 32 bits: the strips' planes are u64 words.
            3 => { p.line_bits = 40; p.acc_bits = 60; }
            _ => {}
        }
        let Ok(plan) = plan_layers(&k, &c, 16, &lens(), &p) else { return Ok(()); };
        let img = DepthImage { width: w, height: h, value: &v, key: &k, cov: &c, n2: 16 };
        check(&img, &plan, &p, FRAME);
    }
}

/// The value 1234 on the background everywhere: value, depth and coverage planes.
fn flat(w: usize, h: usize) -> (Vec<u32>, Vec<u32>, Vec<u16>) {
    (
        vec![1234u32; w * h],
        vec![u32::MAX; w * h],
        vec![0u16; w * h],
    )
}

/// The image of `flat` planes and its layer plan.
fn flat_image<'a>(
    w: usize,
    h: usize,
    (v, k, c): &'a (Vec<u32>, Vec<u32>, Vec<u16>),
    p: &DofCfg,
) -> (DepthImage<'a, u32>, LayerPlan) {
    let plan = plan_layers(k, c, 16, &lens(), p).unwrap();
    let img = DepthImage {
        width: w,
        height: h,
        value: v,
        key: k,
        cov: c,
        n2: 16,
    };
    (img, plan)
}

/// A flat image larger than a tile: every tile is skipped with the option, the output is
/// the value, and the border pixels (renormalised by the in-image tap sums) are exact too.
#[test]
fn flat_image_is_its_value() {
    let (w, h) = (40, 23);
    let planes = flat(w, h);
    let mut p = HwConfig::default_config().dof;
    p.skip_uniform_tiles = true;
    let (img, plan) = flat_image(w, h, &planes, &p);
    assert!(plan.layers[0].m > 0);
    let tiles = check(&img, &plan, &p, FRAME).unwrap();
    assert_eq!(tiles, 3 * 2);
    let (out, work, skipped) = layered_fixed_exec(
        &img,
        &plan,
        &p,
        FRAME,
        Exec::SkipUniform,
        |_| {},
        &igemu::stage::Pool::new(),
    )
    .unwrap();
    assert!(out.iter().all(|&o| o == 1234));
    assert_eq!((work.macs, work.divides), (0, 0));
    assert_eq!(skipped, vec![(w * h) as u64]);
}

/// A flat image whose horizontal sums fit the line word while its vertical sums overflow
/// the accumulator: its uniform windows are not taken as the value, they saturate as the
/// full datapath does.
#[test]
fn flat_image_saturates_the_accumulator() {
    let (w, h) = (40, 23);
    let planes = flat(w, h);
    let mut p = HwConfig::default_config().dof;
    p.acc_bits = p.line_bits;
    let (img, plan) = flat_image(w, h, &planes, &p);
    // 1234 x 16 x 2^12 fits 28 bits; times 2^12 again it does not.
    assert_eq!((p.line_bits, p.coef_bits), (28, 12));
    check(&img, &plan, &p, FRAME);
    let (out, work) = igemu::stage::dof::layered_fixed(&img, &plan, &p, FRAME).unwrap();
    assert_eq!(work.acc_overflows, (w * h) as u64);
    assert!(out.iter().all(|&o| o < 1234));
}
