//! Cycle model: simulated cycles per second of wall time on the default scene's workload
//! (the simulator's own speed, as RTL simulators report it).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use igemu::config::HwConfig;
use igemu::cycles;
use igemu::pipeline::render;
use igemu::scene::Scene;
use igemu::stage::RunOptions;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let hw = HwConfig::default_config();
    let r = render(&Scene::default_scene(), &hw, RunOptions::FAST).expect("default scene renders");
    let total = cycles::simulate(&r.workload, None).total_cycles;
    let mut g = c.benchmark_group("cycles");
    g.sample_size(10);
    // Elements = simulated clock cycles, so criterion reports cycles per second.
    g.throughput(Throughput::Elements(total));
    g.bench_function("simulate default scene", |b| {
        b.iter(|| black_box(cycles::simulate(black_box(&r.workload), None)))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
