//! Shards `K/N` of a run: a contiguous block of its jobs (a sweep's configurations x
//! scenes, a sequence's frames), given as `K/N` or taken from a Slurm array task or a
//! Kubernetes indexed Job (`--shard auto`, docs/cluster.md). Shared by `igemu sweep` and
//! `igemu sequence`.

/// A shard `K/N` (1-based K): a contiguous block of the job list (a sweep's jobs, a
/// sequence's frames), so the shard outputs joined in K order equal the unsharded output.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// 1-based shard number.
    pub k: usize,
    /// Number of shards.
    pub n: usize,
}

impl Shard {
    /// Parses `K/N` with 1 <= K <= N.
    pub fn parse(s: &str) -> Result<Shard, String> {
        let (k, n) = s
            .split_once('/')
            .ok_or_else(|| format!("`{s}` is not K/N (e.g. 2/4)"))?;
        let k: usize = k
            .trim()
            .parse()
            .map_err(|_| format!("`{s}`: K must be a positive integer"))?;
        let n: usize = n
            .trim()
            .parse()
            .map_err(|_| format!("`{s}`: N must be a positive integer"))?;
        if n == 0 || k == 0 || k > n {
            return Err(format!("`{s}`: need 1 <= K <= N, got K = {k}, N = {n}"));
        }
        Ok(Shard { k, n })
    }

    /// Parses a `--shard` value: `K/N`, or `auto` / `auto/N`, which take the shard from the
    /// environment ([`Shard::from_env`], read through `env`). Returns the shard and, for
    /// `auto`, where it came from (e.g. `SLURM_ARRAY_TASK_ID=5 (MIN=4 COUNT=4 STEP=1 MAX=7)`).
    pub fn from_arg(
        s: &str,
        env: impl Fn(&str) -> Option<String>,
    ) -> Result<(Shard, Option<String>), String> {
        let count = match s.trim().strip_prefix("auto") {
            None => return Shard::parse(s).map(|sh| (sh, None)),
            Some("") => None,
            Some(rest) => {
                let n = rest.strip_prefix('/').unwrap_or("x");
                match n.trim().parse::<usize>() {
                    Ok(n) if n > 0 => Some(n),
                    _ => {
                        return Err(format!(
                            "`{s}`: give `auto`, or `auto/N` with N a positive integer (the number of tasks)"
                        ));
                    }
                }
            }
        };
        Shard::from_env(count, env).map(|(sh, from)| (sh, Some(from)))
    }

