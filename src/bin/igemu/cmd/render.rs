//! `igemu render`: render a scene through the fixed-point pipeline and the float
//! reference; write the image, the optional reference, difference, banding and stage dumps,
//! and the report (text, JSON on stdout or a JSON file). Every file is written atomically
//! ([`igemu::output::AtomicFile`]); no output may be an input.

use crate::args::{DumpTap, SceneArgs, TruthArgs, arg_error, parse_dump};
use crate::guard::{Inputs, distinct_outputs};
use crate::out::outln;
use crate::print::print_report;
use clap::Args;
use igemu::error::Error;
use igemu::output;
use igemu::pipeline;
use igemu::stage::RunOptions;
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
    /// Write a tap after a stage as a 16-bit grey PNG: TAP=PATH, TAP one of accumulate[.frame], accumulate.depth, accumulate.coverage, dof[.frame], dof.depth, dof.coverage, gamma[.codes], dither[.codes].
    #[arg(long = "dump", value_name = "TAP=PATH", value_parser = parse_dump)]
    pub dump: Vec<(DumpTap, String)>,
    /// Write the memory images of the plan (LUTs, ROMs, frame memory) as $readmemh hex files with a manifest.json of widths and depths into DIR.
    #[arg(long, value_name = "DIR")]
    pub rom_out: Option<String>,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Write the JSON report to a file.
    #[arg(long)]
    pub report: Option<String>,
    /// Write a self-contained HTML report: images side by side, plan, stage table, signals, plots.
    #[arg(long, value_name = "REPORT.html")]
    pub html: Option<String>,
    /// Skip the stage-local comparisons (faster).
    #[arg(long)]
    pub no_local: bool,
    /// Write the banding map: the output dimmed, smooth regions lifted, visible contour steps white (8-bit PNG).
    #[arg(long)]
    pub banding_out: Option<String>,
    /// Also run the per-pixel depth-of-field reference (slow: O(N^2 M^2)) and the layer theorem check.
    #[arg(long)]
    pub dof_reference: bool,
    #[command(flatten)]
    pub truth: TruthArgs,
    /// Also write the depth-of-field truth's DAC codes (same bit depth as OUT; with --dof-truth, a thin-lens scene).
    #[arg(long, requires = "dof_truth")]
    pub truth_out: Option<String>,
}

/// Runs `igemu render`; returns the exit code.
pub fn run(a: RenderArgs) -> Result<ExitCode, Error> {
    let inputs = Inputs::of(&a.s);
    let mut outs = vec![("--out", a.out.as_str())];
    for (flag, p) in [
        ("--reference-out", &a.reference_out),
        ("--diff-out", &a.diff_out),
        ("--banding-out", &a.banding_out),
        ("--truth-out", &a.truth_out),
        ("--report", &a.report),
        ("--html", &a.html),
    ] {
        outs.extend(p.as_deref().map(|p| (flag, p)));
    }
    outs.extend(a.dump.iter().map(|(_, p)| ("--dump", p.as_str())));
    for (flag, p) in &outs {
        inputs.check(flag, p)?;
    }
    distinct_outputs(&outs)?;
    let rom_dir = a.rom_out.as_deref().map(std::path::Path::new);
    if let Some(dir) = rom_dir {
        inputs.check_in("--rom-out", dir, [igemu::cost::rom::MANIFEST])?;
    }
    let scene = a.s.scene()?;
    if a.truth_out.is_some() && matches!(scene.camera.lens, igemu::scene::Lens::Pinhole) {
        return Err(arg_error(
            "--truth-out",
            format!(
                "scene `{}` has a pinhole camera: everything is in focus, there is no depth-of-field truth to write",
                scene.name
            ),
        ));
    }
    let hw = a.s.hw()?;
    let r = pipeline::render(
        &scene,
        &hw,
        a.s.opts(RunOptions {
            stage_local: !a.no_local,
            dof_reference: a.dof_reference,
            dof_truth_samples: a.truth.samples(),
            ..RunOptions::default()
        }),
    )?;
    let (w, h) = (r.report.scene.width, r.report.scene.height);
    let stages: Vec<_> = r
        .steps
        .iter()
        .map(|s| (s.id, &s.outcome.report.cost, s.outcome.images.as_slice()))
        .collect();
    if let Some(dir) = rom_dir {
        // The hex files' names are known once the plan has run: checked before any write.
        inputs.check_in("--rom-out", dir, igemu::cost::rom::files(&stages))?;
    }
    output::write_dac(&a.out, &r.dac, w, h, r.dac_bits)?;
    if let Some(p) = &a.reference_out {
        output::write_dac(p, &r.dac_ref, w, h, r.dac_bits)?;
    }
    if let Some(p) = &a.diff_out {
        output::write_diff(p, &r.dac, &r.dac_ref, w, h)?;
    }
    if let (Some(p), Some(t)) = (&a.truth_out, &r.truth_dac) {
        output::write_dac(p, t, w, h, r.dac_bits)?;
    }
    if let Some(p) = &a.banding_out {
        let img =
            igemu::perceptual::banding_image(&r.dac, &r.contour_map, (1u32 << r.dac_bits) - 1);
        output::write_raw8(p, &img, w, h)?;
    }
    for (tap, path) in &a.dump {
        let taps = r.taps(tap.stage).ok_or_else(|| {
            arg_error(
                "--dump",
                format!(
                    "stage `{}` is not in the plan of this render: {}",
                    tap.stage,
                    r.plan
                        .decisions
                        .iter()
                        .find(|d| d.stage == tap.stage)
                        .map_or("", |d| d.need.reason.as_str())
                ),
            )
        })?;
        let codes = taps
            .image(tap.plane)
            .expect("the planes of a stage are on its taps");
        output::write_raw16(path, &codes, w, h)?;
    }
    if let Some(dir) = rom_dir {
        igemu::cost::rom::write(dir, &stages)?;
    }
    let json = serde_json::to_string_pretty(&r.report).expect("serialisable");
    if let Some(p) = &a.report {
        output::write_file(p, &json)?;
    }
    if let Some(p) = &a.html {
        output::write_file(p, &igemu::html::render_page(&scene, &hw, &r, p)?)?;
    }
    if a.json {
        outln!("{json}");
    } else {
        print_report(&r.report, &a.out)?;
    }
    Ok(ExitCode::SUCCESS)
}
