//! The dof stage on the default scene's frame: layered (fixed) vs the per-pixel scatter
//! reference (the paper's complexity claim), and fixed vs float layered. Each ratio is
//! printed from one run (`cargo bench --bench dof`).

use criterion::{Criterion, criterion_group, criterion_main};
use igemu::config::HwConfig;
use igemu::pipeline;
use igemu::scene::Scene;
use igemu::stage::dof::{
    DepthImage, Exec, LensMap, layered_f64, layered_fixed, layered_fixed_exec, per_pixel_scatter,
    plan_layers,
};
use igemu::stage::{RunOptions, StageId};
use std::hint::black_box;
use std::time::Instant;

fn bench(c: &mut Criterion) {
    let scene = Scene::default_scene();
    let hw = HwConfig::default_config();
    let (_, taps) =
        pipeline::run_through(&scene, &hw, RunOptions::FAST, StageId::Accumulate).unwrap();
    let fr = &taps.fixed.frame().frame;
    let (w, h) = (fr.width as usize, fr.height as usize);
    let lens = LensMap::from_camera(
        &scene.camera,
        fr.height,
        hw.visibility.z.format.frac_bits,
        hw.dof.sigma,
        hw.dof.sigma_rom_bits,
    )
    .unwrap();
    let plan = plan_layers(&fr.depth, &fr.coverage, 16, &lens, &hw.dof).unwrap();
    let img = DepthImage {
        width: w,
        height: h,
        value: &fr.acc[..],
        key: &fr.depth,
        cov: &fr.coverage,
        n2: 16,
    };
    let vf: Vec<f64> = fr.acc.iter().map(|&v| v as f64).collect();
    let fimg = DepthImage {
        width: w,
        height: h,
        value: &vf[..],
        key: &fr.depth,
        cov: &fr.coverage,
        n2: 16,
    };
    let fmt = hw.accumulate.frame.format;
    let mut grp = c.benchmark_group("dof");
    grp.sample_size(10);
    grp.bench_function("layered_fixed", |b| {
        b.iter(|| black_box(layered_fixed(&img, &plan, &hw.dof, fmt).unwrap()))
    });
    grp.bench_function("layered_f64", |b| {
        b.iter(|| black_box(layered_f64(&fimg, &plan)))
    });
    grp.bench_function("per_pixel_scatter_f64", |b| {
        b.iter(|| black_box(per_pixel_scatter(&fimg, &lens, hw.dof.k, hw.dof.kernel)))
    });
    grp.finish();
    // The ratios, from one run: best of 5 each.
    let best = |f: &dyn Fn()| {
        (0..5)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64()
            })
            .fold(f64::MAX, f64::min)
    };
    let tf = best(&|| {
        black_box(layered_fixed(&img, &plan, &hw.dof, fmt).unwrap());
    });
    let tfull = best(&|| {
        black_box(
            layered_fixed_exec(
                &img,
                &plan,
                &hw.dof,
                fmt,
                Exec::Full,
                |_| {},
                &igemu::stage::Pool::new(),
            )
            .unwrap(),
        );
    });
    let tplan = best(&|| {
        black_box(plan_layers(&fr.depth, &fr.coverage, 16, &lens, &hw.dof).unwrap());
    });
    let tl = best(&|| {
        black_box(layered_f64(&fimg, &plan));
    });
    let tp = best(&|| {
        black_box(per_pixel_scatter(&fimg, &lens, hw.dof.k, hw.dof.kernel));
    });
    eprintln!(
        "dof ratios ({w}x{h}, {} layers): per-pixel / layered-float = {:.2}, per-pixel / layered-fixed = {:.2}, fixed / float layered = {:.2} (ms: fixed {:.1}, float {:.1}, per-pixel {:.1})",
        plan.layers.len(),
        tp / tl,
        tp / tf,
        tf / tl,
        tf * 1e3,
        tl * 1e3,
        tp * 1e3
    );
    eprintln!(
        "dof uniform-window skip: every tap / skip (fixed layered) = {:.2}; per-pixel / (layer plan + fixed layered) = {:.2} (ms: every tap {:.1}, plan {:.1})",
        tfull / tf,
        tp / (tplan + tf),
        tfull * 1e3,
        tplan * 1e3
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
