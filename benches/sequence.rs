//! `cargo bench --bench sequence`: frames per second of emulation of a sequence with and
//! without the reuse between frames (stage outcomes and tile rows), as ratios from one run
//! (the runs alternate, so load on the machine falls on both). Three sequences: the
//! embedded `flypast` (objects move in every frame; its aircraft is the region's left edge,
//! so most frames change every tile row), `docs/flypast-sky.toml` (the same with a sky
//! behind everything: only the tile rows the objects move in are emulated again) and the
//! flypast held still (every stage of frames 1.. is reused). Fixed model only, and with the
//! float reference.

use igemu::config::HwConfig;
use igemu::files::TomlFile;
use igemu::scene::Scene;
use igemu::sequence::{self, SequenceOptions};
use std::time::Instant;

const FRAMES: u32 = 12;
const ROUNDS: usize = 3;

fn fps(scene: &Scene, hw: &HwConfig, reference: bool, reuse: bool) -> f64 {
    let o = SequenceOptions {
        frames: 0..FRAMES,
        reference,
        reuse,
    };
    let t = Instant::now();
    sequence::run(scene, hw, &o, &mut |_| Ok(())).expect("sequence runs");
    FRAMES as f64 / t.elapsed().as_secs_f64()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        println!("sequence: bench");
        return;
    }
    let moving = Scene::embedded("flypast").expect("embedded");
    let (_, text) = igemu::scene::EMBEDDED
        .iter()
        .find(|(n, _)| *n == "flypast")
        .expect("embedded");
    let head = &text[..text.find("[sequence]").expect("a [sequence]")];
    let still_text = format!("{head}[sequence]\nframes = {FRAMES}\n");
    let still = Scene::from_toml(&TomlFile::from_text("flypast-still", &still_text))
        .expect("the still flypast parses");
    let sky = Scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/flypast-sky.toml"
    ))
    .expect("docs/flypast-sky.toml loads");
    let hw = HwConfig::default_config();
    for (name, scene) in [
        ("flypast (moving objects)", &moving),
        ("flypast-sky (moving objects, the region fixed)", &sky),
        ("flypast held still", &still),
    ] {
        for reference in [false, true] {
            let (mut with, mut without) = (Vec::new(), Vec::new());
            for _ in 0..ROUNDS {
                with.push(fps(scene, &hw, reference, true));
                without.push(fps(scene, &hw, reference, false));
            }
            let (w, wo) = (median(with), median(without));
            println!(
                "sequence {name}, {FRAMES} frames, {}: {w:.2} frames/s with reuse, {wo:.2} without (medians of {ROUNDS} alternating runs): reuse / no reuse = {:.2}",
                if reference {
                    "fixed + float reference"
                } else {
                    "fixed only"
                },
                w / wo
            );
        }
    }
}
