//! The bench of the gamma LUT (`hdl-models/rtl/gamma_lut.v`): a frame code in, its DAC code
//! out, checked against [`GammaLut::apply`]. Vectors: scene taps, every LUT address (with a
//! random fraction) and random frame codes.

use super::{RANDOM, SceneTaps, TAPS, bad, gamma_spec};
use crate::config::{CodingKind, HwConfig};
use crate::error::Result;
use crate::hdl::bench::{Bench, Rng};
use crate::stage::gamma::GammaLut;
use std::hint::black_box;
use std::time::Instant;

/// Fills `b` with the gamma LUT's parameters, ROM and vectors.
pub(super) fn bench(b: &mut Bench, hw: &HwConfig, src: &SceneTaps, rng: &mut Rng) -> Result<()> {
    let scene = src.scene;
    if hw.coding.kind == CodingKind::LogAdd {
        return Err(bad(
            hw,
            "coding.kind",
            "the gamma model holds the linear frame's LUT; log-add uses the eq. 15 LUT (not modelled in HDL)".into(),
        ));
    }
    let fmt = hw.accumulate.frame.format;
    let (acc_bits, frac, int_bits) = (fmt.total_bits(), fmt.frac_bits, fmt.int_bits);
    let lut = GammaLut::build(&gamma_spec(scene, hw), int_bits);
    b.params = vec![
        ("ACC_BITS".into(), acc_bits as i64),
        ("FRAC_BITS".into(), frac as i64),
        ("DAC_BITS".into(), hw.gamma.dac_bits as i64),
    ];
    b.roms = vec![(
        "gamma_rom.hex".into(),
        lut.table.iter().map(|&v| v as u64).collect(),
    )];
    b.fields = vec!["acc", "dac"];
    let one = |a: u32| {
        let mut o = [0u16];
        lut.apply(&[a], frac, &mut o);
        vec![a as u64, o[0] as u64]
    };
    let taps = src.frame(TAPS)?;
    b.vectors.extend(taps.iter().map(|t| one(t.2)));
    b.sources.push(("scene", taps.len()));
    for a in 0..1u64 << int_bits {
        let f = rng.bits(frac) as u32;
        b.vectors.push(one(((a << frac) as u32) | f));
    }
    b.sources.push(("exhaustive", 1 << int_bits));
    for _ in 0..RANDOM {
        b.vectors.push(one(rng.bits(acc_bits) as u32));
    }
    b.sources.push(("random", RANDOM));
    let t = Instant::now();
    for v in &b.vectors {
        black_box(one(black_box(v[0] as u32)));
    }
    b.model_ns = t.elapsed().as_nanos() as u64;
    Ok(())
}
