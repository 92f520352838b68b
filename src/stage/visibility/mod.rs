//! Visibility: a per-sample z-buffer in the configured depth format.
//!
//! Surfaces (triangles, lines) are depth-tested with strict `<` (on equal depth the
//! primitive that came first stays) and write depth, primitive id and intensity.
//! Light points are tested against the finished surface buffer and never write: they are
//! added to the frame by the accumulate stage, as light points are in image generators.

use super::accumulate::PointFrags;
use super::input::QPrim;
use super::raster::{Frag, FragF};
use super::taps::{SampleCoding, SampleTap, Taps, processing_order};
use super::{
    Cost, Cx, Facts, LocalError, MemImage, Memory, Need, Notes, SampleRegion, Stage, StageId,
    TokenKind, Tokens, Unit,
};
use crate::config::HwConfig;
use crate::error::Result;
use crate::fixed::{RoundShift, SignalStats};
use crate::scene::Scene;
use rayon::prelude::*;
use std::sync::Arc;

mod float;
mod resolve;
pub use float::{SamplesF, float_samples, point_visible_f64, resolve_f64};
pub use resolve::{RunBounds, resolve};

/// Primitive id of the background (samples no surface covered).
pub const BACKGROUND: u32 = 0;

/// The fixed sample buffer: one entry per sample of the region.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Samples {
    /// Region covered.
    pub reg: SampleRegion,
    /// Depth codes (z-buffer format); `u32::MAX` is "nothing", behind every code. Shared
    /// by the channels of a colour render.
    pub z: Arc<Vec<u32>>,
    /// Winning primitive id (`index + 1`), `BACKGROUND` for none. Shared by the channels of
    /// a colour render.
    pub prim: Arc<Vec<u32>>,
    /// Intensity codes (the background's code where no surface won).
    pub i: Vec<u32>,
}

impl Samples {
    /// A cleared buffer.
    pub fn new(reg: SampleRegion, background_i: u32) -> Self {
        Self::cleared(reg, background_i, &super::Pool::new())
    }

    /// A cleared buffer, its planes from `pool`.
    pub fn cleared(reg: SampleRegion, background_i: u32, pool: &super::Pool) -> Self {
        let n = reg.len();
        Self {
            reg,
            z: pool.filled(n, u32::MAX).into(),
            prim: pool.filled(n, BACKGROUND).into(),
            i: pool.filled(n, background_i),
        }
    }

    /// A buffer whose planes hold whatever their pooled buffers held: every sample must be
    /// set (by [`Part::clear`] over [`parts`] that cover it) before it is read.
    fn uncleared(reg: SampleRegion, pool: &super::Pool) -> Self {
        let n = reg.len();
        Self {
            reg,
            z: pool.scratch(n, 0).into(),
            prim: pool.scratch(n, 0).into(),
            i: pool.scratch(n, 0),
        }
    }
}

/// Depth conversion from the interpolated format to the z-buffer format.
#[derive(Clone, Copy, Debug)]
pub struct ZConvert {
    /// Fraction bits dropped and their rounding.
    pub round: RoundShift,
    /// Largest z-buffer code.
    pub max: u32,
}

impl ZConvert {
    /// Converts one depth code; counts a clamp at the top of the range.
    #[inline]
    pub fn apply(&self, z: u32, clamped: &mut u64) -> u32 {
        let v = self.round.apply(z as i64);
        if v > self.max as i64 {
            *clamped += 1;
            self.max
        } else {
            v as u32
        }
    }
}

/// Work of the visibility stage.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VisWork {
    /// Depth tests of surface samples.
    pub tests: u64,
    /// Tests that passed (read-modify-write of the sample).
    pub writes: u64,
    /// Depth tests of light-point samples.
    pub point_tests: u64,
    /// Light-point samples found visible.
    pub point_visible: u64,
    /// Depths clamped to the top code of the z-buffer format.
    pub clamped: u64,
}

/// One part of the sample buffer: the planes of the rows from sample `s0` on (depth,
/// primitive id, channel 0's intensity, the other channels' intensities).
pub struct Part<'a> {
    s0: usize,
    z: &'a mut [u32],
    prim: &'a mut [u32],
    i: &'a mut [u32],
    extra: Vec<&'a mut [u32]>,
}

