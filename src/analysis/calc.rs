//! Analytic calculators from the source papers (docs/reference.md §1, §2, §6): code widths for
//! intensity, DAC and log coding; thin-lens depth of field and circle of confusion; the
//! Gaussian mask size factor; the brightness error of an uncorrected CRT.

/// A number of levels and the width that holds them.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Levels {
    /// Levels needed (real-valued, as the equation gives it).
    pub levels: f64,
    /// `ceil(log2(levels))`: the narrowest code width with at least that many levels.
    pub bits: u32,
}

impl Levels {
    fn new(levels: f64) -> Self {
        // Smallest b with 2^b >= levels, exactly (no log2 rounding at powers of two).
        let mut bits = 0u32;
        while bits < 1024 && 2f64.powi(bits as i32) < levels {
            bits += 1;
        }
        Self { levels, bits }
    }
}

/// Intensity and DAC code widths for a contrast, Weber fraction and CRT gamma
/// (Kovalev & Tokarev, eq. 9–11).
#[derive(Clone, Debug, serde::Serialize)]
pub struct Widths {
    /// Contrast K = B_max / B_min.
    pub contrast: f64,
    /// Weber–Fechner fraction δ.
    pub weber: f64,
    /// CRT gamma γ.
    pub gamma: f64,
    /// Linear intensity code, eq. 9: `N_I = (K - 1) / δ`.
    pub linear: Levels,
    /// DAC levels after the gamma LUT, eq. 10: `N_U = ((K-1)^(1/γ) / δ) · (γ-1)^(1-1/γ)`.
    pub dac: Levels,
    /// Distinguishable grades for a log code, eq. 11: `m = ln K / ln(1 + δ)`.
    pub log_grades: Levels,
    /// Largest contrast an 8-bit linear code supports: `K = 1 + 256·δ`.
    pub linear8_max_contrast: f64,
}

/// Computes the code widths of docs/reference.md §1 (eq. 9, 10, 11).
///
/// Requires `contrast > 1`, `0 < weber < 1` and `gamma > 1` (eq. 10 takes
/// `(gamma - 1)^(1 - 1/gamma)`, undefined for gamma < 1 and degenerate at 1), all finite.
pub fn widths(contrast: f64, weber: f64, gamma: f64) -> Result<Widths, String> {
    if !(contrast.is_finite() && contrast > 1.0) {
        return Err(format!(
            "contrast K = {contrast}: must be a finite number > 1 (K = B_max / B_min)"
        ));
    }
    if !(weber.is_finite() && weber > 0.0 && weber < 1.0) {
        return Err(format!(
            "weber fraction delta = {weber}: must be in the open range (0, 1); typical 0.02 to 0.05"
        ));
    }
    if !(gamma.is_finite() && gamma > 1.0) {
        return Err(format!(
            "gamma = {gamma}: must be a finite number > 1 (eq. 10 uses (gamma - 1)^(1 - 1/gamma)); CRTs are about 2.2 to 2.8"
        ));
    }
    let k1 = contrast - 1.0;
    let linear = Levels::new(k1 / weber);
    let dac = Levels::new(k1.powf(1.0 / gamma) / weber * (gamma - 1.0).powf(1.0 - 1.0 / gamma));
    let log_grades = Levels::new(contrast.ln() / weber.ln_1p());
    Ok(Widths {
        contrast,
        weber,
        gamma,
        linear,
        dac,
        log_grades,
        linear8_max_contrast: 1.0 + 256.0 * weber,
    })
}

/// Thin-lens depth of field (docs/reference.md §2b). All lengths in the same unit (mm).
#[derive(Clone, Debug, serde::Serialize)]
pub struct DepthOfField {
    /// f-number N.
    pub f_number: f64,
    /// Permissible circle of confusion C.
    pub coc: f64,
    /// Focal length F.
    pub focal: f64,
    /// Focus distance L.
    pub distance: f64,
    /// Front depth of field `ΔL1 = N·C·L² / (F² + N·C·L)`.
    pub front: f64,
    /// Back depth of field `ΔL2 = N·C·L² / (F² - N·C·L)`; `f64::INFINITY` when `F² <= N·C·L`
    /// (at or beyond the hyperfocal distance).
    pub back: f64,
    /// `ΔL = ΔL1 + ΔL2` (infinite with `back`).
    pub total: f64,
    /// Near limit of sharpness `L - ΔL1`.
    pub near: f64,
    /// Far limit of sharpness `L + ΔL2` (infinite with `back`).
    pub far: f64,
    /// Hyperfocal distance `F² / (N·C)`: the focus distance where `ΔL2` becomes infinite in
    /// these formulae (the exact thin-lens value adds F).
    pub hyperfocal: f64,
}

/// Front/back depth of field for f-number `f_number`, permissible CoC `coc`, focal length
/// `focal` and focus distance `distance` (same length unit). All must be positive and finite,
/// and `distance > focal`.
pub fn depth_of_field(
    f_number: f64,
    coc: f64,
    focal: f64,
    distance: f64,
) -> Result<DepthOfField, String> {
    for (name, v) in [
        ("f_number", f_number),
        ("coc", coc),
        ("focal", focal),
        ("distance", distance),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(format!("{name} = {v}: must be a finite number > 0"));
        }
    }
    if distance <= focal {
        return Err(format!(
            "distance = {distance}: must be greater than the focal length ({focal}); a thin lens cannot focus closer"
        ));
    }
    let ncl = f_number * coc * distance;
    let f2 = focal * focal;
    let num = ncl * distance;
    let front = num / (f2 + ncl);
    let back = if f2 <= ncl {
        f64::INFINITY
    } else {
        num / (f2 - ncl)
    };
    Ok(DepthOfField {
        f_number,
        coc,
        focal,
        distance,
        front,
        back,
        total: front + back,
        near: distance - front,
        far: distance + back,
        hyperfocal: f2 / (f_number * coc),
    })
}

/// Circle of confusion of a point at `distance` L with the lens focused at `focus` U:
/// `C = F² / (U - F) · |L - U| / (N·L)` (docs/reference.md §2b, eq. 3 and 7). Same length unit for
/// all; no validation (U = F or L = 0 give infinities).
pub fn circle_of_confusion(focal: f64, f_number: f64, focus: f64, distance: f64) -> f64 {
    focal * focal / (focus - focal) * (distance - focus).abs() / (f_number * distance)
}

/// Gaussian mask half-size factor `sqrt(-ln k)`: the (2M+1)² mask is cut where edge/centre
/// is below `k`, so `M >= factor·|σ|` (docs/reference.md §2a, eq. 4); 1.731 for k = 0.05.
/// NaN unless `0 < k <= 1`.
pub fn gaussian_half_size_factor(k: f64) -> f64 {
    (-k.ln()).sqrt()
}

/// Relative brightness error of a unit object split equally over `split` pixels on a CRT
/// `B = U^γ` without gamma correction: `split · (1/split)^γ - 1`; -0.621 for γ = 2.4 and two
/// pixels. NaN for `split == 0`.
pub fn brightness_error_uncorrected(gamma: f64, split: usize) -> f64 {
    if split == 0 {
        return f64::NAN;
    }
    let n = split as f64;
    n * n.recip().powf(gamma) - 1.0
}
