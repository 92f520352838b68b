//! `igemu filters`: the accumulate filters side by side (docs/filters.md): DC ripple, step
//! ringing, flicker, frequency response, error against the float reference, cost, MACs,
//! cycles and time, one row per filter.

use crate::args::{FilterArg, load_scene};
use crate::out::outln;
use clap::Args;
use igemu::analysis::filters::{FREQUENCIES, FilterRow, row};
use igemu::config::{FilterKind, HwConfig};
use igemu::error::Error;
use std::process::ExitCode;

#[derive(Args)]
pub struct FiltersArgs {
    /// Hardware config: a preset or a TOML file (its filter is replaced row by row).
    #[arg(long)]
    pub hw: Option<String>,
    /// The scene of the error, cost, cycles and time columns (default: the embedded default scene).
    #[arg(long)]
    pub scene: Option<String>,
    /// Only these filters (repeatable; default: all six).
    #[arg(long, value_enum)]
    pub filter: Vec<FilterArg>,
    /// Flicker phases per axis (2..=64).
    #[arg(long, default_value_t = 8, value_parser = crate::args::int_in(2, 64), allow_negative_numbers = true)]
    pub phases: u32,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `igemu filters`; returns the exit code.
pub fn run(a: FiltersArgs) -> Result<ExitCode, Error> {
    let hw = HwConfig::resolve(a.hw.as_deref())?;
    let scene = load_scene(a.scene.as_deref())?;
    let filters: Vec<FilterKind> = if a.filter.is_empty() {
        FilterKind::ALL.to_vec()
    } else {
        a.filter.iter().map(|&f| f.into()).collect()
    };
    let mut rows = Vec::new();
    for f in filters {
        let mut h = hw.clone();
        h.accumulate.filter = f;
        h.validate().map_err(|(field, msg)| h.error(&field, msg))?;
        rows.push(row(&h, f, &scene, a.phases)?);
    }
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&rows).expect("serialisable")
        );
        return Ok(ExitCode::SUCCESS);
    }
    outln!(
        "filters | hardware `{}` | scene `{}` | {}x{} samples/pixel | weight_bits {} | frame {} {}",
        hw.name,
        scene.name,
        hw.raster.samples,
        hw.raster.samples,
        hw.accumulate.weight_bits,
        hw.accumulate.frame.format,
        hw.accumulate.frame.overflow
    );
    outln!(
        "| filter | ripple (LSB of 2^f: quantised / rounded one by one) | step under / over (frame LSB) | float under / over | step under / over (DAC) | flicker sample point acc % | flicker line displayed % | |H| at {} c/px (quantised; analytic) | acc max / mean err (LSB) | DAC max diff | cost bits | weight / acc bits | MACs | cycles | fixed ms |",
        FREQUENCIES.map(|u| u.to_string()).join(", ")
    );
    outln!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for r in &rows {
        outln!("{}", line(r));
    }
    Ok(ExitCode::SUCCESS)
}

fn line(r: &FilterRow) -> String {
    let h = r
        .response
        .iter()
        .map(|x| match x.analytic {
            Some(a) => format!("{:.3}; {:.3}", x.quantised, a),
            None => format!("{:.3}", x.quantised),
        })
        .collect::<Vec<_>>()
        .join(" / ");
    format!(
        "| {} | {} / {} | {} / {} | {:.2} / {:.2} | {} / {} | {:.2} | {:.2} | {} | {:.2} / {:+.3} | {} | {} | {} / {} | {} | {} | {:.1} |",
        r.filter,
        r.ripple.group_spread_lsb,
        r.ripple.rounded_spread_lsb,
        r.step.undershoot,
        r.step.overshoot,
        r.step.float_undershoot,
        r.step.float_overshoot,
        r.step.undershoot_dac,
        r.step.overshoot_dac,
        r.flicker_sample_point_pct,
        r.flicker_line_pct,
        h,
        r.acc_max_err,
        r.acc_mean_err,
        r.dac_max_diff,
        r.cost_bits,
        r.weight_bits,
        r.acc_bits.map_or("frame".to_string(), |b| b.to_string()),
        r.macs,
        r.cycles,
        r.fixed_ms
    )
}
