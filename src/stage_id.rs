//! [`StageId`]: the stages of the pipeline in flow order, the one list every other list of
//! stage names (plan, reports, cycle chains, HDL modules, CLI choices, tests) derives from.
//!
//! It sits at the bottom of the crate (beside `error`, `fixed` and `scene`) so that the
//! configuration can name the stages its sections belong to without importing the stages.

use serde::{Deserialize, Serialize};
use std::fmt;

/// A stage of the pipeline. The order of the variants is the flow order; a plan runs a
/// subsequence of it (`logdomain` only for log coding, `dof` only for a thin lens, `dither`
/// only when configured, and before `gamma` when it is placed before the LUT).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StageId {
    /// Input quantisation of the host's screen-space vertices.
    Input,
    /// Per-primitive setup: edge and plane constants (the only divides).
    Setup,
    /// Bresenham-style edge walk and incremental interpolation (adds and compares).
    Raster,
    /// Per-sample z-buffer.
    Visibility,
    /// Log-domain coding of the stored samples (log codings only).
    Logdomain,
    /// Filtering and accumulation into the frame memory.
    Accumulate,
    /// Depth of field on the finished frame (thin lens only).
    Dof,
    /// Gamma-correction LUT to the DAC.
    Gamma,
    /// Dither (ordered or error diffusion).
    Dither,
}

impl StageId {
    /// Every stage, in flow order.
    pub const ALL: [StageId; 9] = [
        StageId::Input,
        StageId::Setup,
        StageId::Raster,
        StageId::Visibility,
        StageId::Logdomain,
        StageId::Accumulate,
        StageId::Dof,
        StageId::Gamma,
        StageId::Dither,
    ];

    /// The stage's name: the same in reports, `tests/`, `benches/` and `hdl-models/`.
    pub const fn name(self) -> &'static str {
        match self {
            StageId::Input => "input",
            StageId::Setup => "setup",
            StageId::Raster => "raster",
            StageId::Visibility => "visibility",
            StageId::Logdomain => "logdomain",
            StageId::Accumulate => "accumulate",
            StageId::Dof => "dof",
            StageId::Gamma => "gamma",
            StageId::Dither => "dither",
        }
    }

    /// Position in flow order (index into [`StageId::ALL`]).
    pub const fn index(self) -> usize {
        self as usize
    }

    /// The stage of a name.
    pub fn parse(name: &str) -> Option<StageId> {
        StageId::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The names of `ids`, comma separated (for messages).
    pub fn list(ids: &[StageId]) -> String {
        ids.iter().map(|s| s.name()).collect::<Vec<_>>().join(", ")
    }
}

impl fmt::Display for StageId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for StageId {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        StageId::parse(s).ok_or_else(|| {
            format!(
                "unknown stage `{s}`; the stages are {}",
                StageId::list(&StageId::ALL)
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_in_flow_order() {
        for (i, s) in StageId::ALL.into_iter().enumerate() {
            assert_eq!(s.index(), i);
            assert_eq!(StageId::parse(s.name()), Some(s));
            assert_eq!(serde_json::to_value(s).unwrap(), s.name());
        }
        assert!(StageId::ALL.windows(2).all(|w| w[0] < w[1]));
        assert!(
            "nope"
                .parse::<StageId>()
                .unwrap_err()
                .contains("input, setup")
        );
    }
}
