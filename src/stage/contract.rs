//! The stage contract. Every stage implements [`Stage`]; the pipeline's runner knows the
//! stages only through it (as [`DynStage`], the same contract with the stage's private
//! result type erased) and runs, for each planned stage in order:
//!
//! 1. [`Stage::fixed`]: the fixed-point model on its input taps; it writes its output taps
//!    and returns its private result (e.g. the depth-of-field layer plan) and its
//!    [`Facts`] (work items, instrumented signals, notes);
//! 2. [`Stage::float`]: the float reference, the same algorithm in f64 on the float taps;
//! 3. [`Stage::local`] (when asked): the stage-local comparison, the float stage fed the
//!    fixed stage's own input;
//! 4. [`Stage::tokens`], [`Stage::cost`], [`Stage::memories`]: what the cycle model
//!    consumes, the cost from the formats, and the contents of its memories for the pack
//!    check.
//!
//! [`Stage::plan`] answers, before anything runs, whether the scene and hardware need the
//! stage and why; [`Stage::key`] names what the stage reads besides its input taps (its
//! config section, the options, the parts of the plan), so that its result can be reused
//! whenever that and everything upstream are unchanged.

use super::StageId;
use super::layout::Layout;
use super::report::{Cost, Facts, LocalError, MemImage, Notes, Tokens};
use super::taps::Taps;
use crate::config::HwConfig;
use crate::error::Result;
use crate::scene::Scene;
use serde::Serialize;
use std::any::Any;
use std::sync::Arc;

/// Options of a run that change what the stages compute (and so key their results).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct RunOptions {
    /// Run the float reference beside the fixed model (`false`: the fixed-only fast path,
    /// `render --no-reference`; no float taps, no comparisons, see `pipeline::fast`).
    pub reference: bool,
    /// Build every memory's image and pack it into the bits its cost charges
    /// ([`crate::cost::pack`]; also what `--rom-out` writes). Off on the fixed-only path.
    pub pack_check: bool,
    /// Run the stage-local comparisons (float stage on the fixed stage's input).
    pub stage_local: bool,
    /// Also run the (slow) per-pixel depth-of-field reference and the layer theorem check.
    pub dof_reference: bool,
    /// Refuse a plan whose memory estimate exceeds this many bytes (`None`: half the
    /// machine's memory). Not part of any stage's key.
    #[serde(skip)]
    pub max_memory: Option<u64>,
    /// Also compute the depth-of-field truth by averaging this many lens points (0: off;
    /// see `crate::truth`). Not a stage and not part of any stage's key: the truth frame
    /// is memoised under its own key.
    #[serde(skip)]
    pub dof_truth_samples: u32,
    /// Run raster, visibility and accumulate in bands of this many pixel rows (rounded up
    /// to the tile size; `None`: the plan decides from the sample-side memory, one band for
    /// a small screen). The result is the same for any band height (tested); not part of
    /// any stage's key.
    #[serde(skip)]
    pub band_rows: Option<u32>,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            reference: true,
            pack_check: true,
            stage_local: true,
            dof_reference: false,
            max_memory: None,
            dof_truth_samples: 0,
            band_rows: None,
        }
    }
}

impl RunOptions {
    /// The fixed model only: no float reference, no comparisons, no per-pixel or truth
    /// references, no memory images (the fast path of `pipeline::fast`).
    pub const FIXED_ONLY: RunOptions = RunOptions {
        reference: false,
        pack_check: false,
        stage_local: false,
        dof_reference: false,
        max_memory: None,
        dof_truth_samples: 0,
        band_rows: None,
    };

    /// No stage-local comparisons, no per-pixel reference: what sweeps and checks run.
    pub const FAST: RunOptions = RunOptions {
        reference: true,
        pack_check: true,
        stage_local: false,
        dof_reference: false,
        max_memory: None,
        dof_truth_samples: 0,
        band_rows: None,
    };
}

/// A stage's answer to the plan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Need {
    /// Whether the stage runs.
    pub planned: bool,
    /// Why (or why not), in the words of the config field or scene fact that decides.
    pub reason: String,
    /// Runs right before this stage instead of at its place in flow order (the dither placed
    /// before the gamma LUT).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub before: Option<StageId>,
}

