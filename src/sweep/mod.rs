//! Word-width sweeps: every configuration of a grid rendered and compared with the float
//! reference, one JSON line per (configuration, scene), resumable and shardable.
//!
//! * Order: configurations in grid order ([`grid`]), scenes inner; job `i` is configuration
//!   `i / scenes`, scene `i % scenes`.
//! * Rows are appended and flushed one by one as they finish, so a killed sweep loses no
//!   completed row. When every job of the run is done the file is rewritten in job order
//!   (temporary file + rename), so a serial, a parallel and a resumed run give the same file.
//! * `--resume` reads the file, keeps every complete row (keyed by the stable row id, an
//!   FNV-1a hash of scene name and configuration), drops a partial last line and runs the rest.
//! * `--shard K/N` runs a contiguous block of jobs: shard files concatenated in K order equal
//!   the unsharded output.

pub mod grid;
pub mod pareto;
pub mod plot;

use crate::error::{Error, Result};
use crate::pipeline::{self, Cache};
use crate::scene::Scene;
use crate::stage::RunOptions;
use grid::{Config, Shard};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;

/// Error metrics of a row (DAC codes, fixed vs float reference).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ErrorMetrics {
    /// Largest |fixed - reference| DAC code difference.
    pub max_code_diff: u32,
    /// Mean |difference|, codes.
    pub mean_code_diff: f64,
    /// Mean signed difference (fixed - reference), codes: the bias.
    pub mean_signed_code_diff: f64,
    /// PSNR in dB (`None` when identical).
    pub psnr_db: Option<f64>,
    /// Fraction of identical codes.
    pub identical_fraction: f64,
    /// Largest Weber error through the display model.
    pub weber_max: f64,
    /// Mean Weber error.
    pub weber_mean: f64,
    /// Fraction of pixels whose Weber error exceeds the visibility threshold.
    pub weber_visible_fraction: f64,
    /// Visible contour steps in smooth regions (fixed).
    pub contour_steps: u64,
    /// Pixels next to a visible contour step.
    pub contour_pixels: u64,
}

/// Cost of a row.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CostMetrics {
    /// RAM bits over all stages.
    pub storage_bits: u64,
    /// LUT / ROM bits.
    pub lut_bits: u64,
    /// Adders.
    pub adders: u64,
    /// Multipliers.
    pub multipliers: u64,
}

/// Cycle model of a row.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CycleMetrics {
    /// Cycles per frame.
    pub total_cycles: u64,
    /// Frames per second at the configured clock.
    pub fps: f64,
    /// Bottleneck stage.
    pub bottleneck: String,
    /// Whether the frame rate meets the display's refresh rate.
    pub real_time: bool,
}

/// Small-object flicker of a row's hardware (`--flicker PHASES`; see [`crate::analysis::flicker`]):
/// the worst object of the flicker scene swept over `phases x phases` sub-pixel phases.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct FlickerMetrics {
    /// Sub-pixel phases per axis.
    pub phases: u32,
    /// Largest peak-to-peak displayed luminance of an object, % of its mean.
    pub displayed_ripple_pct: f64,
    /// Largest peak-pixel modulation, %.
    pub peak_pixel_modulation_pct: f64,
    /// Largest |brightness error| of an object split over two pixels, %.
    pub half_pixel_brightness_error_pct: f64,
    /// The object with the largest displayed ripple.
    pub worst_object: String,
}

impl FlickerMetrics {
    /// Runs the flicker sweep of `hw`.
    pub fn of(hw: &crate::config::HwConfig, phases: u32) -> Result<FlickerMetrics> {
        let r = crate::analysis::flicker::flicker(hw, phases)?;
        let max = |f: fn(&crate::analysis::flicker::ObjectFlicker) -> f64| {
            r.objects.iter().map(f).fold(0.0, f64::max)
        };
        let worst = r
            .objects
            .iter()
            .max_by(|a, b| a.displayed_ripple_pct.total_cmp(&b.displayed_ripple_pct))
            .map_or(String::new(), |o| o.object.clone());
        Ok(FlickerMetrics {
            phases,
            displayed_ripple_pct: max(|o| o.displayed_ripple_pct),
            peak_pixel_modulation_pct: max(|o| o.peak_pixel_modulation_pct),
            half_pixel_brightness_error_pct: max(|o| o.half_pixel_brightness_error_pct.abs()),
            worst_object: worst,
        })
    }
}

/// Wall time of a row (the only field that differs between runs).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RowTiming {
    /// Milliseconds for the whole render.
    pub render_ms: f64,
}

/// One JSON line of the output.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Row {
    /// Stable id: 16 hex digits of FNV-1a(scene name, '\n', canonical configuration).
    pub id: String,
    /// Job index in the full (unsharded) sweep.
    pub index: usize,
    /// Scene name.
    pub scene: String,
    /// Grid field -> value.
    pub config: BTreeMap<String, serde_json::Value>,
    /// Error metrics.
    pub error: ErrorMetrics,
    /// Cost.
    pub cost: CostMetrics,
    /// Cycles and throughput.
    pub cycles: CycleMetrics,
    /// Small-object flicker (only with `--flicker`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flicker: Option<FlickerMetrics>,
    /// Stages whose result was reused from an earlier row of the run (run state, like the
    /// timing: excluded when rows are compared).
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

