//! The cost model and the pack check (docs/reference.md §7b):
//!
//! * for seven plans (default thin lens on linear12 and on log8-logadd, whose DoF potentiates
//!   the log frame through a LUT; the pinhole default with log8-logadd and
//!   with log8-potentiate; a Bayer dither after the LUT, one before it, Floyd-Steinberg)
//!   every packed memory is verified and the packed set names exactly the memories the plan
//!   uses, in particular the gamma LUT it really builds;
//! * every memory of every stage's cost whose contents the model holds has an image of the
//!   same name (only line buffers of transient values have none), every image is packed
//!   once, and each stage's `storage_bits` and `lut_bits` are the sums of its RAMs and ROMs;
//! * the pack check fails on an entry that does not fit its field (naming the word), on a
//!   word one bit wider than the cost's, on a wrong depth and on an unknown name, and passes
//!   the real image;
//! * `igemu render --rom-out DIR` writes `manifest.json` (stage, name, kind, width, depth,
//!   fields, words, file) and `$readmemh` files of `words` lines of `ceil(width / 4)` hex
//!   digits that decode to the entries of the library render's images.

mod common;

use common::{Rng, hw};
use igemu::config::{DitherKind, HwConfig, Placement};
use igemu::cost::pack;
use igemu::pipeline::{Render, render};
use igemu::scene::Scene;
use igemu::stage::{MemImage, MemKind, RunOptions, StageId};
use std::collections::BTreeSet;
use std::sync::{Arc, OnceLock};

/// Memories whose contents are transient values the model does not keep.
const TRANSIENT: [&str; 3] = [
    "dof line buffers",
    "dof composite buffer",
    "dither error line buffer",
];

/// A memory of a stage, by name.
type Named = (StageId, &'static str);

/// A plan: its name, the scene, the hardware and the (stage, memory) images it must have.
struct Case {
    name: &'static str,
    render: Render,
    images: Vec<Named>,
}

fn dither(kind: DitherKind, placement: Placement) -> HwConfig {
    hw("linear12", |h| {
        h.dither.kind = kind;
        h.dither.placement = placement;
    })
}

/// The seven plans, rendered once.
fn cases() -> &'static [Case] {
    static CASES: OnceLock<Vec<Case>> = OnceLock::new();
    CASES.get_or_init(|| {
        use StageId::*;
        let pinhole = Scene::embedded("default-pinhole").unwrap();
        let linear = [
            (Visibility, "sample buffer"),
            (Accumulate, "frame memory"),
            (Accumulate, "filter weight ROM"),
        ];
        let with = |extra: &[Named]| {
            let mut v = linear.to_vec();
            v.extend_from_slice(extra);
            v
        };
        let mask = (Dither, "dither mask ROM");
        let plans: Vec<(&'static str, Scene, HwConfig, Vec<Named>)> = vec![
            (
                "default thin lens linear12",
                Scene::default_scene(),
                HwConfig::default_config(),
                with(&[
                    (Dof, "dof coefficient ROM"),
                    (Dof, "dof sigma ROM"),
                    (Gamma, "gamma ROM"),
                ]),
            ),
            (
                "default thin lens log8-logadd",
                Scene::default_scene(),
                HwConfig::preset("log8-logadd").unwrap(),
                vec![
                    (Logdomain, "log encoder threshold ROM"),
                    (Logdomain, "sample buffer"),
                    (Accumulate, "frame memory"),
                    (Accumulate, "log weight ROM"),
                    (Accumulate, "sb table"),
                    (Dof, "dof coefficient ROM"),
                    (Dof, "dof sigma ROM"),
                    (Dof, "dof potentiation LUT"),
                    (Gamma, "gamma ROM"),
                ],
            ),
            (
                "pinhole log8-logadd",
                pinhole.clone(),
                HwConfig::preset("log8-logadd").unwrap(),
                vec![
                    (Logdomain, "log encoder threshold ROM"),
                    (Logdomain, "sample buffer"),
                    (Accumulate, "frame memory"),
                    (Accumulate, "log weight ROM"),
                    (Accumulate, "sb table"),
                    (Gamma, "gamma ROM (eq. 15, log input)"),
                ],
            ),
            (
                "pinhole log8-potentiate",
                pinhole.clone(),
                HwConfig::preset("log8-potentiate").unwrap(),
                vec![
                    (Logdomain, "log encoder threshold ROM"),
                    (Logdomain, "potentiation LUT"),
                    (Logdomain, "sample buffer"),
                    (Accumulate, "frame memory"),
                    (Accumulate, "filter weight ROM"),
                    (Gamma, "gamma ROM"),
                ],
            ),
            (
                "bayer4 after the LUT",
                pinhole.clone(),
                dither(DitherKind::Bayer4, Placement::AfterLut),
                with(&[(Gamma, "gamma ROM (extended output)"), mask]),
            ),
            (
                "bayer4 before the LUT",
                pinhole.clone(),
                dither(DitherKind::Bayer4, Placement::BeforeLut),
                with(&[mask, (Gamma, "gamma ROM (reduced address)")]),
            ),
            (
                "floyd-steinberg",
                pinhole,
                dither(DitherKind::FloydSteinberg, Placement::AfterLut),
                with(&[(Gamma, "gamma ROM (extended output)")]),
            ),
        ];
        plans
            .into_iter()
            .map(|(name, scene, hw, images)| Case {
                name,
                render: render(&scene, &hw, RunOptions::FAST)
                    .unwrap_or_else(|e| panic!("{name}: {e}")),
                images,
            })
            .collect()
    })
}

