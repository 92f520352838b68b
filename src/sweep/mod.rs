//! Word-width sweeps: every configuration of a grid rendered and compared with the float
//! reference, one JSON line per (configuration, scene), resumable and shardable.
//!
//! * Order: configurations in grid order ([`grid`]), scenes inner; job `i` is configuration
//!   `i / scenes`, scene `i % scenes`.
//! * Row ids name the row's inputs by content: the scene as parsed, the validated hardware
//!   (not its spelling in the grid) and the tool version ([`rows`] has the definition). A
//!   row is reused only when all three are unchanged.
//! * Rows are appended to `--out` directly and flushed one by one as they finish, by design:
//!   a killed sweep keeps every completed row, and at most the last line is partial. When
//!   every job of the run is done the file is rewritten in job order through a temporary
//!   file in the same folder and a rename, so a serial, a parallel and a resumed run give
//!   the same file, and a failed rewrite leaves the appended rows as they were. The plot
//!   (`--plot`, [`plot`]) is written the same way.
//! * `--resume` reads the file and keeps each row whose id is a job of this run (with the
//!   job's current index, scene name and grid fields, so a reordered or respelled grid
//!   reuses them); it drops the rows whose inputs changed (stale ids), rows of other sweeps
//!   or shards, duplicates and a partial last line, counts them
//!   ([`SweepSummary::dropped`]), rewrites the file without them and runs the rest.
//! * `--shard K/N` runs a contiguous block of jobs: shard files concatenated in K order equal
//!   the unsharded output. Every K/N with 1 <= K <= N is valid ([`grid::Shard::range`]
//!   cannot overflow); shards beyond the number of jobs are empty. `--shard auto` takes K/N
//!   from a Slurm array task or a Kubernetes indexed Job ([`grid::Shard::from_env`]), and
//!   [`merge`] checks and joins the part files of the tasks (docs/cluster.md).

pub mod grid;
pub mod merge;
pub mod metrics;
pub mod pareto;
pub mod plot;
pub mod rows;

pub use metrics::{
    ColourMetrics, CostMetrics, CycleMetrics, ErrorMetrics, FlickerMetrics, RowTiming, StageTiming,
    TruthError, TruthMetrics,
};
pub use rows::{hardware_key, read_rows, rewrite_sorted, row_id, row_id_from_keys, scene_key};

use crate::error::{Error, Result};
use crate::pipeline::{self, Cache};
use crate::scene::Scene;
use crate::stage::RunOptions;
use grid::{Config, Shard};
use rows::io;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;

/// One JSON line of the output.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Row {
    /// Stable id of the row's inputs: 16 hex digits of FNV-1a over the scene's content, the
    /// hardware's content and the tool version ([`row_id`]).
    pub id: String,
    /// Job index in the full (unsharded) sweep.
    pub index: usize,
    /// Scene name.
    pub scene: String,
    /// Grid field -> value.
    pub config: BTreeMap<String, serde_json::Value>,
    /// Error metrics.
    pub error: ErrorMetrics,
    /// The colour error of a colour render (absent for a grey one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colour: Option<ColourMetrics>,
    /// Cost.
    pub cost: CostMetrics,
    /// Cycles and throughput.
    pub cycles: CycleMetrics,
    /// Small-object flicker (only with `--flicker`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flicker: Option<FlickerMetrics>,
    /// Errors against the depth-of-field truth (only with `--dof-truth`, on a thin-lens
    /// scene).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub truth: Option<TruthMetrics>,
    /// Stages whose result was reused from an earlier row of the run, and `dof truth` when
    /// the truth frame was (run state, like the timing: excluded when rows are compared).
    #[serde(default)]
    pub reused: Vec<String>,
    /// Wall time (excluded when rows are compared).
    pub timing: RowTiming,
}

/// One job: a configuration on a scene.
#[derive(Clone, Copy, Debug)]
pub struct Job {
    /// Index in the full sweep.
    pub index: usize,
    /// Configuration number.
    pub config: usize,
    /// Scene number.
    pub scene: usize,
}

/// All jobs of a sweep in order.
pub fn jobs(configs: usize, scenes: usize) -> Vec<Job> {
    (0..configs * scenes)
        .map(|index| Job {
            index,
            config: index / scenes,
            scene: index % scenes,
        })
        .collect()
}

/// The grid fields of a configuration as the JSON of a row.
fn config_json(cfg: &Config) -> BTreeMap<String, serde_json::Value> {
    cfg.fields
        .iter()
        .map(|(k, v)| {
            (
                k.clone(),
                serde_json::to_value(v).unwrap_or(serde_json::Value::Null),
            )
        })
        .collect()
}

/// Renders one configuration on one scene and builds its row (with the flicker sweep at
/// `flicker` phases when given).
pub fn run_job(
    job: Job,
    cfg: &Config,
    scene: &Scene,
    cache: Option<&Cache>,
    flicker: Option<u32>,
) -> Result<Row> {
    let opts = RunOptions::FAST;
    run_job_as(
        row_id(scene, &cfg.hw),
        job,
        cfg,
        scene,
        cache,
        flicker,
        opts,
    )
}

