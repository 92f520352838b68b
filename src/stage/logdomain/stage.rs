//! The logdomain stage through the contract: the encoder turns the sample buffer's linear
//! codes into log codes where they are stored; structure (a) then potentiates them back to
//! linear codes for the linear accumulate, structure (b) leaves them for the log-domain
//! accumulate. The float reference is the spine's linear one (unchanged here); the
//! stage-local comparison is against the exact log (or linear) value of each input code.

use super::{LogCode, LogEncoder, PotentiationLut, check_contrast};
use crate::config::{CodingKind, HwConfig};
use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::stage::input::QPrim;
use crate::stage::taps::{SampleCoding, SampleTap, Taps, processing_order};
use crate::stage::visibility::{SAMPLE_BUFFER, sample_buffer, sample_image};
use crate::stage::{
    Cost, Cx, Facts, LocalError, MemImage, Need, Notes, Stage, StageId, TokenKind, Tokens,
};
use rayon::prelude::*;
use std::sync::Arc;

/// The log code of a scene and hardware config (K from the scene's display block).
pub fn log_code(scene: &Scene, hw: &HwConfig) -> Result<LogCode> {
    let k = scene.display.contrast;
    check_contrast(k).map_err(|msg| Error::File(scene.error("display.contrast", msg)))?;
    Ok(LogCode {
        k,
        bits: hw.coding.log_bits,
    })
}

/// What the fixed model leaves: the encoder, the potentiation LUT (structure a) and the
/// log-coded sample buffer as stored.
pub struct Encoded {
    enc: Arc<LogEncoder>,
    lut: Option<Arc<PotentiationLut>>,
    stored: Arc<SampleTap>,
    prims: usize,
    /// The colour lane (0 for grey): lanes after R store only their code in the shared
    /// sample buffer word.
    lane: usize,
    /// Codes encoded per primitive, in processing order: one per depth test of a surface
    /// (the encoder sits on the sample buffer's write port, beside each test lane), one per
    /// light point (its intensity, encoded once).
    codes: Vec<u64>,
}

/// The logdomain stage.
pub struct Logdomain;

/// The code field alone of a colour lane after R in the sample buffer (the words of
/// [`sample_image`], one field of `bits`).
fn code_image(stored: Arc<SampleTap>, bits: u32) -> MemImage {
    MemImage {
        name: SAMPLE_BUFFER.into(),
        fields: vec![bits],
        words: stored.samples.z.len(),
        region_only: true,
        get: Arc::new(move |r, _| stored.samples.i[r] as u64),
    }
}

fn white_i(hw: &HwConfig) -> u64 {
    let f = hw.input.intensity.format;
    ((1u64 << f.int_bits) - 1) << f.frac_bits
}

impl Stage for Logdomain {
    type Fixed = Encoded;

    fn id(&self) -> StageId {
        StageId::Logdomain
    }

    fn plan(&self, _: &Scene, hw: &HwConfig) -> Result<Need> {
        let b = hw.coding.log_bits;
        Ok(match hw.coding.kind {
            CodingKind::Linear => {
                Need::no("coding.kind = \"linear\": samples and frame keep linear codes")
            }
            CodingKind::LogPotentiate => Need::yes(format!(
                "coding.kind = \"log-potentiate\": {b}-bit log-coded samples, potentiated to linear codes before the filter"
            )),
            CodingKind::LogAdd => Need::yes(format!(
                "coding.kind = \"log-add\": {b}-bit log-coded samples, summed by the log adder"
            )),
        })
    }

    fn key(&self, cx: &Cx) -> serde_json::Value {
        // The encoder and the potentiation LUT read the kind and the code width; the log
        // adder's fields (acc_frac_bits, the sb table, quant, overflow) are the accumulate
        // stage's.
        let c = &cx.hw.coding;
        serde_json::json!({
            "kind": c.kind,
            "log_bits": c.log_bits,
            "display": cx.scene.display,
            // The potentiation LUT's width; the sample buffer's apron.
            "frame_int_bits": cx.hw.accumulate.frame.format.int_bits,
            "filter": cx.hw.accumulate.filter,
        })
    }

