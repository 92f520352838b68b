//! The pipeline: the plan ([`plan`]), the runner that executes it through the stage
//! contract ([`run`]), the cache that reuses unchanged stages ([`cache`]) and the report
//! ([`report`]).
//!
//! A render is: build the plan (which stages, why, region, tiles), run the planned stages in
//! order (each fixed model, its float reference and its stage-local comparison), compare
//! the DAC codes end to end, and simulate the cycle model on the stages' tokens; on request
//! compare both with the depth-of-field truth ([`truth`]). The fixed-only fast path
//! ([`fast`]) runs the fixed model and the cycle model alone.

mod band_tail;
pub mod bands;
pub mod cache;
pub mod colour;
pub mod estimate;
pub mod fast;
pub mod plan;
pub mod report;
pub mod run;
pub mod tile_rows;
pub mod truth;

pub use cache::Cache;
pub use plan::{Plan, guard_band};
pub use report::Report;
pub use run::{Outcome, Step};

use crate::config::HwConfig;
use crate::cycles::Workload;
use crate::error::Result;
use crate::scene::Scene;
use crate::stage::accumulate::Frame;
use crate::stage::{RunOptions, StageId, Taps};

/// Everything a render produces.
pub struct Render {
    /// The report.
    pub report: Report,
    /// The plan it ran.
    pub plan: Plan,
    /// Every stage run, in order, with the taps after it.
    pub steps: Vec<Step>,
    /// Fixed DAC codes, row-major.
    pub dac: Vec<u16>,
    /// Float reference DAC codes.
    pub dac_ref: Vec<u16>,
    /// The depth-of-field truth's DAC codes (`RunOptions::dof_truth_samples`, thin lens).
    pub truth_dac: Option<Vec<u16>>,
    /// DAC width.
    pub dac_bits: u32,
    /// The cycle model's workload (to re-simulate with other timings or a VCD trace).
    pub workload: Workload,
    /// Per pixel: 0 not smooth, 1 smooth, 2 next to a visible contour step.
    pub contour_map: Vec<u8>,
    /// The channels of a colour render (`None`: grey, `dac` is the image).
    pub colour: Option<ColourRender>,
}

/// The channels of a colour render.
pub struct ColourRender {
    /// Each channel's DAC codes, R, G, B (R's equal [`Render::dac`]).
    pub channels: Vec<colour::ChannelCodes>,
    /// The steps after visibility of channels 1.. (channel 0's are in [`Render::steps`]).
    pub lanes: Vec<Vec<Step>>,
    /// Per pixel, row-major: CIEDE2000 of the fixed against the float reference image.
    pub delta_e: Vec<f32>,
}

impl Render {
    /// The taps after stage `id` (`None` when the plan did not run it).
    pub fn taps(&self, id: StageId) -> Option<&Taps> {
        self.steps
            .iter()
            .find(|s| s.id == id)
            .map(|s| &s.outcome.taps)
    }
    /// The taps after the last stage.
    pub fn last(&self) -> &Taps {
        &self.steps.last().expect("a plan runs stages").outcome.taps
    }
    /// The frame memory the gamma stage read (after depth of field for a thin lens).
    pub fn frame(&self) -> &Frame {
        &self.last().fixed.frame().frame
    }
    /// Channel `c`'s frame memory the gamma stage read: [`Render::frame`] for channel 0 and
    /// for a grey render, else the last tap of channel `c`'s lane.
    pub fn channel_frame(&self, c: usize) -> &Frame {
        match self
            .colour
            .as_ref()
            .and_then(|k| k.lanes.get(c.wrapping_sub(1)))
        {
            Some(lane) => {
                &lane
                    .last()
                    .expect("a lane runs stages")
                    .outcome
                    .taps
                    .fixed
                    .frame()
                    .frame
            }
            None => self.frame(),
        }
    }
    /// The cycle model's workload of this run under other timings or another
    /// depth-of-field schedule (same tokens).
    pub fn workload_for(
        &self,
        c: &crate::config::CyclesCfg,
        schedule: crate::config::DofSchedule,
    ) -> Workload {
        report::workload(&self.plan, &self.steps, c, schedule)
    }
    /// The float reference's frame (frame LSBs) the gamma stage read.
    pub fn frame_ref(&self) -> &[f64] {
        self.last().float.frame()
    }
}

/// Renders the scene through the plan, fixed and float, and compares them.
pub fn render(scene: &Scene, hw: &HwConfig, opts: RunOptions) -> Result<Render> {
    render_with(scene, hw, opts, None)
}

/// [`render`] reusing (and filling) `cache`: every stage whose key is cached is not run
/// again. The result is identical to an uncached render.
///
/// The render runs on a thread of the global rayon pool (the caller waits), so every
/// parallel part of a stage is joined from a pool thread: the thread that splits the work
/// computes a part itself and takes back what no other thread has started, instead of
/// sleeping until the pool is done (docs/speed.md).
pub fn render_with(
    scene: &Scene,
    hw: &HwConfig,
    opts: RunOptions,
    cache: Option<&Cache>,
) -> Result<Render> {
    rayon::scope(|_| render_on_pool(scene, hw, opts, cache))
}

