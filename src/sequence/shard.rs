//! A sequence run in shards (`igemu sequence --shard K/N --part FILE`, docs/sequence.md): the
//! run's frames (`--frames A..B`, default the whole sequence) split into N contiguous ranges
//! by [`Shard::range`], as a sweep splits its jobs; shard K runs its range and writes a
//! [`Part`]: its report and what `igemu sequence merge` ([`super::merge`]) needs to join the
//! parts into the report of the whole run.
//!
//! Across a shard border the temporal figures need the frame before: with a reference, a
//! shard that does not start the run emulates that frame first (the lead-in frame, not
//! reported), so its first frame pair is compared exactly as in the unsharded run. The other
//! figures are computed from per-frame series the part carries ([`TemporalState`]).

use super::temporal::TemporalState;
use super::{
    FrameImages, SequenceOptions, SequenceReport, check_frames, run_with_state, temporal_model,
};
use crate::compare::DisplayModel;
use crate::config::HwConfig;
use crate::error::{FileError, Result};
use crate::fnv::fnv1a;
use crate::pipeline::{self, Cache};
use crate::scene::Scene;
use crate::shard::Shard;
use crate::stage::RunOptions;
use crate::sweep::rows::{hardware_key, scene_key};
use serde::{Deserialize, Serialize};
use std::ops::Range;

/// What a part file says it is (its `kind`).
pub const PART_KIND: &str = "igemu sequence part";

/// The part file of one shard.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Part {
    /// Always [`PART_KIND`].
    pub kind: String,
    /// The shard, 1-based.
    pub shard: usize,
    /// Number of shards.
    pub shards: usize,
    /// The frames of the whole (unsharded) run, `[first, end)`.
    pub run: [u32; 2],
    /// The frames of this shard, `[first, end)`.
    pub frames: [u32; 2],
    /// Whether the frame before `frames` was emulated (unreported) for the first pair.
    pub lead_in: bool,
    /// Content key of the scene as parsed (FNV-1a of its JSON, as a sweep's row ids).
    pub scene_key: String,
    /// Content key of the validated hardware, without its name.
    pub hardware_key: String,
    /// Key of the camera in the shard's first frame (whether the camera moves over the run).
    pub first_camera: String,
    /// The display model the temporal figures' DAC codes are on (the grey channel, or R).
    pub display: DisplayModel,
    /// What the temporal figures are computed from.
    pub temporal: TemporalState,
    /// The shard's own report (its frames only).
    pub report: SequenceReport,
}

/// The frames of `shard` of a run of `run`'s frames, refused (naming `--shard`) when the
/// shard would have none (more shards than frames).
pub fn shard_frames(run: &Range<u32>, shard: Shard) -> std::result::Result<Range<u32>, String> {
    let total = run.len();
    let r = shard.range(total);
    if r.is_empty() {
        return Err(format!(
            "{}/{}: the run's {total} frames ({}..{}) leave shard {} without a frame; use at most {total} shards",
            shard.k, shard.n, run.start, run.end, shard.k
        ));
    }
    // Within `run`, so the offsets fit in u32.
    Ok(run.start + r.start as u32..run.start + r.end as u32)
}

/// The key of `scene`'s camera in frame `f`.
fn camera_key(scene: &Scene, f: u32) -> Result<String> {
    let c = scene.frame(f)?.camera;
    let text = serde_json::to_string(&c).unwrap_or_else(|_| format!("{c:?}"));
    Ok(format!("{:016x}", fnv1a(text.as_bytes())))
}

/// A frame's DAC codes, row-major: one plane for a grey scene, R, G, B for colour.
pub(crate) type Planes = Vec<Vec<u16>>;

/// Renders frame `f` of `scene` on `hw` (a shard's lead-in frame): its fixed and reference
/// [`Planes`].
pub(crate) fn lead_in(
    scene: &Scene,
    hw: &HwConfig,
    f: u32,
    cache: Option<&Cache>,
) -> Result<(Planes, Planes)> {
    let r = pipeline::render_with(&scene.frame(f)?, hw, RunOptions::FAST, cache)?;
    Ok(match r.colour {
        Some(c) => c.channels.into_iter().map(|k| (k.dac, k.dac_ref)).unzip(),
        None => (vec![r.dac], vec![r.dac_ref]),
    })
}

/// Runs shard `shard` of the run `o` (`o.frames` the whole run's frames) and returns its
/// part; `on_frame` gets the shard's frames.
pub fn run_shard(
    scene: &Scene,
    hw: &HwConfig,
    o: &SequenceOptions,
    shard: Shard,
    on_frame: &mut dyn FnMut(&FrameImages) -> Result<()>,
) -> Result<Part> {
    check_frames(scene, &o.frames)?;
    let frames = shard_frames(&o.frames, shard).map_err(|msg| FileError {
        file: "--shard".into(),
        line: None,
        col: None,
        field: String::new(),
        msg,
    })?;
    let mine = SequenceOptions {
        frames: frames.clone(),
        ..o.clone()
    };
    let lead_in = frames.start > o.frames.start;
    let (report, temporal) = run_with_state(scene, hw, &mine, lead_in, on_frame)?;
    Ok(Part {
        kind: PART_KIND.into(),
        shard: shard.k,
        shards: shard.n,
        run: [o.frames.start, o.frames.end],
        frames: [frames.start, frames.end],
        lead_in: o.reference && lead_in,
        scene_key: format!("{:016x}", scene_key(scene)),
        hardware_key: format!("{:016x}", hardware_key(hw)),
        first_camera: camera_key(scene, frames.start)?,
        display: temporal_model(scene, hw),
        temporal,
        report,
    })
}
