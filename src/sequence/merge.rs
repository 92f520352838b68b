//! `igemu sequence merge` (docs/sequence.md): the part files of a sharded sequence run
//! ([`super::shard`]) checked and joined into the report of the whole run.
//!
//! The parts must be of one run: the same scene (name and content), hardware (name and
//! content), filter, reference, reuse, `--frames` range and igemu version. Their frame
//! ranges must tile the run's range: frames in no part and frames in two parts are named
//! with the files. Then the per-frame records are joined in frame order, and the summary
//! (worst frame, missed frames, mean, percentiles) and the temporal figures are computed
//! from the joined records and series as one run computes them, so the merged report equals
//! the unsharded run's except the wall-clock and reuse counters (each shard starts with its
//! own cold stage cache): `frames[].wall_ms`, `frames[].reused_stages`,
//! `frames[].emulated_stages` and `reuse` apart from `enabled` and `camera_moves`
//! (`reuse.wall_s` is the sum of the shards' emulation times).

use super::shard::{PART_KIND, Part, shard_frames};
use super::{SequenceReport, reuse_report, summarize};
use crate::error::{Error, FileError, Result};
use crate::shard::Shard;
use std::ops::Range;

/// A part's error: names its file.
fn bad(path: &str, field: &str, msg: impl Into<String>) -> Error {
    FileError {
        file: path.to_string(),
        line: None,
        col: None,
        field: field.to_string(),
        msg: msg.into(),
    }
    .into()
}

/// Reads the part file `path` (written by `igemu sequence --shard K/N --part FILE`) and
/// checks that it holds what its own frames need.
pub fn read(path: &str) -> Result<Part> {
    let bytes = std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_string(),
        source,
    })?;
    let what = "is not a part file of `igemu sequence --shard K/N --part FILE`";
    let p: Part = serde_json::from_slice(&bytes).map_err(|e| {
        Error::from(FileError {
            file: path.to_string(),
            line: (e.line() > 0).then_some(e.line()),
            col: (e.column() > 0).then_some(e.column()),
            field: String::new(),
            msg: format!("{what} (a task killed while writing? rerun its shard): {e}"),
        })
    })?;
    if p.kind != PART_KIND {
        return Err(bad(
            path,
            "kind",
            format!("`{}`: {what} (kind `{PART_KIND}`)", p.kind),
        ));
    }
    check(path, &p)?;
    Ok(p)
}

/// The frames `[a, b)` as a range.
fn range(r: [u32; 2]) -> Range<u32> {
    r[0]..r[1]
}

/// Refuses a part whose lists do not match its frames (an edited or cut file).
fn check(path: &str, p: &Part) -> Result<()> {
    let (run, frames) = (range(p.run), range(p.frames));
    let r = &p.report;
    let n = frames.len();
    let fail = |field: &str, what: String| {
        bad(
            path,
            field,
            format!(
                "{what}: the part does not hold what its frames need (edited? rerun its shard)"
            ),
        )
    };
    if frames.is_empty() || run.is_empty() || frames.start < run.start || frames.end > run.end {
        return Err(fail(
            "frames",
            format!(
                "frames {}..{} are not a non-empty part of the run's frames {}..{}",
                frames.start, frames.end, run.start, run.end
            ),
        ));
    }
    let numbered = r.frames.iter().map(|f| f.frame).eq(frames.clone());
    if !numbered || r.first != frames.start {
        return Err(fail(
            "report.frames",
            format!(
                "its records are not the frames {}..{}",
                frames.start, frames.end
            ),
        ));
    }
    let t = &p.temporal;
    let lead_in = r.reference && frames.start > run.start;
    let pairs = if r.reference {
        n - 1 + usize::from(lead_in)
    } else {
        0
    };
    if p.lead_in != lead_in || t.pairs.len() != pairs || t.pair_sums.len() != pairs {
        return Err(fail(
            "temporal.pairs",
            format!(
                "{} frame pairs for frames {}..{} (expected {pairs})",
                t.pairs.len(),
                frames.start,
                frames.end
            ),
        ));
    }
    let per_ref = if r.reference { n } else { 0 };
    for o in &t.objects {
        let lens = [o.total_fixed.len(), o.peak_fixed.len()];
        let refs = [o.total_reference.len(), o.peak_reference.len()];
        if lens != [n, n] || refs != [per_ref, per_ref] {
            return Err(fail(
                "temporal.objects",
                format!("object {}'s series are not one value per frame", o.object),
            ));
        }
    }
    let pixels = r.width as usize * r.height as usize;
    if let Some(d) = &t.dither
        && (d.frames as usize != n || !d.has_pixels(pixels))
    {
        return Err(fail(
            "temporal.dither",
            format!("the dither's sums are not {n} frames of {pixels} pixels"),
        ));
    }
    Ok(())
}

