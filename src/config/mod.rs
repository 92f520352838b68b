//! The hardware configuration: formats, modes and structure of every stage, one section per
//! stage (and `[cycles]` for the timing), the presets, the TOML overlay and the validation.
//!
//! A config starts from a preset (`linear12` unless the file names another) and the file
//! overrides single fields. Every field is validated; errors name the file, the line, the
//! field and the allowed range.
//!
//! This module sits below the stages: it imports nothing from `stage`, `pipeline`,
//! `cycles`, `sweep` or `hdl` (docs/STRUCTURE.md).

mod accumulate;
mod coding;
mod cycles;
mod dither;
mod dof;
mod gamma;
mod input;
mod overlay;
mod presets;
mod raster;
mod schema;
mod visibility;

pub use accumulate::{
    AccumulateCfg, FilterKind, GAUSSIAN_SIGMA, MAX_WEIGHT_BITS, MITCHELL_BC, MitchellBc,
};
pub use coding::{
    ACC_FRAC_BITS, CodingCfg, CodingKind, MAX_LOG_BITS, MIN_LOG_BITS, TABLE_ADDR_BITS,
    TABLE_FRAC_BITS,
};
pub use cycles::{
    CLOCK_MHZ, CyclesCfg, FRAME_PORT_BITS, StageTiming, TILE, TIMED, TIMING_RANGES, check_clock,
};
pub use dither::FRAC_BITS as DITHER_FRAC_BITS;
pub use dither::{
    BLUE_NOISE_SIZES, DitherCfg, DitherKind, ERROR_INT_BITS, MAX_ERROR_FRAC_BITS, Placement,
};
pub use dof::{
    AlphaNorm, DOF_BITS, DofCfg, DofKernel, DofKind, DofSchedule, DownsampleCfg, LuminanceCfg,
    MAX_HALF_SIZE_LIMIT, SIGMA_ROM_BITS, SigmaForm,
};
pub use dof::{DOWN_BITS, DOWN_FACTORS, DOWN_TAPS, LeakGuard, Reconstruction};
pub use gamma::{DAC_BITS, GammaCfg, MAX_GAMMA};
pub use input::InputCfg;
pub use presets::PRESETS;
pub use raster::{INTERP_GUARD_BITS, MAX_GUARD_BAND, RasterCfg};
pub use visibility::VisibilityCfg;

use crate::error::FileError;
use crate::files::{Source, TomlFile};
use crate::fixed::QFormat;
use serde::Serialize;

/// Largest gamma-LUT address width (the accumulator width): a 2^20-entry ROM.
pub const MAX_LUT_ADDRESS_BITS: u32 = 20;

/// Most sub-pixel bits of `input.coord` (the least is `log2(samples) + 1`).
pub const MAX_SUBPIXEL_BITS: u32 = 12;

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
    pub cycles: CyclesCfg,
    /// Dither (kind `none` plans no dither stage).
    pub dither: DitherCfg,
    /// Depth of field (used only with a thin-lens camera).
    pub dof: DofCfg,
    /// Intensity coding of the stored samples and the frame memory (linear or log).
    pub coding: CodingCfg,
    /// The file (and preset) it was read from: later checks locate its fields
    /// ([`HwConfig::error`]).
    #[serde(skip)]
    pub source: Source,
    /// Per-channel word widths of a colour datapath (`None`: every channel has the widths
    /// above). See [`HwConfig::channel`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub channels: Option<ChannelWidths>,
}

/// The word widths of each channel (R, G, B) of a colour datapath: given when the hardware
/// file writes `input.intensity`, `accumulate.frame` or `gamma.dac_bits` as an array of
/// three (`accumulate.frame = ["UQ5.0", "UQ6.0", "UQ5.0"]`; a scalar means all three). A
/// channel's `input.intensity` follows its frame word's integer bits unless given.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ChannelWidths {
    /// `input.intensity` per channel.
    pub intensity: [QFormat; 3],
    /// `accumulate.frame` per channel.
    pub frame: [QFormat; 3],
    /// `gamma.dac_bits` per channel.
    pub dac_bits: [u32; 3],
}

/// A field that is one value for every channel or an array of three (R, G, B).
#[derive(Clone, Copy, Debug, serde::Deserialize)]
#[serde(untagged)]
pub(crate) enum PerChannel<T> {
    /// The same value in every channel.
    One(T),
    /// One value per channel.
    Three([T; 3]),
}

impl<T: Copy> PerChannel<T> {
    /// Channel 0's value (what the scalar field holds).
    pub(crate) fn first(&self) -> T {
        match self {
            PerChannel::One(v) => *v,
            PerChannel::Three(v) => v[0],
        }
    }
    /// The three values, when given per channel.
    pub(crate) fn three(&self) -> Option<[T; 3]> {
        match self {
            PerChannel::One(_) => None,
            PerChannel::Three(v) => Some(*v),
        }
    }
}

/// Overrides `dst` when `v` is given (the overlay's one operation).
pub(crate) fn set<T>(dst: &mut T, v: Option<T>) {
    if let Some(v) = v {
        *dst = v;
    }
}

impl HwConfig {
    /// A preset by name.
    pub fn preset(name: &str) -> Option<HwConfig> {
        presets::preset(name)
    }

    /// Whether the channels have their own word widths (a colour datapath: the pipeline
    /// renders three channels even for a grey scene).
    pub fn per_channel(&self) -> bool {
        self.channels.is_some()
    }

