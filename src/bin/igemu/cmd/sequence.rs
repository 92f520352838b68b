//! `igemu sequence`: every frame of an animated scene through the fixed pipeline and its
//! float reference; per-frame cycles against the sequence's period, the worst frame, the
//! temporal flicker figures and the reuse between frames (docs/sequence.md).

use crate::args::{FilterArg, SceneArgs, arg_error};
use crate::guard::{Inputs, distinct_outputs};
use crate::out::outln;
use clap::Args;
use igemu::error::Error;
use igemu::output::{Apng, dac_to_u8, diff_values, interleave, write_dac, write_file, write_rgb};
use igemu::sequence::shard::shard_frames;
use igemu::sequence::{self, FrameImages, SequenceOptions, SequenceReport};
use igemu::shard::Shard;
use std::io::Write;
use std::process::ExitCode;

#[derive(Args)]
pub struct SequenceArgs {
    #[command(flatten)]
    pub s: SceneArgs,
    /// Override the accumulate filter (e.g. box against the preset's tent).
    #[arg(long, value_enum)]
    pub filter: Option<FilterArg>,
    /// Frames to run, `A..B` (B excluded; `A..` to the end, `..B` from 0; default: all).
    #[arg(long, value_name = "A..B", allow_hyphen_values = true)]
    pub frames: Option<String>,
    /// Write every frame as a PNG: `-o out.png` writes out-0000.png, out-0001.png, ...
    #[arg(short = 'o', long, value_name = "FILE.png")]
    pub out: Option<String>,
    /// Write the frames as an animated PNG (the fixed output; beside it, with a reference,
    /// the difference to the reference: 128 = identical, 32 grey levels per code).
    #[arg(long, value_name = "FILE.png")]
    pub apng: Option<String>,
    /// Write an HTML report: the frames animated, cycles per frame against the period, error
    /// and flicker per frame, the small objects' luminance over time.
    #[arg(long, value_name = "FILE.html")]
    pub html: Option<String>,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Fixed model only: no float reference (no error figures, no excess flicker).
    #[arg(long)]
    pub no_reference: bool,
    /// Emulate every frame afresh (no stage outcome reused from an earlier frame).
    #[arg(long)]
    pub no_reuse: bool,
    /// Run only shard K of N of the frames (contiguous blocks of the --frames range, as `sweep --shard`); `auto` takes it from a Slurm array task (SLURM_ARRAY_TASK_ID, _MIN, _COUNT, _STEP), `auto/N` also from a Kubernetes indexed Job (JOB_COMPLETION_INDEX of N). Needs --part.
    #[arg(long, value_name = "K/N|auto|auto/N", requires = "part")]
    pub shard: Option<String>,
    /// Write the shard's part file for `igemu sequence merge` (without --shard: the whole run as shard 1/1).
    #[arg(long, value_name = "PART.json")]
    pub part: Option<String>,
}

/// `A..B`, `A..`, `..B` or `A`, `n` the sequence's frames (the range is checked by
/// [`sequence::check_frames`]).
fn frame_range(s: &str, n: u32) -> Result<std::ops::Range<u32>, Error> {
    let bad = || {
        arg_error(
            "--frames",
            format!(
                "`{s}` is not a frame range: write A..B (B excluded), A.., ..B or one frame A, within 0..{n}"
            ),
        )
    };
    let num = |t: &str, d: u32| -> Result<u32, Error> {
        if t.is_empty() {
            Ok(d)
        } else {
            t.trim().parse().map_err(|_| bad())
        }
    };
    Ok(match s.split_once("..") {
        Some((a, b)) => num(a, 0)?..num(b, n)?,
        None => {
            let a = num(s, 0)?;
            a..a.saturating_add(1)
        }
    })
}

/// `out.png` -> `out-0007.png`.
fn numbered(pattern: &str, f: u32) -> String {
    match pattern.rsplit_once('.') {
        Some((stem, ext)) => format!("{stem}-{f:04}.{ext}"),
        None => format!("{pattern}-{f:04}"),
    }
}

