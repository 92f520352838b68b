//! The Verilog models and testbenches of `hdl-models/`, embedded in the binary
//! (`include_str!`), so that an installed binary (`cargo install`) or a moved tree still
//! runs its co-simulation and synthesis: when a simulator needs files they are written out
//! under the cache folder ([`crate::files::cache_dir`]) in a folder named by their hash,
//! each file atomically and only when it differs. `--hdl-dir DIR` ([`use_models`] with
//! [`Models::Dir`]) reads another copy instead (e.g. models being edited); it must hold
//! `rtl/` and `tb/` with the module's files, or the run says which file is missing.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The embedded files: (path under `hdl-models/`, text).
pub const SOURCES: &[(&str, &str)] = &[
    (
        "rtl/acc_mac.v",
        include_str!("../../hdl-models/rtl/acc_mac.v"),
    ),
    (
        "rtl/dither_ordered.v",
        include_str!("../../hdl-models/rtl/dither_ordered.v"),
    ),
    (
        "rtl/dof_row_mac.v",
        include_str!("../../hdl-models/rtl/dof_row_mac.v"),
    ),
    (
        "rtl/edge_stepper.v",
        include_str!("../../hdl-models/rtl/edge_stepper.v"),
    ),
    (
        "rtl/gamma_lut.v",
        include_str!("../../hdl-models/rtl/gamma_lut.v"),
    ),
    (
        "rtl/hs_pipe.v",
        include_str!("../../hdl-models/rtl/hs_pipe.v"),
    ),
    (
        "rtl/log_adder.v",
        include_str!("../../hdl-models/rtl/log_adder.v"),
    ),
    ("tb/hs_tb.vh", include_str!("../../hdl-models/tb/hs_tb.vh")),
    (
        "tb/tb_acc_mac.v",
        include_str!("../../hdl-models/tb/tb_acc_mac.v"),
    ),
    (
        "tb/tb_dither_ordered.v",
        include_str!("../../hdl-models/tb/tb_dither_ordered.v"),
    ),
    (
        "tb/tb_dof_row_mac.v",
        include_str!("../../hdl-models/tb/tb_dof_row_mac.v"),
    ),
    (
        "tb/tb_edge_stepper.v",
        include_str!("../../hdl-models/tb/tb_edge_stepper.v"),
    ),
    (
        "tb/tb_gamma_lut.v",
        include_str!("../../hdl-models/tb/tb_gamma_lut.v"),
    ),
    (
        "tb/tb_log_adder.v",
        include_str!("../../hdl-models/tb/tb_log_adder.v"),
    ),
    (
        "tb/tb_log_adder_exhaustive.v",
        include_str!("../../hdl-models/tb/tb_log_adder_exhaustive.v"),
    ),
];

/// Where the simulators and yosys read the models from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Models {
    /// The embedded copy, written out under this cache folder.
    Embedded(PathBuf),
    /// A folder holding `rtl/` and `tb/` (`--hdl-dir`).
    Dir(PathBuf),
}

static CHOSEN: OnceLock<Models> = OnceLock::new();

/// Chooses where the models are read from, once per process, before the first run (the
/// command line calls it from its flags); without it the embedded copy under the default
/// cache folder is used. A second call with a different choice is an error.
pub fn use_models(m: Models) -> Result<(), String> {
    let got = CHOSEN.get_or_init(|| m.clone());
    if *got == m {
        Ok(())
    } else {
        Err(format!("the HDL models are already read from {got:?}"))
    }
}

/// The folder of the models (`rtl/`, `tb/`): the `--hdl-dir` folder, checked to exist, or
/// the embedded copy written out (see the module docs).
pub fn models_dir() -> Result<PathBuf, String> {
    match CHOSEN.get_or_init(|| Models::Embedded(crate::files::cache_dir(None))) {
        Models::Dir(d) => {
            if d.join("rtl").is_dir() && d.join("tb").is_dir() {
                Ok(d.clone())
            } else {
                Err(format!(
                    "{}: not a folder of HDL models (it needs rtl/ and tb/, as hdl-models/ of the source tree); leave out --hdl-dir to use the models built into igemu",
                    d.display()
                ))
            }
        }
        Models::Embedded(cache) => write_out(cache),
    }
}

/// The path of a model file (`rtl/<module>.v`, `tb/<tb>.v`) under [`models_dir`], checked
/// to exist.
pub fn model_file(sub: &str, name: &str) -> Result<PathBuf, String> {
    let p = models_dir()?.join(sub).join(format!("{name}.v"));
    if p.is_file() {
        Ok(p)
    } else {
        Err(format!("{}: no such HDL model file", p.display()))
    }
}

/// The pipeline shell every module instantiates (`rtl/hs_pipe.v`).
pub const PIPE: &str = "hs_pipe";
/// The handshake driver every vector testbench includes (`tb/hs_tb.vh`).
pub const DRIVER: &str = "hs_tb.vh";

/// What a simulator compiles for testbench `tb` of `module`: the sources (testbench,
/// module, pipeline shell), the folder searched for `` `include``s besides the bench's, and
/// every file read (sources and the handshake driver) for a build's hash.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SimFiles {
    /// Testbench, module and pipeline shell, in that order.
    pub sources: Vec<PathBuf>,
    /// The testbench folder (`tb/`, holding the handshake driver).
    pub include_dir: PathBuf,
    /// The sources and the handshake driver.
    pub read: Vec<PathBuf>,
}

/// The files of testbench `tb` of `module` ([`SimFiles`]), checked to exist.
pub fn sim_files(tb: &str, module: &str) -> Result<SimFiles, String> {
    let sources = vec![
        model_file("tb", tb)?,
        model_file("rtl", module)?,
        model_file("rtl", PIPE)?,
    ];
    let include_dir = models_dir()?.join("tb");
    let driver = include_dir.join(DRIVER);
    if !driver.is_file() {
        return Err(format!("{}: no such HDL model file", driver.display()));
    }
    let mut read = sources.clone();
    read.push(driver);
    Ok(SimFiles {
        sources,
        include_dir,
        read,
    })
}

/// Writes the embedded files under `cache/hdl-models-<hash>/` (those missing or different)
/// and returns that folder.
fn write_out(cache: &Path) -> Result<PathBuf, String> {
    let parts: Vec<&[u8]> = SOURCES
        .iter()
        .flat_map(|(p, t)| [p.as_bytes(), t.as_bytes()])
        .collect();
    let dir = cache.join(format!(
        "hdl-models-{:016x}",
        crate::fnv::fnv1a_parts(&parts)
    ));
    for (p, text) in SOURCES {
        let f = dir.join(p);
        if std::fs::read(&f).is_ok_and(|b| b == text.as_bytes()) {
            continue;
        }
        let parent = f.parent().unwrap_or(&dir);
        std::fs::create_dir_all(parent).map_err(|e| {
            format!(
                "{}: cannot create the folder for the HDL models ({e}); give another with --cache-dir or ${}",
                parent.display(),
                crate::files::CACHE_ENV
            )
        })?;
        crate::output::write_file(&f, text).map_err(|e| e.to_string())?;
    }
    Ok(dir)
}
