//! The vectors of each HDL model: [`vectors`] checks the hardware config and dispatches to
//! the stage's builder (one file per stage), which fills the [`Bench`] with the module's
//! parameters, ROMs and vectors from scene taps, exhaustive and edge cases and random
//! inputs, then times the Rust model over them. Shared here: the scene's frame taps, the
//! vector counts and the error naming a hardware field.

use super::bench::{Bench, Rng};
use super::{MODULES, module_of};
use crate::config::HwConfig;
use crate::error::{Error, Result};
use crate::pipeline;
use crate::scene::Scene;
use crate::stage::RunOptions;
use crate::stage::gamma::GammaSpec;
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

/// Up to `max` frame codes from the scene's fixed render, evenly spread over the image.
fn frame_taps(scene: &Scene, hw: &HwConfig, max: usize) -> Result<Vec<(u32, u32, u32)>> {
    let r = pipeline::render(scene, hw, RunOptions::FAST)?;
    let w = r.frame().width.max(1) as usize;
    let n = r.frame().acc.len();
    let step = n.div_ceil(max).max(1);
    Ok((0..n)
        .step_by(step)
        .map(|p| ((p % w) as u32, (p / w) as u32, r.frame().acc[p]))
        .collect())
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

/// Builds the bench of `stage` for the hardware config, with taps from the scene.
pub fn vectors(stage: StageId, scene: &Scene, hw: &HwConfig) -> Result<Bench> {
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
        StageId::Gamma => gamma::bench(&mut b, scene, hw, &mut rng)?,
        StageId::Accumulate => accumulate::bench(&mut b, scene, hw, &mut rng)?,
        StageId::Dither => dither::bench(&mut b, scene, hw, &mut rng)?,
        StageId::Logdomain => logdomain::bench(&mut b, scene, hw, &mut rng)?,
        StageId::Setup => setup::bench(&mut b, scene, hw)?,
        StageId::Dof => dof::bench(&mut b, scene, hw, &mut rng)?,
        StageId::Input | StageId::Raster | StageId::Visibility => {
            unreachable!("module_of checked the stage")
        }
    }
    Ok(b)
}
