//! Verilator runs of the self-checking testbenches, beside Icarus Verilog.
//!
//! `verilator --binary` (`--cc --exe --main --timing`, then make) turns a testbench and its module into a C++ simulator
//! (Verilator 5: `initial` blocks with `#` delays run as coroutines). The widths come from
//! the bench's `params.vh` at build time, so one build serves every bench with the same
//! testbench, module source and `params.vh`; builds are cached under a directory the caller
//! gives, one subdirectory per input hash (`<tb>-<fnv64>`), built in a temporary directory
//! and renamed into place so that parallel runs never see a half-built simulator. The
//! simulator runs in the bench directory (it reads `vectors.hex` and the ROM files there)
//! and prints the same verdict line as under Icarus ([`super::parse_verdict`]).

use super::models::sim_files;
use super::{SimRun, Verdict};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// A Verilog simulator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sim {
    /// Icarus Verilog (`iverilog` + `vvp`).
    Icarus,
    /// Verilator 5 (`verilator --binary --timing`, C++ build).
    Verilator,
}

impl Sim {
    /// Both simulators.
    pub const ALL: [Sim; 2] = [Sim::Icarus, Sim::Verilator];

    /// The simulator's name (`icarus`, `verilator`).
    pub fn name(self) -> &'static str {
        match self {
            Sim::Icarus => "icarus",
            Sim::Verilator => "verilator",
        }
    }

    /// The simulator of a name, if known.
    pub fn parse(name: &str) -> Option<Sim> {
        Sim::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The programs the simulator needs.
    pub fn programs(self) -> &'static [&'static str] {
        match self {
            Sim::Icarus => &["iverilog", "vvp"],
            Sim::Verilator => &["verilator", "make", "g++"],
        }
    }

    /// Whether the simulator is installed.
    pub fn available(self) -> bool {
        self.programs().iter().all(|p| super::available(p))
    }

    /// Runs testbench `tb` (`hdl-models/tb/<tb>.v`) of `module` on the bench in `dir`;
    /// Verilator builds are cached under `cache`.
    pub fn run(
        self,
        tb: &str,
        module: &str,
        dir: &Path,
        cache: &Path,
    ) -> std::result::Result<SimRun, String> {
        self.run_args(tb, module, dir, cache, &[])
    }

    /// [`Sim::run`] with plusargs for the simulation (`+stall`, `+tokens`: `hs_tb.vh`).
    pub fn run_args(
        self,
        tb: &str,
        module: &str,
        dir: &Path,
        cache: &Path,
        plusargs: &[&str],
    ) -> std::result::Result<SimRun, String> {
        match self {
            Sim::Icarus => super::icarus::run_icarus_args(tb, module, dir, plusargs),
            Sim::Verilator => run_verilator_args(tb, module, dir, cache, plusargs),
        }
    }
}

/// Verilator's command-line options (besides include path, output directory and sources):
/// `--binary` without `--build`, so that the C++ build below can reuse the runtime objects.
const FLAGS: &[&str] = &[
    "--cc",
    "--exe",
    "--main",
    "--timing",
    "-Wno-fatal",
    "-Wno-lint",
    "-O3",
];

/// A Verilator build of a testbench: the simulator binary and whether it came from the cache.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Build {
    /// The simulator executable.
    pub binary: PathBuf,
    /// Whether an earlier build was reused.
    pub cached: bool,
}

fn version() -> String {
    Command::new("verilator")
        .arg("--version")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
        .unwrap_or_default()
}

