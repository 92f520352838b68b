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
use crate::stage::{Cost, Cx, Facts, MemImage, RowStream, TokenKind, Tokens};

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
        let items: Vec<u64> = if cx.hw.dof.skip_uniform_tiles {
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
        let stream = stream(plan, &items, g.width, g.height, cx);
        Tokens {
            kind: TokenKind::Layer,
            item: "pass outputs",
            items,
            port_bits: vec![],
            rows: vec![],
            stream: Some(stream),
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

/// The layers' work as screen rows (the streamed schedule): each layer's pass outputs
/// `items` (one per layer with a box, as [`super::layer_work`]) spread evenly over the rows
/// of its box, the remainder on its first rows. Exact without `dof.skip_uniform_tiles`
/// (every row of a box has its width of outputs per pass); with it, a layer's skipped
/// tiles and scans are spread evenly too (an approximation: the per-row count of skipped
/// pixels is not kept). The radius is the largest margin a layer's passes reach (its
/// `M`, `2 M` with `dof.alpha_norm = "behind"`); a pixel read is the frame word, its
/// coverage (`log2(n2) + 1` bits, as the alpha planes) and its layer index.
fn stream(plan: &LayerPlan, items: &[u64], width: u32, height: u32, cx: &Cx) -> RowStream {
    let (w, h) = (width as usize, height as usize);
    let mut rows = vec![0u64; h];
    let boxes = super::layers::layer_boxes(w, h, plan).into_iter().flatten();
    for ((_, y0, _, y1), &n) in boxes.zip(items) {
        let span = (y1 - y0) as u64;
        for (k, r) in rows[y0..y1].iter_mut().enumerate() {
            *r += n / span + u64::from((k as u64) < n % span);
        }
    }
    let radius = plan
        .layers
        .iter()
        .map(|l| plan.margin(l.m))
        .max()
        .unwrap_or(0) as u32;
    let a_bits = n2(cx).next_power_of_two().trailing_zeros() + 1;
    let index_bits = (plan.layers.len().max(2) - 1).ilog2() + 1;
    RowStream {
        items: rows,
        radius,
        read_bits: cx.hw.accumulate.frame.format.total_bits() + a_bits + index_bits,
    }
}
