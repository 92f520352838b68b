//! The accumulate stage through the contract: the filter kernel, the fixed accumulation of
//! the binned tiles into the frame memory (linear, or in the log domain for `log-add`), the
//! float reference, the stage-local comparison, the tile tokens and the frame port traffic.

use super::PointFrags;
use super::{
    AccParams, AccRef, FRAME_MEMORY, Frame, Kernel, WEIGHT_ROM, accumulate_f64, accumulate_tiles,
    own_depth_coverage, point_weights,
};
use crate::config::{CodingKind, HwConfig};
use crate::error::{Error, Result};
use crate::fixed::Overflow;
use crate::scene::Scene;
use crate::stage::logdomain::{
    LogAdder, LogCode, LogWork, accumulate_pixel, accumulate_pixel_f64, add_term, local_add,
};
use crate::stage::taps::{FrameCoding, FrameTap, SampleCoding, SampleTap, SampleTapF, Taps};
use crate::stage::visibility::Samples;
use crate::stage::{
    Cost, Cx, Facts, LocalError, MemImage, Need, Notes, Region, Stage, StageId, TokenKind, Tokens,
};
use rayon::prelude::*;
use std::sync::Arc;

/// The filter kernel of the hardware configuration.
pub fn kernel(hw: &HwConfig) -> Kernel {
    Kernel::with_bc(
        hw.accumulate.filter,
        hw.raster.samples,
        hw.accumulate.weight_bits,
        hw.accumulate.gaussian_sigma,
        hw.accumulate.mitchell,
    )
}

/// The stage's float reference: the float sample buffer filtered with the kernel's exact
/// weights over the pixel `region` of a `size` screen (the rest is the background), in
/// frame LSBs, unrounded and unsaturated. The buffer covers the samples the region's filter
/// windows read.
pub fn float_frame(
    s: &SampleTapF,
    kernel: &Kernel,
    hw: &HwConfig,
    size: (u32, u32),
    region: &Region,
) -> Vec<f64> {
    let r = AccRef {
        kernel,
        i_frac: hw.input.intensity.format.frac_bits,
        frame_frac: hw.accumulate.frame.format.frac_bits,
        bg_i: s.bg,
        size,
    };
    accumulate_f64(&s.samples.i, &s.samples.reg, region, &s.points, &r)
}

/// What the fixed model leaves: the kernel, its frame writes per binned tile and, for
/// log-add, the log adder.
pub struct Accumulated {
    kernel: Kernel,
    tile_rmw: Vec<u64>,
    adder: Option<Arc<LogAdder>>,
}

/// The accumulate stage.
pub struct Accumulate;

impl Stage for Accumulate {
    type Fixed = Accumulated;

    fn id(&self) -> StageId {
        StageId::Accumulate
    }

    fn plan(&self, _: &Scene, hw: &HwConfig) -> Result<Need> {
        let a = &hw.accumulate;
        let ee = if a.filter.equal_energy() {
            "equal-energy"
        } else {
            "not equal-energy"
        };
        Ok(Need::yes(match hw.coding.kind {
            CodingKind::LogAdd => format!(
                "filters the samples ({}, {ee}) and sums them in the log domain (coding.kind = \"log-add\")",
                a.filter.name()
            ),
            _ => match kernel(hw).accumulator(&a.frame) {
                None => format!(
                    "filters the samples ({}, {ee}) into the {} frame memory",
                    a.filter.name(),
                    a.frame.format
                ),
                Some(q) => format!(
                    "filters the samples ({}, {ee}, signed weights) into a {} accumulator (a sign bit and {} headroom bit(s) over the frame word), clamped to the {} frame memory with {}",
                    a.filter.name(),
                    q.format,
                    q.format.total_bits() - 1 - a.frame.format.total_bits(),
                    a.frame.format,
                    a.frame.overflow
                ),
            },
        }))
    }

    fn key(&self, cx: &Cx) -> serde_json::Value {
        let l = cx.layout;
        serde_json::json!({
            "accumulate": cx.hw.section("accumulate"),
            "coding": cx.hw.section("coding"),
            "region": l.region,
            "tiles": [l.tiles.size, l.tiles.cols, l.tiles.rows],
            "binned": l.tiles.touched.iter().map(|&b| b as u8).collect::<Vec<_>>(),
        })
    }

