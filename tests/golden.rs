//! Golden outputs: the DAC codes of the embedded scenes under each preset, named by hash.
//! A change to any stage that moves a single code fails here; the actual image is written to
//! `tests/output/` for inspection. Update a hash only for an intended change, and say why in
//! the commit. The host front end uses f64 trigonometry and the LUTs `powf`: the hashes are
//! those of x86_64 Linux with this toolchain (the CI machine).

use igemu::config::{AlphaNorm, HwConfig, SigmaForm};
use igemu::pipeline::render;
use igemu::scene::Scene;
use igemu::stage::RunOptions;

/// FNV-1a over the codes as little-endian u16.
fn fnv(codes: &[u16]) -> u64 {
    codes
        .iter()
        .flat_map(|c| c.to_le_bytes())
        .fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
            (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
        })
}

fn check(scene: &str, preset: &str, expected: u64) {
    check_with(scene, preset, |_| {}, expected);
}

fn check_with(scene: &str, preset: &str, edit: impl FnOnce(&mut HwConfig), expected: u64) {
    let s = Scene::embedded(scene).expect("embedded scene");
    let mut hw = HwConfig::preset(preset).expect("preset");
    edit(&mut hw);
    let r = render(&s, &hw, RunOptions::FAST).expect("render");
    let got = fnv(&r.dac);
    if got != expected {
        std::fs::create_dir_all("tests/output").ok();
        let path = format!("tests/output/{scene}.{preset}.{got:016x}.png");
        igemu::output::write_dac(&path, &r.dac, s.image.width, s.image.height, r.dac_bits).ok();
        panic!(
            "{scene} / {preset}: DAC hash {got:016x}, expected {expected:016x}; actual image in {path}"
        );
    }
}

#[test]
fn default_pinhole_linear12() {
    check("default-pinhole", "linear12", 0x910e_fa47_6b30_86f8);
}

/// The paper's blur formula (`dof.sigma = "paper"`, the default since it replaced the
/// affine form): the background blurs at K/U = 3.956 px instead of 3.35. Since
/// `dof.alpha_norm = "behind"` became the default (no seams where the cone crosses layers,
/// docs/dof.md "Seams"), the codes differ from the plain composite's along layer boundaries.
#[test]
fn default_linear12_with_depth_of_field() {
    check("default", "linear12", 0x5135_5ee2_f9ec_3b52);
}

/// The plain back-to-front composite (`dof.alpha_norm = "image"`) keeps the DAC codes it
/// had before the behind normalisation existed.
#[test]
fn default_linear12_with_depth_of_field_image_alpha() {
    check_with(
        "default",
        "linear12",
        |h| h.dof.alpha_norm = AlphaNorm::Image,
        0x88fa_2770_d7b0_81bc,
    );
}

/// The first version's affine blur form with the plain composite keeps the first version's
/// DAC codes.
#[test]
fn default_linear12_with_depth_of_field_affine_sigma() {
    check_with(
        "default",
        "linear12",
        |h| {
            h.dof.sigma = SigmaForm::Affine;
            h.dof.alpha_norm = AlphaNorm::Image;
        },
        0x4357_099f_3035_4706,
    );
}

#[test]
fn default_pinhole_log8_logadd() {
    check("default-pinhole", "log8-logadd", 0x3390_614d_8895_3ab3);
}

/// Focus on the cone (the paper's Fig. 3c), the paper's blur.
#[test]
fn cone_focus_linear12_with_depth_of_field() {
    check("cone-focus", "linear12", 0x0bee_d7ee_cff4_d176);
}

/// The same with the plain composite: the codes from before the behind normalisation.
#[test]
fn cone_focus_linear12_with_depth_of_field_image_alpha() {
    check_with(
        "cone-focus",
        "linear12",
        |h| h.dof.alpha_norm = AlphaNorm::Image,
        0xaf85_9917_b6e8_1ddf,
    );
}