/// The stable id of a (scene, configuration) row.
pub fn row_id(scene: &str, canonical: &str) -> String {
    let mut key = scene.as_bytes().to_vec();
    key.push(b'\n');
    key.extend_from_slice(canonical.as_bytes());
    format!("{:016x}", crate::fnv::fnv1a(&key))
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

/// Renders one configuration on one scene and builds its row (with the flicker sweep at
/// `flicker` phases when given).
pub fn run_job(
    job: Job,
    cfg: &Config,
    scene: &Scene,
    cache: Option<&Cache>,
    flicker: Option<u32>,
) -> Result<Row> {
    let t = std::time::Instant::now();
    let r = pipeline::render_with(scene, &cfg.hw, RunOptions::FAST, cache)?;
    let render_ms = t.elapsed().as_secs_f64() * 1e3;
    let rep = &r.report;
    let c = &rep.end_to_end.codes;
    let w = &rep.end_to_end.weber;
    Ok(Row {
        id: row_id(&scene.name, &cfg.canonical),
        index: job.index,
        scene: scene.name.clone(),
        config: cfg
            .fields
            .iter()
            .map(|(k, v)| {
                (
                    k.clone(),
                    serde_json::to_value(v).unwrap_or(serde_json::Value::Null),
                )
            })
            .collect(),
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
        reused: rep.reused.clone(),
        timing: RowTiming { render_ms },
    })
}

fn io(path: &str) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_string(),
        source,
    }
}

/// Reads the complete rows of an output file. A line that does not parse (a partial last
/// line of a killed run) is dropped; returns the rows and whether anything was dropped.
pub fn read_rows(path: &str) -> Result<(Vec<Row>, bool)> {
    let text = match std::fs::read(path) {
        Ok(b) => String::from_utf8_lossy(&b).into_owned(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok((Vec::new(), false)),
        Err(e) => return Err(io(path)(e)),
    };
    let mut rows = Vec::new();
    let mut dropped = false;
    for (i, line) in text.split('\n').enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        // A line without its newline is partial even if it parses.
        let complete = text.split('\n').nth(i + 1).is_some();
        match serde_json::from_str::<Row>(line) {
            Ok(r) if complete => rows.push(r),
            _ => dropped = true,
        }
    }
    Ok((rows, dropped))
}

/// Writes rows (sorted by index, one per id) to `path` through a temporary file and a rename.
pub fn rewrite_sorted(path: &str, rows: &[Row]) -> Result<()> {
    let mut by_index: BTreeMap<usize, &Row> = BTreeMap::new();
    for r in rows {
        by_index.entry(r.index).or_insert(r);
    }
    let tmp = format!("{path}.tmp");
    {
        let mut f = std::io::BufWriter::new(std::fs::File::create(&tmp).map_err(io(&tmp))?);
        for r in by_index.values() {
            let line = serde_json::to_string(r).expect("rows serialise");
            writeln!(f, "{line}").map_err(io(&tmp))?;
        }
        f.flush().map_err(io(&tmp))?;
    }
    std::fs::rename(&tmp, path).map_err(io(path))
}

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
}

/// Summary of a run.
#[derive(Debug)]
pub struct SweepSummary {
    /// Jobs in this shard.
    pub planned: usize,
    /// Rows found in the file and kept (`--resume`).
    pub reused: usize,
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
    let mine = &all[range];
    let id_of = |j: &Job| row_id(&scenes[j.scene].name, &configs[j.config].canonical);
    let wanted: BTreeSet<String> = mine.iter().map(id_of).collect();
    let mut kept: Vec<Row> = Vec::new();
    if opts.resume {
        let (rows, _dropped) = read_rows(opts.out)?;
        let mut seen = BTreeSet::new();
        for r in rows {
            if wanted.contains(&r.id) && seen.insert(r.id.clone()) {
                kept.push(r);
            }
        }
        // Drop the partial line and any foreign or duplicate row before appending.
        rewrite_sorted(opts.out, &kept)?;
    } else {
        std::fs::File::create(opts.out).map_err(io(opts.out))?;
    }
    let done: BTreeSet<&str> = kept.iter().map(|r| r.id.as_str()).collect();
    let todo: Vec<Job> = mine
        .iter()
        .copied()
        .filter(|j| !done.contains(id_of(j).as_str()))
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
    let work = |j: &Job| -> Result<Row> {
        let row = run_job(
            *j,
            &configs[j.config],
            &scenes[j.scene],
            opts.cache,
            opts.flicker,
        )?;
        let mut line = serde_json::to_string(&row).expect("rows serialise");
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
        computed,
        rows,
    })
}

/// A row as JSON without its run state (timing, reused stages), for comparing runs.
pub fn without_timing(r: &Row) -> serde_json::Value {
    let mut v = serde_json::to_value(r).expect("rows serialise");
    if let Some(o) = v.as_object_mut() {
        o.remove("timing");
        o.remove("reused");
    }
    v
}
