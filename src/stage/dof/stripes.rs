//! The default execution of the fixed layered datapath ([`Exec::Strips`]): the frame in
//! stripes of image rows, each stripe on a thread running every layer over its rows in layer
//! order (the composite's back-to-front order). A small layer then shares the threads with
//! the large ones, and a frame has one parallel region instead of one per layer. A layer's
//! part of a stripe is one of its strips ([`run_strip`]); the results do not depend on
//! where the strips start (docs/dof.md, "Strips"), so they are the same as one layer after
//! the other, and the same on any thread count.

use super::fast::Plane;
use super::fixed::{DofWork, Exec, composite, share, udiv};
use super::layers::{DepthImage, LayerPlan};
use super::scratch::Scratch;
use super::strip::{LayerCx, LayerTaps, layer_macs, run_strip};
use super::uniform::UNIFORM_TILE;
use crate::config::DofCfg;
use rayon::prelude::*;
use std::sync::Mutex;

/// A layer's box `(x0, y0, x1, y1)`, `None` when it holds no pixel.
pub(super) type LayerBox = Option<(usize, usize, usize, usize)>;

/// The work counts and per layer the pixels of skipped uniform tiles, or the overflowing
/// signal.
type Counted = Result<(DofWork, Vec<u64>), (String, u32)>;

/// Every layer of `plan` (none a disc) over its box `boxes[l]` composited into `out` and
/// `def`, in stripes of image rows at least `rows` high: the stripe is the largest strip
/// of any layer ([`Exec::Strips`]: `8 M` rows at least, a multiple of 16, so the uniform
/// tiles never straddle two). `pool` holds one scratch per thread. Returns the work counts
/// and per layer the pixels of skipped uniform tiles; `Err` names an overflowing signal.
#[allow(clippy::too_many_arguments)]
pub(super) fn run<P: Plane>(
    img: &DepthImage<u32>,
    plan: &LayerPlan,
    p: &DofCfg,
    rows: usize,
    boxes: &[LayerBox],
    pool: &[Mutex<Scratch<P>>],
    out: &mut [u64],
    def: &mut [bool],
) -> Counted {
    let (w, h) = (img.width, img.height);
    // Per blurred layer (sigma above 0) with a box: its taps and sums, and its strips' context.
    let taps: Vec<Option<LayerTaps<P>>> = (0..plan.layers.len())
        .map(|l| {
            let (x0, y0, x1, y1) = boxes[l]?;
            (plan.layers[l].m > 0)
                .then(|| LayerTaps::new(plan, l, (w, h), (x0, y0, x1 - x0, y1 - y0)))
        })
        .collect();
    let cxs: Vec<Option<LayerCx<P>>> = taps
        .iter()
        .enumerate()
        .map(|(l, t)| {
            let (x0, y0, x1, y1) = boxes[l]?;
            let boxr = (x0, y0, x1 - x0, y1 - y0);
            Some(t.as_ref()?.cx((img, plan, p), Exec::Strips(rows), l, boxr))
        })
        .collect();
    let stripe = plan
        .layers
        .iter()
        .map(|l| rows.max(8 * l.m).next_multiple_of(UNIFORM_TILE))
        .max()
        .unwrap_or(UNIFORM_TILE)
        .min(h.next_multiple_of(UNIFORM_TILE));
    let n = plan.layers.len();
    let done: Vec<Counted> = out
        .par_chunks_mut((stripe * w).max(1))
        .zip(def.par_chunks_mut((stripe * w).max(1)))
        .enumerate()
        .map(|(k, (o, d))| {
            let (s0, s1) = (k * stripe, k * stripe + o.len() / w);
            let (mut wk, mut sk) = (DofWork::default(), vec![0u64; n]);
            for (l, b) in boxes.iter().enumerate() {
                let Some((x0, y0, x1, y1)) = *b else {
                    continue;
                };
                let (lo, hi) = (s0.max(y0), s1.min(y1));
                if lo >= hi {
                    continue;
                }
                let part = (lo - s0) * w..(hi - s0) * w;
                let (o, d) = (&mut o[part.clone()], &mut d[part]);
                let boxr = (x0, y0, x1 - x0, y1 - y0);
                match &cxs[l] {
                    None => {
                        let np = passthrough(img, plan, l, boxr, (lo - y0, hi - y0), p, o, d);
                        wk.passthrough += np;
                        wk.composites += np;
                    }
                    Some(cx) => {
                        // This thread's scratch; no parallel work runs while it is held.
                        let t = rayon::current_thread_index().unwrap_or(0) % pool.len();
                        let mut s = pool[t].lock().expect("scratch");
                        let r = (lo - y0, hi - y0);
                        run_strip(cx, &mut s, r, o, d, &mut wk, &mut sk[l], None)?;
                    }
                }
            }
            Ok((wk, sk))
        })
        .collect();
    // Counts summed in stripe order (integers: the same on any thread count).
    let (mut work, mut skipped) = (DofWork::default(), vec![0u64; n]);
    for r in done {
        let (wk, sk) = r?;
        work.add(&wk);
        skipped.iter_mut().zip(&sk).for_each(|(a, b)| *a += b);
    }
    for (l, cx) in cxs.iter().enumerate() {
        if let Some(cx) = cx {
            let (_, _, bw, bh) = cx.boxr;
            work.macs += layer_macs(plan, l, (bw * bh) as u64 - skipped[l]);
        }
    }
    Ok((work, skipped))
}

/// Rows `[r0, r1)` of layer `l`'s box `(x0, y0, bw, bh)` with sigma 0 (the identity mask):
/// each pixel's colour and alpha composited straight into `out` and `def`, which start at
/// image row `y0 + r0` (whole rows of the image). Returns the pixels passed through.
#[allow(clippy::too_many_arguments)]
pub(super) fn passthrough(
    img: &DepthImage<u32>,
    plan: &LayerPlan,
    l: usize,
    (x0, y0, bw, _): (usize, usize, usize, usize),
    (r0, r1): (usize, usize),
    p: &DofCfg,
    out: &mut [u64],
    def: &mut [bool],
) -> u64 {
    let w = img.width;
    let (q, g) = (p.alpha_bits, p.guard_bits);
    let one_q = 1u128 << q;
    let mut n = 0;
    for (y, (o, d)) in out.chunks_mut(w).zip(def.chunks_mut(w)).enumerate() {
        let start = (y0 + r0 + y) * w + x0;
        let r = start..start + bw;
        let (key, cov) = (&img.key[r.clone()], &img.cov[r.clone()]);
        let (idx, value) = (&plan.index[r.clone()], &img.value[r]);
        for x in 0..bw {
            let (a, b) = share(plan, key[x], cov[x], idx[x], l, img.n2);
            if a == 0 {
                continue;
            }
            let (a, b) = (u128::from(a), u128::from(b));
            n += 1;
            // The identity mask's sums are `value * a` and `a`: the colour divide
            // `(value * a << g) / a` is exact, `value << g`.
            let col = u128::from(value[x]) << g;
            let aq = udiv(a << q, b);
            composite(&mut o[x0 + x], &mut d[x0 + x], col, aq, one_q, q, p.quant);
        }
    }
    debug_assert_eq!(out.len(), (r1 - r0) * w);
    n
}
