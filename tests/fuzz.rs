//! Fuzzing in `cargo test`: the scene, hardware and grid parsers on randomly mutated files,
//! and the whole pipeline on small random scenes under random hardware. The properties:
//! nothing panics; a file is accepted or refused with an error that names the file and a
//! field (or a line); every accepted configuration renders or is refused with an error
//! (never a panic), within a time bound.
//!
//! The number of cases is bounded for CI; a longer run (docs/reliability.md):
//! `PROPTEST_CASES=20000 cargo test --release --test fuzz`.

mod common;

use common::Rng;
use igemu::config::HwConfig;
use igemu::files::TomlFile;
use igemu::scene::Scene;
use igemu::stage::RunOptions;
use proptest::prelude::*;
use std::panic::{AssertUnwindSafe, catch_unwind};
use toml::Value;

/// Every field a hardware file can set.
const HW: &str = r#"
preset = "linear12"
[input]
coord = "Q13.4"
z = "UQ0.24"
intensity = "UQ12.4"
quant = "RND_CONV"
overflow = "SAT"
[raster]
samples = 4
interp_guard_bits = 14
interp_quant = "RND_CONV"
guard_band = 64
[visibility]
z = "UQ0.24"
quant = "TRN"
[accumulate]
filter = "tent"
weight_bits = 10
gaussian_sigma = 0.5
frame = "UQ12.0"
quant = "RND_CONV"
overflow = "SAT"
[gamma]
dac_bits = 8
quant = "RND_CONV"
gamma = 2.4
correction = true
[cycles]
clock_mhz = 100.0
tile = 16
frame_port_bits = 48
[cycles.raster]
lanes = 4
latency = 4
ii = 1
fifo = 64
[dither]
kind = "bayer4"
placement = "after_lut"
frac_bits = 4
serpentine = true
error = "Q2.8"
blue_noise_size = 16
seed = 1
temporal = false
frame = 0
[dof]
p = 0.1
k = 0.05
coef_bits = 12
alpha_bits = 12
guard_bits = 4
line_bits = 28
acc_bits = 40
max_half_size = 32
quant = "RND_CONV"
overflow = "SAT"
[coding]
kind = "linear"
log_bits = 8
acc_frac_bits = 2
table_addr_bits = 10
table_frac_bits = 0
interpolate = false
"#;

