//! The measured properties of the accumulate filters (`igemu filters`, docs/filters.md): the
//! DC ripple of the quantised kernel over the sample phases, the step response through the
//! pipeline (undershoot and overshoot in frame and DAC codes) against the float filter's
//! value at the same step, and the frequency response of the quantised weights against the
//! transforms of box, tent and B-spline (sinc, sinc², sinc⁴).

use crate::config::{FilterKind, HwConfig};
use crate::error::Result;
use crate::files::TomlFile;
use crate::pipeline;
use crate::scene::Scene;
use crate::stage::RunOptions;
use crate::stage::accumulate::{Kernel, kernel};
use serde::Serialize;

/// Frequencies of the response, cycles per pixel.
pub const FREQUENCIES: [f64; 4] = [0.125, 0.25, 0.375, 0.5];

/// Width and height of the step scene, pixels.
const STEP_W: u32 = 24;
const STEP_H: u32 = 8;
/// The step's two levels (intensities in [0, 1]): far enough from black and white that
/// the negative lobes' undershoot and overshoot are not clipped.
const STEP_LO: f64 = 0.25;
const STEP_HI: f64 = 0.75;

/// The kernel's DC ripple: what one sub-pixel sample gives all pixels, per sample phase.
#[derive(Clone, Debug, Serialize)]
pub struct Ripple {
    /// Largest minus smallest group sum over the `n x n` phases, weight LSBs (0: equal
    /// energy bit for bit).
    pub group_spread_lsb: i64,
    /// The same for the weights rounded one by one (no per-group correction): the ripple a
    /// plain quantisation of the filter would leave.
    pub rounded_spread_lsb: i64,
    /// Largest minus smallest group sum of the exact weights, as a fraction of their mean
    /// (0 for a partition of unity on the sample grid).
    pub exact_spread: f64,
}

/// Ripple of the quantised kernel `k`.
pub fn ripple(k: &Kernel) -> Ripple {
    let n = k.n as usize;
    let one = (1i64 << k.f) as f64;
    let spread = |v: &[f64]| {
        let (lo, hi) = v
            .iter()
            .fold((f64::MAX, f64::MIN), |m, &x| (m.0.min(x), m.1.max(x)));
        hi - lo
    };
    let mut exact = vec![0.0; n * n];
    let mut rounded = vec![0.0; n * n];
    for (e, &w) in k.wf.iter().enumerate() {
        let g = (e / k.size % n) * n + e % k.size % n;
        exact[g] += w;
        rounded[g] += (w * one).round();
    }
    let q: Vec<f64> = k.group_sums().iter().map(|&v| v as f64).collect();
    let mean = exact.iter().sum::<f64>() / exact.len() as f64;
    Ripple {
        group_spread_lsb: spread(&q) as i64,
        rounded_spread_lsb: spread(&rounded) as i64,
        exact_spread: spread(&exact) / mean,
    }
}

/// The response to a vertical step from `STEP_LO` to `STEP_HI` at every sub-pixel phase.
#[derive(Clone, Debug, Serialize)]
pub struct Step {
    /// Frame codes of the dark and the bright side far from the edge.
    pub lo: u32,
    /// See `lo`.
    pub hi: u32,
    /// Largest dip below `lo` over the phases, frame LSBs.
    pub undershoot: i64,
    /// Largest rise above `hi` over the phases, frame LSBs.
    pub overshoot: i64,
    /// The same in DAC codes (after the gamma LUT).
    pub undershoot_dac: i64,
    /// See `undershoot_dac`.
    pub overshoot_dac: i64,
    /// The float filter's (exact weights') undershoot at a step of `hi - lo` codes, frame
    /// LSBs: the largest negative partial sum of its 1-D profile over the sample columns.
    pub float_undershoot: f64,
    /// The float filter's overshoot, frame LSBs.
    pub float_overshoot: f64,
}

