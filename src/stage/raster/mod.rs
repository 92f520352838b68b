//! Raster: Bresenham-style edge walking with add-only interpolation ([`fixed`]), and the
//! float reference evaluating the same top-left rule and the exact attribute planes in f64
//! at the same sample positions ([`float`]).
//!
//! The stage emits, per primitive, the samples it covers (a fragment: sample index, depth
//! and intensity codes) in the order the walker visits them, held as runs, one per span
//! ([`runs`]); visibility resolves them, taking each sample's codes from the run.

pub mod fixed;
pub mod float;
mod parts;
pub mod runs;

pub use fixed::{
    RasterParams, RasterWork, RunSink, raster, raster_point, raster_rows, raster_tri,
    raster_tri_rows,
};
pub use float::{FPrim, FVertex, raster_f64, raster_tri_f64};
pub use parts::{PART_ROWS, walk};
pub use runs::{FragRuns, Run, RunCodes};

pub use super::SampleRegion;
use super::input::QPrim;
use super::taps::{Frags, Taps, processing_order};
use super::{
    Cost, Cx, Facts, LocalError, MemImage, Need, Notes, Stage, StageId, TokenKind, Tokens, Unit,
};
use crate::config::HwConfig;
use crate::error::Result;
use crate::fixed::SignalStats;
use crate::scene::Scene;
use std::sync::Arc;

/// One covered sample of one primitive: buffer index, depth and intensity codes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frag {
    /// Index in the sample region.
    pub s: u32,
    /// Depth, input z-format code.
    pub z: u32,
    /// Intensity per channel, intensity-format codes (unused channels 0).
    pub i: [u32; 3],
}

/// Float fragment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FragF {
    /// Index in the sample region.
    pub s: u32,
    /// Depth in input z-format LSBs.
    pub z: f64,
    /// Intensity per channel in intensity-format LSBs.
    pub i: [f64; 3],
}

/// The raster's parameters from the hardware configuration.
pub fn params(cx: &Cx) -> RasterParams {
    let hw = cx.hw;
    RasterParams {
        grid: cx.layout.grid,
        guard: hw.raster.interp_guard_bits,
        quant: hw.raster.interp_quant,
        i_max: std::array::from_fn(|c| {
            crate::stage::input::intensity_quantizer(hw, c)
                .format
                .max_code()
        }),
        z_max: hw.input.z.format.max_code(),
        channels: cx.layout.channels,
    }
}

/// The stage's float reference: every float primitive's covered samples of `reg`, in
/// primitive order (`capacity`: the fragments to reserve room for).
pub fn float_frags(
    prims: &[FPrim],
    grid: &super::Grid,
    reg: &SampleRegion,
    capacity: usize,
) -> Frags<FragF> {
    Frags::one_part(prims.len(), Vec::with_capacity(capacity), |p, out| {
        raster_f64(&prims[p], grid, reg, out)
    })
}

/// Merges two fragment lists sorted by sample index: coverage mismatches and attribute errors.
fn compare_frags(
    fx: &[Frag],
    fl: &[FragF],
    channels: usize,
    i_err: &mut LocalError,
    z_err: &mut LocalError,
) {
    let (mut a, mut b) = (0, 0);
    while a < fx.len() || b < fl.len() {
        if a < fx.len() && b < fl.len() && fx[a].s == fl[b].s {
            for c in 0..channels {
                i_err.add(fx[a].i[c] as f64, fl[b].i[c]);
            }
            z_err.add(fx[a].z as f64, fl[b].z);
            a += 1;
            b += 1;
        } else if b >= fl.len() || (a < fx.len() && fx[a].s < fl[b].s) {
            i_err.mismatched_items += 1;
            a += 1;
        } else {
            i_err.mismatched_items += 1;
            b += 1;
        }
    }
}

/// The raster stage.
pub struct Raster;

impl Stage for Raster {
    /// Sample positions stepped per primitive (processing order).
    type Fixed = Vec<u64>;

    fn id(&self) -> StageId {
        StageId::Raster
    }

    fn plan(&self, _: &Scene, hw: &HwConfig) -> Result<Need> {
        let n = hw.raster.samples;
        Ok(Need::yes(format!(
            "covers a {n}x{n} sample grid per pixel by edge walking (adds and compares only)"
        )))
    }

    fn key(&self, cx: &Cx) -> serde_json::Value {
        serde_json::json!({
            "raster": cx.hw.section("raster"),
            "grid": cx.layout.grid,
            "samples": cx.layout.samples,
        })
    }

