//! Cycle model: a hand-computed single triangle, analytic bounds on random scenes, timing
//! invariance of every output code, the VCD trace read back, the plan (no dof for a pinhole
//! camera, only the touched quarter of the screen), tile skipping bit-identical to the
//! whole-region accumulate, the cost model's packing check, and the event-driven simulator
//! against the stepwise reference (identical counts and VCD text on the embedded scenes under
//! many timings, and on random workloads).

mod common;

use common::sim::{self, assert_same_as_stepwise};
use common::{Rng, hw, point, scene, tri};
use igemu::config::HwConfig;
use igemu::config::{CyclesCfg, DofSchedule, StageTiming};
use igemu::cycles::vcd::VcdWriter;
use igemu::cycles::{self, ScreenFacts, State, Workload};
use igemu::files::TomlFile;
use igemu::pipeline::{self, Render, render};
use igemu::scene::{Lens, Scene};
use igemu::stage::RunOptions;
use igemu::stage::accumulate::{self, AccParams};
use igemu::stage::{StageId, TokenKind, Tokens};
use proptest::prelude::*;

fn run(s: &Scene, h: &HwConfig) -> Render {
    render(s, h, RunOptions::FAST).unwrap_or_else(|e| panic!("{e}"))
}

/// The cycle report's line of stage `name`.
fn cycles_of(r: &Render, name: &str) -> cycles::StageCycles {
    let c = &r.report.cycles.stages;
    c.iter()
        .find(|s| s.name == name)
        .expect("a timed stage")
        .clone()
}

fn work(r: &Render, stage: &str, key: &str) -> u64 {
    let s = r.report.stages.iter().find(|s| s.name == stage).unwrap();
    s.work.get(key).copied().unwrap_or(0)
}

fn random_scene(rng: &mut Rng, w: u32, h: u32, n: usize) -> Scene {
    let mut objs = String::new();
    for _ in 0..n {
        let (cx, cy) = (
            rng.range(-10.0, w as f64 + 10.0),
            rng.range(-10.0, h as f64 + 10.0),
        );
        let r = rng.range(1.0, 30.0);
        let v = [0, 1, 2].map(|_| {
            [
                cx + rng.range(-r, r),
                cy + rng.range(-r, r),
                rng.range(0.05, 0.95),
            ]
        });
        objs += &tri(v, [0, 1, 2].map(|_| rng.range(0.0, 1.0)));
    }
    if rng.range(0.0, 1.0) < 0.5 {
        objs += &point(
            rng.range(0.0, w as f64),
            rng.range(0.0, h as f64),
            0.5,
            rng.range(0.2, 1.0),
            1.0,
        );
    }
    scene(w, h, rng.range(0.0, 0.3), &objs)
}

fn random_timing(rng: &mut Rng) -> CyclesCfg {
    let mut c = CyclesCfg::default_for(12);
    for id in igemu::config::TIMED {
        let t = c.timing_mut(id).unwrap();
        *t = StageTiming {
            lanes: 1 + (rng.next_u64() % 16) as u32,
            latency: (rng.next_u64() % 20) as u32,
            ii: 1 + (rng.next_u64() % 3) as u32,
            fifo: 1 + (rng.next_u64() % 8) as u32,
        };
    }
    c.frame_port_bits = 1 + (rng.next_u64() % 96) as u32;
    c
}

