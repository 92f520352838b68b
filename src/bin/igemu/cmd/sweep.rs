//! `igemu sweep`: render every configuration of a word-width grid on the scenes, one JSON
//! line each (resumable, shardable, parallel), and print the Pareto front.

use crate::args::{TruthArgs, arg_error};
use crate::guard::Inputs;
use clap::Args;
use igemu::error::Error;
use igemu::output;
use igemu::pipeline;
use std::io::Write;
use std::process::ExitCode;

#[derive(Args)]
pub struct SweepArgs {
    /// Scene TOML files or embedded scene names (default: the embedded default scene).
    pub scenes: Vec<String>,
    /// Grid TOML: dotted hardware fields with lists of values (`gamma.dac_bits = [8, 9]`, `preset = [...]`).
    #[arg(long)]
    pub grid: String,
    /// Output JSON-lines file (one row per configuration and scene).
    #[arg(long)]
    pub out: String,
    /// Keep the complete rows already in OUT and run only the missing configurations.
    #[arg(long)]
    pub resume: bool,
    /// Run only shard K of N (contiguous blocks: the shard files concatenate to the full run); `auto` takes it from a Slurm array task (SLURM_ARRAY_TASK_ID, _MIN, _COUNT, _STEP), `auto/N` also from a Kubernetes indexed Job (JOB_COMPLETION_INDEX of N).
    #[arg(long, value_name = "K/N|auto|auto/N")]
    pub shard: Option<String>,
    /// Configurations rendered in parallel, 1..=1024 (1 = serial; results are identical).
    #[arg(long, default_value_t = 1, value_parser = crate::args::int_in(1, 1024), allow_negative_numbers = true)]
    pub jobs: u32,
    /// Axes of the Pareto front, comma separated: error (mean Weber), code_error, max_error, weber, contours, cost, throughput, flicker (needs --flicker), truth_total, truth_algorithm, truth_quantisation (mean Weber against the depth-of-field truth; need --dof-truth), emulator_time (the fixed models' ms), delta_e, delta_e_p99 (CIEDE2000 mean, 99th percentile), hue_shift (mean, degrees) (a colour scene).
    /// Default: error,cost; truth_total,cost when the grid varies dof.* fields and --dof-truth is given (a dof.* grid ranked on error is warned about: that axis compares each method with its own float version).
    #[arg(long)]
    pub axes: Option<String>,
    /// Run every phase for every configuration (no stage reuse between configurations).
    #[arg(long)]
    pub no_reuse: bool,
    /// Plot error vs cost and error vs throughput with the Pareto fronts (SVG or PNG, by extension).
    #[arg(long, value_name = "PARETO.svg|png")]
    pub plot: Option<String>,
    /// Write a self-contained HTML report: the Pareto plot and every row in a sortable table, the front highlighted.
    #[arg(long, value_name = "SWEEP.html")]
    pub html: Option<String>,
    /// Add small-object flicker metrics to every row: the flicker scene swept over PHASES x PHASES sub-pixel phases (2..=64; `igemu flicker` uses 32).
    #[arg(long, value_name = "PHASES", value_parser = crate::args::int_in(2, 64), allow_negative_numbers = true)]
    pub flicker: Option<u32>,
    /// Refuse a render whose memory estimate exceeds SIZE (bytes, or with K, M, G, T; default half the machine's memory); with --jobs N, N renders run at once.
    #[arg(long, value_name = "SIZE", value_parser = crate::args::parse_size, allow_hyphen_values = true)]
    pub max_memory: Option<u64>,
    /// Errors of every row against the depth-of-field truth (computed once per scene).
    #[command(flatten)]
    pub truth: TruthArgs,
}

