//! Golden outputs: the DAC codes of the embedded scenes under each preset, named by hash.
//! A change to any stage that moves a single code fails here; the actual image is written to
//! `tests/output/` for inspection. Update a hash only for an intended change, and say why in
//! the commit. The host front end uses f64 trigonometry and the LUTs `powf`: the hashes are
//! those of x86_64 Linux with this toolchain (the CI machine).

use igemu::config::HwConfig;
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
    let s = Scene::embedded(scene).expect("embedded scene");
    let r = render(
        &s,
        &HwConfig::preset(preset).expect("preset"),
        RunOptions::FAST,
    )
    .expect("render");
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

#[test]
fn default_linear12_with_depth_of_field() {
    check("default", "linear12", 0x4357_099f_3035_4706);
}

#[test]
fn default_pinhole_log8_logadd() {
    check("default-pinhole", "log8-logadd", 0x3390_614d_8895_3ab3);
}