/// [`run_job`] with the row id already known.
fn run_job_as(
    id: String,
    job: Job,
    cfg: &Config,
    scene: &Scene,
    cache: Option<&Cache>,
    flicker: Option<u32>,
    opts: RunOptions,
) -> Result<Row> {
    let t = std::time::Instant::now();
    let r = pipeline::render_with(scene, &cfg.hw, opts, cache)?;
    let render_ms = t.elapsed().as_secs_f64() * 1e3;
    let rep = &r.report;
    let c = &rep.end_to_end.codes;
    let w = &rep.end_to_end.weber;
    Ok(Row {
        id,
        index: job.index,
        scene: scene.name.clone(),
        config: config_json(cfg),
        error: ErrorMetrics {
            max_code_diff: c.max_abs_diff,
            mean_code_diff: if c.count == 0 {
                0.0
            } else {
                c.histogram
                    .iter()
                    .map(|(&d, &n)| d.unsigned_abs() as f64 * n as f64)
                    .sum::<f64>()
                    / c.count as f64
            },
            mean_signed_code_diff: c.mean_diff,
            psnr_db: c.psnr_db,
            identical_fraction: c.identical_fraction,
            weber_max: w.max,
            weber_mean: w.mean,
            weber_visible_fraction: w.over_delta_fraction,
            contour_steps: rep.contours.contour_steps,
            contour_pixels: rep.contours.contour_pixels,
        },
        colour: rep.colour.as_ref().map(ColourMetrics::of),
        cost: CostMetrics {
            storage_bits: rep.storage_bits,
            lut_bits: rep.lut_bits,
            adders: rep.cycles.cost.adders,
            multipliers: rep.cycles.cost.multipliers,
        },
        cycles: CycleMetrics {
            total_cycles: rep.cycles.total_cycles,
            fps: rep.cycles.throughput.fps,
            bottleneck: rep.cycles.bottleneck.clone(),
            real_time: rep.cycles.throughput.real_time,
        },
        flicker: flicker
            .map(|n| FlickerMetrics::of(&cfg.hw, n))
            .transpose()?,
        truth: rep.dof_truth.as_ref().map(TruthMetrics::of),
        reused: rep
            .reused
            .iter()
            .cloned()
            .chain(
                rep.dof_truth
                    .as_ref()
                    .filter(|t| t.reused)
                    .map(|_| TRUTH_REUSED.to_string()),
            )
            .collect(),
        timing: RowTiming {
            render_ms,
            fixed_ms: rep.timing.fixed_ms,
            float_ms: rep.timing.float_ms,
            stages: rep
                .stages
                .iter()
                .map(|s| StageTiming {
                    name: s.name.clone(),
                    fixed_ms: s.fixed_ms,
                    float_ms: s.float_ms,
                })
                .collect(),
        },
    })
}

/// The entry of [`Row::reused`] for a truth frame taken from the cache.
pub const TRUTH_REUSED: &str = "dof truth";

/// Options of a sweep run.
pub struct SweepOptions<'a> {
    /// Output JSON-lines file.
    pub out: &'a str,
    /// Keep the rows already in `out` and run only the missing ones.
    pub resume: bool,
    /// Run only this shard.
    pub shard: Option<Shard>,
    /// Worker threads over configurations (1 = serial).
    pub jobs: usize,
    /// Stage reuse between configurations (`None`: every render runs every phase).
    pub cache: Option<&'a Cache>,
    /// Add the small-object flicker metrics at this many sub-pixel phases per axis.
    pub flicker: Option<u32>,
    /// The memory limit of each render (`None`: half the machine's memory).
    pub max_memory: Option<u64>,
    /// Compare every row with the depth-of-field truth at this many lens points (computed
    /// once per scene when `cache` is given; part of the row ids).
    pub dof_truth: Option<u32>,
}

/// Summary of a run.
#[derive(Debug)]
pub struct SweepSummary {
    /// Jobs in this shard.
    pub planned: usize,
    /// Jobs of this run whose row was found in the file and kept (`--resume`).
    pub reused: usize,
    /// Lines of the file not kept (`--resume`): rows whose inputs changed (stale ids), rows
    /// of other sweeps or shards, duplicates, and lines that are not complete rows (a
    /// partial last line).
    pub dropped: usize,
    /// Rows computed now.
    pub computed: usize,
    /// All rows of the shard, in order.
    pub rows: Vec<Row>,
}

