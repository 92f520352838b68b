//! The binary does not depend on its source tree (issue 30): a copy of the built `igemu`
//! outside the tree, run from `/`, writes and runs the gamma testbench with the Verilog
//! models built into it, written out under its cache folder (`IGEMU_CACHE_DIR`, here a
//! temporary folder); `--hdl-dir` reads another copy of the models (a broken one fails the
//! testbench, so the flag is really used) and a folder without models is refused with exit 2.
//!
//! This is the equivalent of `cargo install --path . --root TMP && cd / && TMP/bin/igemu hdl
//! vectors --stage gamma --out DIR --run`: the test's own built binary is copied to a temporary
//! folder instead of a second (release) build by `cargo install`, which would take minutes on
//! CI for the same binary code. That no source file reads `CARGO_MANIFEST_DIR` is checked by
//! tests/structure.rs. Without iverilog the runs print a SKIP line, and fail under
//! `IGEMU_REQUIRE_HDL=1` (as tests/hdl_cosim.rs).

use std::path::{Path, PathBuf};
use std::process::Command;

const REQUIRE: &str = "IGEMU_REQUIRE_HDL";

/// A fresh temporary folder outside the source tree.
fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("igemu-portable-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temporary folder");
    d
}

/// The built binary copied to `dir/bin/igemu`.
fn installed(dir: &Path) -> PathBuf {
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).expect("bin folder");
    let exe = bin.join("igemu");
    std::fs::copy(env!("CARGO_BIN_EXE_igemu"), &exe).expect("copy the binary");
    exe
}

/// Runs `exe` in `/` with the cache folder `cache`: (exit code, stdout, stderr).
///
/// A binary just copied can be refused with "text file busy" for a moment: a child that
/// another test thread forks meanwhile holds the copy's write descriptor until its own
/// exec closes it. The run is then retried, for up to about 5 s.
fn run_at_root(exe: &Path, cache: &Path, args: &[&str]) -> (i32, String, String) {
    let run = || {
        Command::new(exe)
            .args(args)
            .current_dir("/")
            .env("IGEMU_CACHE_DIR", cache)
            .output()
    };
    let mut out = run();
    for _ in 0..100 {
        match &out {
            Err(e) if e.kind() == std::io::ErrorKind::ExecutableFileBusy => {
                std::thread::sleep(std::time::Duration::from_millis(50));
                out = run();
            }
            _ => break,
        }
    }
    let out = out.expect("run the copied igemu");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// `hdl vectors --stage gamma --out out --run --hdl-dir models` of the copied binary in `/`:
/// (exit code, stdout, stderr).
fn gamma_with_models(exe: &Path, cache: &Path, out: &str, models: &Path) -> (i32, String, String) {
    let m = models.to_str().expect("utf-8 path");
    let args = [
        "hdl",
        "vectors",
        "--stage",
        "gamma",
        "--out",
        out,
        "--run",
        "--hdl-dir",
        m,
    ];
    run_at_root(exe, cache, &args)
}

/// Whether Icarus Verilog runs; else a SKIP line (a failure under `IGEMU_REQUIRE_HDL=1`).
fn icarus(test: &str) -> bool {
    if igemu::hdl::available("iverilog") && igemu::hdl::available("vvp") {
        return true;
    }
    let line = format!(
        "SKIP {test}: iverilog/vvp not installed (apt-get install -y iverilog); the installed binary's co-simulation not run"
    );
    assert!(
        std::env::var(REQUIRE).map_or(true, |v| v != "1"),
        "{line}; {REQUIRE}=1 requires it"
    );
    println!("{line}");
    false
}

#[test]
fn an_installed_binary_runs_the_gamma_testbench_from_the_root_folder() {
    if !icarus("installed binary, hdl vectors --stage gamma --run") {
        return;
    }
    let tmp = scratch("gamma");
    let exe = installed(&tmp);
    let (cache, out) = (tmp.join("cache"), tmp.join("vectors"));
    let o = out.to_str().expect("utf-8 path");
    let (code, stdout, stderr) = run_at_root(
        &exe,
        &cache,
        &["hdl", "vectors", "--stage", "gamma", "--out", o, "--run"],
    );
    assert_eq!(code, 0, "{stdout}{stderr}");
    assert!(stdout.contains("icarus: TESTBENCH OK"), "{stdout}");
    assert!(out.join("vectors.hex").is_file() && out.join("params.vh").is_file());
    // The models came from the binary, written out under the cache folder.
    let written: Vec<PathBuf> = std::fs::read_dir(&cache)
        .expect("cache folder written")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("hdl-models-"))
        })
        .collect();
    assert_eq!(written.len(), 1, "{written:?}");
    let m = &written[0];
    assert!(m.join("rtl/gamma_lut.v").is_file() && m.join("tb/tb_gamma_lut.v").is_file());
    let _ = std::fs::remove_dir_all(&tmp);
}

