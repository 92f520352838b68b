//! The `igemu` command line. `main` only maps `try_main`'s result to an exit code:
//! 0 ok, 1 a check failed, 2 bad input or error.

use clap::{Args, Parser, Subcommand};
use igemu::config::HwConfig;
use igemu::error::{Error, FileError};
use igemu::pipeline::{self, Render, RenderOptions, Report};
use igemu::scene::Scene;
use igemu::{calc, output};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "igemu",
    version,
    about = "Emulator of fixed-point image-generator hardware, compared code by code with a float reference"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Render a scene through the fixed-point pipeline and the float reference; write the image and the report.
    Render(RenderArgs),
    /// Regression gate: render and exit 1 when a threshold fails.
    Check(CheckArgs),
    /// Word widths from contrast, Weber fraction and gamma (Kovalev & Tokarev eq. 9-11).
    Widths(WidthsArgs),
    /// Depth of field of a thin lens: front and back depth, near and far limits.
    Dof(DofArgs),
    /// Cycle-count a frame on the scene's real workload: bottleneck, frame rate, real-time check, cost.
    Cycles(CyclesArgs),
    /// Small-object flicker: a light point and a thin line swept over 32x32 sub-pixel phases.
    Flicker(FlickerArgs),
    /// HDL co-simulation of the Verilog models in hdl-models/ (see hdl-models/README.md).
    #[command(subcommand)]
    Hdl(HdlCmd),
    /// Hardware cost per stage: the analytic model, and with --synth yosys cell counts of the HDL models.
    Cost(CostArgs),
    /// Word-width sweep: render every configuration of a grid, one JSON line each, and print the Pareto front.
    Sweep(SweepArgs),
    /// Observed min/max per signal and the narrowest format holding it; export the formats as typedefs.
    Ranges(RangesArgs),
}

