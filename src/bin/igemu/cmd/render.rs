//! `igemu render`: render a scene through the fixed-point pipeline and the float
//! reference; write the image, the optional reference, difference, banding and stage dumps,
//! and the report (text, JSON on stdout or a JSON file). Every file is written atomically
//! ([`igemu::output::AtomicFile`]); every output path is checked before the render (no
//! output may be an input or share a path with another).

use crate::args::{DumpTap, SceneArgs, TruthArgs, arg_error, parse_dump};
use crate::guard::{self, Inputs, distinct_outputs};
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
    /// The fixed model alone, with the cycle model, the cost and the overflows: no float reference and no comparison (the fast path; the image is the same).
    #[arg(long)]
    pub no_reference: bool,
    /// Write the banding map: the output dimmed, smooth regions lifted, visible contour steps white (8-bit PNG; one plane per channel for a colour render).
    #[arg(long)]
    pub banding_out: Option<String>,
    /// Write the CIEDE2000 map of a colour render, fixed against float (RGB heat map: black 0, blue 1, yellow 2.3, red 5 and above).
    #[arg(long, value_name = "PATH")]
    pub delta_e_out: Option<String>,
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
    check_outputs(&a, &inputs, &[igemu::cost::rom::MANIFEST.into()])?;
    let rom_dir = a.rom_out.as_deref().map(std::path::Path::new);
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
    if a.no_reference {
        return run_fast(&a, &scene, &hw, &inputs);
    }
    if a.delta_e_out.is_some() && pipeline::plan::channels(&scene, &hw) == 1 {
        return Err(arg_error(
            "--delta-e-out",
            format!(
                "scene `{}` on `{}` renders one grey channel: the CIEDE2000 map is of a colour render (a scene with [r, g, b] colours or `[image] colour = true`, or per-channel hardware widths)",
                scene.name, hw.name
            ),
        ));
    }
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
    let stages = rom_stages(&a, &inputs, &r.steps)?;
    write_image(&a.out, &r, false)?;
    if let Some(p) = &a.reference_out {
        write_image(p, &r, true)?;
    }
    if let Some(p) = &a.diff_out {
        match &r.colour {
            // Each channel's difference map in its own colour plane.
            Some(c) => {
                let maps: Vec<Vec<u8>> = c
                    .channels
                    .iter()
                    .map(|k| output::diff_values(&k.dac, &k.dac_ref))
                    .collect();
                output::write_rgb8(p, &output::interleave(&maps), w, h)?;
            }
            None => output::write_diff(p, &r.dac, &r.dac_ref, w, h)?,
        }
    }
    if let (Some(p), Some(t)) = (&a.truth_out, &r.truth_dac) {
        output::write_dac(p, t, w, h, r.dac_bits)?;
    }
    if let Some(p) = &a.banding_out {
        match &r.colour {
            Some(c) => {
                let maps: Vec<Vec<u8>> = c
                    .channels
                    .iter()
                    .map(|k| {
                        igemu::perceptual::banding_image(
                            &k.dac,
                            &k.contour_map,
                            (1u32 << k.bits) - 1,
                        )
                    })
                    .collect();
                output::write_rgb8(p, &output::interleave(&maps), w, h)?;
            }
            None => {
                let max = (1u32 << r.dac_bits) - 1;
                let img = igemu::perceptual::banding_image(&r.dac, &r.contour_map, max);
                output::write_raw8(p, &img, w, h)?;
            }
        }
    }
    if let (Some(p), Some(c)) = (&a.delta_e_out, &r.colour) {
        output::write_rgb8(p, &igemu::colour::delta_e_image(&c.delta_e, w, h), w, h)?;
    }
    write_dumps(&a, &r.plan, &r.steps, (w, h))?;
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

