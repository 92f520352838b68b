//! The streamed depth-of-field schedule (`dof.schedule = "stream"`, docs/cycles.md): the
//! default scene's rows through line buffers against the finished-frame schedule, a hand-
//! computed back-pressure case and the named edge cases (zero radius, a radius larger than
//! the frame, one tile row, nothing binned), each with the event-driven simulator against
//! the stepwise reference (random streamed workloads: tests/cycles.rs).

mod common;

use common::sim::{assert_same_as_stepwise as same_as_stepwise, streamed};
use igemu::config::{CyclesCfg, DofSchedule, HwConfig};
use igemu::cycles::{self, Lines, SimResult, Workload};
use igemu::pipeline::{Render, render};
use igemu::scene::Scene;
use igemu::stage::{RunOptions, StageId};

fn run(s: &Scene, h: &HwConfig) -> Render {
    render(s, h, RunOptions::FAST).unwrap_or_else(|e| panic!("{e}"))
}

fn stage(r: &SimResult, name: &str) -> cycles::StageCycles {
    r.stages.iter().find(|s| s.name == name).unwrap().clone()
}

#[test]
fn default_scene_streams_dof_rows_behind_accumulate() {
    let s = Scene::default_scene();
    let h = HwConfig::default_config();
    assert_eq!(h.dof.schedule, DofSchedule::Stream, "the default schedule");
    let r = run(&s, &h);
    let mut hf = h.clone();
    hf.dof.schedule = DofSchedule::Frame;
    let rf = run(&s, &hf);
    // Timing only: the images are the same.
    assert_eq!(r.dac, rf.dac);
    let (c, cf) = (&r.report.cycles, &rf.report.cycles);
    assert_eq!(r.workload.schedule, DofSchedule::Stream);
    let w = &r.workload.stages;
    let (acc, dof, gamma) = (
        w.iter().position(|s| s.id == StageId::Accumulate).unwrap(),
        w.iter().position(|s| s.id == StageId::Dof).unwrap(),
        w.iter().position(|s| s.id == StageId::Gamma).unwrap(),
    );
    // One DoF token per screen row, the same pass outputs as the layers' tokens.
    let sf = |n: &str| cf.stages.iter().find(|s| s.name == n).unwrap().clone();
    let st = |n: &str| c.stages.iter().find(|s| s.name == n).unwrap().clone();
    assert_eq!(st("dof").tokens, 480);
    assert_eq!(st("dof").items, sf("dof").items);
    assert!(st("dof").busy >= sf("dof").items.div_ceil(2));
    // The line buffers: the accumulate stage writes, the dof stage reads, gamma follows dof
    // through its FIFO.
    let l: &Lines = w[dof].lines.as_ref().expect("streamed dof");
    assert_eq!(l.source, acc);
    assert_eq!(w[gamma].feeder, Some(dof));
    assert_eq!(l.height, 480);
    assert_eq!(l.tile, 16);
    assert!(l.radius > 0 && l.radius <= 2 * h.dof.max_half_size, "{l:?}");
    assert_eq!(l.capacity, (2 * l.radius + 32).min(480));
    assert_eq!(l.bits, l.capacity as u64 * 640 * l.read_bits as u64);
    // Frame word, coverage of 16 samples (5 bits), a layer index.
    assert!(l.read_bits > 12 + 5, "{l:?}");
    // Back-pressure: accumulate waits for the dof stage on the default scene.
    assert!(st("accumulate").stalled > 0);
    assert_eq!(sf("accumulate").stalled, 0);
    // Overlap: the streamed frame is shorter, and still at least the geometry plus the dof
    // stage's work.
    assert!(c.total_cycles < cf.total_cycles);
    assert!(c.total_cycles >= st("accumulate").starved + st("dof").busy);
    // Both reports carry both schedules; the cost charges the line buffers.
    let (b, bf) = (
        c.schedules.as_ref().unwrap(),
        cf.schedules.as_ref().unwrap(),
    );
    assert_eq!(b.chosen, DofSchedule::Stream);
    assert_eq!(
        (b.stream.cycles, b.frame.cycles),
        (c.total_cycles, cf.total_cycles)
    );
    assert_eq!(
        (bf.stream.cycles, bf.frame.cycles),
        (c.total_cycles, cf.total_cycles)
    );
    assert_eq!(b.stream.line_buffer_bits, l.bits);
    assert_eq!(b.stream.line_buffer_rows, l.capacity);
    assert_eq!(c.cost.line_buffer_bits, l.bits);
    assert_eq!(
        c.cost.total_storage_bits,
        cf.cost.total_storage_bits + l.bits
    );
    assert_eq!(
        c.cost.storage_bits.get(igemu::cost::LINE_BUFFERS),
        Some(&l.bits)
    );
    let lines = c.summary_lines();
    assert!(
        lines
            .iter()
            .any(|x| x.contains("dof schedule stream") && x.contains("frame 1603811 cycles")),
        "{lines:?}"
    );
    let json = serde_json::to_value(c).unwrap();
    assert_eq!(json["schedules"]["frame"]["cycles"], 1_603_811);
    assert_eq!(json["schedules"]["stream"]["line_buffer_bits"], l.bits);
    // The simulators agree on the real streamed workload.
    same_as_stepwise(&r.workload, "default, stream");
}

