//! Safe outputs: every file is written to a temporary in its folder and renamed (a killed
//! render never leaves a truncated PNG; a failed write leaves no temporary), an output that
//! is an input is refused, two outputs on one path are refused, a path that cannot be an
//! output (empty, a folder, a file as `--rom-out`) is refused before any work, and a closed
//! stdout ends the program quietly.

mod common;

use common::{Rng, igemu};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_igemu");

/// A fresh folder for one test.
fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("igemu-outputs-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

/// The names in `d`, sorted.
fn names(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn temporaries(d: &Path) -> Vec<String> {
    names(d)
        .into_iter()
        .filter(|n| n.starts_with('.') && n.ends_with(".tmp"))
        .collect()
}

/// A small valid PNG, different from any render.
fn old_png() -> Vec<u8> {
    let img = image::GrayImage::from_fn(3, 2, |x, y| image::Luma([(x * 40 + y * 7) as u8]));
    let mut v = std::io::Cursor::new(Vec::new());
    img.write_to(&mut v, image::ImageFormat::Png).unwrap();
    v.into_inner()
}

/// What a file's metadata says about its identity and content.
fn stamp(p: &Path) -> Option<(u64, std::time::SystemTime, u64)> {
    use std::os::unix::fs::MetadataExt;
    let m = std::fs::metadata(p).ok()?;
    Some((m.len(), m.modified().ok()?, m.ino()))
}

/// `igemu render -o out.png` is SIGKILLed at random moments and at the moments its output
/// changes (a temporary appears, out.png changes); out.png is always the old PNG or the
/// complete new one, never truncated. (Before the fix, `-o` truncated out.png first: the
/// kill on its first change left a 0-byte or partial file.)
#[test]
fn a_killed_render_leaves_the_old_png_or_a_complete_new_one() {
    let d = dir("kill");
    let out = d.join("out.png");
    let old = old_png();
    let render = || {
        Command::new(BIN)
            .args(["render", "--no-local", "-o", &s(&out)])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("run igemu")
    };
    // One complete run: its time spans the random kills.
    let t = Instant::now();
    assert!(render().wait().unwrap().success());
    let full = t.elapsed().as_secs_f64();
    let mut rng = Rng::new(0x5eed_4b11);
    let (mut kept_old, mut got_new) = (0, 0);
    for trial in 0..12 {
        std::fs::write(&out, &old).unwrap();
        let before = stamp(&out);
        let mut child = render();
        let start = Instant::now();
        let delay = Duration::from_secs_f64(rng.range(0.3, 1.1) * full);
        loop {
            if child.try_wait().unwrap().is_some() {
                break;
            }
            let fire = match trial % 3 {
                0 => start.elapsed() >= delay,
                // A temporary (or any new file) appeared.
                1 => names(&d).len() > 1,
                // out.png itself changed.
                _ => stamp(&out) != before,
            };
            if fire {
                break;
            }
            std::thread::yield_now();
        }
        let _ = child.kill();
        child.wait().unwrap();
        let now = std::fs::read(&out).expect("out.png is there");
        if now == old {
            kept_old += 1;
        } else {
            let img = image::load_from_memory(&now).unwrap_or_else(|e| {
                panic!(
                    "trial {trial}: out.png is neither the old PNG nor a complete one ({} bytes): {e}",
                    now.len()
                )
            });
            assert_eq!((img.width(), img.height()), (640, 480), "trial {trial}");
            got_new += 1;
        }
        // A killed process leaves its hidden temporary behind, nothing else.
        for n in names(&d) {
            if n != "out.png" {
                assert!(n.starts_with(".out.png.") && n.ends_with(".tmp"), "{n}");
                std::fs::remove_file(d.join(n)).unwrap();
            }
        }
    }
    assert_eq!(kept_old + got_new, 12);
}

/// A write that fails leaves no temporary, the destination as it was, and exits 2 naming
/// the path.
#[test]
fn a_failed_write_leaves_no_temporary_and_exits_2_naming_the_path() {
    let d = dir("fail");
    // The folder does not exist.
    let missing = d.join("no-such-folder").join("out.png");
    let (code, _, err) = igemu(&["render", "--no-local", "-o", &s(&missing)]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(&s(&missing)) && err.contains("folder exists"),
        "{err}"
    );
    for args in [
        vec![
            "cycles".to_string(),
            "--vcd".into(),
            s(&missing.with_extension("vcd")),
        ],
        vec![
            "render".to_string(),
            "--no-local".into(),
            "-o".into(),
            s(&d.join("ok.png")),
            "--report".into(),
            s(&missing.with_extension("json")),
        ],
    ] {
        let a: Vec<&str> = args.iter().map(|x| x.as_str()).collect();
        let (code, _, err) = igemu(&a);
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains("no-such-folder") && !err.contains("panicked"),
            "{err}"
        );
    }
    // The destination is a folder.
    let folder = d.join("taken.png");
    std::fs::create_dir(&folder).unwrap();
    let (code, _, err) = igemu(&["render", "--no-local", "-o", &s(&folder)]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(&s(&folder)) && err.contains("is a folder"),
        "{err}"
    );
    // A read-only destination stays as it is.
    let ro = d.join("ro.json");
    std::fs::write(&ro, "keep").unwrap();
    let mut p = std::fs::metadata(&ro).unwrap().permissions();
    p.set_readonly(true);
    std::fs::set_permissions(&ro, p).unwrap();
    let png = s(&d.join("ok.png"));
    let (code, _, err) = igemu(&["render", "--no-local", "-o", &png, "--report", &s(&ro)]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(&s(&ro)) && err.contains("read-only"), "{err}");
    assert_eq!(std::fs::read_to_string(&ro).unwrap(), "keep");
    // A read-only folder (not for root, who may write anywhere).
    let locked = d.join("locked");
    std::fs::create_dir(&locked).unwrap();
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
    }
    if std::fs::write(locked.join("probe"), "").is_err() {
        let dest = locked.join("out.vcd");
        let (code, _, err) = igemu(&["cycles", "--vcd", &s(&dest)]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(&s(&dest)), "{err}");
    }
    for f in [&d, &locked] {
        assert_eq!(temporaries(f), Vec::<String>::new(), "{}", f.display());
    }
}

