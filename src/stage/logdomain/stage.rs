//! Pipeline glue of the `logdomain` stage (docs/reference.md §1): the encoder phase between
//! visibility and accumulate (both structures), the log-domain accumulation (structure b)
//! and the eq. 15 post stage (structure b). Reports the ROMs' quantisation and the log
//! adder's overflow counts as signals of the stage.

use super::adder::LogAdder;
use super::code::{LogCode, LogEncoder, PotentiationLut, check_contrast};
use super::lut::{log_gamma_linear, log_gamma_lut};
use super::sums::{LogWork, accumulate_pixel, accumulate_pixel_f64, add_term, local_add};
use crate::config::{CodingKind, HwConfig};
use crate::error::{Error, FileError, Result};
use crate::fixed::Overflow;
use crate::pipeline::{Accumulated, Front, Geometry, Post, RenderOptions};
use crate::scene::Scene;
use crate::stage::accumulate::{self, AccRef, Frame};
use crate::stage::gamma::GammaSpec;
use crate::stage::{Cost, LocalError, StageReport, Unit, ms_since};
use rayon::prelude::*;
use std::time::Instant;

/// The log code of a scene and hardware config (K from the scene's display block).
pub fn log_code(scene: &Scene, hw: &HwConfig) -> Result<LogCode> {
    let k = scene.display.contrast;
    check_contrast(k).map_err(|msg| {
        Error::File(FileError {
            file: scene.name.clone(),
            line: None,
            col: None,
            field: "display.contrast".into(),
            msg,
        })
    })?;
    Ok(LogCode {
        k,
        bits: hw.coding.log_bits,
    })
}

/// Encodes the stored samples (and light points and the background) to the log code in
/// place; for structure (a) it then potentiates them back to linear codes, so the spine's
/// accumulate runs unchanged. Returns the stage report and, for structure (b), the encoder.
pub fn encode_phase(
    f: &mut Front,
    g: &mut Geometry,
    scene: &Scene,
    hw: &HwConfig,
) -> Result<StageReport> {
    let code = log_code(scene, hw)?;
    let i_fmt = hw.input.intensity.format;
    let white_i = ((1u64 << i_fmt.int_bits) - 1) << i_fmt.frac_bits;
    let enc = LogEncoder::new(code, white_i, i_fmt.total_bits());
    let mut r = StageReport {
        name: "logdomain".into(),
        ..Default::default()
    };
    let t = Instant::now();
    // Stage-local error: log-stage output vs its linear input, in output LSBs.
    let lin_in: Vec<u32> = g.samples.i.clone();
    g.samples
        .i
        .par_iter_mut()
        .for_each(|v| *v = enc.encode(*v as u64));
    for p in g.points.iter_mut() {
        p.i = enc.encode(p.i as u64);
    }
    f.bg.0 = enc.encode(f.bg.0 as u64);
    let encoded = g.samples.i.len() as u64 + g.points.len() as u64 + 1;
    let mut potentiations = 0;
    let mut cost = enc.cost();
    r.signals.push(enc.stats.clone());
    let mut e = LocalError::default();
    if hw.coding.kind == CodingKind::LogPotentiate {
        let frame_bits = hw.accumulate.frame.format.int_bits;
        let lut = PotentiationLut::build(code, frame_bits);
        let sh = i_fmt.frac_bits;
        let pot = |c: u32| lut.table[c as usize] << sh;
        g.samples.i.par_iter_mut().for_each(|v| *v = pot(*v));
        for p in g.points.iter_mut() {
            p.i = pot(p.i);
        }
        f.bg.0 = pot(f.bg.0);
        potentiations = encoded;
        r.fixed_ms = ms_since(t);
        let t = Instant::now();
        // Float: the exact linear input in the potentiated code's LSBs.
        let scale = ((1u64 << frame_bits) - 1) as f64 / white_i as f64;
        for (&a, &b) in g.samples.i.iter().zip(&lin_in) {
            e.add((a >> sh) as f64, b as f64 * scale);
        }
        r.float_ms = ms_since(t);
        let max_lut = (0..=code.grades())
            .map(|c| {
                (lut.table[c as usize] as f64 - PotentiationLut::exact(code, frame_bits, c)).abs()
            })
            .fold(0.0, f64::max);
        r.notes
            .insert("potentiation_lut_max_error_lsb".into(), max_lut.into());
        let c2 = lut.cost();
        cost.lut_bits += c2.lut_bits;
        r.signals.push(lut.stats);
    } else {
        r.fixed_ms = ms_since(t);
        let t = Instant::now();
        for (&a, &b) in g.samples.i.iter().zip(&lin_in) {
            let exact = code.log_of_linear(b as f64 / white_i as f64) * code.grades() as f64;
            e.add(a as f64, exact);
        }
        r.float_ms = ms_since(t);
    }
    r.local = Some(e.finish());
    // The sample buffer stores the log code instead of the linear one.
    let grid = f.grid;
    let full_samples = grid.sw() as u64 * grid.sh() as u64;
    let saved = full_samples * (i_fmt.total_bits() - code.bits.min(i_fmt.total_bits())) as u64;
    g.reports[2].cost.storage_bits = g.reports[2].cost.storage_bits.saturating_sub(saved);
    r.notes
        .insert("sample_buffer_bits_saved".into(), saved.into());
    r.notes.insert("log_grades".into(), code.grades().into());
    r.notes
        .insert("grade_luminance_ratio".into(), code.step_ratio().into());
    let m = scene.display.contrast.ln() / scene.display.weber.ln_1p();
    r.notes.insert("scene_grades_needed_eq11".into(), m.into());
    r.cost = cost;
    r.work.insert("encoded".into(), encoded);
    r.work.insert("potentiations".into(), potentiations);
    Ok(r)
}

