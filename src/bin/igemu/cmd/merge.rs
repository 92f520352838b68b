//! `igemu sweep merge`: the part files of a sharded sweep (one per task of a Slurm array or a
//! Kubernetes indexed Job) checked against the grid and written as one file in job order,
//! with the Pareto front; and [`SweepCmd`], the `sweep` command with its `merge`
//! subcommand.

use crate::args::{TruthArgs, arg_error};
use crate::guard::Inputs;
use clap::Args;
use igemu::error::Error;
use igemu::sweep::{self, merge, pareto};
use std::io::Write;
use std::process::ExitCode;

/// `igemu sweep [SCENE]... --grid ...` or `igemu sweep merge PART.jsonl... --grid ...`.
pub type SweepCmd = crate::with_merge::WithMerge<super::sweep::SweepArgs, MergeArgs>;

#[derive(Args)]
#[command(
    about = "Merge the part files of a sharded sweep: check that every row of the grid is there exactly once (else name the missing, duplicated and foreign rows and exit 1), write them in job order, print the Pareto front",
    mut_arg("dof_truth", |a| a.help("The sweep ran with --dof-truth (its lens-sample count is part of the row ids)")),
    mut_arg("lens_samples", |a| a.help("The sweep's --lens-samples (default 256)"))
)]
pub struct MergeArgs {
    /// The part files (each task's --out), in any order.
    #[arg(required = true, value_name = "PART.jsonl")]
    pub parts: Vec<String>,
    /// The grid TOML of the sweep.
    #[arg(long)]
    pub grid: String,
    /// A scene of the sweep (TOML file or embedded name), repeated in the sweep's order (default: the embedded default scene).
    #[arg(long = "scene", value_name = "SCENE")]
    pub scenes: Vec<String>,
    /// Output JSON-lines file: every row of the sweep, in job order (written only when the merge is complete).
    #[arg(long)]
    pub out: String,
    /// Axes of the Pareto front, as for `igemu sweep` (the same default; flicker needs rows with flicker metrics, truth_* need --dof-truth, delta_e, delta_e_p99 and hue_shift rows of a colour render).
    #[arg(long)]
    pub axes: Option<String>,
    /// Plot error vs cost and error vs throughput with the Pareto fronts (SVG or PNG, by extension).
    #[arg(long, value_name = "PARETO.svg|png")]
    pub plot: Option<String>,
    /// Write a self-contained HTML report: the Pareto plot and every row in a sortable table, the front highlighted.
    #[arg(long, value_name = "SWEEP.html")]
    pub html: Option<String>,
    /// Whether the sweep compared with the depth-of-field truth, and at how many lens points.
    #[command(flatten)]
    pub truth: TruthArgs,
}

/// Runs `igemu sweep` or `igemu sweep merge`.
pub fn run(c: SweepCmd) -> Result<ExitCode, Error> {
    match c {
        SweepCmd::Run(a) => super::sweep::run(a),
        SweepCmd::Merge(a) => run_merge(a),
    }
}

fn run_merge(a: MergeArgs) -> Result<ExitCode, Error> {
    // Everything is checked before the output is touched.
    let mut inputs = Inputs::default();
    inputs.add("the grid file (--grid)", Some(&a.grid));
    for s in &a.scenes {
        inputs.add("a scene file (--scene)", Some(s));
    }
    for p in &a.parts {
        inputs.add("a part file", Some(p));
    }
    inputs.check_outputs(&[
        ("--out", Some(&a.out)),
        ("--plot", a.plot.as_deref()),
        ("--html", a.html.as_deref()),
    ])?;
    if let Some(p) = &a.plot {
        sweep::plot::PlotFormat::of(p).map_err(|m| arg_error("--plot", m))?;
    }
    let given = match &a.axes {
        Some(x) => Some(pareto::Axis::parse_list(x).map_err(|m| arg_error("--axes", m))?),
        None => None,
    };
    let (configs, scenes) = crate::args::grid_and_scenes(&a.grid, &a.scenes)?;
    let axes = super::sweep::choose_axes(given, &configs, a.truth.dof_truth);
    super::sweep::check_truth_axes(&axes, a.truth.dof_truth)?;
    let parts: Vec<merge::Part> = a
        .parts
        .iter()
        .map(|p| merge::Part::read(p))
        .collect::<Result<_, _>>()?;
    let dof_truth = a.truth.dof_truth.then(|| a.truth.samples());
    let m = merge::merge(&configs, &scenes, dof_truth, &parts);
    let mut err = std::io::stderr();
    if !m.skipped.is_empty() {
        let at: Vec<String> = m.skipped.iter().map(|p| p.to_string()).collect();
        let _ = writeln!(
            err,
            "igemu sweep merge: {} lines are not complete rows (a killed task's last line?), skipped: {}",
            at.len(),
            at.join(", ")
        );
    }
    let read: usize = parts.iter().map(|p| p.rows.len()).sum();
    if !m.complete() {
        let _ = write!(
            err,
            "igemu sweep merge: incomplete: {} rows read from {} files for {} jobs ({} configurations x {} scenes); {} not written\n{}",
            read,
            parts.len(),
            m.jobs,
            configs.len(),
            scenes.len(),
            a.out,
            m.problems()
        );
        return Ok(ExitCode::from(1));
    }
    if axes.contains(&pareto::Axis::Flicker)
        && let Some(r) = m.rows.iter().find(|r| r.flicker.is_none())
    {
        return Err(arg_error(
            "--axes",
            format!(
                "the flicker axis needs rows with flicker metrics (a sweep with --flicker); row {} has none",
                r.index
            ),
        ));
    }
    pareto::check_colour_rows(&axes, &m.rows).map_err(|m| arg_error("--axes", m))?;
    sweep::rewrite_sorted(&a.out, &m.rows)?;
    let _ = writeln!(
        err,
        "igemu sweep merge: {} rows from {} files -> {} ({} configurations x {} scenes, in job order)",
        m.rows.len(),
        parts.len(),
        a.out,
        configs.len(),
        scenes.len()
    );
    if let Some(p) = &a.plot {
        sweep::plot::write(&m.rows, &axes, p)?;
    }
    if let Some(p) = &a.html {
        let source = format!("{} ({} parts merged)", a.grid, parts.len());
        igemu::output::write_file(p, &igemu::html::sweep_page(&m.rows, &axes, &source, p)?)?;
    }
    crate::print::print_front(&m.rows, &axes)?;
    Ok(ExitCode::SUCCESS)
}
