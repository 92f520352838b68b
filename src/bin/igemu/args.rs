//! Argument types shared by several commands: the scene and hardware arguments
//! ([`SceneArgs`]) and the clap value enums of the choices (`--stage`, `--sim`, `--export`,
//! `--filter`), plus the error that names a bad flag.

use clap::builder::PossibleValue;
use clap::{Args, ValueEnum};
use igemu::analysis::ranges::Export;
use igemu::config::{FilterKind, HwConfig};
use igemu::error::{Error, FileError};
use igemu::hdl::verilator::Sim;
use igemu::pipeline::{self, Render};
use igemu::scene::Scene;
use igemu::stage::RunOptions;
use igemu::stage_id::StageId;
use std::sync::LazyLock;

#[derive(Args)]
pub struct SceneArgs {
    /// Scene TOML file or embedded scene name (default: the embedded default scene).
    pub scene: Option<String>,
    /// Hardware config: a preset (linear12, linear11, linear8, log8-potentiate, log8-logadd, log7-logadd) or a TOML file.
    #[arg(long)]
    pub hw: Option<String>,
    /// Refuse a render whose memory estimate exceeds SIZE (bytes, or with K, M, G, T: 512M, 8G; default half the machine's memory).
    #[arg(long, value_name = "SIZE", value_parser = parse_size, allow_hyphen_values = true)]
    pub max_memory: Option<u64>,
}

impl SceneArgs {
    /// The scene.
    pub fn scene(&self) -> Result<Scene, Error> {
        load_scene(self.scene.as_deref())
    }

    /// The hardware config.
    pub fn hw(&self) -> Result<HwConfig, Error> {
        Ok(HwConfig::resolve(self.hw.as_deref())?)
    }

    /// `opts` with the memory limit of `--max-memory`.
    pub fn opts(&self, opts: RunOptions) -> RunOptions {
        RunOptions {
            max_memory: self.max_memory.or(opts.max_memory),
            ..opts
        }
    }

    /// Renders the scene on the hardware.
    pub fn render(&self, opts: RunOptions) -> Result<Render, Error> {
        let scene = self.scene()?;
        let hw = self.hw()?;
        pipeline::render(&scene, &hw, self.opts(opts))
    }
}

/// Where the HDL models are read from and where caches go (`hdl vectors --run`, `cost
/// --synth`): the binary carries its own models and never writes into a source tree.
#[derive(Args)]
pub struct HdlDirs {
    /// Read the Verilog models from DIR (holding rtl/ and tb/, as hdl-models/ of the source tree) instead of the copy built into igemu.
    #[arg(long, value_name = "DIR")]
    pub hdl_dir: Option<String>,
    /// The cache folder: Verilator builds, yosys counts, the built-in models written out for the simulators (default: $IGEMU_CACHE_DIR, else $XDG_CACHE_HOME/igemu, else ~/.cache/igemu).
    #[arg(long, value_name = "DIR")]
    pub cache_dir: Option<String>,
}

impl HdlDirs {
    /// Chooses the models ([`igemu::hdl::use_models`]) and returns the cache folder.
    pub fn apply(&self) -> Result<std::path::PathBuf, Error> {
        let cache = igemu::files::cache_dir(self.cache_dir.as_deref().map(std::path::Path::new));
        let models = match &self.hdl_dir {
            Some(d) => igemu::hdl::Models::Dir(d.into()),
            None => igemu::hdl::Models::Embedded(cache.clone()),
        };
        igemu::hdl::use_models(models).map_err(|m| arg_error("--hdl-dir", m))?;
        if self.hdl_dir.is_some() {
            igemu::hdl::models_dir().map_err(|m| arg_error("--hdl-dir", m))?;
        }
        Ok(cache)
    }
}

/// The depth-of-field truth flags of `render` and `sweep` (see [`igemu::truth`]).
#[derive(Args)]
pub struct TruthArgs {
    /// Compare with the depth-of-field truth: a thin-lens image averaged over points of the aperture, in f64 (a thin-lens scene only); reports the total, algorithm and quantisation errors and the truth's noise.
    #[arg(long)]
    pub dof_truth: bool,
    /// Lens points the truth averages: a multiple of 8 in 8..=4096 (default 256); the noise falls as 1/sqrt(N), the time grows as N.
    #[arg(long, value_name = "N", requires = "dof_truth", value_parser = parse_lens_samples, allow_negative_numbers = true)]
    pub lens_samples: Option<u32>,
}

impl TruthArgs {
    /// The lens-sample count of `RunOptions::dof_truth_samples` (0: no truth).
    pub fn samples(&self) -> u32 {
        if self.dof_truth {
            self.lens_samples.unwrap_or(igemu::truth::DEFAULT_SAMPLES)
        } else {
            0
        }
    }
}

