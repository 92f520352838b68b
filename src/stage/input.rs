//! Input quantisation: screen-space vertices from the host (f64) to fixed point.
//!
//! x and y get the configured sub-pixel bits, z the depth format, the intensity the
//! accumulator's code scale (full white = `2^int_bits - 1`) with extra fraction bits.
//! Line widths and light-point sizes are quantised to the coordinate grid too.
//! The float reference of this stage is the host's value itself.

use super::raster::{FPrim, FVertex};
use super::taps::{Prims, PrimsF, Taps, processing_order};
use super::{
    Cost, Cx, Facts, LocalError, MemImage, Need, Notes, Stage, StageId, TokenKind, Tokens, Unit,
};
use crate::config::HwConfig;
use crate::error::{Error, Result};
use crate::fixed::{Overflow, Quantizer, SignalStats};
use crate::scene::{HostScene, Primitive, Scene, ScreenVertex};
use rayon::prelude::*;
use std::sync::Arc;

/// A quantised vertex: raw codes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct QVertex {
    /// x in units of `2^-sub_bits` pixel.
    pub x: i64,
    /// y in units of `2^-sub_bits` pixel.
    pub y: i64,
    /// Depth code.
    pub z: i64,
    /// Intensity code per channel (channels beyond the render's are 0).
    pub i: [i64; 3],
}

/// A quantised primitive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QPrim {
    /// A triangle (a surface: z-buffered).
    Triangle([QVertex; 3]),
    /// A line of the given width (a surface: drawn as a parallelogram).
    Line {
        /// Start.
        a: QVertex,
        /// End.
        b: QVertex,
        /// Width in coordinate units.
        width: i64,
    },
    /// A light point: a square of side `size` units centred on `v`, added to the frame.
    Point {
        /// Centre.
        v: QVertex,
        /// Side in coordinate units.
        size: i64,
    },
}

/// The quantiser set of the stage with its instrumentation.
struct Quantizers<'a> {
    hw: &'a HwConfig,
    channels: usize,
    x: SignalStats,
    y: SignalStats,
    z: SignalStats,
    /// One per channel.
    i: Vec<SignalStats>,
    local: LocalError,
}

impl Quantizers<'_> {
    fn one(
        q: &Quantizer,
        s: &mut SignalStats,
        local: &mut LocalError,
        exact_lsb: f64,
    ) -> Result<i64> {
        let r = q.quantize_f64(exact_lsb * q.format.lsb());
        let rounded = if r.overflow {
            exact_lsb.round() as i128
        } else {
            r.code as i128
        };
        s.record(exact_lsb, rounded, r.overflow);
        if r.overflow && q.overflow == Overflow::Error {
            return Err(overflow_error(&s.name, q, exact_lsb));
        }
        if !r.overflow {
            local.add(r.code as f64, exact_lsb);
        }
        Ok(r.code)
    }

    fn vertex(&mut self, v: &ScreenVertex) -> Result<QVertex> {
        let c = &self.hw.input.coord;
        let scale = (1u64 << c.format.frac_bits) as f64;
        let zs = (1u64 << self.hw.input.z.format.frac_bits) as f64;
        let x = Self::one(c, &mut self.x, &mut self.local, v.x * scale)?;
        let y = Self::one(c, &mut self.y, &mut self.local, v.y * scale)?;
        let z = Self::one(&self.hw.input.z, &mut self.z, &mut self.local, v.z * zs)?;
        let mut i = [0; 3];
        for (k, code) in i.iter_mut().enumerate().take(self.channels) {
            let q = intensity_quantizer(self.hw, k);
            *code = Self::one(&q, &mut self.i[k], &mut self.local, v.i[k] * white_lsb(&q))?;
        }
        Ok(QVertex { x, y, z, i })
    }

    fn prim(&mut self, p: &Primitive) -> Result<QPrim> {
        Ok(match p {
            Primitive::Triangle(v) => QPrim::Triangle([
                self.vertex(&v[0])?,
                self.vertex(&v[1])?,
                self.vertex(&v[2])?,
            ]),
            Primitive::Line { a, b, width } => QPrim::Line {
                a: self.vertex(a)?,
                b: self.vertex(b)?,
                width: self.length(*width),
            },
            Primitive::Point { v, size } => QPrim::Point {
                v: self.vertex(v)?,
                size: self.length(*size),
            },
        })
    }

    /// Adds a later chunk's statistics.
    fn merge(&mut self, o: &Self) {
        self.x.merge(&o.x);
        self.y.merge(&o.y);
        self.z.merge(&o.z);
        for (a, b) in self.i.iter_mut().zip(&o.i) {
            a.merge(b);
        }
        self.local.merge(&o.local);
    }

    fn length(&mut self, px: f64) -> i64 {
        // Widths and sizes: round to the coordinate grid, at least one unit.
        let units = (px * (1u64 << self.hw.subpixel_bits()) as f64).round();
        units.max(1.0) as i64
    }
}

