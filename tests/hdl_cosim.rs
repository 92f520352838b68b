//! HDL co-simulation: every Verilog model in hdl-models/rtl/ agrees bit for bit with the
//! Rust model on its vectors (scene taps, exhaustive, random) at two or more width
//! settings, under Icarus Verilog and Verilator; the log adder also on its full pair space.
//! Without a simulator installed the simulator tests print a skip line for it and pass,
//! unless `IGEMU_REQUIRE_HDL=1` (set by `.ci/run`): then every skip fails its test, so a
//! co-simulation cannot go unrun unseen. The vector and verdict tests run everywhere.

mod common;

use common::sims::{REQUIRE, icarus, skip, skip_or_fail, verilator, verilator_cache};
use common::{hw, scene, tri};
use igemu::config::HwConfig;
use igemu::config::{DitherKind, DofKind, FilterKind};
use igemu::fixed::{Overflow, QFormat, Quant};
use igemu::hdl::verilator::Sim;
use igemu::hdl::{self, Bench, Verdict, exhaustive};
use igemu::scene::Scene;
use igemu::stage_id::StageId;
use std::path::PathBuf;

fn small_scene() -> Scene {
    let objects = [
        tri(
            [[3.0, 2.0, 0.3], [60.0, 9.0, 0.5], [20.0, 45.0, 0.7]],
            [1.0, 0.4, 0.05],
        ),
        tri(
            [[40.0, 5.0, 0.2], [63.0, 40.0, 0.2], [30.0, 30.0, 0.2]],
            [0.9, 0.9, 0.9],
        ),
    ]
    .concat();
    scene(64, 48, 0.1, &objects)
}

/// Under `IGEMU_REQUIRE_HDL=1` a skip fails its test; without it, it passes.
#[test]
fn a_skip_fails_when_the_simulators_are_required() {
    let line = "SKIP test: iverilog/vvp not installed";
    let e = std::panic::catch_unwind(|| skip_or_fail(line, true)).unwrap_err();
    let msg = e.downcast_ref::<String>().expect("a message");
    assert!(msg.contains(line) && msg.contains(REQUIRE), "{msg}");
    skip_or_fail(line, false);
}

/// Writes the bench and runs testbench `tb` on it under `sim`.
fn run_tb(sim: Sim, tb: &str, b: &Bench, tag: &str) -> Verdict {
    let d = dir(&format!("{}-{tag}", sim.name()));
    b.write(&d).expect("write bench");
    let v = sim
        .run(tb, b.module, &d, &verilator_cache())
        .unwrap_or_else(|e| panic!("{tag} under {}: {e}", sim.name()));
    let _ = std::fs::remove_dir_all(&d);
    v.verdict
}

fn dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("igemu-hdl-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn run(b: &Bench, tag: &str) -> Verdict {
    let d = dir(tag);
    b.write(&d).expect("write bench");
    let v = hdl::run_icarus(b.module, &d).unwrap_or_else(|e| panic!("{tag}: {e}"));
    let _ = std::fs::remove_dir_all(&d);
    v
}

/// Builds the stage's bench for each config and checks that the testbench passes all
/// vectors, under Icarus Verilog and under Verilator (each when installed).
fn agree(stage: StageId, configs: &[(&str, HwConfig)], sc: &Scene) {
    let sims: Vec<Sim> = [
        (Sim::Icarus, icarus(stage.name())),
        (Sim::Verilator, verilator(stage.name())),
    ]
    .into_iter()
    .filter(|s| s.1)
    .map(|s| s.0)
    .collect();
    if sims.is_empty() {
        return;
    }
    let mut widths = std::collections::BTreeSet::new();
    for (tag, h) in configs {
        let b = hdl::vectors(stage, sc, h).unwrap_or_else(|e| panic!("{tag}: {e}"));
        widths.insert(b.params.clone());
        for &sim in &sims {
            let tb = format!("tb_{}", b.module);
            assert_eq!(
                run_tb(sim, &tb, &b, &format!("{stage}-{tag}")),
                Verdict::Ok(b.vectors.len() as u64),
                "{stage} at {tag} under {}",
                sim.name()
            );
        }
    }
    assert!(widths.len() >= 2, "{stage}: two or more width settings");
}

