//! The runner: executes the plan stage by stage through the stage contract, and reuses
//! every stage result whose key (its own key material chained with its input's key) is in
//! the cache.

use super::bands::LaneIn;
use super::cache::Cache;
use super::plan::Plan;
use crate::config::HwConfig;
use crate::cost::{PackCheck, pack};
use crate::error::Result;
use crate::fnv::Fnv;
use crate::scene::Scene;
use crate::stage::{
    self, AnyFixed, ChannelFrames, Cx, DynStage, MemImage, Memo, Pool, RunOptions, StageId,
    StageReport, Taps, Tokens, ms_since,
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

/// Runs the plan's stages in order, through `last` (all when `None`): channel 0's steps
/// (a grey render's only ones). See [`run_lanes`] for the other channels of a colour render.
pub fn run(
    scene: &Scene,
    hw: &HwConfig,
    plan: &Plan,
    opts: RunOptions,
    cache: Option<&Cache>,
    last: Option<StageId>,
) -> Result<Vec<Step>> {
    run_lanes(scene, hw, plan, opts, cache, last, &Pool::new()).map(|(steps, _)| steps)
}

/// Runs the plan's stages in order, through `last` (all when `None`). The geometry stages
/// (input to visibility) run once and carry every channel; for a colour render the stages
/// after visibility then run once per channel, each on its channel's samples with its
/// channel's word widths ([`HwConfig::channel`]): channel 0's steps come first (with the
/// geometry's), then the steps after visibility of channels 1.. (one list each). The
/// stages take their planes from `pool` (an empty one for a one-shot run).
pub fn run_lanes(
    scene: &Scene,
    hw: &HwConfig,
    plan: &Plan,
    opts: RunOptions,
    cache: Option<&Cache>,
    last: Option<StageId>,
    pool: &Pool,
) -> Result<(Vec<Step>, Vec<Vec<Step>>)> {
    // Without a stage cache the pool memoises (a run of frames makes its ROMs once).
    let memo: &dyn Memo = match cache {
        Some(c) => c,
        None => pool,
    };
    let taps = Taps {
        host: Some(plan.host.clone()),
        ..Taps::default()
    };
    let order = plan.order();
    let channels = plan.layout.channels;
    let band_rows = super::bands::rows(plan, opts);
    // A banded colour run splits into lanes after accumulate (the bands run every lane's).
    let lanes_from = if band_rows.is_some() {
        StageId::Accumulate
    } else {
        StageId::Visibility
    };
    let split = if channels > 1 {
        order
            .iter()
            .position(|&s| s == lanes_from)
            .map_or(order.len(), |v| v + 1)
    } else {
        order.len()
    };
    let mut run = Runner {
        scene,
        plan,
        opts,
        cache,
        memo,
        pool,
        last,
        band_rows,
        lane_accs: Vec::new(),
    };
    let mut steps = Vec::with_capacity(order.len());
    let (taps, key, done) = run.stages(hw, &order[..split], taps, plan.key, &mut steps)?;
    if done || split == order.len() {
        return Ok((steps, Vec::new()));
    }
    // The lanes run stage by stage, so that a stage reading every channel's frame finds
    // them all finished. After a banded run, each lane starts after its accumulate.
    let banded = std::mem::take(&mut run.lane_accs);
    let mut lanes: Vec<Lane> = if banded.is_empty() {
        (0..channels)
            .map(|c| Lane {
                hw: hw.channel(c),
                taps: taps.lane(c),
                key: lane_key(key, c),
                steps: Vec::new(),
            })
            .collect()
    } else {
        std::iter::once(Lane {
            hw: hw.channel(0),
            taps,
            key,
            steps: Vec::new(),
        })
        .chain(banded.into_iter().enumerate().map(|(c, step)| Lane {
            hw: hw.channel(c + 1),
            taps: step.outcome.taps.clone(),
            key: step.key,
            steps: vec![step],
        }))
        .collect()
    };
    for &id in &order[split..] {
        let cx = Cx {
            scene,
            hw: &lanes[0].hw,
            layout: &plan.layout,
            opts,
            input_key: lanes[0].key,
            memo,
            pool,
        };
        if stage::get(id).reads_channels(&cx) {
            share_frames(&mut lanes);
        }
        let mut done = false;
        for lane in &mut lanes {
            let taps = std::mem::take(&mut lane.taps);
            let (t, k, d) = run.stages(&lane.hw, &[id], taps, lane.key, &mut lane.steps)?;
            (lane.taps, lane.key) = (t, k);
            done |= d;
        }
        if done {
            break;
        }
    }
    let mut lanes = lanes.into_iter().map(|l| l.steps);
    steps.extend(lanes.next().unwrap_or_default());
    Ok((steps, lanes.collect()))
}

/// The key channel `c`'s lane starts from after the stage keyed `key`.
fn lane_key(key: u64, c: usize) -> u64 {
    if c == 0 {
        key
    } else {
        Fnv::new().u64(key).str("channel").u64(c as u64).finish()
    }
}

/// One channel's lane after visibility.
struct Lane {
    /// The channel's configuration ([`HwConfig::channel`]).
    hw: HwConfig,
    /// Its taps after the last stage run.
    taps: Taps,
    /// The key of that stage.
    key: u64,
    /// Its steps.
    steps: Vec<Step>,
}

/// Gives every lane the frames of all lanes (the tap `channels`) and keys each lane's next
/// stage by every lane's input.
fn share_frames(lanes: &mut [Lane]) {
    let fixed: Option<Vec<_>> = lanes.iter().map(|l| l.taps.fixed.frame.clone()).collect();
    let Some(fixed) = fixed else {
        return;
    };
    // No float frames on the fixed-only path.
    let float: Option<Vec<_>> = lanes.iter().map(|l| l.taps.float.frame.clone()).collect();
    let formats: Vec<_> = lanes.iter().map(|l| l.hw.accumulate.frame.format).collect();
    let mut all = Fnv::new().str("channels");
    for l in lanes.iter() {
        all = all.u64(l.key);
    }
    let all = all.finish();
    for (c, l) in lanes.iter_mut().enumerate() {
        l.taps.channels = Some(Arc::new(ChannelFrames {
            lane: c,
            fixed: fixed.clone(),
            float: float.clone(),
            formats: formats.clone(),
        }));
        l.key = Fnv::new().u64(l.key).u64(all).finish();
    }
}

/// What every stage of one run shares.
struct Runner<'a> {
    scene: &'a Scene,
    plan: &'a Plan,
    opts: RunOptions,
    cache: Option<&'a Cache>,
    memo: &'a dyn Memo,
    pool: &'a Pool,
    last: Option<StageId>,
    band_rows: Option<u32>,
    /// A banded colour run's accumulate steps of channels 1.. (channel 0's is the run's).
    lane_accs: Vec<Step>,
}