/// One pixel of the log frame: code, nearest depth, coverage.
type PixelOut = (u32, u32, u16);

/// Structure (b): log-domain accumulation of the (log-coded) samples into a log frame
/// memory, fixed model and exact reference; the float image is the spine's.
pub fn accumulate_phase(
    f: &Front,
    g: &Geometry,
    scene: &Scene,
    hw: &HwConfig,
    enc_report: &mut StageReport,
    opts: RenderOptions,
) -> Result<(Accumulated, LogAdder)> {
    let code = log_code(scene, hw)?;
    let k = &f.kernel;
    let w_min = k.w.iter().copied().filter(|&w| w > 0).min().unwrap_or(1);
    let add = LogAdder::new(code, &hw.coding, k.f, w_min);
    let (width, height) = (f.grid.width, f.grid.height);
    let npix = width as usize * height as usize;
    let t = Instant::now();
    let s = &g.samples;
    let sw = s.reg.width();
    let mut work = LogWork::new(&add);
    // The background (the frame's clear value) through the same adder: its signals count,
    // its work does not (it is one constant).
    let mut bg_work = LogWork::new(&add);
    let bg_code = accumulate_pixel(&add, k.w.iter().map(|&w| (f.bg.0, w)), &mut bg_work);
    work.frame.merge(&bg_work.frame);
    work.term.merge(&bg_work.term);
    let mut frame = Frame {
        width,
        height,
        acc: vec![bg_code as u32; npix],
        depth: vec![u32::MAX; npix],
        coverage: vec![0; npix],
    };
    let region = f.region;
    let window = |px: u32, py: u32| {
        let c0 = (px as i64 * k.n as i64 - k.off - s.reg.c0) as usize;
        let r0 = (py as i64 * k.n as i64 - k.off - s.reg.k0) as usize;
        (c0, r0)
    };
    let rows: Vec<(Vec<PixelOut>, LogWork)> = (region.y0..region.y1)
        .into_par_iter()
        .map(|py| {
            let mut wk = LogWork::new(&add);
            let row = (region.x0..region.x1)
                .map(|px| {
                    let (c0, r0) = window(px, py);
                    let terms = (0..k.size).flat_map(|j| (0..k.size).map(move |i| (j, i)));
                    let a = accumulate_pixel(
                        &add,
                        terms.map(|(j, i)| (s.i[(r0 + j) * sw + c0 + i], k.w[j * k.size + i])),
                        &mut wk,
                    );
                    let (zmin, cov) = accumulate::own_depth_coverage(s, k, r0 * sw + c0, sw);
                    (a as u32, zmin, cov)
                })
                .collect();
            wk.pixels = (region.x1 - region.x0) as u64;
            (row, wk)
        })
        .collect();
    for (py, (row, wk)) in (region.y0..region.y1).zip(rows) {
        let base = py as usize * width as usize + region.x0 as usize;
        for (o, (a, z, c)) in row.into_iter().enumerate() {
            frame.acc[base + o] = a;
            frame.depth[base + o] = z;
            frame.coverage[base + o] = c;
        }
        work.merge(&wk);
    }
    // Light points: their summed weight's log plus the point's code, added in arrival order.
    for pt in &g.points {
        for (px, py, ssum) in accumulate::point_weights(pt, &s.reg, &region, k, |e| k.w[e] as f64) {
            let at = py as usize * width as usize + px as usize;
            let w = (ssum as u32).min(1 << k.f);
            work.term_adds += 1;
            work.log_adds += 1;
            frame.acc[at] = add_term(&add, frame.acc[at] as i64, pt.i, w, &mut work) as u32;
        }
    }
    if hw.coding.overflow == Overflow::Error && work.frame.overflows > 0 {
        return Err(Error::Overflow {
            signal: work.frame.name.clone(),
            format: work.frame.format.to_string(),
            value: work.frame.max.unwrap_or_default(),
            min: 0,
            max: add.max,
        });
    }
    enc_report.fixed_ms += ms_since(t);
    // Stage-local: exact log/exp sums of the same codes and weights.
    if opts.stage_local {
        let t = Instant::now();
        let mut e = LocalError::default();
        for py in region.y0..region.y1 {
            for px in region.x0..region.x1 {
                let (c0, r0) = window(px, py);
                let terms = (0..k.size)
                    .flat_map(|j| (0..k.size).map(move |i| (j, i)))
                    .map(|(j, i)| (s.i[(r0 + j) * sw + c0 + i], k.w[j * k.size + i]));
                let v = accumulate_pixel_f64(code, k.f, terms);
                local_add(
                    &mut e,
                    &add,
                    frame.acc[py as usize * width as usize + px as usize] as i64,
                    v,
                );
            }
        }
        enc_report.float_ms += ms_since(t);
        enc_report.local = Some(e.finish());
    }
    // The float image: the spine's exact linear reference.
    let t = Instant::now();
    let frame_fmt = hw.accumulate.frame.format;
    let frame_ref = accumulate::accumulate_f64(
        &g.samples_ref.i,
        &f.sreg,
        &f.region,
        &g.points_ref,
        &AccRef {
            kernel: k,
            i_frac: hw.input.intensity.format.frac_bits,
            frame_frac: frame_fmt.frac_bits,
            bg_i: f.bg.1,
            size: (width, height),
        },
    );
    enc_report.float_ms += ms_since(t);
    enc_report.record_work(&[
        ("pixels", work.pixels),
        ("term_adds", work.term_adds),
        ("log_adds", work.log_adds),
        ("saturations", work.saturations),
    ]);
    enc_report.signals.extend([
        add.log_w_stats.clone(),
        add.sb_stats.clone(),
        work.term,
        work.frame,
    ]);
    let c = add.cost(npix as u64);
    enc_report.cost.storage_bits += c.storage_bits;
    enc_report.cost.lut_bits += c.lut_bits;
    enc_report.cost.adders.extend(c.adders);
    enc_report.cost.multipliers.extend(c.multipliers);
    for (key, v) in [
        ("frame_bits", add.frame_bits() as u64),
        ("frame_offset", add.off as u64),
        ("sb_table_entries", add.sb.len() as u64),
        ("sb_table_data_bits", add.table_data_bits() as u64),
        ("sb_address_shift", add.shift as u64),
    ] {
        enc_report.notes.insert(key.into(), v.into());
    }
    // The cycle model's plan: the same touched tiles as the linear path. Structure (b)
    // accumulates a pixel's log sums in a register and writes the frame word once, so each
    // touched pixel is one frame write.
    let tiles = crate::cycles::Tiles::touched_by(
        hw.cycles.tile,
        &f.region,
        k,
        &g.samples,
        &g.points,
        width,
        height,
    );
    let tile_rmw = (0..tiles.rows)
        .flat_map(|r| (0..tiles.cols).map(move |c| (r, c)))
        .map(|(r, c)| {
            if !tiles.touched[(r * tiles.cols + c) as usize] {
                return 0;
            }
            let w = tiles.size.min(width - c * tiles.size) as u64;
            let h = tiles.size.min(height - r * tiles.size) as u64;
            w * h
        })
        .collect();
    Ok((
        Accumulated {
            frame,
            frame_ref,
            report: StageReport::default(),
            tiles,
            tile_rmw,
        },
        add,
    ))
}

