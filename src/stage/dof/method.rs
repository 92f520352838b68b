//! The depth-of-field methods behind `dof.kind`: each has a fixed model, a float reference
//! (the same algorithm in f64), cycle-model tokens, a cost and memory images; the dof stage
//! ([`super::Dof`]) dispatches to the configured one and does what all share (the lens,
//! the stage-local comparison, the reference notes).

use super::LensMap;
use crate::error::{Error, Result};
use crate::stage::accumulate::Frame;
use crate::stage::{Cost, Cx, Facts, MemImage, Tokens};

/// One depth-of-field method.
pub trait Method: Sync {
    /// What the fixed model leaves for the float reference, the tokens and the cost (e.g.
    /// the layer plan).
    type Plan: Send + Sync + 'static;

    /// The fixed model on the finished frame (linear frame codes, depth codes, coverage):
    /// its plan, the new frame codes (in the frame format) and its facts (work, signals,
    /// notes).
    fn fixed(
        &self,
        cx: &Cx,
        frame: &Frame,
        lens: &LensMap,
    ) -> Result<(Self::Plan, Vec<u32>, Facts)>;

    /// The float reference: the same method in f64 on `value` (frame LSBs, e.g. the float
    /// pipeline's frame or the fixed frame's codes as reals) with the frame's depth codes
    /// and coverage, using the fixed model's plan where the method has one.
    fn float(
        &self,
        cx: &Cx,
        plan: &Self::Plan,
        frame: &Frame,
        value: &[f64],
        lens: &LensMap,
    ) -> Vec<f64>;

    /// The tokens the cycle model consumes.
    fn tokens(&self, cx: &Cx, plan: &Self::Plan) -> Tokens;

    /// Cost from the formats (memories, adders, multipliers).
    fn cost(&self, cx: &Cx, plan: &Self::Plan, lens: &LensMap) -> Cost;

    /// The contents of its ROMs (names as in [`Method::cost`]) for the pack check.
    fn memories(&self, cx: &Cx, plan: &Self::Plan, lens: &LensMap) -> Vec<MemImage>;
}

/// Samples per pixel (`n^2`) of the configuration.
pub fn n2(cx: &Cx) -> u32 {
    cx.hw.raster.samples * cx.hw.raster.samples
}

/// A method's plan refused for a blur wider than `dof.max_half_size` allows (`msg` says by
/// how much and what to change), naming the hardware file and the field.
pub fn half_size_error(cx: &Cx, msg: String) -> Error {
    Error::File(cx.hw.error("dof.max_half_size", msg))
}
