//! The layout rules of docs/STRUCTURE.md, checked on the source tree:
//!
//! 1. Dependencies point one way, down the layers below: a module imports (`crate::x`)
//!    only modules of its own layer or a lower one. In particular `config` imports no stage,
//!    a stage imports no `pipeline`, `cycles`, `sweep`, `hdl` or command-line code, and the
//!    pipeline imports no `sweep` or `hdl`.
//! 2. The library never prints (`println!`, `eprintln!`, `print!`, `eprint!`, `dbg!` only in
//!    `src/bin/`).
//! 3. No file in `src/` is over 600 lines.
//! 4. The binary does not depend on its source tree: no code under `src/` reads
//!    `CARGO_MANIFEST_DIR` (the HDL models are embedded, caches go to a user cache folder;
//!    tests/portable.rs runs a copy of the binary from `/`).
//!
//! Run alone with `cargo test --test structure`.

use std::path::{Path, PathBuf};

/// Layers, bottom first: a module may import its own layer and the layers below.
const LAYERS: &[&[&str]] = &[
    &[
        "error", "fixed", "fnv", "rng", "stage_id", "files", "output", "shard",
    ],
    &["scene"],
    &["config"],
    &["stage"],
    &["compare", "perceptual", "colour", "cycles", "cost", "truth"],
    &["pipeline"],
    &["analysis", "sweep", "sequence", "hdl", "html"],
];

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).expect("read src") {
        let p = e.expect("entry").path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The code of a file without comments (line comments and doc comments).
fn code_lines(text: &str) -> Vec<(usize, String)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| {
            let code = match l.find("//") {
                // Keep `//` inside string literals (rare in imports): a quote before it.
                Some(at) if !l[..at].contains('"') => &l[..at],
                _ => l,
            };
            (i + 1, code.to_string())
        })
        .collect()
}

/// Top-level crate modules a line refers to as `crate::name`.
fn crate_refs(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = line;
    while let Some(at) = rest.find("crate::") {
        let after = &rest[at + "crate::".len()..];
        let name: String = after
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect();
        if !name.is_empty() {
            out.push(name);
        }
        rest = after;
    }
    out
}

#[test]
fn dependencies_point_down_the_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut violations = Vec::new();
    let mut unknown = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(&src).expect("under src");
        let first = rel.components().next().expect("a component");
        let module = first
            .as_os_str()
            .to_string_lossy()
            .trim_end_matches(".rs")
            .to_string();
        if module == "bin" || module == "lib" {
            continue;
        }
        let Some(own) = layer_of(&module) else {
            unknown.push(module);
            continue;
        };
        let text = std::fs::read_to_string(f).expect("read");
        for (n, line) in code_lines(&text) {
            for r in crate_refs(&line) {
                match layer_of(&r) {
                    Some(l) if l <= own => {}
                    Some(_) => violations.push(format!(
                        "{}:{n}: `{module}` imports `crate::{r}` from a higher layer",
                        rel.display()
                    )),
                    None => {}
                }
            }
        }
    }
    unknown.sort();
    unknown.dedup();
    assert!(
        unknown.is_empty(),
        "modules without a layer in tests/structure.rs (add them to LAYERS and docs/STRUCTURE.md): {unknown:?}"
    );
    assert!(violations.is_empty(), "{}", violations.join("\n"));
}

#[test]
fn the_library_never_prints() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut found = Vec::new();
    for f in files.iter().filter(|f| !f.starts_with(src.join("bin"))) {
        let text = std::fs::read_to_string(f).expect("read");
        for (n, line) in code_lines(&text) {
            for m in ["println!", "eprintln!", "print!", "eprint!", "dbg!"] {
                if line.contains(m) {
                    found.push(format!("{}:{n}: {m}", f.display()));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "the library prints:\n{}",
        found.join("\n")
    );
}

/// The lines of `src/` code that name `var` (comments left out).
fn code_naming(var: &str) -> Vec<String> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut found = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).expect("read");
        for (n, line) in code_lines(&text) {
            if line.contains(var) {
                found.push(format!("{}:{n}", f.display()));
            }
        }
    }
    found
}

#[test]
fn the_binary_does_not_depend_on_its_source_tree() {
    let found = code_naming("CARGO_MANIFEST_DIR");
    assert!(
        found.is_empty(),
        "code under src/ reads the source tree's path (an installed binary has none): {found:?}"
    );
    // The check sees a use in code, not one in a comment.
    assert_eq!(
        code_lines("let d = env!(\"CARGO_MANIFEST_DIR\"); // x").len(),
        1
    );
    assert!(
        code_lines("// env!(\"CARGO_MANIFEST_DIR\")")[0]
            .1
            .is_empty()
    );
}

#[test]
fn files_stay_under_600_lines() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let long: Vec<String> = files
        .iter()
        .filter_map(|f| {
            let n = std::fs::read_to_string(f).expect("read").lines().count();
            (n > 600).then(|| format!("{} ({n} lines)", f.display()))
        })
        .collect();
    assert!(long.is_empty(), "files over 600 lines: {long:?}");
}

#[test]
fn the_checker_catches_an_upward_import() {
    // The rule works on text: a stage line importing the pipeline is a violation.
    let refs = crate_refs("use crate::pipeline::plan::Plan; // crate::sweep in a comment");
    assert_eq!(refs, ["pipeline", "sweep"]);
    let code = code_lines("use crate::pipeline::plan::Plan; // crate::sweep in a comment");
    assert_eq!(crate_refs(&code[0].1), ["pipeline"]);
    assert!(layer_of("pipeline") > layer_of("stage"));
    assert!(layer_of("stage") > layer_of("config"));
    assert!(layer_of("sweep") > layer_of("pipeline"));
}
