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
}

/// Axis names accepted by `--axes`.
pub const AXES: &[&str] = &[
    "error",
    "max_error",
    "weber",
    "contours",
    "cost",
    "throughput",
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
        }
    }

    /// The row's value as shown (throughput positive).
    pub fn value(self, r: &Row) -> f64 {
        match self {
            Axis::Throughput => r.cycles.fps,
            _ => self.key(r),
        }
    }
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

/// An SVG of two panels, error against cost and error against throughput: every row grey,
/// the Pareto front of each panel's two axes in red and joined. Written by hand (no plotting
/// dependency); axis extremes are labelled.
pub fn svg(rows: &[Row], error: Axis) -> String {
    let (pw, ph, m) = (420.0, 320.0, 60.0);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
        2.0 * (pw + m) + m,
        ph + 2.0 * m
    );
    for (k, x_axis) in [Axis::Cost, Axis::Throughput].into_iter().enumerate() {
        let ox = m + k as f64 * (pw + m);
        let xs: Vec<f64> = rows.iter().map(|r| x_axis.value(r)).collect();
        let ys: Vec<f64> = rows.iter().map(|r| error.value(r)).collect();
        let range = |v: &[f64]| {
            let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if !(lo.is_finite() && hi.is_finite()) {
                (0.0, 1.0)
            } else if hi > lo {
                (lo, hi)
            } else {
                (lo - 0.5, hi + 0.5)
            }
        };
        let ((x0, x1), (y0, y1)) = (range(&xs), range(&ys));
        let px = |x: f64| ox + (x - x0) / (x1 - x0) * pw;
        let py = |y: f64| m + ph - (y - y0) / (y1 - y0) * ph;
        s += &format!(
            "<rect x=\"{ox}\" y=\"{m}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"black\"/>\n\
             <text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n\
             <text x=\"{}\" y=\"{}\" text-anchor=\"middle\" transform=\"rotate(-90 {} {})\">{}</text>\n\
             <text x=\"{ox}\" y=\"{}\">{x0:.4e}</text><text x=\"{}\" y=\"{}\" text-anchor=\"end\">{x1:.4e}</text>\n\
             <text x=\"{}\" y=\"{}\" text-anchor=\"end\">{y0:.3e}</text><text x=\"{}\" y=\"{}\" text-anchor=\"end\">{y1:.3e}</text>\n",
            ox + pw / 2.0,
            m + ph + 32.0,
            x_axis.name(),
            ox - 45.0,
            m + ph / 2.0,
            ox - 45.0,
            m + ph / 2.0,
            error.name(),
            m + ph + 14.0,
            ox + pw,
            m + ph + 14.0,
            ox - 3.0,
            m + ph,
            ox - 3.0,
            m + 10.0,
        );
        for (x, y) in xs.iter().zip(&ys) {
            s += &format!(
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"3\" fill=\"#999\"/>\n",
                px(*x),
                py(*y)
            );
        }
        let mut f = front(rows, &[error, x_axis]);
        f.sort_by(|&a, &b| xs[a].total_cmp(&xs[b]));
        let pts: Vec<String> = f
            .iter()
            .map(|&i| format!("{:.1},{:.1}", px(xs[i]), py(ys[i])))
            .collect();
        s += &format!(
            "<polyline points=\"{}\" fill=\"none\" stroke=\"red\"/>\n",
            pts.join(" ")
        );
        for &i in &f {
            s += &format!(
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"4\" fill=\"red\"><title>row {}</title></circle>\n",
                px(xs[i]),
                py(ys[i]),
                rows[i].index
            );
        }
    }
    s += "</svg>\n";
    s
}