#[test]
fn gamma_lut_agrees_exhaustively_at_three_widths() {
    let sc = small_scene();
    let frac = hw("linear12", |h| {
        h.accumulate.frame.format = QFormat::new(false, 10, 2);
        h.input.intensity.format = QFormat::new(false, 10, 4);
        h.gamma.dac_bits = 10;
    });
    let cfgs = [
        ("linear12", hw("linear12", |_| {})),
        ("linear8", hw("linear8", |_| {})),
        ("uq10.2-dac10", frac),
    ];
    // The exhaustive part covers every LUT address.
    let b = hdl::vectors(StageId::Gamma, &sc, &cfgs[2].1).expect("bench");
    let addrs: std::collections::BTreeSet<u64> = b.vectors.iter().map(|v| v[0] >> 2).collect();
    assert_eq!(addrs.len(), 1 << 10);
    agree(StageId::Gamma, &cfgs, &sc);
}

#[test]
fn accumulate_mac_agrees_at_three_settings() {
    let sc = small_scene();
    let cfgs = [
        ("linear12", hw("linear12", |_| {})),
        ("linear8", hw("linear8", |_| {})),
        (
            "trn-wrap-w8",
            hw("linear11", |h| {
                h.accumulate.weight_bits = 8;
                h.accumulate.frame.quant = Quant::Trn;
                h.accumulate.frame.overflow = Overflow::Wrap;
            }),
        ),
        (
            "rnd-satzero",
            hw("linear12", |h| {
                h.accumulate.frame.quant = Quant::Rnd;
                h.accumulate.frame.overflow = Overflow::SatZero;
            }),
        ),
    ];
    // Some vectors overflow (the edge cases), so the overflow path is exercised.
    let b = hdl::vectors(StageId::Accumulate, &sc, &cfgs[0].1).expect("bench");
    assert!(b.vectors.iter().any(|v| v[4] == 1));
    agree(StageId::Accumulate, &cfgs, &sc);
}

/// The signed MAC of the cubic filters with negative lobes: two's-complement weights, the
/// signed accumulator and its clamp to the frame word, at four settings of rounding and
/// overflow (every mode that differs for negative values among them).
#[test]
fn signed_accumulate_mac_agrees_with_catmull_rom_and_mitchell() {
    let sc = small_scene();
    let cubic = |f: FilterKind, q: Quant, o: Overflow| {
        hw("linear12", |h| {
            h.accumulate.filter = f;
            h.accumulate.frame.quant = q;
            h.accumulate.frame.overflow = o;
        })
    };
    let cfgs = [
        (
            "catmull-rom",
            cubic(FilterKind::CatmullRom, Quant::RndConv, Overflow::Sat),
        ),
        (
            "catmull-rom-trnzero-wrap",
            cubic(FilterKind::CatmullRom, Quant::TrnZero, Overflow::Wrap),
        ),
        (
            "mitchell-rndinf-satsym",
            cubic(FilterKind::Mitchell, Quant::RndInf, Overflow::SatSym),
        ),
        (
            "mitchell-rndzero-satzero-w8",
            hw("linear11", |h| {
                h.accumulate.filter = FilterKind::Mitchell;
                h.accumulate.weight_bits = 8;
                h.accumulate.frame.quant = Quant::RndZero;
                h.accumulate.frame.overflow = Overflow::SatZero;
            }),
        ),
    ];
    // The vectors hold negative weights, negative partial sums and clamps both ways.
    let b = hdl::vectors(StageId::Accumulate, &sc, &cfgs[0].1).expect("bench");
    let p = |k: &str| b.params.iter().find(|x| x.0 == k).unwrap().1;
    assert_eq!((p("SIGNED"), p("A_BITS"), p("F_BITS")), (1, 14, 12));
    let wb = p("W_BITS") as u32;
    assert!(
        b.vectors.iter().any(|v| v[0] >> (wb - 1) == 1),
        "negative weights"
    );
    assert!(
        b.vectors.iter().any(|v| v[6] == 1 && v[5] == 0),
        "clamp at black"
    );
    assert!(
        b.vectors.iter().any(|v| v[6] == 1 && v[5] == 4095),
        "clamp at white"
    );
    agree(StageId::Accumulate, &cfgs, &sc);
}