/// Builds the overflow error for a signal.
pub fn overflow_error(signal: &str, q: &Quantizer, exact_lsb: f64) -> Error {
    Error::Overflow {
        signal: signal.to_string(),
        format: q.format.to_string(),
        value: exact_lsb.round() as i128,
        min: q.format.min_code(),
        max: q.format.max_code(),
    }
}

/// The fixed model's output besides the primitives: instrumentation and the stage-local
/// error (each code against the exact value it quantises, in its LSBs).
pub struct Quantized {
    /// Primitives in scene order.
    pub prims: Vec<QPrim>,
    /// `input.x`, `input.y`, `input.z`, and `input.intensity` ([`intensity_signal`]: one per
    /// channel of a colour render).
    pub signals: Vec<SignalStats>,
    /// Codes against exact values.
    pub local: LocalError,
    /// Vertices quantised.
    pub vertices: u64,
}

/// Fixed model: quantises every primitive of the host scene (the intensity of `channels`
/// channels).
pub fn quantize(host: &HostScene, hw: &HwConfig, channels: usize) -> Result<Quantized> {
    quantize_into(host, hw, channels, Vec::new())
}

/// Primitives per chunk of [`quantize_into`]'s parallel pass.
const CHUNK: usize = 1 << 10;

/// [`quantize`] into the list `out` (one kept from an earlier frame). In chunks of
/// primitives on the threads, each with its own statistics, merged in scene order (the
/// same on any thread count); the first overflow error in scene order is the one returned.
pub fn quantize_into(
    host: &HostScene,
    hw: &HwConfig,
    channels: usize,
    mut out: Vec<QPrim>,
) -> Result<Quantized> {
    let new = || Quantizers {
        hw,
        channels,
        x: SignalStats::new("input.x", hw.input.coord.format),
        y: SignalStats::new("input.y", hw.input.coord.format),
        z: SignalStats::new("input.z", hw.input.z.format),
        i: (0..channels)
            .map(|c| {
                SignalStats::new(
                    &intensity_signal(channels, c),
                    intensity_quantizer(hw, c).format,
                )
            })
            .collect(),
        local: LocalError::default(),
    };
    let blank = QPrim::Point {
        v: QVertex {
            x: 0,
            y: 0,
            z: 0,
            i: [0; 3],
        },
        size: 0,
    };
    out.clear();
    out.resize(host.prims.len(), blank);
    let parts: Vec<Result<Quantizers>> = out
        .par_chunks_mut(CHUNK)
        .zip(host.prims.par_chunks(CHUNK))
        .map(|(out, prims)| {
            let mut qs = new();
            for (o, p) in out.iter_mut().zip(prims) {
                *o = qs.prim(p)?;
            }
            Ok(qs)
        })
        .collect();
    let mut qs = new();
    for part in parts {
        qs.merge(&part?);
    }
    Ok(Quantized {
        prims: out,
        local: std::mem::take(&mut qs.local).finish(),
        signals: [qs.x, qs.y, qs.z].into_iter().chain(qs.i).collect(),
        vertices: host.prims.iter().map(|p| u64::from(vertices_of(p))).sum(),
    })
}

/// Vertices of a primitive (3 triangle, 2 line, 1 light point).
pub fn vertices_of(p: &Primitive) -> u32 {
    match p {
        Primitive::Triangle(_) => 3,
        Primitive::Line { .. } => 2,
        Primitive::Point { .. } => 1,
    }
}

/// The name of channel `c`'s vertex-intensity signal among `channels`: `input.intensity`
/// for a grey render, `input.intensity.r`, `.g` and `.b` for a colour one.
pub fn intensity_signal(channels: usize, c: usize) -> String {
    match channels {
        1 => "input.intensity".to_string(),
        _ => format!("input.intensity.{}", ["r", "g", "b"][c]),
    }
}

/// Channel `c`'s vertex-intensity quantiser (`input.intensity`, or the channel's own width).
pub fn intensity_quantizer(hw: &HwConfig, c: usize) -> Quantizer {
    let mut q = hw.input.intensity;
    if let Some(w) = &hw.channels {
        q.format = w.intensity[c];
    }
    q
}