    fn fixed(&self, cx: &Cx, taps: &mut Taps) -> Result<(Encoded, Facts)> {
        let hw = cx.hw;
        let code = log_code(cx.scene, hw)?;
        let i_fmt = hw.input.intensity.format;
        let enc = Arc::new(LogEncoder::new(code, white_i(hw), i_fmt.total_bits()));
        let input = taps.fixed.samples();
        let mut stored = input.clone();
        stored
            .samples
            .i
            .par_iter_mut()
            .for_each(|v| *v = enc.encode(*v as u64));
        for p in stored.points.iter_mut() {
            p.i = enc.encode(p.i as u64);
        }
        stored.bg = enc.encode(stored.bg as u64);
        stored.coding = SampleCoding::Log(code);
        let stored = Arc::new(stored);
        let encoded = input.samples.i.len() as u64 + input.points.len() as u64 + 1;
        let mut facts = Facts {
            signals: vec![enc.stats.clone()],
            ..Facts::default()
        };
        let (out, lut, potentiations) = if hw.coding.kind == CodingKind::LogPotentiate {
            let frame_bits = hw.accumulate.frame.format.int_bits;
            let lut = PotentiationLut::build(code, frame_bits);
            let sh = i_fmt.frac_bits;
            let pot = |c: u32| lut.table[c as usize] << sh;
            let mut lin = (*stored).clone();
            lin.samples.i.par_iter_mut().for_each(|v| *v = pot(*v));
            for p in lin.points.iter_mut() {
                p.i = pot(p.i);
            }
            lin.bg = pot(lin.bg);
            lin.coding = SampleCoding::Linear;
            let max_lut = (0..=code.grades())
                .map(|c| {
                    (lut.table[c as usize] as f64 - PotentiationLut::exact(code, frame_bits, c))
                        .abs()
                })
                .fold(0.0, f64::max);
            facts.note("potentiation_lut_max_error_lsb", max_lut);
            facts.signals.push(lut.stats.clone());
            (Arc::new(lin), Some(Arc::new(lut)), encoded)
        } else {
            (stored.clone(), None, 0)
        };
        let ib = i_fmt.total_bits();
        let full = sample_buffer(cx, taps.fixed.prims().q.len(), ib).depth;
        facts.note(
            "sample_buffer_bits_saved",
            full * (ib - code.bits.min(ib)) as u64,
        );
        facts.note("log_grades", code.grades());
        facts.note("grade_luminance_ratio", code.step_ratio());
        let d = &cx.scene.display;
        facts.note(
            "scene_grades_needed_eq11",
            d.contrast.ln() / d.weber.ln_1p(),
        );
        facts.work = vec![("encoded", encoded), ("potentiations", potentiations)];
        taps.fixed.samples = Some(out);
        let q = &taps.fixed.prims().q;
        let is_point = |p: usize| matches!(q[p], QPrim::Point { .. });
        let frags = taps.fixed.frags();
        let codes = processing_order(is_point, q.len())
            .into_iter()
            .map(|p| {
                if is_point(p) {
                    1
                } else {
                    frags.count(p) as u64
                }
            })
            .collect();
        Ok((
            Encoded {
                enc,
                lut,
                stored,
                prims: q.len(),
                lane: taps.lane,
                codes,
            },
            facts,
        ))
    }

    fn float(&self, _: &Cx, _: &Encoded, _: &mut Taps, _: &mut Notes) -> Result<()> {
        // The float reference stays on the spine's exact linear intensities.
        Ok(())
    }

    /// Each output code against the exact value of its linear input: the log code
    /// `G log_K(1 + (K - 1) x)` (structure b) or, potentiated, the linear input in the
    /// potentiated code's LSBs (structure a).
    fn local(
        &self,
        cx: &Cx,
        e: &Encoded,
        input: &Taps,
        out: &Taps,
        _: &mut Notes,
    ) -> Option<LocalError> {
        let hw = cx.hw;
        let lin_in = &input.fixed.samples().samples.i;
        let got = &out.fixed.samples().samples.i;
        let code = e.enc.code;
        let white = white_i(hw) as f64;
        let mut err = LocalError::default();
        if e.lut.is_some() {
            let frame_bits = hw.accumulate.frame.format.int_bits;
            let sh = hw.input.intensity.format.frac_bits;
            let scale = ((1u64 << frame_bits) - 1) as f64 / white;
            for (&a, &b) in got.iter().zip(lin_in) {
                err.add((a >> sh) as f64, b as f64 * scale);
            }
        } else {
            for (&a, &b) in got.iter().zip(lin_in) {
                let exact = code.log_of_linear(b as f64 / white) * code.grades() as f64;
                err.add(a as f64, exact);
            }
        }
        Some(err.finish())
    }

    fn tokens(&self, _: &Cx, e: &Encoded) -> Option<Tokens> {
        Some(Tokens {
            kind: TokenKind::Primitive,
            item: "codes",
            items: e.codes.clone(),
            port_bits: vec![],
            rows: vec![],
            stream: None,
        })
    }

    /// The encoder (threshold ROM and comparator), the potentiation LUT (structure a) and the
    /// sample buffer, which stores the log code. A colour render's sample word holds the
    /// depth, the id and each channel's code once: lane R charges the depth and the id with
    /// its code, lanes G and B their code alone.
    fn cost(&self, cx: &Cx, e: &Encoded) -> Cost {
        let ib = cx.hw.input.intensity.format.total_bits();
        let mut c = e.enc.cost();
        if let Some(l) = &e.lut {
            c = c.merge(l.cost());
        }
        let code = e.enc.code.bits.min(ib);
        let mut buffer = sample_buffer(cx, e.prims, code);
        if e.lane > 0 {
            buffer.width = code;
        }
        c.merge(Cost::new(vec![buffer], vec![], vec![]))
    }

    fn memories(&self, cx: &Cx, e: &Encoded, _: &Taps) -> Vec<MemImage> {
        let ib = cx.hw.input.intensity.format.total_bits();
        let mut v = vec![e.enc.image()];
        if let Some(l) = &e.lut {
            v.push(l.image());
        }
        let code = e.enc.code.bits.min(ib);
        v.push(if e.lane > 0 {
            code_image(e.stored.clone(), code)
        } else {
            sample_image(cx, vec![(e.stored.clone(), code)], e.prims)
        });
        v
    }
}