/// What must be the same in every part of a run: (field, value).
fn identity(p: &Part) -> Vec<(&'static str, String)> {
    let r = &p.report;
    vec![
        ("report.igemu_version", r.igemu_version.clone()),
        ("report.scene", r.scene.clone()),
        ("report.sequence_frames", r.sequence_frames.to_string()),
        ("run", format!("{}..{}", p.run[0], p.run[1])),
        ("report.hardware", r.hardware.clone()),
        ("report.filter", r.filter.clone()),
        ("report.reference", r.reference.to_string()),
        ("report.reuse.enabled", r.reuse.enabled.to_string()),
        // The contents last: a difference the names above do not show.
        ("scene_key", p.scene_key.clone()),
        ("hardware_key", p.hardware_key.clone()),
    ]
}

/// The shards of `n` over `run` that hold some of `gap` (to rerun).
fn shards_of(run: &Range<u32>, n: usize, gap: &Range<u32>) -> String {
    let ks: Vec<String> = (1..=n)
        .filter(|&k| {
            shard_frames(run, Shard { k, n }).is_ok_and(|r| r.start < gap.end && gap.start < r.end)
        })
        .map(|k| format!("{k}/{n}"))
        .collect();
    ks.join(", ")
}

/// Merges the parts `(path, part)` (any order) into the report of the whole run; see the
/// module docs. Every problem is an error naming the files.
pub fn merge(parts: Vec<(String, Part)>) -> Result<SequenceReport> {
    let Some((path0, first)) = parts.first() else {
        return Err(bad("igemu sequence merge", "", "no part file given"));
    };
    let id0 = identity(first);
    for (path, p) in &parts[1..] {
        for ((field, a), (_, b)) in identity(p).iter().zip(&id0) {
            if a != b {
                return Err(bad(
                    path,
                    field,
                    format!(
                        "`{a}`, but {path0} has `{b}`: the parts of one merge come from one run (the same scene, hardware, filter, reference, reuse, --frames and igemu version)"
                    ),
                ));
            }
        }
    }
    let run = range(first.run);
    let mut order: Vec<usize> = (0..parts.len()).collect();
    order.sort_by_key(|&i| (parts[i].1.frames[0], parts[i].1.frames[1]));
    let mut problems: Vec<(usize, String)> = Vec::new();
    let mut at = run.start;
    let mut last: Option<usize> = None;
    let n = first.shards;
    for &i in &order {
        let f = range(parts[i].1.frames);
        let name = |j: Option<usize>| j.map_or("the run's start".into(), |j| parts[j].0.clone());
        if f.start > at {
            let gap = at..f.start;
            problems.push((
                i,
                format!(
                    "frames {}..{} are in no part (between {} and {}: --shard {} of the parts' {n})",
                    gap.start,
                    gap.end,
                    name(last),
                    parts[i].0,
                    shards_of(&run, n, &gap)
                ),
            ));
        } else if f.start < at {
            problems.push((
                i,
                format!(
                    "frames {}..{} are in both {} and {} (overlapping shards, or a part given twice?)",
                    f.start,
                    f.end.min(at),
                    name(last),
                    parts[i].0
                ),
            ));
        }
        if f.end > at || last.is_none() {
            at = at.max(f.end);
            last = Some(i);
        }
    }
    if at < run.end {
        let gap = at..run.end;
        let j = last.unwrap_or(0);
        problems.push((
            j,
            format!(
                "frames {}..{} are in no part (after {}, the run ends at {}: --shard {} of the parts' {n})",
                gap.start,
                gap.end,
                parts[j].0,
                run.end,
                shards_of(&run, n, &gap)
            ),
        ));
    }
    if let Some((j, _)) = problems.first() {
        let all: Vec<&str> = problems.iter().map(|(_, m)| m.as_str()).collect();
        return Err(bad(
            &parts[*j].0,
            "frames",
            format!(
                "the parts do not tile the run's frames {}..{}: {}; run the missing shards, leave out the extra parts, and merge again",
                run.start,
                run.end,
                all.join("; ")
            ),
        ));
    }
    join(parts, &order)
}

/// Joins the checked parts in `order` (frame order).
fn join(parts: Vec<(String, Part)>, order: &[usize]) -> Result<SequenceReport> {
    let mut slots: Vec<Option<Part>> = parts.into_iter().map(|(_, p)| Some(p)).collect();
    let mut taken = order.iter().filter_map(|&i| slots[i].take());
    let Some(first) = taken.next() else {
        return Err(bad("igemu sequence merge", "", "no part file given"));
    };
    let (display, camera) = (first.display, first.first_camera.clone());
    let mut report = first.report;
    let mut state = first.temporal;
    let mut moves = report.reuse.camera_moves;
    let mut wall_s = report.reuse.wall_s;
    for p in taken {
        moves |= p.report.reuse.camera_moves || p.first_camera != camera;
        wall_s += p.report.reuse.wall_s;
        report.frames.extend(p.report.frames);
        state.join(p.temporal);
    }
    let s = &report.summary;
    report.summary = summarize(&report.frames, s.rate_hz, s.clock_mhz);
    let u = &report.reuse;
    report.reuse = reuse_report(
        (u.enabled, moves),
        (u.tile_rows_off.clone(), u.tile_rows, u.tile_size),
        &report.frames,
        wall_s,
    );
    report.temporal = state.report(&display.luminance_table(), display.weber);
    Ok(report)
}