    fn fixed(&self, cx: &Cx, taps: &mut Taps) -> Result<(Accumulated, Facts)> {
        let hw = cx.hw;
        let k = kernel(hw);
        let s = taps.fixed.samples();
        let size = frame_size(cx.layout);
        let (frame, coding, tile_rmw, adder, facts) = match s.coding {
            SampleCoding::Linear => {
                let ap = AccParams {
                    kernel: k.clone(),
                    i_frac: hw.input.intensity.format.frac_bits,
                    i_max: code_bound(hw.input.intensity.format),
                    frame: hw.accumulate.frame,
                };
                let l = cx.layout;
                let (frame, w, stats, tile_rmw) = accumulate_tiles(
                    &s.samples,
                    &l.region,
                    Some(&l.tiles),
                    &s.points,
                    &ap,
                    s.bg,
                    size,
                    cx.pool,
                )?;
                let mut facts = Facts {
                    work: vec![
                        ("pixels", w.pixels),
                        ("macs", w.macs),
                        ("fragments", w.fragments),
                        ("point_updates", w.point_updates),
                    ],
                    signals: stats,
                    ..Facts::default()
                };
                if let Some(q) = k.accumulator(&hw.accumulate.frame) {
                    facts.work.push(("clamps", w.clamps));
                    facts.note("acc_bits", q.format.total_bits() as u64);
                    facts.note("weight_rom_bits", k.rom_bits() as u64);
                }
                (frame, FrameCoding::Linear, tile_rmw, None, facts)
            }
            SampleCoding::Log(code) => {
                let (frame, add, tile_rmw, facts) = log_accumulate(cx, &k, s, code, size)?;
                let add = Arc::new(add);
                (
                    frame,
                    FrameCoding::Log(add.clone()),
                    tile_rmw,
                    Some(add),
                    facts,
                )
            }
        };
        taps.fixed.frame = Some(Arc::new(FrameTap { frame, coding }));
        Ok((
            Accumulated {
                kernel: k,
                tile_rmw,
                adder,
            },
            facts,
        ))
    }

    fn float(&self, cx: &Cx, a: &Accumulated, taps: &mut Taps, _: &mut Notes) -> Result<()> {
        let l = cx.layout;
        let size = frame_size(l);
        let frame_ref = float_frame(taps.float.samples(), &a.kernel, cx.hw, size, &l.region);
        taps.float.frame = Some(Arc::new(frame_ref));
        taps.float.frame_content = None;
        Ok(())
    }

    /// The float accumulation of the fixed samples (exact weights), code by code; for
    /// log-add the exact log-domain sums of the same codes and weights.
    fn local(
        &self,
        cx: &Cx,
        a: &Accumulated,
        input: &Taps,
        out: &Taps,
        _: &mut Notes,
    ) -> Option<LocalError> {
        let s = input.fixed.samples();
        let frame = &out.fixed.frame().frame;
        let l = cx.layout;
        let k = &a.kernel;
        if let (Some(add), SampleCoding::Log(code)) = (&a.adder, s.coding) {
            let mut e = LocalError::default();
            let sw = s.samples.reg.width();
            for py in l.region.y0..l.region.y1 {
                for px in l.region.x0..l.region.x1 {
                    let (c0, r0) = window(&s.samples, k, px, py);
                    let terms = (0..k.size)
                        .flat_map(|j| (0..k.size).map(move |i| (j, i)))
                        .map(|(j, i)| (s.samples.i[(r0 + j) * sw + c0 + i], log_w(k, j, i)));
                    let v = accumulate_pixel_f64(code, k.f, terms);
                    let at = py as usize * frame.width as usize + px as usize;
                    local_add(&mut e, add, frame.acc[at] as i64, v);
                }
            }
            return Some(e.finish());
        }
        let iv: Vec<f64> = s.samples.i.iter().map(|&v| v as f64).collect();
        let pts: Vec<PointFrags<f64>> = s
            .points
            .iter()
            .map(|p| PointFrags {
                i: p.i as f64,
                samples: p.samples.clone(),
            })
            .collect();
        let r = AccRef {
            kernel: k,
            i_frac: cx.hw.input.intensity.format.frac_bits,
            frame_frac: cx.hw.accumulate.frame.format.frac_bits,
            bg_i: s.bg as f64,
            size: frame_size(l),
        };
        let fl = accumulate_f64(&iv, &l.samples, &l.region, &pts, &r);
        let max = cx.hw.accumulate.frame.format.max_code() as f64;
        let mut e = LocalError::default();
        for (&a, &b) in frame.acc.iter().zip(&fl) {
            e.add(a as f64, b.clamp(0.0, max));
        }
        Some(e.finish())
    }

