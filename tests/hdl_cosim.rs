//! HDL co-simulation: every Verilog model in hdl-models/rtl/ agrees bit for bit with the
//! Rust model on its vectors (scene taps, exhaustive, random) at two or more width
//! settings, under Icarus Verilog. Without iverilog installed the simulator tests print a
//! skip line and pass; the vector and verdict tests run everywhere.

mod common;

use common::{hw, scene, tri};
use igemu::fixed::{Overflow, QFormat, Quant};
use igemu::hdl::{self, Bench, Verdict};
use igemu::hw::HwConfig;
use igemu::scene::Scene;
use igemu::stage::dither::DitherKind;
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

/// Whether Icarus Verilog is installed; prints the skip line when it is not.
fn icarus(test: &str) -> bool {
    if hdl::available("iverilog") && hdl::available("vvp") {
        return true;
    }
    println!(
        "SKIP {test}: iverilog/vvp not installed (apt-get install -y iverilog); HDL co-simulation not run"
    );
    false
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

/// Builds the stage's bench for each config and checks that the testbench passes all vectors.
fn agree(stage: &str, configs: &[(&str, HwConfig)], sc: &Scene) {
    if !icarus(stage) {
        return;
    }
    let mut widths = std::collections::BTreeSet::new();
    for (tag, h) in configs {
        let b = hdl::vectors(stage, sc, h).unwrap_or_else(|e| panic!("{tag}: {e}"));
        widths.insert(b.params.clone());
        assert_eq!(
            run(&b, &format!("{stage}-{tag}")),
            Verdict::Ok(b.vectors.len() as u64),
            "{stage} at {tag}"
        );
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
    let b = hdl::vectors("gamma", &sc, &cfgs[2].1).expect("bench");
    let addrs: std::collections::BTreeSet<u64> = b.vectors.iter().map(|v| v[0] >> 2).collect();
    assert_eq!(addrs.len(), 1 << 10);
    agree("gamma", &cfgs, &sc);
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
    let b = hdl::vectors("accumulate", &sc, &cfgs[0].1).expect("bench");
    assert!(b.vectors.iter().any(|v| v[4] == 1));
    agree("accumulate", &cfgs, &sc);
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
    agree("dither", &cfgs, &sc);
}

#[test]
fn log_adder_agrees_at_three_settings() {
    let sc = small_scene();
    let cfgs = [
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
    ];
    agree("logdomain", &cfgs, &sc);
}

#[test]
fn edge_stepper_agrees_on_scene_edges_at_two_grids() {
    let sc = small_scene();
    let cfgs = [
        ("samples2", hw("linear12", |h| h.raster.samples = 2)),
        ("samples8", hw("linear12", |h| h.raster.samples = 8)),
    ];
    let b = hdl::vectors("setup", &sc, &cfgs[1].1).expect("bench");
    // Loads and steps, some steps with the extra column carry.
    assert!(b.vectors.iter().filter(|v| v[0] == 1).count() >= 6);
    assert!(b.vectors.iter().any(|v| v[0] == 0 && v[8] == 1));
    agree("setup", &cfgs, &sc);
}

#[test]
fn a_broken_vector_fails_the_testbench() {
    if !icarus("broken vector") {
        return;
    }
    let sc = small_scene();
    let mut b = hdl::vectors("gamma", &sc, &hw("linear12", |_| {})).expect("bench");
    assert_eq!(run(&b, "gamma-good"), Verdict::Ok(b.vectors.len() as u64));
    b.vectors[100][1] ^= 1;
    match run(&b, "gamma-broken") {
        Verdict::Failed(m) => assert!(m.starts_with("1 of "), "{m}"),
        v => panic!("a broken vector passed: {v:?}"),
    }
    // A broken expected overflow flag fails too.
    let mut b = hdl::vectors("accumulate", &sc, &hw("linear12", |_| {})).expect("bench");
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
    let e = hdl::vectors("raster", &sc, &hw("linear12", |_| {})).unwrap_err();
    assert!(e.to_string().contains("gamma, accumulate"), "{e}");
    let e = hdl::vectors("logdomain", &sc, &hw("linear12", |_| {})).unwrap_err();
    assert!(e.to_string().contains("coding.kind"), "{e}");
}

#[test]
fn params_file_carries_the_widths() {
    let sc = small_scene();
    let b = hdl::vectors("gamma", &sc, &hw("linear8", |_| {})).expect("bench");
    let p = b.params_vh();
    assert!(p.contains("`define P_ACC_BITS 8\n"), "{p}");
    assert!(p.contains(&format!("`define N_VECTORS {}\n", b.vectors.len())));
    assert_eq!(b.roms[0].1.len(), 256);
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

/// Index of the first expected-output field of a dof bench (pass, layer, pos, len, windows).
fn dof_out(b: &Bench) -> usize {
    b.fields.len() - 4
}

#[test]
fn dof_row_mac_agrees_on_scene_taps_at_two_widths() {
    let sc = Scene::default_scene();
    let narrow = hdl::vectors("dof", &sc, &dof_narrow()).expect("bench");
    let default = hdl::vectors("dof", &sc, &hw("linear12", |_| {})).expect("bench");
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
    assert!(narrow.vectors.iter().any(|v| v[o + 3] < 1 << 8));
    // The default widths never saturate.
    assert!(
        default
            .vectors
            .iter()
            .all(|v| v[dof_out(&default) + 1] == 0)
    );
    if !icarus("dof") {
        return;
    }
    for (tag, b) in [("linear12", &default), ("narrow", &narrow)] {
        assert_eq!(
            run(b, &format!("dof-{tag}")),
            Verdict::Ok(b.vectors.len() as u64),
            "dof at {tag}"
        );
    }
}

#[test]
fn dof_row_mac_gates_off_line_taps_and_broken_vectors_fail() {
    if !icarus("dof broken vector") {
        return;
    }
    let sc = Scene::default_scene();
    let mut b = hdl::vectors("dof", &sc, &dof_narrow()).expect("bench");
    let (o, taps) = (dof_out(&b), (b.fields.len() - 8) / 2);
    let half = taps / 2;
    // Vectors at the left image border: their first window samples lie off the line.
    let border: Vec<usize> = (0..b.vectors.len())
        .filter(|&k| b.vectors[k][2] == 0 && b.vectors[k][3] > 1)
        .take(4)
        .collect();
    assert_eq!(border.len(), 4);
    // Off-line samples are ignored: changing them does not fail the vector.
    b.vectors[border[0]][4] ^= 1;
    b.vectors[border[0]][4 + taps] ^= 1;
    // A changed expected colour sum, overflow flag or border weight fails.
    for (k, field) in [(border[1], o), (border[2], o + 1), (border[3], o + 3)] {
        b.vectors[k][field] ^= 1;
    }
    // So does an on-line input sample whose coefficient is non-zero (the centre tap) of an
    // unsaturated output.
    let k = (0..b.vectors.len())
        .find(|&k| !border.contains(&k) && b.vectors[k][o + 1] == 0 && b.vectors[k][o] > 0)
        .expect("an unsaturated vector");
    b.vectors[k][4 + half] ^= 1 << 4;
    match run(&b, "dof-broken") {
        Verdict::Failed(m) => assert!(m.starts_with("4 of "), "{m}"),
        v => panic!("broken vectors passed: {v:?}"),
    }
}

#[test]
fn dof_row_mac_refuses_pinhole_scenes_and_wide_accumulators() {
    let e = hdl::vectors("dof", &small_scene(), &hw("linear12", |_| {})).unwrap_err();
    assert!(e.to_string().contains("camera.lens"), "{e}");
    let wide = hw("linear12", |h| h.dof.acc_bits = 72);
    let e = hdl::vectors("dof", &Scene::default_scene(), &wide).unwrap_err();
    assert!(e.to_string().contains("dof.acc_bits"), "{e}");
}
