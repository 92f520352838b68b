//! Cycle model: simulated cycles per second of wall time on the default scene's workload
//! (the simulator's own speed, as RTL simulators report it).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use igemu::config::HwConfig;
use igemu::cycles;
use igemu::pipeline::{RenderOptions, render};
use igemu::scene::Scene;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let hw = HwConfig::default_config();
    let r = render(
        &Scene::default_scene(),
        &hw,
        RenderOptions { stage_local: false },
    )
    .expect("default scene renders");
    let total = cycles::simulate(&r.workload, &hw.cycles, None).total_cycles;
    let mut g = c.benchmark_group("cycles");
    g.sample_size(10);
    // Elements = simulated clock cycles, so criterion reports cycles per second.
    g.throughput(Throughput::Elements(total));
    g.bench_function("simulate default scene", |b| {
        b.iter(|| black_box(cycles::simulate(black_box(&r.workload), &hw.cycles, None)))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
