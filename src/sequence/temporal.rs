//! Temporal metrics of a sequence, accumulated frame by frame (one frame pair in memory):
//! the per-pixel flicker the fixed model adds to the motion, the flicker of each small
//! moving object, and what a temporal dither averages to over the frames (docs/sequence.md).
//!
//! * **Per-pixel excess flicker**: between consecutive frames, the change of a pixel's
//!   displayed luminance in the fixed output minus its change in the float reference, in
//!   Weber units: `|dL_fixed - dL_ref| / (delta max(L_ref(t-1), L_ref(t)))`. Above 1 the
//!   fixed model's own flicker is a visible step at that pixel's luminance.
//! * **Small objects** (the width paper's flicker figures, on the real motion): per moving
//!   object whose screen box stays small or thin ([`SMALL`], [`THIN`]), its total displayed luminance
//!   above the background `T(t)` over a window of the box grown by [`MARGIN`] pixels (the
//!   background level: the median code of the window's border), and its peak pixel `P(t)`.
//!   Reported: the ripple `(max T - min T) / mean T` and the peak-pixel modulation
//!   `(max P - min P) / max P`, fixed and reference.
//! * **Temporal dither**: over the pixels whose reference value does not change in the
//!   sequence, the mean of the fixed codes over the frames against that value (does the
//!   dither average to it?), and how many of those pixels step by a visible Weber fraction
//!   from frame to frame (its own flicker at the sequence's rate).
//!
//! A colour sequence's luminance is the displayed `Y` of the pixel's R, G, B codes (each
//! channel's transfer, sRGB primaries, [`ColourDisplay::xyz`]) in cd/m²; its temporal dither
//! figures are those of channel R.

use crate::colour::ColourDisplay;
use crate::compare::DisplayModel;
use serde::{Deserialize, Serialize};

mod state;
pub use state::{DitherState, TemporalState};

/// Largest short side of a small or thin object's screen box, pixels.
pub const SMALL: f64 = 16.0;
/// Largest long side of a thin object's screen box (a wire, a runway edge), pixels.
pub const THIN: f64 = 128.0;
/// Pixels added around a small object's box for its window (the filter's and the blur's
/// reach).
pub const MARGIN: i64 = 3;

/// A pixel window `[x0, x1) x [y0, y1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Window {
    /// Left.
    pub x0: u32,
    /// Top.
    pub y0: u32,
    /// Right (exclusive).
    pub x1: u32,
    /// Bottom (exclusive).
    pub y1: u32,
}

/// One small object over the frames.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ObjectFlicker {
    /// Index in `[[object]]`.
    pub object: usize,
    /// Its kind.
    pub kind: String,
    /// Total displayed luminance above the background per frame, fixed (cd/m² summed).
    pub total_fixed: Vec<f64>,
    /// The same, float reference (empty without one).
    pub total_reference: Vec<f64>,
    /// Peak pixel above the background per frame, fixed.
    pub peak_fixed: Vec<f64>,
    /// The same, float reference.
    pub peak_reference: Vec<f64>,
    /// `(max T - min T) / mean T` in %, fixed.
    pub ripple_fixed_pct: f64,
    /// The same, reference.
    pub ripple_reference_pct: Option<f64>,
    /// `(max P - min P) / max P` in %, fixed.
    pub peak_modulation_fixed_pct: f64,
    /// The same, reference.
    pub peak_modulation_reference_pct: Option<f64>,
}

/// Per-pixel excess flicker between two consecutive frames.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PairFlicker {
    /// The later frame.
    pub frame: u32,
    /// Largest excess, Weber units.
    pub max_weber: f64,
    /// Mean excess over the pixels, Weber units.
    pub mean_weber: f64,
    /// Pixels whose excess is above 1 (a visible step the reference does not make).
    pub visible_pixels: u64,
}

/// Temporal dither over the static pixels.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DitherTemporal {
    /// Pixels whose reference value is the same in every frame.
    pub static_pixels: u64,
    /// Largest |mean of the fixed codes over the frames - the reference value|, DAC codes.
    pub max_mean_error: f64,
    /// Mean of the same over the static pixels.
    pub mean_mean_error: f64,
    /// Static pixels whose fixed code steps by more than a Weber fraction between frames.
    pub flickering_pixels: u64,
    /// Frames averaged.
    pub frames: u32,
}

