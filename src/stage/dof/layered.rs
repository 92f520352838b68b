//! `dof.kind = "layered"` through the [`Method`] interface: the layer plan grown far to
//! near, the fixed layered convolution and compositing, the same layers in f64, one
//! cycle-model token per layer, the cost and the coefficient ROM.

use super::method::{Method, half_size_error, n2};
use super::{
    DepthImage, Exec, LayerPlan, LayerWork, LensMap, STRIP_ROWS, layer_work, layered_f64,
    layered_fixed_exec, overflow_signal, overflow_signal_in, plan_layers_in,
};
use crate::config::DofKernel;
use crate::error::{Error, Result};
use crate::stage::accumulate::Frame;
use crate::stage::{Cost, Cx, Facts, MemImage, TokenKind, Tokens};

/// The layered method.
pub struct Layered;

impl Method for Layered {
    type Plan = LayerPlan;

    fn fixed(
        &self,
        cx: &Cx,
        frame: &Frame,
        lens: &LensMap,
    ) -> Result<(LayerPlan, Vec<u32>, Facts)> {
        let hw = cx.hw;
        let p = &hw.dof;
        let frame_fmt = hw.accumulate.frame.format;
        let mut plan = plan_layers_in(&frame.depth, &frame.coverage, n2(cx), lens, p, cx.pool)
            .map_err(|msg| half_size_error(cx, msg))?;
        let img = DepthImage::of_frame(frame, &frame.acc, n2(cx));
        let (out, work, skipped) = layered_fixed_exec(
            &img,
            &plan,
            p,
            frame_fmt,
            Exec::Strips(STRIP_ROWS),
            |_| {},
            cx.pool,
        )
        .map_err(|(signal, bits)| Error::Overflow {
            signal,
            format: format!("UQ{bits}.0"),
            value: 1i128 << bits,
            min: 0,
            max: ((1u128 << bits.min(63)) - 1) as i64,
        })?;
        let mut facts = Facts {
            work: vec![
                ("layers", plan.layers.len() as u64),
                ("pixels", frame.acc.len() as u64),
                ("macs", work.macs),
                ("divides", work.divides),
                ("composites", work.composites),
                ("passthrough", work.passthrough),
            ],
            signals: vec![
                overflow_signal("dof.line", p.line_bits, work.line_overflows),
                overflow_signal("dof.acc", p.acc_bits, work.acc_overflows),
                overflow_signal_in("dof.out", frame_fmt, work.out_overflows),
            ],
            ..Facts::default()
        };
        if p.skip_uniform_tiles {
            facts.work.push(("skipped_tiles", work.skipped_tiles));
            facts.work.push(("skipped_pixels", skipped.iter().sum()));
        }
        plan.skipped = skipped;
        facts.note("layers", &plan.layers);
        Ok((plan, out, facts))
    }

    fn float(
        &self,
        cx: &Cx,
        plan: &LayerPlan,
        frame: &Frame,
        value: &[f64],
        _: &LensMap,
    ) -> Vec<f64> {
        layered_f64(&DepthImage::of_frame(frame, value, n2(cx)), plan)
    }

    /// One token per layer: the output samples of both 1-D passes over its box (of the one
    /// 2-D pass with `dof.kernel = "disc"`). With
    /// `dof.skip_uniform_tiles` the pixels of skipped tiles produce none, and the detection
    /// scans each blurred layer's box at one pixel per clock: the first layer's scan before
    /// its passes, each next one's alongside the passes of the layer before (a second frame
    /// read port), so a layer takes the longer of its passes and the next scan.
    fn tokens(&self, cx: &Cx, plan: &LayerPlan) -> Tokens {
        let g = &cx.layout.grid;
        let layers = layer_work(plan, g.width as usize, g.height as usize);
        let items = if cx.hw.dof.skip_uniform_tiles {
            let scan = |l: &LayerWork| if l.taps > 1 { l.pixels } else { 0 };
            layers
                .iter()
                .enumerate()
                .map(|(i, l)| {
                    let own = 2 * (l.pixels - l.skipped);
                    let next = layers.get(i + 1).map_or(0, scan);
                    own.max(next) + if i == 0 { scan(l) } else { 0 }
                })
                .collect()
        } else if cx.hw.dof.kernel == DofKernel::Disc {
            // One 2-D pass: one output per box pixel (an identity layer passes its box).
            layers.iter().map(|l| l.pixels).collect()
        } else {
            layers.iter().map(|l| 2 * l.pixels).collect()
        };
        Tokens {
            kind: TokenKind::Layer,
            item: "pass outputs",
            items,
            port_bits: vec![],
        }
    }

    fn cost(&self, cx: &Cx, plan: &LayerPlan, lens: &LensMap) -> Cost {
        let g = &cx.layout.grid;
        super::cost(
            plan,
            &cx.hw.dof,
            g.width as u64,
            g.height as u64,
            cx.hw.accumulate.frame.format.total_bits(),
            n2(cx),
            lens,
        )
    }

    fn memories(&self, cx: &Cx, plan: &LayerPlan, lens: &LensMap) -> Vec<MemImage> {
        let mut m = vec![super::coefficient_image(plan, &cx.hw.dof)];
        m.extend(super::sigma_rom_image(lens));
        m
    }
}
