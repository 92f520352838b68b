//! Accumulate (tent filter, 4x4 samples, 640x480) on the default scene: fixed vs float.

use criterion::{Criterion, criterion_group, criterion_main};
use igemu::config::HwConfig;
use igemu::pipeline::{RenderOptions, guard_band, region_of, render};
use igemu::scene::{Scene, front_end};
use igemu::stage::accumulate::{self, AccParams, Kernel};
use igemu::stage::input;
use igemu::stage::raster::{self, RasterParams, RasterWork};
use igemu::stage::setup::{self, SetupWork};
use igemu::stage::visibility::{self, Samples, VisWork, ZConvert};
use igemu::stage::{Grid, StageReport};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let scene = Scene::default_scene();
    let hw = HwConfig::default_config();
    let host = front_end(&scene, &guard_band(&scene, &hw).unwrap());
    let q = input::quantize(&host, &hw, &mut StageReport::default()).unwrap();
    let (w, h) = (scene.image.width, scene.image.height);
    let grid = Grid::new(hw.raster.samples, hw.subpixel_bits(), w, h);
    let kernel = Kernel::new(hw.accumulate.filter, grid.n, hw.accumulate.weight_bits, 0.5);
    let region = region_of(&q, &hw, w, h);
    let reg = accumulate::sample_region(&region, &kernel);
    let p = RasterParams {
        grid,
        guard: hw.raster.interp_guard_bits,
        quant: hw.raster.interp_quant,
        i_max: 65535,
        z_max: (1 << 24) - 1,
    };
    let zc = ZConvert {
        shift: 0,
        quant: hw.visibility.z.quant,
        max: (1 << 24) - 1,
    };
    let mut samples = Samples::new(reg, 0);
    let (mut sw, mut rw, mut vw) = (
        SetupWork::default(),
        RasterWork::default(),
        VisWork::default(),
    );
    let mut frags = Vec::new();
    for (i, prim) in q.iter().enumerate() {
        frags.clear();
        raster::raster(
            &setup::setup(prim, &grid, &mut sw),
            &p,
            &reg,
            &mut frags,
            &mut rw,
        );
        visibility::resolve(&frags, i as u32 + 1, &zc, &mut samples, &mut vw);
    }
    let ap = AccParams {
        kernel: kernel.clone(),
        i_frac: 4,
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
        b.iter(|| {
            black_box(accumulate::accumulate(&samples, &region, &[], &ap, 0, (w, h)).unwrap())
        })
    });
    g.bench_function("float/f64/tent4x4", |b| {
        b.iter(|| black_box(accumulate::accumulate_f64(&iv, &reg, &region, &[], &ar)))
    });
    g.finish();
    let mut g = c.benchmark_group("render");
    g.sample_size(10);
    g.bench_function("default/linear12/fixed+float", |b| {
        b.iter(|| black_box(render(&scene, &hw, RenderOptions { stage_local: false }).unwrap()))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
