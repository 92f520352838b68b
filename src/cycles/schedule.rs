//! Both depth-of-field schedules' frame times (`dof.schedule`, docs/cycles.md "Streamed
//! depth of field"): the report's comparison of the chosen schedule with the other one.

use super::sim::SimResult;
use super::workload::Workload;
use crate::config::DofSchedule;
use serde::Serialize;

/// One schedule's frame time.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScheduleTime {
    /// Cycles of a frame.
    pub cycles: u64,
    /// Frames per second at the clock.
    pub fps: f64,
    /// Stage with the most busy cycles.
    pub bottleneck: String,
    /// Line-buffer bits the schedule adds (0 on the finished frame).
    pub line_buffer_bits: u64,
    /// Rows the line buffers hold (0 on the finished frame).
    pub line_buffer_rows: u32,
}

impl ScheduleTime {
    /// The frame time of a simulation `r` of `w` at `clock_mhz`.
    pub fn new(w: &Workload, r: &SimResult, clock_mhz: f64) -> Self {
        let rows = w.stages.iter().filter_map(|s| s.lines.as_ref());
        Self {
            cycles: r.total_cycles,
            fps: super::Throughput::new(r.total_cycles, clock_mhz, 0, 0.0).fps,
            bottleneck: r.bottleneck().to_string(),
            line_buffer_bits: w.line_buffer_bits(),
            line_buffer_rows: rows.map(|l| l.capacity).sum(),
        }
    }
}

/// The frame time of both schedules of a plan with a streamed stage.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Schedules {
    /// The schedule of the headline frame time (`dof.schedule`).
    pub chosen: DofSchedule,
    /// Depth of field on the finished frame.
    pub frame: ScheduleTime,
    /// Depth of field streamed behind accumulate through line buffers.
    pub stream: ScheduleTime,
}

impl Schedules {
    /// Both schedules from the chosen one (`w`, `r`) and the other (`ow`, `or`); `None` when
    /// the plan has no stage that streams (both workloads are the frame schedule).
    pub fn new(
        (w, r): (&Workload, &SimResult),
        (ow, or): (&Workload, &SimResult),
        clock_mhz: f64,
    ) -> Option<Self> {
        let (f, s) = match (w.schedule, ow.schedule) {
            (DofSchedule::Frame, DofSchedule::Stream) => ((w, r), (ow, or)),
            (DofSchedule::Stream, DofSchedule::Frame) => ((ow, or), (w, r)),
            _ => return None,
        };
        Some(Self {
            chosen: w.schedule,
            frame: ScheduleTime::new(f.0, f.1, clock_mhz),
            stream: ScheduleTime::new(s.0, s.1, clock_mhz),
        })
    }

    /// The text report's line comparing them.
    pub fn line(&self) -> String {
        let (f, s) = (&self.frame, &self.stream);
        let (chosen, other) = match self.chosen {
            DofSchedule::Stream => ("stream", "frame"),
            DofSchedule::Frame => ("frame", "stream"),
        };
        format!(
            "dof schedule {chosen} (other: {other}): stream {} cycles, {:.1} fps, bottleneck {}, line buffers {} rows = {} bits | frame {} cycles, {:.1} fps, bottleneck {} | stream/frame {:.3}",
            s.cycles,
            s.fps,
            s.bottleneck,
            s.line_buffer_rows,
            s.line_buffer_bits,
            f.cycles,
            f.fps,
            f.bottleneck,
            s.cycles as f64 / f.cycles.max(1) as f64
        )
    }
}