/// The library's atomic writer: an error while writing removes the temporary and keeps
/// the destination; a commit replaces it and keeps its permissions.
#[test]
fn the_atomic_writer_keeps_the_destination_until_commit() {
    use std::io::Write;
    use std::os::unix::fs::PermissionsExt;
    let d = dir("writer");
    let dest = d.join("report.json");
    std::fs::write(&dest, "old").unwrap();
    std::fs::set_permissions(&dest, std::fs::Permissions::from_mode(0o640)).unwrap();
    let e = igemu::output::write_with(&dest, |w| {
        w.write_all(b"half of the new")?;
        Err(std::io::Error::other("disk on fire"))
    })
    .unwrap_err();
    assert!(e.to_string().contains("report.json") && e.to_string().contains("disk on fire"));
    assert_eq!(std::fs::read_to_string(&dest).unwrap(), "old");
    assert_eq!(names(&d), ["report.json"]);
    // Dropped without a commit: nothing changes either.
    let mut f = igemu::output::AtomicFile::create(&dest).unwrap();
    f.write_all(b"never").unwrap();
    assert_eq!(temporaries(&d).len(), 1);
    drop(f);
    assert_eq!(names(&d), ["report.json"]);
    assert_eq!(std::fs::read_to_string(&dest).unwrap(), "old");
    igemu::output::write_file(&dest, "new").unwrap();
    assert_eq!(std::fs::read_to_string(&dest).unwrap(), "new");
    let mode = std::fs::metadata(&dest).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o640);
    assert_eq!(names(&d), ["report.json"]);
}