/// Splits the buffer (and the other channels' intensity planes `extra`) at the ends of the
/// fragment parts' sample ranges `bounds` (disjoint and in order, as the fixed raster's row
/// bands are): part `j` holds the samples from the previous range's end to range `j`'s end
/// (the last part to the end of the buffer; with no ranges, one part holds the buffer).
pub fn parts<'a>(
    buf: &'a mut Samples,
    extra: &'a mut [Vec<u32>],
    bounds: &[(usize, usize)],
) -> Vec<Part<'a>> {
    let n = buf.z.len();
    let whole = [(0, n)];
    let bounds = if bounds.is_empty() {
        &whole[..]
    } else {
        bounds
    };
    // A buffer being resolved is its own (shared only once finished): no copy here.
    let (z, prim) = (Arc::make_mut(&mut buf.z), Arc::make_mut(&mut buf.prim));
    let (mut z, mut prim, mut i) = (&mut z[..], &mut prim[..], &mut buf.i[..]);
    let mut more: Vec<&mut [u32]> = extra.iter_mut().map(|e| &mut e[..]).collect();
    let mut out = Vec::with_capacity(bounds.len());
    let mut s0 = 0;
    for (j, &(_, end)) in bounds.iter().enumerate() {
        let end = if j + 1 == bounds.len() {
            n
        } else {
            end.clamp(s0, n)
        };
        let k = end - s0;
        let (zh, zt) = std::mem::take(&mut z).split_at_mut(k);
        let (ph, pt) = std::mem::take(&mut prim).split_at_mut(k);
        let (ih, it) = std::mem::take(&mut i).split_at_mut(k);
        let mut heads = Vec::with_capacity(more.len());
        for m in more.iter_mut() {
            let (h, t) = std::mem::take(m).split_at_mut(k);
            heads.push(h);
            *m = t;
        }
        (z, prim, i) = (zt, pt, it);
        out.push(Part {
            s0,
            z: zh,
            prim: ph,
            i: ih,
            extra: heads,
        });
        s0 = end;
    }
    out
}

impl Part<'_> {
    /// Clears the part's samples: nothing in depth, the background's id, and channel
    /// `c`'s background intensity `bg[c]`.
    pub fn clear(&mut self, bg: &[u32]) {
        self.z.fill(u32::MAX);
        self.prim.fill(BACKGROUND);
        self.i.fill(bg[0]);
        for (plane, &b) in self.extra.iter_mut().zip(&bg[1..]) {
            plane.fill(b);
        }
    }
}

/// Visible samples of a light point (tested, not written).
pub fn point_visible(
    frags: impl Iterator<Item = Frag>,
    zc: &ZConvert,
    buf: &Samples,
    w: &mut VisWork,
) -> Vec<u32> {
    let mut out = Vec::new();
    for f in frags {
        let z = zc.apply(f.z, &mut w.clamped);
        w.point_tests += 1;
        if z < buf.z[f.s as usize] {
            out.push(f.s);
        }
    }
    w.point_visible += out.len() as u64;
    out
}

/// The z-buffer conversion of the hardware configuration.
pub fn z_convert(hw: &HwConfig) -> ZConvert {
    ZConvert {
        round: RoundShift::new(
            hw.input.z.format.frac_bits - hw.visibility.z.format.frac_bits,
            hw.visibility.z.quant,
        ),
        max: hw.visibility.z.format.max_code() as u32,
    }
}

/// Bits of a sample's primitive id for `prims` primitives (id 0 is the background).
pub fn id_bits(prims: usize) -> u32 {
    (prims as u64 + 1)
        .next_power_of_two()
        .trailing_zeros()
        .max(1)
}

/// The sample buffer's memory: one word per sample the filter windows of the screen's pixels
/// read (the screen's samples plus the filter's apron beyond the edges,
/// which the raster writes inside the guard band), holding the depth code, the stored
/// intensity code (`intensity_bits`: the log code's width under log coding) and the
/// primitive id.
pub fn sample_buffer(cx: &Cx, prims: usize, intensity_bits: u32) -> Memory {
    let zb = cx.hw.visibility.z.format.total_bits();
    // The filter windows reach `size - n` samples beyond the screen's, split over both edges.
    let k = super::accumulate::kernel(cx.hw);
    let apron = (k.size - k.n as usize) as u64;
    let g = &cx.layout.grid;
    Memory::ram(
        SAMPLE_BUFFER,
        (g.sw() as u64 + apron) * (g.sh() as u64 + apron),
        zb + intensity_bits + id_bits(prims),
    )
}

/// Bits of a sample's stored intensity: every channel's `input.intensity` word.
fn intensity_bits(cx: &Cx) -> u32 {
    (0..cx.layout.channels)
        .map(|c| {
            super::input::intensity_quantizer(cx.hw, c)
                .format
                .total_bits()
        })
        .sum()
}

/// Name of the sample buffer memory.
pub const SAMPLE_BUFFER: &str = "sample buffer";

