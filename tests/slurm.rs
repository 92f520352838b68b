//! A sweep on a real Slurm cluster (docs/cluster.md): `examples/slurm/sweep.sbatch`
//! submitted as a 4-task array with `sbatch --wait`, its part files merged with
//! `igemu sweep merge` and compared with a single-machine run of the same grid (identical
//! rows apart from timing); then one task's part file is cut short (a killed task) and that
//! task is resubmitted alone, as docs/cluster.md says.
//!
//! Needs a cluster that answers `scontrol ping` with an idle node on this machine (the
//! batch script runs the binary and writes the parts under the temporary folder):
//! `examples/slurm/local-cluster.sh start` makes one. Without it the test prints a SKIP
//! line and passes, unless `IGEMU_REQUIRE_SLURM=1` (set by .ci/run), which makes it fail.
//! Every wait is bounded (`timeout`, `sbatch --time`); on a failure the daemons' logs and
//! the tasks' outputs are printed.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Instant;

/// Why no cluster is usable, or `None` when one answers with an idle node.
fn no_cluster() -> Option<String> {
    let run = |cmd: &str, args: &[&str]| -> Result<String, String> {
        match Command::new("timeout")
            .arg("10")
            .arg(cmd)
            .args(args)
            .output()
        {
            Ok(o) if o.status.success() => Ok(String::from_utf8_lossy(&o.stdout).into_owned()),
            Ok(o) => Err(format!(
                "`{cmd} {}` failed ({}): {}",
                args.join(" "),
                o.status,
                String::from_utf8_lossy(&o.stderr).trim()
            )),
            Err(e) => Err(format!("cannot run `{cmd}`: {e}")),
        }
    };
    let ping = match run("scontrol", &["ping"]) {
        Ok(p) => p,
        Err(e) => return Some(e),
    };
    if !ping.contains("UP") {
        return Some(format!("scontrol ping: {}", ping.trim()));
    }
    match run("sinfo", &["-h", "-o", "%T"]) {
        Ok(s) if s.lines().any(|l| l.trim() == "idle") => None,
        Ok(s) => Some(format!("no idle node (sinfo: {})", s.trim())),
        Err(e) => Some(e),
    }
}

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/slurm/sweep.sbatch")
}

/// The daemons' logs (through the cluster script) and the tasks' outputs in `dir`.
fn diagnostics(dir: &Path) -> String {
    let mut s = String::new();
    let cluster = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/slurm/local-cluster.sh");
    if let Ok(o) = Command::new("bash").arg(cluster).arg("logs").output() {
        s.push_str(&String::from_utf8_lossy(&o.stdout));
    }
    if let Ok(o) = Command::new("sinfo").args(["-N", "-l"]).output() {
        s.push_str(&String::from_utf8_lossy(&o.stdout));
    }
    let mut outs: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|r| r.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    outs.sort();
    for p in outs
        .iter()
        .filter(|p| p.extension().is_some_and(|x| x == "out"))
    {
        s.push_str(&format!("----- {}\n", p.display()));
        s.push_str(&std::fs::read_to_string(p).unwrap_or_default());
    }
    s
}

/// `sbatch --wait` of the sweep script in `dir` with `env` and the extra sbatch `args`,
/// bounded: 5 minutes of run time per task, 6 minutes in all.
fn sbatch(dir: &Path, name: &str, args: &[&str], env: &[(&str, &str)]) -> Output {
    let o = Command::new("timeout")
        .args(["--kill-after=10", "360", "sbatch", "--wait", "--parsable"])
        .args(["--job-name", name, "--time=5"])
        .arg(format!("--chdir={}", dir.display()))
        .args(args)
        .arg(script())
        .env("IGEMU", env!("CARGO_BIN_EXE_igemu"))
        .envs(env.iter().copied())
        .output()
        .expect("run sbatch");
    if o.status.code() == Some(124) {
        let _ = Command::new("scancel").args(["--name", name]).status();
    }
    o
}