/// Runs `igemu sequence`; returns the exit code.
pub fn run(a: SequenceArgs) -> Result<ExitCode, Error> {
    let inputs = Inputs::of(&a.s);
    let scene = a.s.scene()?;
    let mut hw = a.s.hw()?;
    if let Some(f) = a.filter {
        hw.accumulate.filter = f.into();
        hw.validate()
            .map_err(|(field, msg)| hw.error(&field, msg))?;
    }
    let n = scene.sequence.as_ref().map_or(1, |q| q.frames);
    let run_frames = match &a.frames {
        Some(s) => frame_range(s, n)?,
        None => 0..n,
    };
    sequence::check_frames(&scene, &run_frames)?;
    let shard = match (&a.shard, &a.part) {
        (Some(s), _) => Some(crate::args::shard_arg("sequence", s)?),
        (None, Some(_)) => Some(Shard { k: 1, n: 1 }),
        (None, None) => None,
    };
    let frames = match shard {
        Some(sh) => shard_frames(&run_frames, sh).map_err(|m| arg_error("--shard", m))?,
        None => run_frames.clone(),
    };
    let mut outs: Vec<(&str, String)> = Vec::new();
    if let Some(p) = &a.part {
        inputs.check("--part", p)?;
        outs.push(("--part", p.clone()));
    }
    if let Some(p) = &a.apng {
        inputs.check("--apng", p)?;
        outs.push(("--apng", p.clone()));
    }
    if let Some(p) = &a.html {
        inputs.check("--html", p)?;
        outs.push(("--html", p.clone()));
    }
    if let Some(p) = &a.out {
        for f in frames.clone() {
            let path = numbered(p, f);
            inputs.check("-o", &path)?;
            outs.push(("-o", path));
        }
    }
    distinct_outputs(
        &outs
            .iter()
            .map(|(f, p)| (*f, p.as_str()))
            .collect::<Vec<_>>(),
    )?;
    let (w, h) = (scene.image.width, scene.image.height);
    let reference = !a.no_reference;
    let rate = scene
        .sequence
        .as_ref()
        .map_or(scene.display.refresh_hz, |q| q.rate_hz);
    let width = if reference { 2 * w } else { w };
    let rgb = scene.image.colour;
    let mut apng = match a.apng.as_ref().or(a.html.as_ref()) {
        Some(p) if scene.sequence.is_some() => {
            Some(Apng::new(p, width, h, frames.len() as u32, rate, rgb)?)
        }
        _ => None,
    };
    let opts = SequenceOptions {
        frames: run_frames,
        reference,
        reuse: !a.no_reuse,
    };
    let mut on_frame = |fr: &FrameImages| -> Result<(), Error> {
        if let Some(p) = &a.out {
            let path = numbered(p, fr.frame);
            match (fr.fixed, fr.bits) {
                (&[r, g, b], &[br, bg, bb]) => write_rgb(&path, [r, g, b], [br, bg, bb], w, h)?,
                _ => write_dac(&path, fr.fixed[0], w, h, fr.bits[0])?,
            }
        }
        if let Some(ap) = apng.as_mut() {
            // The fixed output beside its difference to the reference (each channel's in
            // its own colour plane), interleaved per pixel for RGB.
            let fixed: Vec<Vec<u8>> = fr
                .fixed
                .iter()
                .zip(fr.bits)
                .map(|(c, &b)| dac_to_u8(c, b))
                .collect();
            let fixed = interleave(&fixed);
            let data = match fr.reference {
                Some(r) => {
                    let diff: Vec<Vec<u8>> = fr
                        .fixed
                        .iter()
                        .zip(r)
                        .map(|(f, r)| diff_values(f, r))
                        .collect();
                    let diff = interleave(&diff);
                    let row = w as usize * fr.fixed.len();
                    fixed
                        .chunks(row)
                        .zip(diff.chunks(row))
                        .flat_map(|(a, b)| a.iter().chain(b).copied())
                        .collect()
                }
                None => fixed,
            };
            ap.frame(&data)?;
        }
        Ok(())
    };
    let r = match (shard, &a.part) {
        (Some(sh), Some(path)) => {
            let part = sequence::shard::run_shard(&scene, &hw, &opts, sh, &mut on_frame)?;
            let text =
                serde_json::to_string(&part).map_err(|e| arg_error("--part", e.to_string()))?;
            write_file(path, text)?;
            let _ = writeln!(
                std::io::stderr(),
                "igemu sequence: shard {}/{}: frames {}..{} of the run's {}..{} -> {path}",
                sh.k,
                sh.n,
                part.frames[0],
                part.frames[1],
                part.run[0],
                part.run[1]
            );
            part.report
        }
        _ => sequence::run(&scene, &hw, &opts, &mut on_frame)?,
    };
    let bytes = apng.map(Apng::finish_bytes).transpose()?;
    if let (Some(p), Some(b)) = (&a.apng, &bytes) {
        write_file(p, b)?;
    }
    if let Some(p) = &a.html {
        let page = igemu::html::sequence_page(&r, bytes.as_deref().map(|b| (b, width, h)), p)?;
        write_file(p, page)?;
    }
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&r).expect("serialisable")
        );
    } else {
        print(&r)?;
    }
    Ok(ExitCode::SUCCESS)
}

fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map_or("-".into(), |x| x.to_string())
}