impl Runner<'_> {
    /// Runs `order` from `taps` (the taps after the stage keyed `key`) into `steps`; returns
    /// the taps and key after the last stage run and whether `last` was reached.
    fn stages(
        &mut self,
        hw: &HwConfig,
        order: &[StageId],
        mut taps: Taps,
        mut key: u64,
        steps: &mut Vec<Step>,
    ) -> Result<(Taps, u64, bool)> {
        let (scene, plan, opts, last) = (self.scene, self.plan, self.opts, self.last);
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
                memo: self.memo,
                pool: self.pool,
            };
            let k = stage_key(stage, &cx, key, opts);
            if let Some(rows) = self.band_rows.filter(|_| super::bands::is_banded(id)) {
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
                // Accumulate runs once per channel lane, each with its channel's words.
                let acc = group.len() - 1;
                let channels = plan.layout.channels;
                let lanes: Vec<LaneIn> = (0..channels)
                    .map(|c| LaneIn {
                        hw: if channels > 1 {
                            hw.channel(c)
                        } else {
                            hw.clone()
                        },
                        key: lane_key(ins[acc], c),
                    })
                    .collect();
                let acc_keys: Vec<u64> = lanes
                    .iter()
                    .map(|l| {
                        let cx = Cx {
                            hw: &l.hw,
                            input_key: l.key,
                            ..cx
                        };
                        stage_key(stage::get(StageId::Accumulate), &cx, l.key, opts)
                    })
                    .collect();
                keys[acc] = acc_keys[0];
                let (outs, lane_outs) = super::bands::run(
                    &group,
                    scene,
                    hw,
                    plan,
                    opts,
                    (self.memo, self.pool, self.cache),
                    (&ins, &lanes),
                    &taps,
                    rows,
                )?;
                self.lane_accs = lane_outs
                    .into_iter()
                    .zip(&acc_keys[1..])
                    .map(|(o, &k)| Step {
                        id: StageId::Accumulate,
                        key: k,
                        outcome: Arc::new(o),
                        reused: false,
                    })
                    .collect();
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
                    return Ok((taps, key, true));
                }
                continue;
            }
            at += 1;
            let (outcome, reused) = match self.cache {
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
                return Ok((taps, key, true));
            }
        }
        Ok((taps, key, false))
    }
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
    let (outcome, fixed) = execute_keep(stage, cx, input)?;
    stage.recycle(fixed, cx.pool);
    Ok(outcome)
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
    let float_ms = if cx.opts.reference {
        let t = Instant::now();
        stage.float(cx, &fixed, &mut taps, &mut notes)?;
        ms_since(t)
    } else {
        0.0
    };
    let t = Instant::now();
    let local = if cx.opts.reference && cx.opts.stage_local {
        stage.local(cx, &fixed, input, &taps, &mut notes)
    } else {
        None
    };
    let local_ms = ms_since(t);
    // Every channel's frames are read by the stage they were given to, not passed on.
    taps.channels = None;
    let tokens = stage.tokens(cx, &fixed);
    let cost = stage.cost(cx, &fixed);
    let images = if cx.opts.pack_check {
        stage.memories(cx, &fixed, &taps)
    } else {
        Vec::new()
    };
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
