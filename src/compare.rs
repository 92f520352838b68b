//! Code-by-code comparison of fixed and float outputs, and the display model.
//!
//! `codes` compares integer codes (identical fraction, histogram of differences, max
//! |diff|, mean diff, PSNR); `weber` compares displayed luminance through
//! `B = B_min + (B_max - B_min) V^gamma` as Weber fractions `|B_fixed - B_ref| / B_ref`.

use crate::scene::Display;
pub use crate::stage::{WeberCompare, weber_of};
use serde::Serialize;
use std::collections::BTreeMap;

/// Result of an integer code comparison.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CodeCompare {
    /// Codes compared.
    pub count: u64,
    /// Codes that are identical.
    pub identical: u64,
    /// `identical / count`.
    pub identical_fraction: f64,
    /// Largest |fixed - reference|.
    pub max_abs_diff: u32,
    /// Mean (fixed - reference), the bias.
    pub mean_diff: f64,
    /// PSNR in dB against the reference with peak `2^bits - 1`; `null` when identical.
    pub psnr_db: Option<f64>,
    /// Histogram: difference (fixed - reference) to count.
    pub histogram: BTreeMap<i32, u64>,
}

/// Compares two code buffers of the same length.
pub fn codes(fixed: &[u16], reference: &[u16], bits: u32) -> CodeCompare {
    assert_eq!(fixed.len(), reference.len(), "buffers of different length");
    let mut c = CodeCompare {
        count: fixed.len() as u64,
        ..Default::default()
    };
    let (mut sum, mut sq) = (0i64, 0f64);
    for (&a, &b) in fixed.iter().zip(reference) {
        let d = a as i32 - b as i32;
        *c.histogram.entry(d).or_insert(0) += 1;
        c.max_abs_diff = c.max_abs_diff.max(d.unsigned_abs());
        sum += d as i64;
        sq += (d as f64) * (d as f64);
    }
    c.identical = c.histogram.get(&0).copied().unwrap_or(0);
    if c.count > 0 {
        c.identical_fraction = c.identical as f64 / c.count as f64;
        c.mean_diff = sum as f64 / c.count as f64;
        let mse = sq / c.count as f64;
        let peak = ((1u64 << bits) - 1) as f64;
        c.psnr_db = (mse > 0.0).then(|| 10.0 * (peak * peak / mse).log10());
    }
    c
}

/// The display: DAC code to luminance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct DisplayModel {
    /// Stray light, cd/m².
    pub b_min: f64,
    /// Full white, cd/m².
    pub b_max: f64,
    /// Display gamma.
    pub gamma: f64,
    /// Weber fraction that is just visible.
    pub weber: f64,
    /// Largest DAC code.
    pub max_code: f64,
}

impl DisplayModel {
    /// From the scene's display block and the DAC width.
    pub fn new(d: &Display, dac_bits: u32) -> Self {
        Self {
            b_min: d.b_min(),
            b_max: d.b_max,
            gamma: d.gamma,
            weber: d.weber,
            max_code: ((1u64 << dac_bits) - 1) as f64,
        }
    }
    /// Luminance of a DAC code.
    #[inline]
    pub fn luminance(&self, code: u16) -> f64 {
        self.b_min + (self.b_max - self.b_min) * (code as f64 / self.max_code).powf(self.gamma)
    }

    /// [`DisplayModel::luminance`] of every DAC code, indexed by code.
    pub fn luminance_table(&self) -> Vec<f64> {
        (0..=self.max_code as u32)
            .map(|c| self.luminance(c as u16))
            .collect()
    }
}

/// Compares displayed luminance.
pub fn weber(fixed: &[u16], reference: &[u16], m: &DisplayModel) -> WeberCompare {
    let lum = m.luminance_table();
    weber_of(
        fixed
            .iter()
            .zip(reference)
            .map(|(&a, &b)| (lum[a as usize], lum[b as usize])),
        m.weber,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_buffers() {
        let c = codes(&[1, 2, 3], &[1, 2, 3], 8);
        assert_eq!(c.identical, 3);
        assert_eq!(c.psnr_db, None);
        assert_eq!(c.max_abs_diff, 0);
    }

    #[test]
    fn histogram_and_psnr() {
        let c = codes(&[1, 2, 5, 0], &[1, 3, 3, 0], 8);
        assert_eq!(c.histogram.get(&-1), Some(&1));
        assert_eq!(c.histogram.get(&2), Some(&1));
        assert_eq!(c.max_abs_diff, 2);
        assert!((c.mean_diff - 0.25).abs() < 1e-12);
        let mse: f64 = (1.0 + 4.0) / 4.0;
        assert!((c.psnr_db.unwrap() - 10.0 * (255.0f64 * 255.0 / mse).log10()).abs() < 1e-9);
    }
}