#[test]
fn single_triangle_cycle_count_matches_hand_computation() {
    // One triangle well inside tile (2, 2) of a 16-px grid: one geometry token, one tile.
    let s = scene(
        96,
        96,
        0.1,
        &tri(
            [[36.0, 36.0, 0.5], [43.0, 37.0, 0.5], [38.0, 43.0, 0.5]],
            [0.8, 0.5, 0.2],
        ),
    );
    let h = hw("linear12", |h| {
        h.cycles.input = StageTiming {
            lanes: 1,
            latency: 4,
            ii: 1,
            fifo: 2,
        };
        h.cycles.setup = StageTiming {
            lanes: 1,
            latency: 16,
            ii: 4,
            fifo: 2,
        };
        h.cycles.raster = StageTiming {
            lanes: 4,
            latency: 3,
            ii: 1,
            fifo: 2,
        };
        h.cycles.visibility = StageTiming {
            lanes: 2,
            latency: 2,
            ii: 1,
            fifo: 2,
        };
        h.cycles.accumulate = StageTiming {
            lanes: 16,
            latency: 6,
            ii: 2,
            fifo: 2,
        };
        h.cycles.gamma = StageTiming {
            lanes: 1,
            latency: 1,
            ii: 1,
            fifo: 2,
        };
        h.cycles.frame_port_bits = 24;
    });
    let r = run(&s, &h);
    let c = &r.report.cycles;
    assert_eq!(c.plan.tiles_touched, 1);
    assert_eq!(c.plan.tiles_total, 36);
    // The work the stages reported.
    let stepped = work(&r, "raster", "samples") + work(&r, "raster", "walked_samples");
    let tests = work(&r, "visibility", "tests");
    let pixels = work(&r, "accumulate", "pixels");
    let macs = work(&r, "accumulate", "macs");
    let rmw = work(&r, "accumulate", "fragments") + work(&r, "accumulate", "point_updates");
    assert!(stepped > 0 && tests > 0 && pixels > 0);
    // Tent filter on a 4x4 grid: an 8x8-sample window, 64 MACs per pixel.
    assert_eq!(macs, pixels * 64);
    // By hand: each stage serves its one token for ceil(items / lanes) * ii cycles, then
    // the token spends `latency` cycles in the stage's pipeline; nothing overlaps.
    let input = 3 + 4; // 3 vertices, 1 lane, ii 1; latency 4
    let setup = 4 + 16; // 1 primitive, ii 4; latency 16
    let raster = stepped.div_ceil(4) + 3;
    let vis = tests.div_ceil(2) + 2;
    // Accumulate: the MAC lanes (ii 2) or the frame port (2 x 12 bits per RMW, 24 bits per
    // clock: one RMW per clock), whichever is slower; latency 6.
    let acc = (macs.div_ceil(16) * 2).max(rmw * 24 / 24) + 6;
    let gamma = pixels + 1;
    let hand = input + setup + raster + vis + acc + gamma;
    assert_eq!(c.total_cycles, hand, "{c:#?}");
    assert_eq!(c.upper_bound, hand);
    // Nobody stalls with one token; the raster stage waits for input and setup.
    assert!(c.stages.iter().all(|s| s.stalled == 0));
    assert_eq!(c.stages[2].starved, input + setup);
    assert_eq!(c.stages[2].busy, stepped.div_ceil(4));
}

