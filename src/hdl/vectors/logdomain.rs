//! The bench of the log adder (`hdl-models/rtl/log_adder.v`): two log-coded frame words in,
//! their log-domain sum out, checked against [`LogAdder::add`](crate::stage::logdomain::LogAdder::add).
//! Vectors: every pair of 8-bit codes, every difference at a random larger operand (both
//! orders), scene taps and random pairs; the bench also carries the row signatures of the
//! full pair space for the exhaustive testbench ([`crate::hdl::exhaustive`]).

use super::{RANDOM, SceneTaps, TAPS};
use crate::config::HwConfig;
use crate::error::Result;
use crate::hdl::bench::{Bench, Rng};
use crate::hdl::exhaustive;
use std::hint::black_box;
use std::time::Instant;

/// Fills `b` with the log adder's parameters, ROMs and vectors.
pub(super) fn bench(b: &mut Bench, hw: &HwConfig, src: &SceneTaps, rng: &mut Rng) -> Result<()> {
    let scene = src.scene;
    let add = exhaustive::log_adder_of(scene, hw)?;
    let fb = add.frame_bits();
    let td = add.table_data_bits().max(1);
    b.params = vec![
        ("FB".into(), fb as i64),
        ("TD".into(), td as i64),
        ("TF".into(), add.tf as i64),
        ("ADDR_BITS".into(), add.addr_bits as i64),
        ("SHIFT".into(), add.shift as i64),
        ("INTERP".into(), add.interpolate as i64),
        ("MAX".into(), add.max),
    ];
    b.roms = vec![
        (
            "log_rom.hex".into(),
            add.sb.iter().map(|&v| v as u64).collect(),
        ),
        // The full pair space, for tb_log_adder_exhaustive: one signature per row.
        (
            exhaustive::SIG_FILE.into(),
            exhaustive::row_signatures(fb, |a, c| add.add(a, c)),
        ),
    ];
    b.fields = vec!["a", "b", "s"];
    let one = |a: i64, c: i64| vec![a as u64, c as u64, add.add(a, c) as u64];
    // Exhaustive over all pairs of 8-bit codes (the zero code, the smallest sums).
    let small = add.max.min(255);
    for a in 0..=small {
        for c in 0..=small {
            b.vectors.push(one(a, c));
        }
    }
    b.sources.push(("exhaustive 8-bit pairs", b.vectors.len()));
    // Every difference (every table address and the essential zero) at a random
    // larger operand, both operand orders.
    let mut n = 0;
    for d in 0..=add.max {
        let m = d + rng.bits(fb) as i64 % (add.max - d + 1);
        b.vectors.push(one(m, m - d));
        b.vectors.push(one(m - d, m));
        n += 2;
    }
    b.sources.push(("every difference", n));
    let taps = src.frame(TAPS)?;
    for w in taps.windows(2) {
        b.vectors.push(one(w[0].2 as i64, w[1].2 as i64));
    }
    b.sources.push(("scene", taps.len().saturating_sub(1)));
    for _ in 0..RANDOM {
        let a = rng.bits(fb) as i64 % (add.max + 1);
        let c = rng.bits(fb) as i64 % (add.max + 1);
        b.vectors.push(one(a, c));
    }
    b.sources.push(("random", RANDOM));
    let t = Instant::now();
    for v in &b.vectors {
        black_box(one(black_box(v[0] as i64), v[1] as i64));
    }
    b.model_ns = t.elapsed().as_nanos() as u64;
    Ok(())
}