    fn fixed(&self, cx: &Cx, taps: &mut Taps) -> Result<(Vec<u64>, Facts)> {
        let p = params(cx);
        let reg = cx.layout.samples;
        let setups = taps.fixed.setups();
        // A banded run's later bands do not count the walk above their rows again.
        let above = cx.layout.band.is_none_or(|b| b.first);
        let (out, stepped, w) = walk(setups, &p, &reg, above, cx.pool);
        let prims = &taps.fixed.prims().q;
        let order = processing_order(|i| matches!(prims[i], QPrim::Point { .. }), prims.len());
        let tokens = order.iter().map(|&i| stepped[i]).collect();
        taps.fixed.frags = Some(Arc::new(FragRuns {
            runs: out,
            codes: RunCodes::new(&p),
        }));
        let clamped = SignalStats::overflow_counter(
            "raster.clamped",
            cx.hw.input.intensity.format,
            w.clamped,
        );
        let facts = Facts {
            work: vec![
                ("spans", w.spans),
                ("samples", w.samples),
                ("walked_samples", w.walked),
                ("walked_rows", w.rows_walked),
                ("reseeds", w.reseeds),
            ],
            signals: vec![clamped],
            ..Facts::default()
        };
        Ok((tokens, facts))
    }

    fn float(&self, cx: &Cx, _: &Vec<u64>, taps: &mut Taps, _: &mut Notes) -> Result<()> {
        let (grid, reg) = (cx.layout.grid, cx.layout.samples);
        // About as many fragments as the fixed raster emitted.
        let capacity = taps.fixed.frags.as_ref().map_or(0, |f| f.len());
        let out = float_frags(&taps.float.prims().f, &grid, &reg, capacity);
        taps.float.frags = Some(Arc::new(out));
        Ok(())
    }

    /// The float raster run on the quantised primitives, sample by sample against the fixed
    /// fragments (surfaces; light points are flat squares): intensity error (local), depth
    /// error (note `depth_local`), and samples covered by one model only (mismatched items).
    fn local(
        &self,
        cx: &Cx,
        _: &Vec<u64>,
        _: &Taps,
        out: &Taps,
        notes: &mut Notes,
    ) -> Option<LocalError> {
        let (grid, reg) = (cx.layout.grid, cx.layout.samples);
        let prims = &out.fixed.prims().q;
        let frags = out.fixed.frags();
        let (mut i_err, mut z_err) = (LocalError::default(), LocalError::default());
        let (mut fx, mut fl) = (Vec::new(), Vec::new());
        for (p, q) in prims.iter().enumerate() {
            if matches!(q, QPrim::Point { .. }) {
                continue;
            }
            fx.clear();
            fx.extend(frags.of(p));
            fl.clear();
            raster_f64(&FPrim::from_q(q, grid.sub_bits), &grid, &reg, &mut fl);
            // A line is two triangles: sort both lists so they merge by sample.
            fx.sort_by_key(|x| x.s);
            fl.sort_by_key(|x| x.s);
            compare_frags(&fx, &fl, cx.layout.channels, &mut i_err, &mut z_err);
        }
        notes.insert(
            "depth_local".into(),
            serde_json::to_value(z_err.finish()).unwrap_or_default(),
        );
        Some(i_err.finish())
    }

    fn tokens(&self, _: &Cx, stepped: &Vec<u64>) -> Option<Tokens> {
        Some(Tokens {
            kind: TokenKind::Primitive,
            item: "samples stepped",
            items: stepped.clone(),
            port_bits: vec![],
            rows: vec![],
            stream: None,
        })
    }

    fn cost(&self, cx: &Cx, _: &Vec<u64>) -> Cost {
        let hw = cx.hw;
        let cb = hw.input.coord.format.total_bits();
        let g = hw.raster.interp_guard_bits;
        Cost::new(
            vec![],
            vec![
                Unit::adder("edge quotient/remainder", 6, cb + 2),
                Unit::adder(
                    "intensity interpolator",
                    2,
                    hw.input.intensity.format.total_bits() + g + 1,
                ),
                Unit::adder(
                    "depth interpolator",
                    2,
                    hw.input.z.format.total_bits() + g + 1,
                ),
            ],
            vec![],
        )
    }

    fn memories(&self, _: &Cx, _: &Vec<u64>, _: &Taps) -> Vec<MemImage> {
        vec![]
    }
}
