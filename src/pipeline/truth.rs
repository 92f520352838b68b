//! The depth-of-field truth of a render (`RunOptions::dof_truth_samples`, see
//! [`crate::truth`]): the lens-averaged frame, memoised in the cache under a key of
//! everything it depends on (the scene, the `input`, `raster`, `visibility` and
//! `accumulate` sections and the lens-sample count; not the depth-of-field method, the
//! gamma or the dither), so a sweep computes it once per scene; and its report.

use super::cache::Cache;
use super::plan::Plan;
use super::run::Step;
use crate::config::HwConfig;
use crate::error::Result;
use crate::fnv::Fnv;
use crate::scene::Scene;
use crate::stage::{Memo, NoMemo, RunOptions, StageId, memo};
use crate::truth::{self, Images, TruthFrame, TruthReport, TruthSetup};

/// The memo key of a truth frame: the plan's key (the scene and the tool version), the
/// hardware sections the float path reads, and the lens-sample count.
pub fn key(plan: &Plan, hw: &HwConfig, lens_samples: u32) -> u64 {
    let sections: Vec<serde_json::Value> = ["input", "raster", "visibility", "accumulate"]
        .iter()
        .map(|s| hw.section(s))
        .collect();
    Fnv::new()
        .u64(plan.key)
        .str("dof truth")
        .str(&serde_json::Value::Array(sections).to_string())
        .u64(u64::from(lens_samples))
        .finish()
}

/// The truth report of a render, when `opts` asks for it and the plan has a dof stage
/// (a pinhole plan gets a note instead, [`Plan::notes`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn report(
    scene: &Scene,
    hw: &HwConfig,
    plan: &Plan,
    steps: &[Step],
    dac: &[u16],
    dac_ref: &[u16],
    cache: Option<&Cache>,
    opts: RunOptions,
) -> Result<Option<TruthReport>> {
    let n = opts.dof_truth_samples;
    if n == 0 || !plan.layout.has(StageId::Dof) {
        return Ok(None);
    }
    let setup = TruthSetup::new(scene, hw, n)?;
    let m: &dyn Memo = match cache {
        Some(c) => c,
        None => &NoMemo,
    };
    let mut made = false;
    let frame = memo::<TruthFrame>(m, key(plan, hw, n), || {
        made = true;
        setup.run()
    });
    let acc = steps
        .iter()
        .find(|s| s.id == StageId::Accumulate)
        .expect("every plan runs accumulate");
    let images = Images {
        fixed: dac,
        float: dac_ref,
        frame: &acc.outcome.taps.fixed.frame().frame,
    };
    Ok(Some(truth::assess(scene, hw, &frame, !made, &images)))
}
