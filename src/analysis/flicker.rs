//! Small-object flicker: a light point and a thin line swept over a grid of sub-pixel
//! phases, each phase rendered through the real pipeline (fixed model) on a small scene.
//!
//! Per phase `(u, v)` (`u, v = k / phases`, k = 0..phases):
//! * the accumulator sum `sum(acc - acc_background)` (frame LSBs),
//! * the total displayed luminance above the background, `T = sum(B(code) - B(code_bg))`
//!   through the display model `B = B_min + (B_max - B_min) V^gamma`,
//! * the peak pixel's displayed luminance above the background, `P`.
//!
//! Reported per object: the accumulator ripple `max - min` (LSBs and % of the mean), the
//! displayed ripple `(max T - min T) / mean T` in %, the peak-pixel modulation
//! `(max P - min P) / max P` in %, and the brightness change of the half-pixel phase
//! `T(1/2, 0) / T(0, 0) - 1` (the object split equally over two pixels; Kovalev & Tokarev:
//! `2 (1/2)^gamma - 1` = -62 % for gamma 2.4 without gamma correction).

use crate::compare::DisplayModel;
use crate::config::HwConfig;
use crate::error::Result;
use crate::files::TomlFile;
use crate::pipeline;
use crate::scene::Scene;
use crate::stage::RunOptions;
use rayon::prelude::*;
use serde::Serialize;

/// Side of the flicker scene, pixels. Every object has intensity `2^(A-1)` frame codes
/// (half of full white, A = accumulator integer bits).
pub const SCENE_SIZE: u32 = 12;

/// One swept object.
#[derive(Clone, Debug, Serialize)]
pub struct ObjectFlicker {
    /// `point` or `line`.
    pub object: String,
    /// What it is.
    pub description: String,
    /// Largest minus smallest accumulator sum over the phases, frame LSBs.
    pub acc_ripple_lsb: u64,
    /// The same as % of the mean accumulator sum.
    pub acc_ripple_pct: f64,
    /// Mean total displayed luminance above the background (cd/m² summed over pixels).
    pub mean_luminance: f64,
    /// Peak-to-peak total displayed luminance as % of its mean.
    pub displayed_ripple_pct: f64,
    /// Peak-pixel modulation `(max - min) / max` in %.
    pub peak_pixel_modulation_pct: f64,
    /// `T(1/2, 0) / T(0, 0) - 1` in %: the object split equally over two pixels.
    pub half_pixel_brightness_error_pct: f64,
}

/// The flicker report (`igemu flicker --json`).
#[derive(Clone, Debug, Serialize)]
pub struct FlickerReport {
    /// Hardware configuration name.
    pub hardware: String,
    /// Filter.
    pub filter: crate::config::FilterKind,
    /// Whether the gamma LUT corrects the display gamma.
    pub gamma_correction: bool,
    /// Display gamma.
    pub gamma: f64,
    /// Sub-pixel phases per axis.
    pub phases: u32,
    /// Scene side, pixels.
    pub scene_size: u32,
    /// The analytic split error `2 (1/2)^gamma - 1` in % (no correction, box filter).
    pub analytic_split_error_pct: f64,
    /// Per object.
    pub objects: Vec<ObjectFlicker>,
}

fn scene_text(object: &str) -> String {
    format!(
        "name = \"flicker\"\n[image]\nwidth = {SCENE_SIZE}\nheight = {SCENE_SIZE}\nbackground = 0.0\n\
         [camera]\nposition = [0.0, 0.0, 10.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y_deg = 40.0\nnear = 1.0\nfar = 100.0\n\
         [display]\ncontrast = 100.0\ngamma = 2.4\nweber = 0.02\nb_max = 100.0\n{object}"
    )
}

fn object_text(object: &str, u: f64, v: f64, i: f64, sample: f64) -> String {
    let c = SCENE_SIZE as f64 / 2.0;
    match object {
        "point" | "sample_point" => format!(
            "[[object]]\nkind = \"light_point\"\nspace = \"screen\"\nposition = [{}, {}, 0.5]\nintensity = {i:.17}\nsize = {}\n",
            c + 0.5 + u,
            c + 0.5 + v,
            if object == "point" { 1.0 } else { sample }
        ),
        _ => format!(
            "[[object]]\nkind = \"line\"\nspace = \"screen\"\nfrom = [{}, {}, 0.5]\nto = [{}, {}, 0.5]\nintensity = {i:.17}\nwidth = 0.5\n",
            c - 2.0 + u,
            c - 1.0 + v,
            c + 2.0 + u,
            c + 1.0 + v
        ),
    }
}

