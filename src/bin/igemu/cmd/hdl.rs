//! `igemu hdl vectors`: write a stage's HDL vectors, ROM files and `params.vh`, and with
//! `--run` run its self-checking testbench under Icarus Verilog or Verilator (with
//! `--exhaustive`, the log adder's full pair space). On a colour render `--channel` picks
//! the channel whose lane the vectors come from (R by default).

use crate::args::{HdlDirs, SceneArgs, SimArg, StageArg, arg_error};
use crate::guard::Inputs;
use crate::out::outln;
use clap::{Args, Subcommand, ValueEnum};
use igemu::config::HwConfig;
use igemu::error::Error;
use igemu::hdl::verilator::Sim;
use igemu::hdl::{self, Bench, Verdict, exhaustive};
use igemu::scene::Scene;
use igemu::stage_id::StageId;
use std::path::Path;
use std::process::ExitCode;

#[derive(Subcommand)]
pub enum HdlCmd {
    /// Write a stage's vectors (scene taps, exhaustive, random), ROM files and params.vh to a directory.
    Vectors(HdlVectorsArgs),
    /// Measure each HDL model's latency and ii under Verilator (full rate, injected stalls) against the hardware's [cycles.*]; exit 1 where they disagree.
    Timing(super::hdl_timing::HdlTimingArgs),
}

#[derive(Args)]
pub struct HdlVectorsArgs {
    /// Stage with an HDL model (logdomain: log-add hardware; setup: the edge stepper; dof: a thin-lens scene).
    #[arg(long, value_enum)]
    pub stage: StageArg,
    #[command(flatten)]
    pub s: SceneArgs,
    /// Output directory.
    #[arg(long)]
    pub out: String,
    /// Also run the testbench (under --sim; exit 1 when it fails).
    #[arg(long)]
    pub run: bool,
    /// Simulator for --run (Verilator builds cached in CACHE/hdl-verilator, see --cache-dir).
    #[arg(long, value_enum, default_value_t = SimArg::Icarus)]
    pub sim: SimArg,
    /// With --run, stage logdomain: the full pair space (tb_log_adder_exhaustive, one
    /// signature per row); a failing row is then run pair by pair to name the pair.
    #[arg(long, requires = "run")]
    pub exhaustive: bool,
    /// A colour render's channel: the vectors of its lane, with its word widths (default r; refused on a grey render).
    #[arg(long, value_enum)]
    pub channel: Option<ChannelArg>,
    #[command(flatten)]
    pub dirs: HdlDirs,
}

/// `--channel`: a colour render's channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ChannelArg {
    /// Red (channel 0).
    R,
    /// Green (channel 1).
    G,
    /// Blue (channel 2).
    B,
}

/// Runs an `hdl` subcommand.
pub fn run(c: HdlCmd) -> Result<ExitCode, Error> {
    match c {
        HdlCmd::Vectors(a) => vectors(a),
        HdlCmd::Timing(a) => super::hdl_timing::run(a),
    }
}