fn step_scene(x: f64) -> Result<Scene> {
    let (w, h) = (STEP_W as f64, STEP_H as f64);
    let text = format!(
        "name = \"step\"\n[image]\nwidth = {STEP_W}\nheight = {STEP_H}\nbackground = {STEP_LO}\n\
         [camera]\nposition = [0.0, 0.0, 10.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y_deg = 40.0\nnear = 1.0\nfar = 100.0\n\
         [display]\ncontrast = 100.0\ngamma = 2.4\nweber = 0.02\nb_max = 100.0\n\
         [[object]]\nkind = \"triangle\"\nspace = \"screen\"\nvertices = [[{x}, -4.0, 0.5], [{r}, -4.0, 0.5], [{r}, {b}, 0.5]]\nintensity = [{STEP_HI}, {STEP_HI}, {STEP_HI}]\n\
         [[object]]\nkind = \"triangle\"\nspace = \"screen\"\nvertices = [[{x}, -4.0, 0.5], [{r}, {b}, 0.5], [{x}, {b}, 0.5]]\nintensity = [{STEP_HI}, {STEP_HI}, {STEP_HI}]\n",
        r = w + 8.0,
        b = h + 4.0,
    );
    Ok(Scene::from_toml(&TomlFile::from_text("step.toml", &text))?)
}

/// Renders the step at the `n` sample phases of the pixel at the screen's centre and
/// measures the ringing along the middle row.
pub fn step(hw: &HwConfig) -> Result<Step> {
    let n = hw.raster.samples;
    let k = kernel(hw);
    let row = (STEP_H / 2) as usize * STEP_W as usize;
    let (mut lo, mut hi) = (0u32, 0u32);
    let (mut under, mut over, mut under_d, mut over_d) = (0i64, 0i64, 0i64, 0i64);
    for p in 0..n.max(2) {
        let x = (STEP_W / 2) as f64 + p as f64 / n.max(2) as f64;
        let r = pipeline::render(&step_scene(x)?, hw, RunOptions::FAST)?;
        let acc = &r.frame().acc[row..row + STEP_W as usize];
        let dac = &r.dac[row..row + STEP_W as usize];
        lo = acc[0];
        hi = acc[STEP_W as usize - 1];
        let (dlo, dhi) = (dac[0] as i64, dac[STEP_W as usize - 1] as i64);
        for (&a, &d) in acc.iter().zip(dac) {
            under = under.max(lo as i64 - a as i64);
            over = over.max(a as i64 - hi as i64);
            under_d = under_d.max(dlo - d as i64);
            over_d = over_d.max(d as i64 - dhi);
        }
    }
    // The exact weights' 1-D profile (column sums) and its partial sums from the right:
    // the float filter's response to a step at each sample column.
    let cols: Vec<f64> = (0..k.size)
        .map(|i| (0..k.size).map(|j| k.wf[j * k.size + i]).sum())
        .collect();
    let mut tail = 0.0;
    let (mut fu, mut fo) = (0.0f64, 0.0f64);
    for c in cols.iter().rev() {
        tail += c;
        fu = fu.max(-tail);
        fo = fo.max(tail - 1.0);
    }
    let height = hi as f64 - lo as f64;
    Ok(Step {
        lo,
        hi,
        undershoot: under,
        overshoot: over,
        undershoot_dac: under_d,
        overshoot_dac: over_d,
        float_undershoot: fu * height,
        float_overshoot: fo * height,
    })
}

/// The response at one frequency.
#[derive(Clone, Debug, Serialize)]
pub struct Response {
    /// Cycles per pixel.
    pub u: f64,
    /// `|H(u)|` of the quantised weights' 1-D profile over its sample positions.
    pub quantised: f64,
    /// The same of the exact weights.
    pub exact: f64,
    /// The seed's transform (box: sinc, tent: sinc², B-spline: sinc⁴), `None` for the rest.
    pub analytic: Option<f64>,
}

