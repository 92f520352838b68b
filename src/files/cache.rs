//! Where an installed binary keeps its caches (the Verilator builds, the yosys counts, the
//! HDL models written out for a simulator): a user cache folder, never the source tree.

use std::path::{Path, PathBuf};

/// The variable that names the cache folder ahead of the platform's default.
pub const CACHE_ENV: &str = "IGEMU_CACHE_DIR";

/// The cache folder: `over` (a `--cache-dir` flag) if given, else `$IGEMU_CACHE_DIR`, else
/// the platform's user cache folder with `igemu` appended (`$XDG_CACHE_HOME/igemu` or
/// `~/.cache/igemu` on Linux, through the `dirs` crate), else `igemu-cache` in the
/// temporary folder. Not created here: the writers create what they write.
pub fn cache_dir(over: Option<&Path>) -> PathBuf {
    if let Some(p) = over {
        return p.to_path_buf();
    }
    if let Some(p) = std::env::var_os(CACHE_ENV).filter(|v| !v.is_empty()) {
        return PathBuf::from(p);
    }
    match dirs::cache_dir() {
        Some(d) => d.join("igemu"),
        None => std::env::temp_dir().join("igemu-cache"),
    }
}
