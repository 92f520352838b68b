//! A colour render's channels: the DAC codes of each channel's lane (the stages after
//! visibility, run once per channel on its samples with its word widths) and each
//! channel's comparison with its float reference, cost and overflows.
//!
//! Channel 0 (R) is the render's own steps (the geometry stages and R's lane); its
//! comparison is the report's `end_to_end` as for a grey render. The cycle model counts one
//! lane: the three channels are parallel datapaths behind one raster and one z-buffer (as in
//! the image generators the tool models), so a colour frame takes the cycles of a grey one
//! and the cost of three intensity datapaths.

use super::cache::Cache;
use super::report::{EndToEnd, compare_codes, ideal};
use super::run::Step;
use crate::colour::{self, ColourDisplay, DeltaE, HueShift, RgbCodes};
use crate::compare::DisplayModel;
use crate::config::HwConfig;
use crate::cycles::{self, Workload};
use crate::perceptual::ContourReport;
use crate::scene::Scene;
use crate::stage::{PixelTapF, Pool, StageReport};
use serde::Serialize;

/// The channels' names, in order.
pub const NAMES: [&str; 3] = ["R", "G", "B"];

/// One channel's DAC codes, fixed and float.
#[derive(Clone, Debug)]
pub struct ChannelCodes {
    /// Fixed DAC codes, row-major.
    pub dac: Vec<u16>,
    /// Float reference DAC codes.
    pub dac_ref: Vec<u16>,
    /// DAC width.
    pub bits: u32,
    /// Per pixel: 0 not smooth, 1 smooth, 2 next to a visible contour step (this channel).
    pub contour_map: Vec<u8>,
}

/// The overflows, storage bits and LUT bits of a lane's stage reports.
pub fn lane_totals<'a>(
    stages: impl IntoIterator<Item = &'a StageReport> + Clone,
) -> (u64, u64, u64) {
    let s = stages.clone().into_iter();
    (
        s.flat_map(|s| &s.signals).map(|s| s.overflows).sum(),
        stages
            .clone()
            .into_iter()
            .map(|s| s.cost.storage_bits)
            .sum(),
        stages.into_iter().map(|s| s.cost.lut_bits).sum(),
    )
}

/// The fixed DAC codes after the last of `steps`.
pub fn fixed_codes(steps: &[Step], pool: &Pool) -> Vec<u16> {
    let taps = &steps.last().expect("a plan runs stages").outcome.taps;
    let codes = taps.fixed.pixels().codes();
    let mut out = pool.take(codes.len());
    out.extend(codes.iter().map(|&c| c as u16));
    out
}

/// The DAC codes, fixed and float, after the last of `steps`.
pub fn dac_codes(steps: &[Step]) -> (Vec<u16>, Vec<u16>) {
    let taps = &steps.last().expect("a plan runs stages").outcome.taps;
    let dac = fixed_codes(steps, &Pool::new());
    let dac_ref = match taps.float.pixels() {
        PixelTapF::Codes(c) => c.iter().map(|&c| c as u16).collect(),
        PixelTapF::Values(_) => unreachable!("the last stage writes DAC codes"),
    };
    (dac, dac_ref)
}

/// One channel of the report (`render --json`: `colour.channels`).
#[derive(Clone, Debug, Serialize)]
pub struct ChannelReport {
    /// `R`, `G` or `B`.
    pub name: &'static str,
    /// The channel's frame-memory word.
    pub frame: String,
    /// The channel's DAC width.
    pub dac_bits: u32,
    /// The channel's DAC codes against its float reference.
    pub end_to_end: EndToEnd,
    /// Visible contours of the channel through its display transfer.
    pub contours: ContourReport,
    /// Overflows over the signals of the channel's lane.
    pub overflows: u64,
    /// Storage bits (RAM) of the channel's lane, its streamed depth of field's line
    /// buffers included.
    pub storage_bits: u64,
    /// Cycles of a frame through the geometry stages and this channel's lane (the cycle
    /// model on the lane's own tokens).
    pub cycles: u64,
    /// The lane's slowest stage.
    pub bottleneck: String,
    /// LUT / ROM bits of the channel's lane.
    pub lut_bits: u64,
    /// The stages of the channel's lane (after visibility).
    pub stages: Vec<StageReport>,
}

