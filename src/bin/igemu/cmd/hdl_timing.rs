//! `igemu hdl timing`: each HDL model's latency and initiation interval measured under
//! Verilator (full rate and with injected stalls) beside the `[cycles.<stage>]` values of
//! the chosen hardware; exit 1 naming the stage and field where they disagree.

use crate::args::{HdlDirs, SceneArgs, arg_error};
use crate::out::outln;
use clap::builder::PossibleValue;
use clap::{Args, ValueEnum};
use igemu::error::Error;
use igemu::hdl::correlate::{self as corr, BOUND_PCT};
use igemu::hdl::timing::{self, Measured, TIMED, Timed};
use igemu::hdl::verilator::Sim;
use std::path::Path;
use std::process::ExitCode;

#[derive(Args)]
pub struct HdlTimingArgs {
    /// Only this stage (default: the six stages with an HDL model).
    #[arg(long, value_enum)]
    pub stage: Option<TimedArg>,
    /// Instead: stream the scene's real token stream of each stage in the plan through its RTL and compare the RTL's cycles with the cycle model's busy cycles + latency (exit 1 beyond the documented error bound).
    #[arg(long)]
    pub correlate: bool,
    #[command(flatten)]
    pub s: SceneArgs,
    #[command(flatten)]
    pub dirs: HdlDirs,
}

/// A stage whose `[cycles.<stage>]` timing an HDL model implements.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimedArg(pub Timed);

impl ValueEnum for TimedArg {
    fn value_variants<'a>() -> &'a [Self] {
        static ALL: [TimedArg; 6] = [
            TimedArg(TIMED[0]),
            TimedArg(TIMED[1]),
            TimedArg(TIMED[2]),
            TimedArg(TIMED[3]),
            TimedArg(TIMED[4]),
            TimedArg(TIMED[5]),
        ];
        &ALL
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.0.timing.name()))
    }
}

/// The Verilator check every RTL measurement needs: an error naming what to install.
pub fn need_verilator(flag: &str) -> Result<(), Error> {
    if Sim::Verilator.available() {
        return Ok(());
    }
    Err(arg_error(
        flag,
        "RTL timing is measured under Verilator, which is not installed (it needs verilator, make and g++: apt-get install -y verilator make g++)".into(),
    ))
}

/// Measures the chosen stages' RTL on the scene and hardware of `s` (Verilator builds cached
/// under `cache`); each with its bench note.
pub fn measure_all(
    stages: &[Timed],
    s: &SceneArgs,
    cache: &Path,
) -> Result<Vec<(Measured, Option<String>)>, Error> {
    let scene = s.scene()?;
    let hw = s.hw()?;
    stages
        .iter()
        .map(|&t| timing::measure_stage(t, &scene, &hw, cache))
        .collect()
}

/// `igemu cycles --timing-from-rtl`: the hardware's `[cycles]` with the latency and ii
/// measured from the six HDL models on the scene and hardware of `s`, and a line naming them.
pub fn rtl_cycles(
    s: &SceneArgs,
    dirs: &HdlDirs,
    hw: &igemu::config::HwConfig,
) -> Result<(igemu::config::CyclesCfg, String), Error> {
    need_verilator("--timing-from-rtl")?;
    let cache = dirs.apply()?.join("hdl-verilator");
    let measured: Vec<Measured> = measure_all(&TIMED, s, &cache)?
        .into_iter()
        .map(|(m, _)| m)
        .collect();
    let named: Vec<String> = measured
        .iter()
        .map(|m| {
            format!(
                "{} latency {} ii {:.3}",
                m.timed.timing,
                m.latency,
                m.ii_full.value()
            )
        })
        .collect();
    Ok((
        timing::with_measured(&hw.cycles, &measured),
        format!("timing from the RTL (Verilator): {}", named.join(", ")),
    ))
}

