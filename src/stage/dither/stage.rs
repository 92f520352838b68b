//! The dither stage through the contract. After the gamma LUT (the default) it removes the
//! LUT output's `f` extra fraction bits, leaving DAC codes; before the LUT it removes `f`
//! bits of the frame code, leaving the reduced LUT's addresses. The float reference applies
//! the same pattern to the ideal value; the stage-local comparison feeds it the fixed
//! dither's own input.

use super::{Dither, Input, Run, period_mean};
use crate::config::{DitherKind, HwConfig, Placement};
use crate::error::Result;
use crate::scene::Scene;
use crate::stage::taps::{PixelTap, PixelTapF, Taps};
use crate::stage::{Cost, Cx, Facts, LocalError, MemImage, Need, Notes, Stage, StageId, Tokens};
use std::sync::Arc;

/// What the fixed model leaves: the dither, its input's fraction bits and its output's
/// largest code.
pub struct Dithered {
    d: Dither,
    s: u32,
    omax: u32,
}

/// The dither stage.
pub struct DitherStage;

impl Stage for DitherStage {
    type Fixed = Dithered;

    fn id(&self) -> StageId {
        StageId::Dither
    }

    fn plan(&self, _: &Scene, hw: &HwConfig) -> Result<Need> {
        let d = &hw.dither;
        if d.kind == DitherKind::None {
            return Ok(Need::no("dither.kind = \"none\""));
        }
        let kind = serde_json::to_value(d.kind).unwrap_or_default();
        Ok(match d.placement {
            Placement::AfterLut => Need::yes(format!(
                "dither.kind = {kind} after the gamma LUT: removes the LUT output's {} extra fraction bits",
                d.frac_bits
            )),
            Placement::BeforeLut => Need {
                before: Some(StageId::Gamma),
                ..Need::yes(format!(
                    "dither.kind = {kind} before the gamma LUT: removes {} bits of the frame code (a smaller LUT)",
                    d.frac_bits
                ))
            },
        })
    }

    fn key(&self, cx: &Cx) -> serde_json::Value {
        serde_json::json!({"dither": cx.hw.section("dither"), "dac_bits": cx.hw.gamma.dac_bits})
    }

    fn fixed(&self, cx: &Cx, taps: &mut Taps) -> Result<(Dithered, Facts)> {
        let hw = cx.hw;
        let (width, height) = (cx.layout.grid.width, cx.layout.grid.height);
        let d = Dither::new(&hw.dither);
        let f = hw.dither.frac_bits;
        let ff = hw.accumulate.frame.format;
        let (din, s, omax): (Input, u32, u32) = match hw.dither.placement {
            Placement::AfterLut => {
                let px = taps.fixed.pixels();
                // The gamma LUT left its codes unlooked-up: an ordered dither looks them up
                // row by row in its own pass (error diffusion reads them as a plane).
                let x = match (px.ready(), px.lut()) {
                    (None, Some(l)) if d.mask.is_some() => Input::Lut {
                        acc: l.acc(),
                        table: &l.table,
                        shift: l.shift,
                    },
                    _ => Input::Codes(px.codes()),
                };
                (x, px.frac, px.max)
            }
            Placement::BeforeLut => (
                Input::Codes(&taps.fixed.frame().frame.acc),
                f + ff.frac_bits,
                (1u32 << (ff.int_bits - f)) - 1,
            ),
        };
        let mut codes = cx.pool.scratch(din.len(), 0u32);
        let st = d.apply_from(din, (width, height), s, omax, &mut codes, Run::Parallel);
        let mut facts = Facts {
            work: vec![("pixels", din.len() as u64)],
            signals: vec![st],
            ..Facts::default()
        };
        facts.note(
            "input_format",
            format!("UQ{}.{s}", 32 - omax.leading_zeros()),
        );
        if let Some(m) = &d.mask {
            facts.note("mask_size", m.n);
        }
        if let Some(pm) = d
            .cfg
            .temporal
            .then(|| period_mean(&d, &din.to_codes(false), s, omax))
            .flatten()
        {
            facts.note("temporal_period_mean", pm);
        }
        taps.fixed.pixels = Some(Arc::new(PixelTap::new(codes, 0, omax)));
        Ok((Dithered { d, s, omax }, facts))
    }

    fn float(&self, cx: &Cx, x: &Dithered, taps: &mut Taps, _: &mut Notes) -> Result<()> {
        let hw = cx.hw;
        let (width, height) = (cx.layout.grid.width, cx.layout.grid.height);
        let codes = match hw.dither.placement {
            Placement::AfterLut => {
                let PixelTapF::Values(v) = taps.float.pixels() else {
                    unreachable!("the gamma LUT before a dither writes real values")
                };
                x.d.apply_f64(v, width, height, x.omax)
            }
            Placement::BeforeLut => {
                let scale = (1u64 << x.s) as f64;
                let v: Vec<f64> = taps.float.frame().iter().map(|&a| a / scale).collect();
                x.d.apply_f64(&v, width, height, x.omax)
            }
        };
        taps.float.pixels = Some(Arc::new(PixelTapF::Codes(codes)));
        Ok(())
    }

    /// The float dither fed the fixed dither's input (as reals), code by code.
    fn local(
        &self,
        cx: &Cx,
        x: &Dithered,
        input: &Taps,
        out: &Taps,
        _: &mut Notes,
    ) -> Option<LocalError> {
        let (width, height) = (cx.layout.grid.width, cx.layout.grid.height);
        let din: &[u32] = match cx.hw.dither.placement {
            Placement::AfterLut => input.fixed.pixels().codes(),
            Placement::BeforeLut => &input.fixed.frame().frame.acc,
        };
        let scale = (1u64 << x.s) as f64;
        let v: Vec<f64> = din.iter().map(|&c| c as f64 / scale).collect();
        let fl = x.d.apply_f64(&v, width, height, x.omax);
        let mut e = LocalError::default();
        for (&a, &b) in out.fixed.pixels().codes().iter().zip(&fl) {
            e.add(a as f64, b as f64);
        }
        Some(e.finish())
    }

    /// One token per pixel row after depth of field (as gamma) and for error diffusion,
    /// whose row runs left to right (each pixel waits for its left neighbour's error; the
    /// `lanes` of `[cycles.dither]` are rows in flight), else one per binned tile.
    fn tokens(&self, cx: &Cx, x: &Dithered) -> Option<Tokens> {
        let rows = cx.layout.has(StageId::Dof) || x.d.mask.is_none();
        let (kind, items) = cx.layout.pixel_tokens(rows);
        Some(Tokens {
            kind,
            item: "pixels",
            items,
            port_bits: vec![],
            rows: vec![],
            stream: None,
        })
    }

    fn cost(&self, cx: &Cx, x: &Dithered) -> Cost {
        x.d.cost(cx.layout.grid.width, x.s, 32 - x.omax.leading_zeros())
    }

    fn memories(&self, _: &Cx, x: &Dithered, _: &Taps) -> Vec<MemImage> {
        x.d.images()
    }
}