/// The colour part of the report.
#[derive(Clone, Debug, Serialize)]
pub struct ColourReport {
    /// Per channel, R, G, B.
    pub channels: Vec<ChannelReport>,
    /// CIEDE2000 between the fixed and the float reference image through the display
    /// (each channel's transfer, sRGB primaries; [`crate::colour`]).
    pub delta_e: DeltaE,
    /// The hue shift on smooth chromatic surfaces, fixed against float: the colour-mix
    /// distortion of too-narrow words.
    pub hue_shift: HueShift,
    /// Visible contour steps over the three channels (fixed; float reference).
    pub contour_steps: [u64; 2],
}

/// The colour report of the three channels' codes and reports, and the per-pixel CIEDE2000
/// map (row-major).
pub fn report(
    scene: &Scene,
    codes: &[ChannelCodes],
    channels: Vec<ChannelReport>,
) -> (ColourReport, Vec<f32>) {
    let (width, height) = (scene.image.width, scene.image.height);
    let bits = [0, 1, 2].map(|c| codes[c].bits);
    let image = |reference: bool| RgbCodes {
        planes: [0, 1, 2].map(|c| {
            if reference {
                codes[c].dac_ref.as_slice()
            } else {
                codes[c].dac.as_slice()
            }
        }),
        bits,
        width,
        height,
    };
    let (fixed, reference) = (image(false), image(true));
    let display = ColourDisplay::new(&scene.display, bits);
    let mut delta_e = colour::delta_e(&fixed, &reference, &display);
    let map = std::mem::take(&mut delta_e.map);
    let hue_shift = colour::hue_shift(&fixed, &reference, &display);
    let contour_steps = [
        channels.iter().map(|c| c.contours.contour_steps).sum(),
        channels
            .iter()
            .map(|c| c.contours.contour_steps_reference)
            .sum(),
    ];
    let r = ColourReport {
        channels,
        delta_e,
        hue_shift,
        contour_steps,
    };
    (r, map)
}

/// Channel `c`'s codes and report from its lane's steps (`lane`: the stages after the
/// shared geometry) and its cycle `workload` (the geometry's steps and the lane's) under
/// its configuration `hw` (already [`HwConfig::channel`]).
pub fn channel(
    scene: &Scene,
    hw: &HwConfig,
    c: usize,
    lane: &[Step],
    workload: &Workload,
    cache: Option<&Cache>,
) -> (ChannelCodes, ChannelReport) {
    let (dac, dac_ref) = dac_codes(lane);
    let bits = hw.gamma.dac_bits;
    let display = DisplayModel::new(&scene.display, bits);
    let ideal = ideal(scene, hw, lane, cache);
    let compared = compare_codes((&dac, &dac_ref), lane, &ideal, (&display, bits), cache);
    let stages: Vec<StageReport> = lane.iter().map(|s| s.outcome.report.clone()).collect();
    let simulate = || (cycles::simulate(workload, None), 0.0);
    let sim = match cache {
        Some(k) => k.sim(workload.key(), simulate).0,
        None => std::sync::Arc::new(simulate()),
    };
    let (overflows, storage_bits, lut_bits) = lane_totals(&stages);
    // The lane's streamed depth of field has its own line buffers.
    let storage_bits = storage_bits + workload.line_buffer_bits();
    let report = ChannelReport {
        name: NAMES[c],
        frame: hw.accumulate.frame.format.to_string(),
        dac_bits: bits,
        end_to_end: compared.0.clone(),
        contours: compared.1.report.clone(),
        overflows,
        storage_bits,
        lut_bits,
        cycles: sim.0.total_cycles,
        bottleneck: sim.0.bottleneck().to_string(),
        stages,
    };
    let codes = ChannelCodes {
        dac,
        dac_ref,
        bits,
        contour_map: compared.1.map.clone(),
    };
    (codes, report)
}