#[test]
fn analytic_bounds_hold_on_random_scenes() {
    let mut rng = Rng::new(0x5eed_c7c1e5);
    for case in 0..6 {
        let s = random_scene(&mut rng, 96, 64, 1 + case * 3);
        let r = run(&s, &HwConfig::default_config());
        for _ in 0..25 {
            let c = random_timing(&mut rng);
            let w = r.workload_for(&c, DofSchedule::Stream);
            let services: Vec<Vec<u64>> = (0..w.stages.len()).map(|i| w.services(i).0).collect();
            let sim = cycles::simulate(&w, None);
            let (lo, hi) = sim.bounds();
            assert!(
                lo <= sim.total_cycles && sim.total_cycles <= hi,
                "case {case}: {lo} <= {} <= {hi}\n{c:?}",
                sim.total_cycles
            );
            for (st, sv) in sim.stages.iter().zip(&services) {
                assert_eq!(st.busy, sv.iter().sum::<u64>(), "{}", st.name);
                assert_eq!(
                    st.busy + st.stalled + st.starved + st.idle,
                    sim.total_cycles,
                    "{}",
                    st.name
                );
                assert!(st.fifo == 0 || st.fifo_max <= st.fifo);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]
    /// Lanes, latencies, initiation intervals, FIFO depths, the port and the tile size
    /// change cycle counts only, never an output code.
    #[test]
    fn timing_never_changes_an_output_code(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        let s = random_scene(&mut rng, 80, 56, 6);
        let base = run(&s, &HwConfig::default_config());
        let mut h = HwConfig::default_config();
        h.cycles = random_timing(&mut rng);
        h.cycles.tile = [4, 8, 16, 32, 64][(rng.next_u64() % 5) as usize];
        h.validate().unwrap();
        let other = run(&s, &h);
        prop_assert_eq!(&base.dac, &other.dac);
        prop_assert_eq!(base.frame(), other.frame());
        prop_assert_eq!(&base.dac_ref, &other.dac_ref);
        prop_assert!(other.report.cycles.bounds_hold);
    }
}

#[test]
fn tile_skipping_is_bit_identical_to_the_whole_region() {
    let mut rng = Rng::new(77);
    let mut scenes = vec![Scene::default_scene()];
    scenes.extend((0..4).map(|i| random_scene(&mut rng, 120, 90, 2 + 4 * i)));
    for s in &scenes {
        for tile in [4, 16, 64] {
            let mut h = HwConfig::default_config();
            h.cycles.tile = tile;
            let (plan, taps) =
                pipeline::run_through(s, &h, RunOptions::FAST, StageId::Accumulate).unwrap();
            let samples = taps.fixed.samples();
            let ap = AccParams {
                kernel: accumulate::kernel(&h),
                i_frac: h.input.intensity.format.frac_bits,
                i_max: u32::MAX,
                frame: h.accumulate.frame,
            };
            let (whole, _, _) = accumulate::accumulate(
                &samples.samples,
                &plan.layout.region,
                &samples.points,
                &ap,
                samples.bg,
                (s.image.width, s.image.height),
            )
            .unwrap();
            assert_eq!(
                &whole,
                &taps.fixed.frame().frame,
                "scene {} tile {tile}",
                s.name
            );
        }
    }
}

#[test]
fn vcd_trace_reads_back_to_the_reported_counts() {
    let mut rng = Rng::new(4242);
    let s = random_scene(&mut rng, 64, 48, 8);
    let mut h = HwConfig::default_config();
    h.cycles = random_timing(&mut rng);
    h.cycles.raster.fifo = 1; // force back-pressure
    let r = run(&s, &h);
    let mut w = VcdWriter::new(Vec::new(), &r.workload, h.cycles.clock_mhz).unwrap();
    let sim = cycles::simulate(
        &r.workload,
        Some(&mut |t, st: &[State], occ: &[u32]| w.cycle(t, st, occ)),
    );
    let names: Vec<&str> = r.workload.stages.iter().map(|s| s.id.name()).collect();
    assert_eq!(sim.total_cycles, r.report.cycles.total_cycles);
    let bytes = w.finish(sim.total_cycles).unwrap();

    let mut p = vcd::Parser::new(std::io::BufReader::new(&bytes[..]));
    let header = p.parse_header().unwrap();
    let (per, unit) = igemu::cycles::vcd::cycle_time(h.cycles.clock_mhz);
    assert_eq!(header.timescale, Some((1, unit)));
    let code = |name: &str| header.find_var(&["igemu", name]).map(|v| v.code);
    let state_codes: Vec<_> = names
        .iter()
        .map(|n| code(&format!("{n}_state")).unwrap())
        .collect();
    let fifo_codes: Vec<_> = names.iter().map(|n| code(&format!("{n}_fifo"))).collect();
    let ns = names.len();
    let mut state = vec![0u64; ns];
    let mut occ = vec![0u64; ns];
    let mut counts = vec![[0u64; 4]; ns];
    let mut fifo_max = vec![0u64; ns];
    let mut now = 0u64;
    let mut last_time = 0u64;
    while let Some(cmd) = p.next().transpose().unwrap() {
        match cmd {
            vcd::Command::Timestamp(t) => {
                // Time stamps are real time: cycles times the period in the time unit.
                assert!(
                    t.is_multiple_of(per),
                    "time {t} is not a whole cycle of {per} {unit}"
                );
                let t = t / per;
                for i in 0..ns {
                    counts[i][state[i] as usize] += t - now;
                }
                now = t;
                last_time = t;
            }
            vcd::Command::ChangeVector(id, v) => {
                let val = v
                    .iter()
                    .fold(0u64, |a, b| a * 2 + u64::from(b == vcd::Value::V1));
                if let Some(i) = state_codes.iter().position(|&c| c == id) {
                    state[i] = val;
                } else if let Some(i) = fifo_codes.iter().position(|&c| c == Some(id)) {
                    occ[i] = val;
                    fifo_max[i] = fifo_max[i].max(val);
                } else {
                    panic!("unknown id {id}");
                }
            }
            _ => {}
        }
    }
    assert_eq!(last_time, r.report.cycles.total_cycles);
    // The report lists the planned cycle stages (no dof row for this pinhole scene).
    assert_eq!(
        names,
        [
            "input",
            "setup",
            "raster",
            "visibility",
            "accumulate",
            "gamma"
        ]
    );
    assert_eq!(r.report.cycles.stages.len(), names.len());
    for st in &r.report.cycles.stages {
        let i = names.iter().position(|n| *n == st.name).unwrap();
        assert_eq!(counts[i][State::Idle as usize], st.idle, "{} idle", st.name);
        assert_eq!(counts[i][State::Busy as usize], st.busy, "{} busy", st.name);
        assert_eq!(
            counts[i][State::Stalled as usize],
            st.stalled,
            "{} stalled",
            st.name
        );
        assert_eq!(
            counts[i][State::Starved as usize],
            st.starved,
            "{} starved",
            st.name
        );
        assert_eq!(fifo_max[i], st.fifo_max as u64, "{} fifo max", st.name);
    }
    assert!(
        r.report.cycles.stages.iter().any(|s| s.stalled > 0),
        "the trace should show back-pressure"
    );
}

/// The trace, read back with the `vcd` crate, names every stage's signals with their widths
/// (a `_fifo` exactly for the stages with a FIFO), changes only at cycles the simulation
/// reported, holds at each of them the states and FIFO occupancies the simulation reported,
/// and ends at the total.
#[test]
fn vcd_trace_holds_every_simulated_cycle() {
    let mut rng = Rng::new(31337);
    let s = random_scene(&mut rng, 48, 32, 6);
    let mut h = HwConfig::default_config();
    h.cycles = random_timing(&mut rng);
    let r = run(&s, &h);
    let wl = &r.workload;
    let ns = wl.stages.len();
    let mut w = VcdWriter::new(Vec::new(), wl, h.cycles.clock_mhz).unwrap();
    let mut seen: Vec<(u64, Vec<u64>, Vec<u64>)> = Vec::new();
    let sim = cycles::simulate(
        wl,
        Some(&mut |t, st: &[State], occ: &[u32]| {
            w.cycle(t, st, occ);
            let st = st.iter().map(|&s| s as u64).collect();
            seen.push((t, st, occ.iter().map(|&o| o.into()).collect()));
        }),
    );
    let bytes = w.finish(sim.total_cycles).unwrap();

    let mut p = vcd::Parser::new(&bytes[..]);
    let header = p.parse_header().unwrap();
    let (per, unit) = igemu::cycles::vcd::cycle_time(h.cycles.clock_mhz);
    assert_eq!(header.timescale, Some((1, unit)));
    let mut codes = Vec::new(); // (code, stage, is the FIFO)
    for (i, st) in wl.stages.iter().enumerate() {
        let var = |suffix: &str| header.find_var(&["igemu", &format!("{}_{suffix}", st.id.name())]);
        let v = var("state").expect("a state signal per stage");
        assert_eq!(v.size, 2);
        codes.push((v.code, i, false));
        assert_eq!(var("fifo").is_some(), wl.has_fifo(i), "{}", st.id.name());
        if let Some(f) = var("fifo") {
            assert_eq!(f.size, 32);
            codes.push((f.code, i, true));
        }
    }
    let mut changes = Vec::new(); // (time, stage, is the FIFO, value)
    let mut now: Option<u64> = None;
    for cmd in p {
        match cmd.unwrap() {
            vcd::Command::Timestamp(t) => {
                assert!(
                    t.is_multiple_of(per),
                    "time {t} is not a whole cycle of {per} {unit}"
                );
                let t = t / per;
                assert!(now.is_none_or(|n| t > n), "time stamps increase");
                now = Some(t);
            }
            vcd::Command::ChangeVector(id, v) => {
                let &(_, i, fifo) = codes.iter().find(|c| c.0 == id).expect("a declared id");
                let val = v
                    .iter()
                    .fold(0u64, |a, b| a * 2 + u64::from(b == vcd::Value::V1));
                changes.push((now.expect("a time before a change"), i, fifo, val));
            }
            _ => {}
        }
    }
    assert_eq!(now, Some(sim.total_cycles), "the dump ends at the total");
    let (mut state, mut occ) = (vec![u64::MAX; ns], vec![u64::MAX; ns]);
    let mut k = 0;
    for (t, st, oc) in &seen {
        while k < changes.len() && changes[k].0 <= *t {
            let (_, i, fifo, val) = changes[k];
            if fifo {
                occ[i] = val
            } else {
                state[i] = val
            }
            k += 1;
        }
        assert_eq!(&state, st, "states at cycle {t}");
        for i in (0..ns).filter(|&i| wl.has_fifo(i)) {
            assert_eq!(occ[i], oc[i], "stage {i} FIFO at cycle {t}");
        }
    }
    assert_eq!(k, changes.len(), "no change after the last reported cycle");
    assert!(seen.len() > 10 && changes.len() > 2 * ns);
}

#[test]
fn pinhole_camera_plans_no_dof_stage() {
    let s = scene(
        64,
        48,
        0.1,
        &tri(
            [[5.0, 5.0, 0.5], [40.0, 8.0, 0.5], [20.0, 40.0, 0.5]],
            [1.0; 3],
        ),
    );
    assert!(matches!(s.camera.lens, Lens::Pinhole));
    let r = run(&s, &HwConfig::default_config());
    assert!(!r.report.plan.stages.iter().any(|s| s == "dof"));
    assert!(!r.report.cycles.plan.stages.iter().any(|s| s == "dof"));
    assert!(r.report.cycles.plan.unmodelled.is_empty());
}

/// `dof.schedule = "frame"`: the model before the streamed schedule, its numbers unchanged.
#[test]
fn thin_lens_scene_runs_dof_on_the_finished_frame_then_gamma() {
    let s = Scene::default_scene();
    let mut h = HwConfig::default_config();
    h.dof.schedule = DofSchedule::Frame;
    let r = run(&s, &h);
    let c = &r.report.cycles;
    assert!(c.plan.unmodelled.is_empty(), "{:?}", c.plan.unmodelled);
    let st = |n: &str| cycles_of(&r, n);
    let (acc, dof, gamma) = (st("accumulate"), st("dof"), st("gamma"));
    // One token per layer with a box; both passes emit one sample per box pixel; two
    // samples per clock (the h and v port groups of dof_row_mac).
    let dof_stage = r
        .workload
        .stages
        .iter()
        .find(|s| s.id == StageId::Dof)
        .unwrap();
    // Items per layer token: 2 x the pixels of its box.
    let layers: Vec<u64> = dof_stage.items.iter().map(|&i| i / 2).collect();
    assert!(layers.len() >= 2 && layers.len() as u64 <= work(&r, "dof", "layers"));
    assert_eq!(dof.tokens, layers.len() as u64);
    let px: u64 = layers.iter().sum();
    assert_eq!(dof.items, 2 * px);
    assert_eq!(dof.busy, px);
    // Depth of field blurs the whole screen, so gamma converts every pixel, row by row.
    assert_eq!(gamma.items, 640 * 480);
    assert_eq!(gamma.tokens, 480);
    assert_eq!(gamma.busy, 640 * 480);
    // Each starts on the finished frame: no overlap with the stages before it.
    assert!(dof.starved >= acc.busy, "{dof:?} {acc:?}");
    assert!(gamma.starved >= dof.busy + acc.busy, "{gamma:?}");
    assert_eq!(c.total_cycles, dof.busy + dof.starved + dof.idle);
    assert_eq!(c.bottleneck, "dof");
    // The frame time of the default scene before the streamed schedule existed
    // (`igemu cycles default` on main at 70cd7e3), and the comparison names it.
    assert_eq!(c.total_cycles, 1_603_811);
    let both = c.schedules.as_ref().expect("both schedules");
    assert_eq!(both.chosen, DofSchedule::Frame);
    assert_eq!(both.frame.cycles, c.total_cycles);
    assert_eq!(both.frame.line_buffer_bits, 0);
    assert_eq!(c.cost.line_buffer_bits, 0);
    // Twice the lanes, half the busy cycles (each layer rounds up on its own).
    h.cycles.dof.lanes = 4;
    let r4 = run(&s, &h);
    let d4 = cycles_of(&r4, "dof");
    assert_eq!(d4.busy, layers.iter().map(|l| l.div_ceil(2)).sum::<u64>());
    assert!(r4.report.cycles.total_cycles < c.total_cycles);
    assert_eq!(r4.dac, r.dac);
}

#[test]
fn quarter_screen_scene_simulates_only_that_quarter() {
    // Two triangles covering [0, 60]^2 of a 128x128 screen: the top-left quarter's tiles.
    let objs = tri(
        [[0.0, 0.0, 0.5], [60.0, 0.0, 0.5], [0.0, 60.0, 0.5]],
        [0.7; 3],
    ) + &tri(
        [[60.0, 0.0, 0.5], [60.0, 60.0, 0.5], [0.0, 60.0, 0.5]],
        [0.7; 3],
    );
    let s = scene(128, 128, 0.1, &objs);
    let r = run(&s, &HwConfig::default_config());
    let c = &r.report.cycles;
    assert_eq!(c.plan.tiles_total, 64);
    assert_eq!(c.plan.tiles_touched, 16);
    let tiles = &r.plan.layout.tiles;
    assert!(
        (0..tiles.touched.len())
            .filter(|&t| tiles.touched[t])
            .all(|t| t % 8 < 4 && t / 8 < 4)
    );
    assert!(c.plan.pixels_simulated <= 64 * 64);
    assert_eq!(c.plan.pixels_simulated, work(&r, "accumulate", "pixels"));
    let gamma = c.stages.iter().find(|s| s.name == "gamma").unwrap();
    assert_eq!(gamma.items, c.plan.pixels_simulated);
    // Every pixel outside the quarter is background.
    let bg = r.dac[127 * 128 + 127];
    for y in 0..128 {
        for x in 0..128 {
            if x >= 64 || y >= 64 {
                assert_eq!(r.dac[y * 128 + x], bg);
            }
        }
    }
}

#[test]
fn cost_storage_is_exact() {
    let s = Scene::default_scene();
    let h = HwConfig::default_config();
    let r = run(&s, &h);
    let k = &r.report.cycles.cost;
    let (w, ht) = (640u64, 480u64);
    assert_eq!(k.storage_bits["accumulate"], w * ht * 12);
    // The screen's 4x4 samples per pixel plus the tent filter's apron of 2 samples beyond
    // each edge, x (24-bit z + 16-bit intensity + primitive id bits).
    let prims = work(&r, "input", "primitives");
    let id_bits = (prims + 1).next_power_of_two().trailing_zeros() as u64;
    assert_eq!(
        k.storage_bits["visibility"],
        (w * 4 + 4) * (ht * 4 + 4) * (24 + 16 + id_bits)
    );
    assert_eq!(k.rom_bits["gamma"], 4096 * 8);
    assert!(k.packed.iter().all(|p| p.verified), "{:?}", k.packed);
}

#[test]
fn bad_cycle_fields_name_the_field_and_range() {
    for (text, field) in [
        ("[cycles.raster]\nlanes = 0\n", "cycles.raster.lanes"),
        ("[cycles]\ntile = 12\n", "cycles.tile"),
        ("[cycles.gamma]\nfifo = 0\n", "cycles.gamma.fifo"),
        ("[cycles]\nclock_mhz = -5.0\n", "cycles.clock_mhz"),
    ] {
        let e = HwConfig::from_toml(&TomlFile::from_text("hw.toml", text)).unwrap_err();
        assert_eq!(e.field, field, "{e}");
        assert!(e.to_string().contains("must be"), "{e}");
    }
    let e = HwConfig::from_toml(&TomlFile::from_text("hw.toml", "[cycles.dof]\nlanes = 0\n"))
        .unwrap_err();
    assert_eq!(e.field, "cycles.dof.lanes", "{e}");
    // Every stage has a timing section (the dither's too); a name that is no stage is refused.
    let d = HwConfig::from_toml(&TomlFile::from_text(
        "hw.toml",
        "[cycles.dither]\nlanes = 2\n",
    ))
    .unwrap();
    assert_eq!(d.cycles.dither.lanes, 2);
    let e = HwConfig::from_toml(&TomlFile::from_text(
        "hw.toml",
        "[cycles.display]\nlanes = 2\n",
    ))
    .unwrap_err();
    assert!(e.to_string().contains("display"), "{e}");
    let ok = HwConfig::from_toml(&TomlFile::from_text(
        "hw.toml",
        "[cycles]\nclock_mhz = 50.0\n[cycles.raster]\nlanes = 8\nfifo = 3\n",
    ))
    .unwrap();
    assert_eq!(ok.cycles.raster.lanes, 8);
    assert_eq!(ok.cycles.raster.fifo, 3);
    assert_eq!(ok.cycles.raster.latency, 4);
    assert_eq!(ok.cycles.clock_mhz, 50.0);
}

fn all_timings(c: &mut CyclesCfg, mut f: impl FnMut(&mut StageTiming)) {
    for id in igemu::config::TIMED {
        f(c.timing_mut(id).unwrap());
    }
}

#[test]
fn event_simulator_matches_stepwise_on_the_embedded_scenes() {
    let mut rng = Rng::new(0xe7e27);
    for name in ["default", "default-pinhole", "cone-focus"] {
        let s = Scene::embedded(name).unwrap();
        let h = HwConfig::default_config();
        let r = run(&s, &h);
        let base = h.cycles.clone();
        let mut configs: Vec<(&str, CyclesCfg)> = vec![("preset", base.clone())];
        let mut c = base.clone();
        all_timings(&mut c, |t| t.fifo = 1);
        configs.push(("fifo 1", c));
        let mut c = base.clone();
        all_timings(&mut c, |t| t.fifo = 65536);
        configs.push(("fifo 65536", c));
        // One-cycle services and no latency: something changes nearly every clock.
        let mut c = base.clone();
        all_timings(&mut c, |t| {
            t.lanes = 1024;
            t.latency = 0;
            t.fifo = 1;
        });
        configs.push(("lanes 1024, latency 0, fifo 1", c));
        let mut c = base.clone();
        all_timings(&mut c, |t| {
            t.latency = 1024;
            t.ii = 2;
            t.fifo = 2;
        });
        configs.push(("latency 1024, ii 2, fifo 2", c));
        // The frame-memory port bounds the accumulate stage.
        let mut c = base.clone();
        c.frame_port_bits = 16;
        configs.push(("frame port 16 bits", c));
        for _ in 0..3 {
            configs.push(("random", random_timing(&mut rng)));
        }
        let mut port_bound = false;
        for (what, c) in &configs {
            let w = r.workload_for(c, DofSchedule::Frame);
            assert_same_as_stepwise(&w, &format!("{name}, {what}, frame schedule"));
            let w = r.workload_for(c, DofSchedule::Stream);
            let sim = assert_same_as_stepwise(&w, &format!("{name}, {what}"));
            port_bound |= sim.frame_port_bound_cycles > 0;
            if *what == "preset" {
                assert_eq!(sim, cycles::simulate(&r.workload, None), "{name}");
                assert_eq!(sim.total_cycles, r.report.cycles.total_cycles, "{name}");
            }
        }
        assert!(port_bound, "{name}: some timing should be port-bound");
    }
}

/// A random workload: a random run of the timed stages, each with a random token kind (so
/// chains of random length form), random items and port bits, some chains without tokens.
fn random_workload(rng: &mut Rng) -> Workload {
    let kinds = [
        TokenKind::Primitive,
        TokenKind::Tile,
        TokenKind::Layer,
        TokenKind::Row,
    ];
    let mut planned: Vec<(StageId, Tokens)> = Vec::new();
    let mut kind = kinds[0];
    let mut n = 0;
    for id in igemu::config::TIMED {
        if rng.next_u64().is_multiple_of(5) {
            continue;
        }
        if rng.next_u64().is_multiple_of(3) {
            kind = kinds[(rng.next_u64() % 4) as usize];
        }
        // The stages of a chain pass the same tokens (a real run's do).
        if planned.last().is_none_or(|(_, t)| t.kind != kind) {
            n = match rng.next_u64() % 6 {
                0 => 0,
                1 => 1,
                _ => (rng.next_u64() % 40) as usize,
            };
        }
        let big = rng.next_u64().is_multiple_of(2);
        let items = (0..n)
            .map(|_| rng.next_u64() % if big { 400 } else { 4 })
            .collect();
        let port_bits = if rng.next_u64().is_multiple_of(3) {
            (0..n).map(|_| rng.next_u64() % 200).collect()
        } else {
            Vec::new()
        };
        planned.push((
            id,
            Tokens {
                kind,
                item: "items",
                items,
                port_bits,
                rows: vec![],
                stream: None,
            },
        ));
    }
    let mut c = random_timing(rng);
    all_timings(&mut c, |t| {
        if rng.next_u64().is_multiple_of(4) {
            t.fifo = [1, 2, 65536][(rng.next_u64() % 3) as usize];
        }
        if rng.next_u64().is_multiple_of(4) {
            t.latency = [0, 1, 1024][(rng.next_u64() % 3) as usize];
        }
    });
    let planned: Vec<(StageId, Option<&Tokens>)> =
        planned.iter().map(|(id, t)| (*id, Some(t))).collect();
    Workload::new(&planned, &c, ScreenFacts::default(), DofSchedule::Stream)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]
    /// Random chains, tokens and timings: the event-driven simulator's counts, FIFO maxima
    /// and VCD text are the stepwise reference's.
    #[test]
    fn event_simulator_matches_stepwise_on_random_workloads(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        let w = random_workload(&mut rng);
        assert_same_as_stepwise(&w, &format!("{w:?}"));
        // And a streamed depth of field behind accumulate's tiles.
        let w = sim::random_streamed(&mut rng);
        sim::assert_same_as_stepwise(&w, &format!("{w:?}"));
    }
}

#[test]
fn a_workload_that_cannot_finish_ends() {
    // The raster stage waits for 3 tokens its feeder never sends: no run produces this, and
    // the stepwise reference would loop for ever; the event-driven simulator stops.
    let tokens = |n: usize| Tokens {
        kind: TokenKind::Primitive,
        item: "items",
        items: vec![5; n],
        port_bits: Vec::new(),
        rows: vec![],
        stream: None,
    };
    let (a, b) = (tokens(1), tokens(3));
    let c = CyclesCfg::default_for(12);
    let w = Workload::new(
        &[(StageId::Setup, Some(&a)), (StageId::Raster, Some(&b))],
        &c,
        ScreenFacts::default(),
        DofSchedule::Stream,
    );
    let r = cycles::simulate(&w, None);
    assert_eq!(r.stages[1].busy, c.raster.service(5));
    assert!(r.stages[1].starved > 0);
    assert_eq!(r.total_cycles, r.stages[1].busy + r.stages[1].starved);
}

/// Every planned stage has a cycle model: a log-coded render with Floyd-Steinberg times the
/// log encoder (one code per depth test, chained behind visibility per primitive) and the
/// error diffusion (one token per row, its pixels one after another); an ordered dither
/// without depth of field follows gamma tile by tile through a FIFO. (The log coding here is
/// log-potentiate; log-add with a dither is tests/logadd_dither.rs.)
#[test]
fn logdomain_and_dither_have_cycle_models() {
    let s = Scene::embedded("default-pinhole").expect("embedded");
    let mut h = HwConfig::preset("log8-potentiate").expect("preset");
    h.dither.kind = igemu::config::DitherKind::FloydSteinberg;
    let r = run(&s, &h);
    let c = &r.report.cycles;
    assert!(c.plan.unmodelled.is_empty(), "{:?}", c.plan.unmodelled);
    let chain = |id: StageId| {
        r.workload
            .stages
            .iter()
            .position(|s| s.id == id)
            .unwrap_or_else(|| panic!("{id:?} in the chains"))
    };
    let (vis, log, dith) = (
        chain(StageId::Visibility),
        chain(StageId::Logdomain),
        chain(StageId::Dither),
    );
    let w = &r.workload.stages;
    // The encoder: behind visibility, one token per primitive, one code per depth test of a
    // surface and one per light point.
    assert_eq!(w[log].feeder, Some(vis));
    assert_eq!(w[log].kind, TokenKind::Primitive);
    let codes: u64 = w[log].items.iter().sum();
    assert_eq!(
        codes,
        work(&r, "visibility", "tests") + (w[log].items.len() as u64 - w[vis].items.len() as u64)
    );
    assert_eq!(w[log].items.len(), w[vis].items.len());
    let st = |n: &str| cycles_of(&r, n);
    assert!(st("logdomain").busy > 0);
    // Error diffusion: raster order, one row per token; after tile-ordered gamma it waits
    // for the whole frame.
    assert_eq!(w[dith].kind, TokenKind::Row);
    assert_eq!(w[dith].items, vec![640u64; 480]);
    assert_eq!(w[dith].feeder, None);
    let d = st("dither");
    assert_eq!(d.busy, 640 * 480);
    assert!(d.starved >= st("gamma").busy, "{d:?}");
    // A slower loop (two clocks per pixel) doubles the dither's busy cycles.
    h.cycles.dither.ii = 2;
    let r2 = run(&s, &h);
    let d2 = cycles_of(&r2, "dither");
    assert_eq!(d2.busy, 2 * 640 * 480);
    // An ordered dither without depth of field: one token per binned tile behind gamma.
    let mut o = HwConfig::default_config();
    o.dither.kind = igemu::config::DitherKind::Bayer8;
    let ro = run(&s, &o);
    assert!(ro.report.cycles.plan.unmodelled.is_empty());
    let wo = &ro.workload.stages;
    let (g, d) = (
        wo.iter().position(|s| s.id == StageId::Gamma).unwrap(),
        wo.iter().position(|s| s.id == StageId::Dither).unwrap(),
    );
    assert_eq!(wo[d].kind, TokenKind::Tile);
    assert_eq!(wo[d].feeder, Some(g));
    assert_eq!(wo[d].items, wo[g].items);
}

/// The VCD's time scale: one clock period in the largest unit that divides it, so that time
/// stamps are real time and the header's comment and `$timescale` agree (issue 30).
#[test]
fn vcd_time_is_the_clock_period() {
    use vcd::TimescaleUnit as U;
    assert_eq!(igemu::cycles::vcd::cycle_time(100.0), (10, U::NS));
    assert_eq!(igemu::cycles::vcd::cycle_time(1000.0), (1, U::NS));
    assert_eq!(igemu::cycles::vcd::cycle_time(1.0), (1, U::US));
    assert_eq!(igemu::cycles::vcd::cycle_time(400.0), (2500, U::PS));
    // 133 MHz: 7 518 796.99 fs, rounded to the femtosecond.
    assert_eq!(igemu::cycles::vcd::cycle_time(133.0), (7_518_797, U::FS));
    let w = igemu::pipeline::render(
        &igemu::scene::Scene::embedded("default-pinhole").unwrap(),
        &HwConfig::default_config(),
        igemu::stage::RunOptions::FAST,
    )
    .unwrap()
    .workload;
    let text = String::from_utf8(
        VcdWriter::new(Vec::new(), &w, 100.0)
            .unwrap()
            .finish(7)
            .unwrap(),
    )
    .unwrap();
    assert!(
        text.contains("1 clock cycle = 10 x $timescale 1 ns"),
        "{text}"
    );
    assert!(
        text.contains("$timescale 1 ns $end") || text.contains("$timescale\n1 ns"),
        "{text}"
    );
    assert!(text.trim_end().ends_with("#70"), "{text}");
}
