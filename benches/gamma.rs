//! Gamma LUT applied to a 640x480 frame: fixed LUT lookup vs the float formula.

use criterion::{Criterion, criterion_group, criterion_main};
use igemu::fixed::Quant;
use igemu::stage::gamma::{self, GammaLut, GammaSpec};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let spec = GammaSpec::new(2.4, true, 8, Quant::RndConv);
    let lut = GammaLut::build(&spec, 12);
    let acc: Vec<u32> = (0..640 * 480u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 20) & 4095)
        .collect();
    let accf: Vec<f64> = acc.iter().map(|&a| a as f64).collect();
    let mut out = vec![0u16; acc.len()];
    let mut g = c.benchmark_group("gamma");
    g.bench_function("fixed/lut12to8", |b| {
        b.iter(|| lut.apply(black_box(&acc), 0, &mut out))
    });
    g.bench_function("float/powf", |b| {
        b.iter(|| gamma::apply_f64(&spec, black_box(&accf), 4095.0, &mut out))
    });
    g.bench_function("build/lut12to8", |b| {
        b.iter(|| black_box(GammaLut::build(&spec, 12)))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
