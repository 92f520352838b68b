//! Raster (setup + edge walk + interpolation) on the default scene: fixed vs float.

use criterion::{Criterion, criterion_group, criterion_main};
use igemu::config::HwConfig;
use igemu::pipeline::{guard_band, region_of};
use igemu::scene::{Scene, front_end};
use igemu::stage::input::{self, QPrim};
use igemu::stage::raster::{self, FPrim, RasterParams, RasterWork};
use igemu::stage::setup::{self, SetupWork};
use igemu::stage::{Grid, StageReport, accumulate};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let scene = Scene::default_scene();
    let hw = HwConfig::default_config();
    let host = front_end(&scene, &guard_band(&scene, &hw).unwrap());
    let q: Vec<QPrim> = input::quantize(&host, &hw, &mut StageReport::default()).unwrap();
    let grid = Grid::new(
        hw.raster.samples,
        hw.subpixel_bits(),
        scene.image.width,
        scene.image.height,
    );
    let kernel =
        accumulate::Kernel::new(hw.accumulate.filter, grid.n, hw.accumulate.weight_bits, 0.5);
    let reg = accumulate::sample_region(
        &region_of(&q, &hw, scene.image.width, scene.image.height),
        &kernel,
    );
    let p = RasterParams {
        grid,
        guard: hw.raster.interp_guard_bits,
        quant: hw.raster.interp_quant,
        i_max: 65535,
        z_max: (1 << 24) - 1,
    };
    let fprims: Vec<FPrim> = q.iter().map(|p| FPrim::from_q(p, grid.sub_bits)).collect();
    let mut g = c.benchmark_group("raster");
    g.sample_size(20);
    g.bench_function("fixed/linear12/4x4", |b| {
        let mut out = Vec::new();
        b.iter(|| {
            let (mut sw, mut rw) = (SetupWork::default(), RasterWork::default());
            for prim in &q {
                out.clear();
                raster::raster(
                    &setup::setup(prim, &grid, &mut sw),
                    &p,
                    &reg,
                    &mut out,
                    &mut rw,
                );
                black_box(&out);
            }
        })
    });
    g.bench_function("float/f64/4x4", |b| {
        let mut out = Vec::new();
        b.iter(|| {
            for prim in &fprims {
                out.clear();
                raster::raster_f64(prim, &grid, &reg, &mut out);
                black_box(&out);
            }
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