/// `render --no-reference`: the fixed model alone ([`pipeline::fast`]); the outputs that
/// need the float reference are refused naming the flag.
fn run_fast(
    a: &RenderArgs,
    scene: &igemu::scene::Scene,
    hw: &igemu::config::HwConfig,
    inputs: &Inputs,
) -> Result<ExitCode, Error> {
    for (flag, given) in [
        ("--reference-out", a.reference_out.is_some()),
        ("--diff-out", a.diff_out.is_some()),
        ("--banding-out", a.banding_out.is_some()),
        ("--delta-e-out", a.delta_e_out.is_some()),
        ("--html", a.html.is_some()),
        ("--dof-reference", a.dof_reference),
        ("--dof-truth", a.truth.samples() > 0),
    ] {
        if given {
            return Err(arg_error(
                flag,
                format!(
                    "{flag} compares with the float reference, which --no-reference does not run: drop one of the two"
                ),
            ));
        }
    }
    // The memories' images only for --rom-out.
    let opts = RunOptions {
        pack_check: a.rom_out.is_some(),
        ..RunOptions::FIXED_ONLY
    };
    let e = pipeline::fast::emulate(scene, hw, a.s.opts(opts), None)?;
    let (w, h) = (e.report.scene.width, e.report.scene.height);
    let stages = rom_stages(a, inputs, &e.steps)?;
    match e.channels.as_slice() {
        [r, g, b] => output::write_rgb(&a.out, [r, g, b], [e.bits[0], e.bits[1], e.bits[2]], w, h)?,
        planes => output::write_dac(&a.out, &planes[0], w, h, e.bits[0])?,
    }
    write_dumps(a, &e.plan, &e.steps, (w, h))?;
    if let Some(dir) = &a.rom_out {
        igemu::cost::rom::write(std::path::Path::new(dir), &stages)?;
    }
    let json = serde_json::to_string_pretty(&e.report).expect("serialisable");
    if let Some(p) = &a.report {
        output::write_file(p, &json)?;
    }
    if a.json {
        outln!("{json}");
    } else {
        crate::print::print_fast(&e.report, &a.out)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The stages' costs and memory images for `--rom-out`, whose file names are checked
/// against the other outputs and the inputs before any write.
fn rom_stages<'a>(
    a: &RenderArgs,
    inputs: &Inputs,
    steps: &'a [pipeline::Step],
) -> Result<RomStages<'a>, Error> {
    let stages: RomStages = steps
        .iter()
        .map(|s| (s.id, &s.outcome.report.cost, s.outcome.images.as_slice()))
        .collect();
    if a.rom_out.is_some() {
        // The hex files' names are known once the plan has run: checked before any write.
        check_outputs(a, inputs, &igemu::cost::rom::files(&stages))?;
    }
    Ok(stages)
}

/// Each stage's cost and memory images.
type RomStages<'a> = Vec<(
    igemu::stage::StageId,
    &'a igemu::stage::Cost,
    &'a [igemu::stage::MemImage],
)>;

/// Writes the `--dump` taps of a run's steps.
fn write_dumps(
    a: &RenderArgs,
    plan: &pipeline::Plan,
    steps: &[pipeline::Step],
    (w, h): (u32, u32),
) -> Result<(), Error> {
    for (tap, path) in &a.dump {
        let taps = steps
            .iter()
            .find(|s| s.id == tap.stage)
            .map(|s| &s.outcome.taps)
            .ok_or_else(|| {
                arg_error(
                    "--dump",
                    format!(
                        "stage `{}` is not in the plan of this render: {}",
                        tap.stage,
                        plan.decisions
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
    Ok(())
}

/// Writes the render's image (or its float reference): an RGB PNG of the channels' DAC
/// codes for a colour render, else the grey DAC codes.
fn write_image(path: &str, r: &pipeline::Render, reference: bool) -> Result<(), Error> {
    let (w, h) = (r.report.scene.width, r.report.scene.height);
    fn pick(k: &igemu::pipeline::colour::ChannelCodes, reference: bool) -> &[u16] {
        if reference { &k.dac_ref } else { &k.dac }
    }
    match &r.colour {
        Some(c) => {
            let ch = &c.channels;
            let planes = [0, 1, 2].map(|c| pick(&ch[c], reference));
            output::write_rgb(path, planes, [ch[0].bits, ch[1].bits, ch[2].bits], w, h)?;
        }
        None => {
            let codes = if reference { &r.dac_ref } else { &r.dac };
            output::write_dac(path, codes, w, h, r.dac_bits)?;
        }
    }
    Ok(())
}

/// Refuses, before any write, an output path that cannot be written or is an input, a
/// `--rom-out` that is no folder, and two outputs on one path: the files, the `--rom-out`
/// folder and the files `rom_files` in it.
fn check_outputs(a: &RenderArgs, inputs: &Inputs, rom_files: &[String]) -> Result<(), Error> {
    let mut outs = vec![("--out", a.out.clone())];
    for (flag, p) in [
        ("--reference-out", &a.reference_out),
        ("--diff-out", &a.diff_out),
        ("--banding-out", &a.banding_out),
        ("--delta-e-out", &a.delta_e_out),
        ("--truth-out", &a.truth_out),
        ("--report", &a.report),
        ("--html", &a.html),
    ] {
        outs.extend(p.clone().map(|p| (flag, p)));
    }
    outs.extend(a.dump.iter().map(|(_, p)| ("--dump", p.clone())));
    for (flag, p) in &outs {
        inputs.check(flag, p)?;
    }
    if let Some(dir) = &a.rom_out {
        guard::folder("--rom-out", dir)?;
        let d = std::path::Path::new(dir);
        inputs.check_in("--rom-out", d, rom_files)?;
        outs.push(("--rom-out", dir.clone()));
        outs.extend(
            rom_files
                .iter()
                .map(|n| ("--rom-out", d.join(n).display().to_string())),
        );
    }
    let outs: Vec<(&str, &str)> = outs.iter().map(|(f, p)| (*f, p.as_str())).collect();
    distinct_outputs(&outs)
}