#[test]
fn every_packed_memory_is_verified_and_names_the_lut_the_plan_uses() {
    for c in cases() {
        let mut got: Vec<(StageId, String)> = Vec::new();
        for s in &c.render.steps {
            for p in &s.outcome.packs {
                assert!(p.verified, "{}: {:?} {p:?}", c.name, s.id);
                assert!(
                    p.problem.is_none() && p.bits == p.cost_bits && p.bits > 0,
                    "{p:?}"
                );
                got.push((s.id, p.name.clone()));
            }
        }
        let want: Vec<(StageId, String)> =
            c.images.iter().map(|(s, n)| (*s, n.to_string())).collect();
        assert_eq!(got, want, "{}", c.name);
        // The report's summary lists the same checks.
        let summary: Vec<&str> = c
            .render
            .report
            .cycles
            .cost
            .packed
            .iter()
            .map(|p| p.name.as_str())
            .collect();
        let names: Vec<&str> = c.images.iter().map(|(_, n)| *n).collect();
        assert_eq!(summary, names, "{}", c.name);
    }
}

#[test]
fn every_memory_with_contents_has_an_image_and_the_bits_add_up() {
    for c in cases() {
        let (mut ram, mut rom) = (0u64, 0u64);
        for s in &c.render.steps {
            let (o, cost) = (&s.outcome, &s.outcome.report.cost);
            let held: BTreeSet<&str> = cost
                .memories
                .iter()
                .map(|m| m.name.as_str())
                .filter(|n| !TRANSIENT.contains(n))
                .collect();
            let imaged: Vec<&str> = o.images.iter().map(|i| i.name.as_str()).collect();
            assert_eq!(
                imaged.len(),
                held.len(),
                "{} {:?}: {imaged:?}",
                c.name,
                s.id
            );
            assert_eq!(
                imaged.iter().copied().collect::<BTreeSet<_>>(),
                held,
                "{} {:?}",
                c.name,
                s.id
            );
            assert_eq!(o.packs.len(), o.images.len());
            let sum = |k: MemKind| {
                cost.memories
                    .iter()
                    .filter(|m| m.kind == k)
                    .map(|m| m.depth * m.width as u64)
                    .sum::<u64>()
            };
            assert_eq!(
                cost.storage_bits,
                sum(MemKind::Ram),
                "{} {:?}",
                c.name,
                s.id
            );
            assert_eq!(cost.lut_bits, sum(MemKind::Rom), "{} {:?}", c.name, s.id);
            ram += cost.storage_bits;
            rom += cost.lut_bits;
            for (im, p) in o.images.iter().zip(&o.packs) {
                let m = cost.memories.iter().find(|m| m.name == im.name).unwrap();
                assert_eq!(im.fields.iter().sum::<u32>(), m.width, "{}", im.name);
                if im.region_only {
                    assert!(im.words as u64 <= m.depth);
                    assert_eq!(p.cost_bits, im.words as u64 * m.width as u64);
                } else {
                    assert_eq!(
                        (im.words as u64, p.cost_bits),
                        (m.depth, m.bits()),
                        "{}",
                        im.name
                    );
                }
            }
        }
        let k = &c.render.report.cycles.cost;
        // The streamed DoF's line buffers are the cycle model's, not a stage's memory.
        let lines = k.storage_bits.get(igemu::cost::LINE_BUFFERS).copied();
        assert_eq!(lines.unwrap_or(0), k.line_buffer_bits, "{}", c.name);
        assert_eq!(
            (k.total_storage_bits - k.line_buffer_bits, k.total_rom_bits),
            (ram, rom),
            "{}",
            c.name
        );
        // The report's storage total (the sweep's cost axis) holds them too.
        assert_eq!(
            c.render.report.storage_bits, k.total_storage_bits,
            "{}",
            c.name
        );
    }
    // The transient memories are really in the plans that have them.
    let all: BTreeSet<&str> = cases()
        .iter()
        .flat_map(|c| {
            c.render.steps.iter().flat_map(|s| {
                s.outcome
                    .report
                    .cost
                    .memories
                    .iter()
                    .map(|m| m.name.as_str())
            })
        })
        .collect();
    assert!(TRANSIENT.iter().all(|t| all.contains(t)), "{all:?}");
}