/// Parses `--lens-samples`: an integer (negative ones too: the arg allows them) checked by
/// [`igemu::truth::check_samples`].
pub fn parse_lens_samples(s: &str) -> Result<u32, String> {
    let n: i64 = s.trim().parse().map_err(|_| {
        format!(
            "`{s}` is not a count: give a multiple of {} in {}..={}",
            igemu::truth::GROUPS,
            igemu::truth::MIN_SAMPLES,
            igemu::truth::MAX_SAMPLES
        )
    })?;
    igemu::truth::check_samples(n)?;
    Ok(n as u32)
}

/// A value parser of an integer in `lo..=hi`: a number outside it, a negative one included,
/// is refused with the range (give the arg `allow_negative_numbers`, or clap reads `-1` as a
/// flag and names no range).
pub fn int_in(lo: u32, hi: u32) -> impl Fn(&str) -> Result<u32, String> + Clone + Send + Sync {
    move |s| match s.trim().parse::<i64>() {
        Ok(n) if (i64::from(lo)..=i64::from(hi)).contains(&n) => Ok(n as u32),
        Ok(n) => Err(format!("must be an integer in {lo}..={hi}, got {n}")),
        Err(_) => Err(format!("`{s}` is not an integer: give one in {lo}..={hi}")),
    }
}

/// Parses a size: bytes, or a number with `K`, `M`, `G` or `T` (binary units; an optional
/// `i` and `B` are accepted: `512M`, `8GiB`, `1.5G`).
pub fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let upper = t.to_ascii_uppercase();
    let u = upper.trim_end_matches('B').trim_end_matches('I');
    let (num, shift) = match u.chars().last() {
        Some('K') => (&u[..u.len() - 1], 10),
        Some('M') => (&u[..u.len() - 1], 20),
        Some('G') => (&u[..u.len() - 1], 30),
        Some('T') => (&u[..u.len() - 1], 40),
        _ => (u, 0),
    };
    let v: f64 = num.trim().parse().map_err(|_| {
        format!("`{s}` is not a size (bytes, or a number with K, M, G or T, e.g. 512M or 8G)")
    })?;
    let bytes = v * (1u64 << shift) as f64;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < 2f64.powi(63)) {
        return Err(format!("`{s}` must be at least 1 byte and below 8 EiB"));
    }
    Ok(bytes as u64)
}

/// A scene: the default scene, an embedded scene name (unless a file of that name exists)
/// or a TOML file. A name that is neither (no such file, no `/`, no `.toml`) is refused
/// naming what the user meant: a hardware preset given as the scene, or the nearest
/// embedded name, with the list of embedded scenes.
pub fn load_scene(arg: Option<&str>) -> Result<Scene, Error> {
    let Some(a) = arg else {
        return Ok(Scene::default_scene());
    };
    let exists = std::path::Path::new(a).exists();
    match Scene::embedded(a) {
        Some(s) if !exists => Ok(s),
        None if !exists && !a.contains(['/', '\\']) && !a.ends_with(".toml") => {
            Err(unknown_scene(a))
        }
        _ => Ok(Scene::load(a)?),
    }
}

/// The error of a scene argument that names no embedded scene and no file.
fn unknown_scene(a: &str) -> Error {
    let names = igemu::scene::names();
    let list = format!(
        "embedded scenes: {}; or give a scene TOML file",
        names.join(", ")
    );
    let msg = if igemu::config::PRESETS.contains(&a) {
        format!("`{a}` is a hardware preset, not a scene: use `--hw {a}` ({list})")
    } else if let Some(n) = igemu::files::nearest(a, &names) {
        format!("no embedded scene or file `{a}`: did you mean `{n}`? ({list})")
    } else {
        format!("no embedded scene or file `{a}` ({list})")
    };
    arg_error("SCENE", msg)
}

/// The configurations of a grid file (parsed and validated) and the scenes of a sweep
/// (default: the embedded default scene), as `igemu sweep` and `igemu sweep merge` read them.
pub fn grid_and_scenes(
    grid: &str,
    scenes: &[String],
) -> Result<(Vec<igemu::sweep::grid::Config>, Vec<Scene>), Error> {
    use igemu::sweep::grid::Grid;
    let file = igemu::files::TomlFile::read(grid)?;
    let configs = Grid::parse(&file)?.expand(&file)?;
    let scenes = if scenes.is_empty() {
        vec![Scene::default_scene()]
    } else {
        scenes
            .iter()
            .map(|s| load_scene(Some(s)))
            .collect::<Result<_, _>>()?
    };
    Ok((configs, scenes))
}

/// An error naming a flag (or a command) and what is wrong with it.
pub fn arg_error(flag: &str, msg: String) -> Error {
    Error::File(FileError {
        file: flag.into(),
        line: None,
        col: None,
        field: String::new(),
        msg,
    })
}

/// A stage with an HDL model (`hdl vectors --stage`): the choices are the stages of
/// [`StageId::ALL`] that [`igemu::hdl::module_of`] knows, in flow order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StageArg(pub StageId);

impl ValueEnum for StageArg {
    fn value_variants<'a>() -> &'a [Self] {
        static WITH_MODEL: LazyLock<Vec<StageArg>> = LazyLock::new(|| {
            StageId::ALL
                .into_iter()
                .filter(|&s| igemu::hdl::module_of(s).is_some())
                .map(StageArg)
                .collect()
        });
        &WITH_MODEL
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        igemu::hdl::module_of(self.0).map(|_| PossibleValue::new(self.0.name()))
    }
}

