//! The gamma stage through the contract: the LUT the plan needs (plain; with `f` extra
//! output fraction bits when a dither follows; with a reduced address when the dither runs
//! before it; the eq. 15 LUT of a log-coded frame, also with `f` extra output fraction bits
//! when a dither follows), its float reference and its stage-local comparison.

use super::{GammaLut, GammaSpec, apply_powers, lookup, powers, powers_key};
use super::{extended_lut, reduced_lut};
use crate::config::{DitherKind, HwConfig};
use crate::error::Result;
use crate::fnv::Fnv;
use crate::scene::Scene;
use crate::stage::logdomain::{LogAdder, log_gamma_linear, log_gamma_lut, log_gamma_lut_extended};
use crate::stage::taps::{FrameCoding, LutRead, PixelTap, PixelTapF, Taps};
use crate::stage::{
    Cost, Cx, Facts, LocalError, MemImage, Memory, Need, Notes, Stage, StageId, Tokens, Unit, memo,
};
use rayon::prelude::*;
use std::sync::Arc;

/// Which LUT the plan uses.
#[derive(Clone, Debug)]
pub enum Lut {
    /// Frame code to DAC code.
    Plain(Arc<GammaLut>),
    /// Frame code to DAC code with `f` fraction bits (`UQd.f`): a dither follows.
    Extended(Arc<Vec<u32>>, u32),
    /// Dithered address (`A - f` bits) to DAC code: the dither ran before.
    Reduced(Arc<GammaLut>, u32),
    /// Log frame code to DAC code (eq. 15).
    Log(Arc<Vec<u16>>, Arc<LogAdder>),
    /// Log frame code to DAC code with `f` fraction bits (eq. 15, `UQd.f`): a dither follows.
    LogExtended(Arc<Vec<u32>>, Arc<LogAdder>, u32),
}

/// The gamma stage.
pub struct Gamma;

/// The LUT's codes: a plane, or left to the ordered dither after it to look up.
enum Codes {
    Plane(Vec<u32>),
    Deferred(LutRead),
}

/// The memo key of a LUT's contents: what they are made from (its kind, the exponent, the
/// DAC quantiser, the address bits and the extra fraction or dropped address bits `f`), so
/// a run of frames builds its ROM once.
fn lut_key(kind: &str, spec: &GammaSpec, acc_bits: u32, f: u32) -> u64 {
    Fnv::new()
        .str("gamma lut")
        .str(kind)
        .u64(spec.exponent.to_bits())
        .str(&format!("{:?}", spec.dac))
        .u64(u64::from(acc_bits))
        .u64(u64::from(f))
        .finish()
}

/// The key of an eq. 15 LUT (log-coded frame input) of `kind` with `f` extra output bits.
fn log_lut_key(kind: &str, spec: &GammaSpec, add: &LogAdder, f: u32) -> u64 {
    Fnv::new()
        .u64(lut_key(kind, spec, 0, f))
        .str(&format!("{:?}", add.code))
        .u64(u64::from(add.fa))
        .u64(add.off as u64)
        .u64(add.max as u64)
        .finish()
}

fn frame_bits(hw: &HwConfig) -> (u32, u32) {
    let f = hw.accumulate.frame.format;
    (f.int_bits, f.frac_bits)
}

impl Stage for Gamma {
    type Fixed = Lut;

    fn id(&self) -> StageId {
        StageId::Gamma
    }

    fn plan(&self, scene: &Scene, hw: &HwConfig) -> Result<Need> {
        let g = hw.gamma.gamma.unwrap_or(scene.display.gamma);
        Ok(Need::yes(if hw.gamma.correction {
            format!(
                "the frame drives the {}-bit DAC through a LUT correcting gamma {g}",
                hw.gamma.dac_bits
            )
        } else {
            format!(
                "the frame drives the {}-bit DAC through a linear LUT (gamma.correction = false)",
                hw.gamma.dac_bits
            )
        }))
    }

