//! Gamma LUT: every entry against the formula, monotonicity, unreachable DAC codes.

use igemu::fixed::Quant;
use igemu::stage::gamma::{GammaLut, GammaSpec};

#[test]
fn every_entry_matches_the_formula() {
    for addr in [8u32, 11, 12] {
        for dac in [8u32, 9] {
            let spec = GammaSpec::new(2.4, true, dac, Quant::RndConv);
            let lut = GammaLut::build(&spec, addr);
            let white = ((1u32 << addr) - 1) as f64;
            let max = ((1u32 << dac) - 1) as f64;
            for (c, &u) in lut.table.iter().enumerate() {
                let ideal = (c as f64 / white).powf(1.0 / 2.4) * max;
                assert!(
                    (u as f64 - ideal).abs() <= 0.5,
                    "addr {addr} dac {dac} code {c}: {u} vs {ideal}"
                );
            }
            assert!(lut.is_monotone());
            assert_eq!(lut.table[0], 0);
            assert_eq!(*lut.table.last().unwrap() as f64, max);
        }
    }
}

#[test]
fn unreachable_codes_shrink_with_wider_accumulators() {
    let spec = GammaSpec::new(2.4, true, 8, Quant::RndConv);
    let u8 = GammaLut::build(&spec, 8).unreachable_codes().len();
    let u11 = GammaLut::build(&spec, 11).unreachable_codes().len();
    let u12 = GammaLut::build(&spec, 12).unreachable_codes().len();
    eprintln!(
        "unreachable 8-bit DAC codes (gamma 2.4): 8-bit acc {u8}, 11-bit {u11}, 12-bit {u12}"
    );
    assert!(u8 > u11 && u11 >= u12);
    // A linear LUT with as many addresses as codes reaches all of them.
    assert!(
        GammaLut::build(&GammaSpec::new(2.4, false, 8, Quant::RndConv), 8)
            .unreachable_codes()
            .is_empty()
    );
}

#[test]
fn truncating_lut_differs_from_rounding_lut_by_at_most_one() {
    let r = GammaLut::build(&GammaSpec::new(2.4, true, 8, Quant::RndConv), 12);
    let t = GammaLut::build(&GammaSpec::new(2.4, true, 8, Quant::Trn), 12);
    let diffs = r.table.iter().zip(&t.table).filter(|(a, b)| a != b).count();
    assert!(diffs > 0);
    assert!(
        r.table
            .iter()
            .zip(&t.table)
            .all(|(a, b)| a >= b && a - b <= 1)
    );
}