/// A small scene with every object kind.
const SMALL: &str = r#"
name = "small"
[image]
width = 48
height = 32
background = 0.1
[camera]
position = [0.0, 0.0, 10.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y_deg = 40.0
near = 1.0
far = 100.0
[camera.lens]
kind = "thin_lens"
focal_length = 0.02
lens_radius = 0.01
focus_distance = 10.0
deep = 0.5
coc = 0.000035
[display]
contrast = 100.0
gamma = 2.4
weber = 0.02
b_max = 100.0
[[light]]
direction = [0.0, 0.0, 1.0]
intensity = 1.0
[[object]]
kind = "sphere"
center = [0.0, 0.0, 0.0]
radius = 1.0
tessellation = 6
[[object]]
kind = "torus"
center = [1.0, 1.0, -2.0]
axis = [0.0, 1.0, 0.0]
major_radius = 1.0
minor_radius = 0.3
tessellation = 6
[[object]]
kind = "cone"
base = [-1.0, -1.0, 1.0]
axis = [0.0, 1.0, 0.0]
radius = 0.5
tessellation = 5
capped = true
[[object]]
kind = "cylinder"
base = [2.0, -1.0, 0.0]
axis = [0.0, 1.0, 0.0]
radius = 0.3
tessellation = 5
[[object]]
kind = "triangle"
space = "screen"
vertices = [[1.0, 1.0, 0.2], [30.0, 4.0, 0.5], [6.0, 28.0, 0.9]]
intensity = [0.1, 0.9, 0.5]
[[object]]
kind = "quad"
space = "screen"
vertices = [[30.0, 20.0, 0.3], [46.0, 20.0, 0.3], [46.0, 31.0, 0.3], [30.0, 31.0, 0.3]]
intensity = [0.5, 0.5, 0.5, 0.5]
[[object]]
kind = "line"
space = "screen"
from = [2.0, 30.0, 0.1]
to = [45.0, 2.0, 0.1]
intensity = 0.8
width = 1.5
[[object]]
kind = "light_point"
space = "screen"
position = [24.0, 16.0, 0.05]
intensity = 1.0
size = 1.0
"#;

const GRID: &str = r#"
preset = ["linear12", "linear11"]
accumulate.frame = ["UQ11.0", "UQ12.0"]
gamma.dac_bits = [8, 9]
dither.kind = ["none", "bayer4"]
"#;

/// Replacement values: extremes, wrong types, wrong shapes.
fn wild(rng: &mut Rng) -> Value {
    let f = [
        0.0,
        -1.0,
        1e308,
        -1e308,
        1e-308,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        0.5,
        1e8,
        65536.0,
    ];
    let i = [0i64, -1, 1, 3, 7, 64, 65536, i64::MAX, i64::MIN, 1 << 40];
    match rng.next_u64() % 9 {
        0 | 1 => Value::Float(f[(rng.next_u64() % f.len() as u64) as usize]),
        2 | 3 => Value::Integer(i[(rng.next_u64() % i.len() as u64) as usize]),
        4 => Value::String(
            ["", "junk", "UQ99.0", "Q0.0", "RND", "64"][(rng.next_u64() % 6) as usize].into(),
        ),
        5 => Value::Boolean(rng.next_u64().is_multiple_of(2)),
        6 => Value::Array(
            (0..rng.next_u64() % 6)
                .map(|_| Value::Float(f[(rng.next_u64() % f.len() as u64) as usize]))
                .collect(),
        ),
        7 => Value::Array(vec![Value::Float(0.0), Value::String("junk".into())]),
        _ => Value::Table(toml::Table::new()),
    }
}

/// All value paths of a table (tables and arrays of tables walked).
fn paths(v: &Value, at: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    match v {
        Value::Table(t) => {
            for (k, x) in t {
                at.push(k.clone());
                out.push(at.clone());
                paths(x, at, out);
                at.pop();
            }
        }
        Value::Array(a) => {
            for (k, x) in a.iter().enumerate() {
                at.push(format!("#{k}"));
                out.push(at.clone());
                paths(x, at, out);
                at.pop();
            }
        }
        _ => {}
    }
}

fn slot<'a>(v: &'a mut Value, path: &[String]) -> Option<&'a mut Value> {
    let mut cur = v;
    for p in path {
        cur = match (cur, p.strip_prefix('#')) {
            (Value::Array(a), Some(k)) => a.get_mut(k.parse::<usize>().ok()?)?,
            (Value::Table(t), None) => t.get_mut(p)?,
            _ => return None,
        };
    }
    Some(cur)
}

/// A mutated TOML text: values replaced, keys removed or added, lines duplicated, the text
/// truncated.
fn mutate(text: &str, rng: &mut Rng) -> String {
    let mut v: Value = Value::Table(toml::from_str(text).expect("the template parses"));
    let mut all = Vec::new();
    paths(&v, &mut Vec::new(), &mut all);
    for _ in 0..1 + rng.next_u64() % 3 {
        let p = &all[(rng.next_u64() % all.len() as u64) as usize];
        match rng.next_u64() % 4 {
            0 | 1 => {
                if let Some(s) = slot(&mut v, p) {
                    *s = wild(rng);
                }
            }
            2 => {
                if let Some((last, parent)) = p.split_last()
                    && let Some(Value::Table(t)) = slot(&mut v, parent)
                {
                    t.remove(last);
                }
            }
            _ => {
                if let Some(Value::Table(t)) = slot(&mut v, &p[..p.len() - 1]) {
                    t.insert("unknown_field".into(), wild(rng));
                }
            }
        }
    }
    let mut out = toml::to_string(&v).unwrap_or_default();
    match rng.next_u64() % 6 {
        0 => {
            // Duplicate a line (a duplicate key, or a duplicate table header).
            let lines: Vec<&str> = out.lines().collect();
            if !lines.is_empty() {
                let k = (rng.next_u64() % lines.len() as u64) as usize;
                let mut l: Vec<&str> = lines.clone();
                l.insert(k, lines[k]);
                out = l.join("\n");
            }
        }
        1 => {
            let cut = (rng.next_u64() % (out.len() as u64 + 1)) as usize;
            out = out.chars().take(cut).collect();
        }
        _ => {}
    }
    out
}

