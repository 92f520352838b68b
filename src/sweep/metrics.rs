//! The metrics of a sweep row: its error against the float reference, cost, cycles, and
//! on request the small-object flicker, the errors against the depth-of-field truth, and the
//! emulator's own time.

use crate::error::Result;
use serde::{Deserialize, Serialize};

/// Error metrics of a row (DAC codes, fixed vs float reference).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ErrorMetrics {
    /// Largest |fixed - reference| DAC code difference.
    pub max_code_diff: u32,
    /// Mean |difference|, codes.
    pub mean_code_diff: f64,
    /// Mean signed difference (fixed - reference), codes: the bias.
    pub mean_signed_code_diff: f64,
    /// PSNR in dB (`None` when identical).
    pub psnr_db: Option<f64>,
    /// Fraction of identical codes.
    pub identical_fraction: f64,
    /// Largest Weber error through the display model.
    pub weber_max: f64,
    /// Mean Weber error.
    pub weber_mean: f64,
    /// Fraction of pixels whose Weber error exceeds the visibility threshold.
    pub weber_visible_fraction: f64,
    /// Visible contour steps in smooth regions (fixed).
    pub contour_steps: u64,
    /// Pixels next to a visible contour step.
    pub contour_pixels: u64,
}

/// Cost of a row.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CostMetrics {
    /// RAM bits over all stages.
    pub storage_bits: u64,
    /// LUT / ROM bits.
    pub lut_bits: u64,
    /// Adders.
    pub adders: u64,
    /// Multipliers.
    pub multipliers: u64,
}

/// Cycle model of a row.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CycleMetrics {
    /// Cycles per frame.
    pub total_cycles: u64,
    /// Frames per second at the configured clock.
    pub fps: f64,
    /// Bottleneck stage.
    pub bottleneck: String,
    /// Whether the frame rate meets the display's refresh rate.
    pub real_time: bool,
}

/// Small-object flicker of a row's hardware (`--flicker PHASES`; see [`crate::analysis::flicker`]):
/// the worst object of the flicker scene swept over `phases x phases` sub-pixel phases.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct FlickerMetrics {
    /// Sub-pixel phases per axis.
    pub phases: u32,
    /// Largest peak-to-peak displayed luminance of an object, % of its mean.
    pub displayed_ripple_pct: f64,
    /// Largest peak-pixel modulation, %.
    pub peak_pixel_modulation_pct: f64,
    /// Largest |brightness error| of an object split over two pixels, %.
    pub half_pixel_brightness_error_pct: f64,
    /// The object with the largest displayed ripple.
    pub worst_object: String,
}

impl FlickerMetrics {
    /// Runs the flicker sweep of `hw`.
    pub fn of(hw: &crate::config::HwConfig, phases: u32) -> Result<FlickerMetrics> {
        let r = crate::analysis::flicker::flicker(hw, phases)?;
        let max = |f: fn(&crate::analysis::flicker::ObjectFlicker) -> f64| {
            r.objects.iter().map(f).fold(0.0, f64::max)
        };
        let worst = r
            .objects
            .iter()
            .max_by(|a, b| a.displayed_ripple_pct.total_cmp(&b.displayed_ripple_pct))
            .map_or(String::new(), |o| o.object.clone());
        Ok(FlickerMetrics {
            phases,
            displayed_ripple_pct: max(|o| o.displayed_ripple_pct),
            peak_pixel_modulation_pct: max(|o| o.peak_pixel_modulation_pct),
            half_pixel_brightness_error_pct: max(|o| o.half_pixel_brightness_error_pct.abs()),
            worst_object: worst,
        })
    }
}

/// One error against the depth-of-field truth over one set of pixels (see
/// [`crate::truth::Diff`]).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct TruthError {
    /// Mean |difference|, DAC codes.
    pub mean_code_diff: f64,
    /// RMS difference, DAC codes.
    pub rms_code_diff: f64,
    /// Largest |difference|, DAC codes.
    pub max_code_diff: u32,
    /// Mean Weber fraction through the display model.
    pub weber_mean: f64,
    /// Fraction of pixels whose Weber fraction exceeds the visibility threshold.
    pub weber_visible_fraction: f64,
}

impl TruthError {
    fn of(d: &crate::truth::Diff) -> Self {
        Self {
            mean_code_diff: d.mean_abs,
            rms_code_diff: d.rms,
            max_code_diff: d.max_abs,
            weber_mean: d.weber_mean,
            weber_visible_fraction: d.weber_visible_fraction,
        }
    }

