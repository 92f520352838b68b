//! The commands, one file each: its clap arguments and its `run`, which returns the exit
//! code (0 ok, 1 a check failed) or the error `main` reports with exit code 2.

pub mod check;
pub mod cost;
pub mod cycles;
pub mod dof;
pub mod filters;
pub mod flicker;
pub mod hdl;
pub mod hdl_timing;
pub mod merge;
pub mod ranges;
pub mod render;
pub mod sequence;
pub mod sequence_merge;
pub mod sweep;
pub mod widths;
