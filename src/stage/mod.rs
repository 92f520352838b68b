//! The stages of the pipeline, in flow order, and the contract every stage implements
//! ([`Stage`]): its config section, whether the plan needs it and why, its fixed-point model
//! on its input taps, its float reference, its stage-local comparison, the tokens the cycle
//! model consumes, its cost and its memories' contents. Each stage's module holds all of it
//! side by side; a large stage is a folder.
//!
//! A stage imports nothing from `pipeline`, `cycles`, `sweep`, `hdl` or the command line
//! (docs/STRUCTURE.md).

pub mod accumulate;
pub mod dither;
pub mod dof;
pub mod gamma;
pub mod input;
pub mod logdomain;
pub mod parts;
pub mod pool;
pub mod raster;
pub mod setup;
pub mod taps;
pub mod visibility;

mod contract;
mod layout;
mod report;

pub use crate::stage_id::StageId;
pub use contract::{AnyFixed, Cx, DynStage, Memo, Need, NoMemo, RunOptions, Stage, memo};
pub use layout::{Band, Grid, Layout, Region, SampleRegion, Tiles};
pub use pool::Pool;
pub use report::{
    Cost, Facts, LocalError, MemImage, MemKind, Memory, Notes, RowStream, StageReport, TokenKind,
    Tokens, Unit, WeberCompare, ms_since, weber_of,
};
pub use taps::{ChannelFrames, FixedTaps, FloatTaps, LutRead, PixelTap, PixelTapF, Taps};

/// The implementation of a stage: the one place that maps stage ids to stages.
pub fn get(id: StageId) -> &'static dyn DynStage {
    match id {
        StageId::Input => &input::Input,
        StageId::Setup => &setup::SetupStage,
        StageId::Raster => &raster::Raster,
        StageId::Visibility => &visibility::Visibility,
        StageId::Logdomain => &logdomain::Logdomain,
        StageId::Accumulate => &accumulate::Accumulate,
        StageId::Dof => &dof::Dof,
        StageId::Gamma => &gamma::Gamma,
        StageId::Dither => &dither::DitherStage,
    }
}