struct Phase {
    acc: u64,
    lum: f64,
    peak: f64,
}

fn one(object: &str, u: f64, v: f64, hw: &HwConfig) -> Result<Phase> {
    // Half of full white: 2^(A-1) frame codes, so that every I*S product of the box and
    // tent filters is an exact frame code (no per-pixel rounding in the ripple).
    let a = hw.accumulate.frame.format.int_bits;
    let i = (1u64 << (a - 1)) as f64 / ((1u64 << a) - 1) as f64;
    let sample = 1.0 / hw.raster.samples as f64;
    let text = scene_text(&object_text(object, u, v, i, sample));
    let scene = Scene::from_toml(&TomlFile::from_text("flicker.toml", &text))?;
    let r = pipeline::render(&scene, hw, RunOptions::FAST)?;
    let mut d = scene.display.clone();
    if let Some(g) = hw.gamma.gamma {
        d.gamma = g;
    }
    let m = DisplayModel::new(&d, hw.gamma.dac_bits);
    let b0 = m.luminance(0);
    let acc: u64 = r.frame().acc.iter().map(|&a| a as u64).sum();
    let lum: Vec<f64> = r.dac.iter().map(|&c| m.luminance(c) - b0).collect();
    Ok(Phase {
        acc,
        lum: lum.iter().sum(),
        peak: lum.iter().cloned().fold(0.0, f64::max),
    })
}

/// Sweeps both objects over `phases x phases` sub-pixel phases with the hardware `hw`.
pub fn flicker(hw: &HwConfig, phases: u32) -> Result<FlickerReport> {
    let gamma = hw.gamma.gamma.unwrap_or(2.4);
    let mut objects = Vec::new();
    for (object, description) in [
        ("point", "light point, 1x1 px"),
        ("sample_point", "light point of one sample (1/n x 1/n px)"),
        ("line", "line 4.5 px long at 26.6 degrees, 0.5 px wide"),
    ] {
        let grid: Vec<(u32, u32)> = (0..phases)
            .flat_map(|j| (0..phases).map(move |i| (i, j)))
            .collect();
        let res: Vec<Phase> = grid
            .par_iter()
            .map(|&(i, j)| {
                one(
                    object,
                    i as f64 / phases as f64,
                    j as f64 / phases as f64,
                    hw,
                )
            })
            .collect::<Result<_>>()?;
        let n = res.len() as f64;
        let (amin, amax) = res
            .iter()
            .fold((u64::MAX, 0), |m, p| (m.0.min(p.acc), m.1.max(p.acc)));
        let amean = res.iter().map(|p| p.acc as f64).sum::<f64>() / n;
        let (lmin, lmax) = res.iter().fold((f64::MAX, f64::MIN), |m, p| {
            (m.0.min(p.lum), m.1.max(p.lum))
        });
        let lmean = res.iter().map(|p| p.lum).sum::<f64>() / n;
        let (pmin, pmax) = res.iter().fold((f64::MAX, f64::MIN), |m, p| {
            (m.0.min(p.peak), m.1.max(p.peak))
        });
        let half = &res[(phases / 2) as usize];
        objects.push(ObjectFlicker {
            object: object.into(),
            description: description.into(),
            acc_ripple_lsb: amax - amin,
            acc_ripple_pct: 100.0 * (amax - amin) as f64 / amean,
            mean_luminance: lmean,
            displayed_ripple_pct: 100.0 * (lmax - lmin) / lmean,
            peak_pixel_modulation_pct: 100.0 * (pmax - pmin) / pmax,
            half_pixel_brightness_error_pct: 100.0 * (half.lum / res[0].lum - 1.0),
        });
    }
    Ok(FlickerReport {
        hardware: hw.name.clone(),
        filter: hw.accumulate.filter,
        gamma_correction: hw.gamma.correction,
        gamma,
        phases,
        scene_size: SCENE_SIZE,
        analytic_split_error_pct: 100.0 * (2.0 * 0.5f64.powf(gamma) - 1.0),
        objects,
    })
}