/// The temporal section of a sequence report.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TemporalReport {
    /// Frame pairs compared.
    pub pairs: u64,
    /// Largest per-pixel excess flicker over the sequence, Weber units (`None`: no reference).
    pub max_excess_weber: Option<f64>,
    /// Mean per-pixel excess over all pairs and pixels.
    pub mean_excess_weber: Option<f64>,
    /// Pixel changes above 1 Weber unit that the reference does not make, over all pairs.
    pub visible_excess: u64,
    /// Per pair (empty without a reference).
    pub per_pair: Vec<PairFlicker>,
    /// The small moving objects.
    pub objects: Vec<ObjectFlicker>,
    /// The temporal dither (`None` unless `dither.temporal`).
    pub dither: Option<DitherTemporal>,
}

/// How a frame's codes become displayed luminance.
enum Light {
    /// One grey channel: the luminance of each code.
    Grey,
    /// R, G, B mixed to `Y` through the colour display, times full white (cd/m²).
    Colour(Box<ColourDisplay>, f64),
}

/// The accumulator of [`TemporalReport`].
pub struct Temporal {
    light: Light,
    /// Channel 0's luminance of each code (the grey channel, or R).
    lum: Vec<f64>,
    weber: f64,
    width: u32,
    /// This frame's and the previous frame's luminance, fixed and reference (kept in the
    /// same buffers from frame to frame).
    cur: (Vec<f64>, Vec<f64>),
    prev: Option<(Vec<f64>, Vec<f64>)>,
    /// What the figures are computed from.
    state: TemporalState,
}

impl Temporal {
    /// An accumulator for frames of `width` pixels per row on display `model`, following the
    /// small objects `objects` (index, kind), with the temporal dither's sums when `dither`.
    pub fn new(
        model: &DisplayModel,
        width: u32,
        objects: Vec<(usize, String)>,
        dither: bool,
    ) -> Self {
        Self::with_light(Light::Grey, model, width, objects, dither)
    }

    /// [`Temporal::new`] for R, G, B frames on colour display `display` (full white
    /// `b_max`, cd/m²); the temporal dither's figures are channel R's.
    pub fn colour(
        display: &ColourDisplay,
        b_max: f64,
        width: u32,
        objects: Vec<(usize, String)>,
        dither: bool,
    ) -> Self {
        let light = Light::Colour(Box::new(display.clone()), b_max);
        Self::with_light(light, display.channel(0), width, objects, dither)
    }

    fn with_light(
        light: Light,
        model: &DisplayModel,
        width: u32,
        objects: Vec<(usize, String)>,
        dither: bool,
    ) -> Self {
        Self {
            light,
            lum: model.luminance_table(),
            weber: model.weber,
            width,
            cur: (Vec::new(), Vec::new()),
            prev: None,
            state: TemporalState {
                objects: objects
                    .into_iter()
                    .map(|(object, kind)| ObjectFlicker {
                        object,
                        kind,
                        ..ObjectFlicker::default()
                    })
                    .collect(),
                dither: dither.then(DitherState::default),
                ..TemporalState::default()
            },
        }
    }

    /// The displayed luminance of a frame's planes (one grey plane, or R, G, B) into `out`.
    fn light(&self, planes: &[&[u16]], out: &mut Vec<f64>) {
        out.clear();
        match &self.light {
            Light::Grey => out.extend(planes[0].iter().map(|&c| self.lum[c as usize])),
            Light::Colour(d, b_max) => {
                let [r, g, b] = [0, 1, 2].map(|c| planes[c]);
                out.extend(
                    r.iter()
                        .zip(g)
                        .zip(b)
                        .map(|((&r, &g), &b)| d.xyz([r, g, b]).y * b_max),
                );
            }
        }
    }

    /// Takes frame `fixed` (and its `reference`; planes as for [`Temporal::add`]) as the
    /// frame before the first one added, without adding it: the first frame added is then
    /// compared with it (a shard's lead-in frame, the last frame of the shard before).
    pub fn prime(&mut self, fixed: &[&[u16]], reference: Option<&[&[u16]]>) {
        let (mut lf, mut lr) = self.prev.take().unwrap_or_default();
        self.light(fixed, &mut lf);
        lr.clear();
        if let Some(r) = reference {
            self.light(r, &mut lr);
        }
        self.prev = Some((lf, lr));
    }

