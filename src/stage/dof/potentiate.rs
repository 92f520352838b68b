//! Depth of field after a log-coded frame (`coding.kind = "log-add"`): the frame memory
//! holds log codes, but every DoF method blurs light, which adds linearly. A potentiation
//! LUT between the frame memory and the DoF input (the structure-(a) idea applied to the
//! frame word) turns each log code `a` into the linear frame code
//! `round(W (K^L - 1)/(K - 1))`, `L = (a - off) / (G 2^fa)` clamped to [0, 1], the zero code
//! to 0, `W` the full white of `accumulate.frame`: the same linear intensity the eq. 15
//! gamma LUT shows for that code. The DoF output is then a linear frame, and the gamma stage
//! uses its linear LUT.

use crate::fixed::{Overflow, QFormat, Quant, Quantizer, SignalStats, quantize_slice_f64};
use crate::stage::logdomain::{LogAdder, log_gamma_linear};
use crate::stage::{Cost, MemImage, Memory};
use std::sync::Arc;

/// Name of the potentiation LUT.
pub const POT_LUT: &str = "dof potentiation LUT";

/// The potentiation LUT: one linear frame code per log frame code.
#[derive(Clone, Debug)]
pub struct FramePotentiation {
    /// Entries `0..=add.max`.
    pub table: Arc<Vec<u32>>,
    /// Bits of an entry (the linear frame format's width).
    pub width: u32,
    /// `dof.potentiation`: the entries' quantisation (`UQ<width>.0`, RND_INF, SAT).
    pub stats: SignalStats,
}

impl FramePotentiation {
    /// Builds the LUT of `add`'s log frame codes into the linear frame format `frame`
    /// (integer codes: its fraction bits are kept as fraction bits of the entries).
    pub fn build(add: &LogAdder, frame: QFormat) -> Self {
        let q = Quantizer::new(
            QFormat::new(false, frame.int_bits, frame.frac_bits),
            Quant::RndInf,
            Overflow::Sat,
        );
        let white = frame.max_code() as f64 / (1u64 << frame.frac_bits) as f64;
        let xs: Vec<f64> = (0..=add.max)
            .map(|a| log_gamma_linear(add, a) * white)
            .collect();
        let mut codes = vec![0i64; xs.len()];
        let mut stats = SignalStats::new("dof.potentiation", q.format);
        quantize_slice_f64(&q, &xs, &mut codes, &mut stats);
        Self {
            table: Arc::new(codes.into_iter().map(|c| c as u32).collect()),
            width: q.format.total_bits(),
            stats,
        }
    }

    /// The linear frame of a log frame (codes above the table saturate to its last entry).
    pub fn apply(&self, log: &[u32]) -> Vec<u32> {
        let last = self.table.len() - 1;
        log.iter()
            .map(|&a| self.table[(a as usize).min(last)])
            .collect()
    }

    /// Cost: one ROM.
    pub fn cost(&self) -> Cost {
        Cost::new(
            vec![Memory::rom(POT_LUT, self.table.len() as u64, self.width)],
            vec![],
            vec![],
        )
    }

    /// The ROM's image for the pack check.
    pub fn image(&self) -> MemImage {
        MemImage::table(POT_LUT, self.width, self.table.clone())
    }
}
