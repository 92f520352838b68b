//! `dof.kind = "luminance"` through the pipeline and the command line (docs/dof-luminance.md):
//! work, signals, cost, the alpha ROM's pack, row tokens, both Fig. 3 scenes end to end and
//! bad `[dof.luminance]` values. Figures are printed with `--nocapture`.

mod common;

use igemu::config::{DofKind, HwConfig, LuminanceCfg};
use igemu::files::TomlFile;
use igemu::pipeline;
use igemu::scene::Scene;
use igemu::stage::dof::luminance::{ALPHA_LINES, ALPHA_ROM, BLEED_LINES, PRE_LINES};
use igemu::stage::{MemKind, RunOptions, StageId, TokenKind};
use std::collections::BTreeSet;

fn lum_hw() -> HwConfig {
    common::hw("linear12", |h| h.dof.kind = DofKind::Luminance)
}

#[test]
fn default_kind_stays_layered() {
    assert_eq!(HwConfig::default_config().dof.kind, DofKind::Layered);
    for p in igemu::config::PRESETS {
        let h = HwConfig::preset(p).unwrap();
        assert_eq!(h.dof.kind, DofKind::Layered);
        assert_eq!(h.dof.luminance, LuminanceCfg::default());
    }
}

#[test]
fn render_reports_work_signals_cost_pack_and_row_tokens() {
    let scene = Scene::default_scene();
    let r = pipeline::render(&scene, &lum_hw(), RunOptions::default()).unwrap();
    let d = r.report.stages.iter().find(|s| s.name == "dof").unwrap();
    let (w, h) = (640u64, 480u64);
    assert_eq!(d.work["pixels"], w * h);
    assert_eq!(d.work["macs"], 9 * w * h);
    assert_eq!(d.work["divides"], 2 * w * h);
    assert_eq!(d.work["rom_reads"], w * h);
    assert_eq!(d.work["pre_adds"], 4 * w * h);
    assert!(d.work["bleeding"] > 0);
    let names: Vec<&str> = d.signals.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        ["dof.lum.pre", "dof.lum.mean", "dof.lum.blur", "dof.lum.out"]
    );
    assert!(d.signals.iter().all(|s| s.overflows == 0));
    assert!(d.notes["alpha"]["band_pixels"].as_u64().unwrap() > 0);
    // Cost, exact from the formats: 12-bit codes, 4 guard bits, UQ1.10 alpha, 2^10 + 1
    // ROM entries, radius 1.
    let mem = |n: &str| d.cost.memories.iter().find(|m| m.name == n).unwrap();
    assert_eq!((mem(PRE_LINES).depth, mem(PRE_LINES).width), (2 * w, 12));
    assert_eq!(
        (mem(BLEED_LINES).depth, mem(BLEED_LINES).width),
        (2 * w, 16)
    );
    assert_eq!(
        (mem(ALPHA_LINES).depth, mem(ALPHA_LINES).width),
        (2 * w, 11)
    );
    assert_eq!((mem(ALPHA_ROM).depth, mem(ALPHA_ROM).width), (1025, 11));
    assert_eq!(d.cost.storage_bits, 2 * w * (12 + 16 + 11));
    assert_eq!(d.cost.lut_bits, 1025 * 11);
    let pack = r
        .report
        .cycles
        .cost
        .packed
        .iter()
        .find(|p| p.name == ALPHA_ROM)
        .unwrap();
    assert!(pack.verified, "{pack:?}");
    assert_eq!(pack.cost_bits, 1025 * 11);
    // One row token per screen row after accumulate's tiles, chained to gamma by a FIFO.
    let st = &r.workload.stages;
    let i = st.iter().position(|s| s.id == StageId::Dof).unwrap();
    assert_eq!(st[i].kind, TokenKind::Row);
    assert_eq!(st[i].items, vec![2 * w; h as usize]);
    assert_eq!(st[i - 1].id, StageId::Accumulate);
    assert_eq!(st[i].feeder, None);
    assert_eq!(st[i + 1].id, StageId::Gamma);
    assert_eq!(st[i + 1].feeder, Some(i));
    // Stage-local: fixed against the float method on the same frame.
    let local = d.local.as_ref().unwrap();
    assert!(local.max_abs_lsb < 2.0, "{local:?}");
    println!(
        "default scene: local max {:.3} LSB, identical {:.2} %, {} cycles per frame, dof {:.1} ms",
        local.max_abs_lsb,
        100.0 * local.identical as f64 / local.values as f64,
        r.report.cycles.total_cycles,
        d.fixed_ms
    );
}

