//! `dof.kernel` (docs/dof.md, "Kernel shape"): the disc's quantised 2-D weights, the
//! fitted Gaussian's scale, the hardware-file field and its refusals, and the 2-D layer
//! filter's determinism and flat-field exactness.

mod common;

use igemu::config::{DofKernel, HwConfig};
use igemu::files::TomlFile;
use igemu::stage::dof::{FITTED_SCALE, Mask2, disc_f64, disc_half_size, gaussian_sigma};
use igemu::stage::{RunOptions, StageId};
use proptest::prelude::*;

proptest! {
    /// Equal energy: every disc's weights sum exactly to `2^(2 coef_bits)`, its float
    /// weights to 1, and the mask is as wide as the pixels the disc overlaps.
    #[test]
    fn disc_weights_sum_exactly_to_one(r in 0.0f64..20.0, cb in 4u32..=16) {
        let d = Mask2::disc(r, 2 * cb);
        prop_assert_eq!(d.w.iter().sum::<u64>(), 1u64 << (2 * cb));
        prop_assert!((d.wf.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        prop_assert_eq!(d.m, disc_half_size(r));
        prop_assert_eq!(d.w.len(), d.side() * d.side());
        // The disc's area: pi r^2 px when it spans more than its own pixel.
        if d.m > 0 {
            let centre = d.wf[d.m * d.side() + d.m];
            let area = 1.0 / centre.max(1e-300);
            prop_assert!(r < 0.9 || (area - std::f64::consts::PI * r * r).abs() < 0.05 * area + 1.0,
                "r {} area from the centre weight {}", r, area);
        }
    }
}

#[test]
fn a_disc_inside_its_pixel_is_the_identity_and_the_weights_are_point_symmetric() {
    for r in [0.0, 0.2, 0.5] {
        assert_eq!(disc_f64(r), vec![1.0]);
        assert_eq!(disc_half_size(r), 0);
    }
    assert_eq!(disc_half_size(0.51), 1);
    assert_eq!(disc_half_size(2.0), 2);
    let d = disc_f64(3.3);
    let n = (d.len() as f64).sqrt() as usize;
    for y in 0..n {
        for x in 0..n {
            let a = d[y * n + x];
            assert!((a - d[(n - 1 - y) * n + n - 1 - x]).abs() < 1e-12);
            assert!((a - d[x * n + y]).abs() < 1e-12);
        }
    }
    assert_eq!(
        gaussian_sigma(DofKernel::FittedGaussian, 4.0),
        FITTED_SCALE * 4.0
    );
    assert_eq!(gaussian_sigma(DofKernel::Gaussian, 4.0), 4.0);
}

fn hw_file(text: &str) -> Result<HwConfig, String> {
    HwConfig::from_toml(&TomlFile::from_text("h.toml", text)).map_err(|e| e.to_string())
}

#[test]
fn the_kernel_is_read_from_the_hardware_file_and_bad_values_are_refused() {
    let h = hw_file("preset = \"linear12\"\n[dof]\nkernel = \"disc\"\n").expect("disc");
    assert_eq!(h.dof.kernel, DofKernel::Disc);
    let h = hw_file("preset = \"linear12\"\n[dof]\nkernel = \"fitted_gaussian\"\n").unwrap();
    assert_eq!(h.dof.kernel, DofKernel::FittedGaussian);
    let e = hw_file("preset = \"linear12\"\n[dof]\nkernel = \"pillbox\"\n").unwrap_err();
    assert!(e.contains("h.toml:3") && e.contains("dof.kernel"), "{e}");
    assert!(e.contains("`gaussian`, `disc`, `fitted_gaussian`"), "{e}");
    let e = hw_file("preset = \"linear12\"\n[dof]\nkernel = \"disc\"\nskip_uniform_tiles = true\n")
        .unwrap_err();
    assert!(
        e.contains("dof.skip_uniform_tiles") && e.contains("disc"),
        "{e}"
    );
}

/// The dof stage's fixed output codes on the default scene.
fn dof_codes(hw: &HwConfig) -> Vec<u32> {
    let scene = igemu::scene::Scene::default_scene();
    let steps = common::steps_through(&scene, hw, RunOptions::FAST, StageId::Dof);
    let s = steps
        .iter()
        .find(|s| s.id == StageId::Dof)
        .expect("dof ran");
    s.outcome.taps.fixed.frame().frame.acc.clone()
}

#[test]
fn the_disc_layers_are_bit_identical_on_one_and_two_threads() {
    let hw = common::hw("linear12", |h| h.dof.kernel = DofKernel::Disc);
    let on = |n: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .expect("pool")
            .install(|| dof_codes(&hw))
    };
    let one = on(1);
    assert_eq!(one, on(2));
    // and they blur: not the Gaussian kernel's image
    let g = dof_codes(&common::hw("linear12", |_| {}));
    assert_ne!(one, g);
}
