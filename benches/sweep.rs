//! Stage reuse in sweeps: 64 configurations of the default scene that differ only in gamma
//! and dither widths, against one full render. With reuse, the phases before the post stage
//! run once (a fresh cache per iteration, so the first configuration pays for them) and the
//! other 63 run only the gamma/dither post stage and the comparison.
//!
//! Besides criterion's figures, the bench prints the ratio (64-configuration sweep / one
//! render) measured in one run, interleaved, best of `ROUNDS`.

use criterion::Criterion;
use igemu::files::TomlFile;
use igemu::pipeline::{self, RenderOptions};
use igemu::scene::Scene;
use igemu::sweep::{self, cache::PhaseCache, grid};
use std::hint::black_box;
use std::time::Instant;

const GRID: &str = "gamma.dac_bits = [6, 7, 8, 9, 10, 11, 12, 13]\n\
                    dither.kind = [\"none\", \"bayer4\"]\n\
                    dither.frac_bits = [1, 2, 3, 4]\n";
const ROUNDS: usize = 3;

fn configs() -> Vec<grid::Config> {
    let file = TomlFile::from_text("bench-grid.toml", GRID);
    let g = grid::Grid::parse(&file).expect("grid parses");
    let c = g.expand(&file).expect("grid expands");
    assert_eq!(c.len(), 64);
    c
}

fn one_render(scene: &Scene, hw: &igemu::config::HwConfig) {
    // As a sweep renders: no stage-local comparisons.
    let r = pipeline::render(scene, hw, RenderOptions { stage_local: false }).expect("render");
    black_box(r.report.end_to_end.codes.max_abs_diff);
}

fn sweep64(scene: &Scene, configs: &[grid::Config]) {
    let cache = PhaseCache::new();
    for (i, c) in configs.iter().enumerate() {
        let job = sweep::Job {
            index: i,
            config: i,
            scene: 0,
        };
        let row = sweep::run_job(job, c, scene, Some(&cache), None).expect("row");
        black_box(row.error.max_code_diff);
    }
    assert_eq!(cache.stats(), (63, 1), "one early computation, 63 reuses");
}

fn main() {
    let scene = Scene::default_scene();
    let configs = configs();
    let hw = configs[0].hw.clone();
    let mut c = Criterion::default().sample_size(10).configure_from_args();
    {
        let mut g = c.benchmark_group("sweep");
        g.bench_function("render/default", |b| b.iter(|| one_render(&scene, &hw)));
        g.bench_function("sweep64_gamma_dither/reuse", |b| {
            b.iter(|| sweep64(&scene, &configs))
        });
        g.finish();
    }
    c.final_summary();
    // The ratio in one run, interleaved (noisy machines): best of ROUNDS each.
    let (mut render, mut sweep) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..ROUNDS {
        let t = Instant::now();
        one_render(&scene, &hw);
        render = render.min(t.elapsed().as_secs_f64());
        let t = Instant::now();
        sweep64(&scene, &configs);
        sweep = sweep.min(t.elapsed().as_secs_f64());
    }
    println!(
        "sweep of 64 gamma/dither configurations with reuse: {:.0} ms; one full render: {:.0} ms; ratio {:.2} (target < 5)",
        sweep * 1e3,
        render * 1e3,
        sweep / render
    );
}
