//! The bench of the dof row MAC (`hdl-models/rtl/dof_row_mac.v`): one output sample of the
//! horizontal or vertical pass of the layered depth of field, checked against
//! [`row_mac`] and [`border_sum`], the code `layered_fixed` runs.
//!
//! Vector fields (`TAPS = 2 HALF + 1`, `HALF` the largest mask half-size of the scene's
//! layers): `pass` (0 horizontal, 1 vertical), `layer`, `pos`, `len`, `TAPS` colour samples
//! `x`, `TAPS` alpha samples `a`, `TAPS` behind samples `d`, then the expected `sx`
//! (saturated colour sum), `ovf`, `sa` (alpha sum), `sd` (behind sum, the alpha's
//! normaliser) and `w` (in-line tap sum, the border renormalisation weight). Window
//! sample `t` sits at line position `pos + t - HALF`; samples off the line hold random
//! values the module must ignore.

use super::{RANDOM, SceneTaps, TAPS, bad};
use crate::config::{DofKernel, DofKind, HwConfig};
use crate::error::{Error, Result};
use crate::hdl::bench::{Bench, Rng};
use crate::scene::Lens;
use crate::stage::StageId;
use crate::stage::dof::{
    DepthImage, LayerPlanes, LensMap, MacOut, border_sum, layered_fixed_observed, plan_layers,
    row_mac,
};
use std::hint::black_box;
use std::time::Instant;

/// Bits to hold `v`.
fn bits(v: u128) -> u32 {
    (128 - v.leading_zeros()).max(1)
}

/// A vector's expected outputs: `sx`, `ovf`, `sa`, `sd`, `w`.
fn expected(r: &MacOut, w: u64) -> [u64; 5] {
    [r.x as u64, r.overflow as u64, r.a as u64, r.d as u64, w]
}