    /// One token per binned tile: its pixels' MACs, and its frame read-modify-writes
    /// (2 frame words each) over the frame port.
    fn tokens(&self, cx: &Cx, a: &Accumulated) -> Option<Tokens> {
        let l = cx.layout;
        let taps = (a.kernel.size * a.kernel.size) as u64;
        let bits = frame_bits(cx.hw, a) as u64;
        let (mut items, mut port_bits, mut rows) = (Vec::new(), Vec::new(), Vec::new());
        for (t, r) in l.tiles.binned_in(&l.region) {
            items.push(r.pixels() * taps);
            rows.push(r.y0);
            port_bits.push(a.tile_rmw.get(t).copied().unwrap_or(0) * 2 * bits);
        }
        Some(Tokens {
            kind: TokenKind::Tile,
            item: "MACs",
            items,
            port_bits,
            rows,
            stream: None,
        })
    }

    fn cost(&self, cx: &Cx, a: &Accumulated) -> Cost {
        let pixels = cx.layout.grid.pixels();
        match &a.adder {
            Some(add) => add.cost(pixels),
            None => super::cost(
                &AccParams {
                    kernel: a.kernel.clone(),
                    i_frac: cx.hw.input.intensity.format.frac_bits,
                    i_max: code_bound(cx.hw.input.intensity.format),
                    frame: cx.hw.accumulate.frame,
                },
                cx.hw.input.intensity.format.total_bits(),
                pixels,
            ),
        }
    }

    /// The frame memory (not on one band of a banded run: the runner packs the whole frame
    /// once every band is in) and the weight ROM or the log adder's tables.
    fn memories(&self, cx: &Cx, a: &Accumulated, out: &Taps) -> Vec<MemImage> {
        let mut v = Vec::new();
        if cx.layout.band.is_none() {
            let tap = out.fixed.frame.clone().expect("accumulate wrote the frame");
            let fb = frame_bits(cx.hw, a);
            v.push(MemImage {
                name: FRAME_MEMORY.into(),
                fields: vec![fb],
                words: tap.frame.acc.len(),
                region_only: false,
                get: Arc::new(move |w, _| tap.frame.acc[w] as u64),
            });
        }
        match &a.adder {
            Some(add) => v.extend(add.images()),
            None => {
                // Two's complement in the ROM word (the unsigned kernels' weights as they are).
                let bits = a.kernel.rom_bits();
                let mask = if bits >= 32 {
                    u32::MAX
                } else {
                    (1u32 << bits) - 1
                };
                let w: Vec<u32> = a.kernel.w.iter().map(|&v| v as u32 & mask).collect();
                v.push(MemImage::table(WEIGHT_ROM, bits, Arc::new(w)));
            }
        }
        v
    }
}

/// The size of the frame the stage writes: the screen, or one band's rows of it.
fn frame_size(l: &crate::stage::Layout) -> (u32, u32) {
    match l.band {
        Some(b) => (l.grid.width, b.y1 - b.y0),
        None => (l.grid.width, l.grid.height),
    }
}

/// The frame memory's word: the log frame's, a signed kernel's accumulator (the partial
/// sums live there between a pixel's fragments), else the frame format's.
fn frame_bits(hw: &HwConfig, a: &Accumulated) -> u32 {
    match &a.adder {
        Some(add) => add.frame_bits(),
        None => a
            .kernel
            .accumulator(&hw.accumulate.frame)
            .map_or(hw.accumulate.frame.format.total_bits(), |q| {
                q.format.total_bits()
            }),
    }
}

/// Kernel weight `(j, i)` for the log-add path, whose kernels have no negative weight (the
/// configuration refuses a filter with negative lobes under `coding.kind = "log-add"`).
fn log_w(k: &Kernel, j: usize, i: usize) -> u32 {
    k.w[j * k.size + i].max(0) as u32
}

/// Buffer column and row of the first sample of pixel `(px, py)`'s filter window.
fn window(s: &Samples, k: &Kernel, px: u32, py: u32) -> (usize, usize) {
    let c0 = (px as i64 * k.n as i64 - k.off - s.reg.c0) as usize;
    let r0 = (py as i64 * k.n as i64 - k.off - s.reg.k0) as usize;
    (c0, r0)
}

/// One pixel of the log frame: code, nearest depth, coverage.
type PixelOut = (u32, u32, u16);