impl Need {
    /// The stage runs, because `reason`.
    pub fn yes(reason: impl Into<String>) -> Self {
        Self {
            planned: true,
            reason: reason.into(),
            before: None,
        }
    }
    /// The stage does not run, because `reason`.
    pub fn no(reason: impl Into<String>) -> Self {
        Self {
            planned: false,
            reason: reason.into(),
            before: None,
        }
    }
}

/// A store for values a stage computes from data that many runs share (e.g. the float
/// gamma curve of one frame for every DAC width of a sweep). The pipeline's cache backs it;
/// [`NoMemo`] computes every time.
pub trait Memo: Sync {
    /// The value stored under `key`, or `make()` (then stored).
    fn get_or_make(
        &self,
        key: u64,
        make: &mut dyn FnMut() -> Arc<dyn Any + Send + Sync>,
    ) -> Arc<dyn Any + Send + Sync>;
}

/// A [`Memo`] that stores nothing.
pub struct NoMemo;

impl Memo for NoMemo {
    fn get_or_make(
        &self,
        _key: u64,
        make: &mut dyn FnMut() -> Arc<dyn Any + Send + Sync>,
    ) -> Arc<dyn Any + Send + Sync> {
        make()
    }
}

/// `memo.get_or_make` with a typed value. Keys must be unique per type: include a tag.
pub fn memo<T: Any + Send + Sync>(m: &dyn Memo, key: u64, make: impl FnOnce() -> T) -> Arc<T> {
    let mut make = Some(make);
    let v = m.get_or_make(key, &mut || {
        let f = make.take().expect("called once");
        Arc::new(f())
    });
    match v.downcast::<T>() {
        Ok(t) => t,
        // A key collision between types: compute rather than fail.
        Err(_) => Arc::new((make.take().expect("not called"))()),
    }
}

/// What a stage reads while it runs, besides its taps.
pub struct Cx<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The hardware configuration.
    pub hw: &'a HwConfig,
    /// The plan's layout (grid, region, tiles, the stages in run order).
    pub layout: &'a Layout,
    /// Run options.
    pub opts: RunOptions,
    /// Key of the stage's input (everything upstream), for [`memo`] keys.
    pub input_key: u64,
    /// Shared values.
    pub memo: &'a dyn Memo,
    /// Buffers kept across the frames of a run (see [`super::pool`]).
    pub pool: &'a super::Pool,
}

/// The contract of a stage (see the module docs).
pub trait Stage: Sync + 'static {
    /// What the fixed model leaves for the float reference, the comparison, the tokens and
    /// the cost (e.g. work counters, the layer plan).
    type Fixed: Send + Sync + 'static;

    /// Which stage this is.
    fn id(&self) -> StageId;
    /// Whether the plan needs the stage for this scene and hardware, and why; an error when
    /// the configuration cannot run on this scene.
    fn plan(&self, scene: &Scene, hw: &HwConfig) -> Result<Need>;
    /// What the stage reads besides its input taps: its config section(s), the scene facts
    /// and plan parts it uses. Its result is reused when this and the input are unchanged.
    fn key(&self, cx: &Cx) -> serde_json::Value;
    /// The fixed-point model: reads its input taps, writes its output taps.
    fn fixed(&self, cx: &Cx, taps: &mut Taps) -> Result<(Self::Fixed, Facts)>;
    /// The float reference: reads the float taps (and the fixed model's private result),
    /// writes its float output taps.
    fn float(&self, cx: &Cx, fixed: &Self::Fixed, taps: &mut Taps, notes: &mut Notes)
    -> Result<()>;
    /// The stage-local comparison of the fixed output with the float stage run on the fixed
    /// stage's input (`None`: the stage has none).
    fn local(
        &self,
        cx: &Cx,
        fixed: &Self::Fixed,
        input: &Taps,
        output: &Taps,
        notes: &mut Notes,
    ) -> Option<LocalError>;
    /// The tokens the cycle model consumes (`None`: no cycle model).
    fn tokens(&self, cx: &Cx, fixed: &Self::Fixed) -> Option<Tokens>;
    /// Cost from the formats.
    fn cost(&self, cx: &Cx, fixed: &Self::Fixed) -> Cost;
    /// The contents of its memories (names as in [`Stage::cost`]) for the pack check.
    fn memories(&self, cx: &Cx, fixed: &Self::Fixed, output: &Taps) -> Vec<MemImage>;
    /// Whether the stage reads every channel's frame of a colour render (the tap
    /// `channels`), not only its own lane's: the runner then runs the lanes up to it in
    /// step and keys each lane's result by every lane's input.
    fn reads_channels(&self, _cx: &Cx) -> bool {
        false
    }
    /// Gives the planes of the private result back to `pool` once the runner is done with
    /// it (buffers that live across frames, see [`super::pool`]); by default it is dropped.
    fn recycle(&self, _fixed: Self::Fixed, _pool: &super::Pool) {}
}

