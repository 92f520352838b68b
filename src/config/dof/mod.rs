//! `[dof]`: the depth-of-field stage (docs/dof.md): which method (`kind`), how the blur
//! per depth code is computed (`sigma`, `sigma_rom_bits`), the layered datapath's widths, and
//! the `[dof.luminance]` and `[dof.downsample]` methods' own sections.

mod downsample;
mod luminance;

pub use downsample::{
    DOWN_BITS, DOWN_FACTORS, DOWN_TAPS, DownsampleCfg, LeakGuard, RawDownsample, Reconstruction,
};
pub use luminance::{LuminanceCfg, RawLuminance};

use super::set;
use crate::fixed::{Overflow, Quant};
use serde::{Deserialize, Serialize};

/// The depth-of-field method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DofKind {
    /// Layered adaptive convolution of the depth image (one mask per depth layer).
    Layered,
    /// Luminance-aware blur: mean pre-blur, bright neighbours bleed into darker ones, blended
    /// with the sharp frame by the normalised blur factor.
    Luminance,
    /// Downsample to 1/16 of the area, separable Gaussian, blended with the sharp frame per
    /// pixel by the circle of confusion (Poisson-disc taps).
    Downsample,
}

impl DofKind {
    /// Every kind, in the order the docs list them.
    pub const ALL: [DofKind; 3] = [DofKind::Layered, DofKind::Luminance, DofKind::Downsample];

    /// The name in a hardware file.
    pub fn name(self) -> &'static str {
        match self {
            DofKind::Layered => "layered",
            DofKind::Luminance => "luminance",
            DofKind::Downsample => "downsample",
        }
    }
}

/// The shape of the layered method's mask for a blur radius `sigma` (`dof.kernel`,
/// docs/dof.md "Kernel shape"); quantised with the equal-energy property either way.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DofKernel {
    /// The paper's separable `exp(-r^2 / sigma^2)` (RMS radius `sigma / sqrt(2)`, wider than
    /// the lens's disc of radius `sigma`).
    Gaussian,
    /// The lens's own uniform disc of radius `|sigma|` (pixel-area weights), a direct 2-D
    /// filter: `(2M + 1)^2` taps.
    Disc,
    /// A separable Gaussian fitted to the disc: `exp(-r^2 / (s sigma)^2)` with the `s` that
    /// minimises the largest edge-profile difference to the disc.
    FittedGaussian,
}

impl DofKernel {
    /// Every kernel, in the order the docs list them.
    pub const ALL: [DofKernel; 3] = [
        DofKernel::Gaussian,
        DofKernel::Disc,
        DofKernel::FittedGaussian,
    ];

    /// The name in a hardware file.
    pub fn name(self) -> &'static str {
        match self {
            DofKernel::Gaussian => "gaussian",
            DofKernel::Disc => "disc",
            DofKernel::FittedGaussian => "fitted_gaussian",
        }
    }
}

/// How the blur per depth code is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SigmaForm {
    /// The paper's eq. 3: beyond the in-focus band the object distance is shifted by `deep`
    /// toward the focus, `sigma = K (1/U - 1/(D - deep))` (in front: `D + deep`); the
    /// hardware reads sigma from a ROM indexed by the top `sigma_rom_bits` of the depth code,
    /// interpolating linearly between entries.
    Paper,
    /// Shifted in inverse depth instead, so sigma is affine in the depth code: one multiply
    /// per pixel, no ROM (the first version's form).
    Affine,
}

impl SigmaForm {
    /// The name in a hardware file.
    pub fn name(self) -> &'static str {
        match self {
            SigmaForm::Paper => "paper",
            SigmaForm::Affine => "affine",
        }
    }
}

/// What a layer's compositing alpha is normalised by (`dof.alpha_norm`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AlphaNorm {
    /// By the blurred coverage of the layer and every layer behind it (docs/dof.md,
    /// "Seams"): where a surface crosses from one layer into a nearer one, the two blurred
    /// masks add up to one and nothing behind shows through; a third plane through the
    /// passes.
    Behind,
    /// By the in-image tap sum (the border renormalisation only): the plain back-to-front
    /// composite, which lets the background show through as a dark seam wherever a
    /// surface crosses a layer boundary.
    Image,
}

impl AlphaNorm {
    /// Every choice.
    pub const ALL: [AlphaNorm; 2] = [AlphaNorm::Behind, AlphaNorm::Image];

