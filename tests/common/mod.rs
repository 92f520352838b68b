//! Shared helpers of the integration tests: scenes built from TOML text, seeded randomness,
//! a synthetic lens.
#![allow(dead_code)]

pub mod reports;
pub mod sim;
pub mod sims;

use igemu::config::HwConfig;
use igemu::files::TomlFile;
use igemu::scene::Scene;

/// The TOML text of a scene with a pinhole camera and the given `[[object]]` blocks.
pub fn scene_toml(width: u32, height: u32, background: f64, objects: &str) -> String {
    format!(
        "[image]\nwidth = {width}\nheight = {height}\nbackground = {background}\n\n\
         [camera]\nposition = [0.0, 0.0, 10.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nfov_y_deg = 40.0\nnear = 1.0\nfar = 100.0\n\n\
         [display]\ncontrast = 100.0\ngamma = 2.4\nweber = 0.02\nb_max = 100.0\n\n{objects}"
    )
}

/// A scene with a pinhole camera and the given `[[object]]` blocks ([`scene_toml`]).
pub fn scene(width: u32, height: u32, background: f64, objects: &str) -> Scene {
    let text = scene_toml(width, height, background, objects);
    Scene::from_toml(&TomlFile::from_text("test.toml", &text))
        .unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// A screen-space triangle block.
pub fn tri(v: [[f64; 3]; 3], i: [f64; 3]) -> String {
    format!(
        "[[object]]\nkind = \"triangle\"\nspace = \"screen\"\nvertices = [[{}, {}, {}], [{}, {}, {}], [{}, {}, {}]]\nintensity = [{}, {}, {}]\n\n",
        v[0][0],
        v[0][1],
        v[0][2],
        v[1][0],
        v[1][1],
        v[1][2],
        v[2][0],
        v[2][1],
        v[2][2],
        i[0],
        i[1],
        i[2]
    )
}

/// A screen-space light point block.
pub fn point(x: f64, y: f64, z: f64, i: f64, size: f64) -> String {
    format!(
        "[[object]]\nkind = \"light_point\"\nspace = \"screen\"\nposition = [{x}, {y}, {z}]\nintensity = {i}\nsize = {size}\n\n"
    )
}

/// A screen-space line block.
pub fn line(a: [f64; 3], b: [f64; 3], i: f64, width: f64) -> String {
    format!(
        "[[object]]\nkind = \"line\"\nspace = \"screen\"\nfrom = [{}, {}, {}]\nto = [{}, {}, {}]\nintensity = {i}\nwidth = {width}\n\n",
        a[0], a[1], a[2], b[0], b[1], b[2]
    )
}

/// The `[[object]]` blocks of a random 40x30 scene: `min_tris` plus up to 11 more triangles
/// anywhere around the screen, then up to 3 light points and lines, from `rng`.
pub fn random_objects(rng: &mut Rng, min_tris: u64) -> String {
    let mut objects = String::new();
    for _ in 0..(min_tris + rng.next_u64() % 12) {
        let mut p = || {
            [
                rng.range(-40.0, 80.0),
                rng.range(-40.0, 80.0),
                rng.range(0.0, 1.0),
            ]
        };
        let (a, b, c) = (p(), p(), p());
        objects += &tri([a, b, c], [0.2, 0.9, 1.3]);
    }
    for _ in 0..(rng.next_u64() % 4) {
        let (x, y, z, i) = (
            rng.range(-5.0, 50.0),
            rng.range(-5.0, 50.0),
            rng.range(0.0, 1.0),
            rng.range(0.0, 2.0),
        );
        objects += &point(x, y, z, i, 1.0 + (rng.next_u64() % 3) as f64);
        let (a, b) = (
            [rng.range(-5.0, 50.0), rng.range(-5.0, 50.0), 0.5],
            [rng.range(-5.0, 50.0), rng.range(-5.0, 50.0), 0.5],
        );
        objects += &line(a, b, 0.7, 1.0);
    }
    objects
}

/// A preset with changes.
pub fn hw(preset: &str, f: impl FnOnce(&mut HwConfig)) -> HwConfig {
    let mut h = HwConfig::preset(preset).expect("preset");
    f(&mut h);
    h.validate().unwrap_or_else(|e| panic!("{e:?}"));
    h
}

/// The seeded generator of the tests: the library's (`rand`'s ChaCha8 from a `u64` seed).
#[allow(unused_imports)]
pub use igemu::rng::Rng;

/// The variables `--shard auto` reads: removed from every run of [`igemu_env`], so that a
/// test run inside a Slurm job or a Kubernetes pod sees only what the test sets.
pub const SHARD_VARS: &[&str] = &[
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_MIN",
    "SLURM_ARRAY_TASK_MAX",
    "SLURM_ARRAY_TASK_COUNT",
    "SLURM_ARRAY_TASK_STEP",
    "JOB_COMPLETION_INDEX",
];

/// Runs the `igemu` binary with `env` as the only shard variables: (exit code, stdout,
/// stderr).
pub fn igemu_env(args: &[&str], env: &[(&str, &str)]) -> (i32, String, String) {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_igemu"));
    c.args(args);
    for v in SHARD_VARS {
        c.env_remove(v);
    }
    c.envs(env.iter().copied());
    let o = c.output().expect("run igemu");
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into(),
        String::from_utf8_lossy(&o.stderr).into(),
    )
}