/// Runs a sweep. `progress` is called after each row with (done, total).
pub fn run(
    configs: &[Config],
    scenes: &[Scene],
    opts: &SweepOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<SweepSummary> {
    let all = jobs(configs.len(), scenes.len());
    let range = opts.shard.map_or(0..all.len(), |s| s.range(all.len()));
    let mine = &all[range.clone()];
    let ids = &rows::job_ids(configs, scenes, opts.dof_truth)[range];
    let (kept, dropped) = if opts.resume {
        let (rows, skipped) = read_rows(opts.out)?;
        let (kept, unused) = keep_rows(rows, mine, ids, configs, scenes);
        // Drop the partial line and every row not kept before appending.
        rewrite_sorted(opts.out, &kept)?;
        (kept, skipped + unused)
    } else {
        std::fs::File::create(opts.out).map_err(io(opts.out))?;
        (Vec::new(), 0)
    };
    let done: BTreeSet<usize> = kept.iter().map(|r| r.index).collect();
    let todo: Vec<(Job, &String)> = mine
        .iter()
        .copied()
        .zip(ids)
        .filter(|(j, _)| !done.contains(&j.index))
        .collect();
    let reused = kept.len();
    let file = std::fs::OpenOptions::new()
        .append(true)
        .open(opts.out)
        .map_err(io(opts.out))?;
    let writer = std::sync::Mutex::new(file);
    let count = std::sync::atomic::AtomicUsize::new(reused);
    let total = mine.len();
    progress(reused, total);
    let work = |(j, id): &(Job, &String)| -> Result<Row> {
        let row = run_job_as(
            (*id).clone(),
            *j,
            &configs[j.config],
            &scenes[j.scene],
            opts.cache,
            opts.flicker,
            RunOptions {
                max_memory: opts.max_memory,
                dof_truth_samples: opts.dof_truth.unwrap_or(0),
                ..RunOptions::FAST
            },
        )?;
        let mut line = serde_json::to_string(&row).unwrap_or_default();
        line.push('\n');
        {
            let mut f = writer.lock().unwrap_or_else(|e| e.into_inner());
            // One write of the whole line, then flush: a kill leaves at most a partial last line.
            f.write_all(line.as_bytes()).map_err(io(opts.out))?;
            f.flush().map_err(io(opts.out))?;
        }
        let n = count.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
        progress(n, total);
        Ok(row)
    };
    let new_rows: Vec<Row> = if opts.jobs <= 1 {
        todo.iter().map(work).collect::<Result<_>>()?
    } else {
        use rayon::prelude::*;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(opts.jobs)
            .build()
            .map_err(|e| {
                Error::File(crate::error::FileError {
                    file: "--jobs".into(),
                    line: None,
                    col: None,
                    field: String::new(),
                    msg: format!("cannot start {} threads: {e}", opts.jobs),
                })
            })?;
        pool.install(|| todo.par_iter().map(work).collect::<Result<_>>())?
    };
    let computed = new_rows.len();
    let mut rows = kept;
    rows.extend(new_rows);
    rows.sort_by_key(|r| r.index);
    rewrite_sorted(opts.out, &rows)?;
    Ok(SweepSummary {
        planned: total,
        reused,
        dropped,
        computed,
        rows,
    })
}

/// The rows of `file` that answer jobs of this run, one per job (`ids[i]` is the id of
/// `mine[i]`), relabelled with the job's index, scene name and grid fields; and the number of
/// rows of `file` not used. A job takes the row with its id and index if there is one, else
/// the first row with its id (a reordered grid, or two configurations of one grid that
/// spell the same hardware). A colour render's row without colour metrics (written before
/// rows had them) is not kept.
fn keep_rows(
    file: Vec<Row>,
    mine: &[Job],
    ids: &[String],
    configs: &[Config],
    scenes: &[Scene],
) -> (Vec<Row>, usize) {
    let mut exact: BTreeMap<(&str, usize), usize> = BTreeMap::new();
    let mut first: BTreeMap<&str, usize> = BTreeMap::new();
    for (p, r) in file.iter().enumerate() {
        exact.entry((r.id.as_str(), r.index)).or_insert(p);
        first.entry(r.id.as_str()).or_insert(p);
    }
    let mut used = vec![false; file.len()];
    let mut kept = Vec::new();
    for (j, id) in mine.iter().zip(ids) {
        let at = exact
            .get(&(id.as_str(), j.index))
            .or_else(|| first.get(id.as_str()));
        let colour = pipeline::plan::channels(&scenes[j.scene], &configs[j.config].hw) > 1;
        if let Some(&p) = at.filter(|&&p| file[p].colour.is_some() == colour) {
            used[p] = true;
            kept.push(relabel(file[p].clone(), j, configs, scenes));
        }
    }
    let unused = used.iter().filter(|&&u| !u).count();
    (kept, unused)
}

/// `r` as the row of job `j`: its index, scene name and grid fields (a row found by its id
/// may come from a reordered or respelled grid).
pub(crate) fn relabel(mut r: Row, j: &Job, configs: &[Config], scenes: &[Scene]) -> Row {
    r.index = j.index;
    r.scene = scenes[j.scene].name.clone();
    r.config = config_json(&configs[j.config]);
    r
}

/// A row as JSON without its run state (timing, reused stages), for comparing runs.
pub fn without_timing(r: &Row) -> serde_json::Value {
    let mut v = serde_json::to_value(r).unwrap_or_default();
    if let Some(o) = v.as_object_mut() {
        o.remove("timing");
        o.remove("reused");
    }
    v
}
