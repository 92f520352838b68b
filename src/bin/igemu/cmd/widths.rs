//! `igemu widths`: word widths from contrast, Weber fraction and gamma (Kovalev & Tokarev
//! eq. 9-11), validated by emulating a ramp at the recommended widths and one bit narrower.

use crate::args::{arg_error, load_scene, num};
use crate::out::outln;
use crate::print::print_width_checks;
use clap::Args;
use igemu::analysis::calc;
use igemu::error::Error;
use std::process::ExitCode;

#[derive(Args)]
pub struct WidthsArgs {
    /// Contrast K = B_max / B_min (> 1); default: the scene's display block.
    #[arg(long, allow_negative_numbers = true)]
    pub contrast: Option<f64>,
    /// Weber fraction delta (0 < delta < 1); default: the scene's display block.
    #[arg(long, allow_negative_numbers = true)]
    pub weber: Option<f64>,
    /// Display gamma (1 < gamma <= 5, as the scene's display.gamma); default: the scene's display block, else 2.4.
    #[arg(long, allow_negative_numbers = true)]
    pub gamma: Option<f64>,
    /// Take contrast, Weber fraction and gamma from this scene's display block (flags override).
    #[arg(long)]
    pub scene: Option<String>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Widest code the calculator reports: more levels than `2^MAX_BITS` (or infinitely many)
/// come from a contrast and Weber fraction no display has.
const MAX_BITS: u32 = 64;

/// Checks the flags against the ranges of [`calc::widths`] (gamma also at most 5, the
/// range of a scene's `display.gamma`), each naming its flag.
fn check_flags(a: &WidthsArgs) -> Result<(), Error> {
    let bad = |flag: &str, v: f64, range: &str, hint: &str| {
        Err(arg_error(
            flag,
            format!("must be a finite number {range}, got {}; {hint}", num(v)),
        ))
    };
    if let Some(k) = a.contrast
        && !(k.is_finite() && k > 1.0)
    {
        return bad("--contrast", k, "> 1", "K = B_max / B_min");
    }
    if let Some(d) = a.weber
        && !(d.is_finite() && d > 0.0 && d < 1.0)
    {
        return bad("--weber", d, "in (0, 1)", "typical 0.02 to 0.05");
    }
    if let Some(g) = a.gamma
        && !(g.is_finite() && g > 1.0 && g <= 5.0)
    {
        return bad(
            "--gamma",
            g,
            "in (1, 5]",
            "eq. 10 uses (gamma - 1)^(1 - 1/gamma); CRTs are about 2.2 to 2.8",
        );
    }
    Ok(())
}

/// Runs `igemu widths`; returns the exit code.
pub fn run(a: WidthsArgs) -> Result<ExitCode, Error> {
    check_flags(&a)?;
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
    for (eq, l) in [
        ("N_I (eq. 9)", &w.linear),
        ("N_U (eq. 10)", &w.dac),
        ("m (eq. 11)", &w.log_grades),
    ] {
        if !(l.levels.is_finite() && l.bits <= MAX_BITS) {
            return Err(arg_error(
                "--contrast/--weber",
                format!(
                    "K = {} and delta = {} need {eq} = {} levels, more than a {MAX_BITS}-bit code holds; lower the contrast or raise the Weber fraction",
                    num(contrast),
                    num(weber),
                    num(l.levels)
                ),
            ));
        }
    }
    let checks = igemu::analysis::widths::validate_widths(&w);
    if a.json {
        let mut v = serde_json::to_value(&w).expect("serialisable");
        v["validation"] = serde_json::to_value(&checks).expect("serialisable");
        outln!(
            "{}",
            serde_json::to_string_pretty(&v).expect("serialisable")
        );
    } else {
        outln!(
            "contrast K = {}, Weber fraction = {}, gamma = {}",
            w.contrast,
            w.weber,
            w.gamma
        );
        outln!(
            "  linear intensity levels (eq. 9)  N_I = {:8.1}  -> {:2} bits",
            w.linear.levels,
            w.linear.bits
        );
        outln!(
            "  DAC levels (eq. 10)              N_U = {:8.1}  -> {:2} bits",
            w.dac.levels,
            w.dac.bits
        );
        outln!(
            "  log-code grades (eq. 11)         m   = {:8.1}  -> {:2} bits",
            w.log_grades.levels,
            w.log_grades.bits
        );
        outln!(
            "  largest contrast an 8-bit linear code holds: K = {:.2}",
            w.linear8_max_contrast
        );
        print_width_checks(&checks, w.weber)?;
    }
    Ok(ExitCode::SUCCESS)
}
