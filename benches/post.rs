//! The post stage (gamma LUT + Bayer 8x8 dither) inside the pipeline against a plain C++
//! integer model of the same chain compiled with `g++ -O2` (`benches/cpp/post_chain.cpp`;
//! the stand-in for a hand-written `ac_fixed` testbench, whose headers are not packaged
//! for this machine). One run, interleaved:
//!
//! * **pipeline**: the default scene (640x480, linear12, `dither.kind = "bayer8"`) frame
//!   after frame on one `fast::Emulator`; the time is the gamma and dither stages' own
//!   `fixed_ms` in each frame's report (the stages as a render runs them: their kernels, the
//!   LUT, the pooled planes and the instrumentation), on the pipeline's rayon threads.
//! * **C++**: the same frame (the DoF stage's output codes), LUT and mask, through the C++
//!   chain on one thread; its output must equal the pipeline's DAC codes code for code.
//!
//! Prints the best and median of each and the ratio C++ time / pipeline time (above 1: the
//! pipeline is faster). Without `g++` it says so and measures the pipeline alone.

use igemu::config::{DitherKind, HwConfig};
use igemu::pipeline::fast;
use igemu::scene::Scene;
use igemu::stage::dither::Dither;
use igemu::stage::gamma::{GammaSpec, extended_lut};
use igemu::stage::{RunOptions, StageId};
use std::path::Path;
use std::process::Command;

const FRAMES: usize = 40;
const CPP_ROUNDS: usize = 200;

fn write_u32(path: &Path, v: &[u32]) {
    let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
    std::fs::write(path, bytes).expect("write bench input");
}

fn read_u32(path: &Path) -> Vec<u32> {
    std::fs::read(path)
        .expect("read C++ output")
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

fn stats(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[0], v[v.len() / 2])
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        println!("post: bench");
        return;
    }
    let scene = Scene::embedded("default").expect("embedded");
    let mut hw = HwConfig::default_config();
    hw.dither.kind = DitherKind::Bayer8;
    let emu = fast::Emulator::new();
    let mut pipeline_ms = Vec::with_capacity(FRAMES);
    let (mut gamma_ms, mut dither_ms) = (Vec::new(), Vec::new());
    let mut last = None;
    for k in 0..=FRAMES {
        let e = emu
            .emulate(&scene, &hw, RunOptions::FIXED_ONLY, None)
            .expect("emulate");
        let ms = |name: &str| -> f64 {
            let s = e.report.stages.iter().find(|s| s.name == name);
            s.expect("the stage runs").fixed_ms
        };
        // Frame 0 fills the pool; from frame 1 on the planes are reused.
        if k > 0 {
            gamma_ms.push(ms("gamma"));
            dither_ms.push(ms("dither"));
            pipeline_ms.push(ms("gamma") + ms("dither"));
        }
        if k == FRAMES {
            last = Some(e);
        } else {
            emu.recycle(e);
        }
    }
    let e = last.expect("a frame");
    let (p_best, p_med) = stats(pipeline_ms);
    let ((g_best, _), (d_best, _)) = (stats(gamma_ms), stats(dither_ms));
    println!(
        "post (gamma LUT + Bayer 8x8 in the pipeline, default 640x480, {} threads): best {:.1} us, median {:.1} us over {FRAMES} pooled frames (best gamma {:.1} us, dither {:.1} us)",
        rayon::current_num_threads(),
        p_best * 1e3,
        p_med * 1e3,
        g_best * 1e3,
        d_best * 1e3
    );

    // The frame the gamma stage read: the taps after the stage before it.
    let gi = e
        .steps
        .iter()
        .position(|s| s.id == StageId::Gamma)
        .expect("gamma runs");
    let frame = &e.steps[gi - 1].outcome.taps.fixed.frame().frame;
    let spec = GammaSpec::of(&scene, &hw);
    let fmt = hw.accumulate.frame.format;
    let f = hw.dither.frac_bits;
    let lut = extended_lut(&spec, fmt.int_bits, f);
    let mask = Dither::new(&hw.dither)
        .mask
        .expect("an ordered dither has a mask");
    let out_max = (1u32 << hw.gamma.dac_bits) - 1;

    let dir = std::env::temp_dir().join(format!("igemu-post-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let d = dir.as_path();
    write_u32(
        &d.join("params.u32"),
        &[
            frame.width,
            frame.height,
            lut.len() as u32,
            f,
            mask.n,
            mask.bits,
            out_max,
            fmt.frac_bits,
        ],
    );
    write_u32(&d.join("acc.u32"), &frame.acc);
    write_u32(&d.join("lut.u32"), &lut);
    write_u32(&d.join("mask.u32"), &mask.rank);
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/cpp/post_chain.cpp");
    let exe = d.join("post_chain");
    let built = Command::new("g++")
        .args(["-O2", "-std=c++17", "-o"])
        .arg(&exe)
        .arg(&src)
        .status();
    if !built.is_ok_and(|s| s.success()) {
        println!("post: SKIP the C++ baseline (g++ not installed or the build failed)");
        return;
    }
    let run = Command::new(&exe)
        .arg(d)
        .arg(CPP_ROUNDS.to_string())
        .output()
        .expect("run the C++ baseline");
    assert!(run.status.success(), "C++ baseline failed: {run:?}");
    let text = String::from_utf8_lossy(&run.stdout).into_owned();
    let best_ns: f64 = text
        .split_whitespace()
        .nth(1)
        .and_then(|t| t.parse().ok())
        .expect("best_ns in the C++ output");
    let out = read_u32(&d.join("out.u32"));
    std::fs::remove_dir_all(d).ok();
    let dac: Vec<u32> = e.channels[0].iter().map(|&c| c as u32).collect();
    assert_eq!(out, dac, "the C++ chain must give the pipeline's DAC codes");
    println!(
        "post (C++ -O2 plain integer chain, 1 thread, same frame, LUT and mask; codes identical): best {:.1} us over {CPP_ROUNDS} rounds",
        best_ns / 1e3
    );
    println!(
        "post ratio: C++ best / pipeline best = {:.2}, C++ best / pipeline median = {:.2} (above 1: the pipeline is faster)",
        best_ns / 1e6 / p_best,
        best_ns / 1e6 / p_med
    );
}
