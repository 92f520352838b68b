//! The vectors of each HDL model: [`vectors`] checks the hardware config and dispatches to
//! the stage's builder (one file per stage), which fills the [`Bench`] with the module's
//! parameters, ROMs and vectors from scene taps, exhaustive and edge cases and random
//! inputs, then times the Rust model over them. Shared here: the scene's taps of a channel
//! ([`SceneTaps`]), the vector counts and the error naming a hardware field.
//!
//! A colour render's bench is one channel's: its module gets that channel's word widths
//! ([`HwConfig::channel`]) and its scene taps come from that channel's lane (the stages after
//! visibility run once per channel, `pipeline::run::run_lanes`).

use super::bench::{Bench, Rng};
use super::{MODULES, module_of};
use crate::config::HwConfig;
use crate::error::{Error, Result};
use crate::pipeline::{self, Plan};
use crate::scene::Scene;
use crate::stage::gamma::GammaSpec;
use crate::stage::{RunOptions, Taps};
use crate::stage_id::StageId;

mod accumulate;
mod dither;
mod dof;
mod gamma;
mod logdomain;
mod setup;

/// Random vectors of each bench.
const RANDOM: usize = 2000;
/// Edge-stepper rows: whole edges are added until this many rows are reached.
const EDGE_ROWS: usize = 40_000;
/// Scene taps of each bench.
const TAPS: usize = 2000;

/// An error naming `field` of the hardware config.
pub(crate) fn bad(hw: &HwConfig, field: &str, msg: String) -> Error {
    Error::File(hw.error(field, msg))
}

/// Where a bench takes its scene taps: the scene rendered on the whole configuration `hw`
/// (every channel), channel `channel`'s lane.
pub(crate) struct SceneTaps<'a> {
    /// The scene.
    pub scene: &'a Scene,
    hw: &'a HwConfig,
    /// The channel (0 R, 1 G, 2 B; 0 for a grey render).
    pub channel: usize,
}

impl SceneTaps<'_> {
    /// Up to `max` frame codes of the channel from the scene's fixed render, evenly spread
    /// over the image.
    fn frame(&self, max: usize) -> Result<Vec<(u32, u32, u32)>> {
        let r = pipeline::render(self.scene, self.hw, RunOptions::FAST)?;
        let frame = r.channel_frame(self.channel);
        let w = frame.width.max(1) as usize;
        let n = frame.acc.len();
        let step = n.div_ceil(max).max(1);
        Ok((0..n)
            .step_by(step)
            .map(|p| ((p % w) as u32, (p / w) as u32, frame.acc[p]))
            .collect())
    }

    /// The plan and the channel's taps after stage `last` (a geometry stage's carry every
    /// channel).
    fn through(&self, last: StageId) -> Result<(Plan, Taps)> {
        pipeline::run_through_channel(self.scene, self.hw, RunOptions::FAST, last, self.channel)
    }
}

/// The gamma LUT's specification (the hardware's gamma, else the scene's display gamma).
fn gamma_spec(scene: &Scene, hw: &HwConfig) -> GammaSpec {
    let gamma_value = hw.gamma.gamma.unwrap_or(scene.display.gamma);
    GammaSpec::new(
        gamma_value,
        hw.gamma.correction,
        hw.gamma.dac_bits,
        hw.gamma.quant,
    )
}

/// Builds the bench of `stage` for the hardware config, with taps from the scene (channel R
/// of a colour render).
pub fn vectors(stage: StageId, scene: &Scene, hw: &HwConfig) -> Result<Bench> {
    vectors_of_channel(stage, scene, hw, 0)
}

/// [`vectors`] of channel `channel` (0 R, 1 G, 2 B) of a colour render: the module with that
/// channel's word widths, the scene taps of its lane. A grey render has channel 0 only.
pub fn vectors_of_channel(
    stage: StageId,
    scene: &Scene,
    full: &HwConfig,
    channel: usize,
) -> Result<Bench> {
    let channels = pipeline::plan::channels(scene, full);
    if channel >= channels {
        return Err(Error::File(crate::error::FileError {
            file: "--channel".into(),
            line: None,
            col: None,
            field: String::new(),
            msg: format!(
                "no channel {channel}: scene `{}` on this hardware renders {channels} channel(s)",
                scene.name
            ),
        }));
    }
    let hw = &full.channel(channel);
    let src = SceneTaps {
        scene,
        hw: full,
        channel,
    };
    let module = module_of(stage).ok_or_else(|| {
        bad(
            hw,
            "--stage",
            format!(
                "no HDL model of stage `{stage}`; allowed: {}",
                MODULES
                    .iter()
                    .map(|m| m.0.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )
    })?;
    let frame = hw.accumulate.frame;
    if frame.format.signed {
        return Err(bad(
            hw,
            "accumulate.frame",
            format!(
                "the HDL models take an unsigned frame word, not {}",
                frame.format
            ),
        ));
    }
    let mut rng = Rng::new(0x1D1_5EED ^ frame.format.total_bits() as u64);
    let mut b = Bench {
        stage,
        module,
        params: vec![],
        roms: vec![],
        fields: vec![],
        vectors: vec![],
        sources: vec![],
        model_ns: 0,
    };
    match stage {
        StageId::Gamma => gamma::bench(&mut b, hw, &src, &mut rng)?,
        StageId::Accumulate => accumulate::bench(&mut b, hw, &src, &mut rng)?,
        StageId::Dither => dither::bench(&mut b, hw, &src, &mut rng)?,
        StageId::Logdomain => logdomain::bench(&mut b, hw, &src, &mut rng)?,
        StageId::Setup => setup::bench(&mut b, &src)?,
        StageId::Dof => dof::bench(&mut b, hw, &src, &mut rng)?,
        StageId::Input | StageId::Raster | StageId::Visibility => {
            unreachable!("module_of checked the stage")
        }
    }
    Ok(b)
}