    /// Total luminance above the background and the peak over window `w` of luminance
    /// plane `lum` (the background: the median of the window's border; a grey plane's
    /// luminance rises with the code, so that is the median code's).
    fn window(&self, lum: &[f64], w: Window) -> (f64, f64) {
        let at = |x: u32, y: u32| lum[(y * self.width + x) as usize];
        let mut ring: Vec<f64> = Vec::new();
        for y in w.y0..w.y1 {
            for x in w.x0..w.x1 {
                if y == w.y0 || y + 1 == w.y1 || x == w.x0 || x + 1 == w.x1 {
                    ring.push(at(x, y));
                }
            }
        }
        ring.sort_unstable_by(f64::total_cmp);
        let bg = ring.get(ring.len() / 2).copied().unwrap_or(self.lum[0]);
        let (mut total, mut peak) = (0.0, 0.0f64);
        for y in w.y0..w.y1 {
            for x in w.x0..w.x1 {
                let d = at(x, y) - bg;
                total += d;
                peak = peak.max(d);
            }
        }
        (total, peak)
    }

    /// Adds frame `frame`: its fixed codes (one grey plane, or R, G, B), the reference's
    /// (if run), each small object's window (in the order given to [`Temporal::new`]) and,
    /// for a temporal dither, the reference's value before the dither (DAC codes as reals,
    /// channel 0).
    pub fn add(
        &mut self,
        frame: u32,
        fixed: &[&[u16]],
        reference: Option<&[&[u16]]>,
        windows: &[Window],
        ideal: Option<&[f64]>,
    ) {
        let (mut lf, mut lr) = std::mem::take(&mut self.cur);
        self.light(fixed, &mut lf);
        if let Some(r) = reference {
            self.light(r, &mut lr);
        }
        for (k, w) in windows.iter().enumerate() {
            let (t, p) = self.window(&lf, *w);
            let o = &mut self.state.objects[k];
            o.total_fixed.push(t);
            o.peak_fixed.push(p);
            if reference.is_some() {
                let (t, p) = self.window(&lr, *w);
                let o = &mut self.state.objects[k];
                o.total_reference.push(t);
                o.peak_reference.push(p);
            }
        }
        if let (Some((pf, pr)), Some(_)) = (&self.prev, reference)
            && !pr.is_empty()
        {
            let (mut max, mut sum, mut visible) = (0.0f64, 0.0, 0u64);
            for i in 0..lf.len() {
                let df = lf[i] - pf[i];
                let dr = lr[i] - pr[i];
                let e = (df - dr).abs() / (self.weber * lr[i].max(pr[i]));
                max = max.max(e);
                sum += e;
                visible += u64::from(e > 1.0);
            }
            self.state.pair_sums.push(sum);
            self.state.pixels += lf.len() as u64;
            self.state.pairs.push(PairFlicker {
                frame,
                max_weber: max,
                mean_weber: sum / lf.len().max(1) as f64,
                visible_pixels: visible,
            });
        }
        let fixed = fixed[0];
        if let (Some(d), Some(ideal)) = (&mut self.state.dither, ideal) {
            if d.frames == 0 {
                d.ideal = ideal.to_vec();
                d.moved = vec![false; ideal.len()];
                d.sum = vec![0; ideal.len()];
                d.lo = fixed.to_vec();
                d.hi = fixed.to_vec();
            }
            for i in 0..fixed.len() {
                d.moved[i] |= ideal[i] != d.ideal[i];
                d.sum[i] += u32::from(fixed[i]);
                d.lo[i] = d.lo[i].min(fixed[i]);
                d.hi[i] = d.hi[i].max(fixed[i]);
            }
            d.frames += 1;
        }
        if reference.is_none() {
            lr.clear();
        }
        // This frame's planes become the previous frame's, whose buffers the next takes.
        self.cur = self.prev.replace((lf, lr)).unwrap_or_default();
    }

    /// The report of the frames added.
    pub fn finish(self) -> TemporalReport {
        self.state.report(&self.lum, self.weber)
    }

