//! Merging the part files of a sharded sweep (`igemu sweep merge`, docs/cluster.md): the
//! rows of every task of a Slurm array or a Kubernetes indexed Job put back into one file.
//!
//! The expected rows are recomputed from the grid and the scenes, exactly as the sweep
//! computes them: job `i` of the unsharded run and its row id ([`super::rows::job_ids`],
//! the id by content of the scene, the validated hardware, the tool version and the
//! depth-of-field truth's lens-sample count). Every row read is matched to a job by its id
//! (the job of the row's own index first, when two configurations of the grid spell the
//! same hardware) and takes that job's index, scene name and grid fields, as `--resume`
//! does. The merge is complete when every job has exactly one row, no row belongs to no job,
//! and the rows agree on `--flicker` (which is not part of the id); then the rows are in job
//! order, which is the order of the unsharded run. Otherwise [`Merged::problems`] names the
//! missing jobs (index, id, scene, configuration), the duplicated ones (id and every
//! `file:line`), the foreign rows and the `--flicker` mix.

use super::grid::Config;
use super::rows::{io, job_ids, parse_rows};
use super::{Row, jobs, relabel};
use crate::error::Result;
use crate::scene::Scene;
use std::collections::{BTreeMap, HashMap};
use std::fmt;

/// How many entries of each kind of problem are listed one by one.
pub const LISTED: usize = 20;

/// One part file read back.
#[derive(Clone, Debug)]
pub struct Part {
    /// The path as given.
    pub path: String,
    /// Its complete rows with their 1-based line numbers.
    pub rows: Vec<(usize, Row)>,
    /// Lines that are not complete rows (a killed task's partial last line, a stray line).
    pub skipped: Vec<usize>,
}

impl Part {
    /// Reads a part file (a missing file is an error).
    pub fn read(path: &str) -> Result<Part> {
        let bytes = std::fs::read(path).map_err(io(path))?;
        let (rows, skipped) = parse_rows(&String::from_utf8_lossy(&bytes));
        Ok(Part {
            path: path.to_string(),
            rows,
            skipped,
        })
    }
}

/// Where a row stands: `file:line`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Place {
    /// The part file.
    pub file: String,
    /// 1-based line.
    pub line: usize,
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.file, self.line)
    }
}

/// A job of the grid that no part file has a row for.
#[derive(Clone, Debug, PartialEq)]
pub struct Missing {
    /// Job index in the unsharded run.
    pub index: usize,
    /// The row id it expects.
    pub id: String,
    /// Scene name.
    pub scene: String,
    /// The configuration (`path=value;...`).
    pub config: String,
}

/// A job with more than one row.
#[derive(Clone, Debug, PartialEq)]
pub struct Duplicate {
    /// Job index.
    pub index: usize,
    /// The row id.
    pub id: String,
    /// Every row of the job, the one kept first.
    pub places: Vec<Place>,
}

/// A row whose id is no job of the grid on these scenes: a stale row (the scene, the grid,
/// `--dof-truth` or the tool version changed) or a row of another sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Foreign {
    /// Its id.
    pub id: String,
    /// The index written in the row.
    pub index: usize,
    /// Where it stands.
    pub place: Place,
}

/// The outcome of a merge.
#[derive(Clone, Debug)]
pub struct Merged {
    /// Jobs of the grid (configurations x scenes).
    pub jobs: usize,
    /// One row per job that has one, in job order, relabelled with the job's index, scene
    /// name and grid fields.
    pub rows: Vec<Row>,
    /// Jobs without a row.
    pub missing: Vec<Missing>,
    /// Jobs with more than one row.
    pub duplicated: Vec<Duplicate>,
    /// Rows of no job.
    pub foreign: Vec<Foreign>,
    /// When the rows disagree on `--flicker`: each setting (phases, `None` without) with the
    /// first row that has it.
    pub flicker: Vec<(Option<u32>, Place)>,
    /// Lines that are not complete rows (reported, not an error by themselves: a job they
    /// should have held is missing).
    pub skipped: Vec<Place>,
}

impl Merged {
    /// Whether every job has exactly one row and nothing else was found.
    pub fn complete(&self) -> bool {
        self.missing.is_empty()
            && self.duplicated.is_empty()
            && self.foreign.is_empty()
            && self.flicker.is_empty()
    }

    /// The problems as text, one kind per paragraph (empty when [`Merged::complete`]).
    pub fn problems(&self) -> Problems<'_> {
        Problems(self)
    }
}