/// A copy of `im` whose field `k` of word `w` reads `v`.
fn with_entry(im: &MemImage, w: usize, k: usize, v: u64) -> MemImage {
    let get = im.get.clone();
    MemImage {
        get: Arc::new(move |r, f| if (r, f) == (w, k) { v } else { get(r, f) }),
        ..im.clone()
    }
}

#[test]
fn a_corrupted_entry_width_depth_or_name_fails_the_pack_check() {
    let mut rng = Rng::new(11);
    let mut checked = 0;
    for c in cases() {
        for s in &c.render.steps {
            let cost = &s.outcome.report.cost;
            for im in &s.outcome.images {
                let ok = &pack::check(cost, std::slice::from_ref(im))[0];
                assert!(ok.verified, "{ok:?}");
                // One entry that does not fit its field.
                let w = (rng.next_u64() % im.words as u64) as usize;
                let k = (rng.next_u64() % im.fields.len() as u64) as usize;
                let f = im.fields[k];
                let bad = with_entry(im, w, k, (1u64 << f) | (im.get)(w, k));
                let p = &pack::check(cost, &[bad])[0];
                assert!(!p.verified, "{}: {p:?}", im.name);
                let problem = p.problem.clone().unwrap();
                assert!(
                    problem.contains(&format!("word {w} field {k}")),
                    "{problem}"
                );
                // A word one bit wider than the cost's.
                let mut wide = im.clone();
                *wide.fields.last_mut().unwrap() += 1;
                let p = &pack::check(cost, &[wide])[0];
                assert!(!p.verified, "{}: {p:?}", im.name);
                let width = im.fields.iter().sum::<u32>();
                let want = format!(
                    "fields sum to {} bits but the cost charges {width}-bit words",
                    width + 1
                );
                assert!(p.problem.as_ref().unwrap().contains(&want), "{p:?}");
                // A wrong depth: one word short of a ROM, one past a region image's memory.
                let depth = cost
                    .memories
                    .iter()
                    .find(|m| m.name == im.name)
                    .unwrap()
                    .depth as usize;
                let words = if im.region_only {
                    depth + 1
                } else {
                    im.words - 1
                };
                let short = MemImage {
                    words,
                    ..im.clone()
                };
                let p = &pack::check(cost, &[short])[0];
                assert!(!p.verified, "{}: {p:?}", im.name);
                assert!(
                    p.problem
                        .as_ref()
                        .unwrap()
                        .contains(&format!("{words} words but the cost charges")),
                    "{p:?}"
                );
                // A name the stage's cost does not have.
                let stranger = MemImage {
                    name: format!("{} (spare)", im.name),
                    ..im.clone()
                };
                assert!(!pack::check(cost, &[stranger])[0].verified);
                checked += 1;
            }
        }
    }
    assert_eq!(
        checked,
        cases().iter().map(|c| c.images.len()).sum::<usize>()
    );
    // The packer itself refuses a bit vector of the wrong size.
    let c = &cases()[0];
    let g = c
        .render
        .steps
        .iter()
        .find(|s| s.id == StageId::Gamma)
        .unwrap();
    let im = &g.outcome.images[0];
    assert_eq!(pack::pack(im, 4096 * 8), Ok(4096 * 8));
    assert!(pack::pack(im, 4096 * 8 + 1).is_err());
}

