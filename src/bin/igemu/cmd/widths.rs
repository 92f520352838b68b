//! `igemu widths`: word widths from contrast, Weber fraction and gamma (Kovalev & Tokarev
//! eq. 9-11), validated by emulating a ramp at the recommended widths and one bit narrower.

use crate::args::{arg_error, load_scene};
use crate::print::print_width_checks;
use clap::Args;
use igemu::analysis::calc;
use igemu::error::Error;
use std::process::ExitCode;

#[derive(Args)]
pub struct WidthsArgs {
    /// Contrast K = B_max / B_min (> 1); default: the scene's display block.
    #[arg(long)]
    pub contrast: Option<f64>,
    /// Weber fraction delta (0 < delta < 1); default: the scene's display block.
    #[arg(long)]
    pub weber: Option<f64>,
    /// Display gamma (> 1); default: the scene's display block, else 2.4.
    #[arg(long)]
    pub gamma: Option<f64>,
    /// Take contrast, Weber fraction and gamma from this scene's display block (flags override).
    #[arg(long)]
    pub scene: Option<String>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `igemu widths`; returns the exit code.
pub fn run(a: WidthsArgs) -> Result<ExitCode, Error> {
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
    let checks = igemu::analysis::widths::validate_widths(&w);
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