    fn split(s: &crate::truth::Split<crate::truth::Diff>) -> crate::truth::Split<Self> {
        crate::truth::Split {
            whole: Self::of(&s.whole),
            edge: Self::of(&s.edge),
            interior: Self::of(&s.interior),
        }
    }
}

/// The errors of a row against the depth-of-field truth (`--dof-truth`, a thin-lens scene
/// only; see [`crate::truth`]): the axes `truth_total`, `truth_algorithm` and
/// `truth_quantisation` read the whole image's mean Weber fraction.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct TruthMetrics {
    /// Lens points the truth averages.
    pub lens_samples: u32,
    /// The truth's noise: RMS over the pixels of its standard error, DAC codes.
    pub noise_dac_rms: f64,
    /// Pixels of the depth-edge band.
    pub edge_pixels: u64,
    /// Fixed pipeline vs truth.
    pub total: crate::truth::Split<TruthError>,
    /// Float reference pipeline vs truth (the method's approximation).
    pub algorithm: crate::truth::Split<TruthError>,
    /// Fixed vs float reference (the quantisation).
    pub quantisation: crate::truth::Split<TruthError>,
}

impl TruthMetrics {
    /// The row's metrics from a render's truth report.
    pub fn of(t: &crate::truth::TruthReport) -> Self {
        Self {
            lens_samples: t.lens_samples,
            noise_dac_rms: t.noise.dac.whole.rms,
            edge_pixels: t.edge_pixels,
            total: TruthError::split(&t.total),
            algorithm: TruthError::split(&t.algorithm),
            quantisation: TruthError::split(&t.quantisation),
        }
    }
}

/// Wall time of a row (the only field that differs between runs).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RowTiming {
    /// Milliseconds for the whole render (stages taken from the cache cost nothing here).
    pub render_ms: f64,
    /// The emulator's own time for this configuration: the fixed models' milliseconds summed
    /// over the stages, each as measured when it was computed (a stage reused from the
    /// cache keeps its time), so rows compare the speed of emulating their hardware; the
    /// axis `emulator_time`.
    #[serde(default)]
    pub fixed_ms: f64,
    /// The float references' milliseconds, summed likewise.
    #[serde(default)]
    pub float_ms: f64,
    /// Per stage, in run order.
    #[serde(default)]
    pub stages: Vec<StageTiming>,
}

/// The emulator's time of one stage of a row.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct StageTiming {
    /// Stage name.
    pub name: String,
    /// Fixed model, ms.
    pub fixed_ms: f64,
    /// Float reference, ms.
    pub float_ms: f64,
}

/// The colour error of a colour render's row (`None` for a grey render; see
/// [`crate::pipeline::colour::ColourReport`]): CIEDE2000 of the fixed against the float image
/// through the display, and the hue shift on smooth chromatic surfaces. The axes `delta_e`,
/// `delta_e_p99` and `hue_shift` read it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ColourMetrics {
    /// Mean CIEDE2000 `Delta E_00` over the pixels.
    pub delta_e_mean: f64,
    /// Its 99th percentile.
    pub delta_e_p99: f64,
    /// Its largest value.
    pub delta_e_max: f64,
    /// Pixels with `Delta E_00` over the 2.3 just-noticeable difference.
    pub delta_e_over_jnd: u64,
    /// Mean hue shift on the smooth chromatic pixels, degrees.
    pub hue_shift_mean_deg: f64,
    /// Its 99th percentile, degrees.
    pub hue_shift_p99_deg: f64,
    /// The smooth chromatic pixels the hue shift is measured on.
    pub hue_shift_pixels: u64,
    /// Visible contour steps over the three channels (fixed).
    pub contour_steps: u64,
}

impl ColourMetrics {
    /// The row's colour metrics from a render's colour report.
    pub fn of(c: &crate::pipeline::colour::ColourReport) -> Self {
        Self {
            delta_e_mean: c.delta_e.mean,
            delta_e_p99: c.delta_e.p99,
            delta_e_max: c.delta_e.max,
            delta_e_over_jnd: c.delta_e.over_jnd,
            hue_shift_mean_deg: c.hue_shift.mean_deg,
            hue_shift_p99_deg: c.hue_shift.p99_deg,
            hue_shift_pixels: c.hue_shift.pixels,
            contour_steps: c.contour_steps[0],
        }
    }
}
