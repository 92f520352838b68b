//! The hardware configuration: formats, modes and structure of every stage.
//!
//! A config starts from a preset (`linear12` unless the file names another) and the
//! file overrides single fields. Every field is validated; errors name the file, the
//! line, the field and the allowed range.

use crate::error::FileError;
use crate::files::TomlFile;
use crate::fixed::{Overflow, QFormat, Quant, Quantizer};
use serde::{Deserialize, Serialize};

/// Largest gamma-LUT address width (the accumulator width): a 2^20-entry ROM.
pub const MAX_LUT_ADDRESS_BITS: u32 = 20;
/// Largest guard band beyond the screen edge, in pixels.
pub const MAX_GUARD_BAND: u32 = 4096;
/// Preset names, the first is the default.
pub const PRESETS: &[&str] = &[
    "linear12",
    "linear11",
    "linear8",
    "log8-potentiate",
    "log8-logadd",
    "log7-logadd",
];

/// Filter used to turn sub-pixel samples into pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FilterKind {
    /// 1-pixel base box (area sampling); equal energy.
    Box,
    /// 2x2-pixel base separable tent ("bed of nails"); equal energy.
    Tent,
    /// Gaussian over a 3x3-pixel base; not equal energy (the counter-example).
    Gaussian,
}

impl FilterKind {
    /// Base of the filter in pixels per axis.
    pub fn base(self) -> u32 {
        match self {
            FilterKind::Box => 1,
            FilterKind::Tent => 2,
            FilterKind::Gaussian => 3,
        }
    }
    /// Whether the filter is a partition of unity (equal energy).
    pub fn equal_energy(self) -> bool {
        !matches!(self, FilterKind::Gaussian)
    }
}

/// Input quantisation of screen-space vertices.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InputCfg {
    /// x and y; fraction bits are the sub-pixel bits.
    pub coord: Quantizer,
    /// Screen depth in [0, 1).
    pub z: Quantizer,
    /// Vertex intensity in accumulator codes (full white = 2^int_bits - 1).
    pub intensity: Quantizer,
}

/// Setup and raster.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RasterCfg {
    /// Samples per pixel along each axis (grid n x n).
    pub samples: u32,
    /// Extra fraction bits of the incremental interpolators and their gradients.
    pub interp_guard_bits: u32,
    /// Rounding of an interpolator to the sample's intensity / z format.
    pub interp_quant: Quant,
    /// Guard band beyond each screen edge, pixels (geometry is clipped to it on the host).
    pub guard_band: u32,
}

/// Per-sample z-buffer.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VisibilityCfg {
    /// Stored depth format and its quantisation from the interpolator.
    pub z: Quantizer,
}

/// Filtering and frame-memory accumulation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AccumulateCfg {
    /// The filter.
    pub filter: FilterKind,
    /// Fraction bits of the filter weights S: the weights of one pixel sum to exactly 2^weight_bits.
    pub weight_bits: u32,
    /// Gaussian sigma in pixels.
    pub gaussian_sigma: f64,
    /// Frame-memory word: rounding of each `I*S` product and overflow of the running sum.
    pub frame: Quantizer,
}

/// Gamma-correction LUT.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GammaCfg {
    /// DAC width in bits.
    pub dac_bits: u32,
    /// Rounding used when the LUT is built from the formula (and at the reference DAC).
    pub quant: Quant,
    /// Gamma the LUT corrects; `None` takes the scene's display gamma.
    pub gamma: Option<f64>,
    /// `false` models a system without gamma correction (a linear LUT).
    pub correction: bool,
}

/// The whole hardware configuration.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HwConfig {
    /// Preset or file name.
    pub name: String,
    /// Input quantisation.
    pub input: InputCfg,
    /// Setup and raster.
    pub raster: RasterCfg,
    /// Z-buffer.
    pub visibility: VisibilityCfg,
    /// Filter and accumulation.
    pub accumulate: AccumulateCfg,
    /// Gamma LUT.
    pub gamma: GammaCfg,
    /// Timing of the stages for the cycle model (`[cycles]`).
    pub cycles: crate::cycles::CyclesCfg,
    /// Dither (kind `none` plans no dither stage).
    pub dither: crate::stage::dither::DitherCfg,
    /// Depth of field (used only with a thin-lens camera).
    pub dof: crate::stage::dof::DofParams,
    /// Intensity coding of the stored samples and the frame memory (linear or log).
    pub coding: crate::stage::logdomain::CodingCfg,
}

const fn q(signed: bool, i: u32, f: u32, quant: Quant, overflow: Overflow) -> Quantizer {
    Quantizer::new(QFormat::new(signed, i, f), quant, overflow)
}

