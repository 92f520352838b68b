//! The `logdomain` stage: log code, potentiation LUT, Gaussian-log adder, eq. 15 LUT,
//! ramp contours, and the CLI's bad-input messages.

use igemu::fixed::Quant;
use igemu::stage::gamma::GammaSpec;
use igemu::stage::logdomain::*;

fn code(bits: u32) -> LogCode {
    LogCode { k: 100.0, bits }
}

fn adder(bits: u32, fa: u32, tf: u32, a: u32, interp: bool) -> LogAdder {
    let cfg = CodingCfg {
        kind: CodingKind::LogAdd,
        log_bits: bits,
        acc_frac_bits: fa,
        table_addr_bits: a,
        table_frac_bits: tf,
        interpolate: interp,
    };
    LogAdder::new(code(bits), &cfg, 10, 7)
}

/// Error statistics of the adder over every pair of frame codes `1..=max` (exact: log of
/// the sum of the exact values), in frame LSBs.
fn pair_stats(add: &LogAdder, step: usize) -> (f64, f64, u64) {
    let (mut max, mut sum, mut n) = (0f64, 0f64, 0u64);
    for a in (1..=add.max).step_by(step) {
        for b in (1..=add.max).step_by(step) {
            let r = add.add(a, b);
            let exact = add
                .position(add.value(a) + add.value(b))
                .min(add.max as f64);
            let e = r as f64 - exact;
            max = max.max(e.abs());
            sum += e;
            n += 1;
        }
    }
    (max, sum / n as f64, n)
}

#[test]
fn debug_adder_stats() {
    for (fa, tf) in [(0, 0), (0, 2), (2, 0), (2, 2), (4, 4)] {
        let add = adder(8, fa, tf, 8, false);
        let (max, mean, n) = pair_stats(&add, 1 + add.max as usize / 700);
        eprintln!(
            "fa {fa} tf {tf}: shift {} max {max:.3} mean {mean:+.4} n {n} sb0 {}",
            add.shift, add.sb[0]
        );
    }
}
