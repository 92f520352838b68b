//! `igemu dof`: depth of field of a thin lens, front and back depth, near and far limits.

use crate::args::{arg_error, num};
use crate::out::outln;
use clap::Args;
use igemu::analysis::calc;
use igemu::error::Error;
use std::process::ExitCode;

#[derive(Args)]
pub struct DofArgs {
    /// f-number N.
    #[arg(long, allow_negative_numbers = true)]
    pub f_number: f64,
    /// Permissible circle of confusion C (same length unit as the others, e.g. mm).
    #[arg(long, allow_negative_numbers = true)]
    pub coc: f64,
    /// Focal length F.
    #[arg(long, allow_negative_numbers = true)]
    pub focal: f64,
    /// Focus distance L.
    #[arg(long, allow_negative_numbers = true)]
    pub distance: f64,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// The f-numbers `dof` accepts: real lenses are about f/0.7 to f/64, pinhole cameras f/1000.
const F_NUMBER: (f64, f64) = (0.5, 1000.0);
/// The lengths `dof` accepts (any one unit): every result stays a finite number.
const LENGTH: (f64, f64) = (1e-6, 1e9);

/// Checks each flag against its range, naming it.
fn check_flags(a: &DofArgs) -> Result<(), Error> {
    for (flag, v, (lo, hi), what) in [
        ("--f-number", a.f_number, F_NUMBER, "an f-number"),
        ("--coc", a.coc, LENGTH, "a length"),
        ("--focal", a.focal, LENGTH, "a length"),
        ("--distance", a.distance, LENGTH, "a length"),
    ] {
        if !(v.is_finite() && (lo..=hi).contains(&v)) {
            return Err(arg_error(
                flag,
                format!(
                    "must be {what} in [{}, {}], got {}",
                    num(lo),
                    num(hi),
                    num(v)
                ),
            ));
        }
    }
    if a.distance <= a.focal {
        return Err(arg_error(
            "--distance",
            format!(
                "must be greater than --focal ({}), got {}; a thin lens cannot focus closer",
                a.focal, a.distance
            ),
        ));
    }
    Ok(())
}

/// Runs `igemu dof`; returns the exit code.
pub fn run(a: DofArgs) -> Result<ExitCode, Error> {
    check_flags(&a)?;
    let d = calc::depth_of_field(a.f_number, a.coc, a.focal, a.distance)
        .map_err(|m| arg_error("dof", m))?;
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&d).expect("serialisable")
        );
    } else {
        outln!(
            "N = {}, C = {}, F = {}, L = {}",
            d.f_number,
            d.coc,
            d.focal,
            d.distance
        );
        outln!("  front depth of field  dL1 = {:.2}", d.front);
        outln!("  back depth of field   dL2 = {:.2}", d.back);
        outln!("  total                 dL  = {:.2}", d.total);
        outln!(
            "  sharp from {:.2} to {:.2} (hyperfocal distance {:.1})",
            d.near,
            d.far,
            d.hyperfocal
        );
    }
    Ok(ExitCode::SUCCESS)
}
