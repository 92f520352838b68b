//! Pareto fronts of sweep rows: the rows no other row beats on every chosen axis.

use super::Row;

/// An axis of the front.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// Mean Weber error through the display model (minimised): comparable across DAC widths,
    /// unlike code differences.
    Error,
    /// Mean |code difference| in DAC codes (minimised).
    CodeError,
    /// Largest |code difference| (minimised).
    MaxError,
    /// Largest Weber error (minimised).
    Weber,
    /// Visible contour steps (minimised).
    Contours,
    /// Storage + LUT bits (minimised).
    Cost,
    /// Frames per second (maximised).
    Throughput,
    /// Largest displayed ripple of a small moving object, % (minimised; needs `--flicker`).
    Flicker,
    /// Mean Weber error of the fixed pipeline against the depth-of-field truth (minimised;
    /// needs `--dof-truth`).
    TruthTotal,
    /// Mean Weber error of the float reference pipeline against the truth: the method's.
    TruthAlgorithm,
    /// Mean Weber error of the fixed pipeline against the float reference, from the truth's
    /// split (the same images as `error`).
    TruthQuantisation,
    /// The emulator's fixed-model milliseconds for the row's configuration (minimised):
    /// speed against error.
    EmulatorTime,
    /// Mean CIEDE2000 of the fixed against the float image (minimised; a colour render).
    DeltaE,
    /// The 99th percentile of CIEDE2000 (minimised; a colour render).
    DeltaEP99,
    /// Mean hue shift on smooth chromatic surfaces, degrees (minimised; a colour render).
    HueShift,
}

/// Axis names accepted by `--axes`.
pub const AXES: &[&str] = &[
    "error",
    "code_error",
    "max_error",
    "weber",
    "contours",
    "cost",
    "throughput",
    "flicker",
    "truth_total",
    "truth_algorithm",
    "truth_quantisation",
    "emulator_time",
    "delta_e",
    "delta_e_p99",
    "hue_shift",
];

impl Axis {
    /// Parses an axis name.
    pub fn parse(s: &str) -> Result<Axis, String> {
        Ok(match s.trim() {
            "error" => Axis::Error,
            "code_error" => Axis::CodeError,
            "max_error" => Axis::MaxError,
            "weber" => Axis::Weber,
            "contours" => Axis::Contours,
            "cost" => Axis::Cost,
            "throughput" | "fps" => Axis::Throughput,
            "flicker" => Axis::Flicker,
            "truth_total" => Axis::TruthTotal,
            "truth_algorithm" => Axis::TruthAlgorithm,
            "truth_quantisation" => Axis::TruthQuantisation,
            "emulator_time" => Axis::EmulatorTime,
            "delta_e" => Axis::DeltaE,
            "delta_e_p99" => Axis::DeltaEP99,
            "hue_shift" => Axis::HueShift,
            other => {
                return Err(format!(
                    "unknown axis `{other}`; allowed: {}",
                    AXES.join(", ")
                ));
            }
        })
    }

    /// Parses a comma-separated list of at least two distinct axes.
    pub fn parse_list(s: &str) -> Result<Vec<Axis>, String> {
        let v: Vec<Axis> = s.split(',').map(Axis::parse).collect::<Result<_, _>>()?;
        if v.len() < 2 {
            return Err(format!(
                "give at least two axes (e.g. error,cost), got `{s}`"
            ));
        }
        for (i, a) in v.iter().enumerate() {
            if v[..i].contains(a) {
                return Err(format!("axis {a:?} given twice in `{s}`"));
            }
        }
        Ok(v)
    }

