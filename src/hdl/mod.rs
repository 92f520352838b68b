//! HDL co-simulation: test vectors from the Rust model for the Verilog models in
//! `hdl-models/rtl/`, the parameter file that carries the widths of a hardware config,
//! running the self-checking testbenches under Icarus Verilog and Verilator, parsing their
//! verdict, and yosys synthesis cell counts.
//!
//! A bench directory holds `params.vh` (`` `define``s: vector count, fields per vector and
//! the module's parameters), `vectors.hex` (one 64-bit hex word per field, `N_FIELDS`
//! words per vector: inputs then expected outputs) and the ROM files the module loads
//! with `$readmemh`. The testbench prints exactly one verdict line,
//! `TESTBENCH OK <n> vectors` or `TESTBENCH FAILED: ...`.
//!
//! Files: [`bench`](mod@bench) (the bench, its files, the verdict), [`icarus`] (Icarus runs, shared
//! simulation plumbing), [`models`] (the Verilog embedded in the binary, written out where a
//! simulator reads it, or a `--hdl-dir` copy), `vectors/` (one vector builder per stage), [`exhaustive`] (the log
//! adder's full pair space), [`verilator`], [`synth`] (yosys) [`timing`] (latency and ii
//! measured from the RTL against `[cycles.*]`) and [`correlate`] (the RTL on a run's token
//! stream against the cycle model).

use crate::stage_id::StageId;

pub mod bench;
pub mod correlate;
pub mod exhaustive;
pub mod icarus;
pub mod models;
pub mod synth;
pub mod timing;
mod vectors;
pub mod verilator;

pub use bench::{Bench, Verdict, parse_verdict};
pub use icarus::{SimRun, available, run_icarus, run_icarus_tb, run_icarus_timed};
pub use models::{Models, model_file, models_dir, use_models};
pub(crate) use vectors::bad;
pub use vectors::{vectors, vectors_of_channel};

/// Stages with an HDL model: (stage, Verilog module).
pub const MODULES: &[(StageId, &str)] = &[
    (StageId::Gamma, "gamma_lut"),
    (StageId::Accumulate, "acc_mac"),
    (StageId::Dither, "dither_ordered"),
    (StageId::Logdomain, "log_adder"),
    (StageId::Setup, "edge_stepper"),
    (StageId::Dof, "dof_row_mac"),
];

/// The Verilog module of a stage, if it has one.
pub fn module_of(id: StageId) -> Option<&'static str> {
    MODULES.iter().find(|m| m.0 == id).map(|m| m.1)
}
