//! `igemu flicker`: small-object flicker, a light point and a thin line swept over
//! sub-pixel phases.

use crate::args::FilterArg;
use crate::out::outln;
use clap::Args;
use igemu::config::HwConfig;
use igemu::error::Error;
use std::process::ExitCode;

#[derive(Args)]
pub struct FlickerArgs {
    /// Hardware config: a preset (linear12, linear11, linear8) or a TOML file.
    #[arg(long)]
    pub hw: Option<String>,
    /// Override the filter.
    #[arg(long, value_enum)]
    pub filter: Option<FilterArg>,
    /// Model a system without gamma correction (a linear LUT).
    #[arg(long)]
    pub no_gamma_correction: bool,
    /// Sub-pixel phases per axis (2..=64).
    #[arg(long, default_value_t = 32, value_parser = crate::args::int_in(2, 64), allow_negative_numbers = true)]
    pub phases: u32,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `igemu flicker`; returns the exit code.
pub fn run(a: FlickerArgs) -> Result<ExitCode, Error> {
    let mut hw = HwConfig::resolve(a.hw.as_deref())?;
    if let Some(f) = a.filter {
        hw.accumulate.filter = f.into();
        hw.validate()
            .map_err(|(field, msg)| hw.error(&field, msg))?;
    }
    if a.no_gamma_correction {
        hw.gamma.correction = false;
    }
    let r = igemu::analysis::flicker::flicker(&hw, a.phases)?;
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&r).expect("serialisable")
        );
        return Ok(ExitCode::SUCCESS);
    }
    outln!(
        "flicker | hardware `{}` | filter {} | gamma {} {} | {}x{} phases on a {}x{} px scene",
        r.hardware,
        r.filter.name(),
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
        outln!("{} ({}):", o.object, o.description);
        outln!(
            "  accumulator sum ripple        {} LSB ({:.4}% of the mean)",
            o.acc_ripple_lsb,
            o.acc_ripple_pct
        );
        outln!(
            "  displayed luminance ripple    {:.3}% peak to peak of the mean ({:.3} cd/m2 summed)",
            o.displayed_ripple_pct,
            o.mean_luminance
        );
        outln!(
            "  peak-pixel modulation         {:.2}%",
            o.peak_pixel_modulation_pct
        );
        outln!(
            "  split 50/50 over two pixels   {:+.2}% brightness vs the pixel-aligned phase",
            o.half_pixel_brightness_error_pct
        );
    }
    if !r.gamma_correction {
        outln!(
            "analytic split error without correction: 2 (1/2)^{} - 1 = {:+.2}%",
            r.gamma,
            r.analytic_split_error_pct
        );
    }
    Ok(ExitCode::SUCCESS)
}