/// Every output flag that names an input file exits 2 naming the flag and the file, and the
/// input is unchanged.
#[test]
fn an_output_that_is_an_input_is_refused_and_the_input_is_unchanged() {
    let d = dir("inputs");
    let scene = d.join("scene.toml");
    std::fs::write(&scene, igemu::scene::EMBEDDED[0].1).unwrap();
    let hw = d.join("hw.toml");
    std::fs::write(&hw, "[gamma]\ndac_bits = 8\n").unwrap();
    let grid = d.join("grid.toml");
    std::fs::write(&grid, "gamma.dac_bits = [8, 9]\n").unwrap();
    let link = d.join("link.png");
    std::os::unix::fs::symlink(&scene, &link).unwrap();
    let roms = d.join("roms");
    std::fs::create_dir(&roms).unwrap();
    let rom_hw = roms.join("manifest.json");
    std::fs::write(&rom_hw, "[gamma]\ndac_bits = 8\n").unwrap();
    let bench = d.join("bench");
    std::fs::create_dir(&bench).unwrap();
    let bench_hw = bench.join("vectors.hex");
    std::fs::write(&bench_hw, "[gamma]\ndac_bits = 8\n").unwrap();
    let inputs = [&scene, &hw, &grid, &rom_hw, &bench_hw];
    let before: Vec<Vec<u8>> = inputs.iter().map(|p| std::fs::read(p).unwrap()).collect();
    let png = s(&d.join("ok.png"));
    let (sc, h, g) = (s(&scene), s(&hw), s(&grid));
    let (lk, rh, rd, bh, bd) = (s(&link), s(&rom_hw), s(&roms), s(&bench_hw), s(&bench));
    let rows = s(&d.join("rows.jsonl"));
    let dump = format!("accumulate={sc}");
    let cases: Vec<(Vec<&str>, &str, String)> = vec![
        (
            vec!["render", &sc, "-o", &png, "--report", &sc],
            "--report",
            sc.clone(),
        ),
        (vec!["render", &sc, "-o", &sc], "--out", sc.clone()),
        (vec!["render", &sc, "-o", &lk], "--out", lk.clone()),
        (
            vec!["render", &sc, "-o", &png, "--reference-out", &sc],
            "--reference-out",
            sc.clone(),
        ),
        (
            vec!["render", &sc, "-o", &png, "--diff-out", &sc],
            "--diff-out",
            sc.clone(),
        ),
        (
            vec!["render", &sc, "-o", &png, "--banding-out", &sc],
            "--banding-out",
            sc.clone(),
        ),
        (
            vec!["render", &sc, "-o", &png, "--dump", &dump],
            "--dump",
            sc.clone(),
        ),
        (
            vec!["render", "--hw", &h, "-o", &png, "--report", &h],
            "--report",
            h.clone(),
        ),
        (
            vec!["render", "--hw", &rh, "-o", &png, "--rom-out", &rd],
            "--rom-out",
            rh.clone(),
        ),
        (vec!["cycles", &sc, "--vcd", &sc], "--vcd", sc.clone()),
        (vec!["cycles", "--hw", &h, "--vcd", &h], "--vcd", h.clone()),
        (
            vec!["sweep", &sc, "--grid", &g, "--out", &g],
            "--out",
            g.clone(),
        ),
        (
            vec!["sweep", &sc, "--grid", &g, "--out", &sc],
            "--out",
            sc.clone(),
        ),
        (
            vec!["sweep", &sc, "--grid", &g, "--out", &rows, "--plot", &sc],
            "--plot",
            sc.clone(),
        ),
        (
            vec!["sweep", &sc, "--grid", &g, "--out", &rows, "--html", &g],
            "--html",
            g.clone(),
        ),
        (
            vec!["render", &sc, "-o", &png, "--html", &sc],
            "--html",
            sc.clone(),
        ),
        (
            vec![
                "hdl", "vectors", "--stage", "gamma", "--hw", &bh, "--out", &bd,
            ],
            "--out",
            bh.clone(),
        ),
    ];
    for (args, flag, file) in &cases {
        let (code, out, err) = igemu(args);
        assert_eq!(code, 2, "{args:?}: {out}{err}");
        assert!(
            err.contains(&format!("{flag}: {file} is ")) && err.contains("choose another path"),
            "{args:?}: {err}"
        );
    }
    for (p, b) in inputs.iter().zip(&before) {
        assert_eq!(&std::fs::read(p).unwrap(), b, "{} changed", p.display());
    }
    assert!(!d.join("ok.png").exists(), "refused before any work");
    assert!(!d.join("rows.jsonl").exists(), "refused before any work");
}

/// Two outputs of one render naming the same file (directly, through `..` or `./`, before
/// it exists) are refused before any work: the second would silently replace the first.
#[test]
fn two_outputs_on_one_path_are_refused() {
    let d = dir("same");
    let png = s(&d.join("x.png"));
    let dotdot = s(&d.join("..").join(d.file_name().unwrap()).join("x.png"));
    let dump = format!("accumulate={png}");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["render", "-o", &png, "--report", &png], "--report"),
        (
            vec!["render", "-o", &png, "--diff-out", &dotdot],
            "--diff-out",
        ),
        (vec!["render", "-o", &png, "--dump", &dump], "--dump"),
        (vec!["render", "-o", &png, "--html", &dotdot], "--html"),
        (
            vec![
                "sweep",
                "--grid",
                "examples/grid.toml",
                "--out",
                &png,
                "--html",
                &png,
            ],
            "--html",
        ),
        (
            vec![
                "render",
                "-o",
                &dotdot,
                "--reference-out",
                &png,
                "--banding-out",
                &png,
            ],
            "--reference-out",
        ),
    ];
    for (args, flag) in &cases {
        let (code, out, err) = igemu(args);
        assert_eq!(code, 2, "{args:?}: {out}{err}");
        assert!(
            err.contains(&format!("{flag}: ")) && err.contains("is also the output of --out"),
            "{args:?}: {err}"
        );
        assert!(names(&d).is_empty(), "{args:?}: refused before any work");
    }
}

/// Runs `igemu render --no-local ARGS` in the folder `d`: (exit code, stderr).
fn render_in(d: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::new(BIN)
        .current_dir(d)
        .args(["render", "--no-local"])
        .args(args)
        .output()
        .unwrap();
    let code = out.status.code().unwrap_or(-1);
    (code, String::from_utf8_lossy(&out.stderr).into())
}

