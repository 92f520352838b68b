//! Input quantisation: screen-space vertices from the host (f64) to fixed point.
//!
//! x and y get the configured sub-pixel bits, z the depth format, the intensity the
//! accumulator's code scale (full white = `2^int_bits - 1`) with extra fraction bits.
//! Line widths and light-point sizes are quantised to the coordinate grid too.
//! The float reference of this stage is the host's value itself.

use super::{Cost, LocalError, StageReport, Unit};
use crate::config::HwConfig;
use crate::error::{Error, Result};
use crate::fixed::{Overflow, Quantizer, SignalStats};
use crate::scene::{HostScene, Primitive, ScreenVertex};

/// A quantised vertex: raw codes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct QVertex {
    /// x in units of `2^-sub_bits` pixel.
    pub x: i64,
    /// y in units of `2^-sub_bits` pixel.
    pub y: i64,
    /// Depth code.
    pub z: i64,
    /// Intensity code.
    pub i: i64,
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
    x: SignalStats,
    y: SignalStats,
    z: SignalStats,
    i: SignalStats,
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
        let white = self.white();
        let zs = (1u64 << self.hw.input.z.format.frac_bits) as f64;
        let is = (1u64 << self.hw.input.intensity.format.frac_bits) as f64;
        Ok(QVertex {
            x: Self::one(c, &mut self.x, &mut self.local, v.x * scale)?,
            y: Self::one(c, &mut self.y, &mut self.local, v.y * scale)?,
            z: Self::one(&self.hw.input.z, &mut self.z, &mut self.local, v.z * zs)?,
            i: Self::one(
                &self.hw.input.intensity,
                &mut self.i,
                &mut self.local,
                v.i * white * is,
            )?,
        })
    }

    fn white(&self) -> f64 {
        ((1u64 << self.hw.input.intensity.format.int_bits) - 1) as f64
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

/// Fixed model: quantises every primitive of the host scene.
pub fn quantize(host: &HostScene, hw: &HwConfig, report: &mut StageReport) -> Result<Vec<QPrim>> {
    let mut qs = Quantizers {
        hw,
        x: SignalStats::new("input.x", hw.input.coord.format),
        y: SignalStats::new("input.y", hw.input.coord.format),
        z: SignalStats::new("input.z", hw.input.z.format),
        i: SignalStats::new("input.intensity", hw.input.intensity.format),
        local: LocalError::default(),
    };
    let mut out = Vec::with_capacity(host.prims.len());
    let mut vertices = 0u64;
    for p in &host.prims {
        out.push(match p {
            Primitive::Triangle(v) => {
                vertices += 3;
                QPrim::Triangle([qs.vertex(&v[0])?, qs.vertex(&v[1])?, qs.vertex(&v[2])?])
            }
            Primitive::Line { a, b, width } => {
                vertices += 2;
                QPrim::Line {
                    a: qs.vertex(a)?,
                    b: qs.vertex(b)?,
                    width: qs.length(*width),
                }
            }
            Primitive::Point { v, size } => {
                vertices += 1;
                QPrim::Point {
                    v: qs.vertex(v)?,
                    size: qs.length(*size),
                }
            }
        });
    }
    report.work.insert("vertices".into(), vertices);
    report.work.insert("primitives".into(), out.len() as u64);
    report.local = Some(std::mem::take(&mut qs.local).finish());
    let w = |q: &Quantizer| q.format.total_bits();
    report.cost = Cost {
        adders: vec![
            Unit::adder("x/y rounder", 2, w(&hw.input.coord)),
            Unit::adder("z rounder", 1, w(&hw.input.z)),
            Unit::adder("intensity rounder", 1, w(&hw.input.intensity)),
        ],
        ..Cost::default()
    };
    report.signals = vec![qs.x, qs.y, qs.z, qs.i];
    Ok(out)
}
