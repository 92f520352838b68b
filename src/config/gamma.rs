//! `[gamma]`: the gamma-correction LUT and the DAC.

use super::set;
use crate::fixed::Quant;
use serde::{Deserialize, Serialize};

/// `gamma.dac_bits`: the DAC width.
pub const DAC_BITS: std::ops::RangeInclusive<u32> = 1..=16;
/// Largest `gamma.gamma` (the lower bound is exclusive 0).
pub const MAX_GAMMA: f64 = 5.0;

/// Gamma-correction LUT.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GammaCfg {
    /// DAC width in bits.
    pub dac_bits: u32,
    /// Rounding used when the LUT is built from the formula (and at the reference DAC).
    pub quant: Quant,
    /// Gamma the LUT corrects; `None` takes the scene's display gamma.
    pub gamma: Option<f64>,
    /// `false` models a system without gamma correction (a linear LUT).
    pub correction: bool,
}

/// `[gamma]` as written in the hardware file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawGamma {
    pub(super) dac_bits: Option<super::PerChannel<u32>>,
    quant: Option<Quant>,
    gamma: Option<f64>,
    correction: Option<bool>,
}

impl RawGamma {
    /// Overrides the given fields.
    pub(super) fn apply(self, c: &mut GammaCfg) {
        set(&mut c.dac_bits, self.dac_bits.map(|d| d.first()));
        set(&mut c.quant, self.quant);
        if self.gamma.is_some() {
            c.gamma = self.gamma;
        }
        set(&mut c.correction, self.correction);
    }
}

impl GammaCfg {
    /// Checks the ranges; returns the failing field and a message.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let d = self.dac_bits;
        if !DAC_BITS.contains(&d) {
            return Err((
                "gamma.dac_bits".into(),
                format!(
                    "must be in {}..={}, got {d}",
                    DAC_BITS.start(),
                    DAC_BITS.end()
                ),
            ));
        }
        if let Some(g) = self.gamma
            && !(g.is_finite() && g > 0.0 && g <= MAX_GAMMA)
        {
            return Err((
                "gamma.gamma".into(),
                format!(
                    "must be a finite number in (0, {MAX_GAMMA}], got {}",
                    crate::files::num(g)
                ),
            ));
        }
        Ok(())
    }
}