/// The error names the file and a field or a line.
fn names_the_field(e: &igemu::error::FileError, file: &str) -> bool {
    // A grid cut down to nothing has no field to name: its message says what to write.
    let whole_file = e.msg.contains("names no field; give e.g.");
    e.file == file && (!e.field.is_empty() || e.line.is_some() || whole_file)
}

fn cases(default: u32) -> ProptestConfig {
    let n = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default);
    ProptestConfig::with_cases(n)
}

proptest! {
    #![proptest_config(cases(300))]

    #[test]
    fn mutated_scene_files_are_accepted_or_refused_naming_the_field(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        for template in [SMALL, include_str!("../src/scene/default.toml")] {
            let text = mutate(template, &mut rng);
            let r = catch_unwind(|| Scene::from_toml(&TomlFile::from_text("fuzz.toml", &text)));
            let r = r.unwrap_or_else(|_| panic!("scene parser panicked on:\n{text}"));
            if let Err(e) = r {
                prop_assert!(names_the_field(&e, "fuzz.toml"), "{e}\n{text}");
            }
        }
    }

    #[test]
    fn mutated_hardware_files_are_accepted_or_refused_naming_the_field(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        let text = mutate(HW, &mut rng);
        let r = catch_unwind(|| HwConfig::from_toml(&TomlFile::from_text("hw.toml", &text)));
        let r = r.unwrap_or_else(|_| panic!("hardware parser panicked on:\n{text}"));
        if let Err(e) = r {
            prop_assert!(names_the_field(&e, "hw.toml"), "{e}\n{text}");
        }
    }

    #[test]
    fn mutated_grids_are_accepted_or_refused_naming_the_field(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        let text = mutate(GRID, &mut rng);
        let file = TomlFile::from_text("grid.toml", &text);
        let r = catch_unwind(AssertUnwindSafe(|| {
            igemu::sweep::grid::Grid::parse(&file).and_then(|g| g.expand(&file))
        }));
        let r = r.unwrap_or_else(|_| panic!("grid parser panicked on:\n{text}"));
        if let Err(e) = r {
            prop_assert!(names_the_field(&e, "grid.toml"), "{e}\n{text}");
        }
    }
}

/// A random hardware configuration: every overlay field drawn from (slightly beyond) its
/// range, as a hardware file text.
fn random_hw(rng: &mut Rng) -> String {
    let mut pick = |xs: &[&str]| xs[(rng.next_u64() % xs.len() as u64) as usize].to_string();
    let quants = [
        "TRN",
        "TRN_ZERO",
        "RND",
        "RND_ZERO",
        "RND_INF",
        "RND_MIN_INF",
        "RND_CONV",
    ];
    let preset = pick(&[
        "linear12",
        "linear11",
        "linear8",
        "log8-potentiate",
        "log8-logadd",
        "log7-logadd",
    ]);
    let samples = pick(&["1", "2", "4", "8"]);
    let coord = pick(&["Q13.4", "Q12.4", "Q14.5", "Q11.3"]);
    let filter = pick(&["box", "tent", "gaussian"]);
    let weight_bits = pick(&["6", "8", "10", "12", "16"]);
    let frame = pick(&["UQ8.0", "UQ10.0", "UQ11.0", "UQ12.0", "UQ12.2", "UQ14.0"]);
    let overflow = pick(&["SAT", "WRAP", "SAT_ZERO", "SAT_SYM"]);
    let q1 = pick(&quants);
    let q2 = pick(&quants);
    let dac = pick(&["1", "4", "6", "8", "9", "10", "12", "16"]);
    let dither = pick(&[
        "none",
        "bayer2",
        "bayer4",
        "bayer8",
        "blue_noise",
        "floyd_steinberg",
    ]);
    let placement = pick(&["after_lut", "before_lut"]);
    let frac = pick(&["1", "2", "3", "4"]);
    let p = pick(&["0.02", "0.1", "0.3", "0.9"]);
    let coef = pick(&["4", "8", "12", "20"]);
    let kind = pick(&["layered", "luminance", "downsample"]);
    let sigma = pick(&["paper", "affine"]);
    let rom_bits = pick(&["4", "6", "10", "16"]);
    let tile = pick(&["4", "8", "16", "64", "256"]);
    let guard = pick(&["0", "1", "8", "64"]);
    format!(
        "preset = \"{preset}\"\n[raster]\nsamples = {samples}\nguard_band = {guard}\n[input]\ncoord = \"{coord}\"\nquant = \"{q1}\"\n\
         [accumulate]\nfilter = \"{filter}\"\nweight_bits = {weight_bits}\nframe = \"{frame}\"\nquant = \"{q2}\"\noverflow = \"{overflow}\"\n\
         [gamma]\ndac_bits = {dac}\n[dither]\nkind = \"{dither}\"\nplacement = \"{placement}\"\nfrac_bits = {frac}\n\
         [dof]\nkind = \"{kind}\"\nsigma = \"{sigma}\"\nsigma_rom_bits = {rom_bits}\np = {p}\ncoef_bits = {coef}\n[cycles]\ntile = {tile}\n"
    )
}

