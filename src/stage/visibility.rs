//! Visibility: a per-sample z-buffer in the configured depth format.
//!
//! Surfaces (triangles, lines) are depth-tested with strict `<` (on equal depth the
//! primitive that came first stays) and write depth, primitive id and intensity.
//! Light points are tested against the finished surface buffer and never write: they are
//! added to the frame by the accumulate stage, as light points are in image generators.

use super::raster::{Frag, FragF, SampleRegion};
use crate::fixed::{Quant, round_shift_i64};

/// Primitive id of the background (samples no surface covered).
pub const BACKGROUND: u32 = 0;

/// The fixed sample buffer: one entry per sample of the region.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Samples {
    /// Region covered.
    pub reg: SampleRegion,
    /// Depth codes (z-buffer format); `u32::MAX` is "nothing", behind every code.
    pub z: Vec<u32>,
    /// Winning primitive id (`index + 1`), `BACKGROUND` for none.
    pub prim: Vec<u32>,
    /// Intensity codes (the background's code where no surface won).
    pub i: Vec<u32>,
}

impl Samples {
    /// A cleared buffer.
    pub fn new(reg: SampleRegion, background_i: u32) -> Self {
        let n = reg.len();
        Self {
            reg,
            z: vec![u32::MAX; n],
            prim: vec![BACKGROUND; n],
            i: vec![background_i; n],
        }
    }
}

/// The float sample buffer.
#[derive(Clone, Debug, PartialEq)]
pub struct SamplesF {
    /// Region covered.
    pub reg: SampleRegion,
    /// Depth in input z-format LSBs; `inf` is "nothing".
    pub z: Vec<f64>,
    /// Winning primitive id.
    pub prim: Vec<u32>,
    /// Intensity in intensity-format LSBs.
    pub i: Vec<f64>,
}

impl SamplesF {
    /// A cleared buffer.
    pub fn new(reg: SampleRegion, background_i: f64) -> Self {
        let n = reg.len();
        Self {
            reg,
            z: vec![f64::INFINITY; n],
            prim: vec![BACKGROUND; n],
            i: vec![background_i; n],
        }
    }
}

/// Depth conversion from the interpolated format to the z-buffer format.
#[derive(Clone, Copy, Debug)]
pub struct ZConvert {
    /// Fraction bits dropped.
    pub shift: u32,
    /// Rounding.
    pub quant: Quant,
    /// Largest z-buffer code.
    pub max: u32,
}

impl ZConvert {
    /// Converts one depth code; counts a clamp at the top of the range.
    #[inline]
    pub fn apply(&self, z: u32, clamped: &mut u64) -> u32 {
        let v = round_shift_i64(z as i64, self.shift, self.quant);
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

/// Depth-tests the fragments of surface `prim` into the buffer.
pub fn resolve(frags: &[Frag], prim: u32, zc: &ZConvert, buf: &mut Samples, w: &mut VisWork) {
    for f in frags {
        let s = f.s as usize;
        let z = zc.apply(f.z, &mut w.clamped);
        if z < buf.z[s] {
            buf.z[s] = z;
            buf.prim[s] = prim;
            buf.i[s] = f.i;
            w.writes += 1;
        }
    }
    w.tests += frags.len() as u64;
}

/// Visible samples of a light point (tested, not written).
pub fn point_visible(frags: &[Frag], zc: &ZConvert, buf: &Samples, w: &mut VisWork) -> Vec<u32> {
    let mut out = Vec::with_capacity(frags.len());
    for f in frags {
        let z = zc.apply(f.z, &mut w.clamped);
        if z < buf.z[f.s as usize] {
            out.push(f.s);
        }
    }
    w.point_tests += frags.len() as u64;
    w.point_visible += out.len() as u64;
    out
}

/// Float reference: depth test without quantisation.
pub fn resolve_f64(frags: &[FragF], prim: u32, buf: &mut SamplesF) {
    for f in frags {
        let s = f.s as usize;
        if f.z < buf.z[s] {
            buf.z[s] = f.z;
            buf.prim[s] = prim;
            buf.i[s] = f.i;
        }
    }
}

/// Float reference of light-point visibility.
pub fn point_visible_f64(frags: &[FragF], buf: &SamplesF) -> Vec<(u32, f64)> {
    frags
        .iter()
        .filter(|f| f.z < buf.z[f.s as usize])
        .map(|f| (f.s, f.i))
        .collect()
}