fn render_on_pool(
    scene: &Scene,
    hw: &HwConfig,
    opts: RunOptions,
    cache: Option<&Cache>,
) -> Result<Render> {
    let plan = plan::build(scene, hw)?;
    check_memory(scene, &plan, opts)?;
    let channels = plan.layout.channels;
    if channels > 1 && opts.dof_truth_samples > 0 {
        return Err(crate::error::Error::File(scene.error(
            "image.colour",
            "the depth-of-field truth (--dof-truth) of a colour render is not modelled yet: render a grey scene (colour = false) for the truth",
        )));
    }
    let (steps, lanes) = run::run_lanes(
        scene,
        hw,
        &plan,
        opts,
        cache,
        None,
        &crate::stage::Pool::new(),
    )?;
    // Channel 0's configuration: the report's end-to-end figures are its lane's.
    let hw0 = hw.channel(0);
    let (dac, dac_ref) = colour::dac_codes(&steps);
    let ideal = report::ideal(scene, &hw0, &steps, cache);
    let (mut report, mut workloads, contour_map) = report::build(
        scene,
        hw,
        &plan,
        (&steps, &lanes),
        &dac,
        &dac_ref,
        &ideal,
        cache,
        opts,
    );
    let colour = (channels > 1).then(|| {
        let split = steps.len() - lanes[0].len();
        let mut codes = Vec::with_capacity(channels);
        let mut reports = Vec::with_capacity(channels);
        for c in 0..channels {
            let lane = if c == 0 {
                &steps[split..]
            } else {
                &lanes[c - 1][..]
            };
            let (k, r) = colour::channel(scene, &hw.channel(c), c, lane, &workloads[c], cache);
            codes.push(k);
            reports.push(r);
        }
        let (r, delta_e) = colour::report(scene, &codes, reports);
        report.colour = Some(r);
        ColourRender {
            channels: codes,
            lanes,
            delta_e,
        }
    });
    let (dof_truth, truth_dac) =
        match truth::report(scene, hw, &plan, &steps, &dac, &dac_ref, cache, opts)? {
            Some((r, d)) => (Some(r), Some(d)),
            None => (None, None),
        };
    report.dof_truth = dof_truth;
    Ok(Render {
        report,
        plan,
        steps,
        dac,
        dac_ref,
        truth_dac,
        dac_bits: hw.gamma.dac_bits,
        workload: workloads.swap_remove(0),
        contour_map,
        colour,
    })
}

/// Refuses a plan whose memory estimate is over the limit (`opts.max_memory`, by default
/// half the machine's memory), naming the fields that drive it.
fn check_memory(scene: &Scene, plan: &Plan, opts: RunOptions) -> Result<()> {
    let e = &plan.memory(opts);
    let limit = opts.max_memory.unwrap_or_else(estimate::default_limit);
    if e.bytes <= limit {
        return Ok(());
    }
    let parts: Vec<String> = e
        .parts
        .iter()
        .map(|p| format!("{} {} from {}", p.what, estimate::human(p.bytes), p.drivers))
        .collect();
    Err(scene
        .error(
            "image.width, image.height, raster.samples",
            format!(
                "the plan needs about {} ({}) but the limit is {} (--max-memory; by default half the machine's memory); reduce the resolution or raster.samples, or raise --max-memory",
                estimate::human(e.bytes),
                parts.join("; "),
                estimate::human(limit)
            ),
        )
        .into())
}

/// Runs the plan through stage `last` and returns the taps after it (for test vectors and
/// stage-level tests). Errors when the plan does not run `last`.
pub fn run_through(
    scene: &Scene,
    hw: &HwConfig,
    opts: RunOptions,
    last: StageId,
) -> Result<(Plan, Taps)> {
    run_through_channel(scene, hw, opts, last, 0)
}

/// [`run_through`] taking the taps of channel `c`'s lane when `last` runs after visibility
/// in a colour render (a geometry stage's taps carry every channel; a grey render has
/// channel 0 only).
pub fn run_through_channel(
    scene: &Scene,
    hw: &HwConfig,
    opts: RunOptions,
    last: StageId,
    c: usize,
) -> Result<(Plan, Taps)> {
    let plan = plan::build(scene, hw)?;
    if !plan.layout.has(last) {
        return Err(crate::error::Error::File(crate::error::FileError {
            file: hw.name.clone(),
            line: None,
            col: None,
            field: String::new(),
            msg: format!(
                "the plan for scene `{}` does not run stage `{last}` ({})",
                scene.name,
                plan.decisions
                    .iter()
                    .find(|d| d.stage == last)
                    .map_or(String::new(), |d| d.need.reason.clone())
            ),
        }));
    }
    check_memory(scene, &plan, opts)?;
    let (steps, lanes) = if c == 0 {
        // Channel 0's steps only: the other lanes are not run.
        (
            run::run(scene, hw, &plan, opts, None, Some(last))?,
            Vec::new(),
        )
    } else {
        run::run_lanes(
            scene,
            hw,
            &plan,
            opts,
            None,
            Some(last),
            &crate::stage::Pool::new(),
        )?
    };
    let lane = lanes.get(c.wrapping_sub(1)).unwrap_or(&steps);
    let taps = lane.last().expect("the plan runs it").outcome.taps.clone();
    Ok((plan, taps))
}