    /// The name in a hardware file.
    pub fn name(self) -> &'static str {
        match self {
            AlphaNorm::Behind => "behind",
            AlphaNorm::Image => "image",
        }
    }
}

/// When the depth-of-field stage runs against the accumulate stage (`dof.schedule`,
/// docs/cycles.md "Streamed depth of field"). Timing only: the images are the same.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DofSchedule {
    /// On the finished frame: accumulate writes the whole frame memory, then the stage runs.
    Frame,
    /// Streamed (the default): rows flow from accumulate into line buffers holding the
    /// largest blur radius of the plan, and a row starts as soon as the rows it reads are
    /// complete; accumulate stalls while the line buffers are full.
    #[default]
    Stream,
}

impl DofSchedule {
    /// Both schedules, the default first.
    pub const ALL: [DofSchedule; 2] = [DofSchedule::Stream, DofSchedule::Frame];

    /// The name in a hardware file.
    pub fn name(self) -> &'static str {
        match self {
            DofSchedule::Frame => "frame",
            DofSchedule::Stream => "stream",
        }
    }
}

/// `dof.sigma_rom_bits`: depth-code bits that index the sigma ROM (`2^bits + 1` entries
/// plus one for infinity).
pub const SIGMA_ROM_BITS: std::ops::RangeInclusive<u32> = 4..=16;

/// Largest configurable mask half-size M (pixels): a `(2M+1)`-tap line.
pub const MAX_HALF_SIZE_LIMIT: u32 = 64;

/// `dof.coef_bits`, `dof.alpha_bits`, `dof.guard_bits`, `dof.line_bits`, `dof.acc_bits`: the
/// ranges of the word widths.
pub const DOF_BITS: [(&str, u32, u32); 5] = [
    ("coef_bits", 4, 20),
    ("alpha_bits", 4, 24),
    ("guard_bits", 0, 16),
    ("line_bits", 8, 64),
    ("acc_bits", 8, 96),
];

/// The `[dof]` section: the depth-of-field stage (used only with a thin-lens camera).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DofCfg {
    /// The method.
    pub kind: DofKind,
    /// The mask shape of the layered method and the downsample method's small blur.
    pub kernel: DofKernel,
    /// When the stage runs: on the finished frame or streamed behind accumulate.
    pub schedule: DofSchedule,
    /// The blur per depth code.
    pub sigma: SigmaForm,
    /// Depth-code bits indexing the sigma ROM (`sigma = "paper"`).
    pub sigma_rom_bits: u32,
    /// Difference-degree threshold P of a layer, in (0, 1).
    pub p: f64,
    /// Mask cut ratio k (edge / centre), in (0, 1).
    pub k: f64,
    /// Fraction bits of the 1-D mask coefficients (UQ0.f; they sum to 2^f).
    pub coef_bits: u32,
    /// Fraction bits of the compositing alpha.
    pub alpha_bits: u32,
    /// What the compositing alpha is normalised by.
    pub alpha_norm: AlphaNorm,
    /// Guard fraction bits of the layer colour and the composite.
    pub guard_bits: u32,
    /// Width of the line-buffer word (horizontal-pass sum of `x * m`).
    pub line_bits: u32,
    /// Width of the vertical-pass accumulator.
    pub acc_bits: u32,
    /// Largest mask half-size M the hardware holds.
    pub max_half_size: u32,
    /// Rounding of the composite to the frame format.
    pub quant: Quant,
    /// Overflow of the line buffer and accumulator (SAT or ERROR).
    pub overflow: Overflow,
    /// The layered datapath detects 16x16 output tiles whose every pixel's mask window is
    /// uniform (same code, same layer, full coverage) and writes their value without the tap
    /// passes (docs/dof.md, "Uniform tiles"): a detection pre-scan per layer, fewer MACs and
    /// pass outputs. The outputs are the same either way; the emulator skips uniform windows
    /// regardless, this models a chip that does too.
    pub skip_uniform_tiles: bool,
    /// `[dof.luminance]`: the luminance-aware method.
    pub luminance: LuminanceCfg,
    /// `[dof.downsample]`: the downsample-and-blend method.
    pub downsample: DownsampleCfg,
}

