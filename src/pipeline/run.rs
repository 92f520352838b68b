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
    self, AnyFixed, Cx, DynStage, MemImage, Memo, NoMemo, RunOptions, StageId, StageReport, Taps,
    Tokens, ms_since,
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
    let band_rows = super::bands::rows(plan, opts);
    let order = plan.order();
    let mut at = 0;
    while at < order.len() {
        let id = order[at];
        let stage = stage::get(id);
        let cx = Cx {
            scene,
            hw,
            layout: &plan.layout,
            opts,
            input_key: key,
            memo,
        };
        let k = stage_key(stage, &cx, key, opts);
        if let Some(rows) = band_rows.filter(|_| super::bands::is_banded(id)) {
            // Raster, visibility and accumulate, band by band (see `bands`).
            let group: Vec<StageId> = order[at..]
                .iter()
                .copied()
                .take_while(|&s| super::bands::is_banded(s))
                .collect();
            if let Some(l) = last.filter(|l| group.contains(l) && *l != StageId::Accumulate) {
                return Err(banded_tap(scene, l, rows));
            }
            let (mut ins, mut keys) = (vec![key], vec![k]);
            for &g in &group[1..] {
                let cx = Cx {
                    input_key: keys[keys.len() - 1],
                    ..cx
                };
                ins.push(cx.input_key);
                keys.push(stage_key(stage::get(g), &cx, cx.input_key, opts));
            }
            let outs = super::bands::run(&group, scene, hw, plan, opts, memo, &ins, &taps, rows)?;
            for ((&g, &gk), o) in group.iter().zip(&keys).zip(outs) {
                taps = o.taps.clone();
                key = gk;
                steps.push(Step {
                    id: g,
                    key: gk,
                    outcome: Arc::new(o),
                    reused: false,
                });
            }
            at += group.len();
            if last.is_some_and(|l| group.contains(&l)) {
                break;
            }
            continue;
        }
        at += 1;
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

/// A stage's key: its key material chained with its input's key and the options.
fn stage_key(stage: &dyn DynStage, cx: &Cx, input: u64, opts: RunOptions) -> u64 {
    let material = stage.key(cx);
    Fnv::new()
        .u64(input)
        .str(stage.id().name())
        .str(&material.to_string())
        .str(&serde_json::to_string(&opts).unwrap_or_default())
        .finish()
}

/// The error of asking for the taps of a stage a banded run keeps no whole-screen taps of.
fn banded_tap(scene: &Scene, id: StageId, rows: u32) -> crate::error::Error {
    scene
        .error(
            "image.width, image.height",
            format!(
                "this plan runs raster, visibility and accumulate in bands of {rows} pixel rows (the screen's sample buffers would not fit in memory at once): there is no whole-screen `{id}` tap; use a smaller screen"
            ),
        )
        .into()
}

/// Runs one stage through the contract on the taps of its input.
fn execute(stage: &dyn DynStage, cx: &Cx, input: &Taps) -> Result<Outcome> {
    execute_keep(stage, cx, input).map(|o| o.0)
}

/// [`execute`], also returning the stage's private result.
pub(super) fn execute_keep(
    stage: &dyn DynStage,
    cx: &Cx,
    input: &Taps,
) -> Result<(Outcome, AnyFixed)> {
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
    Ok((
        Outcome {
            taps,
            report,
            tokens,
            packs,
            images,
        },
        fixed,
    ))
}
