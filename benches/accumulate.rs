//! Accumulate (tent filter, 4x4 samples, 640x480) on the default scene: fixed (the whole
//! region, and the binned tiles as the stage runs it) vs float (the whole region).

use criterion::{Criterion, criterion_group, criterion_main};
use igemu::config::HwConfig;
use igemu::pipeline::{self, render};
use igemu::scene::Scene;
use igemu::stage::accumulate::{self, AccParams};
use igemu::stage::{RunOptions, StageId};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let scene = Scene::default_scene();
    let hw = HwConfig::default_config();
    let (plan, taps) =
        pipeline::run_through(&scene, &hw, RunOptions::FAST, StageId::Visibility).unwrap();
    let (w, h) = (scene.image.width, scene.image.height);
    let kernel = accumulate::kernel(&hw);
    let (region, reg) = (plan.layout.region, plan.layout.samples);
    let samples = &taps.fixed.samples().samples;
    let ap = AccParams {
        kernel: kernel.clone(),
        i_frac: 4,
        i_max: hw.input.intensity.format.max_code() as u32,
        frame: hw.accumulate.frame,
    };
    let ar = accumulate::AccRef {
        kernel: &kernel,
        i_frac: 4,
        frame_frac: 0,
        bg_i: 0.0,
        size: (w, h),
    };
    let iv: Vec<f64> = samples.i.iter().map(|&v| v as f64).collect();
    let mut g = c.benchmark_group("accumulate");
    g.sample_size(20);
    g.bench_function("fixed/linear12/tent4x4", |b| {
        b.iter(|| black_box(accumulate::accumulate(samples, &region, &[], &ap, 0, (w, h)).unwrap()))
    });
    // What the stage runs: the binned tiles only (the rest takes the background code).
    let tiles = &plan.layout.tiles;
    g.bench_function("fixed/linear12/tent4x4/binned", |b| {
        b.iter(|| {
            black_box(
                accumulate::accumulate_tiles(
                    samples,
                    &region,
                    Some(tiles),
                    &[],
                    &ap,
                    0,
                    (w, h),
                    &igemu::stage::Pool::new(),
                )
                .unwrap(),
            )
        })
    });
    g.bench_function("float/f64/tent4x4", |b| {
        b.iter(|| black_box(accumulate::accumulate_f64(&iv, &reg, &region, &[], &ar)))
    });
    g.finish();
    let mut g = c.benchmark_group("render");
    g.sample_size(10);
    g.bench_function("default/linear12/fixed+float", |b| {
        b.iter(|| black_box(render(&scene, &hw, RunOptions::FAST).unwrap()))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
