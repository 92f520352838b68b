//! Gamma LUT + dither on a 640x480 frame next to a plain copy of the same bytes, in one
//! group, so the ratio reads directly: `copy/u32` is the floor any per-pixel stage pays.

use criterion::{Criterion, criterion_group, criterion_main};
use igemu::config::{DitherCfg, DitherKind};
use igemu::fixed::Quant;
use igemu::stage::dither::Dither;
use igemu::stage::gamma::GammaSpec;
use igemu::stage::gamma::extended_lut;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let (w, h) = (640u32, 480u32);
    let spec = GammaSpec::new(2.4, true, 8, Quant::RndConv);
    let f = 4;
    let lut = extended_lut(&spec, 12, f);
    let acc: Vec<u32> = (0..w * h)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 20) & 4095)
        .collect();
    let mut x = vec![0u32; acc.len()];
    let mut out = vec![0u32; acc.len()];
    let mut g = c.benchmark_group("dither");
    g.bench_function("copy/u32", |b| {
        b.iter(|| out.copy_from_slice(black_box(&acc)))
    });
    g.bench_function("lut/12to8.4", |b| {
        b.iter(|| {
            for (o, &a) in x.iter_mut().zip(black_box(&acc)) {
                *o = lut[a as usize];
            }
        })
    });
    for (name, kind) in [
        ("bayer8", DitherKind::Bayer8),
        ("blue_noise16", DitherKind::BlueNoise),
        ("floyd_steinberg", DitherKind::FloydSteinberg),
    ] {
        let d = Dither::new(&DitherCfg {
            kind,
            ..DitherCfg::default()
        });
        g.bench_function(format!("lut+{name}"), |b| {
            b.iter(|| {
                for (o, &a) in x.iter_mut().zip(black_box(&acc)) {
                    *o = lut[a as usize];
                }
                d.apply(&x, w, h, f, 255, &mut out)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