/// Merges the rows of `parts` into the sweep of `configs` on `scenes` (with the truth's
/// lens-sample count `dof_truth`, as given to the sweep): see the module docs.
pub fn merge(
    configs: &[Config],
    scenes: &[Scene],
    dof_truth: Option<u32>,
    parts: &[Part],
) -> Merged {
    let all = jobs(configs.len(), scenes.len());
    let ids = job_ids(configs, scenes, dof_truth);
    let mut by_id: HashMap<&str, Vec<usize>> = HashMap::new();
    for (j, id) in ids.iter().enumerate() {
        by_id.entry(id.as_str()).or_default().push(j);
    }
    let mut taken: Vec<Option<(Place, &Row)>> = vec![None; all.len()];
    let mut extra: BTreeMap<usize, Vec<Place>> = BTreeMap::new();
    let mut foreign = Vec::new();
    let mut flicker: BTreeMap<Option<u32>, Place> = BTreeMap::new();
    let mut skipped = Vec::new();
    for p in parts {
        let place = |line: usize| Place {
            file: p.path.clone(),
            line,
        };
        skipped.extend(p.skipped.iter().map(|&l| place(l)));
        for (line, row) in &p.rows {
            let Some(slots) = by_id.get(row.id.as_str()) else {
                foreign.push(Foreign {
                    id: row.id.clone(),
                    index: row.index,
                    place: place(*line),
                });
                continue;
            };
            flicker
                .entry(row.flicker.as_ref().map(|f| f.phases))
                .or_insert_with(|| place(*line));
            // The job of the row's own index when the id is that job's, else the first job
            // of the id without a row.
            let own = slots.contains(&row.index).then_some(row.index);
            let free = own
                .filter(|&j| taken[j].is_none())
                .or_else(|| slots.iter().copied().find(|&j| taken[j].is_none()));
            match free {
                Some(j) => taken[j] = Some((place(*line), row)),
                None => extra
                    .entry(own.unwrap_or(slots[0]))
                    .or_default()
                    .push(place(*line)),
            }
        }
    }
    let mut rows = Vec::new();
    let mut missing = Vec::new();
    for (j, t) in all.iter().zip(&taken) {
        match t {
            Some((_, r)) => rows.push(relabel((*r).clone(), j, configs, scenes)),
            None => missing.push(Missing {
                index: j.index,
                id: ids[j.index].clone(),
                scene: scenes[j.scene].name.clone(),
                config: configs[j.config].canonical.clone(),
            }),
        }
    }
    let duplicated = extra
        .into_iter()
        .map(|(j, more)| {
            let first = taken[j].as_ref().map(|(p, _)| p.clone());
            Duplicate {
                index: j,
                id: ids[j].clone(),
                places: first.into_iter().chain(more).collect(),
            }
        })
        .collect();
    Merged {
        jobs: all.len(),
        rows,
        missing,
        duplicated,
        foreign,
        flicker: if flicker.len() > 1 {
            flicker.into_iter().collect()
        } else {
            Vec::new()
        },
        skipped,
    }
}

/// Sorted indices as ranges: `3, 5..=9, 12`.
pub fn ranges(sorted: &[usize]) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut i = 0;
    while i < sorted.len() {
        let mut j = i;
        while j + 1 < sorted.len() && sorted[j + 1] == sorted[j] + 1 {
            j += 1;
        }
        out.push(if j == i {
            sorted[i].to_string()
        } else {
            format!("{}..={}", sorted[i], sorted[j])
        });
        i = j + 1;
    }
    out.join(", ")
}

/// The problems of a [`Merged`] as text ([`Merged::problems`]).
pub struct Problems<'a>(&'a Merged);

/// Writes `items` one per line (at most [`LISTED`], then how many more).
fn list<T>(
    f: &mut fmt::Formatter<'_>,
    items: &[T],
    line: impl Fn(&mut fmt::Formatter<'_>, &T) -> fmt::Result,
) -> fmt::Result {
    for it in items.iter().take(LISTED) {
        write!(f, "  ")?;
        line(f, it)?;
        writeln!(f)?;
    }
    if items.len() > LISTED {
        writeln!(f, "  ... and {} more", items.len() - LISTED)?;
    }
    Ok(())
}

impl fmt::Display for Problems<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = self.0;
        if !m.missing.is_empty() {
            let idx: Vec<usize> = m.missing.iter().map(|x| x.index).collect();
            writeln!(
                f,
                "missing {} of {} rows (job indices {}): rerun the task that had them with --resume",
                m.missing.len(),
                m.jobs,
                ranges(&idx)
            )?;
            list(f, &m.missing, |f, x| {
                write!(
                    f,
                    "index {} id {} scene `{}` {}",
                    x.index, x.id, x.scene, x.config
                )
            })?;
        }
        if !m.duplicated.is_empty() {
            writeln!(
                f,
                "{} rows duplicated (each job must have one row: overlapping shards, or a part file given twice?)",
                m.duplicated.len()
            )?;
            list(f, &m.duplicated, |f, x| {
                let at: Vec<String> = x.places.iter().map(Place::to_string).collect();
                write!(f, "index {} id {} at {}", x.index, x.id, at.join(", "))
            })?;
        }
        if !m.foreign.is_empty() {
            writeln!(
                f,
                "{} rows not in the grid on these scenes (stale: another grid, scene, --dof-truth or igemu version?)",
                m.foreign.len()
            )?;
            list(f, &m.foreign, |f, x| {
                write!(f, "id {} (index {}) at {}", x.id, x.index, x.place)
            })?;
        }
        if !m.flicker.is_empty() {
            let s: Vec<String> = m
                .flicker
                .iter()
                .map(|(n, p)| match n {
                    Some(n) => format!("--flicker {n} (first at {p})"),
                    None => format!("no --flicker (first at {p})"),
                })
                .collect();
            writeln!(
                f,
                "the rows come from sweeps with different flicker settings: {}",
                s.join(", ")
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::ranges;

    #[test]
    fn ranges_join_consecutive_indices() {
        assert_eq!(ranges(&[]), "");
        assert_eq!(ranges(&[4]), "4");
        assert_eq!(ranges(&[0, 1, 2, 5, 7, 8]), "0..=2, 5, 7..=8");
    }
}