    /// Display name.
    pub fn name(self) -> &'static str {
        match self {
            Axis::Error => "mean Weber error",
            Axis::CodeError => "mean code diff",
            Axis::MaxError => "max code diff",
            Axis::Weber => "max Weber error",
            Axis::Contours => "contour steps",
            Axis::Cost => "storage + LUT bits",
            Axis::Throughput => "frames/s",
            Axis::Flicker => "displayed flicker ripple %",
            Axis::TruthTotal => "Weber vs truth",
            Axis::TruthAlgorithm => "float Weber vs truth",
            Axis::TruthQuantisation => "Weber fixed vs float",
            Axis::EmulatorTime => "emulator fixed ms",
            Axis::DeltaE => "mean CIEDE2000",
            Axis::DeltaEP99 => "p99 CIEDE2000",
            Axis::HueShift => "mean hue shift deg",
        }
    }

    /// The row's value on this axis, oriented so that smaller is better.
    pub fn key(self, r: &Row) -> f64 {
        match self {
            Axis::Error => r.error.weber_mean,
            Axis::CodeError => r.error.mean_code_diff,
            Axis::MaxError => r.error.max_code_diff as f64,
            Axis::Weber => r.error.weber_max,
            Axis::Contours => r.error.contour_steps as f64,
            Axis::Cost => (r.cost.storage_bits + r.cost.lut_bits) as f64,
            Axis::Throughput => -r.cycles.fps,
            Axis::Flicker => r
                .flicker
                .as_ref()
                .map_or(f64::INFINITY, |f| f.displayed_ripple_pct),
            Axis::TruthTotal => truth(r, |t| t.total.whole.weber_mean),
            Axis::TruthAlgorithm => truth(r, |t| t.algorithm.whole.weber_mean),
            Axis::TruthQuantisation => truth(r, |t| t.quantisation.whole.weber_mean),
            Axis::EmulatorTime => r.timing.fixed_ms,
            Axis::DeltaE => colour(r, |c| c.delta_e_mean),
            Axis::DeltaEP99 => colour(r, |c| c.delta_e_p99),
            Axis::HueShift => colour(r, |c| c.hue_shift_mean_deg),
        }
    }

    /// Whether the axis reads the colour error of a colour render.
    pub fn needs_colour(self) -> bool {
        matches!(self, Axis::DeltaE | Axis::DeltaEP99 | Axis::HueShift)
    }

    /// The name `--axes` takes for this axis.
    pub fn arg(self) -> &'static str {
        AXES.iter()
            .copied()
            .find(|a| Axis::parse(a) == Ok(self))
            .unwrap_or("?")
    }

    /// Whether the axis reads the depth-of-field truth (`--dof-truth`).
    pub fn needs_truth(self) -> bool {
        matches!(
            self,
            Axis::TruthTotal | Axis::TruthAlgorithm | Axis::TruthQuantisation
        )
    }

    /// The row's value as shown (throughput positive).
    pub fn value(self, r: &Row) -> f64 {
        match self {
            Axis::Throughput => r.cycles.fps,
            _ => self.key(r),
        }
    }

    /// Whether the axis counts (bits, steps, codes): its values are integers.
    pub fn is_integer(self) -> bool {
        matches!(self, Axis::Cost | Axis::Contours | Axis::MaxError)
    }

    /// A value of this axis as text: an integer axis without decimals (`264687504`), else
    /// four decimals; `-` where the row has no value (no truth, no colour).
    pub fn show(self, v: f64) -> String {
        if !v.is_finite() {
            "-".into()
        } else if self.is_integer() {
            format!("{v:.0}")
        } else {
            format!("{v:.4}")
        }
    }

    /// Whether the axis compares each configuration with its own float reference (the
    /// same algorithm in f64): blind to how far a depth-of-field method is from a thin lens.
    pub fn against_own_reference(self) -> bool {
        matches!(
            self,
            Axis::Error | Axis::CodeError | Axis::MaxError | Axis::Weber | Axis::Contours
        )
    }
}

/// The `dof.*` fields a grid varies (values that differ between its configurations).
pub fn varied_dof_fields(configs: &[super::grid::Config]) -> Vec<String> {
    let mut keys: Vec<&String> = configs
        .iter()
        .flat_map(|c| c.fields.keys())
        .filter(|k| k.starts_with("dof."))
        .collect();
    keys.sort();
    keys.dedup();
    keys.into_iter()
        .filter(|k| {
            let first = configs.first().and_then(|c| c.fields.get(*k));
            configs.iter().any(|c| c.fields.get(*k) != first)
        })
        .cloned()
        .collect()
}

/// The axes a sweep ranks on when `--axes` is not given: `error,cost`, or `truth_total,cost`
/// when the grid varies `dof.*` fields and the truth is computed (`--dof-truth`).
pub fn default_axes(configs: &[super::grid::Config], dof_truth: bool) -> Vec<Axis> {
    if dof_truth && !varied_dof_fields(configs).is_empty() {
        vec![Axis::TruthTotal, Axis::Cost]
    } else {
        vec![Axis::Error, Axis::Cost]
    }
}

