//! Running the self-checking testbenches under Icarus Verilog (`iverilog` + `vvp`), and
//! what both simulators share: whether a program is installed ([`available`]), the timed
//! run of a built simulation and its verdict ([`SimRun`]).

use super::bench::{Verdict, parse_verdict};
use super::models::sim_files;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// Whether a program runs (`prog -V` or `--version`).
pub fn available(prog: &str) -> bool {
    Command::new(prog)
        .arg(if prog == "iverilog" {
            "-V"
        } else {
            "--version"
        })
        .output()
        .is_ok()
}

/// A testbench run: verdict and wall times.
#[derive(Clone, Debug, PartialEq)]
pub struct SimRun {
    /// The verdict.
    pub verdict: Verdict,
    /// iverilog compile time (seconds).
    pub compile_s: f64,
    /// vvp simulation time, including reading the vector file (seconds).
    pub sim_s: f64,
    /// The simulation's standard output (the verdict and, from the vector testbenches, the
    /// `TIMING` line: [`super::timing`]).
    pub stdout: String,
}

/// Compiles and runs the testbench of `module` on the bench in `dir` under Icarus Verilog;
/// returns the verdict, or the simulator's output when there is none.
pub fn run_icarus(module: &str, dir: &Path) -> std::result::Result<Verdict, String> {
    run_icarus_timed(module, dir).map(|r| r.verdict)
}

/// [`run_icarus`] with the compile and simulation wall times.
pub fn run_icarus_timed(module: &str, dir: &Path) -> std::result::Result<SimRun, String> {
    run_icarus_tb(&format!("tb_{module}"), module, dir)
}

/// [`run_icarus_timed`] of testbench `tb` (`hdl-models/tb/<tb>.v`) of `module`.
pub fn run_icarus_tb(tb: &str, module: &str, dir: &Path) -> std::result::Result<SimRun, String> {
    run_icarus_args(tb, module, dir, &[])
}

/// [`run_icarus_tb`] with plusargs for the simulation (`+stall`, `+tokens`: `hs_tb.vh`).
pub fn run_icarus_args(
    tb: &str,
    module: &str,
    dir: &Path,
    plusargs: &[&str],
) -> std::result::Result<SimRun, String> {
    let f = sim_files(tb, module)?;
    let sim = dir.join("sim.vvp");
    let t = Instant::now();
    let c = Command::new("iverilog")
        .arg("-g2005")
        .arg("-I")
        .arg(dir)
        .arg("-I")
        .arg(&f.include_dir)
        .arg("-o")
        .arg(&sim)
        .args(&f.sources)
        .output()
        .map_err(|e| format!("iverilog: {e}"))?;
    if !c.status.success() {
        return Err(format!(
            "iverilog failed: {}",
            String::from_utf8_lossy(&c.stderr)
        ));
    }
    let compile_s = t.elapsed().as_secs_f64();
    let mut vvp = Command::new("vvp");
    // vvp runs in the bench directory (the ROM files are read from there): give it the
    // compiled simulation by a name relative to that directory.
    vvp.arg("-n").arg("sim.vvp").args(plusargs).current_dir(dir);
    run_simulation(vvp, "vvp", compile_s)
}

/// Runs a built simulation (`what` names it in errors), times it and parses its verdict.
pub(crate) fn run_simulation(
    mut cmd: Command,
    what: &str,
    compile_s: f64,
) -> std::result::Result<SimRun, String> {
    let t = Instant::now();
    let r = cmd.output().map_err(|e| format!("{what}: {e}"))?;
    let sim_s = t.elapsed().as_secs_f64();
    let out = String::from_utf8_lossy(&r.stdout).to_string();
    let verdict = parse_verdict(&out).ok_or_else(|| {
        format!(
            "no single verdict line in the {what} output: {out}{}",
            String::from_utf8_lossy(&r.stderr)
        )
    })?;
    Ok(SimRun {
        verdict,
        compile_s,
        sim_s,
        stdout: out,
    })
}
