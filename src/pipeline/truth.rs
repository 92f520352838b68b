//! The depth-of-field truth of a render (`RunOptions::dof_truth_samples`, see
//! [`crate::truth`]): the lens-averaged frame, memoised in the cache under a key of
//! everything it depends on (the scene and the lens-sample count: its sampling is the same
//! for every hardware), so a sweep computes it once per scene; and its report.

use super::cache::Cache;
use super::plan::Plan;
use super::run::Step;
use crate::config::HwConfig;
use crate::error::Result;
use crate::fnv::Fnv;
use crate::scene::Scene;
use crate::stage::{Memo, NoMemo, RunOptions, StageId, memo};
use crate::truth::{self, Images, TruthFrame, TruthReport, TruthSetup};

/// The memo key of a truth frame: the plan's key (the scene and the tool version) and the
/// lens-sample count (the truth's sampling is the same for every hardware, see
/// [`crate::truth::truth_hw`]).
pub fn key(plan: &Plan, lens_samples: u32) -> u64 {
    Fnv::new()
        .u64(plan.key)
        .str("dof truth (area-sampled, box)")
        .u64(u64::from(lens_samples))
        .finish()
}

/// The truth report of a render and the truth's DAC codes, when `opts` asks for it and the plan has a dof stage
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
) -> Result<Option<(TruthReport, Vec<u16>)>> {
    let n = opts.dof_truth_samples;
    if n == 0 || !plan.layout.has(StageId::Dof) {
        return Ok(None);
    }
    let setup = TruthSetup::new(scene, n)?;
    let m: &dyn Memo = match cache {
        Some(c) => c,
        None => &NoMemo,
    };
    let mut made = false;
    let frame = memo::<TruthFrame>(m, key(plan, n), || {
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
    let report = truth::assess(scene, hw, &frame, !made, &images);
    Ok(Some((report, truth::truth_dac(&frame, scene, hw))))
}
