//! The post phase with a dither: gamma LUT and dither, fixed and float, in the configured
//! placement, with their stage reports.

use super::luts::{extended_lut, reduced_lut};
use super::unit::{Dither, period_mean};
use crate::config::{DitherCfg, Placement};
use crate::stage::gamma::GammaSpec;
use crate::stage::{Cost, LocalError, StageReport, Unit, ms_since};
use rayon::prelude::*;
use std::time::Instant;

/// Outputs of the gamma + dither post phase.
pub struct DitheredPost {
    /// Fixed DAC codes.
    pub dac: Vec<u16>,
    /// Float reference DAC codes.
    pub dac_ref: Vec<u16>,
    /// Gamma and dither reports, in flow order.
    pub reports: Vec<StageReport>,
}

/// The post phase with a dither: gamma LUT and dither, fixed and float, in the configured
/// order. `acc` are frame codes with `frame_frac` fraction bits and `acc_bits` integer bits,
/// `frame_ref` the float frame in frame LSBs, `powers` its [`GammaSpec::power`]s
/// (`spec.power(frame_ref[i] / white)`, computed once per exponent by the caller).
#[allow(clippy::too_many_arguments)]
pub fn post(
    acc: &[u32],
    frame_ref: &[f64],
    size: (u32, u32),
    acc_bits: u32,
    frame_frac: u32,
    spec: &GammaSpec,
    cfg: &DitherCfg,
    stage_local: bool,
    powers: &[f64],
) -> DitheredPost {
    let (width, height) = size;
    let d = Dither::new(cfg);
    let f = cfg.frac_bits;
    let dac_bits = spec.dac.format.int_bits;
    let dac_max = spec.dac.format.max_code() as u32;
    let white = (1u64 << acc_bits) - 1;
    let mut rg = StageReport {
        name: "gamma".into(),
        ..Default::default()
    };
    let mut rd = StageReport {
        name: "dither".into(),
        ..Default::default()
    };
    let n = acc.len();
    let mut dac = vec![0u16; n];
    let mut codes = vec![0u32; n];
    let (din, s, omax) = match cfg.placement {
        Placement::AfterLut => {
            let t = Instant::now();
            let lut = extended_lut(spec, acc_bits, f);
            let amax = lut.len() - 1;
            let x: Vec<u32> = acc
                .par_iter()
                .map(|&a| lut[((a >> frame_frac) as usize).min(amax)])
                .collect();
            rg.fixed_ms = ms_since(t);
            rg.cost = Cost {
                lut_bits: lut.len() as u64 * (dac_bits + f) as u64,
                adders: vec![Unit::adder("LUT address", 1, acc_bits)],
                ..Cost::default()
            };
            rg.work.insert("lookups".into(), n as u64);
            rg.work.insert("lut_entries".into(), lut.len() as u64);
            rg.notes.insert(
                "monotone".into(),
                lut.windows(2).all(|w| w[0] <= w[1]).into(),
            );
            rg.notes
                .insert("output_format".into(), format!("UQ{dac_bits}.{f}").into());
            if stage_local {
                let mut e = LocalError::default();
                for (&a, &v) in acc.iter().zip(&x) {
                    let ideal = spec.ideal((a >> frame_frac) as f64 / white as f64);
                    e.add(v as f64, ideal * (1u64 << f) as f64);
                }
                rg.local = Some(e.finish());
            }
            (x, f, dac_max)
        }
        Placement::BeforeLut => (acc.to_vec(), f + frame_frac, (1u32 << (acc_bits - f)) - 1),
    };
    let t = Instant::now();
    let st = d.apply(&din, width, height, s, omax, &mut codes);
    rd.fixed_ms = ms_since(t);
    rd.signals.push(st);
    match cfg.placement {
        Placement::AfterLut => dac.iter_mut().zip(&codes).for_each(|(o, &c)| *o = c as u16),
        Placement::BeforeLut => {
            let t = Instant::now();
            let lut = reduced_lut(spec, acc_bits, f);
            dac.par_iter_mut()
                .zip(codes.par_iter())
                .for_each(|(o, &a)| *o = lut.table[a as usize]);
            rg.fixed_ms = ms_since(t);
            rg.cost = lut.cost();
            rg.work.insert("lookups".into(), n as u64);
            rg.work.insert("lut_entries".into(), lut.table.len() as u64);
            rg.notes.insert("monotone".into(), lut.is_monotone().into());
            if stage_local {
                let mut e = LocalError::default();
                for (&a, &c) in codes.iter().zip(&dac) {
                    e.add(
                        c as f64,
                        spec.ideal(((a << f) as f64 / white as f64).min(1.0)),
                    );
                }
                rg.local = Some(e.finish());
            }
        }
    }
    rd.work.insert("pixels".into(), n as u64);
    rd.cost = d.cost(width, s, 32 - omax.leading_zeros());
    rd.notes.insert(
        "input_format".into(),
        format!("UQ{}.{s}", 32 - omax.leading_zeros()).into(),
    );
    if let Some(m) = &d.mask {
        rd.notes.insert("mask_size".into(), m.n.into());
    }
    if stage_local {
        let scale = (1u64 << s) as f64;
        let v: Vec<f64> = din.iter().map(|&x| x as f64 / scale).collect();
        let fl = d.apply_f64(&v, width, height, omax);
        let mut e = LocalError::default();
        for (&a, &b) in codes.iter().zip(&fl) {
            e.add(a as f64, b as f64);
        }
        rd.local = Some(e.finish());
    }
    if let Some(pm) = period_mean(&d, &din, s, omax) {
        rd.notes.insert(
            "temporal_period_mean".into(),
            serde_json::to_value(pm).unwrap_or_default(),
        );
    }
    // Float reference: the ideal value, the same pattern, quantised only by the dither.
    let t = Instant::now();
    let dac_ref: Vec<u16> = match cfg.placement {
        Placement::AfterLut => {
            let v: Vec<f64> = powers.par_iter().map(|&p| spec.scale(p)).collect();
            d.apply_f64(&v, width, height, dac_max)
                .into_iter()
                .map(|c| c as u16)
                .collect()
        }
        Placement::BeforeLut => {
            let scale = (1u64 << (f + frame_frac)) as f64;
            let v: Vec<f64> = frame_ref.iter().map(|&a| a / scale).collect();
            let amax = (1u32 << (acc_bits - f)) - 1;
            d.apply_f64(&v, width, height, amax)
                .into_par_iter()
                .map(|a| spec.code(((a << f) as f64 / white as f64).min(1.0)))
                .collect()
        }
    };
    rd.float_ms = ms_since(t);
    DitheredPost {
        dac,
        dac_ref,
        reports: match cfg.placement {
            Placement::AfterLut => vec![rg, rd],
            Placement::BeforeLut => vec![rd, rg],
        },
    }
}