    /// The report of the frames added and the state it is computed from (a shard's part).
    pub fn finish_with_state(self) -> (TemporalReport, TemporalState) {
        let report = self.state.clone().report(&self.lum, self.weber);
        (report, self.state)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> DisplayModel {
        DisplayModel {
            b_min: 1.0,
            b_max: 100.0,
            gamma: 2.4,
            weber: 0.02,
            max_code: 255.0,
        }
    }

    #[test]
    fn a_fixed_output_that_follows_the_reference_has_no_excess_flicker() {
        let mut t = Temporal::new(&model(), 4, vec![], false);
        let a = [10u16, 200, 30, 40];
        let b = [12u16, 180, 30, 90];
        t.add(0, &[&a], Some(&[&a]), &[], None);
        t.add(1, &[&b], Some(&[&b]), &[], None);
        let r = t.finish();
        assert_eq!(r.pairs, 1);
        assert_eq!(r.max_excess_weber, Some(0.0));
        // A pixel the fixed output steps while the reference holds is visible.
        let mut t = Temporal::new(&model(), 4, vec![], false);
        t.add(0, &[&a], Some(&[&a]), &[], None);
        t.add(1, &[&b], Some(&[&a]), &[], None);
        let r = t.finish();
        assert!(r.max_excess_weber.unwrap() > 1.0);
        assert_eq!(r.visible_excess, 3);
    }

    #[test]
    fn an_object_that_keeps_its_light_has_no_ripple_and_one_that_jumps_has() {
        let w = Window {
            x0: 0,
            y0: 0,
            x1: 5,
            y1: 5,
        };
        let mut t = Temporal::new(&model(), 5, vec![(0, "light_point".into())], false);
        let mut f = vec![0u16; 25];
        for k in 0..4u32 {
            f.fill(0);
            f[12 + (k % 2) as usize] = 200;
            t.add(k, &[&f], None, &[w], None);
        }
        let r = t.finish();
        assert_eq!(r.objects[0].ripple_fixed_pct, 0.0);
        assert_eq!(r.objects[0].peak_modulation_fixed_pct, 0.0);
        assert!(r.max_excess_weber.is_none());
        let mut t = Temporal::new(&model(), 5, vec![(0, "light_point".into())], false);
        for k in 0..4u32 {
            f.fill(0);
            f[12] = if k % 2 == 0 { 200 } else { 100 };
            t.add(k, &[&f], None, &[w], None);
        }
        let r = t.finish();
        assert!(r.objects[0].ripple_fixed_pct > 50.0);
    }

    #[test]
    fn a_temporal_dither_that_averages_to_the_value_has_no_mean_error() {
        let mut t = Temporal::new(&model(), 2, vec![], true);
        // Value 10.5 dithered as 10, 11, 10, 11; the second pixel moves and is left out.
        for k in 0..4u32 {
            let c = 10 + (k % 2) as u16;
            t.add(k, &[&[c, 50]], None, &[], Some(&[10.5, 50.0 + k as f64]));
        }
        let d = t.finish().dither.expect("temporal dither");
        assert_eq!(d.static_pixels, 1);
        assert_eq!(d.max_mean_error, 0.0);
        assert_eq!(d.frames, 4);
    }

    #[test]
    fn a_primed_second_half_joins_to_the_whole_run_in_grey_and_colour() {
        let display = ColourDisplay::new(&crate::scene::Display::default(), [8, 8, 8]);
        let m = display.channel(0);
        let new = |colour: bool| {
            let objects = vec![(0, "light_point".into())];
            if colour {
                Temporal::colour(&display, 100.0, 3, objects, true)
            } else {
                Temporal::new(display.channel(0), 3, objects, true)
            }
        };
        let w = Window {
            x0: 0,
            y0: 0,
            x1: 3,
            y1: 3,
        };
        // Frame k: fixed and reference planes (R, G, B; grey uses the first).
        let frame = |k: u16| {
            let p = |o: u16| {
                (0..9)
                    .map(|i| (i * 29 + k * 37 + o) % 256)
                    .collect::<Vec<u16>>()
            };
            ([p(0), p(5), p(11)], [p(1), p(5), p(9)])
        };
        for colour in [false, true] {
            let n = if colour { 3 } else { 1 };
            let add = |t: &mut Temporal, k: u16| {
                let (f, r) = frame(k);
                let (f, r) = (
                    f.each_ref().map(Vec::as_slice),
                    r.each_ref().map(Vec::as_slice),
                );
                let ideal: Vec<f64> = r[0].iter().map(|&c| f64::from(c)).collect();
                t.add(u32::from(k), &f[..n], Some(&r[..n]), &[w], Some(&ideal));
            };
            let mut whole = new(colour);
            (0..5).for_each(|k| add(&mut whole, k));
            let (mut first, mut second) = (new(colour), new(colour));
            (0..2).for_each(|k| add(&mut first, k));
            let (f, r) = frame(1);
            let (f, r) = (
                f.each_ref().map(Vec::as_slice),
                r.each_ref().map(Vec::as_slice),
            );
            second.prime(&f[..n], Some(&r[..n]));
            (2..5).for_each(|k| add(&mut second, k));
            let mut state = first.finish_with_state().1;
            state.join(second.finish_with_state().1);
            let whole = serde_json::to_value(whole.finish()).unwrap();
            let joined = serde_json::to_value(state.report(&m.luminance_table(), m.weber));
            assert_eq!(whole["pairs"], 4, "colour {colour}");
            assert_eq!(joined.unwrap(), whole, "colour {colour}");
        }
    }
}