#[test]
fn hdl_dir_reads_another_copy_of_the_models() {
    let tmp = scratch("hdl-dir");
    let exe = installed(&tmp);
    let cache = tmp.join("cache");
    let out = tmp.join("vectors");
    let o = out.to_str().expect("utf-8 path");
    // A folder without rtl/ and tb/: exit 2 naming the flag and the folder, before any file.
    let empty = tmp.join("empty");
    std::fs::create_dir_all(&empty).expect("folder");
    let e = empty.to_str().expect("utf-8 path");
    let (code, _, stderr) = gamma_with_models(&exe, &cache, o, &empty);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("--hdl-dir") && stderr.contains(e) && stderr.contains("rtl/"),
        "{stderr}"
    );
    assert!(!out.exists(), "nothing written before the refusal");
    if !icarus("hdl vectors --hdl-dir") {
        return;
    }
    // A copy of the models whose gamma LUT inverts its output: the testbench now fails.
    let broken = tmp.join("models");
    for (p, text) in igemu::hdl::models::SOURCES {
        let f = broken.join(p);
        std::fs::create_dir_all(f.parent().expect("parent")).expect("folder");
        let text = if *p == "rtl/gamma_lut.v" {
            let t = text.replace(".in_data(rom[", ".in_data(~rom[");
            assert_ne!(&t, text, "the gamma model changed: update this test's edit");
            t
        } else {
            text.to_string()
        };
        std::fs::write(f, text).expect("write model");
    }
    let (code, stdout, stderr) = gamma_with_models(&exe, &cache, o, &broken);
    assert_eq!(code, 1, "{stdout}{stderr}");
    assert!(stdout.contains("TESTBENCH FAILED"), "{stdout}");
    let _ = std::fs::remove_dir_all(&tmp);
}

/// Every file of `hdl-models/rtl` and `hdl-models/tb` (`.v`, the `.vh` driver) is built into
/// the binary.
#[test]
fn every_model_file_is_embedded() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("hdl-models");
    let mut on_disk: Vec<String> = ["rtl", "tb"]
        .iter()
        .flat_map(|sub| {
            std::fs::read_dir(root.join(sub))
                .expect("hdl-models folder")
                .filter_map(|e| e.ok())
                .map(move |e| format!("{sub}/{}", e.file_name().to_string_lossy()))
        })
        .filter(|p| p.ends_with(".v") || p.ends_with(".vh"))
        .collect();
    on_disk.sort();
    let mut embedded: Vec<String> = igemu::hdl::models::SOURCES
        .iter()
        .map(|(p, _)| p.to_string())
        .collect();
    embedded.sort();
    assert_eq!(embedded, on_disk);
    for (p, text) in igemu::hdl::models::SOURCES {
        assert_eq!(
            std::fs::read_to_string(root.join(p)).expect("model"),
            *text,
            "{p}"
        );
    }
}