fn write(name: &str, text: &str) -> String {
    let d = std::env::temp_dir().join(format!("igemu-lum-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

#[test]
fn command_line_renders_default_and_cone_focus_and_counts_cycles() {
    let hw = write("lum.toml", "[dof]\nkind = \"luminance\"\n");
    let out = write("o.png", "");
    for scene in ["default", "cone-focus"] {
        let (code, stdout, err) = common::igemu(&["render", scene, "--hw", &hw, "-o", &out]);
        assert_eq!(code, 0, "{err}");
        // The plan runs dof and gives the luminance method as its reason.
        let plan = stdout
            .lines()
            .find(|l| l.trim_start().starts_with("dof ") && l.contains("thin lens"))
            .unwrap_or_else(|| panic!("{stdout}"));
        let words: Vec<&str> = plan.split_whitespace().collect();
        assert_eq!(&words[..2], ["dof", "in"], "{plan}");
        assert!(plan.contains("luminance-aware blur"), "{plan}");
        assert!(
            stdout.contains("dof luminance alpha ROM 11275 bits ok"),
            "{stdout}"
        );
        let line = stdout.lines().find(|l| l.starts_with("dof ")).unwrap();
        assert!(
            line.contains("bleeding") && line.contains("rom_reads"),
            "{line}"
        );
        let (code, json, err) =
            common::igemu(&["render", scene, "--hw", &hw, "-o", &out, "--json"]);
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value = serde_json::from_str(&json).unwrap();
        let d = v["stages"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["name"] == "dof")
            .unwrap();
        assert_eq!(d["work"]["pixels"], 640 * 480);
        assert!(d["notes"]["alpha"]["max"].as_f64().unwrap() > 0.0);
    }
    let (code, stdout, err) = common::igemu(&["cycles", "default", "--hw", &hw]);
    assert_eq!(code, 0, "{err}");
    let line = stdout.lines().find(|l| l.starts_with("dof ")).unwrap();
    assert!(
        line.contains(" 480 ") && line.ends_with("pass outputs"),
        "{line}"
    );
}

#[test]
fn bad_values_are_refused_naming_the_field_and_range() {
    let cases = [
        ("radius", "9", "0..=8"),
        ("pre_bits", "7", "8..=48"),
        ("guard_bits", "17", "0..=16"),
        ("alpha_bits", "1", "2..=16"),
        ("alpha_rom_bits", "17", "2..=16"),
        ("focus_scale", "1.5", "[0.0, 1.0]"),
        ("focus_scale", "nan", "[0.0, 1.0]"),
        ("ramp", "-1.0", "[0.0, 1000.0]"),
        ("ramp", "inf", "[0.0, 1000.0]"),
    ];
    let out = write("bad.png", "");
    for (field, bad, range) in cases {
        let path = format!("dof.luminance.{field}");
        let text = format!("[dof]\nkind = \"luminance\"\n[dof.luminance]\n{field} = {bad}\n");
        // The library: the field, its line, the range; the hint names the same range.
        let e = HwConfig::from_toml(&TomlFile::from_text("h.toml", &text)).unwrap_err();
        assert_eq!(e.field, path, "{e}");
        assert_eq!(e.line, Some(4), "{e}");
        assert!(e.msg.contains(range), "{e}");
        let hint = HwConfig::field_hint(&path).unwrap();
        assert!(hint.contains(range), "{path}: {hint}");
        // The command line: exit 2 with the same.
        let hw = write(&format!("{field}.toml"), &text);
        let (code, _, err) = common::igemu(&["render", "--hw", &hw, "-o", &out]);
        assert_eq!(code, 2, "{field} = {bad}: {err}");
        assert!(err.contains(&path) && err.contains(range), "{err}");
    }
    // Wrong types and unknown fields name the field too.
    for (text, want) in [
        ("[dof.luminance]\nradius = -1\n", "dof.luminance.radius"),
        ("[dof.luminance]\nradius = \"2\"\n", "dof.luminance.radius"),
        ("[dof.luminance]\nradios = 2\n", "radios"),
    ] {
        let hw = write("t.toml", text);
        let (code, _, err) = common::igemu(&["render", "--hw", &hw, "-o", &out]);
        assert_eq!(code, 2, "{text}: {err}");
        assert!(err.contains(want), "{text}: {err}");
    }
    assert!(
        HwConfig::field_hint("dof.luminance")
            .unwrap()
            .contains("focus_scale")
    );
    assert!(HwConfig::field_hint("dof.luminance.nothing").is_none());
}

#[test]
fn every_dof_memory_with_contents_has_an_image_and_the_bits_add_up() {
    // As tests/cost.rs for the other plans: the line buffers hold transient values (no
    // image); the alpha ROM's contents are the model's, imaged, packed once and verified;
    // storage and ROM bits are the sums of the memories, also after a log-add frame.
    let transient = [PRE_LINES, BLEED_LINES, ALPHA_LINES];
    for preset in ["linear12", "log8-logadd"] {
        for scene in [
            Scene::default_scene(),
            Scene::embedded("cone-focus").unwrap(),
        ] {
            let hw = common::hw(preset, |h| h.dof.kind = DofKind::Luminance);
            let r = pipeline::render(&scene, &hw, RunOptions::FAST).unwrap();
            let s = r.steps.iter().find(|s| s.id == StageId::Dof).unwrap();
            let (o, cost) = (&s.outcome, &s.outcome.report.cost);
            let held: BTreeSet<&str> = cost
                .memories
                .iter()
                .map(|m| m.name.as_str())
                .filter(|n| !transient.contains(n))
                .collect();
            let imaged: BTreeSet<&str> = o.images.iter().map(|i| i.name.as_str()).collect();
            assert_eq!(imaged, held, "{preset} {}", scene.name);
            assert_eq!(o.images.len(), held.len());
            assert!(imaged.contains(ALPHA_ROM));
            assert_eq!(
                imaged.contains("dof potentiation LUT"),
                preset == "log8-logadd"
            );
            assert_eq!(o.packs.len(), o.images.len());
            assert!(o.packs.iter().all(|p| p.verified), "{:?}", o.packs);
            let sum = |k: MemKind| {
                cost.memories
                    .iter()
                    .filter(|m| m.kind == k)
                    .map(|m| m.bits())
                    .sum::<u64>()
            };
            assert_eq!(cost.storage_bits, sum(MemKind::Ram));
            assert_eq!(cost.lut_bits, sum(MemKind::Rom));
            for (im, p) in o.images.iter().zip(&o.packs) {
                let m = cost.memories.iter().find(|m| m.name == im.name).unwrap();
                assert_eq!(im.fields.iter().sum::<u32>(), m.width, "{}", im.name);
                assert_eq!((im.words as u64, p.cost_bits), (m.depth, m.bits()));
            }
        }
    }
}
