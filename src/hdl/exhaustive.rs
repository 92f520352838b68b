//! The log adder's full input space: per-row signatures for
//! `hdl-models/tb/tb_log_adder_exhaustive.v` and the row vectors that name a failing pair.
//!
//! A vector file of all `2^(2 FB)` pairs (16.7 M at `FB = 12`) would be too large, so the
//! testbench iterates every pair itself and folds each row's outputs into a signature; the
//! Rust model writes the expected signature of every row (`log_sig.hex`, written with the
//! log adder's bench). A failing row is then checked pair by pair with [`row_bench`] and the
//! ordinary vector testbench.

use super::Bench;
use crate::config::CodingKind;
use crate::config::HwConfig;
use crate::error::Result;
use crate::fixed::Quant;
use crate::scene::Scene;
use crate::stage::logdomain::{LogAdder, log_code};
use crate::stage_id::StageId;

/// The exhaustive testbench of the log adder.
pub const TESTBENCH: &str = "tb_log_adder_exhaustive";

/// The signature file the exhaustive testbench reads.
pub const SIG_FILE: &str = "log_sig.hex";

/// FNV-1a offset basis (32 bit). This 32-bit fold is a checksum the Verilog testbench
/// computes too, step for step, not an id or a cache key: it stays written out here (the
/// project's ids and keys use `crate::fnv`, on the `fnv` crate).
pub const FNV_BASIS: u32 = 0x811c_9dc5;

/// One FNV-1a step over an output word: `(h ^ s) * 16777619 mod 2^32`. A bijection of `h`
/// for a fixed `s`, so a single wrong output always changes the signature.
#[inline]
pub fn fnv_step(h: u32, s: u64) -> u32 {
    (h ^ s as u32).wrapping_mul(0x0100_0193)
}

/// The signature of one row's outputs, in order.
pub fn signature(outputs: impl IntoIterator<Item = u64>) -> u32 {
    outputs.into_iter().fold(FNV_BASIS, fnv_step)
}

/// The signatures of every row `a` of `f(a, 0..2^fb)` for `a` in `0..2^fb`.
pub fn row_signatures(fb: u32, f: impl Fn(i64, i64) -> i64 + Sync) -> Vec<u64> {
    use rayon::prelude::*;
    let rows = 1i64 << fb;
    (0..rows)
        .into_par_iter()
        .map(|a| signature((0..rows).map(|c| f(a, c) as u64)) as u64)
        .collect()
}

/// Pairs the exhaustive testbench checks (`2^(2 FB)`) for the log adder's bench.
pub fn pairs(b: &Bench) -> Option<u64> {
    let fb = b.params.iter().find(|p| p.0 == "FB")?.1;
    Some(1u64 << (2 * fb))
}

/// The row of a failing exhaustive verdict (`... first row a=<n> ...`).
pub fn failed_row(msg: &str) -> Option<i64> {
    let r = msg.split("first row a=").nth(1)?;
    r.split(|c: char| !c.is_ascii_digit()).next()?.parse().ok()
}

/// The log adder's bench with its vectors replaced by row `a`: `(a, b, s(a, b))` for every
/// `b`, for the ordinary vector testbench, which names the first pair that differs.
pub fn row_bench(scene: &Scene, hw: &HwConfig, a: i64) -> Result<Bench> {
    let mut b = super::vectors(StageId::Logdomain, scene, hw)?;
    let add = log_adder_of(scene, hw)?;
    let rows = 1i64 << add.frame_bits();
    b.vectors = (0..rows)
        .map(|c| vec![a as u64, c as u64, add.add(a, c) as u64])
        .collect();
    b.sources = vec![("exhaustive row", rows as usize)];
    Ok(b)
}

/// The log adder of a log-add hardware config on the scene (as the pipeline builds it).
pub fn log_adder_of(scene: &Scene, hw: &HwConfig) -> Result<LogAdder> {
    if hw.coding.kind != CodingKind::LogAdd {
        return Err(super::bad(
            hw,
            "coding.kind",
            "the log adder needs a log-add coding (e.g. --hw log8-logadd)".into(),
        ));
    }
    if !matches!(hw.coding.quant, Quant::Rnd | Quant::RndInf) {
        return Err(super::bad(
            hw,
            "coding.quant",
            format!(
                "the RTL log_adder.v rounds the sum half up (RND; RND_INF is the same on its non-negative sums), got {}",
                hw.coding.quant
            ),
        ));
    }
    let k = &crate::stage::accumulate::kernel(hw);
    let w_min = k.w.iter().copied().filter(|&w| w > 0).min().unwrap_or(1) as u32;
    Ok(LogAdder::new(log_code(scene, hw)?, &hw.coding, k.f, w_min))
}