fn tmp_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("igemu-cost-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `igemu render SCENE --hw HW --rom-out DIR` and checks the files against `r`.
fn rom_out_matches(scene: &str, hw_arg: &str, r: &Render, tag: &str) -> BTreeSet<String> {
    let dir = tmp_dir(tag);
    let roms = dir.join("roms");
    let png = dir.join("out.png");
    let args = [
        "render",
        scene,
        "--hw",
        hw_arg,
        "--no-local",
        "-o",
        png.to_str().unwrap(),
        "--rom-out",
        roms.to_str().unwrap(),
    ];
    let (code, _, err) = common::igemu(&args);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(roms.join("manifest.json")).unwrap();
    let m: serde_json::Value = serde_json::from_str(&text).unwrap();
    let entries = m["memories"].as_array().unwrap();
    let images: Vec<(StageId, &MemImage, &igemu::stage::Cost)> = r
        .steps
        .iter()
        .flat_map(|s| {
            s.outcome
                .images
                .iter()
                .map(move |im| (s.id, im, &s.outcome.report.cost))
        })
        .collect();
    assert_eq!(entries.len(), images.len(), "{text}");
    let mut written = BTreeSet::new();
    for (e, (stage, im, cost)) in entries.iter().zip(images) {
        let mem = cost.memories.iter().find(|m| m.name == im.name).unwrap();
        let kind = if mem.kind == MemKind::Rom {
            "rom"
        } else {
            "ram"
        };
        let width: u32 = im.fields.iter().sum();
        let fields: Vec<u64> = im.fields.iter().map(|&f| f as u64).collect();
        assert_eq!(e["stage"], stage.name(), "{e}");
        assert_eq!(e["name"], im.name.as_str());
        assert_eq!(e["kind"], kind);
        assert_eq!(e["width"].as_u64(), Some(width as u64));
        assert_eq!(e["depth"].as_u64(), Some(mem.depth));
        assert_eq!(e["words"].as_u64(), Some(im.words as u64));
        let got_fields: Vec<u64> = e["fields"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .collect();
        assert_eq!(got_fields, fields);
        let Some(file) = e["file"].as_str() else {
            // Only a RAM image over the size limit is listed without a file.
            assert!(
                kind == "ram" && im.words > igemu::cost::rom::MAX_RAM_WORDS,
                "{e}"
            );
            continue;
        };
        let hex = std::fs::read_to_string(roms.join(file)).unwrap();
        let digits = width.div_ceil(4) as usize;
        let lines: Vec<&str> = hex.lines().collect();
        assert_eq!(lines.len(), im.words, "{file}");
        for (w, line) in lines.iter().enumerate() {
            assert_eq!(line.len(), digits, "{file} line {w}: `{line}`");
            let mut word = u128::from_str_radix(line, 16).unwrap();
            for (k, &f) in im.fields.iter().enumerate() {
                assert_eq!(
                    (word & ((1u128 << f) - 1)) as u64,
                    (im.get)(w, k),
                    "{file} word {w} field {k}"
                );
                word >>= f;
            }
            assert_eq!(word, 0, "{file} word {w}: bits above the width");
        }
        written.insert(im.name.clone());
    }
    let _ = std::fs::remove_dir_all(&dir);
    written
}

#[test]
fn rom_out_writes_the_images_of_the_library_render() {
    // The default plan: gamma ROM, frame memory, filter weights, dof coefficients and the
    // sigma ROM; the sample buffer is over the size limit and listed only.
    let written = rom_out_matches("default", "linear12", &cases()[0].render, "default");
    for name in [
        "gamma ROM",
        "frame memory",
        "filter weight ROM",
        "dof coefficient ROM",
        "dof sigma ROM",
    ] {
        assert!(written.contains(name), "{written:?}");
    }
    assert!(!written.contains("sample buffer"));
    // A hardware file with a dither after the LUT: the 12-bit extended gamma ROM (3 digits).
    let dir = tmp_dir("hw");
    let hw_file = dir.join("bayer4.toml");
    std::fs::write(&hw_file, "[dither]\nkind = \"bayer4\"\n").unwrap();
    let written = rom_out_matches(
        "default-pinhole",
        hw_file.to_str().unwrap(),
        &cases()[4].render,
        "bayer4",
    );
    for name in [
        "gamma ROM (extended output)",
        "dither mask ROM",
        "frame memory",
    ] {
        assert!(written.contains(name), "{written:?}");
    }
    // The log-add plan: eq. 15 LUT, log weight ROM, sb table, log frame memory.
    let written = rom_out_matches(
        "default-pinhole",
        "log8-logadd",
        &cases()[2].render,
        "logadd",
    );
    for name in [
        "gamma ROM (eq. 15, log input)",
        "sb table",
        "log weight ROM",
        "frame memory",
    ] {
        assert!(written.contains(name), "{written:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