/// Structure (b): log-domain accumulation of the log-coded samples of the binned tiles into
/// a log frame memory. Returns the frame, the adder, the frame writes per tile and the facts.
fn log_accumulate(
    cx: &Cx,
    k: &Kernel,
    s: &SampleTap,
    code: LogCode,
    size: (u32, u32),
) -> Result<(Frame, LogAdder, Vec<u64>, Facts)> {
    let w_min = k.w.iter().copied().filter(|&w| w > 0).min().unwrap_or(1) as u32;
    let add = LogAdder::new(code, &cx.hw.coding, k.f, w_min);
    let (width, height) = size;
    let l = cx.layout;
    let (region, tiles) = (l.region, &l.tiles);
    let samples = &s.samples;
    let sw = samples.reg.width();
    let mut work = LogWork::new(&add);
    // The background (the frame's clear value) through the same adder: its signals count,
    // its work does not (it is one constant).
    let mut bg_work = LogWork::new(&add);
    let bg_code = accumulate_pixel(
        &add,
        k.w.iter().map(|&w| (s.bg, w.max(0) as u32)),
        &mut bg_work,
    );
    work.frame.merge(&bg_work.frame);
    work.term.merge(&bg_work.term);
    let mut frame = Frame::cleared(width, height, bg_code as u32, cx.pool);
    let rows: Vec<(Vec<PixelOut>, LogWork)> = (region.y0..region.y1)
        .into_par_iter()
        .map(|py| {
            let mut wk = LogWork::new(&add);
            let row = (region.x0..region.x1)
                .map(|px| {
                    if !tiles.is_touched(px, py) {
                        return (bg_code as u32, u32::MAX, 0);
                    }
                    wk.pixels += 1;
                    let (c0, r0) = window(samples, k, px, py);
                    let terms = (0..k.size).flat_map(|j| (0..k.size).map(move |i| (j, i)));
                    let a = accumulate_pixel(
                        &add,
                        terms.map(|(j, i)| (samples.i[(r0 + j) * sw + c0 + i], log_w(k, j, i))),
                        &mut wk,
                    );
                    let (zmin, cov) = own_depth_coverage(samples, k, r0 * sw + c0, sw);
                    (a as u32, zmin, cov)
                })
                .collect();
            (row, wk)
        })
        .collect();
    let mut tile_rmw = vec![0u64; tiles.touched.len()];
    for (py, (row, wk)) in (region.y0..region.y1).zip(rows) {
        let base = py as usize * width as usize + region.x0 as usize;
        for (o, (a, z, c)) in row.into_iter().enumerate() {
            frame.acc[base + o] = a;
            frame.depth[base + o] = z;
            frame.coverage[base + o] = c;
            let px = region.x0 + o as u32;
            if tiles.is_touched(px, py) {
                // A pixel's log sum stays in a register: one frame write per pixel.
                tile_rmw[tiles.index(px, py)] += 1;
            }
        }
        work.merge(&wk);
    }
    // Light points: their summed weight's log plus the point's code, added in arrival order.
    for pt in &s.points {
        for (px, py, ssum) in point_weights(pt, &samples.reg, &region, k, |e| f64::from(k.w[e])) {
            let at = py as usize * width as usize + px as usize;
            let w = (ssum as u32).min(1 << k.f);
            work.term_adds += 1;
            work.log_adds += 1;
            frame.acc[at] = add_term(&add, frame.acc[at] as i64, pt.i, w, &mut work) as u32;
            tile_rmw[tiles.index(px, py)] += 1;
        }
    }
    if cx.hw.coding.overflow == Overflow::Error && work.frame.overflows > 0 {
        return Err(Error::Overflow {
            signal: work.frame.name.clone(),
            format: work.frame.format.to_string(),
            value: work.frame.max.unwrap_or_default(),
            min: 0,
            max: add.max,
        });
    }
    let mut facts = Facts {
        work: vec![
            ("pixels", work.pixels),
            ("term_adds", work.term_adds),
            ("log_adds", work.log_adds),
            ("saturations", work.saturations),
        ],
        signals: vec![
            add.log_w_stats.clone(),
            add.sb_stats.clone(),
            work.term,
            work.frame,
        ],
        ..Facts::default()
    };
    for (key, v) in [
        ("frame_bits", add.frame_bits() as u64),
        ("frame_offset", add.off as u64),
        ("sb_table_entries", add.sb.len() as u64),
        ("sb_table_data_bits", add.table_data_bits() as u64),
        ("sb_address_shift", add.shift as u64),
    ] {
        facts.note(key, v);
    }
    Ok((frame, add, tile_rmw, facts))
}

/// The largest code of format `f` as a bound on the sample buffer's intensity codes (the
/// raster and visibility clamp them into the format).
fn code_bound(f: crate::fixed::QFormat) -> u32 {
    u32::try_from(f.max_code()).unwrap_or(u32::MAX)
}
