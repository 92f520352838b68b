//! Stage reuse in sweeps, against one full render of the default scene:
//! * 64 configurations that differ only in gamma and dither widths: the stages before gamma
//!   run once (a fresh cache per iteration, so the first configuration pays for them), the
//!   other 63 run only gamma, the dither and the comparison;
//! * 16 configurations that differ only in `dof.*` fields: input, setup, raster, visibility
//!   and accumulate run once, the other 15 run only dof, gamma and the comparison.
//!
//! Besides criterion's figures, the bench prints each ratio (sweep / one render) measured in
//! one run, interleaved, best of `ROUNDS`.

use criterion::Criterion;
use igemu::files::TomlFile;
use igemu::pipeline::{self, Cache};
use igemu::scene::Scene;
use igemu::stage::RunOptions;
use igemu::sweep::{self, grid};
use std::hint::black_box;
use std::time::Instant;

const GAMMA_GRID: &str = "gamma.dac_bits = [6, 7, 8, 9, 10, 11, 12, 13]\n\
                          dither.kind = [\"none\", \"bayer4\"]\n\
                          dither.frac_bits = [1, 2, 3, 4]\n";
const DOF_GRID: &str = "dof.p = [0.1, 0.2]\n\
                        dof.coef_bits = [10, 12]\n\
                        dof.alpha_bits = [10, 12]\n\
                        dof.guard_bits = [2, 4]\n";
const ROUNDS: usize = 3;

fn configs(text: &str, n: usize) -> Vec<grid::Config> {
    let file = TomlFile::from_text("bench-grid.toml", text);
    let g = grid::Grid::parse(&file).expect("grid parses");
    let c = g.expand(&file).expect("grid expands");
    assert_eq!(c.len(), n);
    c
}

fn one_render(scene: &Scene, hw: &igemu::config::HwConfig) {
    // As a sweep renders: no stage-local comparisons.
    let r = pipeline::render(scene, hw, RunOptions::FAST).expect("render");
    black_box(r.report.end_to_end.codes.max_abs_diff);
}

/// Runs the sweep with a fresh cache; every row after the first reuses `reused` stages.
fn sweep(scene: &Scene, configs: &[grid::Config], reused: &[&str]) {
    let cache = Cache::new();
    for (i, c) in configs.iter().enumerate() {
        let job = sweep::Job {
            index: i,
            config: i,
            scene: 0,
        };
        let row = sweep::run_job(job, c, scene, Some(&cache), None).expect("row");
        black_box(row.error.max_code_diff);
        if i > 0 {
            assert!(
                reused.iter().all(|s| row.reused.iter().any(|r| r == s)),
                "row {i} reused {:?}",
                row.reused
            );
        }
    }
}

fn main() {
    let scene = Scene::default_scene();
    let gamma = configs(GAMMA_GRID, 64);
    let dof = configs(DOF_GRID, 16);
    let early = [
        "input",
        "setup",
        "raster",
        "visibility",
        "accumulate",
        "dof",
    ];
    let hw = gamma[0].hw.clone();
    let mut c = Criterion::default().sample_size(10).configure_from_args();
    {
        let mut g = c.benchmark_group("sweep");
        g.bench_function("render/default", |b| b.iter(|| one_render(&scene, &hw)));
        g.bench_function("sweep64_gamma_dither/reuse", |b| {
            b.iter(|| sweep(&scene, &gamma, &early))
        });
        g.bench_function("sweep16_dof/reuse", |b| {
            b.iter(|| sweep(&scene, &dof, &early[..5]))
        });
        g.finish();
    }
    c.final_summary();
    // The ratios in one run, interleaved (noisy machines): best of ROUNDS each.
    let (mut render, mut s64, mut s16) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
    for _ in 0..ROUNDS {
        let t = Instant::now();
        one_render(&scene, &hw);
        render = render.min(t.elapsed().as_secs_f64());
        let t = Instant::now();
        sweep(&scene, &gamma, &early);
        s64 = s64.min(t.elapsed().as_secs_f64());
        let t = Instant::now();
        sweep(&scene, &dof, &early[..5]);
        s16 = s16.min(t.elapsed().as_secs_f64());
    }
    println!(
        "one full render: {:.0} ms\n\
         sweep of 64 gamma/dither configurations with reuse: {:.0} ms, ratio {:.2} (64 full renders: 64)\n\
         sweep of 16 dof configurations with reuse: {:.0} ms, ratio {:.2} (16 full renders: 16)",
        render * 1e3,
        s64 * 1e3,
        s64 / render,
        s16 * 1e3,
        s16 / render
    );
}
