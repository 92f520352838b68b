//! The bench of the accumulation MAC (`hdl-models/rtl/acc_mac.v`): a filter weight times a
//! sample intensity added into the accumulating word with the frame's rounding and overflow
//! modes, checked against [`AccParams::mac_code`]; for a signed kernel (Catmull-Rom,
//! Mitchell) the weights and the accumulator are two's complement and the accumulator's clamp
//! to the frame word is checked against [`AccParams::clamp_code`]. Vectors: scene taps (kernel weights, vertex
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
    let frame = hw.accumulate.frame;
    let (_, input) = src.through(StageId::Input)?;
    let ch = src.channel;
    let bg = input.fixed.prims().bg;
    let i_fmt = hw.input.intensity.format;
    let ap = AccParams {
        kernel: kernel.clone(),
        i_frac: i_fmt.frac_bits,
        i_max: u32::MAX,
        frame,
    };
    let signed = kernel.signed();
    // The accumulating word: a signed kernel's accumulator, else the frame word.
    let acc_q = kernel.accumulator(&frame).unwrap_or(frame);
    let (acc_bits, frame_bits) = (acc_q.format.total_bits(), frame.format.total_bits());
    let quant = match (frame.quant, signed) {
        (Quant::Trn, _) | (Quant::TrnZero, false) => 0,
        (Quant::Rnd, _) | (Quant::RndInf, false) => 1,
        (Quant::RndMinInf, _) | (Quant::RndZero, false) => 2,
        (Quant::RndConv, _) => 3,
        (Quant::TrnZero, true) => 4,
        (Quant::RndInf, true) => 5,
        (Quant::RndZero, true) => 6,
    };
    let ovf = match (frame.overflow, signed) {
        (Overflow::Wrap, _) => 0,
        (Overflow::SatZero, _) => 2,
        (Overflow::SatSym, true) => 3,
        _ => 1,
    };
    let wb = if signed {
        kernel.rom_bits()
    } else {
        (32 - kernel
            .w
            .iter()
            .max()
            .copied()
            .unwrap_or(1)
            .unsigned_abs()
            .leading_zeros())
        .max(kernel.f + 1)
    };
    let ib = i_fmt.total_bits();
    b.params = vec![
        ("W_BITS".into(), wb as i64),
        ("I_BITS".into(), ib as i64),
        ("F_BITS".into(), frame_bits as i64),
        ("SHIFT".into(), ap.product_shift() as i64),
        ("QUANT".into(), quant),
        ("OVF".into(), ovf),
        ("SIGNED".into(), i64::from(signed)),
        ("A_BITS".into(), acc_bits as i64),
    ];
    b.fields = vec![
        "w",
        "i",
        "acc_in",
        "acc_out",
        "ovf",
        "clamp_out",
        "clamp_ovf",
    ];
    // Words in the vectors: two's complement masked to their width.
    let mask = |v: i64, bits: u32| (v as u64) & ((1u64 << bits) - 1);
    // Sign extension of a `bits`-wide word (the accumulator of a signed kernel).
    let sext = |v: u64, bits: u32| {
        if signed {
            ((v << (64 - bits)) as i64) >> (64 - bits)
        } else {
            v as i64
        }
    };
    let one = |w: i32, i: u32, a: i64| {
        let (c, o) = ap.mac_code(a, w, i);
        let (k, ko) = ap.clamp_code(c);
        vec![
            mask(w as i64, wb),
            i as u64,
            mask(a, acc_bits),
            mask(c, acc_bits),
            o as u64,
            mask(k, frame_bits),
            ko as u64,
        ]
    };
    // Scene taps: the kernel's weights, the scene's vertex intensity codes and
    // the rendered frame codes as the running sum.
    let taps = src.frame(TAPS)?;
    let ws: Vec<i32> = kernel.w.clone();
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
        b.vectors.push(one(w, i, t.2 as i64));
    }
    b.sources.push(("scene", taps.len()));
    // Edge cases: the extreme weights times the extreme intensities onto every boundary of
    // the accumulating word and of the frame word.
    let (wmin, wmax) = if signed {
        (-(1i64 << (wb - 1)), (1i64 << (wb - 1)) - 1)
    } else {
        (0, (1i64 << wb) - 1)
    };
    let imax = (1u64 << ib) - 1;
    let (amin, amax) = (acc_q.format.min_code(), acc_q.format.max_code());
    let fmax = frame.format.max_code();
    let mut edge = 0;
    let weights = [wmin, -1, 0, 1, 1 << kernel.f, wmax];
    for w in weights.into_iter().filter(|w| (wmin..=wmax).contains(w)) {
        for i in [0, 1, imax / 2, imax] {
            for a in [
                amin,
                amin + 1,
                -1,
                0,
                1,
                amax / 2,
                fmax,
                fmax + 1,
                amax - 1,
                amax,
            ] {
                if (amin..=amax).contains(&a) {
                    b.vectors.push(one(w as i32, i as u32, a));
                    edge += 1;
                }
            }
        }
    }
    b.sources.push(("edge", edge));
    for _ in 0..RANDOM {
        // Random weight, intensity and running sum over their whole words.
        let w = sext(rng.bits(wb), wb) as i32;
        let a = sext(rng.bits(acc_bits), acc_bits);
        b.vectors.push(one(w, rng.bits(ib) as u32, a));
    }
    b.sources.push(("random", RANDOM));
    let t = Instant::now();
    for v in &b.vectors {
        let w = sext(v[0], wb) as i32;
        black_box(one(w, v[1] as u32, black_box(sext(v[2], acc_bits))));
    }
    b.model_ns = t.elapsed().as_nanos() as u64;
    Ok(())
}