    /// The shard of this task of a Slurm job array or a Kubernetes indexed Job (`--shard
    /// auto`, or `auto/N` with `count` = N):
    /// * Slurm (`SLURM_ARRAY_TASK_ID` set): the array must be a range `A-B` or `A-B:S`
    ///   (`SLURM_ARRAY_TASK_MIN` + (`SLURM_ARRAY_TASK_COUNT` - 1) x `SLURM_ARRAY_TASK_STEP`
    ///   = `SLURM_ARRAY_TASK_MAX`), whatever its first index: K = (ID - MIN) / STEP + 1,
    ///   N = COUNT. `auto/N` also requires COUNT = N. A one-task array is refused with
    ///   `auto` (it would be shard 1/1, the whole run: the usual mistake when one failed
    ///   task is resubmitted alone), allowed with `auto/1`.
    /// * Kubernetes (`JOB_COMPLETION_INDEX` set, 0-based): K = index + 1 of N, which must be
    ///   given (`auto/N`, N = the Job's `completions`): the pod does not see it.
    ///
    /// A missing or bad variable is an error naming it and the allowed range.
    pub fn from_env(
        count: Option<usize>,
        env: impl Fn(&str) -> Option<String>,
    ) -> Result<(Shard, String), String> {
        let spec = count.map_or("`auto`".to_string(), |c| format!("`auto/{c}`"));
        let var = |name: &str| -> Result<Option<usize>, String> {
            match env(name) {
                None => Ok(None),
                Some(v) => v
                    .trim()
                    .parse()
                    .map(Some)
                    .map_err(|_| format!("{spec}: {name}=`{v}` is not a non-negative integer")),
            }
        };
        let need = |name: &str| -> Result<usize, String> {
            var(name)?.ok_or_else(|| {
                format!("{spec}: SLURM_ARRAY_TASK_ID is set but {name} is not (Slurm sets both in an array task)")
            })
        };
        if let Some(id) = var("SLURM_ARRAY_TASK_ID")? {
            let min = need("SLURM_ARRAY_TASK_MIN")?;
            let n = need("SLURM_ARRAY_TASK_COUNT")?;
            let step = var("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1);
            let max = var("SLURM_ARRAY_TASK_MAX")?;
            let from = format!(
                "SLURM_ARRAY_TASK_ID={id} (MIN={min} COUNT={n} STEP={step}{})",
                max.map_or(String::new(), |m| format!(" MAX={m}"))
            );
            if n == 0 || step == 0 {
                return Err(format!(
                    "{spec}: {from}: SLURM_ARRAY_TASK_COUNT and SLURM_ARRAY_TASK_STEP must be at least 1"
                ));
            }
            let last = (n as u128 - 1) * step as u128 + min as u128;
            if max.is_some_and(|m| m as u128 != last) {
                return Err(format!(
                    "{spec}: {from}: the array is not a range A-B or A-B:S (a list of task ids?); \
                     submit --array=A-B[:S] or give the shard as --shard K/N"
                ));
            }
            if id < min || (id - min) % step != 0 || (id - min) / step >= n {
                let ids = match n {
                    1 => format!("{min}"),
                    2 => format!("{min} or {last}"),
                    _ => format!("one of {min}, {}, ..., {last}", min as u128 + step as u128),
                };
                return Err(format!("{spec}: {from}: SLURM_ARRAY_TASK_ID must be {ids}"));
            }
            match count {
                Some(c) if c != n => {
                    return Err(format!(
                        "{spec}: {from}: the array has {n} tasks, not {c} (a resubmitted subset \
                         of the tasks? give each task's shard as --shard K/{c})"
                    ));
                }
                None if n == 1 => {
                    return Err(format!(
                        "{spec}: {from}: a one-task array would run everything (every job or frame) as shard 1/1 \
                         (one failed task resubmitted alone? give its shard as --shard K/N); \
                         --shard auto/1 if you mean it"
                    ));
                }
                _ => {}
            }
            let k = (id - min) / step + 1;
            return Ok((Shard { k, n }, from));
        }
        if let Some(index) = var("JOB_COMPLETION_INDEX")? {
            let from = format!("JOB_COMPLETION_INDEX={index}");
            let Some(n) = count else {
                return Err(format!(
                    "{spec}: {from} (a Kubernetes indexed Job) needs the number of tasks: \
                     --shard auto/N with N = the Job's completions"
                ));
            };
            if index >= n {
                return Err(format!(
                    "{spec}: {from} must be in 0..={} (0-based, N = {n} completions)",
                    n - 1
                ));
            }
            return Ok((Shard { k: index + 1, n }, from));
        }
        Err(format!(
            "{spec}: neither SLURM_ARRAY_TASK_ID (a Slurm array task) nor JOB_COMPLETION_INDEX \
             (a Kubernetes indexed Job) is set; outside such a task give --shard K/N"
        ))
    }

    /// The half-open range of job indices of this shard among `total` jobs:
    /// `floor((K - 1) * total / N)..floor(K * total / N)`, computed in 128 bits so that no
    /// K, N or total overflows. Shard `K` ends where shard `K + 1` starts, shard 1 starts at
    /// 0 and shard N ends at `total`, so the shards partition the jobs; when N exceeds the
    /// number of jobs some shards are empty. A shard built by hand with K outside `1..=N`
    /// is clamped into the valid range.
    pub fn range(&self, total: usize) -> std::ops::Range<usize> {
        let n = self.n.max(1) as u128;
        let k = (self.k.max(1) as u128).min(n);
        // k * total / n <= total, so the casts back are exact.
        let at = |k: u128| (k * total as u128 / n) as usize;
        at(k - 1)..at(k)
    }
}
