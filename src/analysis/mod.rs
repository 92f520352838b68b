//! Analyses built on the pipeline and the formulas of the source papers: the analytic word
//! widths and depth of field ([`calc`]), the emulated validation of the widths on a ramp
//! ([`widths`]), small-object flicker ([`flicker`]), the accumulate filters' measured
//! properties ([`filters`]) and observed signal ranges with format export ([`ranges`]).

pub mod calc;
pub mod filters;
pub mod flicker;
pub mod ranges;
pub mod widths;
