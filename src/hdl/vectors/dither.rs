//! The bench of the ordered dither (`hdl-models/rtl/dither_ordered.v`): an extended DAC
//! code, the pixel position and the frame's mask offset in, the dithered DAC code and its
//! saturation flag out, checked against [`ordered_code`]. The mask is the configured one,
//! Bayer 4x4 without an ordered dither configured. Vectors: scene taps, every input code at
//! every mask phase, random ones.

use super::{RANDOM, SceneTaps, TAPS, gamma_spec};
use crate::config::HwConfig;
use crate::error::Result;
use crate::hdl::bench::{Bench, Rng};
use crate::stage::dither::{Mask, ordered_code};
use crate::stage::gamma::extended_lut;
use std::hint::black_box;
use std::time::Instant;

/// Fills `b` with the ordered dither's parameters, mask ROM and vectors.
pub(super) fn bench(b: &mut Bench, hw: &HwConfig, src: &SceneTaps, rng: &mut Rng) -> Result<()> {
    let scene = src.scene;
    let fmt = hw.accumulate.frame.format;
    let (frac, int_bits) = (fmt.frac_bits, fmt.int_bits);
    // The configured mask; without an ordered dither configured, Bayer 4x4.
    let cfg = &hw.dither;
    let mask = Mask::of(cfg).unwrap_or_else(|| Mask::bayer(4));
    let s = cfg.frac_bits;
    let dac = hw.gamma.dac_bits;
    let omax = (1u32 << dac) - 1;
    let xb = dac + s;
    let log_n = mask.n.trailing_zeros();
    b.params = vec![
        ("X_BITS".into(), xb as i64),
        ("S".into(), s as i64),
        ("LOG_N".into(), log_n as i64),
        ("O_BITS".into(), dac as i64),
        ("OMAX".into(), omax as i64),
    ];
    b.roms = vec![(
        "dither_rom.hex".into(),
        mask.rank.iter().map(|&v| v as u64).collect(),
    )];
    b.fields = vec!["x", "px", "py", "ox", "oy", "c", "sat"];
    let m = mask.n - 1;
    let one = |x: u32, px: u32, py: u32, off: (u32, u32)| {
        let c = ordered_code(x, s, mask.at(px, py, off), mask.bits);
        vec![
            x as u64,
            (px & m) as u64,
            (py & m) as u64,
            off.0 as u64,
            off.1 as u64,
            c.min(omax as u64),
            (c > omax as u64) as u64,
        ]
    };
    let lut = extended_lut(&gamma_spec(scene, hw), int_bits, s);
    let amax = lut.len() - 1;
    let taps = src.frame(TAPS)?;
    let off = mask.offset(cfg.frame);
    for t in &taps {
        let x = lut[((t.2 >> frac) as usize).min(amax)];
        b.vectors.push(one(x, t.0, t.1, off));
    }
    b.sources.push(("scene", taps.len()));
    // Exhaustive: every input code at every mask phase (offset of frame 0).
    let off0 = mask.offset(0);
    for x in 0..1u32 << xb {
        for p in 0..mask.n * mask.n {
            b.vectors.push(one(x, p % mask.n, p / mask.n, off0));
        }
    }
    b.sources
        .push(("exhaustive", (1usize << xb) * (mask.n * mask.n) as usize));
    for _ in 0..RANDOM {
        let t = rng.bits(32) as u32;
        let off = mask.offset(t);
        b.vectors.push(one(
            rng.bits(xb) as u32,
            rng.bits(log_n) as u32,
            rng.bits(log_n) as u32,
            off,
        ));
    }
    b.sources.push(("random", RANDOM));
    let t = Instant::now();
    for v in &b.vectors {
        let off = (v[3] as u32, v[4] as u32);
        black_box(one(black_box(v[0] as u32), v[1] as u32, v[2] as u32, off));
    }
    b.model_ns = t.elapsed().as_nanos() as u64;
    Ok(())
}