/// Structure (b) post stage: the eq. 15 gamma LUT on the log frame; the float image goes
/// through the spine's float gamma.
pub fn post(
    a: &Accumulated,
    add: &LogAdder,
    scene: &Scene,
    hw: &HwConfig,
    opts: RenderOptions,
) -> Post {
    let gamma_value = hw.gamma.gamma.unwrap_or(scene.display.gamma);
    let spec = GammaSpec::new(
        gamma_value,
        hw.gamma.correction,
        hw.gamma.dac_bits,
        hw.gamma.quant,
    );
    let mut r = StageReport {
        name: "gamma".into(),
        ..Default::default()
    };
    let t = Instant::now();
    let lut = log_gamma_lut(add, &spec);
    let max = lut.len() - 1;
    let dac: Vec<u16> = a
        .frame
        .acc
        .par_iter()
        .map(|&c| lut[(c as usize).min(max)])
        .collect();
    r.fixed_ms = ms_since(t);
    r.work.insert("lookups".into(), dac.len() as u64);
    r.work.insert("lut_entries".into(), lut.len() as u64);
    let fb = add.frame_bits();
    r.cost = Cost {
        lut_bits: lut.len() as u64 * hw.gamma.dac_bits as u64,
        adders: vec![Unit::adder("LUT address", 1, fb)],
        ..Cost::default()
    };
    r.notes.insert(
        "monotone".into(),
        lut.windows(2).all(|w| w[0] <= w[1]).into(),
    );
    r.notes.insert("log_input_eq15".into(), true.into());
    if opts.stage_local {
        let mut e = LocalError::default();
        for (&c, &d) in a.frame.acc.iter().zip(&dac) {
            e.add(d as f64, spec.ideal(log_gamma_linear(add, c as i64)));
        }
        r.local = Some(e.finish());
    }
    let t = Instant::now();
    let frame_fmt = hw.accumulate.frame.format;
    let white = frame_fmt.max_code() >> frame_fmt.frac_bits;
    let white_lsb = white as f64 * (1u64 << frame_fmt.frac_bits) as f64;
    let mut dac_ref = vec![0u16; a.frame_ref.len()];
    crate::stage::gamma::apply_f64(&spec, &a.frame_ref, white_lsb, &mut dac_ref);
    r.float_ms = ms_since(t);
    Post {
        dac,
        dac_ref,
        reports: vec![r],
    }
}
