//! `[visibility]`: the per-sample z-buffer word.

use super::set;
use crate::fixed::{QFormat, Quant, Quantizer};
use serde::{Deserialize, Serialize};

/// Per-sample z-buffer.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VisibilityCfg {
    /// Stored depth format and its quantisation from the interpolator.
    pub z: Quantizer,
}

/// `[visibility]` as written in the hardware file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawVisibility {
    z: Option<QFormat>,
    quant: Option<Quant>,
}

impl RawVisibility {
    /// Overrides the given fields.
    pub(super) fn apply(self, c: &mut VisibilityCfg) {
        set(&mut c.z.format, self.z);
        set(&mut c.z.quant, self.quant);
    }
}
