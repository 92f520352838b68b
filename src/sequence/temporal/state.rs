//! What the temporal figures ([`super::TemporalReport`]) are computed from: the per-pair
//! excess flicker, the small objects' series and the temporal dither's per-pixel sums,
//! serialisable so that a shard's part carries it and `igemu sequence merge` joins the
//! shards' states into the figures of the whole run (docs/sequence.md).

use super::{DitherTemporal, ObjectFlicker, PairFlicker, TemporalReport};
use serde::{Deserialize, Serialize};

/// What the temporal figures are computed from, frame by frame: a shard's part carries it so
/// that `igemu sequence merge` joins the shards' states ([`TemporalState::join`]) and
/// computes the figures of the whole run exactly as one run does ([`TemporalState::report`]).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct TemporalState {
    /// Per pair of consecutive frames.
    pub pairs: Vec<PairFlicker>,
    /// Per pair, the excess summed over its pixels (the mean over the run sums these in
    /// frame order, so that joined shards give the same mean to the last bit).
    pub pair_sums: Vec<f64>,
    /// Pixels compared over all pairs.
    pub pixels: u64,
    /// The small objects' series (their figures are computed by the report).
    pub objects: Vec<ObjectFlicker>,
    /// The temporal dither's per-pixel sums.
    pub dither: Option<DitherState>,
}

/// The temporal dither's per-pixel sums over the frames added.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct DitherState {
    /// The reference's value before the dither in the first frame.
    pub ideal: Vec<f64>,
    /// Whether the value changed in a later frame.
    pub moved: Vec<bool>,
    /// Sum of the fixed codes.
    pub sum: Vec<u32>,
    /// Smallest fixed code.
    pub lo: Vec<u16>,
    /// Largest fixed code.
    pub hi: Vec<u16>,
    /// Frames added.
    pub frames: u32,
}

fn ripple(v: &[f64]) -> f64 {
    let (lo, hi) = v
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
    if mean > 0.0 {
        100.0 * (hi - lo) / mean
    } else {
        0.0
    }
}

fn modulation(v: &[f64]) -> f64 {
    let (lo, hi) = v
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    if hi > 0.0 {
        100.0 * (hi - lo) / hi
    } else {
        0.0
    }
}

impl DitherState {
    /// Adds the sums of the frames after these (`next`, of the same screen).
    fn join(&mut self, next: DitherState) {
        if self.frames == 0 {
            *self = next;
            return;
        }
        if next.frames == 0 {
            return;
        }
        for i in 0..self.ideal.len() {
            self.moved[i] |= next.moved[i] || next.ideal[i] != self.ideal[i];
            self.sum[i] += next.sum[i];
            self.lo[i] = self.lo[i].min(next.lo[i]);
            self.hi[i] = self.hi[i].max(next.hi[i]);
        }
        self.frames += next.frames;
    }

    /// Whether every per-pixel list has `n` entries.
    pub fn has_pixels(&self, n: usize) -> bool {
        [
            self.moved.len(),
            self.sum.len(),
            self.lo.len(),
            self.hi.len(),
        ]
        .iter()
        .all(|&l| l == self.ideal.len())
            && (self.frames == 0 || self.ideal.len() == n)
    }
}

impl TemporalState {
    /// Appends the state of the frames right after these (a shard's `next`, whose first
    /// pair compares its first frame with the last of these): the pairs, the series and the
    /// dither's sums follow on; a small object is kept only when it is small in `next` too
    /// (small in every frame, as in one run).
    pub fn join(&mut self, next: TemporalState) {
        self.pairs.extend(next.pairs);
        self.pair_sums.extend(next.pair_sums);
        self.pixels += next.pixels;
        let mut later = next.objects;
        self.objects.retain_mut(|o| {
            let Some(n) = later.iter_mut().find(|n| n.object == o.object) else {
                return false;
            };
            o.total_fixed.append(&mut n.total_fixed);
            o.total_reference.append(&mut n.total_reference);
            o.peak_fixed.append(&mut n.peak_fixed);
            o.peak_reference.append(&mut n.peak_reference);
            true
        });
        match (&mut self.dither, next.dither) {
            (Some(d), Some(n)) => d.join(n),
            (d, n) => *d = d.take().or(n),
        }
    }

    /// The figures of the frames added, on the display of luminance table `lum` (per DAC
    /// code) and Weber fraction `weber`.
    pub fn report(self, lum: &[f64], weber: f64) -> TemporalReport {
        let reference = !self.pairs.is_empty();
        let objects = self
            .objects
            .into_iter()
            .map(|mut o| {
                o.ripple_fixed_pct = ripple(&o.total_fixed);
                o.peak_modulation_fixed_pct = modulation(&o.peak_fixed);
                if !o.total_reference.is_empty() {
                    o.ripple_reference_pct = Some(ripple(&o.total_reference));
                    o.peak_modulation_reference_pct = Some(modulation(&o.peak_reference));
                }
                o
            })
            .collect();
        let code = |c: u16| lum.get(c as usize).copied().unwrap_or(f64::NAN);
        let dither = self.dither.map(|d| {
            let (mut n, mut max, mut sum, mut flick) = (0u64, 0.0f64, 0.0, 0u64);
            for i in 0..d.ideal.len() {
                if d.moved[i] {
                    continue;
                }
                n += 1;
                let e = (d.sum[i] as f64 / d.frames as f64 - d.ideal[i]).abs();
                max = max.max(e);
                sum += e;
                let (lo, hi) = (code(d.lo[i]), code(d.hi[i]));
                flick += u64::from(hi - lo > weber * lo);
            }
            DitherTemporal {
                static_pixels: n,
                max_mean_error: max,
                mean_mean_error: if n > 0 { sum / n as f64 } else { 0.0 },
                flickering_pixels: flick,
                frames: d.frames,
            }
        });
        let total = self.pair_sums.iter().fold(0.0, |a, s| a + s);
        TemporalReport {
            pairs: self.pairs.len() as u64,
            max_excess_weber: reference
                .then(|| self.pairs.iter().map(|p| p.max_weber).fold(0.0, f64::max)),
            mean_excess_weber: reference.then(|| total / self.pixels.max(1) as f64),
            visible_excess: self.pairs.iter().map(|p| p.visible_pixels).sum(),
            per_pair: self.pairs,
            objects,
            dither,
        }
    }
}