/// Runs `igemu hdl timing`.
pub fn run(a: HdlTimingArgs) -> Result<ExitCode, Error> {
    need_verilator("hdl timing")?;
    let cache = a.dirs.apply()?.join("hdl-verilator");
    let hw = a.s.hw()?;
    let stages: Vec<Timed> = match a.stage {
        Some(t) => vec![t.0],
        None => TIMED.to_vec(),
    };
    if a.correlate {
        return correlate(&stages, &a.s, &cache);
    }
    let measured = measure_all(&stages, &a.s, &cache)?;
    outln!(
        "hdl timing | hardware `{}` | Verilator, per module instance (the model's lanes = instances x lanes per instance)",
        hw.name
    );
    outln!(
        "{:<11} {:<15} {:>11} {:>13} {:>13} {:>15} {:>8} {:>8}  verdict",
        "stage",
        "module",
        "latency",
        "ii full",
        "ii stalled",
        "lanes",
        "vectors",
        "stalls"
    );
    let mut bad = Vec::new();
    for (m, note) in &measured {
        let Some(&t) = hw.cycles.timing(m.timed.timing) else {
            continue;
        };
        let miss = timing::compare(m, &t);
        outln!(
            "{:<11} {:<15} {:>11} {:>13} {:>13} {:>15} {:>8} {:>8}  {}",
            m.timed.timing.name(),
            m.timed.module,
            format!("{} / {}", m.latency, t.latency),
            format!("{:.3} / {}", m.ii_full.value(), t.ii),
            format!("{:.3} / {}", m.ii_stall.value(), t.ii),
            format!(
                "{} = {} x {}",
                t.lanes,
                t.lanes / m.timed.lanes,
                m.timed.lanes
            ),
            m.items,
            m.stalls,
            if miss.is_empty() { "agree" } else { "DISAGREE" }
        );
        if let Some(n) = note {
            outln!("  ({}: {n})", m.timed.timing.name());
        }
        bad.extend(miss);
    }
    outln!(
        "latency, ii: RTL / [cycles.<stage>]; ii stalled: net of the stall cycles (the testbench withheld an input or held back a valid output); lanes: model = instances x lanes per instance"
    );
    for m in &bad {
        outln!("mismatch: {m} (hardware `{}`)", hw.name);
    }
    Ok(if bad.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// `igemu hdl timing --correlate`: the RTL's cycles on the run's token stream against the
/// cycle model's, per stage of the plan with an HDL model.
fn correlate(stages: &[Timed], s: &SceneArgs, cache: &Path) -> Result<ExitCode, Error> {
    let scene = s.scene()?;
    let hw = s.hw()?;
    let r = igemu::pipeline::render(&scene, &hw, s.opts(igemu::stage::RunOptions::FAST))?;
    outln!(
        "hdl timing --correlate | scene `{}` {}x{} | hardware `{}` | one instance: the busiest lane's ceil(items / lanes) vectors per token, under Verilator",
        scene.name,
        r.report.scene.width,
        r.report.scene.height,
        hw.name
    );
    outln!(
        "{:<11} {:<15} {:>7} {:>10} {:>9} {:>11} {:>11} {:>9}",
        "stage",
        "module",
        "tokens",
        "items",
        "vectors",
        "RTL cycles",
        "model",
        "error"
    );
    let mut worst: f64 = 0.0;
    let mut absent = Vec::new();
    for &t in stages {
        let (b, _) = timing::bench_for(t, &scene, &hw)?;
        let Some(c) = corr::correlate(t, &r.workload, &b, cache)? else {
            absent.push(t.timing.name());
            continue;
        };
        worst = worst.max(c.error_pct().abs());
        outln!(
            "{:<11} {:<15} {:>7} {:>10} {:>9} {:>11} {:>11} {:>8.3}%",
            t.timing.name(),
            t.module,
            c.tokens,
            c.items,
            c.vectors,
            c.rtl_cycles,
            c.model_cycles(),
            c.error_pct()
        );
    }
    outln!("model: the stage's busy cycles + latency; error: (RTL - model) / model");
    if !absent.is_empty() {
        outln!("not in the plan: {}", absent.join(", "));
    }
    if worst > BOUND_PCT {
        outln!("mismatch: correlation error {worst:.3}% exceeds the bound {BOUND_PCT}%");
        return Ok(ExitCode::from(1));
    }
    outln!("worst error {worst:.3}% within the bound {BOUND_PCT}%");
    Ok(ExitCode::SUCCESS)
}