/// An output path that cannot be written is refused before any work, naming the flag: an
/// empty path (the empty `--rom-out` wrote its hex files and manifest.json into the current
/// folder and exited 0), a folder given as a file, a file or a path inside a file given as
/// `--rom-out` (a raw "File exists (os error 17)" after o.png was written), and `--rom-out`
/// on another output's path or holding one (o.png written, then the error).
#[test]
fn unwritable_output_paths_and_rom_out_clashes_are_refused_before_any_work() {
    let d = dir("paths");
    std::fs::write(d.join("f.txt"), "keep").unwrap();
    std::fs::create_dir(d.join("roms")).unwrap();
    let before = names(&d);
    let cases: &[(&[&str], &str)] = &[
        (
            &["-o", "o.png", "--rom-out", ""],
            "--rom-out: '' is not a file name; name a folder",
        ),
        (&["-o", ""], "--out: '' is not a file name; name a file"),
        (
            &["-o", "o.png", "--report", ""],
            "--report: '' is not a file name",
        ),
        (
            &["-o", "o.png", "--html", ""],
            "--html: '' is not a file name",
        ),
        (
            &["-o", "o.png", "--diff-out", "x/"],
            "--diff-out: x/ is not a file name",
        ),
        (
            &["-o", "o.png", "--report", "roms"],
            "--report: roms is a folder",
        ),
        (
            &["-o", "o.png", "--rom-out", "f.txt"],
            "--rom-out: f.txt is a file, not a folder",
        ),
        (
            &["-o", "o.png", "--rom-out", "f.txt/roms"],
            "--rom-out: f.txt/roms is inside f.txt, which is a file",
        ),
        (
            &["-o", "o.png", "--rom-out", "o.png"],
            "--rom-out: o.png is also the output of --out",
        ),
        (
            &[
                "-o",
                "o.png",
                "--rom-out",
                "roms",
                "--report",
                "roms/manifest.json",
            ],
            "--rom-out: roms/manifest.json is also the output of --report",
        ),
        (
            // A hex file's name is known once the plan has run, still before any write.
            &["-o", "roms/gamma.gamma_rom.hex", "--rom-out", "roms"],
            "--rom-out: roms/gamma.gamma_rom.hex is also the output of --out",
        ),
    ];
    for (args, msg) in cases {
        let (code, err) = render_in(&d, args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(msg), "{args:?}: {err}");
        assert_eq!(names(&d), before, "{args:?}: nothing written");
        assert_eq!(names(&d.join("roms")), Vec::<String>::new(), "{args:?}");
    }
    assert_eq!(std::fs::read_to_string(d.join("f.txt")).unwrap(), "keep");
    // The same folder is fine as `--rom-out`, and `.` is the current one.
    let (code, err) = render_in(&d, &["-o", "o.png", "--rom-out", "."]);
    assert_eq!(code, 0, "{err}");
    assert!(d.join("manifest.json").exists() && d.join("o.png").exists());
}

/// Runs the binary with its stdout on a pipe whose reader is already closed: (exit code,
/// stderr).
fn with_closed_stdout(args: &[&str]) -> (i32, String) {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let out = Command::new(BIN)
        .args(args)
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// A closed stdout (`igemu render --json | head -c 10`) ends the program quietly with 0:
/// no message, no panic. (Before, every command panicked with exit 101.)
#[test]
fn a_closed_stdout_ends_quietly_with_exit_0() {
    let d = dir("pipe");
    let png = s(&d.join("out.png"));
    let dof = [
        "dof",
        "--f-number",
        "11",
        "--coc",
        "0.035",
        "--focal",
        "200",
        "--distance",
        "2500",
    ];
    let cases: Vec<Vec<&str>> = vec![
        vec!["render", "--no-local", "--json", "-o", &png],
        vec!["render", "--no-local", "-o", &png],
        vec!["widths", "--contrast", "100", "--weber", "0.02"],
        vec!["cycles"],
        vec!["ranges", "--export", "verilog"],
        dof.to_vec(),
        vec!["check"],
        vec!["--help"],
    ];
    for args in &cases {
        let (code, err) = with_closed_stdout(args);
        assert_eq!(code, 0, "{args:?}: {err}");
        assert_eq!(err, "", "{args:?}");
    }
}

/// Another write error on stdout (a full disk) exits 2 with the reason.
#[test]
fn a_full_stdout_exits_2() {
    let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
        return;
    };
    let out = Command::new(BIN)
        .args(["widths", "--contrast", "100", "--weber", "0.02"])
        .stdout(full)
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("stdout") && !err.contains("panicked"), "{err}");
}
