//! `igemu render`: render a scene through the fixed-point pipeline and the float
//! reference; write the image, the optional reference, difference, banding and stage dumps,
//! and the report (text, JSON on stdout or a JSON file).

use crate::args::{SceneArgs, arg_error};
use crate::print::print_report;
use clap::Args;
use igemu::error::Error;
use igemu::output;
use igemu::pipeline::{self, RenderOptions};
use std::process::ExitCode;

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub s: SceneArgs,
    /// Output image of the fixed pipeline's DAC codes.
    #[arg(short = 'o', long = "out", default_value = "igemu.png")]
    pub out: String,
    /// Also write the float reference's DAC codes (same bit depth as OUT).
    #[arg(long)]
    pub reference_out: Option<String>,
    /// Also write the difference map (128 = identical, 32 grey levels per code).
    #[arg(long)]
    pub diff_out: Option<String>,
    /// Write a stage's raw codes as a 16-bit grey PNG: STAGE=PATH with STAGE one of accumulate, coverage, depth, gamma.
    #[arg(long = "dump", value_name = "STAGE=PATH")]
    pub dump: Vec<String>,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Write the JSON report to a file.
    #[arg(long)]
    pub report: Option<String>,
    /// Skip the stage-local comparisons (faster).
    #[arg(long)]
    pub no_local: bool,
    /// Write the banding map: the output dimmed, smooth regions lifted, visible contour steps white (8-bit PNG).
    #[arg(long)]
    pub banding_out: Option<String>,
    /// Also run the per-pixel depth-of-field reference (slow: O(N^2 M^2)) and the layer theorem check.
    #[arg(long)]
    pub dof_reference: bool,
}

/// Runs `igemu render`; returns the exit code.
pub fn run(a: RenderArgs) -> Result<ExitCode, Error> {
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
    let r = pipeline::render_ext(
        &a.s.scene()?,
        &a.s.hw()?,
        RenderOptions {
            stage_local: !a.no_local,
        },
        a.dof_reference,
    )?;
    let (w, h) = (r.report.scene.width, r.report.scene.height);
    output::write_dac(&a.out, &r.dac, w, h, r.dac_bits)?;
    if let Some(p) = &a.reference_out {
        output::write_dac(p, &r.dac_ref, w, h, r.dac_bits)?;
    }
    if let Some(p) = &a.diff_out {
        output::write_diff(p, &r.dac, &r.dac_ref, w, h)?;
    }
    if let Some(p) = &a.banding_out {
        let img =
            igemu::perceptual::banding_image(&r.dac, &r.contour_map, (1u32 << r.dac_bits) - 1);
        output::write_raw8(p, &img, w, h)?;
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
