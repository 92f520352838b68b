//! An output never overwrites an input, and every output path is checked before any work:
//! a path that names no file, a folder given as a file and a file given as a folder are
//! refused naming the flag. Each command collects its input files (scene
//! files, the `--hw` file, the `--grid` file) by canonical path and checks every output
//! path against them before any work. An output that does not exist yet cannot be an
//! input; a symbolic link or a `..` path to an input is the input. Two outputs of one
//! command may not name the same file either (the second would replace the first).

use crate::args::{SceneArgs, arg_error};
use igemu::error::Error;
use std::path::{Path, PathBuf};

/// The input files of a command: (what it is, canonical path).
#[derive(Default)]
pub struct Inputs(Vec<(String, PathBuf)>);

impl Inputs {
    /// The scene file and the `--hw` file of `s` (a preset or an embedded scene name is no
    /// file).
    pub fn of(s: &SceneArgs) -> Inputs {
        let mut i = Inputs::default();
        i.add("the scene file", s.scene.as_deref());
        i.add("the hardware file (--hw)", s.hw.as_deref());
        i
    }

    /// Adds `path` as `what` when it names an existing file.
    pub fn add(&mut self, what: &str, path: Option<&str>) {
        if let Some(c) = path.and_then(|p| std::fs::canonicalize(p).ok())
            && c.is_file()
        {
            self.0.push((what.into(), c));
        }
    }

    /// Refuses `out` (the value of `flag`) when it cannot be written as a file (no file
    /// name, a folder, read-only: [`igemu::output::unwritable`]) or is one of the inputs.
    pub fn check(&self, flag: &str, out: &str) -> Result<(), Error> {
        if let Some(why) = igemu::output::unwritable(Path::new(out)) {
            return Err(arg_error(flag, format!("{} {why}", shown(out))));
        }
        self.check_path(flag, out, Path::new(out))
    }

    /// Refuses every given output (flag, path) that is one of the inputs, and two outputs
    /// that name the same file.
    pub fn check_outputs(&self, outs: &[(&str, Option<&str>)]) -> Result<(), Error> {
        let given: Vec<(&str, &str)> = outs
            .iter()
            .filter_map(|&(flag, p)| p.map(|p| (flag, p)))
            .collect();
        for (flag, p) in &given {
            self.check(flag, p)?;
        }
        distinct_outputs(&given)
    }

    /// Refuses any of `names` in the folder `dir` (the value of `flag`) that is an input.
    pub fn check_in<S: AsRef<str>>(
        &self,
        flag: &str,
        dir: &Path,
        names: impl IntoIterator<Item = S>,
    ) -> Result<(), Error> {
        for n in names {
            let p = dir.join(n.as_ref());
            self.check_path(flag, &p.display().to_string(), &p)?;
        }
        Ok(())
    }

    fn check_path(&self, flag: &str, shown: &str, out: &Path) -> Result<(), Error> {
        let Ok(c) = std::fs::canonicalize(out) else {
            return Ok(());
        };
        match self.0.iter().find(|(_, p)| *p == c) {
            Some((what, _)) => Err(arg_error(
                flag,
                format!(
                    "{shown} is {what}; choose another path (an output never overwrites an input)"
                ),
            )),
            None => Ok(()),
        }
    }
}

/// A path as messages show it: `''` for the empty one.
fn shown(p: &str) -> &str {
    if p.is_empty() { "''" } else { p }
}

/// Refuses `dir` (the value of `flag`, an output folder created when missing) when it cannot
/// be one: empty, or it or a parent is a file ([`igemu::output::unwritable_folder`]).
pub fn folder(flag: &str, dir: &str) -> Result<(), Error> {
    match igemu::output::unwritable_folder(Path::new(dir)) {
        Some(why) => Err(arg_error(flag, format!("{} {why}", shown(dir)))),
        None => Ok(()),
    }
}

/// Where `p` would be written: its folder canonicalised (when it exists) joined with its
/// file name, so `a/../x.png` and `x.png` compare equal before either exists.
fn destination(p: &str) -> PathBuf {
    let path = Path::new(p);
    if let Ok(c) = std::fs::canonicalize(path) {
        return c;
    }
    let parent = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    match (std::fs::canonicalize(parent), path.file_name()) {
        (Ok(d), Some(n)) => d.join(n),
        _ => path.to_path_buf(),
    }
}

/// Refuses two outputs (flag, path) that name the same file; a special file (`/dev/null`, a
/// FIFO: written in place, see [`igemu::output::AtomicFile`]) may take several.
pub fn distinct_outputs(outs: &[(&str, &str)]) -> Result<(), Error> {
    let dest: Vec<PathBuf> = outs.iter().map(|(_, p)| destination(p)).collect();
    let special = |p: &Path| std::fs::metadata(p).is_ok_and(|m| !m.is_file() && !m.is_dir());
    for j in 1..outs.len() {
        if let Some(i) = (0..j).find(|&i| dest[i] == dest[j] && !special(&dest[j])) {
            return Err(arg_error(
                outs[j].0,
                format!(
                    "{} is also the output of {}; give each output its own path",
                    outs[j].1, outs[i].0
                ),
            ));
        }
    }
    Ok(())
}
