//! Gamma LUT + dither on a 640x480 frame next to a plain copy of the same bytes, in one
//! group, so the ratio reads directly: `copy/u32` is the floor any per-pixel stage pays.
//!
//! `lut/...` and `lut+...` run the stages' own kernels (the gamma stage's block lookup, the
//! dither stage's [`Dither::apply`]); `serial/...` the same kernels on one thread;
//! `portable/...` the same serial kernels in their baseline x86-64 build (without the AVX2
//! build the kernels pick at run time when the CPU has it); `per_value/...` the
//! straightforward per-pixel form the kernels replaced (kept here as the before-figure). After criterion, the ratios to the copy are printed from one interleaved
//! run (best of several rounds each; the machine is shared and noisy).

use criterion::{Criterion, criterion_group};
use igemu::config::{DitherCfg, DitherKind};
use igemu::fixed::Quant;
use igemu::stage::dither::{Dither, Mask, Run, apply_ordered_with, ordered_code};
use igemu::stage::gamma::{GammaSpec, extended_lut, lookup, lookup_block, lookup_block_portable};
use std::hint::black_box;
use std::time::Instant;

const W: u32 = 640;
const H: u32 = 480;
const F: u32 = 4;

struct Data {
    lut: Vec<u32>,
    acc: Vec<u32>,
}

fn data() -> Data {
    let spec = GammaSpec::new(2.4, true, 8, Quant::RndConv);
    Data {
        lut: extended_lut(&spec, 12, F),
        acc: (0..W * H)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 20) & 4095)
            .collect(),
    }
}

fn dither(kind: DitherKind) -> Dither {
    Dither::new(&DitherCfg {
        kind,
        ..DitherCfg::default()
    })
}

/// The per-pixel form the kernels replaced: a bounds-checked lookup per value, then
/// [`ordered_code`] with the mask read per pixel.
fn per_value(d: &Data, m: &Mask, x: &mut [u32], out: &mut [u32]) -> u64 {
    let amax = d.lut.len() - 1;
    for (o, &a) in x.iter_mut().zip(black_box(&d.acc)) {
        *o = d.lut[(a as usize).min(amax)];
    }
    let mut sat = 0;
    for (i, (o, &v)) in out.iter_mut().zip(x.iter()).enumerate() {
        let c = ordered_code(v, F, m.at(i as u32 % W, i as u32 / W, (0, 0)), m.bits);
        sat += u64::from(c > 255);
        *o = c.min(255) as u32;
    }
    sat
}

/// The serial kernels in their portable build: the block lookup, then the row-wise Bayer 8x8
/// dither (frame 0, as [`Dither::apply_with`] with `Run::Serial` runs it).
fn portable(d: &Data, m: &Mask, x: &mut [u32], out: &mut [u32]) -> u64 {
    lookup_block_portable(&d.lut, black_box(&d.acc), 0, x);
    apply_ordered_with(x, W, F, 255, m, 0, out, Run::Portable)
}

/// Runs `f` on a thread of the global rayon pool, as the pipeline runs its stages
/// (`pipeline::render`), so the kernels' parallel parts are joined from a pool thread.
fn on_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    rayon::scope(|_| f())
}

fn bench(c: &mut Criterion) {
    let d = data();
    let mut x = vec![0u32; d.acc.len()];
    let mut out = vec![0u32; d.acc.len()];
    let mut g = c.benchmark_group("dither");
    g.bench_function("copy/u32", |b| {
        b.iter(|| out.copy_from_slice(black_box(&d.acc)))
    });
    g.bench_function("lut/12to8.4", |b| {
        on_pool(|| b.iter(|| lookup(&d.lut, black_box(&d.acc), 0, &mut x)))
    });
    g.bench_function("serial/lut/12to8.4", |b| {
        b.iter(|| lookup_block(&d.lut, black_box(&d.acc), 0, &mut x))
    });
    let b8 = dither(DitherKind::Bayer8);
    g.bench_function("serial/lut+bayer8", |b| {
        b.iter(|| {
            lookup_block(&d.lut, black_box(&d.acc), 0, &mut x);
            b8.apply_with(&x, (W, H), F, 255, &mut out, Run::Serial)
        })
    });
    for (name, kind) in [
        ("bayer2", DitherKind::Bayer2),
        ("bayer4", DitherKind::Bayer4),
        ("bayer8", DitherKind::Bayer8),
        ("blue_noise16", DitherKind::BlueNoise),
        ("floyd_steinberg", DitherKind::FloydSteinberg),
    ] {
        let dt = dither(kind);
        g.bench_function(format!("lut+{name}"), |b| {
            on_pool(|| {
                b.iter(|| {
                    lookup(&d.lut, black_box(&d.acc), 0, &mut x);
                    dt.apply(&x, W, H, F, 255, &mut out)
                })
            })
        });
    }
    let m = Mask::bayer(8);
    g.bench_function("portable/lut+bayer8", |b| {
        b.iter(|| portable(&d, &m, &mut x, &mut out))
    });
    g.bench_function("per_value/lut+bayer8", |b| {
        b.iter(|| per_value(&d, &m, &mut x, &mut out))
    });
    g.finish();
}