#[test]
fn a_pinhole_scene_has_one_schedule() {
    let s = Scene::embedded("default-pinhole").unwrap();
    let h = HwConfig::default_config();
    let r = run(&s, &h);
    let c = &r.report.cycles;
    assert!(c.schedules.is_none());
    assert_eq!(c.cost.line_buffer_bits, 0);
    assert_eq!(r.workload.schedule, DofSchedule::Frame);
    let f = r.workload_for(&h.cycles, DofSchedule::Frame);
    assert_eq!(f.key(), r.workload.key());
    assert!(serde_json::to_value(c).unwrap().get("schedules").is_none());
}

fn zero_latency() -> CyclesCfg {
    let mut c = CyclesCfg::default_for(12);
    for id in igemu::config::TIMED {
        c.timing_mut(id).unwrap().latency = 0;
    }
    c
}

/// Tile 1, six rows, radius 0: the line buffers hold 2 rows. Accumulate writes a row per
/// clock, the dof stage needs 10 clocks per row, so from the third row on accumulate waits
/// for the dof stage to finish the oldest row (9 stalled clocks per row, 4 rows); the dof
/// stage waits only for the first row.
#[test]
fn back_pressure_by_hand() {
    let c = zero_latency();
    assert_eq!((c.accumulate.lanes, c.dof.lanes), (16, 2));
    let acc: Vec<(u32, u64)> = (0..6).map(|y| (y, 1)).collect();
    let w = streamed(&acc, &[20; 6], 0, 1, false, &c);
    assert_eq!(w.stages[1].lines.as_ref().unwrap().capacity, 2);
    assert_eq!(w.line_buffer_bits(), 2 * 5 * 7);
    let r = same_as_stepwise(&w, "by hand");
    let (a, d) = (stage(&r, "accumulate"), stage(&r, "dof"));
    assert_eq!((a.busy, a.stalled), (6, 4 * 9));
    assert_eq!((d.busy, d.starved), (60, 1));
    assert_eq!(r.total_cycles, 61);
}

/// Two tile rows of 4 rows; `radius` rows of blur.
fn two_tile_rows(radius: u32, gamma: bool, c: &CyclesCfg) -> Workload {
    let acc = [(0, 64), (0, 64), (4, 64), (4, 64)];
    streamed(&acc, &[9, 0, 17, 4, 4, 31, 2, 8], radius, 4, gamma, c)
}

#[test]
fn zero_radius_reads_only_its_own_tile_row() {
    let c = CyclesCfg::default_for(12);
    let w = two_tile_rows(0, true, &c);
    let l = w.stages[1].lines.clone().unwrap();
    assert_eq!(l.capacity, 8);
    let r = same_as_stepwise(&w, "zero radius");
    // The first row starts when the first tile row is out (before accumulate's last tile).
    let a = stage(&r, "accumulate");
    let d = stage(&r, "dof");
    assert!(d.starved < a.busy + a.latency as u64, "{d:?} {a:?}");
}

#[test]
fn a_radius_larger_than_the_frame_waits_for_the_whole_frame() {
    let c = CyclesCfg::default_for(12);
    let w = two_tile_rows(1000, true, &c);
    let l = w.stages[1].lines.clone().unwrap();
    assert_eq!(l.capacity, 8, "capped at the frame");
    let r = same_as_stepwise(&w, "radius > frame");
    let (a, d) = (stage(&r, "accumulate"), stage(&r, "dof"));
    assert_eq!(a.stalled, 0, "the whole frame fits");
    // Four tiles of 64 MACs at 16 lanes, then the pipeline: only then the first row.
    assert_eq!(d.starved, 4 * 4 + a.latency as u64);
}

#[test]
fn one_tile_row() {
    let c = CyclesCfg::default_for(12);
    let w = streamed(&[(0, 40), (0, 40)], &[6, 6, 6], 1, 16, true, &c);
    assert_eq!(w.stages[1].lines.as_ref().unwrap().capacity, 3);
    let r = same_as_stepwise(&w, "one tile row");
    let (a, d) = (stage(&r, "accumulate"), stage(&r, "dof"));
    assert_eq!(d.starved, 2 * 3 + a.latency as u64);
}

#[test]
fn nothing_binned_streams_the_background() {
    let c = CyclesCfg::default_for(12);
    // A frame of background rows: the dof stage has nothing to wait for.
    let w = streamed(&[], &[4; 5], 2, 2, true, &c);
    assert!(w.stages[1].lines.is_some());
    let r = same_as_stepwise(&w, "nothing binned");
    assert_eq!(stage(&r, "dof").starved, 0);
}

#[test]
fn the_schedule_is_read_from_the_hardware_file_and_bad_values_are_refused() {
    use igemu::files::TomlFile;
    let hw = |text: &str| {
        HwConfig::from_toml(&TomlFile::from_text("h.toml", text)).map_err(|e| e.to_string())
    };
    let h = hw("preset = \"linear12\"\n[dof]\nschedule = \"frame\"\n").unwrap();
    assert_eq!(h.dof.schedule, DofSchedule::Frame);
    let h = hw("preset = \"linear12\"\n[dof]\nschedule = \"stream\"\n").unwrap();
    assert_eq!(h.dof.schedule, DofSchedule::Stream);
    let e = hw("preset = \"linear12\"\n[dof]\nschedule = \"rows\"\n").unwrap_err();
    assert!(e.contains("h.toml:3") && e.contains("dof.schedule"), "{e}");
    assert!(e.contains("`frame`, `stream`"), "{e}");
    let e = hw("preset = \"linear12\"\n[dof]\nschedule = 1\n").unwrap_err();
    assert!(
        e.contains("dof.schedule") && e.contains("\"stream\", \"frame\""),
        "{e}"
    );
}
