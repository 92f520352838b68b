//! `igemu dof`: depth of field of a thin lens, front and back depth, near and far limits.

use crate::args::arg_error;
use clap::Args;
use igemu::analysis::calc;
use igemu::error::Error;
use std::process::ExitCode;

#[derive(Args)]
pub struct DofArgs {
    /// f-number N.
    #[arg(long)]
    pub f_number: f64,
    /// Permissible circle of confusion C (same length unit as the others, e.g. mm).
    #[arg(long)]
    pub coc: f64,
    /// Focal length F.
    #[arg(long)]
    pub focal: f64,
    /// Focus distance L.
    #[arg(long)]
    pub distance: f64,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `igemu dof`; returns the exit code.
pub fn run(a: DofArgs) -> Result<ExitCode, Error> {
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