/// Fills `b` with the dof row MAC's parameters, coefficient ROM and vectors.
pub(super) fn bench(b: &mut Bench, hw: &HwConfig, src: &SceneTaps, rng: &mut Rng) -> Result<()> {
    let scene = src.scene;
    let p = &hw.dof;
    if !matches!(scene.camera.lens, Lens::ThinLens { .. }) {
        return Err(Error::File(scene.error(
            "camera.lens",
            "the dof row MAC needs a thin-lens camera (depth of field); this scene has a pinhole camera (the default and cone-focus scenes have a thin lens)",
        )));
    }
    if p.kind != DofKind::Layered {
        return Err(bad(
            hw,
            "dof.kind",
            format!(
                "the dof row MAC is the layered method's datapath; dof.kind = \"{}\" has no Verilog model yet (use kind = \"layered\" for the vectors)",
                p.kind.name()
            ),
        ));
    }
    if p.kernel == DofKernel::Disc {
        return Err(bad(
            hw,
            "dof.kernel",
            "the dof row MAC is the separable passes' datapath; dof.kernel = \"disc\" is a direct 2-D filter with no Verilog model yet (use kernel = \"gaussian\" or \"fitted_gaussian\" for the vectors)".into(),
        ));
    }
    if p.acc_bits > 64 {
        return Err(bad(
            hw,
            "dof.acc_bits",
            format!(
                "the HDL vectors carry 64-bit words; the dof row MAC bench takes dof.acc_bits <= 64, got {}",
                p.acc_bits
            ),
        ));
    }
    let (_, taps) = src.through(StageId::Accumulate)?;
    let frame = &taps.fixed.frame().frame;
    let (w, h) = (frame.width as usize, frame.height as usize);
    let lens = LensMap::of(scene, hw, frame.height).expect("a thin-lens camera, checked above");
    let n2 = hw.raster.samples * hw.raster.samples;
    let plan = plan_layers(&frame.depth, &frame.coverage, n2, &lens, p)
        .map_err(|m| bad(hw, "dof.max_half_size", m))?;
    let frame_fmt = hw.accumulate.frame.format;
    let cb = p.coef_bits;
    let half = plan.layers.iter().map(|l| l.m).max().unwrap_or(0).max(1);
    let taps = 2 * half + 1;
    let nl = plan.layers.len().max(1);
    let maxlen = w.max(h);
    let ha_bits = bits(n2 as u128);
    let hx_bits = bits(frame_fmt.max_code() as u128 * n2 as u128);
    let h_sa = ha_bits + cb;
    let (vx_bits, va_bits) = (p.line_bits, h_sa);
    let v_sa = va_bits + cb;
    let line_max = (1u128 << p.line_bits) - 1;
    let acc_max = (1u128 << p.acc_bits) - 1;
    b.params = vec![
        ("HALF".into(), half as i64),
        ("LAYERS".into(), nl as i64),
        ("LAYER_BITS".into(), bits(nl as u128 - 1) as i64),
        ("C_BITS".into(), cb as i64 + 1),
        ("POS_BITS".into(), bits(maxlen as u128) as i64),
        ("HX_BITS".into(), hx_bits as i64),
        ("HA_BITS".into(), ha_bits as i64),
        ("H_OUT_BITS".into(), p.line_bits as i64),
        ("H_SA_BITS".into(), h_sa as i64),
        ("VX_BITS".into(), vx_bits as i64),
        ("VA_BITS".into(), va_bits as i64),
        ("V_OUT_BITS".into(), p.acc_bits as i64),
        ("V_SA_BITS".into(), v_sa as i64),
    ];
    // One centred TAPS-entry coefficient set per layer.
    let mut rom = vec![0u64; nl * taps];
    for (l, layer) in plan.layers.iter().enumerate() {
        let o = l * taps + half - layer.m;
        rom[o..o + layer.coef.len()].copy_from_slice(&layer.coef);
    }
    b.roms = vec![("dof_rom.hex".into(), rom)];
    b.fields = ["pass", "layer", "pos", "len"].to_vec();
    b.fields.extend(std::iter::repeat_n("x", taps));
    b.fields.extend(std::iter::repeat_n("a", taps));
    b.fields.extend(std::iter::repeat_n("d", taps));
    b.fields.extend(["sx", "ovf", "sa", "sd", "w"]);
    let in_bits = |pass: u64| {
        if pass == 0 {
            (hx_bits, ha_bits)
        } else {
            (vx_bits, va_bits)
        }
    };
    // The Rust model of one vector: the layer's own taps over the window.
    let one = |v: &[u64]| -> [u64; 5] {
        let (pass, c) = (v[0], &plan.layers[v[1] as usize].coef);
        let (pos, len) = (v[2] as usize, v[3] as usize);
        let plane = |k: usize| &v[4 + k * taps..4 + (k + 1) * taps];
        let at = |i: usize| i + half - pos;
        let max = if pass == 0 { line_max } else { acc_max };
        let r = row_mac(c, pos, len, max, |i| {
            let s = |k: usize| plane(k)[at(i)] as u128;
            (s(0), s(1), s(2))
        });
        expected(&r, border_sum(c, pos, len))
    };
    // A vector's inputs: samples on the line from `on(i)`, random values off it.
    let window = |rng: &mut Rng,
                  pass: u64,
                  l: usize,
                  pos: usize,
                  len: usize,
                  on: &mut dyn FnMut(usize) -> (u64, u64, u64)| {
        let (xb, ab) = in_bits(pass);
        let mut v = vec![pass, l as u64, pos as u64, len as u64];
        let (mut a, mut d) = (Vec::with_capacity(taps), Vec::with_capacity(taps));
        for t in 0..taps {
            let i = pos as i64 + t as i64 - half as i64;
            let (x, y, z) = if i >= 0 && (i as usize) < len {
                on(i as usize)
            } else {
                (rng.bits(xb), rng.bits(ab), rng.bits(ab))
            };
            v.push(x);
            a.push(y);
            d.push(z);
        }
        v.extend(a);
        v.extend(d);
        v
    };
    // Scene taps: output samples of both passes spread over every blurred layer's box, the
    // expected values from the pipeline's own call (box coordinates).
    let img = DepthImage::of_frame(frame, &frame.acc, n2);
    // A first run counts the output samples of the blurred layers' boxes.
    let mut outputs = 0usize;
    let _ = layered_fixed_observed(&img, &plan, p, frame_fmt, |lp| outputs += lp.bw * lp.bh);
    let stride = (outputs / (TAPS / 2)).max(1);
    let mut scene_v: Vec<Vec<u64>> = vec![];
    let mut k = 0usize;
    let observe = |lp: &LayerPlanes| {
        let c = &plan.layers[lp.layer].coef;
        let (bw, bh) = (lp.bw, lp.bh);
        for y in 0..bh {
            for x in 0..bw {
                k += 1;
                if !k.is_multiple_of(stride) {
                    continue;
                }
                let (px, py) = (x + lp.x0, y + lp.y0);
                let row = y * bw;
                let r = row_mac(c, x, bw, line_max, |i| {
                    let j = row + i;
                    (lp.xi[j] as u128, lp.ai[j] as u128, lp.di[j] as u128)
                });
                let mut inb = |i: usize| -> (u64, u64, u64) {
                    if (lp.x0..lp.x0 + bw).contains(&i) {
                        let j = row + i - lp.x0;
                        (lp.xi[j], lp.ai[j], lp.di[j])
                    } else {
                        (0, 0, 0)
                    }
                };
                let mut v = window(rng, 0, lp.layer, px, w, &mut inb);
                v.extend(expected(&r, border_sum(c, px, w)));
                scene_v.push(v);
                let r = row_mac(c, y, bh, acc_max, |i| {
                    let j = i * bw + x;
                    (lp.hx[j] as u128, lp.ha[j] as u128, lp.hd[j] as u128)
                });
                let mut inb = |i: usize| -> (u64, u64, u64) {
                    if (lp.y0..lp.y0 + bh).contains(&i) {
                        let j = (i - lp.y0) * bw + x;
                        (lp.hx[j], lp.ha[j], lp.hd[j])
                    } else {
                        (0, 0, 0)
                    }
                };
                let mut v = window(rng, 1, lp.layer, py, h, &mut inb);
                v.extend(expected(&r, border_sum(c, py, h)));
                scene_v.push(v);
            }
        }
    };
    // With dof.overflow = ERROR a saturating run stops; the taps observed so far are kept.
    let _ = layered_fixed_observed(&img, &plan, p, frame_fmt, observe);
    // The module's form (image coordinates, off-box samples zero) gives the pipeline's values.
    debug_assert!(
        scene_v
            .iter()
            .all(|v| one(&v[..4 + 3 * taps])[..] == v[4 + 3 * taps..])
    );
    b.sources.push(("scene", scene_v.len()));
    b.vectors = scene_v;
    let layers: Vec<usize> = (0..plan.layers.len())
        .filter(|&l| plan.layers[l].m > 0)
        .collect();
    let layers = if layers.is_empty() {
        (0..plan.layers.len()).collect()
    } else {
        layers
    };
    let push = |b: &mut Bench, mut v: Vec<u64>| {
        v.extend(one(&v));
        b.vectors.push(v);
    };
    // Edge cases: every blurred layer, both passes, short and full lines, first, middle and
    // last position, all-zero, all-maximum and random inputs.
    let mut edge = 0;
    for &l in &layers {
        for pass in 0..2u64 {
            let (xb, ab) = in_bits(pass);
            let full = if pass == 0 { w } else { h };
            for len in [1, 2, half.min(maxlen), full, maxlen] {
                for pos in [0, len / 2, len - 1] {
                    for fill in 0..3 {
                        let mut r2 = Rng::new(rng.next_u64());
                        let mut on = |_: usize| match fill {
                            0 => (0, 0, 0),
                            1 => ((1u64 << xb) - 1, (1u64 << ab) - 1, (1u64 << ab) - 1),
                            _ => (r2.bits(xb), r2.bits(ab), r2.bits(ab)),
                        };
                        let v = window(rng, pass, l, pos, len, &mut on);
                        push(b, v);
                        edge += 1;
                    }
                }
            }
        }
    }
    b.sources.push(("edge", edge));
    for _ in 0..RANDOM {
        let l = layers[rng.next_u64() as usize % layers.len()];
        let pass = rng.next_u64() & 1;
        let (xb, ab) = in_bits(pass);
        let len = 1 + rng.next_u64() as usize % maxlen;
        let pos = rng.next_u64() as usize % len;
        // Half the vectors near the top of the input range (saturation).
        let top = rng.next_u64() & 1 == 1;
        let mut r2 = Rng::new(rng.next_u64());
        let v = window(rng, pass, l, pos, len, &mut |_| {
            let x = r2.bits(xb);
            let x = if top { x | (1u64 << (xb - 1)) } else { x };
            (x, r2.bits(ab), r2.bits(ab))
        });
        push(b, v);
    }
    b.sources.push(("random", RANDOM));
    let t = Instant::now();
    for v in &b.vectors {
        black_box(one(black_box(&v[..4 + 3 * taps])));
    }
    b.model_ns = t.elapsed().as_nanos() as u64;
    Ok(())
}
