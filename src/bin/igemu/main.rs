//! The `igemu` command line. `main` only maps `try_main`'s result to an exit code:
//! 0 ok, 1 a check failed, 2 bad input or error (clap's own argument errors exit 2 too).
//! A closed stdout (`igemu render --json | head -c 10`) ends the program quietly with 0.
//!
//! Files: `out.rs` (stdout: `out!`, `outln!`), `guard.rs` (an output never overwrites an
//! input), `args.rs` (argument types shared by several commands), `print.rs` (the text
//! reports), `cmd/` (one file per command: its arguments and its run).

mod out;

mod args;
mod cmd;
mod guard;
mod print;
mod with_merge;

use clap::{Parser, Subcommand};
use igemu::error::Error;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "igemu",
    version,
    about = "Emulator of fixed-point image-generator hardware, compared code by code with a float reference"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Render a scene through the fixed-point pipeline and the float reference; write the image and the report.
    Render(cmd::render::RenderArgs),
    /// Regression gate: render and exit 1 when a threshold fails.
    Check(cmd::check::CheckArgs),
    /// Word widths from contrast, Weber fraction and gamma (Kovalev & Tokarev eq. 9-11).
    Widths(cmd::widths::WidthsArgs),
    /// Depth of field of a thin lens: front and back depth, near and far limits.
    Dof(cmd::dof::DofArgs),
    /// Cycle-count a frame on the scene's real workload: bottleneck, frame rate, real-time check, cost.
    Cycles(cmd::cycles::CyclesArgs),
    /// Every frame of an animated scene ([sequence]): cycles per frame against the period, the worst frame, temporal flicker, reuse between frames; `--shard K/N` runs a block of the frames, `sequence merge` joins the parts.
    Sequence(cmd::sequence_merge::SequenceCmd),
    /// Small-object flicker: a light point and a thin line swept over 32x32 sub-pixel phases.
    Flicker(cmd::flicker::FlickerArgs),
    /// The accumulate filters side by side: ripple, step ringing, flicker, frequency response, error, cost, MACs, cycles, time.
    Filters(cmd::filters::FiltersArgs),
    /// HDL co-simulation of the Verilog models in hdl-models/ (see hdl-models/README.md).
    #[command(subcommand)]
    Hdl(cmd::hdl::HdlCmd),
    /// Hardware cost per stage: the analytic model, and with --synth yosys cell counts of the HDL models.
    Cost(cmd::cost::CostArgs),
    /// Word-width sweep: render every configuration of a grid, one JSON line each, and print the Pareto front; `sweep merge` joins the part files of a sharded sweep.
    Sweep(cmd::merge::SweepCmd),
    /// Observed min/max per signal and the narrowest format holding it; export the formats as typedefs.
    Ranges(cmd::ranges::RangesArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match try_main(cli).and_then(|code| out::flush().map(|()| code)) {
        Ok(code) => code,
        // The reader of stdout is gone: nothing more to say, as command-line tools do.
        Err(e) if out::is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            use std::io::Write;
            let _ = writeln!(std::io::stderr(), "igemu: error: {e}");
            ExitCode::from(2)
        }
    }
}

fn try_main(cli: Cli) -> Result<ExitCode, Error> {
    match cli.cmd {
        Cmd::Render(a) => cmd::render::run(a),
        Cmd::Check(a) => cmd::check::run(a),
        Cmd::Widths(a) => cmd::widths::run(a),
        Cmd::Dof(a) => cmd::dof::run(a),
        Cmd::Cycles(a) => cmd::cycles::run(a),
        Cmd::Sequence(a) => cmd::sequence_merge::run(a),
        Cmd::Flicker(a) => cmd::flicker::run(a),
        Cmd::Filters(a) => cmd::filters::run(a),
        Cmd::Hdl(c) => cmd::hdl::run(c),
        Cmd::Cost(a) => cmd::cost::run(a),
        Cmd::Sweep(a) => cmd::merge::run(a),
        Cmd::Ranges(a) => cmd::ranges::run(a),
    }
}