#[derive(Args)]
struct RangesArgs {
    #[command(flatten)]
    s: SceneArgs,
    /// Print the configuration's formats as ac_fixed, ap_fixed, systemc or verilog instead.
    #[arg(long, value_parser = ["ac_fixed", "ap_fixed", "systemc", "verilog"])]
    export: Option<String>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct SweepArgs {
    /// Scene TOML files or embedded scene names (default: the embedded default scene).
    scenes: Vec<String>,
    /// Grid TOML: dotted hardware fields with lists of values (`gamma.dac_bits = [8, 9]`, `preset = [...]`).
    #[arg(long)]
    grid: String,
    /// Output JSON-lines file (one row per configuration and scene).
    #[arg(long)]
    out: String,
    /// Keep the complete rows already in OUT and run only the missing configurations.
    #[arg(long)]
    resume: bool,
    /// Run only shard K of N (contiguous blocks: the shard files concatenate to the full run).
    #[arg(long, value_name = "K/N")]
    shard: Option<String>,
    /// Configurations rendered in parallel (1 = serial; results are identical).
    #[arg(long, default_value_t = 1)]
    jobs: usize,
    /// Axes of the Pareto front, comma separated: error (mean Weber), code_error, max_error, weber, contours, cost, throughput, flicker (needs --flicker).
    #[arg(long, default_value = "error,cost")]
    axes: String,
    /// Run every phase for every configuration (no stage reuse between configurations).
    #[arg(long)]
    no_reuse: bool,
    /// Plot error vs cost and error vs throughput with the Pareto fronts (SVG or PNG, by extension).
    #[arg(long, value_name = "PARETO.svg|png")]
    plot: Option<String>,
    /// Add small-object flicker metrics to every row: the flicker scene swept over PHASES x PHASES sub-pixel phases (2..=64; `igemu flicker` uses 32).
    #[arg(long, value_name = "PHASES")]
    flicker: Option<u32>,
}

#[derive(Args)]
struct CostArgs {
    #[command(flatten)]
    s: SceneArgs,
    /// Synthesise each HDL model with yosys at the configured widths (cached in target/hdl-synth).
    #[arg(long)]
    synth: bool,
}

#[derive(Subcommand)]
enum HdlCmd {
    /// Write a stage's vectors (scene taps, exhaustive, random), ROM files and params.vh to a directory.
    Vectors(HdlVectorsArgs),
}

#[derive(Args)]
struct HdlVectorsArgs {
    /// Stage: gamma, accumulate, dither, logdomain (log-add hardware), setup (edge stepper), dof (thin-lens scene).
    #[arg(long)]
    stage: String,
    #[command(flatten)]
    s: SceneArgs,
    /// Output directory.
    #[arg(long)]
    out: String,
    /// Also run the testbench (under --sim; exit 1 when it fails).
    #[arg(long)]
    run: bool,
    /// Simulator for --run: icarus or verilator (build cached in target/hdl-verilator).
    #[arg(long, default_value = "icarus")]
    sim: String,
    /// With --run, stage logdomain: the full pair space (tb_log_adder_exhaustive, one
    /// signature per row); a failing row is then run pair by pair to name the pair.
    #[arg(long, requires = "run")]
    exhaustive: bool,
}

#[derive(Args)]
struct CyclesArgs {
    #[command(flatten)]
    s: SceneArgs,
    /// Clock frequency in MHz (default: the hardware file's cycles.clock_mhz).
    #[arg(long)]
    clock_mhz: Option<f64>,
    /// Write a VCD trace of stage states and FIFO occupancy (for GTKWave).
    #[arg(long)]
    vcd: Option<String>,
    /// Print the cycle report as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct FlickerArgs {
    /// Hardware config: a preset (linear12, linear11, linear8) or a TOML file.
    #[arg(long)]
    hw: Option<String>,
    /// Override the filter.
    #[arg(long, value_enum)]
    filter: Option<FilterArg>,
    /// Model a system without gamma correction (a linear LUT).
    #[arg(long)]
    no_gamma_correction: bool,
    /// Sub-pixel phases per axis (2..=64).
    #[arg(long, default_value_t = 32)]
    phases: u32,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum FilterArg {
    Box,
    Tent,
    Gaussian,
}

#[derive(Args)]
struct SceneArgs {
    /// Scene TOML file or embedded scene name (default: the embedded default scene).
    scene: Option<String>,
    /// Hardware config: a preset (linear12, linear11, linear8, log8-potentiate, log8-logadd, log7-logadd) or a TOML file.
    #[arg(long)]
    hw: Option<String>,
}

#[derive(Args)]
struct RenderArgs {
    #[command(flatten)]
    s: SceneArgs,
    /// Output image of the fixed pipeline's DAC codes.
    #[arg(short = 'o', long = "out", default_value = "igemu.png")]
    out: String,
    /// Also write the float reference's DAC codes (same bit depth as OUT).
    #[arg(long)]
    reference_out: Option<String>,
    /// Also write the difference map (128 = identical, 32 grey levels per code).
    #[arg(long)]
    diff_out: Option<String>,
    /// Write a stage's raw codes as a 16-bit grey PNG: STAGE=PATH with STAGE one of accumulate, coverage, depth, gamma.
    #[arg(long = "dump", value_name = "STAGE=PATH")]
    dump: Vec<String>,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    json: bool,
    /// Write the JSON report to a file.
    #[arg(long)]
    report: Option<String>,
    /// Skip the stage-local comparisons (faster).
    #[arg(long)]
    no_local: bool,
    /// Write the banding map: the output dimmed, smooth regions lifted, visible contour steps white (8-bit PNG).
    #[arg(long)]
    banding_out: Option<String>,
    /// Also run the per-pixel depth-of-field reference (slow: O(N^2 M^2)) and the layer theorem check.
    #[arg(long)]
    dof_reference: bool,
}

#[derive(Args)]
struct CheckArgs {
    #[command(flatten)]
    s: SceneArgs,
    /// Fail when any DAC code differs from the reference by more than N.
    #[arg(long)]
    max_code_diff: Option<u32>,
    /// Fail when the fraction of identical DAC codes is below F (0..=1).
    #[arg(long)]
    min_identical: Option<f64>,
    /// Fail when more than this fraction of pixels has a visible (over delta) Weber error.
    #[arg(long)]
    max_visible: Option<f64>,
    /// Print the verdict as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct WidthsArgs {
    /// Contrast K = B_max / B_min (> 1); default: the scene's display block.
    #[arg(long)]
    contrast: Option<f64>,
    /// Weber fraction delta (0 < delta < 1); default: the scene's display block.
    #[arg(long)]
    weber: Option<f64>,
    /// Display gamma (> 1); default: the scene's display block, else 2.4.
    #[arg(long)]
    gamma: Option<f64>,
    /// Take contrast, Weber fraction and gamma from this scene's display block (flags override).
    #[arg(long)]
    scene: Option<String>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct DofArgs {
    /// f-number N.
    #[arg(long)]
    f_number: f64,
    /// Permissible circle of confusion C (same length unit as the others, e.g. mm).
    #[arg(long)]
    coc: f64,
    /// Focal length F.
    #[arg(long)]
    focal: f64,
    /// Focus distance L.
    #[arg(long)]
    distance: f64,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match try_main(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("igemu: error: {e}");
            ExitCode::from(2)
        }
    }
}

fn arg_error(flag: &str, msg: String) -> Error {
    Error::File(FileError {
        file: flag.into(),
        line: None,
        col: None,
        field: String::new(),
        msg,
    })
}

fn load_scene(arg: Option<&str>) -> Result<Scene, Error> {
    match arg {
        None => Ok(Scene::default_scene()),
        Some(a) => match Scene::embedded(a) {
            Some(s) if !std::path::Path::new(a).exists() => Ok(s),
            _ => Ok(Scene::load(a)?),
        },
    }
}

fn run(s: &SceneArgs, opts: RenderOptions) -> Result<Render, Error> {
    let scene = load_scene(s.scene.as_deref())?;
    let hw = HwConfig::resolve(s.hw.as_deref())?;
    pipeline::render(&scene, &hw, opts)
}

fn try_main(cli: Cli) -> Result<ExitCode, Error> {
    match cli.cmd {
        Cmd::Render(a) => render(a),
        Cmd::Check(a) => check(a),
        Cmd::Cycles(a) => cycles(a),
        Cmd::Widths(a) => {
            let display = match &a.scene {
                Some(p) => Some(load_scene(Some(p))?.display),
                None => None,
            };
            let need = |v: Option<f64>, d: Option<f64>, flag: &str| {
                v.or(d).ok_or_else(|| {
                    arg_error(
                        flag,
                        format!("give {flag} or --scene FILE (its display block)"),
                    )
                })
            };
            let contrast = need(
                a.contrast,
                display.as_ref().map(|d| d.contrast),
                "--contrast",
            )?;
            let weber = need(a.weber, display.as_ref().map(|d| d.weber), "--weber")?;
            let gamma = a.gamma.or(display.as_ref().map(|d| d.gamma)).unwrap_or(2.4);
            let w = calc::widths(contrast, weber, gamma).map_err(|m| arg_error("widths", m))?;
            let checks = igemu::stage::logdomain::validate_widths(&w);
            if a.json {
                let mut v = serde_json::to_value(&w).expect("serialisable");
                v["validation"] = serde_json::to_value(&checks).expect("serialisable");
                println!(
                    "{}",
                    serde_json::to_string_pretty(&v).expect("serialisable")
                );
            } else {
                println!(
                    "contrast K = {}, Weber fraction = {}, gamma = {}",
                    w.contrast, w.weber, w.gamma
                );
                println!(
                    "  linear intensity levels (eq. 9)  N_I = {:8.1}  -> {:2} bits",
                    w.linear.levels, w.linear.bits
                );
                println!(
                    "  DAC levels (eq. 10)              N_U = {:8.1}  -> {:2} bits",
                    w.dac.levels, w.dac.bits
                );
                println!(
                    "  log-code grades (eq. 11)         m   = {:8.1}  -> {:2} bits",
                    w.log_grades.levels, w.log_grades.bits
                );
                println!(
                    "  largest contrast an 8-bit linear code holds: K = {:.2}",
                    w.linear8_max_contrast
                );
                print_width_checks(&checks, w.weber);
            }
            Ok(ExitCode::SUCCESS)
        }
        Cmd::Flicker(a) => flicker(a),
        Cmd::Hdl(HdlCmd::Vectors(a)) => hdl_vectors(a),
        Cmd::Cost(a) => cost(a),
        Cmd::Sweep(a) => sweep(a),
        Cmd::Ranges(a) => ranges(a),
        Cmd::Dof(a) => {
            let d = calc::depth_of_field(a.f_number, a.coc, a.focal, a.distance)
                .map_err(|m| arg_error("dof", m))?;
            if a.json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&d).expect("serialisable")
                );
            } else {
                println!(
                    "N = {}, C = {}, F = {}, L = {}",
                    d.f_number, d.coc, d.focal, d.distance
                );
                println!("  front depth of field  dL1 = {:.2}", d.front);
                println!("  back depth of field   dL2 = {:.2}", d.back);
                println!("  total                 dL  = {:.2}", d.total);
                println!(
                    "  sharp from {:.2} to {:.2} (hyperfocal distance {:.1})",
                    d.near, d.far, d.hyperfocal
                );
            }
            Ok(ExitCode::SUCCESS)
        }
    }
}

