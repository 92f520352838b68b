//! The simulator checks of the HDL tests: a skip line when a simulator is missing, which
//! fails the test under `IGEMU_REQUIRE_HDL=1`, and the Verilator build cache.

use igemu::hdl;
use igemu::hdl::verilator::Sim;
use std::path::PathBuf;

/// The environment variable that turns every skip into a failure.
pub const REQUIRE: &str = "IGEMU_REQUIRE_HDL";

/// Whether the simulators are required (`IGEMU_REQUIRE_HDL=1`).
pub fn required() -> bool {
    std::env::var(REQUIRE).is_ok_and(|v| v == "1")
}

/// A test part that cannot run: prints its skip line, or fails the test when `require`.
pub fn skip_or_fail(line: &str, require: bool) {
    if require {
        panic!("{line}; {REQUIRE}=1 requires it: install the simulators or unset {REQUIRE}");
    }
    println!("{line}");
}

/// A skip of the running test (fails it under `IGEMU_REQUIRE_HDL=1`).
pub fn skip(line: &str) {
    skip_or_fail(line, required());
}

/// Whether Icarus Verilog is installed; prints the skip line when it is not.
pub fn icarus(test: &str) -> bool {
    if hdl::available("iverilog") && hdl::available("vvp") {
        return true;
    }
    skip(&format!(
        "SKIP {test}: iverilog/vvp not installed (apt-get install -y iverilog); HDL co-simulation not run"
    ));
    false
}

/// Whether Verilator is installed; prints the skip line when it is not.
pub fn verilator(test: &str) -> bool {
    if Sim::Verilator.available() {
        return true;
    }
    skip(&format!(
        "SKIP {test} under Verilator: verilator (with make, g++) not installed (apt-get install -y verilator make g++); Verilator co-simulation not run"
    ));
    false
}

/// Verilator builds, shared by all tests and kept between runs (keyed by the testbench,
/// module and params.vh).
pub fn verilator_cache() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("hdl-verilator")
}