#[test]
fn ordered_dither_agrees_exhaustively_at_three_settings() {
    let sc = small_scene();
    let cfgs = [
        ("linear12-bayer4", hw("linear12", |_| {})),
        (
            "linear8-bayer8-f2",
            hw("linear8", |h| {
                h.dither.kind = DitherKind::Bayer8;
                h.dither.frac_bits = 2;
            }),
        ),
        (
            "bayer2-f3-frame5",
            hw("linear12", |h| {
                h.dither.kind = DitherKind::Bayer2;
                h.dither.frac_bits = 3;
                h.dither.temporal = true;
                h.dither.frame = 5;
            }),
        ),
    ];
    agree(StageId::Dither, &cfgs, &sc);
}

/// The log adder's three vector-testbench settings.
fn log_settings() -> [(&'static str, HwConfig); 3] {
    [
        ("log8-logadd", hw("log8-logadd", |_| {})),
        ("log7-logadd", hw("log7-logadd", |_| {})),
        (
            "log8-interp-tf2-a6",
            hw("log8-logadd", |h| {
                h.coding.interpolate = true;
                h.coding.table_frac_bits = 2;
                h.coding.table_addr_bits = 6;
            }),
        ),
    ]
}

#[test]
fn log_adder_agrees_at_three_settings() {
    let sc = small_scene();
    agree(StageId::Logdomain, &log_settings(), &sc);
}

#[test]
fn edge_stepper_agrees_on_scene_edges_at_two_grids() {
    let sc = small_scene();
    let cfgs = [
        ("samples2", hw("linear12", |h| h.raster.samples = 2)),
        ("samples8", hw("linear12", |h| h.raster.samples = 8)),
    ];
    let b = hdl::vectors(StageId::Setup, &sc, &cfgs[1].1).expect("bench");
    // Loads and steps, some steps with the extra column carry.
    assert!(b.vectors.iter().filter(|v| v[0] == 1).count() >= 6);
    assert!(b.vectors.iter().any(|v| v[0] == 0 && v[8] == 1));
    agree(StageId::Setup, &cfgs, &sc);
}

#[test]
fn a_broken_vector_fails_the_testbench() {
    if !icarus("broken vector") {
        return;
    }
    let sc = small_scene();
    let mut b = hdl::vectors(StageId::Gamma, &sc, &hw("linear12", |_| {})).expect("bench");
    assert_eq!(run(&b, "gamma-good"), Verdict::Ok(b.vectors.len() as u64));
    b.vectors[100][1] ^= 1;
    match run(&b, "gamma-broken") {
        Verdict::Failed(m) => assert!(m.starts_with("1 of "), "{m}"),
        v => panic!("a broken vector passed: {v:?}"),
    }
    // A broken expected overflow flag fails too.
    let mut b = hdl::vectors(StageId::Accumulate, &sc, &hw("linear12", |_| {})).expect("bench");
    let last = b.vectors.len() - 1;
    b.vectors[last][4] ^= 1;
    assert!(matches!(run(&b, "acc-broken"), Verdict::Failed(_)));
}

#[test]
fn verdict_lines_parse() {
    assert_eq!(
        hdl::parse_verdict("VCD info\nTESTBENCH OK 12 vectors\n"),
        Some(Verdict::Ok(12))
    );
    assert_eq!(
        hdl::parse_verdict("TESTBENCH FAILED: 1 of 3 vectors differ"),
        Some(Verdict::Failed("1 of 3 vectors differ".into()))
    );
    assert_eq!(hdl::parse_verdict("nothing"), None);
    assert_eq!(
        hdl::parse_verdict("TESTBENCH OK 1 vectors\nTESTBENCH OK 1 vectors"),
        None
    );
}

#[test]
fn unknown_stage_and_linear_log_adder_are_refused() {
    let sc = small_scene();
    let e = hdl::vectors(StageId::Raster, &sc, &hw("linear12", |_| {})).unwrap_err();
    assert!(e.to_string().contains("gamma, accumulate"), "{e}");
    let e = hdl::vectors(StageId::Logdomain, &sc, &hw("linear12", |_| {})).unwrap_err();
    assert!(e.to_string().contains("coding.kind"), "{e}");
    // The linear MAC is not the log-add hardware: its vectors are refused there.
    let e = hdl::vectors(StageId::Accumulate, &sc, &hw("log8-logadd", |_| {})).unwrap_err();
    assert!(
        e.to_string().contains("coding.kind") && e.to_string().contains("--stage logdomain"),
        "{e}"
    );
    // The dof row MAC is the layered method's: refused for the other two kinds.
    for kind in [DofKind::Luminance, DofKind::Downsample] {
        let dof = Scene::default_scene();
        let e =
            hdl::vectors(StageId::Dof, &dof, &hw("linear12", |h| h.dof.kind = kind)).unwrap_err();
        assert!(
            e.to_string().contains("dof.kind") && e.to_string().contains(kind.name()),
            "{e}"
        );
    }
}

#[test]
fn params_file_carries_the_widths() {
    let sc = small_scene();
    let b = hdl::vectors(StageId::Gamma, &sc, &hw("linear8", |_| {})).expect("bench");
    let p = b.params_vh();
    assert!(p.contains("`define P_ACC_BITS 8\n"), "{p}");
    assert!(p.contains(&format!("`define N_VECTORS {}\n", b.vectors.len())));
    assert_eq!(b.roms[0].1.len(), 256);
}

/// A log-add setting with a 9-bit frame code (7-bit log code, no extra fraction bits): its
/// full pair space (2^18) is small enough for Icarus too.
fn log7_fa0() -> HwConfig {
    hw("log7-logadd", |h| h.coding.acc_frac_bits = 0)
}

/// The log adder on every pair of frame codes, at four settings: under Verilator at all of
/// them (2^24 pairs at the 12-bit default frame codes), under Icarus at the 9-bit one only
/// (2^24 pairs take over 2 minutes in vvp on the development machine).
#[test]
fn log_adder_agrees_on_every_pair() {
    let sc = small_scene();
    let mut cfgs = log_settings().to_vec();
    cfgs.push(("log7-fa0", log7_fa0()));
    let benches: Vec<(&str, Bench)> = cfgs
        .iter()
        .map(|(t, h)| (*t, hdl::vectors(StageId::Logdomain, &sc, h).expect("bench")))
        .collect();
    let fb = |b: &Bench| b.params.iter().find(|p| p.0 == "FB").expect("FB").1;
    // The default presets' frame codes are 12 bits; one signature per row of the full space.
    assert_eq!(fb(&benches[0].1), 12);
    assert_eq!(fb(&benches[3].1), 9);
    for (_, b) in &benches {
        let sig = b
            .roms
            .iter()
            .find(|r| r.0 == exhaustive::SIG_FILE)
            .expect("signatures");
        assert_eq!(sig.1.len(), 1 << fb(b));
    }
    let widths: std::collections::BTreeSet<_> = benches.iter().map(|b| &b.1.params).collect();
    assert_eq!(widths.len(), 4);
    let mut ran = 0;
    if icarus("log adder, every pair at FB=9") {
        let b = &benches[3].1;
        assert_eq!(
            run_tb(Sim::Icarus, exhaustive::TESTBENCH, b, "log-all-log7-fa0"),
            Verdict::Ok(1 << 18)
        );
        ran += 1;
    }
    if verilator("log adder, every pair at FB=12 (three settings) and FB=9") {
        for (tag, b) in &benches {
            let n = exhaustive::pairs(b).expect("pairs");
            assert_eq!(
                run_tb(
                    Sim::Verilator,
                    exhaustive::TESTBENCH,
                    b,
                    &format!("log-all-{tag}")
                ),
                Verdict::Ok(n),
                "every pair at {tag}"
            );
            ran += 1;
        }
    }
    if ran == 0 {
        skip("SKIP log adder on every pair: no simulator installed");
    }
}

/// A corrupted expected signature fails the exhaustive testbench and names its row (whose
/// pair-by-pair run then passes: the model and RTL agree, the signature was wrong); a
/// corrupted ROM entry fails it too, and the failing row's pair-by-pair run names the pair.
#[test]
fn a_corrupted_signature_or_rom_entry_fails_the_exhaustive_testbench() {
    let sc = small_scene();
    let h = log7_fa0();
    let sims: Vec<Sim> = [
        (Sim::Icarus, icarus("corrupted signature")),
        (Sim::Verilator, verilator("corrupted signature")),
    ]
    .into_iter()
    .filter(|s| s.1)
    .map(|s| s.0)
    .collect();
    for sim in sims {
        let good = hdl::vectors(StageId::Logdomain, &sc, &h).expect("bench");
        let sig_k = good
            .roms
            .iter()
            .position(|r| r.0 == exhaustive::SIG_FILE)
            .expect("sig");
        let mut b = good.clone();
        b.roms[sig_k].1[37] ^= 1 << 20;
        let m = match run_tb(sim, exhaustive::TESTBENCH, &b, "log-bad-sig") {
            Verdict::Failed(m) => m,
            v => panic!("a corrupted signature passed under {}: {v:?}", sim.name()),
        };
        assert!(
            m.starts_with("1 of 512 rows differ, first row a=37 "),
            "{m}"
        );
        let row = exhaustive::failed_row(&m).expect("row");
        let rb = exhaustive::row_bench(&sc, &h, row).expect("row bench");
        assert!(rb.vectors.iter().all(|v| v[0] == 37));
        assert_eq!(
            run_tb(sim, "tb_log_adder", &rb, "log-row-37"),
            Verdict::Ok(512)
        );
        // One ROM entry off by one: sb(2^SHIFT) is used by every pair at difference 1..
        let mut b = good.clone();
        let rom_k = b
            .roms
            .iter()
            .position(|r| r.0 == "log_rom.hex")
            .expect("rom");
        b.roms[rom_k].1[1] ^= 1;
        let m = match run_tb(sim, exhaustive::TESTBENCH, &b, "log-bad-rom") {
            Verdict::Failed(m) => m,
            v => panic!("a corrupted ROM entry passed under {}: {v:?}", sim.name()),
        };
        let row = exhaustive::failed_row(&m).expect("row");
        let mut rb = exhaustive::row_bench(&sc, &h, row).expect("row bench");
        rb.roms[rom_k].1[1] ^= 1;
        match run_tb(sim, "tb_log_adder", &rb, "log-row-bad-rom") {
            Verdict::Failed(m) => assert!(m.contains(&format!("(a={row:x} b=")), "{m}"),
            v => panic!("row {row} with a corrupted ROM passed: {v:?}"),
        }
    }
}

#[test]
fn exhaustive_signatures_fold_each_row_in_order() {
    // FNV-1a over output words; the order matters and any single change shows.
    let s = exhaustive::signature([1, 2, 3]);
    assert_ne!(s, exhaustive::signature([2, 1, 3]));
    assert_ne!(s, exhaustive::signature([1, 2, 2]));
    assert_eq!(exhaustive::signature([]), exhaustive::FNV_BASIS);
    let rows = exhaustive::row_signatures(3, |a, c| a * 8 + c);
    assert_eq!(rows.len(), 8);
    assert_eq!(rows[5] as u32, exhaustive::signature(40..48));
    assert_eq!(
        exhaustive::failed_row("1 of 512 rows differ, first row a=37 (x)"),
        Some(37)
    );
    assert_eq!(exhaustive::failed_row("1 of 3 vectors differ"), None);
}

#[test]
fn cli_runs_the_exhaustive_log_adder_and_refuses_bad_flags() {
    let igemu = env!("CARGO_BIN_EXE_igemu");
    let d = dir("cli");
    let out = |args: &[&str]| {
        let o = std::process::Command::new(igemu)
            .args(args)
            .output()
            .expect("run igemu");
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr),
        )
    };
    let ds = d.display().to_string();
    let (c, t) = out(&[
        "hdl", "vectors", "--stage", "gamma", "--out", &ds, "--run", "--sim", "ghdl",
    ]);
    assert_eq!(c, Some(2), "{t}");
    // clap's message names the flag, the bad value and the choices.
    assert!(
        t.contains("--sim") && t.contains("ghdl") && t.contains("icarus, verilator"),
        "{t}"
    );
    let (c, t) = out(&[
        "hdl",
        "vectors",
        "--stage",
        "gamma",
        "--out",
        &ds,
        "--run",
        "--exhaustive",
    ]);
    assert_eq!(c, Some(2), "{t}");
    assert!(t.contains("--stage logdomain"), "{t}");
    if !verilator("cli --exhaustive") {
        return;
    }
    std::fs::create_dir_all(&d).expect("dir");
    let hw_file = d.join("log7-fa0.toml");
    std::fs::write(
        &hw_file,
        "preset = \"log7-logadd\"\n[coding]\nacc_frac_bits = 0\n",
    )
    .expect("hw");
    let hw_s = hw_file.display().to_string();
    let bench = d.join("bench").display().to_string();
    let (c, t) = out(&[
        "hdl",
        "vectors",
        "--stage",
        "logdomain",
        "--hw",
        &hw_s,
        "default-pinhole",
        "--out",
        &bench,
        "--run",
        "--sim",
        "verilator",
        "--exhaustive",
    ]);
    assert_eq!(c, Some(0), "{t}");
    assert!(
        t.contains("verilator: tb_log_adder_exhaustive: TESTBENCH OK 262144 vectors (every pair)"),
        "{t}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Narrow dof words: 8-bit coefficients, a 16-bit line buffer and an 18-bit accumulator
/// saturate on the default scene (both passes).
fn dof_narrow() -> HwConfig {
    hw("linear12", |h| {
        h.dof.coef_bits = 8;
        h.dof.line_bits = 16;
        h.dof.acc_bits = 18;
    })
}

/// Index of the first expected-output field of a dof bench (pass, layer, pos, len, windows;
/// then sx, ovf, sa, sd, w).
fn dof_out(b: &Bench) -> usize {
    b.fields.len() - 5
}

#[test]
fn dof_row_mac_agrees_on_scene_taps_at_two_widths() {
    let sc = Scene::default_scene();
    let narrow = hdl::vectors(StageId::Dof, &sc, &dof_narrow()).expect("bench");
    let default = hdl::vectors(StageId::Dof, &sc, &hw("linear12", |_| {})).expect("bench");
    assert_ne!(narrow.params, default.params);
    let o = dof_out(&narrow);
    let n_scene = narrow.sources[0].1;
    assert_eq!(narrow.sources[0].0, "scene");
    assert!(n_scene >= 1000, "{:?}", narrow.sources);
    // The narrow words saturate on real scene taps in both passes, and some outputs sit at
    // the image border (renormalisation weight below 2^f).
    for pass in 0..2 {
        assert!(
            narrow.vectors[..n_scene]
                .iter()
                .any(|v| v[0] == pass && v[o + 1] == 1),
            "pass {pass} saturates"
        );
    }
    assert!(narrow.vectors.iter().any(|v| v[o + 4] < 1 << 8));
    // Some horizontal scene taps see nearer layers: their behind sum falls below a whole
    // pixel's (16 samples times the in-line taps' sum).
    assert!(
        narrow.vectors[..n_scene]
            .iter()
            .any(|v| v[0] == 0 && v[o + 3] < v[o + 4] * 16)
    );
    // The default widths never saturate.
    assert!(
        default
            .vectors
            .iter()
            .all(|v| v[dof_out(&default) + 1] == 0)
    );
    for (sim, installed) in [
        (Sim::Icarus, icarus("dof")),
        (Sim::Verilator, verilator("dof")),
    ] {
        if !installed {
            continue;
        }
        for (tag, b) in [("linear12", &default), ("narrow", &narrow)] {
            assert_eq!(
                run_tb(sim, "tb_dof_row_mac", b, &format!("dof-{tag}")),
                Verdict::Ok(b.vectors.len() as u64),
                "dof at {tag} under {}",
                sim.name()
            );
        }
    }
}

#[test]
fn dof_row_mac_gates_off_line_taps_and_broken_vectors_fail() {
    if !icarus("dof broken vector") {
        return;
    }
    let sc = Scene::default_scene();
    let mut b = hdl::vectors(StageId::Dof, &sc, &dof_narrow()).expect("bench");
    let (o, taps) = (dof_out(&b), (b.fields.len() - 9) / 3);
    let half = taps / 2;
    // Vectors at the left image border: their first window samples lie off the line.
    let border: Vec<usize> = (0..b.vectors.len())
        .filter(|&k| b.vectors[k][2] == 0 && b.vectors[k][3] > 1)
        .take(5)
        .collect();
    assert_eq!(border.len(), 5);
    // Off-line samples are ignored: changing them does not fail the vector.
    b.vectors[border[0]][4] ^= 1;
    b.vectors[border[0]][4 + taps] ^= 1;
    b.vectors[border[0]][4 + 2 * taps] ^= 1;
    // A changed expected colour sum, overflow flag, behind sum or border weight fails.
    for (k, field) in [
        (border[1], o),
        (border[2], o + 1),
        (border[3], o + 3),
        (border[4], o + 4),
    ] {
        b.vectors[k][field] ^= 1;
    }
    // So does an on-line input sample whose coefficient is non-zero (the centre tap) of an
    // unsaturated output.
    let k = (0..b.vectors.len())
        .find(|&k| !border.contains(&k) && b.vectors[k][o + 1] == 0 && b.vectors[k][o] > 0)
        .expect("an unsaturated vector");
    b.vectors[k][4 + half] ^= 1 << 4;
    match run(&b, "dof-broken") {
        Verdict::Failed(m) => assert!(m.starts_with("5 of "), "{m}"),
        v => panic!("broken vectors passed: {v:?}"),
    }
}

#[test]
fn dof_row_mac_refuses_pinhole_scenes_and_wide_accumulators() {
    let e = hdl::vectors(StageId::Dof, &small_scene(), &hw("linear12", |_| {})).unwrap_err();
    assert!(e.to_string().contains("camera.lens"), "{e}");
    let wide = hw("linear12", |h| h.dof.acc_bits = 72);
    let e = hdl::vectors(StageId::Dof, &Scene::default_scene(), &wide).unwrap_err();
    assert!(e.to_string().contains("dof.acc_bits"), "{e}");
}

/// `igemu cost --synth`: yosys cell counts of a module at two widths, then from the cache.
#[test]
fn yosys_cell_counts_grow_with_the_widths_and_are_cached() {
    if !hdl::available("yosys") {
        skip("SKIP yosys synthesis: yosys not installed (apt-get install -y yosys)");
        return;
    }
    let sc = small_scene();
    let cache = dir("synth-cache");
    let narrow = hdl::vectors(StageId::Accumulate, &sc, &hw("linear8", |_| {})).expect("bench");
    let wide = hdl::vectors(StageId::Accumulate, &sc, &hw("linear12", |_| {})).expect("bench");
    let a = hdl::synth::synth(&narrow, &cache).expect("synth");
    let b = hdl::synth::synth(&wide, &cache).expect("synth");
    assert!(!a.cached && !b.cached);
    assert!(a.cells > 0 && a.flip_flops() > 0, "{a:?}");
    assert!(b.cells > a.cells, "wider words, more cells: {a:?} {b:?}");
    let again = hdl::synth::synth(&narrow, &cache).expect("synth");
    assert!(again.cached);
    assert_eq!((again.cells, &again.by_type), (a.cells, &a.by_type));
    // The signed datapath of Catmull-Rom (two's-complement weights, the 14-bit signed
    // accumulator and its clamp) against the unsigned one of the tent at the same preset.
    let signed = hw("linear12", |h| h.accumulate.filter = FilterKind::CatmullRom);
    let s = hdl::vectors(StageId::Accumulate, &sc, &signed).expect("bench");
    let c = hdl::synth::synth(&s, &cache).expect("synth");
    eprintln!(
        "acc_mac cells: linear8 tent {}, linear12 tent {}, linear12 catmull_rom {} (flip-flops {} / {} / {})",
        a.cells,
        b.cells,
        c.cells,
        a.flip_flops(),
        b.flip_flops(),
        c.flip_flops()
    );
    assert!(
        c.flip_flops() > b.flip_flops(),
        "the wider accumulator: {b:?} {c:?}"
    );
    let _ = std::fs::remove_dir_all(&cache);
}

#[test]
fn a_relative_bench_directory_runs_under_icarus() {
    if !icarus("a_relative_bench_directory_runs_under_icarus") {
        return;
    }
    // The test runs in the crate's directory: a bench directory relative to it.
    let rel = format!("target/hdl-relative-{}", std::process::id());
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_igemu"))
        .args(["hdl", "vectors", "--stage", "gamma", "--out", &rel, "--run"])
        .output()
        .expect("run igemu");
    let text =
        String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr);
    std::fs::remove_dir_all(&rel).ok();
    assert_eq!(o.status.code(), Some(0), "{text}");
    assert!(text.contains("TESTBENCH OK"), "{text}");
}