/// Full white in LSBs of the intensity quantiser `q` (`2^int_bits - 1` integer codes).
fn white_lsb(q: &Quantizer) -> f64 {
    ((1u64 << q.format.int_bits) - 1) as f64 * (1u64 << q.format.frac_bits) as f64
}

/// The background's intensity code per channel (quantised like a vertex intensity).
pub fn background_code(host: &HostScene, hw: &HwConfig) -> [u32; 3] {
    std::array::from_fn(|c| {
        let q = intensity_quantizer(hw, c);
        q.quantize_f64(host.background[c] * white_lsb(&q) * q.format.lsb())
            .code as u32
    })
}

/// Float reference: the host primitive in the fixed formats' units (no rounding).
pub fn fprim(p: &Primitive, hw: &HwConfig) -> FPrim {
    let white: [f64; 3] = std::array::from_fn(|c| white_lsb(&intensity_quantizer(hw, c)));
    let z_scale = (1u64 << hw.input.z.format.frac_bits) as f64;
    let v = |v: &ScreenVertex| FVertex {
        x: v.x,
        y: v.y,
        z: v.z * z_scale,
        i: std::array::from_fn(|c| v.i[c] * white[c]),
    };
    match p {
        Primitive::Triangle(t) => FPrim::Triangle([v(&t[0]), v(&t[1]), v(&t[2])]),
        Primitive::Line { a, b, width } => FPrim::Line {
            a: v(a),
            b: v(b),
            width: *width,
        },
        Primitive::Point { v: c, size } => FPrim::Point {
            v: v(c),
            size: *size,
        },
    }
}

/// The stage's float reference: every host primitive in the fixed formats' units and the
/// background's intensity in intensity LSBs, unrounded.
pub fn float_prims(host: &HostScene, hw: &HwConfig) -> PrimsF {
    let f = host.prims.iter().map(|p| fprim(p, hw)).collect();
    let bg = std::array::from_fn(|c| host.background[c] * white_lsb(&intensity_quantizer(hw, c)));
    PrimsF { f, bg }
}

/// Where a host primitive can touch the screen, from its coordinates quantised with
/// `input.coord` (exactly as the fixed model quantises them): the plan's region and tile
/// bins come from it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Footprint {
    /// Pixel box `[x0, y0, x1, y1)` (not clamped to the screen): the coordinates' bounding
    /// box widened by the line width or point size and by the filter apron.
    pub pixels: [i64; 4],
    /// A triangle's quantised vertices (coordinate units), for an exact overlap test.
    pub triangle: Option<[(i64, i64); 3]>,
}

/// The [`Footprint`]s of the host's primitives with the configured filter's apron (a
/// pixel's window reaches `base / 2 + 1` pixels beyond a sample), in their order: on the
/// threads in parts of 4096 primitives (a scene of fewer runs serially).
pub fn footprints(host: &HostScene, hw: &HwConfig) -> Vec<Footprint> {
    let apron = hw.accumulate.filter.base() as i64 / 2 + 1;
    host.prims
        .par_iter()
        .with_min_len(FOOTPRINT_PART)
        .map(|p| footprint(p, hw, apron))
        .collect()
}

/// Primitives per part of [`footprints`] on the threads.
const FOOTPRINT_PART: usize = 4096;

/// The [`Footprint`] of a host primitive with a filter reaching `apron` pixels beyond a
/// sample.
pub fn footprint(p: &Primitive, hw: &HwConfig, apron: i64) -> Footprint {
    let c = &hw.input.coord;
    let s = c.format.frac_bits;
    let q = |v: &ScreenVertex| (c.quantize_f64(v.x).code, c.quantize_f64(v.y).code);
    let unit = (1u64 << s) as f64;
    let len = |px: f64| ((px * unit).round()).max(1.0) as i64;
    let mut b = [i64::MAX, i64::MAX, i64::MIN, i64::MIN];
    let mut add = |(x, y): (i64, i64), r: i64| {
        b = [
            b[0].min(x - r),
            b[1].min(y - r),
            b[2].max(x + r),
            b[3].max(y + r),
        ];
    };
    let mut triangle = None;
    match p {
        Primitive::Triangle(v) => {
            let t = [q(&v[0]), q(&v[1]), q(&v[2])];
            t.iter().for_each(|&v| add(v, 0));
            triangle = Some(t);
        }
        Primitive::Line { a, b: e, width } => {
            add(q(a), len(*width));
            add(q(e), len(*width));
        }
        Primitive::Point { v, size } => add(q(v), len(*size)),
    }
    Footprint {
        pixels: [
            (b[0] >> s) - apron,
            (b[1] >> s) - apron,
            (b[2] >> s) + 1 + apron,
            (b[3] >> s) + 1 + apron,
        ],
        triangle,
    }
}