fn text(o: &Output) -> String {
    format!(
        "{}\n{}{}",
        o.status,
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The variable that turns a skip into a failure (set by .ci/run).
const REQUIRE: &str = "IGEMU_REQUIRE_SLURM";

/// No usable cluster (`why`): fails under `require`, else returns the SKIP line.
fn skip_or_fail(why: &str, require: bool) -> String {
    let hint = "start one with `examples/slurm/local-cluster.sh start` (root; apt-get install slurm-wlm munge)";
    if require {
        panic!("{REQUIRE}=1 but no Slurm cluster is usable: {why}; {hint}");
    }
    format!("SKIP tests/slurm.rs: NO SLURM CLUSTER, THE ARRAY SWEEP DID NOT RUN: {why}; {hint}")
}

/// Under `IGEMU_REQUIRE_SLURM=1` a skip fails the test; without it, it passes.
#[test]
fn a_skip_fails_when_slurm_is_required() {
    let e = std::panic::catch_unwind(|| skip_or_fail("no cluster", true)).unwrap_err();
    let msg = e.downcast_ref::<String>().expect("a message");
    assert!(msg.contains("no cluster") && msg.contains(REQUIRE), "{msg}");
    assert!(skip_or_fail("no cluster", false).starts_with("SKIP tests/slurm.rs"));
}

#[test]
fn a_four_task_array_sweep_merges_to_the_single_machine_run() {
    if let Some(why) = no_cluster() {
        let line = skip_or_fail(&why, std::env::var(REQUIRE).is_ok_and(|v| v == "1"));
        // On the stream itself, past the test harness's capture of `eprintln!`: loud.
        use std::io::Write;
        let _ = writeln!(std::io::stderr(), "\n{line}\n");
        return;
    }
    let d = std::env::temp_dir().join(format!("igemu-slurm-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    let (scenes, grid) = common::small_sweep(&d);
    let scene_list = scenes.join(" ");
    let parts = d.join("parts");
    let parts_s = parts.to_string_lossy().into_owned();
    let env = [
        ("GRID", grid.as_str()),
        ("SCENES", scene_list.as_str()),
        ("PARTS", parts_s.as_str()),
    ];
    let name = format!("igemu-test-{}", std::process::id());
    let (t, submitted) = (Instant::now(), std::time::SystemTime::now());
    let o = sbatch(&d, &name, &[], &env);
    let wall = t.elapsed().as_secs_f64();
    assert!(
        o.status.success(),
        "sbatch --wait: {}\n{}",
        text(&o),
        diagnostics(&d)
    );
    let job = String::from_utf8_lossy(&o.stdout).trim().to_string();
    // Each task said which shard it took, from its array index (the script's --array=0-3).
    for k in 0..4 {
        let log = d.join(format!("slurm-{job}_{k}.out"));
        let log = std::fs::read_to_string(&log).unwrap_or_default();
        let said = format!("shard {}/4 from SLURM_ARRAY_TASK_ID={k} ", k + 1);
        assert!(log.contains(&said), "task {k}: {log}\n{}", diagnostics(&d));
        let rows = common::rows_without_timing(&format!("{parts_s}/part-{k}.jsonl"));
        let idx: Vec<u64> = rows
            .iter()
            .map(|r| r["index"].as_u64().expect("index"))
            .collect();
        assert_eq!(
            idx,
            [2 * k, 2 * k + 1],
            "task {k}'s shard is its block of jobs"
        );
    }
    let part_files: Vec<String> = (0..4)
        .map(|k| format!("{parts_s}/part-{k}.jsonl"))
        .collect();
    let merged = d.join("all.jsonl").to_string_lossy().into_owned();
    let merge = || {
        let mut a: Vec<&str> = vec!["sweep", "merge"];
        a.extend(part_files.iter().map(String::as_str));
        a.extend(["--grid", &grid, "--out", &merged]);
        for s in &scenes {
            a.extend(["--scene", s.as_str()]);
        }
        common::igemu(&a)
    };
    let t = Instant::now();
    let (code, stdout, err) = merge();
    let merge_s = t.elapsed().as_secs_f64();
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("Pareto front"), "{stdout}");
    let single = d.join("single.jsonl").to_string_lossy().into_owned();
    let mut a: Vec<&str> = vec!["sweep"];
    a.extend(scenes.iter().map(String::as_str));
    a.extend(["--grid", &grid, "--out", &single]);
    let (code, _, err) = common::igemu(&a);
    assert_eq!(code, 0, "{err}");
    let rows = common::rows_without_timing(&merged);
    assert_eq!(rows.len(), 8);
    assert_eq!(rows, common::rows_without_timing(&single));
    // When the array really ended: sbatch --wait sees it at its next poll of the job state.
    let last = part_files
        .iter()
        .filter_map(|p| std::fs::metadata(p).and_then(|m| m.modified()).ok())
        .max()
        .and_then(|m| m.duration_since(submitted).ok())
        .map_or(f64::NAN, |d| d.as_secs_f64());
    eprintln!(
        "slurm: 4-task array sweep of 8 jobs: last part written {last:.2} s after sbatch, \
         sbatch --wait returned after {wall:.2} s, merge {merge_s:.3} s"
    );

    // Task 2 killed after its first row: the merge names the lost row; the task's shard
    // resubmitted alone (SHARD=3/4 sbatch --array=2) computes only that row.
    let p2 = &part_files[2];
    let first = std::fs::read_to_string(p2)
        .expect("part 2")
        .lines()
        .next()
        .expect("a row")
        .to_string();
    std::fs::write(p2, format!("{first}\n")).expect("cut part 2");
    let (code, _, err) = merge();
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("missing 1 of 8 rows (job indices 5)"), "{err}");
    // A one-task array without the shard is refused (it would run the whole grid).
    let o = sbatch(&d, &name, &["--array=2"], &env);
    assert!(!o.status.success(), "{}", text(&o));
    let job = String::from_utf8_lossy(&o.stdout).trim().to_string();
    let log = std::fs::read_to_string(d.join(format!("slurm-{job}_2.out"))).unwrap_or_default();
    assert!(log.contains("one-task array"), "{log}\n{}", diagnostics(&d));
    let o = sbatch(
        &d,
        &name,
        &["--array=2"],
        &[env[0], env[1], env[2], ("SHARD", "3/4")],
    );
    assert!(o.status.success(), "{}\n{}", text(&o), diagnostics(&d));
    let job = String::from_utf8_lossy(&o.stdout).trim().to_string();
    let log = std::fs::read_to_string(d.join(format!("slurm-{job}_2.out"))).unwrap_or_default();
    assert!(
        log.contains("kept 1, dropped 0 (stale or foreign), computed 1"),
        "{log}"
    );
    let (code, _, err) = merge();
    assert_eq!(code, 0, "{err}");
    assert_eq!(common::rows_without_timing(&merged), rows);
    let _ = std::fs::remove_dir_all(&d);
}
