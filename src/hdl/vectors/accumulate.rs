//! The bench of the accumulation MAC (`hdl-models/rtl/acc_mac.v`): a filter weight times a
//! sample intensity added into a frame word with the frame's rounding and overflow modes,
//! checked against [`AccParams::mac_code`]. Vectors: scene taps (kernel weights, vertex
//! intensities, rendered frame codes), edge cases at the frame boundaries and random ones.

use super::{RANDOM, SceneTaps, TAPS};
use crate::config::HwConfig;
use crate::error::Result;
use crate::fixed::{Overflow, Quant};
use crate::hdl::bench::{Bench, Rng};
use crate::stage::StageId;
use crate::stage::accumulate::AccParams;
use crate::stage::input::QPrim;
use std::hint::black_box;
use std::time::Instant;

/// Fills `b` with the accumulation MAC's parameters and vectors.
pub(super) fn bench(b: &mut Bench, hw: &HwConfig, src: &SceneTaps, rng: &mut Rng) -> Result<()> {
    if hw.coding.kind == crate::config::CodingKind::LogAdd {
        return Err(super::bad(
            hw,
            "coding.kind",
            "the accumulate model is the linear MAC (acc_mac.v); log-add sums with the log adder, whose model is --stage logdomain".into(),
        ));
    }
    let kernel = crate::stage::accumulate::kernel(hw);
    if kernel.signed() {
        return Err(super::bad(
            hw,
            "accumulate.filter",
            "acc_mac.v takes unsigned weights; a filter with negative lobes has no bench yet"
                .into(),
        ));
    }
    let frame = hw.accumulate.frame;
    let acc_bits = frame.format.total_bits();
    let (_, input) = src.through(StageId::Input)?;
    let ch = src.channel;
    let bg = input.fixed.prims().bg;
    let i_fmt = hw.input.intensity.format;
    let ap = AccParams {
        kernel: kernel.clone(),
        i_frac: i_fmt.frac_bits,
        frame,
    };
    let quant = match frame.quant {
        Quant::Trn | Quant::TrnZero => 0,
        Quant::Rnd | Quant::RndInf => 1,
        Quant::RndZero | Quant::RndMinInf => 2,
        Quant::RndConv => 3,
    };
    let ovf = match frame.overflow {
        Overflow::Wrap => 0,
        Overflow::SatZero => 2,
        _ => 1,
    };
    let wb = 32
        - kernel
            .w
            .iter()
            .max()
            .copied()
            .unwrap_or(1)
            .unsigned_abs()
            .leading_zeros();
    let wb = wb.max(kernel.f + 1);
    let ib = i_fmt.total_bits();
    b.params = vec![
        ("W_BITS".into(), wb as i64),
        ("I_BITS".into(), ib as i64),
        ("F_BITS".into(), acc_bits as i64),
        ("SHIFT".into(), ap.product_shift() as i64),
        ("QUANT".into(), quant),
        ("OVF".into(), ovf),
    ];
    b.fields = vec!["w", "i", "acc_in", "acc_out", "ovf"];
    let one = |w: u32, i: u32, a: u32| {
        let (c, o) = ap.mac_code(a as i64, w as i32, i);
        vec![w as u64, i as u64, a as u64, c as u64, o as u64]
    };
    // Scene taps: the kernel's weights, the scene's vertex intensity codes and
    // the rendered frame codes as the running sum.
    let taps = src.frame(TAPS)?;
    let ws: Vec<u32> = kernel.w.iter().map(|&v| v as u32).collect();
    let is: Vec<u32> = input
        .fixed
        .prims()
        .q
        .iter()
        .flat_map(|p| match p {
            QPrim::Triangle(v) => vec![v[0].i[ch], v[1].i[ch], v[2].i[ch]],
            QPrim::Line { a, b, .. } => vec![a.i[ch], b.i[ch]],
            QPrim::Point { v, .. } => vec![v.i[ch]],
        })
        .map(|i| i.max(0) as u32)
        .chain(std::iter::once(bg[ch]))
        .collect();
    for (k, t) in taps.iter().enumerate() {
        let w = ws[k % ws.len()];
        let i = is[(k / ws.len() + k) % is.len()];
        b.vectors.push(one(w, i, t.2));
    }
    b.sources.push(("scene", taps.len()));
    // Edge cases: full weight x full intensity onto every frame boundary.
    let wmax = (1u64 << wb) - 1;
    let imax = (1u64 << ib) - 1;
    let amax = (1u64 << acc_bits) - 1;
    let mut edge = 0;
    for w in [0, 1, 1u64 << kernel.f, wmax] {
        for i in [0, 1, imax / 2, imax] {
            for a in [0, 1, amax / 2, amax - 1, amax] {
                b.vectors.push(one(w as u32, i as u32, a as u32));
                edge += 1;
            }
        }
    }
    b.sources.push(("edge", edge));
    for _ in 0..RANDOM {
        // Random weight up to 2^f (a weight sum never exceeds it), random operands.
        let w = rng.bits(wb) as u32;
        b.vectors
            .push(one(w, rng.bits(ib) as u32, rng.bits(acc_bits) as u32));
    }
    b.sources.push(("random", RANDOM));
    let t = Instant::now();
    for v in &b.vectors {
        black_box(one(v[0] as u32, v[1] as u32, black_box(v[2] as u32)));
    }
    b.model_ns = t.elapsed().as_nanos() as u64;
    Ok(())
}