/// Builds (or reuses) the Verilator simulator of testbench `tb` of `module` with the
/// `params.vh` in `dir`, under `cache/<tb>-<hash>`.
pub fn build(
    tb: &str,
    module: &str,
    dir: &Path,
    cache: &Path,
) -> std::result::Result<Build, String> {
    let f = sim_files(tb, module)?;
    let read = |p: &Path| std::fs::read(p).map_err(|e| format!("{}: {e}", p.display()));
    let mut texts = f
        .read
        .iter()
        .map(|p| read(p))
        .collect::<Result<Vec<_>, _>>()?;
    texts.push(read(&dir.join("params.vh"))?);
    let ver = version();
    texts.push(FLAGS.join(" ").into_bytes());
    texts.push(ver.clone().into_bytes());
    let h = crate::fnv::fnv1a_parts(&texts.iter().map(|t| t.as_slice()).collect::<Vec<_>>());
    let name = format!("{tb}-{h:016x}");
    let exe = format!("V{tb}");
    let done = cache.join(&name);
    if done.join(&exe).is_file() {
        return Ok(Build {
            binary: done.join(&exe),
            cached: true,
        });
    }
    static SEQ: AtomicU64 = AtomicU64::new(0);
    let tmp = cache.join(format!(
        "{name}.tmp-{}-{}",
        std::process::id(),
        SEQ.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).map_err(|e| format!("{}: {e}", tmp.display()))?;
    let fail = |what: &str, out: &std::process::Output| {
        let _ = std::fs::remove_dir_all(&tmp);
        format!(
            "{what} of {tb} failed: {}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    };
    let out = Command::new("verilator")
        .args(FLAGS)
        .arg("-I".to_string() + &dir.display().to_string())
        .arg("-I".to_string() + &f.include_dir.display().to_string())
        .arg("--top-module")
        .arg(tb)
        .arg("--Mdir")
        .arg(&tmp)
        .arg("-o")
        .arg(&exe)
        .args(&f.sources)
        .output()
        .map_err(|e| format!("verilator: {e}"))?;
    if !out.status.success() {
        return Err(fail("verilator", &out));
    }
    // The Verilator runtime (verilated*.o) is the same for every testbench built with these
    // flags: compiled once, then copied in (newer than the generated makefile, so make
    // keeps it) before the model's own C++ is compiled.
    let runtime = cache.join(format!(
        "runtime-{:016x}",
        crate::fnv::fnv1a_parts(&[FLAGS.join(" ").as_bytes(), ver.as_bytes()])
    ));
    let had_runtime = runtime_objects(&runtime)
        .into_iter()
        .map(|o| std::fs::copy(&o, tmp.join(o.file_name().unwrap_or_default())))
        .collect::<std::io::Result<Vec<_>>>()
        .is_ok_and(|v| !v.is_empty());
    let out = Command::new("make")
        .arg("-C")
        .arg(&tmp)
        .arg("-f")
        .arg(format!("V{tb}.mk"))
        .output()
        .map_err(|e| format!("make: {e}"))?;
    if !out.status.success() || !tmp.join(&exe).is_file() {
        return Err(fail("C++ build (make)", &out));
    }
    if !had_runtime {
        let rt_tmp = PathBuf::from(format!("{}.rt", tmp.display()));
        let _ = std::fs::create_dir_all(&rt_tmp);
        let ok = runtime_objects(&tmp)
            .into_iter()
            .all(|o| std::fs::copy(&o, rt_tmp.join(o.file_name().unwrap_or_default())).is_ok());
        if !ok || std::fs::rename(&rt_tmp, &runtime).is_err() {
            let _ = std::fs::remove_dir_all(&rt_tmp);
        }
    }
    // Another run may have finished the same build first; either copy will do.
    if std::fs::rename(&tmp, &done).is_err() {
        let _ = std::fs::remove_dir_all(&tmp);
        if !done.join(&exe).is_file() {
            return Err(format!(
                "verilator build: cannot move into {}",
                done.display()
            ));
        }
    }
    Ok(Build {
        binary: done.join(&exe),
        cached: false,
    })
}

/// The Verilator runtime objects (`verilated*.o`) in a build directory.
fn runtime_objects(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|d| {
            d.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| {
                    p.file_name()
                        .and_then(|n| n.to_str())
                        .is_some_and(|n| n.starts_with("verilated") && n.ends_with(".o"))
                })
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// Builds (cached under `cache`) and runs testbench `tb` of `module` on the bench in `dir`
/// under Verilator; `compile_s` is the build time (near 0 when cached).
pub fn run_verilator_tb(
    tb: &str,
    module: &str,
    dir: &Path,
    cache: &Path,
) -> std::result::Result<SimRun, String> {
    run_verilator_args(tb, module, dir, cache, &[])
}

/// [`run_verilator_tb`] with plusargs for the simulation (`+stall`, `+tokens`: `hs_tb.vh`).
pub fn run_verilator_args(
    tb: &str,
    module: &str,
    dir: &Path,
    cache: &Path,
    plusargs: &[&str],
) -> std::result::Result<SimRun, String> {
    let t = Instant::now();
    let b = build(tb, module, dir, cache)?;
    let compile_s = t.elapsed().as_secs_f64();
    let mut sim = Command::new(&b.binary);
    sim.args(plusargs).current_dir(dir);
    super::icarus::run_simulation(
        sim,
        &format!("Verilator ({})", b.binary.display()),
        compile_s,
    )
}

/// Runs the vector testbench of `module` on the bench in `dir` under Verilator.
pub fn run_verilator(
    module: &str,
    dir: &Path,
    cache: &Path,
) -> std::result::Result<Verdict, String> {
    run_verilator_tb(&format!("tb_{module}"), module, dir, cache).map(|r| r.verdict)
}
