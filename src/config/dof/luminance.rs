//! `[dof.luminance]`: the luminance-aware method (`dof.kind = "luminance"`); see docs/dof.md.

use serde::{Deserialize, Serialize};

/// `[dof.luminance]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LuminanceCfg {}

impl LuminanceCfg {
    /// Checks the fields; returns the failing field (without the `dof.luminance.` prefix) and
    /// the allowed range.
    pub fn validate(&self) -> Result<(), (String, String)> {
        Ok(())
    }

    /// What a field (without the `dof.luminance.` prefix) expects: the message hint.
    pub(crate) fn hint(field: &str) -> Option<String> {
        match field {
            "" => Some("a table [dof.luminance] (each field optional)".into()),
            _ => None,
        }
    }
}

/// `[dof.luminance]` as written in the hardware file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawLuminance {}

impl RawLuminance {
    /// Overrides the given fields.
    pub(crate) fn apply(self, _c: &mut LuminanceCfg) {}
}
