//! Cycle model: simulated cycles per second of wall time on the default scene's workload
//! (the simulator's own speed, as RTL simulators report it): the event-driven simulator
//! (`simulate`, jumping over quiet cycles) and the one-clock-at-a-time reference
//! (`simulate_stepwise`) in one group, so their ratio comes from one run; each with and
//! without a VCD trace written to memory.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use igemu::config::HwConfig;
use igemu::cycles::{self, State, Workload, vcd::VcdWriter};
use igemu::pipeline::render;
use igemu::scene::Scene;
use igemu::stage::RunOptions;
use std::hint::black_box;
use std::time::Instant;

fn with_vcd(
    w: &Workload,
    sim: fn(&Workload, Option<&mut cycles::Trace>) -> cycles::SimResult,
) -> usize {
    let mut vcd = VcdWriter::new(Vec::new(), w, 100.0).expect("in memory");
    let r = sim(
        w,
        Some(&mut |t, st: &[State], occ: &[u32]| vcd.cycle(t, st, occ)),
    );
    vcd.finish(r.total_cycles).expect("in memory").len()
}

fn bench(c: &mut Criterion) {
    let hw = HwConfig::default_config();
    let r = render(&Scene::default_scene(), &hw, RunOptions::FAST).expect("default scene renders");
    let w = &r.workload;
    let total = cycles::simulate(w, None).total_cycles;
    assert_eq!(cycles::simulate_stepwise(w, None).total_cycles, total);
    let mut g = c.benchmark_group("cycles");
    g.sample_size(10);
    // Elements = simulated clock cycles, so criterion reports cycles per second.
    g.throughput(Throughput::Elements(total));
    g.bench_function("event-driven/default scene", |b| {
        b.iter(|| black_box(cycles::simulate(black_box(w), None)))
    });
    g.bench_function("stepwise/default scene", |b| {
        b.iter(|| black_box(cycles::simulate_stepwise(black_box(w), None)))
    });
    g.bench_function("event-driven + vcd/default scene", |b| {
        b.iter(|| black_box(with_vcd(black_box(w), cycles::simulate)))
    });
    g.bench_function("stepwise + vcd/default scene", |b| {
        b.iter(|| black_box(with_vcd(black_box(w), cycles::simulate_stepwise)))
    });
    g.finish();
    // The ratio directly, from interleaved runs in this process (criterion's lines above give
    // each one's throughput).
    let time = |f: &dyn Fn()| {
        let t = Instant::now();
        f();
        t.elapsed().as_secs_f64()
    };
    let (mut fast, mut slow) = (Vec::new(), Vec::new());
    for _ in 0..7 {
        fast.push(time(&|| {
            black_box(cycles::simulate(black_box(w), None));
        }));
        slow.push(time(&|| {
            black_box(cycles::simulate_stepwise(black_box(w), None));
        }));
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (f, s) = (median(&mut fast), median(&mut slow));
    println!(
        "cycles: {total} cycles | event-driven {:.1} M cycles/s, stepwise {:.1} M cycles/s | ratio {:.1} (median of 7 interleaved runs)",
        total as f64 / f / 1e6,
        total as f64 / s / 1e6,
        s / f
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