/// Whether the closed triangle `t` meets the closed rectangle `r = [x0, y0, x1, y1]`
/// (separating axes: the rectangle's two and the triangle's three edge normals).
pub fn triangle_meets(t: &[(i64, i64); 3], r: [i64; 4]) -> bool {
    let corners = [(r[0], r[1]), (r[2], r[1]), (r[0], r[3]), (r[2], r[3])];
    let span = |pts: &mut dyn Iterator<Item = i128>| {
        pts.fold((i128::MAX, i128::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)))
    };
    let mut axes = vec![(1i128, 0i128), (0, 1)];
    for k in 0..3 {
        let (a, b) = (t[k], t[(k + 1) % 3]);
        axes.push((-((b.1 - a.1) as i128), (b.0 - a.0) as i128));
    }
    axes.into_iter().all(|(nx, ny)| {
        let dot = |(x, y): (i64, i64)| nx * x as i128 + ny * y as i128;
        let (tl, th) = span(&mut t.iter().map(|&v| dot(v)));
        let (rl, rh) = span(&mut corners.iter().map(|&v| dot(v)));
        th >= rl && rh >= tl
    })
}

/// The input stage.
pub struct Input;

impl Stage for Input {
    type Fixed = (LocalError, Vec<u64>);

    fn id(&self) -> StageId {
        StageId::Input
    }

    fn plan(&self, _scene: &Scene, hw: &HwConfig) -> Result<Need> {
        let i = &hw.input;
        Ok(Need::yes(format!(
            "the first modelled stage: vertices to x, y {}, z {}, intensity {}",
            i.coord.format, i.z.format, i.intensity.format
        )))
    }

    fn key(&self, cx: &Cx) -> serde_json::Value {
        serde_json::json!({
            "input": cx.hw.section("input"),
            "guard_band": cx.hw.raster.guard_band,
            "channels": cx.layout.channels,
            // Each channel's own intensity word (`input.intensity` holds channel R's only).
            "channel_intensity": cx.hw.channels.as_ref().map(|w| w.intensity),
        })
    }

    fn fixed(&self, cx: &Cx, taps: &mut Taps) -> Result<(Self::Fixed, Facts)> {
        let host = taps.host();
        let q = quantize_into(host, cx.hw, cx.layout.channels, cx.pool.take(0))?;
        let bg = background_code(host, cx.hw);
        let order = processing_order(
            |i| matches!(host.prims[i], Primitive::Point { .. }),
            host.prims.len(),
        );
        let tokens = order
            .iter()
            .map(|&i| vertices_of(&host.prims[i]) as u64)
            .collect();
        let facts = Facts {
            work: vec![
                ("vertices", q.vertices),
                ("primitives", q.prims.len() as u64),
            ],
            signals: q.signals,
            ..Facts::default()
        };
        taps.fixed.prims = Some(Arc::new(Prims { q: q.prims, bg }));
        Ok(((q.local, tokens), facts))
    }

    fn float(&self, cx: &Cx, _: &Self::Fixed, taps: &mut Taps, _: &mut Notes) -> Result<()> {
        taps.float.prims = Some(Arc::new(float_prims(taps.host(), cx.hw)));
        Ok(())
    }

    fn local(
        &self,
        _: &Cx,
        fixed: &Self::Fixed,
        _: &Taps,
        _: &Taps,
        _: &mut Notes,
    ) -> Option<LocalError> {
        Some(fixed.0.clone())
    }

    fn tokens(&self, _: &Cx, fixed: &Self::Fixed) -> Option<Tokens> {
        Some(Tokens {
            kind: TokenKind::Primitive,
            item: "vertices",
            items: fixed.1.clone(),
            port_bits: vec![],
            rows: vec![],
            stream: None,
        })
    }

    fn cost(&self, cx: &Cx, _: &Self::Fixed) -> Cost {
        let hw = cx.hw;
        let w = |q: &Quantizer| q.format.total_bits();
        Cost::new(
            vec![],
            vec![
                Unit::adder("x/y rounder", 2, w(&hw.input.coord)),
                Unit::adder("z rounder", 1, w(&hw.input.z)),
                Unit::adder(
                    "intensity rounder",
                    cx.layout.channels as u32,
                    w(&hw.input.intensity),
                ),
            ],
            vec![],
        )
    }

    fn memories(&self, _: &Cx, _: &Self::Fixed, _: &Taps) -> Vec<MemImage> {
        vec![]
    }
}
