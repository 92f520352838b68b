//! The `igemu` command line. `main` only maps `try_main`'s result to an exit code:
//! 0 ok, 1 a check failed, 2 bad input or error.

use clap::{Args, Parser, Subcommand};
use igemu::error::{Error, FileError};
use igemu::hw::HwConfig;
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
    let r = run(
        &a.s,
        RenderOptions {
            stage_local: !a.no_local,
        },
    )?;
    let (w, h) = (r.report.scene.width, r.report.scene.height);
    output::write_dac(&a.out, &r.dac, w, h, r.dac_bits)?;
    if let Some(p) = &a.reference_out {
        output::write_dac(p, &r.dac_ref, w, h, r.dac_bits)?;
    }
    if let Some(p) = &a.diff_out {
        output::write_diff(p, &r.dac, &r.dac_ref, w, h)?;
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
    println!(
        "cost: storage {} bits ({:.1} KiB), LUT/ROM {} bits | overflows {}",
        r.storage_bits,
        r.storage_bits as f64 / 8192.0,
        r.lut_bits,
        r.overflows
    );
    println!("wrote {out}");
}
