//! `[dof.downsample]`: the downsample-and-blend method (`dof.kind = "downsample"`); see docs/dof.md.

use serde::{Deserialize, Serialize};

/// `[dof.downsample]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct DownsampleCfg {}

impl DownsampleCfg {
    /// Checks the fields; returns the failing field (without the `dof.downsample.` prefix) and
    /// the allowed range.
    pub fn validate(&self) -> Result<(), (String, String)> {
        Ok(())
    }

    /// What a field (without the `dof.downsample.` prefix) expects: the message hint.
    pub(crate) fn hint(field: &str) -> Option<String> {
        match field {
            "" => Some("a table [dof.downsample] (each field optional)".into()),
            _ => None,
        }
    }
}

/// `[dof.downsample]` as written in the hardware file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawDownsample {}

impl RawDownsample {
    /// Overrides the given fields.
    pub(crate) fn apply(self, _c: &mut DownsampleCfg) {}
}