fn render(a: RenderArgs) -> Result<ExitCode, Error> {
    let mut dumps = Vec::new();
    for d in &a.dump {
        let Some((stage, path)) = d.split_once('=') else {
            return Err(arg_error("--dump", format!("`{d}` is not STAGE=PATH")));
        };
        if !["accumulate", "coverage", "depth", "gamma"].contains(&stage) {
            return Err(arg_error(
                "--dump",
                format!("unknown stage `{stage}`; allowed: accumulate, coverage, depth, gamma"),
            ));
        }
        dumps.push((stage.to_string(), path.to_string()));
    }
    let r = pipeline::render_ext(
        &load_scene(a.s.scene.as_deref())?,
        &HwConfig::resolve(a.s.hw.as_deref())?,
        RenderOptions {
            stage_local: !a.no_local,
        },
        a.dof_reference,
    )?;
    let (w, h) = (r.report.scene.width, r.report.scene.height);
    output::write_dac(&a.out, &r.dac, w, h, r.dac_bits)?;
    if let Some(p) = &a.reference_out {
        output::write_dac(p, &r.dac_ref, w, h, r.dac_bits)?;
    }
    if let Some(p) = &a.diff_out {
        output::write_diff(p, &r.dac, &r.dac_ref, w, h)?;
    }
    if let Some(p) = &a.banding_out {
        let img =
            igemu::perceptual::banding_image(&r.dac, &r.contour_map, (1u32 << r.dac_bits) - 1);
        output::write_raw8(p, &img, w, h)?;
    }
    for (stage, path) in &dumps {
        let codes: Vec<u32> = match stage.as_str() {
            "accumulate" => r.frame.acc.clone(),
            "coverage" => r.frame.coverage.iter().map(|&c| c as u32).collect(),
            "depth" => r
                .frame
                .depth
                .iter()
                .map(|&z| if z == u32::MAX { 65535 } else { z >> 8 })
                .collect(),
            _ => r.dac.iter().map(|&c| c as u32).collect(),
        };
        output::write_raw16(path, &codes, w, h)?;
    }
    let json = serde_json::to_string_pretty(&r.report).expect("serialisable");
    if let Some(p) = &a.report {
        std::fs::write(p, &json).map_err(|e| Error::Io {
            path: p.clone(),
            source: e,
        })?;
    }
    if a.json {
        println!("{json}");
    } else {
        print_report(&r.report, &a.out);
    }
    Ok(ExitCode::SUCCESS)
}