impl HwConfig {
    /// A preset by name.
    pub fn preset(name: &str) -> Option<HwConfig> {
        let (acc_bits, coding) = match name {
            "linear12" => (12, crate::stage::logdomain::CodingCfg::linear()),
            "linear11" => (11, crate::stage::logdomain::CodingCfg::linear()),
            "linear8" => (8, crate::stage::logdomain::CodingCfg::linear()),
            _ => (12, crate::stage::logdomain::CodingCfg::preset(name)?),
        };
        Some(HwConfig {
            name: name.to_string(),
            input: InputCfg {
                // Q13.4: +-4096 px at 1/16 px.
                coord: q(true, 13, 4, Quant::RndConv, Overflow::Sat),
                z: q(false, 0, 24, Quant::RndConv, Overflow::Sat),
                intensity: q(false, acc_bits, 4, Quant::RndConv, Overflow::Sat),
            },
            raster: RasterCfg {
                samples: 4,
                interp_guard_bits: 14,
                interp_quant: Quant::RndConv,
                guard_band: 64,
            },
            visibility: VisibilityCfg {
                z: q(false, 0, 24, Quant::Trn, Overflow::Sat),
            },
            accumulate: AccumulateCfg {
                filter: FilterKind::Tent,
                weight_bits: 10,
                gaussian_sigma: 0.5,
                frame: q(false, acc_bits, 0, Quant::RndConv, Overflow::Sat),
            },
            gamma: GammaCfg {
                dac_bits: 8,
                quant: Quant::RndConv,
                gamma: None,
                correction: true,
            },
            cycles: crate::cycles::CyclesCfg::default_for(acc_bits),
            dither: crate::stage::dither::DitherCfg::default(),
            dof: crate::stage::dof::DofParams {
                p: 0.1,
                k: 0.05,
                coef_bits: 12,
                alpha_bits: 12,
                guard_bits: 4,
                // x * coverage ((2^acc - 1) * 16 < 2^(acc + 4) for 4x4 samples) times the 2^12 tap sum.
                line_bits: acc_bits + 4 + 12,
                acc_bits: acc_bits + 4 + 24,
                max_half_size: 32,
                quant: Quant::RndConv,
                overflow: Overflow::Sat,
            },
            coding,
        })
    }

    /// The default configuration (`linear12`).
    pub fn default_config() -> HwConfig {
        Self::preset(PRESETS[0]).expect("the first preset exists")
    }

    /// Resolves `--hw` values: a preset name or a TOML file path.
    pub fn resolve(arg: Option<&str>) -> Result<HwConfig, FileError> {
        match arg {
            None => Ok(Self::default_config()),
            Some(a) => match Self::preset(a) {
                Some(p) => Ok(p),
                None if a.ends_with(".toml") || std::path::Path::new(a).exists() => {
                    Self::from_toml(&TomlFile::read(a)?)
                }
                None => Err(FileError {
                    file: "--hw".into(),
                    line: None,
                    col: None,
                    field: String::new(),
                    msg: format!(
                        "`{a}` is neither a preset ({}) nor a .toml file",
                        PRESETS.join(", ")
                    ),
                }),
            },
        }
    }

