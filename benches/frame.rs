//! A whole frame of the embedded scenes (640x480, 4x4 samples, linear12): the fixed-only
//! fast path (`render --no-reference`, `pipeline::fast::emulate`) against the full render
//! (fixed model, float reference, comparisons; `RunOptions::FAST`, as sweeps and checks run)
//! in one run. `fixed-only` runs frame after frame on one [`fast::Emulator`], whose pool
//! keeps the planes across frames (as a sequence or a display-rate run does);
//! `fixed-only-once` is a one-shot `render --no-reference` that allocates them afresh.
//! Frames per second of emulation are 1000 / (the fixed-only median in ms).

use criterion::{Criterion, criterion_group, criterion_main};
use igemu::config::HwConfig;
use igemu::pipeline::{fast, render};
use igemu::scene::Scene;
use igemu::stage::RunOptions;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let hw = HwConfig::default_config();
    let mut g = c.benchmark_group("frame");
    g.sample_size(10);
    for name in ["default", "default-pinhole", "default-colour"] {
        let scene = Scene::embedded(name).expect("embedded");
        let emu = fast::Emulator::new();
        g.bench_function(format!("{name}/fixed-only"), |b| {
            b.iter(|| {
                let e = emu
                    .emulate(&scene, &hw, RunOptions::FIXED_ONLY, None)
                    .unwrap();
                black_box(&e.channels);
                emu.recycle(e);
            })
        });
        g.bench_function(format!("{name}/fixed-only-once"), |b| {
            b.iter(|| black_box(fast::emulate(&scene, &hw, RunOptions::FIXED_ONLY, None).unwrap()))
        });
        g.bench_function(format!("{name}/full"), |b| {
            b.iter(|| black_box(render(&scene, &hw, RunOptions::FAST).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
