//! `igemu ranges`: the observed min/max per signal and the narrowest format holding it, or
//! with `--export` the configuration's formats as ac_fixed, ap_fixed, SystemC or Verilog.
//! A colour render lists each channel (a `channel` column) and exports a typedef per channel.

use crate::args::{ExportArg, SceneArgs};
use crate::out::{out, outln};
use clap::Args;
use igemu::analysis::ranges;
use igemu::error::Error;
use igemu::stage::RunOptions;
use std::process::ExitCode;

#[derive(Args)]
pub struct RangesArgs {
    #[command(flatten)]
    pub s: SceneArgs,
    /// Print the configuration's formats as ac_fixed, ap_fixed, systemc or verilog instead.
    #[arg(long, value_enum)]
    pub export: Option<ExportArg>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `igemu ranges`; returns the exit code.
pub fn run(a: RangesArgs) -> Result<ExitCode, Error> {
    if let Some(e) = a.export {
        let hw = a.s.hw()?;
        let channels = igemu::pipeline::plan::channels(&a.s.scene()?, &hw);
        out!("{}", ranges::export(&hw, e.into(), channels));
        return Ok(ExitCode::SUCCESS);
    }
    let r = a.s.render(RunOptions::FAST)?;
    let rows = ranges::ranges_of(&r.report);
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&rows).expect("serialisable")
        );
        return Ok(ExitCode::SUCCESS);
    }
    // A colour render has a channel column (`-`: a signal the channels share).
    let colour = r.report.colour.is_some();
    let channel = |c: Option<&str>| {
        if colour {
            format!("{:<8}", c.unwrap_or("-"))
        } else {
            String::new()
        }
    };
    outln!(
        "{:<12} {}{:<28} {:>10} {:>14} {:>14} {:>10} {:>10}",
        "stage",
        if colour {
            format!("{:<8}", "channel")
        } else {
            String::new()
        },
        "signal",
        "format",
        "min (LSB)",
        "max (LSB)",
        "narrowest",
        "overflows"
    );
    // The overflow counters, each once (a colour render lists a lane's per channel).
    let mut counters: Vec<&str> = Vec::new();
    for s in rows.iter().filter(|s| s.overflow_only) {
        if !counters.contains(&s.signal.as_str()) {
            counters.push(&s.signal);
        }
    }
    let counters = counters.join(", ");
    for s in &rows {
        let opt = |v: Option<i128>| v.map_or("-".to_string(), |v| v.to_string());
        outln!(
            "{:<12} {}{:<28} {:>10} {:>14} {:>14} {:>10} {:>10}",
            s.stage,
            channel(s.channel),
            s.signal,
            s.format,
            opt(s.min),
            opt(s.max),
            s.narrowest.clone().unwrap_or_else(|| "-".into()),
            s.overflows
        );
    }
    if !counters.is_empty() {
        outln!("-: {counters} count only their overflows (their datapaths record no values)");
    }
    Ok(ExitCode::SUCCESS)
}