impl DofCfg {
    /// Checks the `[dof]` fields; returns the failing field and the allowed range.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let p = self;
        let err = |f: &str, m: String| Err((format!("dof.{f}"), m));
        if !(p.p.is_finite() && p.p > 0.0 && p.p < 1.0) {
            return err(
                "p",
                format!(
                    "must be in (0, 1) (the layer difference-degree threshold), got {}",
                    crate::files::num(p.p)
                ),
            );
        }
        if !(p.k.is_finite() && p.k > 0.0 && p.k < 1.0) {
            return err(
                "k",
                format!(
                    "must be in (0, 1) (mask edge/centre ratio), got {}",
                    crate::files::num(p.k)
                ),
            );
        }
        let widths = [
            p.coef_bits,
            p.alpha_bits,
            p.guard_bits,
            p.line_bits,
            p.acc_bits,
        ];
        for ((field, lo, hi), v) in DOF_BITS.into_iter().zip(widths) {
            if !(lo..=hi).contains(&v) {
                return err(field, format!("must be in {lo}..={hi}, got {v}"));
            }
        }
        if !(1..=MAX_HALF_SIZE_LIMIT).contains(&p.max_half_size) {
            return err(
                "max_half_size",
                format!(
                    "must be in 1..={MAX_HALF_SIZE_LIMIT} pixels, got {}",
                    p.max_half_size
                ),
            );
        }
        if !matches!(p.overflow, Overflow::Sat | Overflow::Error) {
            return err(
                "overflow",
                format!("must be SAT or ERROR, got {:?}", p.overflow),
            );
        }
        if !SIGMA_ROM_BITS.contains(&p.sigma_rom_bits) {
            return err(
                "sigma_rom_bits",
                format!(
                    "must be in {}..={} (depth-code bits indexing the sigma ROM), got {}",
                    SIGMA_ROM_BITS.start(),
                    SIGMA_ROM_BITS.end(),
                    p.sigma_rom_bits
                ),
            );
        }
        if p.kernel == DofKernel::Disc && p.skip_uniform_tiles {
            return err(
                "skip_uniform_tiles",
                "must be false with dof.kernel = \"disc\" (the uniform-tile skip is the separable passes' option; the direct 2-D filter has none)".into(),
            );
        }
        p.luminance
            .validate()
            .map_err(|(f, m)| (format!("dof.luminance.{f}"), m))?;
        p.downsample
            .validate()
            .map_err(|(f, m)| (format!("dof.downsample.{f}"), m))?;
        Ok(())
    }
}

/// `[dof]` as written in the hardware file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDof {
    kind: Option<DofKind>,
    kernel: Option<DofKernel>,
    schedule: Option<DofSchedule>,
    sigma: Option<SigmaForm>,
    sigma_rom_bits: Option<u32>,
    p: Option<f64>,
    k: Option<f64>,
    coef_bits: Option<u32>,
    alpha_bits: Option<u32>,
    alpha_norm: Option<AlphaNorm>,
    guard_bits: Option<u32>,
    line_bits: Option<u32>,
    acc_bits: Option<u32>,
    max_half_size: Option<u32>,
    quant: Option<Quant>,
    overflow: Option<Overflow>,
    skip_uniform_tiles: Option<bool>,
    luminance: Option<RawLuminance>,
    downsample: Option<RawDownsample>,
}

impl RawDof {
    /// Overrides the given fields.
    pub(crate) fn apply(self, c: &mut DofCfg) {
        set(&mut c.kind, self.kind);
        set(&mut c.kernel, self.kernel);
        set(&mut c.schedule, self.schedule);
        set(&mut c.sigma, self.sigma);
        set(&mut c.sigma_rom_bits, self.sigma_rom_bits);
        set(&mut c.p, self.p);
        set(&mut c.k, self.k);
        set(&mut c.coef_bits, self.coef_bits);
        set(&mut c.alpha_bits, self.alpha_bits);
        set(&mut c.alpha_norm, self.alpha_norm);
        set(&mut c.guard_bits, self.guard_bits);
        set(&mut c.line_bits, self.line_bits);
        set(&mut c.acc_bits, self.acc_bits);
        set(&mut c.max_half_size, self.max_half_size);
        set(&mut c.quant, self.quant);
        set(&mut c.overflow, self.overflow);
        set(&mut c.skip_uniform_tiles, self.skip_uniform_tiles);
        if let Some(l) = self.luminance {
            l.apply(&mut c.luminance);
        }
        if let Some(d) = self.downsample {
            d.apply(&mut c.downsample);
        }
    }
}