/// A Verilog simulator (`hdl vectors --sim`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SimArg {
    Icarus,
    Verilator,
}

impl From<SimArg> for Sim {
    fn from(s: SimArg) -> Sim {
        match s {
            SimArg::Icarus => Sim::Icarus,
            SimArg::Verilator => Sim::Verilator,
        }
    }
}

/// A typedef language of `ranges --export`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ExportArg {
    #[value(name = "ac_fixed")]
    AcFixed,
    #[value(name = "ap_fixed")]
    ApFixed,
    #[value(name = "systemc")]
    SystemC,
    #[value(name = "verilog")]
    Verilog,
}

impl From<ExportArg> for Export {
    fn from(e: ExportArg) -> Export {
        match e {
            ExportArg::AcFixed => Export::AcFixed,
            ExportArg::ApFixed => Export::ApFixed,
            ExportArg::SystemC => Export::SystemC,
            ExportArg::Verilog => Export::Verilog,
        }
    }
}

/// A reconstruction filter (`flicker --filter`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FilterArg {
    Box,
    Tent,
    Gaussian,
    #[value(name = "cubic_bspline")]
    CubicBspline,
    #[value(name = "catmull_rom")]
    CatmullRom,
    /// Mitchell-Netravali with the hardware file's `accumulate.mitchell` (B = C = 1/3 by default).
    Mitchell,
}

impl From<FilterArg> for FilterKind {
    fn from(f: FilterArg) -> FilterKind {
        match f {
            FilterArg::Box => FilterKind::Box,
            FilterArg::Tent => FilterKind::Tent,
            FilterArg::Gaussian => FilterKind::Gaussian,
            FilterArg::CubicBspline => FilterKind::CubicBspline,
            FilterArg::CatmullRom => FilterKind::CatmullRom,
            FilterArg::Mitchell => FilterKind::Mitchell,
        }
    }
}

/// A number for a message: plain when it reads well, else in exponent form (`1e308`, not
/// 309 digits).
pub fn num(v: f64) -> String {
    let a = v.abs();
    if !v.is_finite() || a == 0.0 || (1e-4..1e7).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// A pixel tap to dump (`render --dump TAP=PATH`): `STAGE` or `STAGE.PLANE` for the stages
/// whose taps are images ([`igemu::stage::taps::image_planes`]): the frame memory after
/// accumulate and dof (planes `frame`, `depth`, `coverage`; `frame` by default), the codes
/// after gamma and dither.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DumpTap {
    /// The stage whose output taps are dumped.
    pub stage: StageId,
    /// The plane.
    pub plane: &'static str,
}

impl ValueEnum for DumpTap {
    fn value_variants<'a>() -> &'a [Self] {
        static TAPS: LazyLock<Vec<DumpTap>> = LazyLock::new(|| {
            StageId::ALL
                .into_iter()
                .flat_map(|stage| {
                    igemu::stage::taps::image_planes(stage)
                        .iter()
                        .map(move |&plane| DumpTap { stage, plane })
                })
                .collect()
        });
        &TAPS
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        let first = igemu::stage::taps::image_planes(self.stage).first() == Some(&self.plane);
        let name = format!("{}.{}", self.stage, self.plane);
        let v = PossibleValue::new(name.clone());
        // `STAGE` alone names its first plane.
        Some(if first { v.alias(self.stage.name()) } else { v })
    }
}

/// Parses `TAP=PATH` for `--dump`.
pub fn parse_dump(s: &str) -> Result<(DumpTap, String), String> {
    let (tap, path) = s
        .split_once('=')
        .ok_or_else(|| format!("`{s}` is not TAP=PATH"))?;
    let t = DumpTap::from_str(tap, false).map_err(|_| {
        let all: Vec<String> = DumpTap::value_variants()
            .iter()
            .map(|t| format!("{}.{}", t.stage, t.plane))
            .collect();
        format!(
            "unknown tap `{tap}`; allowed: {} (a stage alone names its first plane)",
            all.join(", ")
        )
    })?;
    if path.is_empty() {
        return Err(format!("`{s}` names no PATH"));
    }
    Ok((t, path.to_string()))
}

/// The shard of `--shard` of `igemu CMD`: `K/N`, or `auto`/`auto/N` from the environment of
/// a Slurm array task or a Kubernetes indexed Job (then said on stderr).
pub fn shard_arg(cmd: &str, s: &str) -> Result<igemu::shard::Shard, Error> {
    let (shard, from) = igemu::shard::Shard::from_arg(s, |v| std::env::var(v).ok())
        .map_err(|m| arg_error("--shard", m))?;
    if let Some(from) = from {
        use std::io::Write;
        let _ = writeln!(
            std::io::stderr(),
            "igemu {cmd}: --shard {s}: shard {}/{} from {from}",
            shard.k,
            shard.n
        );
    }
    Ok(shard)
}