/// A fresh temporary folder `igemu-PREFIX-PID-NAME`.
pub fn tmp_dir(prefix: &str, name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("igemu-{prefix}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// Runs the `igemu` binary: (exit code, stdout, stderr).
pub fn igemu(args: &[&str]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_igemu"))
        .args(args)
        .output()
        .expect("run igemu");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// `v` rounded to an integer with the hardware rounding mode `q`, computed with the `fixed`
/// crate's own rounding functions (independent of `igemu::fixed`).
pub fn round_with(v: fixed::types::I64F64, q: igemu::fixed::Quant) -> i64 {
    use igemu::fixed::Quant;
    let tie = v.frac() == fixed::types::I64F64::from_num(0.5);
    let r = match q {
        Quant::Trn => v.floor(),
        Quant::TrnZero => v.round_to_zero(),
        _ if !tie => v.round(),
        Quant::Rnd => v.ceil(),
        Quant::RndZero => v.round_to_zero(),
        Quant::RndInf => v.round(),
        Quant::RndMinInf => v.floor(),
        Quant::RndConv => v.round_ties_even(),
    };
    r.to_num::<i64>()
}

/// The steps of a render through stage `last` (with the reports, tokens, packs and images).
pub fn steps_through(
    scene: &Scene,
    hw: &HwConfig,
    opts: igemu::stage::RunOptions,
    last: igemu::stage::StageId,
) -> Vec<igemu::pipeline::Step> {
    let plan = igemu::pipeline::plan::build(scene, hw).unwrap_or_else(|e| panic!("{e}"));
    igemu::pipeline::run::run(scene, hw, &plan, opts, None, Some(last))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// A synthetic depth-of-field lens (affine sigma, `z_frac` fraction bits in the depth
/// codes): sigma = 12 (z - 0.5) behind 0.5, 12 (z - 0.4) in front of 0.4 (pixels).
pub fn affine_lens(z_frac: u32) -> igemu::stage::dof::LensMap {
    igemu::stage::dof::LensMap {
        form: igemu::config::SigmaForm::Affine,
        k: 12.0,
        inv_focus: 0.55,
        deep: 0.0,
        inv_near: 1.0,
        inv_far: 0.0,
        rom_bits: 10,
        rom: Vec::new().into(),
        g: 12.0,
        z_far_edge: 0.5,
        z_near_edge: 0.4,
        z_inf: 1.0,
        z_frac,
        coc_px: 1.0,
    }
}

/// A small sweep in `dir` for the sweep-merge and Slurm tests: two scene files `a.toml`,
/// `b.toml` (a shaded triangle, a line and a light point on 96x64, two backgrounds) and a
/// grid `g.toml` of 4 configurations (`gamma.dac_bits` x `dither.kind`): 8 jobs. Returns
/// (the scene paths, the grid path).
pub fn small_sweep(dir: &std::path::Path) -> (Vec<String>, String) {
    let objects = [
        tri(
            [[6.0, 6.0, 0.3], [90.0, 12.0, 0.5], [24.0, 58.0, 0.7]],
            [0.05, 0.9, 0.4],
        ),
        line([3.0, 50.0, 0.2], [93.0, 30.0, 0.2], 0.7, 1.5),
        point(48.0, 20.0, 0.1, 1.0, 2.0),
    ]
    .concat();
    std::fs::create_dir_all(dir).expect("sweep dir");
    let scenes = [("a.toml", 0.02), ("b.toml", 0.1)]
        .iter()
        .map(|(name, bg)| {
            let p = dir.join(name);
            std::fs::write(&p, scene_toml(96, 64, *bg, &objects)).expect("write scene");
            p.to_string_lossy().into_owned()
        })
        .collect();
    let grid = dir.join("g.toml");
    std::fs::write(
        &grid,
        "gamma.dac_bits = [6, 8]\ndither.kind = [\"none\", \"bayer4\"]\n",
    )
    .expect("write grid");
    (scenes, grid.to_string_lossy().into_owned())
}

/// The rows of a sweep's rows file as JSON without their run state (`timing`, `reused`),
/// asserting that no line was skipped.
pub fn rows_without_timing(path: &str) -> Vec<serde_json::Value> {
    let (rows, skipped) = igemu::sweep::read_rows(path).expect("read rows");
    assert_eq!(skipped, 0, "{path} has a partial or bad line");
    rows.iter().map(igemu::sweep::without_timing).collect()
}

/// Runs `configs` on `scenes` into `out` through the library (serial, no stage reuse).
pub fn run_sweep(
    out: &str,
    configs: &[igemu::sweep::grid::Config],
    scenes: &[Scene],
    resume: bool,
) -> igemu::sweep::SweepSummary {
    let opts = igemu::sweep::SweepOptions {
        out,
        resume,
        shard: None,
        jobs: 1,
        cache: None,
        flicker: None,
        max_memory: None,
        dof_truth: None,
    };
    igemu::sweep::run(configs, scenes, &opts, &|_, _| {}).expect("sweep")
}

/// One frame of a sequence run: each plane's fixed codes (one for grey, R, G, B for
/// colour) and the reference's.
pub type SequenceFrame = (Vec<Vec<u16>>, Option<Vec<Vec<u16>>>);

/// Runs frames `frames` of `scene`'s sequence on `hw`, keeping every frame's planes.
pub fn run_sequence(
    scene: &Scene,
    hw: &HwConfig,
    frames: std::ops::Range<u32>,
    reference: bool,
    reuse: bool,
) -> (igemu::sequence::SequenceReport, Vec<SequenceFrame>) {
    let mut kept = Vec::new();
    let o = igemu::sequence::SequenceOptions {
        frames,
        reference,
        reuse,
    };
    let r = igemu::sequence::run(scene, hw, &o, &mut |f| {
        assert_eq!(f.fixed.len(), f.bits.len());
        let planes = |p: &[&[u16]]| p.iter().map(|c| c.to_vec()).collect::<Vec<_>>();
        kept.push((planes(f.fixed), f.reference.map(planes)));
        Ok(())
    })
    .unwrap_or_else(|e| panic!("{e}"));
    (r, kept)
}

/// The options of a serial, fresh sweep writing `out`, reusing stages in `cache` (`None`:
/// full renders), with the depth-of-field truth at `dof_truth` rays when asked.
pub fn serial_sweep<'a>(
    out: &'a str,
    cache: Option<&'a igemu::pipeline::Cache>,
    dof_truth: Option<u32>,
) -> igemu::sweep::SweepOptions<'a> {
    igemu::sweep::SweepOptions {
        out,
        resume: false,
        shard: None,
        jobs: 1,
        cache,
        flicker: None,
        max_memory: None,
        dof_truth,
    }
}