    /// Parses and validates a hardware file.
    pub fn from_toml(file: &TomlFile) -> Result<HwConfig, FileError> {
        let raw: RawHw = file.parse()?;
        let base = raw.preset.as_deref().unwrap_or(PRESETS[0]);
        let mut hw = Self::preset(base).ok_or_else(|| {
            file.error(
                "preset",
                format!("unknown preset `{base}`; allowed: {}", PRESETS.join(", ")),
            )
        })?;
        hw.name = file.name.clone();
        let intensity_given = raw.input.as_ref().is_some_and(|i| i.intensity.is_some());
        if let Some(i) = raw.input {
            set(&mut hw.input.coord.format, i.coord);
            set(&mut hw.input.coord.quant, i.quant);
            set(&mut hw.input.z.quant, i.quant);
            set(&mut hw.input.intensity.quant, i.quant);
            set(&mut hw.input.coord.overflow, i.overflow);
            set(&mut hw.input.z.overflow, i.overflow);
            set(&mut hw.input.intensity.overflow, i.overflow);
            set(&mut hw.input.z.format, i.z);
            set(&mut hw.input.intensity.format, i.intensity);
        }
        if let Some(r) = raw.raster {
            set(&mut hw.raster.samples, r.samples);
            set(&mut hw.raster.interp_guard_bits, r.interp_guard_bits);
            set(&mut hw.raster.interp_quant, r.interp_quant);
            set(&mut hw.raster.guard_band, r.guard_band);
        }
        if let Some(v) = raw.visibility {
            set(&mut hw.visibility.z.format, v.z);
            set(&mut hw.visibility.z.quant, v.quant);
        }
        if let Some(a) = raw.accumulate {
            set(&mut hw.accumulate.filter, a.filter);
            set(&mut hw.accumulate.weight_bits, a.weight_bits);
            set(&mut hw.accumulate.gaussian_sigma, a.gaussian_sigma);
            set(&mut hw.accumulate.frame.format, a.frame);
            set(&mut hw.accumulate.frame.quant, a.quant);
            set(&mut hw.accumulate.frame.overflow, a.overflow);
            // The vertex intensity follows the accumulator's integer width unless given.
            if a.frame.is_some() && !intensity_given {
                hw.input.intensity.format.int_bits = hw.accumulate.frame.format.int_bits;
            }
        }
        if let Some(g) = raw.gamma {
            set(&mut hw.gamma.dac_bits, g.dac_bits);
            set(&mut hw.gamma.quant, g.quant);
            if g.gamma.is_some() {
                hw.gamma.gamma = g.gamma;
            }
            set(&mut hw.gamma.correction, g.correction);
        }
        if let Some(c) = raw.cycles {
            c.apply(&mut hw.cycles);
        }
        if let Some(d) = raw.dither {
            d.apply(&mut hw.dither);
        }
        if let Some(d) = raw.dof {
            set(&mut hw.dof.p, d.p);
            set(&mut hw.dof.k, d.k);
            set(&mut hw.dof.coef_bits, d.coef_bits);
            set(&mut hw.dof.alpha_bits, d.alpha_bits);
            set(&mut hw.dof.guard_bits, d.guard_bits);
            set(&mut hw.dof.line_bits, d.line_bits);
            set(&mut hw.dof.acc_bits, d.acc_bits);
            set(&mut hw.dof.max_half_size, d.max_half_size);
            set(&mut hw.dof.quant, d.quant);
            set(&mut hw.dof.overflow, d.overflow);
        }
        if let Some(c) = raw.coding {
            c.apply(&mut hw.coding);
        }
        hw.validate()
            .map_err(|(field, msg)| file.error(&field, msg))?;
        Ok(hw)
    }