/// `|H(u)|` of the kernel's 1-D profile (row sums of the quantised and exact weights,
/// normalised to a DC gain of 1) at [`FREQUENCIES`], with the seed's transform where it
/// gives one.
pub fn frequency_response(k: &Kernel) -> Vec<Response> {
    let n = k.n as f64;
    let x = |i: usize| (i as f64 - k.off as f64 + 0.5) / n - 0.5;
    let prof = |w: &dyn Fn(usize) -> f64| -> Vec<f64> {
        let v: Vec<f64> = (0..k.size)
            .map(|i| (0..k.size).map(|j| w(j * k.size + i)).sum())
            .collect();
        let s: f64 = v.iter().sum();
        v.iter().map(|a| a / s).collect()
    };
    let q = prof(&|e| f64::from(k.w[e]));
    let e = prof(&|e| k.wf[e]);
    let h = |p: &[f64], u: f64| {
        let (re, im) = p.iter().enumerate().fold((0.0, 0.0), |(re, im), (i, &a)| {
            let t = 2.0 * std::f64::consts::PI * u * x(i);
            (re + a * t.cos(), im - a * t.sin())
        });
        (re * re + im * im).sqrt()
    };
    let sinc = |u: f64| {
        let t = std::f64::consts::PI * u;
        t.sin() / t
    };
    FREQUENCIES
        .iter()
        .map(|&u| Response {
            u,
            quantised: h(&q, u),
            exact: h(&e, u),
            analytic: match k.kind {
                FilterKind::Box => Some(sinc(u)),
                FilterKind::Tent => Some(sinc(u).powi(2)),
                FilterKind::CubicBspline => Some(sinc(u).powi(4)),
                _ => None,
            },
        })
        .collect()
}

/// One filter's row of the table in docs/filters.md.
#[derive(Clone, Debug, Serialize)]
pub struct FilterRow {
    /// The filter's name in the hardware file.
    pub filter: String,
    /// DC ripple of the kernel.
    pub ripple: Ripple,
    /// Step response.
    pub step: Step,
    /// Frequency response.
    pub response: Vec<Response>,
    /// `igemu flicker`'s accumulator ripple of the one-sample light point, % of its mean.
    pub flicker_sample_point_pct: f64,
    /// `igemu flicker`'s displayed ripple of the thin line, % of its mean.
    pub flicker_line_pct: f64,
    /// The default scene: the accumulate stage's largest |fixed - float|, frame LSBs.
    pub acc_max_err: f64,
    /// The default scene: the accumulate stage's mean fixed - float, frame LSBs.
    pub acc_mean_err: f64,
    /// The default scene: the largest end-to-end DAC code difference.
    pub dac_max_diff: u32,
    /// The accumulate stage's RAM and ROM bits.
    pub cost_bits: u64,
    /// Weight ROM word.
    pub weight_bits: u32,
    /// The signed accumulator's word (`None`: the frame word accumulates).
    pub acc_bits: Option<u32>,
    /// The default scene's MACs.
    pub macs: u64,
    /// The default scene's cycles per frame.
    pub cycles: u64,
    /// The default scene's accumulate fixed-model time, ms (one run on the shared machine).
    pub fixed_ms: f64,
}

/// The row of filter `f` under `hw`: the kernel, the step and `phases x phases` flicker
/// phases, and one render of `scene` (the default scene in `igemu filters`).
pub fn row(hw: &HwConfig, f: FilterKind, scene: &Scene, phases: u32) -> Result<FilterRow> {
    let mut hw = hw.clone();
    hw.accumulate.filter = f;
    let k = kernel(&hw);
    let fl = super::flicker::flicker(&hw, phases)?;
    let pct = |o: &str, displayed: bool| {
        fl.objects.iter().find(|x| x.object == o).map_or(0.0, |x| {
            if displayed {
                x.displayed_ripple_pct
            } else {
                x.acc_ripple_pct
            }
        })
    };
    let r = pipeline::render(scene, &hw, RunOptions::default())?;
    let st = r
        .report
        .stages
        .iter()
        .find(|s| s.name == "accumulate")
        .expect("the accumulate stage runs");
    let local = st.local.clone().unwrap_or_default();
    Ok(FilterRow {
        filter: f.name().into(),
        ripple: ripple(&k),
        step: step(&hw)?,
        response: frequency_response(&k),
        flicker_sample_point_pct: pct("sample_point", false),
        flicker_line_pct: pct("line", true),
        acc_max_err: local.max_abs_lsb,
        acc_mean_err: local.mean_lsb,
        dac_max_diff: r.report.end_to_end.codes.max_abs_diff,
        cost_bits: st.cost.storage_bits + st.cost.lut_bits,
        weight_bits: k.rom_bits(),
        acc_bits: k
            .accumulator(&hw.accumulate.frame)
            .map(|q| q.format.total_bits()),
        macs: st.work.get("macs").copied().unwrap_or(0),
        cycles: r.report.cycles.total_cycles,
        fixed_ms: st.fixed_ms,
    })
}