    fn key(&self, cx: &Cx) -> serde_json::Value {
        // The dither's section matters only when the plan runs it (it shapes the LUT).
        let dither = cx.layout.has(StageId::Dither);
        serde_json::json!({
            "gamma": cx.hw.section("gamma"),
            "dither": dither.then(|| cx.hw.section("dither")),
            "display_gamma": cx.scene.display.gamma,
            "dof": cx.layout.has(StageId::Dof),
        })
    }

    fn fixed(&self, cx: &Cx, taps: &mut Taps) -> Result<(Lut, Facts)> {
        let hw = cx.hw;
        let spec = GammaSpec::of(cx.scene, hw);
        let (acc_bits, frac) = frame_bits(hw);
        let dac_max = spec.dac.format.max_code() as u32;
        let mut facts = Facts::default();
        let dither_after = cx.layout.next(StageId::Gamma) == Some(StageId::Dither);
        let dither_before = cx.layout.has(StageId::Dither) && !dither_after;
        // An ordered dither right after the LUT looks the codes up itself, row by row in its
        // own pass (`PixelTap::deferred`): the LUT's plane never goes to memory.
        let fuse = dither_after && !matches!(hw.dither.kind, DitherKind::FloydSteinberg);
        let frame_tap = taps.fixed.frame.clone();
        let plane = |table: &Arc<Vec<u32>>, shift: u32| -> Codes {
            match frame_tap.as_ref().filter(|_| fuse) {
                Some(frame) => Codes::Deferred(LutRead {
                    frame: frame.clone(),
                    table: table.clone(),
                    shift,
                }),
                None => {
                    let acc = &taps.fixed.frame().frame.acc;
                    let mut codes = cx.pool.scratch(acc.len(), 0u32);
                    lookup(table, acc, shift, &mut codes);
                    Codes::Plane(codes)
                }
            }
        };
        let (lut, codes, px_frac): (Lut, Codes, u32) = if dither_before {
            let f = hw.dither.frac_bits;
            let lut = memo(cx.memo, lut_key("reduced", &spec, acc_bits, f), || {
                reduced_lut(&spec, acc_bits, f)
            });
            let addr = taps.fixed.pixels().codes();
            let mut codes = cx.pool.scratch(addr.len(), 0u32);
            lookup(&lut.table, addr, 0, &mut codes);
            facts.note("monotone", lut.is_monotone());
            (Lut::Reduced(lut, f), Codes::Plane(codes), 0)
        } else {
            let frame = taps.fixed.frame();
            let acc = &frame.frame.acc;
            match &frame.coding {
                FrameCoding::Log(add) if dither_after => {
                    let f = hw.dither.frac_bits;
                    let lut = memo(cx.memo, log_lut_key("log extended", &spec, add, f), || {
                        log_gamma_lut_extended(add, &spec, f)
                    });
                    let codes = plane(&lut, 0);
                    facts.note("monotone", lut.windows(2).all(|w| w[0] <= w[1]));
                    facts.note("log_input_eq15", true);
                    facts.note("output_format", format!("UQ{}.{f}", hw.gamma.dac_bits));
                    (Lut::LogExtended(lut, add.clone(), f), codes, f)
                }
                FrameCoding::Log(add) => {
                    let lut = memo(cx.memo, log_lut_key("log", &spec, add, 0), || {
                        log_gamma_lut(add, &spec)
                    });
                    let mut codes = cx.pool.scratch(acc.len(), 0u32);
                    lookup(&lut, acc, 0, &mut codes);
                    facts.note("monotone", lut.windows(2).all(|w| w[0] <= w[1]));
                    facts.note("log_input_eq15", true);
                    (Lut::Log(lut, add.clone()), Codes::Plane(codes), 0)
                }
                FrameCoding::Linear if dither_after => {
                    let f = hw.dither.frac_bits;
                    let lut = memo(cx.memo, lut_key("extended", &spec, acc_bits, f), || {
                        extended_lut(&spec, acc_bits, f)
                    });
                    let codes = plane(&lut, frac);
                    facts.note("monotone", lut.windows(2).all(|w| w[0] <= w[1]));
                    facts.note("output_format", format!("UQ{}.{f}", hw.gamma.dac_bits));
                    (Lut::Extended(lut, f), codes, f)
                }
                FrameCoding::Linear => {
                    let lut = memo(cx.memo, lut_key("plain", &spec, acc_bits, 0), || {
                        GammaLut::build(&spec, acc_bits)
                    });
                    let mut codes = cx.pool.scratch(acc.len(), 0u32);
                    lut.apply_u32(acc, frac, &mut codes);
                    facts.note("monotone", lut.is_monotone());
                    let unreachable = lut.unreachable_codes();
                    facts.note("unreachable_dac_codes", unreachable.len() as u64);
                    facts.note(
                        "first_unreachable",
                        unreachable.iter().take(16).collect::<Vec<_>>(),
                    );
                    (Lut::Plain(lut), Codes::Plane(codes), 0)
                }
            }
        };
        let entries = match &lut {
            Lut::Plain(l) | Lut::Reduced(l, _) => l.table.len(),
            Lut::Extended(t, _) | Lut::LogExtended(t, _, _) => t.len(),
            Lut::Log(t, _) => t.len(),
        };
        let lookups = match &codes {
            Codes::Plane(c) => c.len(),
            Codes::Deferred(l) => {
                facts.note("lookup", "in the dither's pass, row by row (fused)");
                l.acc().len()
            }
        };
        facts.work = vec![("lookups", lookups as u64), ("lut_entries", entries as u64)];
        taps.fixed.pixels = Some(Arc::new(match codes {
            Codes::Plane(c) => PixelTap::new(c, px_frac, dac_max),
            Codes::Deferred(l) => PixelTap::deferred(l, px_frac, dac_max),
        }));
        Ok((lut, facts))
    }