    /// Checks every field; returns the failing field path and a message with the allowed range.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let fmt = |field: &str, f: &QFormat| f.validate().map_err(|m| (field.to_string(), m));
        fmt("input.coord", &self.input.coord.format)?;
        fmt("input.z", &self.input.z.format)?;
        fmt("input.intensity", &self.input.intensity.format)?;
        fmt("visibility.z", &self.visibility.z.format)?;
        fmt("accumulate.frame", &self.accumulate.frame.format)?;
        let err = |field: &str, msg: String| Err((field.to_string(), msg));
        let c = &self.input.coord.format;
        if !c.signed {
            return err(
                "input.coord",
                format!("must be signed (Q...), got {c}: the guard band extends left of x = 0"),
            );
        }
        let n = self.raster.samples;
        if !matches!(n, 1 | 2 | 4 | 8) {
            return err(
                "raster.samples",
                format!("must be 1, 2, 4 or 8 (an n x n grid), got {n}"),
            );
        }
        let need_sub = n.trailing_zeros() + 1;
        if c.frac_bits < need_sub {
            return err(
                "input.coord",
                format!(
                    "has {} sub-pixel bits; a {n}x{n} sample grid needs at least {need_sub} (sample centres must fall on the coordinate grid)",
                    c.frac_bits
                ),
            );
        }
        if c.frac_bits > 12 {
            return err(
                "input.coord",
                format!(
                    "sub-pixel bits must be in {need_sub}..=12, got {}",
                    c.frac_bits
                ),
            );
        }
        if self.raster.interp_guard_bits > 24 {
            return err(
                "raster.interp_guard_bits",
                format!("must be in 0..=24, got {}", self.raster.interp_guard_bits),
            );
        }
        if self.raster.guard_band > MAX_GUARD_BAND {
            return err(
                "raster.guard_band",
                format!(
                    "must be in 0..={MAX_GUARD_BAND} pixels, got {}",
                    self.raster.guard_band
                ),
            );
        }
        for (field, f) in [
            ("input.z", &self.input.z.format),
            ("visibility.z", &self.visibility.z.format),
        ] {
            if f.signed || f.int_bits != 0 {
                return err(field, format!("must be UQ0.n (depth in [0,1)), got {f}"));
            }
        }
        if self.visibility.z.format.frac_bits > self.input.z.format.frac_bits {
            return err(
                "visibility.z",
                format!(
                    "{} is wider than the interpolated depth {}",
                    self.visibility.z.format, self.input.z.format
                ),
            );
        }
        let acc = &self.accumulate.frame.format;
        let int = &self.input.intensity.format;
        if acc.signed || int.signed {
            return err(
                "accumulate.frame",
                format!("intensity codes are unsigned (UQ), got {acc} and {int}"),
            );
        }
        if acc.int_bits == 0 || acc.int_bits > MAX_LUT_ADDRESS_BITS {
            return err(
                "accumulate.frame",
                format!(
                    "integer bits (the gamma LUT address) must be in 1..={MAX_LUT_ADDRESS_BITS}, got {}",
                    acc.int_bits
                ),
            );
        }
        if int.int_bits != acc.int_bits {
            return err(
                "input.intensity",
                format!(
                    "must have the accumulator's integer bits ({}) so full white is the same code, got {int}",
                    acc.int_bits
                ),
            );
        }
        let wb = self.accumulate.weight_bits;
        let min_wb = 2 * n.trailing_zeros();
        if wb < min_wb || wb > 16 {
            return err(
                "accumulate.weight_bits",
                format!(
                    "must be in {min_wb}..=16 for a {n}x{n} grid (each sample's share 2^w/n^2 must be an integer), got {wb}"
                ),
            );
        }
        let s = self.accumulate.gaussian_sigma;
        if !(s.is_finite() && (0.1..=2.0).contains(&s)) {
            return err(
                "accumulate.gaussian_sigma",
                format!("must be a finite number in 0.1..=2.0 pixels, got {s}"),
            );
        }
        let d = self.gamma.dac_bits;
        if !(1..=16).contains(&d) {
            return err("gamma.dac_bits", format!("must be in 1..=16, got {d}"));
        }
        if let Some(g) = self.gamma.gamma
            && !(g.is_finite() && g > 0.0 && g <= 5.0)
        {
            return err(
                "gamma.gamma",
                format!("must be a finite number in (0, 5], got {g}"),
            );
        }
        self.cycles.validate()?;
        self.dither.validate(acc.int_bits, d)?;
        crate::stage::dof::validate(&self.dof)?;
        self.coding.validate()?;
        if self.coding.kind == crate::stage::logdomain::CodingKind::LogAdd
            && self.dither.kind != crate::stage::dither::DitherKind::None
        {
            return err(
                "dither.kind",
                "dithering is modelled after the linear gamma LUT only; with coding.kind = \"log-add\" use kind = \"none\" (or log-potentiate)".into(),
            );
        }
        Ok(())
    }

    /// Sub-pixel bits of the vertex coordinates.
    pub fn subpixel_bits(&self) -> u32 {
        self.input.coord.format.frac_bits
    }
}

fn set<T>(dst: &mut T, v: Option<T>) {
    if let Some(v) = v {
        *dst = v;
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHw {
    preset: Option<String>,
    input: Option<RawInput>,
    raster: Option<RawRaster>,
    visibility: Option<RawVisibility>,
    accumulate: Option<RawAccumulate>,
    gamma: Option<RawGamma>,
    cycles: Option<crate::cycles::RawCycles>,
    dither: Option<crate::stage::dither::RawDither>,
    dof: Option<RawDof>,
    coding: Option<crate::stage::logdomain::RawCoding>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawInput {
    coord: Option<QFormat>,
    z: Option<QFormat>,
    intensity: Option<QFormat>,
    quant: Option<Quant>,
    overflow: Option<Overflow>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRaster {
    samples: Option<u32>,
    interp_guard_bits: Option<u32>,
    interp_quant: Option<Quant>,
    guard_band: Option<u32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawVisibility {
    z: Option<QFormat>,
    quant: Option<Quant>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAccumulate {
    filter: Option<FilterKind>,
    weight_bits: Option<u32>,
    gaussian_sigma: Option<f64>,
    frame: Option<QFormat>,
    quant: Option<Quant>,
    overflow: Option<Overflow>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGamma {
    dac_bits: Option<u32>,
    quant: Option<Quant>,
    gamma: Option<f64>,
    correction: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDof {
    p: Option<f64>,
    k: Option<f64>,
    coef_bits: Option<u32>,
    alpha_bits: Option<u32>,
    guard_bits: Option<u32>,
    line_bits: Option<u32>,
    acc_bits: Option<u32>,
    max_half_size: Option<u32>,
    quant: Option<Quant>,
    overflow: Option<Overflow>,
}