/// The sample buffer's modelled region as a memory image (depth, each channel's intensity
/// of `channels` (its sample tap and stored width), id). An empty sample ("nothing",
/// `u32::MAX` in the model) is stored as the far code (all ones) with the background id.
pub fn sample_image(cx: &Cx, channels: Vec<(Arc<SampleTap>, u32)>, prims: usize) -> MemImage {
    let zb = cx.hw.visibility.z.format.total_bits();
    let zmax = cx.hw.visibility.z.format.max_code() as u64;
    let mut fields = vec![zb];
    fields.extend(channels.iter().map(|c| c.1));
    fields.push(id_bits(prims));
    let n = channels.len();
    let taps: Vec<Arc<SampleTap>> = channels.into_iter().map(|c| c.0).collect();
    MemImage {
        name: SAMPLE_BUFFER.into(),
        fields,
        words: taps[0].samples.z.len(),
        region_only: true,
        get: Arc::new(move |r, k| match k {
            0 => (taps[0].samples.z[r] as u64).min(zmax),
            k if k <= n => taps[k - 1].samples.i[r] as u64,
            _ => taps[0].samples.prim[r] as u64,
        }),
    }
}

/// The visibility stage.
pub struct Visibility;

impl Stage for Visibility {
    /// Depth tests per primitive (processing order).
    type Fixed = Vec<u64>;

    fn id(&self) -> StageId {
        StageId::Visibility
    }

    fn plan(&self, _: &Scene, hw: &HwConfig) -> Result<Need> {
        Ok(Need::yes(format!(
            "surfaces are depth-tested per sample in a {} z-buffer",
            hw.visibility.z.format
        )))
    }

    fn key(&self, cx: &Cx) -> serde_json::Value {
        serde_json::json!({
            "visibility": cx.hw.section("visibility"),
            // The sample buffer's cost moves to logdomain when the samples are log coded;
            // its apron follows the filter.
            "log_coded": cx.layout.has(StageId::Logdomain),
            "filter": cx.hw.accumulate.filter,
        })
    }

    fn fixed(&self, cx: &Cx, taps: &mut Taps) -> Result<(Vec<u64>, Facts)> {
        let zc = z_convert(cx.hw);
        let prims = taps.fixed.prims();
        let frags = taps.fixed.frags();
        let mut w = VisWork::default();
        let reg = cx.layout.samples;
        let channels = cx.layout.channels;
        // The planes are cleared part by part on the threads that resolve into them.
        let mut buf = Samples::uncleared(reg, cx.pool);
        let mut extra: Vec<Vec<u32>> = (1..channels)
            .map(|_| cx.pool.scratch(reg.len(), 0))
            .collect();
        let bg_codes = prims.bg;
        let n = prims.q.len();
        let surface = |p: usize| !matches!(prims.q[p], QPrim::Point { .. });
        // The raster's parts are bands of sample rows: each part of the buffer resolves its
        // own band's fragments, surface by surface in primitive order; the counts are
        // integers summed in part order.
        let codes = &frags.codes;
        let bounds = RunBounds::new(codes, &zc);
        let mut cut = parts(&mut buf, &mut extra, &frags.runs.bounds);
        // Parts without fragments (none when the raster's bands cover the region) are
        // cleared here.
        for part in cut.iter_mut().skip(frags.runs.parts.len()) {
            part.clear(&bg_codes);
        }
        let done: Vec<(VisWork, Vec<(u32, u64)>)> = cut
            .into_par_iter()
            .zip(frags.runs.parts.par_iter().zip(&frags.runs.spans))
            // One part per task: a thread done early takes the next part.
            .with_max_len(1)
            .map(|(mut part, (data, spans))| {
                part.clear(&bg_codes);
                let mut wk = VisWork::default();
                let mut tested = Vec::with_capacity(spans.len());
                for sp in spans.iter().filter(|sp| surface(sp.prim as usize)) {
                    let before = wk.tests;
                    resolve(
                        &data[sp.a..sp.b],
                        (codes, &bounds),
                        sp.prim + 1,
                        &zc,
                        &mut part,
                        &mut wk,
                    );
                    tested.push((sp.prim, wk.tests - before));
                }
                (wk, tested)
            })
            .collect();
        let mut tests = vec![0u64; n];
        for (wk, tested) in done {
            w.tests += wk.tests;
            w.writes += wk.writes;
            w.clamped += wk.clamped;
            for (p, k) in tested {
                tests[p as usize] += k;
            }
        }
        let i_max: Vec<i64> = (0..channels)
            .map(|c| {
                super::input::intensity_quantizer(cx.hw, c)
                    .format
                    .max_code()
            })
            .collect();
        let mut points = vec![Vec::new(); channels];
        for (p, q) in prims.q.iter().enumerate() {
            let QPrim::Point { v, .. } = q else { continue };
            let before = w.point_tests;
            let vis = point_visible(frags.of(p), &zc, &buf, &mut w);
            tests[p] = w.point_tests - before;
            for (c, pts) in points.iter_mut().enumerate() {
                pts.push(PointFrags {
                    i: v.i[c].clamp(0, i_max[c]) as u32,
                    samples: vis.clone(),
                });
            }
        }
        let order = processing_order(|i| matches!(prims.q[i], QPrim::Point { .. }), n);
        let tokens = order.iter().map(|&i| tests[i]).collect();
        let zst =
            SignalStats::overflow_counter("visibility.z", cx.hw.visibility.z.format, w.clamped);
        let mut facts = Facts {
            work: vec![
                ("tests", w.tests),
                ("writes", w.writes),
                ("point_tests", w.point_tests),
                ("point_visible", w.point_visible),
            ],
            signals: vec![zst],
            ..Facts::default()
        };
        facts.note("samples_in_region", cx.layout.samples.len() as u64);
        let bg = prims.bg;
        let mut points = points.into_iter();
        let mut tap = |c: usize, samples: Samples| {
            Arc::new(SampleTap {
                samples,
                points: points.next().expect("one list per channel"),
                bg: bg[c],
                coding: SampleCoding::Linear,
            })
        };
        // Channels 1.. share the depth and the winning primitive of every sample (the
        // planes, not copies of them).
        let more: Vec<Samples> = extra
            .into_iter()
            .map(|i| Samples {
                reg,
                z: buf.z.clone(),
                prim: buf.prim.clone(),
                i,
            })
            .collect();
        taps.fixed.samples = Some(tap(0, buf));
        taps.fixed.more_samples = more
            .into_iter()
            .enumerate()
            .map(|(c, s)| tap(c + 1, s))
            .collect();
        Ok((tokens, facts))
    }