    fn float(&self, cx: &Cx, lut: &Lut, taps: &mut Taps, _: &mut Notes) -> Result<()> {
        let hw = cx.hw;
        let spec = GammaSpec::of(cx.scene, hw);
        let out = match lut {
            Lut::Reduced(..) => {
                let PixelTapF::Codes(addr) = taps.float.pixels() else {
                    unreachable!("the dither writes addresses before the LUT")
                };
                let (acc_bits, _) = frame_bits(hw);
                let white = ((1u64 << acc_bits) - 1) as f64;
                let f = hw.dither.frac_bits;
                PixelTapF::Codes(
                    addr.par_iter()
                        .map(|&a| spec.code((((a as u64) << f) as f64 / white).min(1.0)) as u32)
                        .collect(),
                )
            }
            _ => {
                let frame_ref = taps.float.frame();
                let key = powers_key(taps.float.frame_key(cx.input_key), &spec);
                let p = memo(cx.memo, key, || powers(frame_ref, hw, &spec));
                if let Lut::Extended(..) | Lut::LogExtended(..) = lut {
                    PixelTapF::Values(p.par_iter().map(|&v| spec.scale(v)).collect())
                } else {
                    let mut dac = vec![0u16; p.len()];
                    apply_powers(&spec, &p, &mut dac);
                    PixelTapF::Codes(dac.into_iter().map(u32::from).collect())
                }
            }
        };
        taps.float.pixels = Some(Arc::new(out));
        Ok(())
    }

    /// The float gamma curve of each input code against the LUT's entry for it, in output
    /// LSBs (DAC codes, or DAC codes with `f` fraction bits for the extended LUT).
    fn local(
        &self,
        cx: &Cx,
        lut: &Lut,
        input: &Taps,
        out: &Taps,
        _: &mut Notes,
    ) -> Option<LocalError> {
        let hw = cx.hw;
        let spec = GammaSpec::of(cx.scene, hw);
        let (acc_bits, frac) = frame_bits(hw);
        let white = ((1u64 << acc_bits) - 1) as f64;
        let codes = out.fixed.pixels().codes();
        let mut e = LocalError::default();
        match lut {
            Lut::Reduced(_, f) => {
                for (&a, &c) in input.fixed.pixels().codes().iter().zip(codes) {
                    e.add(
                        c as f64,
                        spec.ideal((((a as u64) << f) as f64 / white).min(1.0)),
                    );
                }
            }
            Lut::Log(_, add) => {
                for (&c, &d) in input.fixed.frame().frame.acc.iter().zip(codes) {
                    e.add(d as f64, spec.ideal(log_gamma_linear(add, c as i64)));
                }
            }
            Lut::LogExtended(_, add, f) => {
                let scale = (1u64 << f) as f64;
                for (&c, &v) in input.fixed.frame().frame.acc.iter().zip(codes) {
                    e.add(
                        v as f64,
                        spec.ideal(log_gamma_linear(add, c as i64)) * scale,
                    );
                }
            }
            Lut::Extended(_, f) => {
                for (&a, &v) in input.fixed.frame().frame.acc.iter().zip(codes) {
                    let ideal = spec.ideal((a >> frac) as f64 / white);
                    e.add(v as f64, ideal * (1u64 << f) as f64);
                }
            }
            Lut::Plain(_) => {
                for (&a, &d) in input.fixed.frame().frame.acc.iter().zip(codes) {
                    e.add(d as f64, spec.ideal((a >> frac) as f64 / white));
                }
            }
        }
        Some(e.finish())
    }

