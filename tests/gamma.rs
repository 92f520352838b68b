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

/// The block lookup kernel against the straightforward per-value lookup it replaced (kept
/// here as the reference), on random tables, shifts and frames, and on the embedded scenes.
mod kernel {
    use igemu::pipeline::render;
    use igemu::scene::Scene;
    use igemu::stage::RunOptions;
    use igemu::stage::StageId;
    use igemu::stage::gamma::{
        BLOCK, GammaLut, GammaSpec, lookup, lookup_block, lookup_block_portable,
    };
    use proptest::prelude::*;

    /// Per value: `table[min(a >> shift, len - 1)]` (entry 0 for shifts past the word).
    fn reference<T: Copy + Into<u32>>(table: &[T], acc: &[u32], shift: u32) -> Vec<u32> {
        acc.iter()
            .map(|&a| {
                let i = a.checked_shr(shift).unwrap_or(0) as usize;
                table[i.min(table.len() - 1)].into()
            })
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        #[test]
        fn lookup_matches_the_per_value_form(
            bits in 0u32..14,
            extra in 0usize..3,
            shift in 0u32..40,
            vshift in 0u32..32,
            len in 0usize..3000,
            big: bool,
            seed: u64,
        ) {
            let mut s = seed | 1;
            let mut next = || {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                s
            };
            let n = (1usize << bits) + extra;
            let t32: Vec<u32> = (0..n).map(|_| next() as u32).collect();
            let t16: Vec<u16> = t32.iter().map(|&v| v as u16).collect();
            let len = if big { len + 2 * BLOCK + 17 } else { len };
            let acc: Vec<u32> = (0..len).map(|_| (next() as u32) >> vshift).collect();
            let want32 = reference(&t32, &acc, shift);
            let mut out = vec![1u32; len];
            lookup(&t32, &acc, shift, &mut out);
            prop_assert_eq!(&out, &want32);
            let mut out = vec![1u32; len];
            lookup_block(&t32, &acc, shift, &mut out);
            prop_assert_eq!(&out, &want32);
            // The portable build (the calls above take the AVX2 build where the CPU has it).
            let mut out = vec![1u32; len];
            lookup_block_portable(&t32, &acc, shift, &mut out);
            prop_assert_eq!(&out, &want32);
            let want16 = reference(&t16, &acc, shift);
            let mut out = vec![1u32; len];
            lookup(&t16, &acc, shift, &mut out);
            prop_assert_eq!(&out, &want16);
            let mut o16 = vec![1u16; len];
            lookup(&t16, &acc, shift, &mut o16);
            prop_assert!(o16.iter().zip(&want16).all(|(&a, &b)| u32::from(a) == b));
            let mut o16 = vec![1u16; len];
            lookup_block_portable(&t16, &acc, shift, &mut o16);
            prop_assert!(o16.iter().zip(&want16).all(|(&a, &b)| u32::from(a) == b));
        }
    }

    /// A frame of several chunks on 1, 2, 3 and 7 threads (one chunk per thread), with
    /// addresses past the table (clamped) and shifts 0 and 3: the same codes on each.
    #[test]
    fn the_same_codes_on_any_thread_count() {
        let t: Vec<u32> = (0..4096u32)
            .map(|i| i.wrapping_mul(2_654_435_761) >> 7)
            .collect();
        let acc: Vec<u32> = (0..5 * BLOCK as u32 + 333)
            .map(|i| (i.wrapping_mul(2_246_822_519) >> 17) & 0x7fff)
            .collect();
        for shift in [0, 3] {
            let want = reference(&t, &acc, shift);
            for n in [1, 2, 3, 7] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .unwrap();
                let mut out = vec![0u32; acc.len()];
                pool.install(|| lookup(&t, &acc, shift, &mut out));
                assert_eq!(out, want, "{n} threads, shift {shift}");
            }
        }
    }

    #[test]
    fn empty_table_and_short_outputs_do_not_panic() {
        let mut out = vec![5u32; 4];
        lookup::<u32, u32>(&[], &[1, 2, 3, 4], 0, &mut out);
        assert_eq!(out, vec![0; 4]);
        let mut out = vec![5u32; 2];
        lookup(&[9u32, 8], &[1, 0, 1], 0, &mut out);
        assert_eq!(out, vec![8, 9]);
    }

    /// The plain LUT of the embedded scenes (no dither), per value on the gamma stage's input.
    #[test]
    fn embedded_scenes_match_the_per_value_lookup() {
        for name in ["default", "cone-focus"] {
            let sc = Scene::embedded(name).unwrap();
            let mut h = igemu::config::HwConfig::preset("linear12").unwrap();
            h.dither.kind = igemu::config::DitherKind::None;
            let r = render(&sc, &h, RunOptions::default()).unwrap();
            let gi = r.steps.iter().position(|s| s.id == StageId::Gamma).unwrap();
            let ff = h.accumulate.frame.format;
            let lut = GammaLut::build(&GammaSpec::of(&sc, &h), ff.int_bits);
            let acc = &r.steps[gi - 1].outcome.taps.fixed.frame().frame.acc;
            let want: Vec<u32> = acc
                .iter()
                .map(|&a| lut.table[((a >> ff.frac_bits) as usize).min(lut.table.len() - 1)] as u32)
                .collect();
            assert_eq!(
                r.steps[gi].outcome.taps.fixed.pixels().codes(),
                want,
                "{name}"
            );
            let mut dac = vec![0u16; acc.len()];
            lut.apply(acc, ff.frac_bits, &mut dac);
            assert!(dac.iter().zip(&want).all(|(&a, &b)| u32::from(a) == b));
        }
    }
}
