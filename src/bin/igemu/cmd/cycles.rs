//! `igemu cycles`: cycle-count a frame on the scene's real workload, optionally writing a
//! VCD trace of the stage states and FIFO occupancy (streamed to a temporary file renamed
//! over `--vcd` at the end).

use crate::args::{SceneArgs, arg_error};
use crate::guard::Inputs;
use crate::out::outln;
use crate::print::print_cycles;
use clap::Args;
use igemu::error::Error;
use igemu::pipeline;
use igemu::stage::RunOptions;
use std::process::ExitCode;

#[derive(Args)]
pub struct CyclesArgs {
    #[command(flatten)]
    pub s: SceneArgs,
    /// Clock frequency in MHz (default: the hardware file's cycles.clock_mhz).
    #[arg(long, allow_negative_numbers = true)]
    pub clock_mhz: Option<f64>,
    /// Write a VCD trace of stage states and FIFO occupancy (for GTKWave).
    #[arg(long)]
    pub vcd: Option<String>,
    /// Print the cycle report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Use the latency and ii measured from the HDL models under Verilator (igemu hdl timing) for the stages that have one.
    #[arg(long)]
    pub timing_from_rtl: bool,
    #[command(flatten)]
    pub dirs: crate::args::HdlDirs,
}

/// Runs `igemu cycles`; returns the exit code.
pub fn run(a: CyclesArgs) -> Result<ExitCode, Error> {
    use igemu::cycles::{self, vcd::VcdWriter};
    if let Some(p) = &a.vcd {
        Inputs::of(&a.s).check("--vcd", p)?;
    }
    let scene = a.s.scene()?;
    let mut hw = a.s.hw()?;
    if let Some(mhz) = a.clock_mhz {
        igemu::config::check_clock(mhz).map_err(|m| arg_error("--clock-mhz", m))?;
        hw.cycles.clock_mhz = mhz;
    }
    let rtl = if a.timing_from_rtl {
        let (c, line) = super::hdl_timing::rtl_cycles(&a.s, &a.dirs, &hw)?;
        hw.cycles = c;
        Some(line)
    } else {
        None
    };
    let r = pipeline::render(&scene, &hw, a.s.opts(RunOptions::FAST))?;
    let mut c = r.report.cycles.clone();
    if let Some(path) = &a.vcd {
        let io = |e: std::io::Error| Error::Io {
            path: path.clone(),
            source: e,
        };
        let file = igemu::output::AtomicFile::create(path)?;
        let mut w = VcdWriter::new(file, &r.workload, hw.cycles.clock_mhz).map_err(io)?;
        let t = std::time::Instant::now();
        let sim = cycles::simulate(
            &r.workload,
            Some(&mut |t, st: &[cycles::State], occ: &[u32]| w.cycle(t, st, occ)),
        );
        let wall = t.elapsed().as_secs_f64();
        // The same frame (the comparison with the other schedule is kept).
        let schedules = c.schedules.take();
        c = cycles::report(
            &r.workload,
            r.plan.order(),
            hw.cycles.clock_mhz,
            scene.display.refresh_hz,
            c.cost.clone(),
            &sim,
            wall,
            (&r.workload, &sim),
        );
        c.schedules = schedules;
        w.finish(c.total_cycles).map_err(io)?.commit()?;
    }
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&c).expect("serialisable")
        );
    } else {
        outln!(
            "igemu {} cycles | scene `{}` {}x{} | hardware `{}`",
            r.report.igemu_version,
            r.report.scene.name,
            r.report.scene.width,
            r.report.scene.height,
            r.report.hardware.name
        );
        if let Some(l) = &rtl {
            outln!("{l}");
        }
        print_cycles(&c)?;
        if let Some(p) = &a.vcd {
            outln!("wrote {p}");
        }
    }
    Ok(ExitCode::SUCCESS)
}