pub(crate) fn print(r: &SequenceReport) -> Result<(), Error> {
    let s = &r.summary;
    outln!(
        "sequence `{}` | hardware `{}` | filter {} | {}x{} | frames {}..{} of {} | {} Hz | {}",
        r.scene,
        r.hardware,
        r.filter,
        r.width,
        r.height,
        r.first,
        r.first + s.frames,
        r.sequence_frames,
        s.rate_hz,
        if r.reference {
            "fixed and float reference"
        } else {
            "fixed only"
        }
    );
    // A colour sequence with a reference adds each frame's CIEDE2000 (mean / largest).
    let colour = r.frames.iter().any(|f| f.delta_e_max.is_some());
    outln!(
        "{:>6} {:>10} {:>9} {:>8} {:>5} {:>10} {:>6} {:>9} {:>7} {:>8} {:>9} {:>8}{}",
        "frame",
        "cycles",
        "ms",
        "fps",
        "miss",
        "identical",
        "max",
        "weber",
        "reused",
        "emulated",
        "tile rows",
        "wall ms",
        if colour { "   dE00 mean/max" } else { "" }
    );
    for f in &r.frames {
        let de = match (f.delta_e_mean, f.delta_e_max) {
            (Some(m), Some(x)) => format!("  {m:>7.4} {x:>6.2}"),
            _ => String::new(),
        };
        outln!(
            "{:>6} {:>10} {:>9.3} {:>8.1} {:>5} {:>10} {:>6} {:>9} {:>7} {:>8} {:>9} {:>8.1}{de}",
            f.frame,
            f.cycles,
            f.frame_ms,
            f.fps,
            if f.misses_period { "MISS" } else { "" },
            opt(f.identical_fraction.map(|x| format!("{:.4}", x))),
            opt(f.max_abs_diff),
            opt(f.weber_max.map(|x| format!("{:.3}", x))),
            f.reused_stages,
            f.emulated_stages,
            format!(
                "{}/{}",
                f.tile_rows_emulated,
                f.tile_rows_emulated + f.tile_rows_reused
            ),
            f.wall_ms
        );
    }
    outln!(
        "worst frame: {} with {} cycles = {:.3} ms at {} MHz | period {:.0} cycles ({:.3} ms at {} Hz) | {} of {} frames miss it ({:.1}%)",
        s.worst_frame,
        s.worst_cycles,
        s.worst_frame_ms,
        s.clock_mhz,
        s.period_cycles,
        1e3 / s.rate_hz,
        s.rate_hz,
        s.missed,
        s.frames,
        100.0 * s.missed_fraction
    );
    outln!(
        "cycles per frame: mean {:.0} | p50 {} | p95 {} | p99 {}",
        s.mean_cycles,
        s.p50_cycles,
        s.p95_cycles,
        s.p99_cycles
    );
    let t = &r.temporal;
    match (t.max_excess_weber, t.mean_excess_weber) {
        (Some(max), Some(mean)) => outln!(
            "per-pixel excess flicker (fixed frame-to-frame change minus the reference's, Weber units) over {} frame pairs: max {:.3}, mean {:.5}, {} visible pixel steps (> 1)",
            t.pairs,
            max,
            mean,
            t.visible_excess
        ),
        _ => outln!(
            "per-pixel excess flicker: needs the float reference (run without --no-reference)"
        ),
    }
    for o in &t.objects {
        outln!(
            "small object {} ({}): displayed total ripple {:.3}% (reference {}) | peak-pixel modulation {:.2}% (reference {})",
            o.object,
            o.kind,
            o.ripple_fixed_pct,
            opt(o.ripple_reference_pct.map(|x| format!("{x:.3}%"))),
            o.peak_modulation_fixed_pct,
            opt(o.peak_modulation_reference_pct.map(|x| format!("{x:.2}%")))
        );
    }
    if let Some(d) = &t.dither {
        outln!(
            "temporal dither over {} frames: {} static pixels | mean of the codes against the reference value: max {:.3}, mean {:.4} codes | {} pixels step visibly between frames",
            d.frames,
            d.static_pixels,
            d.max_mean_error,
            d.mean_mean_error,
            d.flickering_pixels
        );
    }
    let u = &r.reuse;
    outln!(
        "reuse: {} | {} frames after the first reused every stage | stages emulated {}, reused {} | {:.2} frames/s of emulation ({:.2} s){}",
        if u.enabled { "on" } else { "off (--no-reuse)" },
        u.frames_fully_reused,
        u.stages_emulated,
        u.stages_reused,
        u.frames_per_s,
        u.wall_s,
        if u.camera_moves {
            " | the camera moves: no frame repeats an earlier one"
        } else {
            ""
        }
    );
    match &u.tile_rows_off {
        Some(why) => outln!("tile rows: not reused: {why}"),
        None => {
            let all = u.tile_rows_emulated + u.tile_rows_reused;
            outln!(
                "tile rows ({} rows of {} px; raster, visibility, accumulate): after the first frame {} of {} emulated ({:.1}%), {} reused | wall time of the first frame / median later frame = {:.2}",
                u.tile_rows,
                u.tile_size,
                u.tile_rows_emulated,
                all,
                100.0 * u.tile_rows_emulated as f64 / all.max(1) as f64,
                u.tile_rows_reused,
                u.first_over_later_wall
            );
        }
    }
    Ok(())
}