/// A stage's private result, type-erased.
pub type AnyFixed = Box<dyn Any + Send + Sync>;

/// [`Stage`] with the private result type erased: what the runner calls.
pub trait DynStage: Sync {
    /// [`Stage::id`].
    fn id(&self) -> StageId;
    /// [`Stage::plan`].
    fn plan(&self, scene: &Scene, hw: &HwConfig) -> Result<Need>;
    /// [`Stage::key`].
    fn key(&self, cx: &Cx) -> serde_json::Value;
    /// [`Stage::fixed`].
    fn fixed(&self, cx: &Cx, taps: &mut Taps) -> Result<(AnyFixed, Facts)>;
    /// [`Stage::float`].
    fn float(&self, cx: &Cx, fixed: &AnyFixed, taps: &mut Taps, notes: &mut Notes) -> Result<()>;
    /// [`Stage::local`].
    fn local(
        &self,
        cx: &Cx,
        fixed: &AnyFixed,
        input: &Taps,
        output: &Taps,
        notes: &mut Notes,
    ) -> Option<LocalError>;
    /// [`Stage::tokens`].
    fn tokens(&self, cx: &Cx, fixed: &AnyFixed) -> Option<Tokens>;
    /// [`Stage::cost`].
    fn cost(&self, cx: &Cx, fixed: &AnyFixed) -> Cost;
    /// [`Stage::memories`].
    fn memories(&self, cx: &Cx, fixed: &AnyFixed, output: &Taps) -> Vec<MemImage>;
    /// [`Stage::reads_channels`].
    fn reads_channels(&self, cx: &Cx) -> bool;
    /// [`Stage::recycle`].
    fn recycle(&self, fixed: AnyFixed, pool: &super::Pool);
}

fn typed<S: Stage>(f: &AnyFixed) -> &S::Fixed {
    f.downcast_ref::<S::Fixed>()
        .expect("the runner passes a stage its own fixed result")
}

impl<S: Stage> DynStage for S {
    fn id(&self) -> StageId {
        Stage::id(self)
    }
    fn plan(&self, scene: &Scene, hw: &HwConfig) -> Result<Need> {
        Stage::plan(self, scene, hw)
    }
    fn key(&self, cx: &Cx) -> serde_json::Value {
        Stage::key(self, cx)
    }
    fn fixed(&self, cx: &Cx, taps: &mut Taps) -> Result<(AnyFixed, Facts)> {
        let (f, facts) = Stage::fixed(self, cx, taps)?;
        Ok((Box::new(f), facts))
    }
    fn float(&self, cx: &Cx, fixed: &AnyFixed, taps: &mut Taps, notes: &mut Notes) -> Result<()> {
        Stage::float(self, cx, typed::<S>(fixed), taps, notes)
    }
    fn local(
        &self,
        cx: &Cx,
        fixed: &AnyFixed,
        input: &Taps,
        output: &Taps,
        notes: &mut Notes,
    ) -> Option<LocalError> {
        Stage::local(self, cx, typed::<S>(fixed), input, output, notes)
    }
    fn tokens(&self, cx: &Cx, fixed: &AnyFixed) -> Option<Tokens> {
        Stage::tokens(self, cx, typed::<S>(fixed))
    }
    fn cost(&self, cx: &Cx, fixed: &AnyFixed) -> Cost {
        Stage::cost(self, cx, typed::<S>(fixed))
    }
    fn memories(&self, cx: &Cx, fixed: &AnyFixed, output: &Taps) -> Vec<MemImage> {
        Stage::memories(self, cx, typed::<S>(fixed), output)
    }
    fn reads_channels(&self, cx: &Cx) -> bool {
        Stage::reads_channels(self, cx)
    }
    fn recycle(&self, fixed: AnyFixed, pool: &super::Pool) {
        if let Ok(f) = fixed.downcast::<S::Fixed>() {
            Stage::recycle(self, *f, pool);
        }
    }
}