fn vectors(a: HdlVectorsArgs) -> Result<ExitCode, Error> {
    let scene = a.s.scene()?;
    let hw = a.s.hw()?;
    let sim = Sim::from(a.sim);
    if a.exhaustive && a.stage.0 != StageId::Logdomain {
        return Err(arg_error(
            "--exhaustive",
            "only the log adder (--stage logdomain) has an exhaustive testbench".into(),
        ));
    }
    let channels = igemu::pipeline::plan::channels(&scene, &hw);
    if let Some(c) = a.channel.filter(|_| channels == 1) {
        return Err(arg_error(
            "--channel",
            format!(
                "`--channel {}` needs a colour render: scene `{}` renders one grey channel on hardware `{}`; give a colour scene (e.g. default-colour) or per-channel widths, or leave out --channel",
                c.to_possible_value()
                    .map_or("?".into(), |v| v.get_name().to_string()),
                scene.name,
                hw.name
            ),
        ));
    }
    let channel = a.channel.map_or(0, |c| c as usize);
    // The models and the cache before any file is written: a bad --hdl-dir is refused first.
    let cache = if a.run {
        a.dirs.apply()?.join("hdl-verilator")
    } else {
        std::path::PathBuf::new()
    };
    let inputs = Inputs::of(&a.s);
    crate::guard::folder("--out", &a.out)?;
    let dir = Path::new(&a.out);
    inputs.check_in("--out", dir, ["params.vh", "vectors.hex"])?;
    let b = hdl::vectors_of_channel(a.stage.0, &scene, &hw, channel)?;
    inputs.check_in("--out", dir, b.files())?;
    b.write(dir)?;
    let src: Vec<String> = b.sources.iter().map(|(k, n)| format!("{n} {k}")).collect();
    let lane = if channels > 1 {
        format!(" | channel {}", igemu::pipeline::colour::NAMES[channel])
    } else {
        String::new()
    };
    outln!(
        "hdl vectors | stage {} (module {}) | hardware `{}`{lane} | {} vectors ({}) | {}",
        b.stage,
        b.module,
        hw.name,
        b.vectors.len(),
        src.join(", "),
        dir.display()
    );
    let params: Vec<String> = b.params.iter().map(|(k, v)| format!("{k}={v}")).collect();
    outln!("parameters: {}", params.join(" "));
    if !a.run {
        return Ok(ExitCode::SUCCESS);
    }
    if a.exhaustive {
        return run_exhaustive(sim, &b, dir, &cache, &scene, &hw, &inputs);
    }
    let tb = format!("tb_{}", b.module);
    let r = sim
        .run(&tb, b.module, dir, &cache)
        .map_err(|m| arg_error("--run", m))?;
    match r.verdict {
        Verdict::Ok(n) => {
            let rust = n as f64 / (b.model_ns.max(1) as f64 * 1e-9);
            let sim_rate = n as f64 / r.sim_s;
            outln!(
                "{}: TESTBENCH OK {n} vectors | compile {:.2} s, simulate {:.3} s = {sim_rate:.0} vectors/s | Rust model {:.3} ms = {rust:.0} vectors/s | Rust / Verilog = {:.0}x",
                sim.name(),
                r.compile_s,
                r.sim_s,
                b.model_ns as f64 * 1e-6,
                rust / sim_rate
            );
            Ok(ExitCode::SUCCESS)
        }
        Verdict::Failed(m) => {
            outln!("{}: TESTBENCH FAILED: {m}", sim.name());
            Ok(ExitCode::from(1))
        }
    }
}

/// `hdl vectors --stage logdomain --run --exhaustive`: the full pair space by row
/// signatures; a failing row is then run pair by pair with the vector testbench.
fn run_exhaustive(
    sim: Sim,
    b: &Bench,
    dir: &Path,
    cache: &Path,
    scene: &Scene,
    hw: &HwConfig,
    inputs: &Inputs,
) -> Result<ExitCode, Error> {
    let r = sim
        .run(exhaustive::TESTBENCH, b.module, dir, cache)
        .map_err(|m| arg_error("--run", m))?;
    match r.verdict {
        Verdict::Ok(n) => {
            outln!(
                "{}: {}: TESTBENCH OK {n} vectors (every pair) | compile {:.2} s, simulate {:.2} s = {:.0} vectors/s",
                sim.name(),
                exhaustive::TESTBENCH,
                r.compile_s,
                r.sim_s,
                n as f64 / r.sim_s
            );
            Ok(ExitCode::SUCCESS)
        }
        Verdict::Failed(m) => {
            outln!(
                "{}: {}: TESTBENCH FAILED: {m}",
                sim.name(),
                exhaustive::TESTBENCH
            );
            if let Some(row) = exhaustive::failed_row(&m) {
                let rb = exhaustive::row_bench(scene, hw, row)?;
                let rdir = dir.join(format!("row-{row}"));
                inputs.check_in("--out", &rdir, rb.files())?;
                rb.write(&rdir)?;
                let rr = sim
                    .run(&format!("tb_{}", rb.module), rb.module, &rdir, cache)
                    .map_err(|m| arg_error("--run", m))?;
                let v = match rr.verdict {
                    Verdict::Ok(n) => format!("TESTBENCH OK {n} vectors"),
                    Verdict::Failed(m) => format!("TESTBENCH FAILED: {m}"),
                };
                outln!("row a={row} pair by pair ({}): {v}", rdir.display());
            }
            Ok(ExitCode::from(1))
        }
    }
}
