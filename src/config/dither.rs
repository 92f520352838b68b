//! `[dither]`: the dither kind, its placement around the gamma LUT and its arithmetic
//! (docs/dither.md).

use super::set;
use crate::fixed::QFormat;
use serde::{Deserialize, Serialize};

/// `dither.frac_bits`: the bits the dither removes.
pub const FRAC_BITS: std::ops::RangeInclusive<u32> = 1..=8;
/// Integer bits of the Floyd-Steinberg error format `dither.error`.
pub const ERROR_INT_BITS: std::ops::RangeInclusive<u32> = 1..=4;
/// Most fraction bits of `dither.error` (the least is `frac_bits`).
pub const MAX_ERROR_FRAC_BITS: u32 = 24;
/// `dither.blue_noise_size`: the sides of the blue-noise mask.
pub const BLUE_NOISE_SIZES: [u32; 4] = [8, 16, 32, 64];

/// Dither kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DitherKind {
    /// No dither: the stage is not planned.
    None,
    /// Ordered, Bayer 2x2.
    Bayer2,
    /// Ordered, Bayer 4x4.
    Bayer4,
    /// Ordered, Bayer 8x8.
    Bayer8,
    /// Void-and-cluster blue-noise mask.
    BlueNoise,
    /// Floyd-Steinberg error diffusion.
    FloydSteinberg,
}

/// Where the dither sits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Placement {
    /// After the gamma LUT: removes the LUT's `f` extra fraction bits.
    AfterLut,
    /// Before the gamma LUT: reduces the LUT address by `f` bits.
    BeforeLut,
}

/// The `[dither]` section of the hardware config.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DitherCfg {
    /// Kind.
    pub kind: DitherKind,
    /// Placement.
    pub placement: Placement,
    /// Bits the dither removes (`f`): LUT output fraction bits, or LUT address bits.
    pub frac_bits: u32,
    /// Floyd-Steinberg: reverse every odd row.
    pub serpentine: bool,
    /// Floyd-Steinberg error format, in output LSBs (signed, at least `f` fraction bits).
    pub error: QFormat,
    /// Side of the blue-noise mask (8, 16, 32 or 64).
    pub blue_noise_size: u32,
    /// Seed of the blue-noise generator.
    pub seed: u64,
    /// Temporal variant (ordered and blue-noise masks).
    pub temporal: bool,
    /// Frame number the render shows (temporal variant).
    pub frame: u32,
}

impl Default for DitherCfg {
    fn default() -> Self {
        Self {
            kind: DitherKind::None,
            placement: Placement::AfterLut,
            frac_bits: 4,
            serpentine: true,
            error: QFormat::new(true, 2, 8),
            blue_noise_size: 16,
            seed: 1,
            temporal: false,
            frame: 0,
        }
    }
}

/// The `[dither]` TOML table (every field optional).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawDither {
    kind: Option<DitherKind>,
    placement: Option<Placement>,
    frac_bits: Option<u32>,
    serpentine: Option<bool>,
    error: Option<QFormat>,
    blue_noise_size: Option<u32>,
    seed: Option<u64>,
    temporal: Option<bool>,
    frame: Option<u32>,
}

impl RawDither {
    /// Overrides the fields given.
    pub(super) fn apply(self, c: &mut DitherCfg) {
        set(&mut c.kind, self.kind);
        set(&mut c.placement, self.placement);
        set(&mut c.frac_bits, self.frac_bits);
        set(&mut c.serpentine, self.serpentine);
        set(&mut c.error, self.error);
        set(&mut c.blue_noise_size, self.blue_noise_size);
        set(&mut c.seed, self.seed);
        set(&mut c.temporal, self.temporal);
        set(&mut c.frame, self.frame);
    }
}

impl DitherCfg {
    /// Checks the section against the frame and DAC widths: `(field, message)` on failure.
    /// The ranges of `frac_bits`, `error` and `blue_noise_size` hold whatever the kind (a
    /// field of a file is never left unchecked); their fit to the DAC and the accumulator
    /// only when a dither is planned.
    pub fn validate(&self, acc_int_bits: u32, dac_bits: u32) -> Result<(), (String, String)> {
        let err = |f: &str, m: String| Err((format!("dither.{f}"), m));
        let f = self.frac_bits;
        if !FRAC_BITS.contains(&f) {
            return err(
                "frac_bits",
                format!(
                    "must be in {}..={}, got {f}",
                    FRAC_BITS.start(),
                    FRAC_BITS.end()
                ),
            );
        }
        let e = &self.error;
        let (ei, ef) = (ERROR_INT_BITS, MAX_ERROR_FRAC_BITS);
        if !e.signed || !ei.contains(&e.int_bits) || e.frac_bits < f || e.frac_bits > ef {
            return err(
                "error",
                format!(
                    "must be signed Qi.fe with i in {}..={} and fe in {f}..={ef} (at least frac_bits fraction bits), got {e}",
                    ei.start(),
                    ei.end()
                ),
            );
        }
        if !BLUE_NOISE_SIZES.contains(&self.blue_noise_size) {
            return err(
                "blue_noise_size",
                format!("must be 8, 16, 32 or 64, got {}", self.blue_noise_size),
            );
        }
        if self.kind == DitherKind::None {
            return Ok(());
        }
        match self.placement {
            Placement::AfterLut if dac_bits + f > 24 => {
                return err(
                    "frac_bits",
                    format!(
                        "the LUT output (DAC {dac_bits} bits + {f} fraction bits) must be at most 24 bits"
                    ),
                );
            }
            Placement::BeforeLut if f >= acc_int_bits => {
                return err(
                    "frac_bits",
                    format!(
                        "before the LUT the dither removes address bits: must be in 1..={} (the accumulator has {acc_int_bits} integer bits)",
                        acc_int_bits - 1
                    ),
                );
            }
            _ => {}
        }
        if self.temporal && self.kind == DitherKind::FloydSteinberg {
            return err(
                "temporal",
                "the temporal variant needs a mask (bayer2/4/8 or blue_noise), not floyd_steinberg"
                    .into(),
            );
        }
        Ok(())
    }
}
