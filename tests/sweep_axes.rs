//! What a sweep ranks on and how it shows it (issue 30): a grid varying `dof.*` ranked on an
//! axis that compares each configuration with its own float reference is warned about, and
//! with `--dof-truth` ranks on the truth by default; the Pareto plot labels each front point
//! with its row index; counts (bits, steps) print as integers.

mod common;

use common::{igemu, run_sweep, small_sweep};
use igemu::files::TomlFile;
use igemu::scene::Scene;
use igemu::sweep::grid::{Config, Grid};
use igemu::sweep::pareto::{self, Axis};

fn configs(text: &str) -> Vec<Config> {
    let f = TomlFile::from_text("g.toml", text);
    Grid::parse(&f).expect("grid").expand(&f).expect("configs")
}

#[test]
fn a_dof_grid_on_its_own_reference_is_warned_and_defaults_to_the_truth() {
    let kind = configs("dof.kind = [\"layered\", \"luminance\", \"downsample\"]\n");
    assert_eq!(pareto::varied_dof_fields(&kind), ["dof.kind"]);
    let w = pareto::dof_axes_warning(&kind, &[Axis::Error, Axis::Throughput]).expect("warned");
    assert!(
        w.contains("dof.kind") && w.contains("error") && w.contains("--dof-truth"),
        "{w}"
    );
    assert!(pareto::dof_axes_warning(&kind, &[Axis::TruthTotal, Axis::Cost]).is_none());
    assert_eq!(
        pareto::default_axes(&kind, true),
        [Axis::TruthTotal, Axis::Cost]
    );
    assert_eq!(
        pareto::default_axes(&kind, false),
        [Axis::Error, Axis::Cost]
    );
    // DoF parameters too, with another field beside them; a field held at one value is not varied.
    let p = configs("dof.p = [0.01, 0.2]\ndof.coef_bits = [8]\ngamma.dac_bits = [8, 9]\n");
    assert_eq!(pareto::varied_dof_fields(&p), ["dof.p"]);
    assert!(pareto::dof_axes_warning(&p, &[Axis::MaxError, Axis::Cost]).is_some());
    // A grid without dof.* fields: no warning, the usual default.
    let g = configs("gamma.dac_bits = [8, 9]\n");
    assert!(pareto::varied_dof_fields(&g).is_empty());
    assert!(pareto::dof_axes_warning(&g, &[Axis::Error, Axis::Cost]).is_none());
    assert_eq!(pareto::default_axes(&g, true), [Axis::Error, Axis::Cost]);
}

#[test]
fn the_command_line_warns_on_a_dof_grid() {
    let dir = std::env::temp_dir().join(format!("igemu-sweep-axes-{}", std::process::id()));
    let (scenes, _) = small_sweep(&dir);
    let grid = dir.join("dof.toml");
    std::fs::write(&grid, "dof.kind = [\"layered\", \"downsample\"]\n").expect("grid");
    let out = dir.join("rows.jsonl");
    let args = [
        "sweep",
        &scenes[0],
        "--grid",
        grid.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    let (code, stdout, stderr) = igemu(&args);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("warning: the grid varies dof.kind"),
        "{stderr}"
    );
    assert!(
        stdout.contains("mean Weber error x storage + LUT bits"),
        "{stdout}"
    );
    // Ranked on the truth: no warning.
    let mut truth = args.to_vec();
    truth.extend([
        "--resume",
        "--axes",
        "truth_total,cost",
        "--dof-truth",
        "--lens-samples",
        "8",
    ]);
    let (code, _, stderr) = igemu(&truth);
    assert_eq!(code, 0, "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn counts_print_as_integers_and_front_points_are_labelled() {
    let dir = std::env::temp_dir().join(format!("igemu-sweep-labels-{}", std::process::id()));
    let (scenes, grid) = small_sweep(&dir);
    // The printed front: the cost column is an integer, the error column has decimals.
    let out = dir.join("rows.jsonl");
    let (code, stdout, stderr) = igemu(&[
        "sweep",
        &scenes[0],
        "--grid",
        &grid,
        "--out",
        out.to_str().unwrap(),
        "--axes",
        "error,cost",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let rows: Vec<&str> = stdout.lines().skip(2).collect();
    assert!(!rows.is_empty(), "{stdout}");
    for l in &rows {
        let f: Vec<&str> = l.split_whitespace().collect();
        assert!(f[2].contains('.'), "error with decimals: {l}");
        assert!(f[3].parse::<u64>().is_ok(), "cost as an integer: {l}");
    }
    assert_eq!(Axis::Cost.show(264687504.0), "264687504");
    assert_eq!(Axis::Contours.show(3.0), "3");
    assert_eq!(Axis::Error.show(0.5), "0.5000");
    assert_eq!(Axis::TruthTotal.show(f64::INFINITY), "-");
    // The plot: every front point of each panel labelled `#index`, no other row.
    let text = std::fs::read_to_string(&grid).expect("grid");
    let cfgs = configs(&text);
    let scene = Scene::load(&scenes[0]).expect("scene");
    let rows_path = dir.join("lib.jsonl");
    let s = run_sweep(rows_path.to_str().unwrap(), &cfgs, &[scene], false);
    let axes = [Axis::Error, Axis::Cost];
    // plotters writes a text's content on its own line: joined, a label reads `>#3<`.
    let svg: String = igemu::sweep::plot::svg(&s.rows, &axes)
        .expect("svg")
        .lines()
        .map(str::trim)
        .collect();
    let mut labelled = std::collections::BTreeSet::new();
    for panel in igemu::sweep::plot::panel_axes(&axes) {
        for i in pareto::front(&s.rows, &[Axis::Error, panel]) {
            labelled.insert(s.rows[i].index);
        }
    }
    for r in &s.rows {
        let tag = format!(">#{}<", r.index);
        assert_eq!(
            svg.contains(&tag),
            labelled.contains(&r.index),
            "row {}",
            r.index
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
