//! The runner: executes the plan stage by stage through the stage contract, and reuses
//! every stage result whose key (its own key material chained with its input's key) is in
//! the cache.

use super::cache::Cache;
use super::plan::Plan;
use crate::config::HwConfig;
use crate::cost::{PackCheck, pack};
use crate::error::Result;
use crate::fnv::Fnv;
use crate::scene::Scene;
use crate::stage::{
    self, Cx, DynStage, MemImage, Memo, NoMemo, RunOptions, StageId, StageReport, Taps, Tokens,
    ms_since,
};
use std::sync::Arc;
use std::time::Instant;

/// What one stage produced: the taps after it, its report, its tokens for the cycle model,
/// the pack checks of its memories and their images.
#[derive(Clone)]
pub struct Outcome {
    /// Every tap after the stage.
    pub taps: Taps,
    /// The stage's report.
    pub report: StageReport,
    /// Its tokens (`None`: no cycle model).
    pub tokens: Option<Tokens>,
    /// Its memories packed and read back.
    pub packs: Vec<PackCheck>,
    /// Its memories' contents.
    pub images: Vec<MemImage>,
}

/// One executed (or reused) stage.
#[derive(Clone)]
pub struct Step {
    /// The stage.
    pub id: StageId,
    /// Its key: its key material chained with its input's key.
    pub key: u64,
    /// What it produced.
    pub outcome: Arc<Outcome>,
    /// Whether the outcome came from the cache.
    pub reused: bool,
}

/// Runs the plan's stages in order, through `last` (all when `None`).
pub fn run(
    scene: &Scene,
    hw: &HwConfig,
    plan: &Plan,
    opts: RunOptions,
    cache: Option<&Cache>,
    last: Option<StageId>,
) -> Result<Vec<Step>> {
    let memo: &dyn Memo = match cache {
        Some(c) => c,
        None => &NoMemo,
    };
    let mut taps = Taps {
        host: Some(plan.host.clone()),
        ..Taps::default()
    };
    let mut key = plan.key;
    let mut steps = Vec::with_capacity(plan.order().len());
    for &id in plan.order() {
        let stage = stage::get(id);
        let cx = Cx {
            scene,
            hw,
            layout: &plan.layout,
            opts,
            input_key: key,
            memo,
        };
        let material = stage.key(&cx);
        let k = Fnv::new()
            .u64(key)
            .str(id.name())
            .str(&material.to_string())
            .str(&serde_json::to_string(&opts).unwrap_or_default())
            .finish();
        let (outcome, reused) = match cache {
            Some(c) => c.stage(k, || execute(stage, &cx, &taps))?,
            None => (Arc::new(execute(stage, &cx, &taps)?), false),
        };
        taps = outcome.taps.clone();
        key = k;
        steps.push(Step {
            id,
            key: k,
            outcome,
            reused,
        });
        if last == Some(id) {
            break;
        }
    }
    Ok(steps)
}

/// Runs one stage through the contract on the taps of its input.
fn execute(stage: &dyn DynStage, cx: &Cx, input: &Taps) -> Result<Outcome> {
    let mut taps = input.clone();
    let t = Instant::now();
    let (fixed, facts) = stage.fixed(cx, &mut taps)?;
    let fixed_ms = ms_since(t);
    let mut notes = facts.notes;
    let t = Instant::now();
    stage.float(cx, &fixed, &mut taps, &mut notes)?;
    let float_ms = ms_since(t);
    let t = Instant::now();
    let local = if cx.opts.stage_local {
        stage.local(cx, &fixed, input, &taps, &mut notes)
    } else {
        None
    };
    let local_ms = ms_since(t);
    let tokens = stage.tokens(cx, &fixed);
    let cost = stage.cost(cx, &fixed);
    let images = stage.memories(cx, &fixed, &taps);
    let packs = pack::check(&cost, &images);
    let report = StageReport {
        name: stage.id().name().to_string(),
        fixed_ms,
        float_ms,
        local_ms,
        work: facts
            .work
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect(),
        cost,
        signals: facts.signals,
        local,
        notes,
    };
    Ok(Outcome {
        taps,
        report,
        tokens,
        packs,
        images,
    })
}