fn check(a: CheckArgs) -> Result<ExitCode, Error> {
    if let Some(f) = a.min_identical
        && !(0.0..=1.0).contains(&f)
    {
        return Err(arg_error(
            "--min-identical",
            format!("must be in 0..=1, got {f}"),
        ));
    }
    let r = run(&a.s, RenderOptions { stage_local: false })?;
    let c = &r.report.end_to_end.codes;
    let wv = &r.report.end_to_end.weber;
    let mut failed = Vec::new();
    if let Some(n) = a.max_code_diff
        && c.max_abs_diff > n
    {
        failed.push(format!("max |code diff| {} > {n}", c.max_abs_diff));
    }
    if let Some(f) = a.min_identical
        && c.identical_fraction < f
    {
        failed.push(format!(
            "identical fraction {:.6} < {f}",
            c.identical_fraction
        ));
    }
    if let Some(f) = a.max_visible
        && wv.over_delta_fraction > f
    {
        failed.push(format!(
            "visible-error fraction {:.6} > {f}",
            wv.over_delta_fraction
        ));
    }
    if a.json {
        let v = serde_json::json!({
            "passed": failed.is_empty(),
            "failures": failed,
            "max_abs_diff": c.max_abs_diff,
            "identical_fraction": c.identical_fraction,
            "visible_fraction": wv.over_delta_fraction,
        });
        println!(
            "{}",
            serde_json::to_string_pretty(&v).expect("serialisable")
        );
    } else if failed.is_empty() {
        println!(
            "check passed: max |code diff| {}, identical {:.4}%, visible {:.4}%",
            c.max_abs_diff,
            100.0 * c.identical_fraction,
            100.0 * wv.over_delta_fraction
        );
    } else {
        for f in &failed {
            println!("check FAILED: {f}");
        }
    }
    Ok(if failed.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

fn cycles(a: CyclesArgs) -> Result<ExitCode, Error> {
    use igemu::cycles::{self, vcd::VcdWriter};
    let scene = load_scene(a.s.scene.as_deref())?;
    let mut hw = HwConfig::resolve(a.s.hw.as_deref())?;
    if let Some(mhz) = a.clock_mhz {
        igemu::config::check_clock(mhz).map_err(|m| arg_error("--clock-mhz", m))?;
        hw.cycles.clock_mhz = mhz;
    }
    let r = pipeline::render(&scene, &hw, RenderOptions { stage_local: false })?;
    let mut c = r.report.cycles.clone();
    if let Some(path) = &a.vcd {
        let io = |e: std::io::Error| Error::Io {
            path: path.clone(),
            source: e,
        };
        let file = std::fs::File::create(path).map_err(io)?;
        let fifo: Vec<bool> = (0..cycles::CYCLE_STAGES.len())
            .map(|i| r.workload.has_fifo(i))
            .collect();
        let mut w = VcdWriter::new(std::io::BufWriter::new(file), &fifo, hw.cycles.clock_mhz)
            .map_err(io)?;
        let planned = c.plan.stages.clone();
        let cost = c.cost.clone();
        c = cycles::report(
            &r.workload,
            &hw.cycles,
            &planned,
            scene.display.refresh_hz,
            cost,
            Some(&mut |t, st: &[cycles::State], occ: &[u32]| w.cycle(t, st, occ)),
        );
        w.finish(c.total_cycles).map_err(io)?;
    }
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&c).expect("serialisable")
        );
    } else {
        println!(
            "igemu {} cycles | scene `{}` {}x{} | hardware `{}`",
            r.report.igemu_version,
            r.report.scene.name,
            r.report.scene.width,
            r.report.scene.height,
            r.report.hardware.name
        );
        print_cycles(&c);
        if let Some(p) = &a.vcd {
            println!("wrote {p}");
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn print_cycles(c: &igemu::cycles::CycleReport) {
    let p = &c.plan;
    println!(
        "plan: {} | tiles {}x{} px: {} of {} touched | pixels simulated {} of {} ({:.1}%){}",
        p.stages.join(" -> "),
        p.tile,
        p.tile,
        p.tiles_touched,
        p.tiles_total,
        p.pixels_simulated,
        p.pixels_total,
        100.0 * p.pixels_simulated as f64 / p.pixels_total.max(1) as f64,
        if p.unmodelled.is_empty() {
            String::new()
        } else {
            format!(" | no cycle model: {}", p.unmodelled.join(", "))
        }
    );
    println!(
        "{:<11} {:>5} {:>4} {:>3} {:>5} {:>8} {:>12} {:>10} {:>10} {:>10} {:>9}  item",
        "stage",
        "lanes",
        "lat",
        "ii",
        "fifo",
        "tokens",
        "items",
        "busy",
        "stalled",
        "starved",
        "fifo max"
    );
    for s in &c.stages {
        println!(
            "{:<11} {:>5} {:>4} {:>3} {:>5} {:>8} {:>12} {:>10} {:>10} {:>10} {:>9}  {}",
            s.name,
            s.lanes,
            s.latency,
            s.ii,
            s.fifo,
            s.tokens,
            s.items,
            s.busy,
            s.stalled,
            s.starved,
            s.fifo_max,
            s.item
        );
    }
    let t = &c.throughput;
    println!(
        "frame: {} cycles | bottleneck {} | bounds {} <= {} <= {} {} | frame-port-bound cycles {}",
        c.total_cycles,
        c.bottleneck,
        c.lower_bound,
        c.total_cycles,
        c.upper_bound,
        if c.bounds_hold { "hold" } else { "VIOLATED" },
        c.frame_port_bound_cycles
    );
    println!(
        "at {} MHz: {:.3} ms/frame, {:.1} fps, {:.2} Mpixel/s | display needs {} Hz = {:.2} Mpixel/s: {}",
        t.clock_mhz,
        t.frame_ms,
        t.fps,
        t.pixel_rate / 1e6,
        t.refresh_hz,
        t.required_pixel_rate / 1e6,
        if t.real_time {
            "real time"
        } else {
            "NOT real time"
        }
    );
    let k = &c.cost;
    let list = |m: &std::collections::BTreeMap<String, u64>| {
        m.iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    println!(
        "cost: RAM {} bits ({}) | ROM {} bits ({}) | {} adders ({} bits) | {} multipliers ({} bit-products)",
        k.total_storage_bits,
        list(&k.storage_bits),
        k.total_rom_bits,
        list(&k.rom_bits),
        k.adders,
        k.adder_bits,
        k.multipliers,
        k.multiplier_bit_products
    );
    let packed: Vec<String> = k
        .packed
        .iter()
        .map(|p| {
            format!(
                "{} {} bits {}",
                p.name,
                p.bits,
                if p.verified { "ok" } else { "MISMATCH" }
            )
        })
        .collect();
    println!("packed with bitvec and read back: {}", packed.join(", "));
    println!(
        "simulator: {} cycles in {:.2} ms = {:.1} M cycles/s",
        c.total_cycles,
        c.sim.wall_ms,
        c.sim.cycles_per_s / 1e6
    );
}

fn print_width_checks(checks: &[igemu::stage::logdomain::RampCheck], weber: f64) {
    println!(
        "validation by emulation: a {}-sample ramp over the full contrast, quantised and through the gamma LUT;",
        igemu::stage::logdomain::RAMP_SAMPLES
    );
    println!("  contours = adjacent output steps with a luminance ratio above 1 + {weber}");
    println!(
        "  {:<7} {:>9} {:>8} {:>12} {:>8} {:>9}  verdict",
        "coding", "code bits", "DAC bits", "widths", "levels", "contours"
    );
    for c in checks {
        let verdict = match (c.recommended, c.disagrees) {
            (true, false) => "0 as theory predicts",
            (false, false) => "visible, as theory predicts",
            (true, true) => "DISAGREES with theory: contours at the recommended widths",
            (false, true) => "DISAGREES with theory: no visible contour one bit narrower",
        };
        println!(
            "  {:<7} {:>9} {:>8} {:>12} {:>8} {:>9}  {verdict}",
            c.coding,
            c.code_bits,
            c.dac_bits,
            if c.recommended {
                "recommended"
            } else {
                "1 bit less"
            },
            c.levels,
            c.contours
        );
    }
}

fn fmt_work(w: &std::collections::BTreeMap<String, u64>) -> String {
    w.iter()
        .filter(|(_, v)| **v > 0)
        .map(|(k, v)| format!("{k} {v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn print_report(r: &Report, out: &str) {
    let p = &r.plan;
    println!(
        "igemu {} | scene `{}` {}x{} | hardware `{}` | {} threads",
        r.igemu_version,
        r.scene.name,
        r.scene.width,
        r.scene.height,
        r.hardware.name,
        r.timing.threads
    );
    println!(
        "plan: {} | region x {}..{} y {}..{} ({:.1}% of the screen) | {}x{} samples/pixel | gamma {}",
        p.stages.join(" -> "),
        p.region.x0,
        p.region.x1,
        p.region.y0,
        p.region.y1,
        100.0 * p.region_fraction,
        p.samples,
        p.samples,
        p.gamma
    );
    println!();
    println!(
        "{:<11} {:>9} {:>9}  {:>10} {:>10} {:>9}  work",
        "stage", "fixed ms", "float ms", "max|err|", "mean err", "overflow"
    );
    for s in &r.stages {
        let (me, mean) = s.local.as_ref().map_or(("-".into(), "-".into()), |l| {
            (
                format!("{:.3}", l.max_abs_lsb),
                format!("{:+.4}", l.mean_lsb),
            )
        });
        let ov: u64 = s.signals.iter().map(|x| x.overflows).sum();
        println!(
            "{:<11} {:>9.2} {:>9.2}  {:>10} {:>10} {:>9}  {}",
            s.name,
            s.fixed_ms,
            s.float_ms,
            me,
            mean,
            ov,
            fmt_work(&s.work)
        );
    }
    println!(
        "{:<11} {:>9.2} {:>9.2}  (host front end {:.2} ms, f64, shared)",
        "total", r.timing.fixed_ms, r.timing.float_ms, r.timing.host_ms
    );
    let c = &r.end_to_end.codes;
    let w = &r.end_to_end.weber;
    println!();
    println!(
        "end to end, DAC codes ({} bits), fixed vs float reference:",
        r.hardware.gamma.dac_bits
    );
    println!(
        "  identical {:.4}% | max |diff| {} | mean diff {:+.5} | PSNR {}",
        100.0 * c.identical_fraction,
        c.max_abs_diff,
        c.mean_diff,
        c.psnr_db
            .map_or("inf (identical)".into(), |p| format!("{p:.2} dB"))
    );
    let hist: Vec<String> = c
        .histogram
        .iter()
        .map(|(d, n)| format!("{d:+}: {n}"))
        .collect();
    println!("  histogram of differences: {}", hist.join(", "));
    println!(
        "  luminance (display model): max Weber {:.4} | mean {:.6} | visible (> {}) {} px ({:.4}%)",
        w.max,
        w.mean,
        w.delta,
        w.over_delta,
        100.0 * w.over_delta_fraction
    );
    let k = &r.contours;
    println!(
        "  visible contours (smooth regions, window {}x{} px per side, delta {}): {} steps ({} px) | float reference: {} steps | smooth steps {}",
        k.window[0],
        k.window[1],
        k.delta,
        k.contour_steps,
        k.contour_pixels,
        k.contour_steps_reference,
        k.smooth_steps
    );
    if let Some(pm) = r
        .stages
        .iter()
        .find_map(|s| s.notes.get("temporal_period_mean"))
    {
        println!(
            "  temporal dither: static frame over a period of {} frames: {} of {} pixels average exactly to their input (max |error| {} LSB)",
            pm["period"], pm["exact_pixels"], pm["pixels"], pm["max_abs_error"]
        );
    }
    println!(
        "cost: storage {} bits ({:.1} KiB), LUT/ROM {} bits | overflows {}",
        r.storage_bits,
        r.storage_bits as f64 / 8192.0,
        r.lut_bits,
        r.overflows
    );
    println!();
    print_cycles(&r.cycles);
    println!("wrote {out}");
}

fn flicker(a: FlickerArgs) -> Result<ExitCode, Error> {
    use igemu::config::FilterKind;
    if !(2..=64).contains(&a.phases) {
        return Err(arg_error(
            "--phases",
            format!("must be in 2..=64, got {}", a.phases),
        ));
    }
    let mut hw = HwConfig::resolve(a.hw.as_deref())?;
    if let Some(f) = a.filter {
        hw.accumulate.filter = match f {
            FilterArg::Box => FilterKind::Box,
            FilterArg::Tent => FilterKind::Tent,
            FilterArg::Gaussian => FilterKind::Gaussian,
        };
    }
    if a.no_gamma_correction {
        hw.gamma.correction = false;
    }
    let r = igemu::flicker::flicker(&hw, a.phases)?;
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&r).expect("serialisable")
        );
        return Ok(ExitCode::SUCCESS);
    }
    println!(
        "flicker | hardware `{}` | filter {:?} | gamma {} {} | {}x{} phases on a {}x{} px scene",
        r.hardware,
        r.filter,
        r.gamma,
        if r.gamma_correction {
            "corrected"
        } else {
            "NOT corrected"
        },
        r.phases,
        r.phases,
        r.scene_size,
        r.scene_size
    );
    for o in &r.objects {
        println!("{} ({}):", o.object, o.description);
        println!(
            "  accumulator sum ripple        {} LSB ({:.4}% of the mean)",
            o.acc_ripple_lsb, o.acc_ripple_pct
        );
        println!(
            "  displayed luminance ripple    {:.3}% peak to peak of the mean ({:.3} cd/m2 summed)",
            o.displayed_ripple_pct, o.mean_luminance
        );
        println!(
            "  peak-pixel modulation         {:.2}%",
            o.peak_pixel_modulation_pct
        );
        println!(
            "  split 50/50 over two pixels   {:+.2}% brightness vs the pixel-aligned phase",
            o.half_pixel_brightness_error_pct
        );
    }
    if !r.gamma_correction {
        println!(
            "analytic split error without correction: 2 (1/2)^{} - 1 = {:+.2}%",
            r.gamma, r.analytic_split_error_pct
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn hdl_vectors(a: HdlVectorsArgs) -> Result<ExitCode, Error> {
    use igemu::hdl;
    let scene = load_scene(a.s.scene.as_deref())?;
    let hw = HwConfig::resolve(a.s.hw.as_deref())?;
    let sim = hdl::verilator::Sim::parse(&a.sim).ok_or_else(|| {
        arg_error(
            "--sim",
            format!("unknown simulator `{}`; allowed: icarus, verilator", a.sim),
        )
    })?;
    if a.exhaustive && a.stage != "logdomain" {
        return Err(arg_error(
            "--exhaustive",
            "only the log adder (--stage logdomain) has an exhaustive testbench".into(),
        ));
    }
    let stage = igemu::stage_id::StageId::parse(&a.stage)
        .filter(|&s| hdl::module_of(s).is_some())
        .ok_or_else(|| {
            arg_error(
                "--stage",
                format!(
                    "no HDL model of stage `{}`; allowed: {}",
                    a.stage,
                    hdl::MODULES
                        .iter()
                        .map(|m| m.0.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        })?;
    let b = hdl::vectors(stage, &scene, &hw)?;
    let dir = std::path::Path::new(&a.out);
    b.write(dir)?;
    let src: Vec<String> = b.sources.iter().map(|(k, n)| format!("{n} {k}")).collect();
    println!(
        "hdl vectors | stage {} (module {}) | hardware `{}` | {} vectors ({}) | {}",
        b.stage,
        b.module,
        hw.name,
        b.vectors.len(),
        src.join(", "),
        dir.display()
    );
    let params: Vec<String> = b.params.iter().map(|(k, v)| format!("{k}={v}")).collect();
    println!("parameters: {}", params.join(" "));
    if !a.run {
        return Ok(ExitCode::SUCCESS);
    }
    let cache = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("target")
        .join("hdl-verilator");
    if a.exhaustive {
        return hdl_exhaustive(sim, &b, dir, &cache, &scene, &hw);
    }
    let tb = format!("tb_{}", b.module);
    let r = sim
        .run(&tb, b.module, dir, &cache)
        .map_err(|m| arg_error("--run", m))?;
    match r.verdict {
        hdl::Verdict::Ok(n) => {
            let rust = n as f64 / (b.model_ns.max(1) as f64 * 1e-9);
            let sim_rate = n as f64 / r.sim_s;
            println!(
                "{}: TESTBENCH OK {n} vectors | compile {:.2} s, simulate {:.3} s = {sim_rate:.0} vectors/s | Rust model {:.3} ms = {rust:.0} vectors/s | Rust / Verilog = {:.0}x",
                sim.name(),
                r.compile_s,
                r.sim_s,
                b.model_ns as f64 * 1e-6,
                rust / sim_rate
            );
            Ok(ExitCode::SUCCESS)
        }
        hdl::Verdict::Failed(m) => {
            println!("{}: TESTBENCH FAILED: {m}", sim.name());
            Ok(ExitCode::from(1))
        }
    }
}

/// `hdl vectors --stage logdomain --run --exhaustive`: the full pair space by row
/// signatures; a failing row is then run pair by pair with the vector testbench.
fn hdl_exhaustive(
    sim: igemu::hdl::verilator::Sim,
    b: &igemu::hdl::Bench,
    dir: &std::path::Path,
    cache: &std::path::Path,
    scene: &Scene,
    hw: &HwConfig,
) -> Result<ExitCode, Error> {
    use igemu::hdl::{self, exhaustive};
    let r = sim
        .run(exhaustive::TESTBENCH, b.module, dir, cache)
        .map_err(|m| arg_error("--run", m))?;
    match r.verdict {
        hdl::Verdict::Ok(n) => {
            println!(
                "{}: {}: TESTBENCH OK {n} vectors (every pair) | compile {:.2} s, simulate {:.2} s = {:.0} vectors/s",
                sim.name(),
                exhaustive::TESTBENCH,
                r.compile_s,
                r.sim_s,
                n as f64 / r.sim_s
            );
            Ok(ExitCode::SUCCESS)
        }
        hdl::Verdict::Failed(m) => {
            println!(
                "{}: {}: TESTBENCH FAILED: {m}",
                sim.name(),
                exhaustive::TESTBENCH
            );
            if let Some(row) = exhaustive::failed_row(&m) {
                let rb = exhaustive::row_bench(scene, hw, row)?;
                let rdir = dir.join(format!("row-{row}"));
                rb.write(&rdir)?;
                let rr = sim
                    .run(&format!("tb_{}", rb.module), rb.module, &rdir, cache)
                    .map_err(|m| arg_error("--run", m))?;
                let v = match rr.verdict {
                    hdl::Verdict::Ok(n) => format!("TESTBENCH OK {n} vectors"),
                    hdl::Verdict::Failed(m) => format!("TESTBENCH FAILED: {m}"),
                };
                println!("row a={row} pair by pair ({}): {v}", rdir.display());
            }
            Ok(ExitCode::from(1))
        }
    }
}

fn cost(a: CostArgs) -> Result<ExitCode, Error> {
    use igemu::hdl;
    let scene = load_scene(a.s.scene.as_deref())?;
    let hw = HwConfig::resolve(a.s.hw.as_deref())?;
    let r = pipeline::render(&scene, &hw, RenderOptions { stage_local: false })?;
    println!(
        "cost | hardware `{}` | scene `{}`{}",
        hw.name,
        scene.name,
        if a.synth {
            " | yosys synth (generic gates)"
        } else {
            ""
        }
    );
    println!(
        "{:<11} {:>12} {:>10} {:>7} {:>6}  HDL model: yosys cells (flip-flops)",
        "stage", "storage_bits", "lut_bits", "adders", "mults"
    );
    let cache = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("target")
        .join("hdl-synth");
    for st in &r.report.stages {
        let c = &st.cost;
        let adders: u32 = c.adders.iter().map(|u| u.count).sum();
        let mults: u32 = c.multipliers.iter().map(|u| u.count).sum();
        let model = igemu::stage_id::StageId::parse(&st.name)
            .and_then(|id| Some((id, hdl::module_of(id)?)));
        let synth = match model {
            Some((id, m)) if a.synth => match hdl::vectors(id, &scene, &hw) {
                Ok(b) => match hdl::synth::synth(&b, &cache) {
                    Ok(s) => format!(
                        "{m}: {} cells ({} FF){}",
                        s.cells,
                        s.flip_flops(),
                        if s.cached { ", cached" } else { "" }
                    ),
                    Err(e) => format!("{m}: synthesis failed: {e}"),
                },
                Err(e) => format!("{m}: {e}"),
            },
            Some((_, m)) => format!("{m} (use --synth)"),
            None => "-".into(),
        };
        println!(
            "{:<11} {:>12} {:>10} {:>7} {:>6}  {synth}",
            st.name, c.storage_bits, c.lut_bits, adders, mults
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn sweep(a: SweepArgs) -> Result<ExitCode, Error> {
    use igemu::sweep::{self, grid, pareto};
    // Everything is checked before the first render.
    let shard = match &a.shard {
        Some(s) => Some(grid::Shard::parse(s).map_err(|m| arg_error("--shard", m))?),
        None => None,
    };
    if a.jobs == 0 || a.jobs > 1024 {
        return Err(arg_error(
            "--jobs",
            format!("must be in 1..=1024, got {}", a.jobs),
        ));
    }
    let axes = pareto::Axis::parse_list(&a.axes).map_err(|m| arg_error("--axes", m))?;
    if let Some(p) = &a.plot {
        sweep::plot::PlotFormat::of(p).map_err(|m| arg_error("--plot", m))?;
    }
    if let Some(n) = a.flicker
        && !(2..=64).contains(&n)
    {
        return Err(arg_error(
            "--flicker",
            format!("phases must be in 2..=64, got {n}"),
        ));
    }
    if a.flicker.is_none() && axes.contains(&pareto::Axis::Flicker) {
        return Err(arg_error(
            "--axes",
            "the flicker axis needs the flicker metrics: add --flicker PHASES".into(),
        ));
    }
    let file = igemu::files::TomlFile::read(&a.grid)?;
    let configs = grid::Grid::parse(&file)?.expand(&file)?;
    let scenes: Vec<Scene> = if a.scenes.is_empty() {
        vec![Scene::default_scene()]
    } else {
        a.scenes
            .iter()
            .map(|s| load_scene(Some(s)))
            .collect::<Result<_, _>>()?
    };
    for c in &configs {
        for s in &scenes {
            pipeline::guard_band(s, &c.hw).map_err(|e| {
                arg_error(
                    &a.grid,
                    format!(
                        "configuration {} ({}) on scene `{}`: {e}",
                        c.index, c.canonical, s.name
                    ),
                )
            })?;
        }
    }
    let cache = sweep::cache::PhaseCache::new();
    let opts = sweep::SweepOptions {
        out: &a.out,
        resume: a.resume,
        shard,
        jobs: a.jobs,
        cache: if a.no_reuse { None } else { Some(&cache) },
        flicker: a.flicker,
    };
    // Progress bar with ETA on a terminal (indicatif hides it when stderr is not a terminal).
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:30} {pos}/{len} rows  {elapsed} elapsed, ETA {eta}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let progress = |done: usize, total: usize| {
        if bar.length() != Some(total as u64) {
            // The first call: rows kept by --resume do not count towards the rate.
            bar.set_length(total as u64);
            bar.set_position(done as u64);
            bar.reset_eta();
        } else {
            bar.set_position(done as u64);
        }
    };
    let summary = sweep::run(&configs, &scenes, &opts, &progress);
    bar.finish_and_clear();
    let summary = summary?;
    eprintln!(
        "igemu sweep: {} configurations x {} scenes; this run: {} rows ({} kept from {}, {} computed) -> {}",
        configs.len(),
        scenes.len(),
        summary.planned,
        summary.reused,
        a.out,
        summary.computed,
        a.out
    );
    let rows = &summary.rows;
    if let Some(p) = &a.plot {
        sweep::plot::write(rows, axes[0], p)?;
    }
    let front = pareto::front(rows, &axes);
    println!(
        "Pareto front on {} ({} of {} rows):",
        axes.iter()
            .map(|x| x.name())
            .collect::<Vec<_>>()
            .join(" x "),
        front.len(),
        rows.len()
    );
    print!("  {:>5}  {:<16}", "index", "scene");
    for x in &axes {
        print!("  {:>18}", x.name());
    }
    println!("  configuration");
    for &i in &front {
        let r = &rows[i];
        print!("  {:>5}  {:<16}", r.index, r.scene);
        for x in &axes {
            print!("  {:>18.4}", x.value(r));
        }
        let cfg: Vec<String> = r.config.iter().map(|(k, v)| format!("{k}={v}")).collect();
        println!("  {}", cfg.join(" "));
    }
    Ok(ExitCode::SUCCESS)
}

fn ranges(a: RangesArgs) -> Result<ExitCode, Error> {
    use igemu::sweep::ranges::{self, Export};
    if let Some(e) = &a.export {
        let hw = HwConfig::resolve(a.s.hw.as_deref())?;
        let lang = match e.as_str() {
            "ac_fixed" => Export::AcFixed,
            "ap_fixed" => Export::ApFixed,
            "systemc" => Export::SystemC,
            _ => Export::Verilog,
        };
        print!("{}", ranges::export(&hw, lang));
        return Ok(ExitCode::SUCCESS);
    }
    let r = run(&a.s, RenderOptions { stage_local: false })?;
    let rows = ranges::ranges(&r.report.stages);
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&rows).expect("serialisable")
        );
        return Ok(ExitCode::SUCCESS);
    }
    println!(
        "{:<12} {:<28} {:>10} {:>14} {:>14} {:>10} {:>10}",
        "stage", "signal", "format", "min (LSB)", "max (LSB)", "narrowest", "overflows"
    );
    for s in rows {
        let opt = |v: Option<i128>| v.map_or("-".to_string(), |v| v.to_string());
        println!(
            "{:<12} {:<28} {:>10} {:>14} {:>14} {:>10} {:>10}",
            s.stage,
            s.signal,
            s.format,
            opt(s.min),
            opt(s.max),
            s.narrowest.unwrap_or_else(|| "-".into()),
            s.overflows
        );
    }
    Ok(ExitCode::SUCCESS)
}