    /// One token per binned tile (the pixels of the region in it); after depth of field,
    /// one per screen row (the layers blur and composite over the whole screen).
    fn tokens(&self, cx: &Cx, _: &Lut) -> Option<Tokens> {
        let (kind, items) = cx.layout.pixel_tokens(cx.layout.has(StageId::Dof));
        Some(Tokens {
            kind,
            item: "pixels",
            items,
            port_bits: vec![],
            rows: vec![],
            stream: None,
        })
    }

    fn cost(&self, cx: &Cx, lut: &Lut) -> Cost {
        let dac_bits = cx.hw.gamma.dac_bits;
        let (acc_bits, _) = frame_bits(cx.hw);
        match lut {
            Lut::Plain(l) => l.cost(ROM),
            Lut::Reduced(l, _) => l.cost(ROM_REDUCED),
            Lut::Extended(t, f) => Cost::new(
                vec![Memory::rom(ROM_EXTENDED, t.len() as u64, dac_bits + f)],
                vec![Unit::adder("LUT address", 1, acc_bits)],
                vec![],
            ),
            Lut::Log(t, add) => Cost::new(
                vec![Memory::rom(ROM_LOG, t.len() as u64, dac_bits)],
                vec![Unit::adder("LUT address", 1, add.frame_bits())],
                vec![],
            ),
            Lut::LogExtended(t, add, f) => Cost::new(
                vec![Memory::rom(ROM_LOG_EXTENDED, t.len() as u64, dac_bits + f)],
                vec![Unit::adder("LUT address", 1, add.frame_bits())],
                vec![],
            ),
        }
    }

    fn memories(&self, cx: &Cx, lut: &Lut, _: &Taps) -> Vec<MemImage> {
        let dac_bits = cx.hw.gamma.dac_bits;
        vec![match lut {
            Lut::Plain(l) => MemImage::table(ROM, dac_bits, Arc::new(l.table.clone())),
            Lut::Reduced(l, _) => MemImage::table(ROM_REDUCED, dac_bits, Arc::new(l.table.clone())),
            Lut::Extended(t, f) => MemImage::table(ROM_EXTENDED, dac_bits + f, t.clone()),
            Lut::Log(t, _) => MemImage::table(ROM_LOG, dac_bits, t.clone()),
            Lut::LogExtended(t, _, f) => MemImage::table(ROM_LOG_EXTENDED, dac_bits + f, t.clone()),
        }]
    }
}

/// The plain gamma ROM.
pub const ROM: &str = "gamma ROM";
/// The gamma ROM with extra output fraction bits (a dither follows).
pub const ROM_EXTENDED: &str = "gamma ROM (extended output)";
/// The gamma ROM with a reduced address (the dither runs before).
pub const ROM_REDUCED: &str = "gamma ROM (reduced address)";
/// The eq. 15 gamma ROM of a log-coded frame.
pub const ROM_LOG: &str = "gamma ROM (eq. 15, log input)";
/// The eq. 15 gamma ROM with extra output fraction bits (a dither follows).
pub const ROM_LOG_EXTENDED: &str = "gamma ROM (eq. 15, log input, extended output)";