    fn float(&self, cx: &Cx, _: &Vec<u64>, taps: &mut Taps, _: &mut Notes) -> Result<()> {
        let mut s = float_samples(
            taps.float.prims(),
            taps.float.frags(),
            cx.layout.samples,
            cx.layout.channels,
        )
        .into_iter()
        .map(Arc::new);
        taps.float.samples = s.next();
        taps.float.more_samples = s.collect();
        Ok(())
    }

    /// A float z-buffer fed the fixed raster's fragments (in sample order per primitive):
    /// samples won by a different primitive are mismatched items.
    fn local(
        &self,
        _: &Cx,
        _: &Vec<u64>,
        _: &Taps,
        out: &Taps,
        _: &mut Notes,
    ) -> Option<LocalError> {
        let prims = out.fixed.prims();
        let frags = out.fixed.frags();
        let fixed = &out.fixed.samples().samples;
        let mut shadow = SamplesF::new(fixed.reg, prims.bg[0] as f64);
        let mut exact: Vec<FragF> = Vec::new();
        for (p, q) in prims.q.iter().enumerate() {
            if matches!(q, QPrim::Point { .. }) {
                continue;
            }
            exact.clear();
            exact.extend(frags.of(p).map(|x| FragF {
                s: x.s,
                z: x.z as f64,
                i: x.i.map(|i| i as f64),
            }));
            exact.sort_by_key(|x| x.s);
            resolve_f64(&exact, p as u32 + 1, &mut shadow, &mut []);
        }
        let mut e = LocalError::default();
        for (a, b) in fixed.prim.iter().zip(&shadow.prim) {
            e.values += 1;
            if a == b {
                e.identical += 1;
            } else {
                e.mismatched_items += 1;
            }
        }
        Some(e)
    }

    fn tokens(&self, _: &Cx, tests: &Vec<u64>) -> Option<Tokens> {
        Some(Tokens {
            kind: TokenKind::Primitive,
            item: "depth tests",
            items: tests.clone(),
            port_bits: vec![],
            rows: vec![],
            stream: None,
        })
    }

    fn cost(&self, cx: &Cx, tests: &Vec<u64>) -> Cost {
        let zb = cx.hw.visibility.z.format.total_bits();
        let memories = if cx.layout.has(StageId::Logdomain) {
            vec![]
        } else {
            vec![sample_buffer(cx, tests.len(), intensity_bits(cx))]
        };
        Cost::new(memories, vec![Unit::adder("depth compare", 1, zb)], vec![])
    }

    fn memories(&self, cx: &Cx, tests: &Vec<u64>, out: &Taps) -> Vec<MemImage> {
        if cx.layout.has(StageId::Logdomain) {
            return vec![];
        }
        let s = out
            .fixed
            .samples
            .clone()
            .expect("visibility wrote the samples");
        let channels = std::iter::once(s)
            .chain(out.fixed.more_samples.iter().cloned())
            .enumerate()
            .map(|(c, t)| {
                let q = super::input::intensity_quantizer(cx.hw, c);
                (t, q.format.total_bits())
            })
            .collect();
        vec![sample_image(cx, channels, tests.len())]
    }
}
