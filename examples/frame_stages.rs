//! Per-stage time of the fixed-only frame at steady state: `frames` frames of an embedded
//! scene (or of a scene file) on one `fast::Emulator` (its pool keeps the planes across frames, as a sequence
//! or `cargo bench --bench frame`'s `fixed-only` runs them), the first three dropped, the
//! medians printed: the host front end's time, each stage's fixed-model time, the whole frame's wall time, the sum of
//! the stages and the cycle simulation's own time.
//!
//! ```text
//! cargo run --release --example frame_stages -- default 30
//! ```

use igemu::config::HwConfig;
use igemu::pipeline::fast;
use igemu::scene::Scene;
use igemu::stage::RunOptions;
use std::time::Instant;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("default", String::as_str);
    let frames: usize = args.get(1).map_or(Ok(30), |s| s.parse())?;
    let hw = HwConfig::default_config();
    // An embedded scene's name, or a scene file.
    let scene = match Scene::embedded(name) {
        Some(s) => s,
        None => Scene::load(name)?,
    };
    let emu = fast::Emulator::new();
    let mut stages: Vec<(String, Vec<f64>)> = Vec::new();
    let (mut wall, mut fixed, mut sim, mut host) = (vec![], vec![], vec![], vec![]);
    for k in 0..frames.max(4) {
        let t = Instant::now();
        let e = emu.emulate(&scene, &hw, RunOptions::FIXED_ONLY, None)?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        if k >= 3 {
            wall.push(ms);
            fixed.push(e.report.timing.fixed_ms);
            sim.push(e.report.cycles.sim.wall_ms);
            host.push(e.report.timing.host_ms);
            for (i, s) in e.report.stages.iter().enumerate() {
                if stages.len() <= i {
                    stages.push((s.name.clone(), Vec::new()));
                }
                stages[i].1.push(s.fixed_ms);
            }
        }
        emu.recycle(e);
    }
    println!("{name}: medians of {} pooled frames (ms)", wall.len());
    println!("  {:<12} {:>7.2}", "host", median(&mut host));
    for (stage, v) in &mut stages {
        println!("  {stage:<12} {:>7.2}", median(v));
    }
    println!("  {:<12} {:>7.2}", "stages", median(&mut fixed));
    println!("  {:<12} {:>7.2}", "cycle sim", median(&mut sim));
    println!("  {:<12} {:>7.2}", "frame wall", median(&mut wall));
    Ok(())
}