criterion_group!(benches, bench);

/// Best-of-`ROUNDS` times of the copy, the LUT, LUT + Bayer 8x8 and the per-value form,
/// interleaved in one run: on the calling thread (the kernels' serial blocks, the per-value
/// form), and inside rayon pools of 1 and 2 threads (the stages' kernels as the pipeline runs
/// them), each next to a copy on the same thread.
fn ratios() {
    const ROUNDS: usize = 200;
    let d = data();
    let b8 = dither(DitherKind::Bayer8);
    let m = Mask::bayer(8);
    let mut x = vec![0u32; d.acc.len()];
    let mut out = vec![0u32; d.acc.len()];
    let pools: Vec<rayon::ThreadPool> = [1, 2]
        .iter()
        .map(|&n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .expect("thread pool")
        })
        .collect();
    // [copy, lut, lut+bayer8, per_value] on the caller, then [copy, lut, lut+bayer8] per pool,
    // then [lut, lut+bayer8] portable on the caller.
    let mut best = [f64::INFINITY; 12];
    let mut time = |i: usize, f: &mut dyn FnMut()| {
        let t = Instant::now();
        f();
        best[i] = best[i].min(t.elapsed().as_secs_f64());
    };
    for _ in 0..ROUNDS {
        time(0, &mut || out.copy_from_slice(black_box(&d.acc)));
        time(1, &mut || {
            lookup_block(&d.lut, black_box(&d.acc), 0, &mut x)
        });
        time(2, &mut || {
            lookup_block(&d.lut, black_box(&d.acc), 0, &mut x);
            black_box(b8.apply_with(&x, (W, H), F, 255, &mut out, Run::Serial));
        });
        time(3, &mut || {
            black_box(per_value(&d, &m, &mut x, &mut out));
        });
        time(10, &mut || {
            lookup_block_portable(&d.lut, black_box(&d.acc), 0, &mut x)
        });
        time(11, &mut || {
            black_box(portable(&d, &m, &mut x, &mut out));
        });
        for (k, pool) in pools.iter().enumerate() {
            pool.install(|| {
                time(4 + 3 * k, &mut || out.copy_from_slice(black_box(&d.acc)));
                time(5 + 3 * k, &mut || {
                    lookup(&d.lut, black_box(&d.acc), 0, &mut x)
                });
                time(6 + 3 * k, &mut || {
                    lookup(&d.lut, black_box(&d.acc), 0, &mut x);
                    black_box(b8.apply(&x, W, H, F, 255, &mut out));
                });
            });
        }
    }
    let line = |name: &str, t: f64, copy: f64| {
        println!(
            "  {name:<40} {:>8.1} us  {:>6.2}x the copy's time  throughput {:.3} of the copy's",
            t * 1e6,
            t / copy,
            copy / t
        )
    };
    println!("dither ratios (640x480, best of {ROUNDS} rounds each, interleaved in one run):");
    line("copy/u32 (caller)", best[0], best[0]);
    line("serial/lut/12to8.4 (caller)", best[1], best[0]);
    line("serial/lut+bayer8 (caller)", best[2], best[0]);
    line("portable/lut/12to8.4 (caller)", best[10], best[0]);
    line("portable/lut+bayer8 (caller)", best[11], best[0]);
    line("per_value/lut+bayer8 (caller)", best[3], best[0]);
    for (k, n) in ["1 thread", "2 threads"].iter().enumerate() {
        let copy = best[4 + 3 * k];
        line(&format!("copy/u32 (pool of {n})"), copy, copy);
        line(&format!("lut/12to8.4 (pool of {n})"), best[5 + 3 * k], copy);
        line(&format!("lut+bayer8 (pool of {n})"), best[6 + 3 * k], copy);
    }
}

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
    ratios();
}