    /// The configuration of channel `c` (0 R, 1 G, 2 B): these fields with channel `c`'s
    /// word widths, and no per-channel widths left. What the stages of a channel's lane read.
    pub fn channel(&self, c: usize) -> HwConfig {
        let mut hw = self.clone();
        if let Some(w) = hw.channels.take() {
            hw.input.intensity.format = w.intensity[c];
            hw.accumulate.frame.format = w.frame[c];
            hw.gamma.dac_bits = w.dac_bits[c];
        }
        hw
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
                        "`{a}` is neither a preset ({}) nor a .toml file{}",
                        PRESETS.join(", "),
                        if crate::scene::names().contains(&a) {
                            format!(
                                "; `{a}` is an embedded scene: give it as the SCENE argument instead of --hw"
                            )
                        } else {
                            crate::files::nearest(a, PRESETS)
                                .map_or(String::new(), |n| format!("; did you mean `{n}`?"))
                        }
                    ),
                }),
            },
        }
    }

    /// Parses and validates a hardware file.
    pub fn from_toml(file: &TomlFile) -> Result<HwConfig, FileError> {
        let hw = overlay::apply_file(file)?;
        hw.validate()
            .map_err(|(field, msg)| file.error(&field, msg))?;
        Ok(hw)
    }

    /// An error at a hardware field, found after parsing (a check against the scene): at
    /// its file and line when the hardware file gives the field, else naming the file or
    /// the preset.
    pub fn error(&self, field: &str, msg: impl Into<String>) -> FileError {
        self.source.error(&self.name, field, msg)
    }

    /// What a hardware field expects, by dotted path (`accumulate.weight_bits` -> `an
    /// integer in 2 log2(raster.samples)..=16`): the type and range that messages name.
    /// `None` for a path that is not a field.
    pub fn field_hint(path: &str) -> Option<String> {
        schema::hint(path)
    }

    /// A section as JSON, by its name in the file (`"accumulate"`, `"dof"`, ...): the key
    /// material of the stages that read it.
    pub fn section(&self, name: &str) -> serde_json::Value {
        let mut v = serde_json::to_value(self).unwrap_or_default();
        v.get_mut(name)
            .map(serde_json::Value::take)
            .unwrap_or_default()
    }

    /// Checks every field; returns the failing field path and a message with the allowed range.
    pub fn validate(&self) -> Result<(), (String, String)> {
        if self.channels.is_some() {
            // Every channel's datapath is a whole configuration of its own.
            for c in 0..3 {
                self.channel(c)
                    .validate()
                    .map_err(|(f, m)| (f, format!("{m} (channel {})", ["R", "G", "B"][c])))?;
            }
            return Ok(());
        }
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
        if c.frac_bits > MAX_SUBPIXEL_BITS {
            return err(
                "input.coord",
                format!(
                    "sub-pixel bits must be in {need_sub}..={MAX_SUBPIXEL_BITS}, got {}",
                    c.frac_bits
                ),
            );
        }
        let g = self.raster.interp_guard_bits;
        if !INTERP_GUARD_BITS.contains(&g) {
            return err(
                "raster.interp_guard_bits",
                format!(
                    "must be in {}..={}, got {g}",
                    INTERP_GUARD_BITS.start(),
                    INTERP_GUARD_BITS.end()
                ),
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
        if wb < min_wb || wb > MAX_WEIGHT_BITS {
            return err(
                "accumulate.weight_bits",
                format!(
                    "must be in {min_wb}..={MAX_WEIGHT_BITS} for a {n}x{n} grid (each sample's share 2^w/n^2 must be an integer), got {wb}"
                ),
            );
        }
        let s = self.accumulate.gaussian_sigma;
        if !(s.is_finite() && GAUSSIAN_SIGMA.contains(&s)) {
            return err(
                "accumulate.gaussian_sigma",
                format!(
                    "must be a finite number in {:?}..={:?} pixels, got {}",
                    GAUSSIAN_SIGMA.start(),
                    GAUSSIAN_SIGMA.end(),
                    crate::files::num(s)
                ),
            );
        }
        let m = self.accumulate.mitchell;
        for (field, v) in [
            ("accumulate.mitchell.b", m.b),
            ("accumulate.mitchell.c", m.c),
        ] {
            if !(v.is_finite() && MITCHELL_BC.contains(&v)) {
                return err(
                    field,
                    format!(
                        "must be a finite number in {:?}..={:?}, got {}",
                        MITCHELL_BC.start(),
                        MITCHELL_BC.end(),
                        crate::files::num(v)
                    ),
                );
            }
        }
        let negative = self
            .accumulate
            .filter
            .cubic(m)
            .is_some_and(|bc| bc.negative_lobes());
        if negative && self.coding.kind == CodingKind::LogAdd {
            return err(
                "accumulate.filter",
                format!(
                    "\"{}\" has negative lobes (signed weights), which have no logarithm; with coding.kind = \"log-add\" use box, tent, gaussian or cubic_bspline",
                    self.accumulate.filter.name()
                ),
            );
        }
        self.gamma.validate()?;
        self.cycles.validate()?;
        self.dither.validate(acc.int_bits, self.gamma.dac_bits)?;
        self.dof.validate()?;
        self.coding.validate()?;
        if self.coding.kind == CodingKind::LogAdd
            && self.dither.kind != DitherKind::None
            && self.dither.placement == Placement::BeforeLut
        {
            return err(
                "dither.placement",
                "a log-add frame is dithered after its eq. 15 gamma LUT only (the LUT output's extra fraction bits); before the LUT a dither would drop bits of the log code: use placement = \"after_lut\"".into(),
            );
        }
        Ok(())
    }

    /// Sub-pixel bits of the vertex coordinates.
    pub fn subpixel_bits(&self) -> u32 {
        self.input.coord.format.frac_bits
    }
}
