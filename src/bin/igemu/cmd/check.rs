//! `igemu check`: the regression gate. Renders and exits 1 when a threshold on the DAC
//! code differences or the visible error fails.

use crate::args::{SceneArgs, arg_error};
use crate::out::outln;
use clap::Args;
use igemu::error::Error;
use igemu::stage::RunOptions;
use std::process::ExitCode;

#[derive(Args)]
pub struct CheckArgs {
    #[command(flatten)]
    pub s: SceneArgs,
    /// Fail when any DAC code differs from the reference by more than N (0..=65535: DAC codes have at most 16 bits).
    #[arg(long, value_name = "N", value_parser = crate::args::int_in(0, 65535), allow_negative_numbers = true)]
    pub max_code_diff: Option<u32>,
    /// Fail when the fraction of identical DAC codes is below F (0..=1).
    #[arg(long, allow_negative_numbers = true)]
    pub min_identical: Option<f64>,
    /// Fail when more than this fraction of pixels has a visible (over delta) Weber error (0..=1).
    #[arg(long, allow_negative_numbers = true)]
    pub max_visible: Option<f64>,
    /// Print the verdict as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `igemu check`; returns the exit code.
pub fn run(a: CheckArgs) -> Result<ExitCode, Error> {
    for (flag, v) in [
        ("--min-identical", a.min_identical),
        ("--max-visible", a.max_visible),
    ] {
        if let Some(f) = v
            && !(f.is_finite() && (0.0..=1.0).contains(&f))
        {
            return Err(arg_error(
                flag,
                format!("must be a fraction in 0..=1, got {f}"),
            ));
        }
    }
    let r = a.s.render(RunOptions::FAST)?;
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
        outln!(
            "{}",
            serde_json::to_string_pretty(&v).expect("serialisable")
        );
    } else if failed.is_empty() {
        outln!(
            "check passed: max |code diff| {}, identical {:.4}%, visible {:.4}%",
            c.max_abs_diff,
            100.0 * c.identical_fraction,
            100.0 * wv.over_delta_fraction
        );
    } else {
        for f in &failed {
            outln!("check FAILED: {f}");
        }
    }
    Ok(if failed.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}
