//! `[input]`: quantisation of the host's screen-space vertices.

use super::set;
use crate::fixed::{Overflow, QFormat, Quant, Quantizer};
use serde::{Deserialize, Serialize};

/// Input quantisation of screen-space vertices.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InputCfg {
    /// x and y; fraction bits are the sub-pixel bits.
    pub coord: Quantizer,
    /// Screen depth in [0, 1).
    pub z: Quantizer,
    /// Vertex intensity in accumulator codes (full white = 2^int_bits - 1).
    pub intensity: Quantizer,
}

/// `[input]` as written in the hardware file (every field optional).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawInput {
    coord: Option<QFormat>,
    z: Option<QFormat>,
    pub(super) intensity: Option<super::PerChannel<QFormat>>,
    quant: Option<Quant>,
    overflow: Option<Overflow>,
}

impl RawInput {
    /// Overrides the given fields; `quant` and `overflow` apply to all three quantisers.
    pub(super) fn apply(self, c: &mut InputCfg) {
        for q in [&mut c.coord, &mut c.z, &mut c.intensity] {
            set(&mut q.quant, self.quant);
            set(&mut q.overflow, self.overflow);
        }
        set(&mut c.coord.format, self.coord);
        set(&mut c.z.format, self.z);
        set(&mut c.intensity.format, self.intensity.map(|f| f.first()));
    }
}