/// A small random scene: triangles, a line, light points; pinhole or a thin lens.
fn random_scene(rng: &mut Rng) -> String {
    let (w, h) = (8 + rng.next_u64() % 56, 8 + rng.next_u64() % 40);
    let mut objs = String::new();
    for _ in 0..rng.next_u64() % 5 {
        let v: Vec<[f64; 3]> = (0..3)
            .map(|_| {
                [
                    rng.range(-20.0, w as f64 + 20.0),
                    rng.range(-20.0, h as f64 + 20.0),
                    rng.range(0.0, 0.999),
                ]
            })
            .collect();
        objs += &common::tri([v[0], v[1], v[2]], [0, 1, 2].map(|_| rng.range(0.0, 1.0)));
    }
    if rng.next_u64().is_multiple_of(2) {
        objs += &common::line(
            [rng.range(0.0, w as f64), rng.range(0.0, h as f64), 0.3],
            [rng.range(0.0, w as f64), rng.range(0.0, h as f64), 0.3],
            rng.range(0.0, 1.0),
            rng.range(0.1, 4.0),
        );
    }
    for _ in 0..rng.next_u64() % 3 {
        objs += &common::point(
            rng.range(0.0, w as f64),
            rng.range(0.0, h as f64),
            rng.range(0.0, 0.9),
            1.0,
            rng.range(0.1, 3.0),
        );
    }
    let lens = if rng.next_u64().is_multiple_of(2) {
        "[camera.lens]\nkind = \"thin_lens\"\nfocal_length = 0.02\nlens_radius = 0.02\nfocus_distance = 10.0\ndeep = 0.2\ncoc = 0.000035\n\n"
    } else {
        ""
    };
    format!(
        "[image]\nwidth = {w}\nheight = {h}\nbackground = {}\n\n\
         [camera]\nposition = [0.0, 0.0, 10.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nfov_y_deg = 40.0\nnear = 1.0\nfar = 100.0\n\n{lens}\
         [display]\ncontrast = 100.0\ngamma = 2.4\nweber = 0.02\nb_max = 100.0\n\n{objs}",
        rng.range(0.0, 1.0)
    )
}

proptest! {
    #![proptest_config(cases(60))]

    /// Any hardware the parser accepts renders any small scene or is refused with an error:
    /// no panic, within a time bound.
    #[test]
    fn the_pipeline_never_panics_on_random_scenes_and_hardware(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        let hw_text = random_hw(&mut rng);
        let scene_text = random_scene(&mut rng);
        let Ok(hw) = HwConfig::from_toml(&TomlFile::from_text("hw.toml", &hw_text)) else {
            return Ok(());
        };
        let scene = Scene::from_toml(&TomlFile::from_text("s.toml", &scene_text))
            .unwrap_or_else(|e| panic!("{e}\n{scene_text}"));
        let t = std::time::Instant::now();
        let r = catch_unwind(AssertUnwindSafe(|| {
            igemu::pipeline::render(&scene, &hw, RunOptions::default())
        }));
        prop_assert!(r.is_ok(), "the pipeline panicked on\n{hw_text}\n{scene_text}");
        prop_assert!(t.elapsed().as_secs_f64() < 30.0, "too slow:\n{hw_text}\n{scene_text}");
        if let Ok(Ok(r)) = r {
            prop_assert!(r.report.cycles.cost.packed.iter().all(|p| p.verified),
                "{:?}\n{hw_text}", r.report.cycles.cost.packed);
        }
    }
}