/// The warning of a ranking that misleads: the grid varies `dof.*` fields while an axis
/// compares each configuration with its own float reference, so a method is measured
/// against itself in f64 (its quantisation), not against a thin lens. `None` otherwise.
pub fn dof_axes_warning(configs: &[super::grid::Config], axes: &[Axis]) -> Option<String> {
    let dof = varied_dof_fields(configs);
    let own: Vec<&str> = axes
        .iter()
        .filter(|a| a.against_own_reference())
        .map(|a| a.arg())
        .collect();
    if dof.is_empty() || own.is_empty() {
        return None;
    }
    Some(format!(
        "the grid varies {} but the axis {} compares each configuration with its own float reference (the same depth-of-field method in f64): it ranks quantisation, not how close a method comes to a thin lens; add --dof-truth and rank on truth_total (e.g. --axes truth_total,cost; docs/dof-truth.md)",
        dof.join(", "),
        own.join(", ")
    ))
}

/// A truth metric of a row; a row without the truth (a pinhole scene, or no `--dof-truth`)
/// is worst.
fn truth(r: &Row, f: impl Fn(&super::TruthMetrics) -> f64) -> f64 {
    r.truth.as_ref().map_or(f64::INFINITY, f)
}

/// A colour metric of a row; a row without colour (a grey render) is worst.
fn colour(r: &Row, f: impl Fn(&super::ColourMetrics) -> f64) -> f64 {
    r.colour.as_ref().map_or(f64::INFINITY, f)
}

/// Whether `a` dominates `b`: no worse on every axis and better on one.
pub fn dominates(a: &Row, b: &Row, axes: &[Axis]) -> bool {
    let mut better = false;
    for &ax in axes {
        let (x, y) = (ax.key(a), ax.key(b));
        if x > y {
            return false;
        }
        if x < y {
            better = true;
        }
    }
    better
}

/// Indices of the non-dominated rows, ordered by the first axis then the row index.
/// Rows of different scenes are never compared with each other.
pub fn front(rows: &[Row], axes: &[Axis]) -> Vec<usize> {
    let mut out: Vec<usize> = (0..rows.len())
        .filter(|&i| {
            !rows
                .iter()
                .any(|o| o.scene == rows[i].scene && dominates(o, &rows[i], axes))
        })
        .collect();
    out.sort_by(|&a, &b| {
        rows[a]
            .scene
            .cmp(&rows[b].scene)
            .then(axes[0].key(&rows[a]).total_cmp(&axes[0].key(&rows[b])))
            .then(rows[a].index.cmp(&rows[b].index))
    });
    out
}

/// Refuses a colour axis (`delta_e`, `delta_e_p99`, `hue_shift`) on a sweep with a job that
/// renders grey (one channel: a grey scene on hardware without per-channel widths), naming
/// the axis, the scene and the configuration.
pub fn check_colour_axes(
    axes: &[Axis],
    configs: &[super::grid::Config],
    scenes: &[crate::scene::Scene],
) -> Result<(), String> {
    let Some(axis) = axes.iter().find(|a| a.needs_colour()) else {
        return Ok(());
    };
    for c in configs {
        for s in scenes {
            if crate::pipeline::plan::channels(s, &c.hw) == 1 {
                return Err(format!(
                    "the {} axis needs a colour scene: scene `{}` renders one grey channel under configuration {} ({}); sweep a colour scene (e.g. default-colour, or `colour = true` in its [image]) or per-channel widths (e.g. `accumulate.frame = [[\"UQ5.0\", \"UQ6.0\", \"UQ5.0\"]]`)",
                    axis.arg(),
                    s.name,
                    c.index,
                    c.canonical
                ));
            }
        }
    }
    Ok(())
}

/// Refuses a colour axis on rows of which one has no colour metrics (a grey render's row,
/// `igemu sweep merge`).
pub fn check_colour_rows(axes: &[Axis], rows: &[Row]) -> Result<(), String> {
    let Some(axis) = axes.iter().find(|a| a.needs_colour()) else {
        return Ok(());
    };
    match rows.iter().find(|r| r.colour.is_none()) {
        None => Ok(()),
        Some(r) => Err(format!(
            "the {} axis needs a colour scene: row {} (scene `{}`) is a grey render's and has no colour metrics",
            axis.arg(),
            r.index,
            r.scene
        )),
    }
}
