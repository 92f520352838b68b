//! `[dof]`: the layered depth-of-field datapath (docs/dof.md).

use super::set;
use crate::fixed::{Overflow, Quant};
use serde::{Deserialize, Serialize};

/// Largest configurable mask half-size M (pixels): a `(2M+1)`-tap line.
pub const MAX_HALF_SIZE_LIMIT: u32 = 64;

/// `dof.coef_bits`, `dof.alpha_bits`, `dof.guard_bits`, `dof.line_bits`, `dof.acc_bits`: the
/// ranges of the word widths.
pub const DOF_BITS: [(&str, u32, u32); 5] = [
    ("coef_bits", 4, 20),
    ("alpha_bits", 4, 24),
    ("guard_bits", 0, 16),
    ("line_bits", 8, 64),
    ("acc_bits", 8, 96),
];

/// The `[dof]` section: the layered depth-of-field datapath (used only with a thin-lens camera).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DofCfg {
    /// Difference-degree threshold P of a layer, in (0, 1).
    pub p: f64,
    /// Mask cut ratio k (edge / centre), in (0, 1).
    pub k: f64,
    /// Fraction bits of the 1-D mask coefficients (UQ0.f; they sum to 2^f).
    pub coef_bits: u32,
    /// Fraction bits of the compositing alpha.
    pub alpha_bits: u32,
    /// Guard fraction bits of the layer colour and the composite.
    pub guard_bits: u32,
    /// Width of the line-buffer word (horizontal-pass sum of `x * m`).
    pub line_bits: u32,
    /// Width of the vertical-pass accumulator.
    pub acc_bits: u32,
    /// Largest mask half-size M the hardware holds.
    pub max_half_size: u32,
    /// Rounding of the composite to the frame format.
    pub quant: Quant,
    /// Overflow of the line buffer and accumulator (SAT or ERROR).
    pub overflow: Overflow,
}

impl DofCfg {
    /// Checks the `[dof]` fields; returns the failing field and the allowed range.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let p = self;
        let err = |f: &str, m: String| Err((format!("dof.{f}"), m));
        if !(p.p.is_finite() && p.p > 0.0 && p.p < 1.0) {
            return err(
                "p",
                format!(
                    "must be in (0, 1) (the layer difference-degree threshold), got {}",
                    crate::files::num(p.p)
                ),
            );
        }
        if !(p.k.is_finite() && p.k > 0.0 && p.k < 1.0) {
            return err(
                "k",
                format!(
                    "must be in (0, 1) (mask edge/centre ratio), got {}",
                    crate::files::num(p.k)
                ),
            );
        }
        let widths = [
            p.coef_bits,
            p.alpha_bits,
            p.guard_bits,
            p.line_bits,
            p.acc_bits,
        ];
        for ((field, lo, hi), v) in DOF_BITS.into_iter().zip(widths) {
            if !(lo..=hi).contains(&v) {
                return err(field, format!("must be in {lo}..={hi}, got {v}"));
            }
        }
        if !(1..=MAX_HALF_SIZE_LIMIT).contains(&p.max_half_size) {
            return err(
                "max_half_size",
                format!(
                    "must be in 1..={MAX_HALF_SIZE_LIMIT} pixels, got {}",
                    p.max_half_size
                ),
            );
        }
        if !matches!(p.overflow, Overflow::Sat | Overflow::Error) {
            return err(
                "overflow",
                format!("must be SAT or ERROR, got {:?}", p.overflow),
            );
        }
        Ok(())
    }
}

/// `[dof]` as written in the hardware file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawDof {
    p: Option<f64>,
    k: Option<f64>,
    coef_bits: Option<u32>,
    alpha_bits: Option<u32>,
    guard_bits: Option<u32>,
    line_bits: Option<u32>,
    acc_bits: Option<u32>,
    max_half_size: Option<u32>,
    quant: Option<Quant>,
    overflow: Option<Overflow>,
}

impl RawDof {
    /// Overrides the given fields.
    pub(super) fn apply(self, c: &mut DofCfg) {
        set(&mut c.p, self.p);
        set(&mut c.k, self.k);
        set(&mut c.coef_bits, self.coef_bits);
        set(&mut c.alpha_bits, self.alpha_bits);
        set(&mut c.guard_bits, self.guard_bits);
        set(&mut c.line_bits, self.line_bits);
        set(&mut c.acc_bits, self.acc_bits);
        set(&mut c.max_half_size, self.max_half_size);
        set(&mut c.quant, self.quant);
        set(&mut c.overflow, self.overflow);
    }
}