/// Runs `igemu sweep`; returns the exit code.
pub fn run(a: SweepArgs) -> Result<ExitCode, Error> {
    use igemu::sweep::{self, pareto};
    // Everything is checked before the first render.
    let mut inputs = Inputs::default();
    inputs.add("the grid file (--grid)", Some(&a.grid));
    for s in &a.scenes {
        inputs.add("a scene file", Some(s));
    }
    inputs.check_outputs(&[
        ("--out", Some(&a.out)),
        ("--plot", a.plot.as_deref()),
        ("--html", a.html.as_deref()),
    ])?;
    let shard = match &a.shard {
        Some(s) => Some(crate::args::shard_arg("sweep", s)?),
        None => None,
    };
    let given = match &a.axes {
        Some(x) => Some(pareto::Axis::parse_list(x).map_err(|m| arg_error("--axes", m))?),
        None => None,
    };
    if let Some(p) = &a.plot {
        sweep::plot::PlotFormat::of(p).map_err(|m| arg_error("--plot", m))?;
    }
    let (configs, scenes) = crate::args::grid_and_scenes(&a.grid, &a.scenes)?;
    let axes = choose_axes(given, &configs, a.truth.dof_truth);
    if a.flicker.is_none() && axes.contains(&pareto::Axis::Flicker) {
        return Err(arg_error(
            "--axes",
            "the flicker axis needs the flicker metrics: add --flicker PHASES".into(),
        ));
    }
    check_truth_axes(&axes, a.truth.dof_truth)?;
    pareto::check_colour_axes(&axes, &configs, &scenes).map_err(|m| arg_error("--axes", m))?;
    for c in &configs {
        for s in &scenes {
            // Located at the grid's key or the scene's line (the configuration's source).
            pipeline::guard_band(s, &c.hw).map_err(|mut e| {
                e.msg = format!(
                    "configuration {} ({}) on scene `{}`: {}",
                    c.index, c.canonical, s.name, e.msg
                );
                e
            })?;
        }
    }
    let cache = igemu::pipeline::Cache::new();
    let opts = sweep::SweepOptions {
        out: &a.out,
        resume: a.resume,
        shard,
        jobs: a.jobs as usize,
        cache: if a.no_reuse { None } else { Some(&cache) },
        flicker: a.flicker,
        max_memory: a.max_memory,
        dof_truth: a.truth.dof_truth.then(|| a.truth.samples()),
    };
    // Progress bar with ETA on a terminal (indicatif hides it when stderr is not a terminal).
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:30} {pos}/{len} rows  {elapsed} elapsed, ETA {eta}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let progress = |done: usize, total: usize| {
        if bar.length() != Some(total as u64) {
            // The first call: rows kept by --resume do not count towards the rate.
            bar.set_length(total as u64);
            bar.set_position(done as u64);
            bar.reset_eta();
        } else {
            bar.set_position(done as u64);
        }
    };
    let summary = sweep::run(&configs, &scenes, &opts, &progress);
    bar.finish_and_clear();
    let summary = summary?;
    // A closed stderr must not stop the command: the rows are written.
    let _ = writeln!(
        std::io::stderr(),
        "igemu sweep: {} configurations x {} scenes; this run: {} rows -> {}: kept {}, dropped {} (stale or foreign), computed {}",
        configs.len(),
        scenes.len(),
        summary.planned,
        a.out,
        summary.reused,
        summary.dropped,
        summary.computed
    );
    let rows = &summary.rows;
    if let Some(p) = &a.plot {
        sweep::plot::write(rows, &axes, p)?;
    }
    if let Some(p) = &a.html {
        output::write_file(p, &igemu::html::sweep_page(rows, &axes, &a.grid, p)?)?;
    }
    crate::print::print_front(rows, &axes)?;
    Ok(ExitCode::SUCCESS)
}

/// The axes of the front: those of `--axes` (`given`), else [`igemu::sweep::pareto::default_axes`]
/// (said on stderr when they are the truth axes); a grid varying `dof.*` ranked on an axis
/// that compares each configuration with its own float reference is warned about on stderr.
pub fn choose_axes(
    given: Option<Vec<igemu::sweep::pareto::Axis>>,
    configs: &[igemu::sweep::grid::Config],
    dof_truth: bool,
) -> Vec<igemu::sweep::pareto::Axis> {
    use igemu::sweep::pareto;
    let axes = given.unwrap_or_else(|| {
        let d = pareto::default_axes(configs, dof_truth);
        if d.iter().any(|x| x.needs_truth()) {
            let _ = writeln!(
                std::io::stderr(),
                "igemu sweep: the grid varies {}: ranking on truth_total,cost (the depth-of-field truth) by default; give --axes to choose",
                pareto::varied_dof_fields(configs).join(", ")
            );
        }
        d
    });
    if let Some(w) = pareto::dof_axes_warning(configs, &axes) {
        let _ = writeln!(std::io::stderr(), "igemu sweep: warning: {w}");
    }
    axes
}

/// Refuses a `truth_*` axis without `--dof-truth`.
pub fn check_truth_axes(axes: &[igemu::sweep::pareto::Axis], dof_truth: bool) -> Result<(), Error> {
    if !dof_truth && axes.iter().any(|x| x.needs_truth()) {
        return Err(arg_error(
            "--axes",
            "the truth_* axes need the depth-of-field truth: add --dof-truth".into(),
        ));
    }
    Ok(())
}
