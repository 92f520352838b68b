//! Raster (setup + edge walk + interpolation) on the default scene: fixed vs float.

use criterion::{Criterion, criterion_group, criterion_main};
use igemu::config::HwConfig;
use igemu::pipeline;
use igemu::scene::Scene;
use igemu::stage::input::QPrim;
use igemu::stage::raster::{self, FPrim, RasterParams, RasterWork};
use igemu::stage::setup::{self, SetupWork};
use igemu::stage::{RunOptions, StageId};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let scene = Scene::default_scene();
    let hw = HwConfig::default_config();
    let (plan, taps) =
        pipeline::run_through(&scene, &hw, RunOptions::FAST, StageId::Input).unwrap();
    let q: &[QPrim] = &taps.fixed.prims().q;
    let (grid, reg) = (plan.layout.grid, plan.layout.samples);
    let p = RasterParams {
        grid,
        guard: hw.raster.interp_guard_bits,
        quant: hw.raster.interp_quant,
        i_max: [65535; 3],
        channels: 1,
        z_max: (1 << 24) - 1,
    };
    let fprims: Vec<FPrim> = q.iter().map(|p| FPrim::from_q(p, grid.sub_bits)).collect();
    let mut g = c.benchmark_group("raster");
    g.sample_size(20);
    g.bench_function("fixed/linear12/4x4", |b| {
        let mut out = Vec::new();
        b.iter(|| {
            let (mut sw, mut rw) = (SetupWork::default(), RasterWork::default());
            for prim in q {
                out.clear();
                raster::raster(
                    &setup::setup(prim, &grid, p.guard, &mut sw),
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
