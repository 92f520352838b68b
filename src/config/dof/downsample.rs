//! `[dof.downsample]`: the downsample-and-blend method (`dof.kind = "downsample"`); see
//! docs/dof-downsample.md.

use serde::{Deserialize, Serialize};

/// `dof.downsample.factor`: the accepted downsampling factors per axis.
pub const DOWN_FACTORS: [u32; 3] = [2, 4, 8];

/// `dof.downsample.taps`: the range of the Poisson-disc taps besides the centre (even: the
/// set is point-symmetric).
pub const DOWN_TAPS: std::ops::RangeInclusive<u32> = 2..=64;

/// `dof.downsample.{offset_bits, blend_bits, blend_rom_bits, guard_bits, bilinear_bits}`:
/// the ranges of the word widths.
pub const DOWN_BITS: [(&str, u32, u32); 5] = [
    ("offset_bits", 2, 16),
    ("blend_bits", 2, 16),
    ("blend_rom_bits", 2, 16),
    ("guard_bits", 0, 16),
    ("bilinear_bits", 2, 16),
];

/// How a tap in front of the centre pixel is weighted (so that a sharp foreground does not
/// leak into a blurred background).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LeakGuard {
    /// `w = 1 - max(0, b_centre - b_tap)`: down-weighted by how much sharper than the centre
    /// it is (continuous; no divide).
    Difference,
    /// `w = b_tap`: every tap in front weighs its own blur factor (the classic GPU form).
    TapBlur,
    /// Every tap weighs 1.
    None,
}

impl LeakGuard {
    /// Every rule, in the order the docs list them.
    pub const ALL: [LeakGuard; 3] = [LeakGuard::Difference, LeakGuard::TapBlur, LeakGuard::None];

    /// The name in a hardware file.
    pub fn name(self) -> &'static str {
        match self {
            LeakGuard::Difference => "difference",
            LeakGuard::TapBlur => "tap_blur",
            LeakGuard::None => "none",
        }
    }
}

/// The filter that brings the blurred small image back to full resolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Reconstruction {
    /// 2x2 texels, the tent (the default).
    Bilinear,
    /// 4x4 texels, the cubic B-spline (no negative lobe: smoother than the tent).
    CubicBspline,
    /// 4x4 texels, Catmull-Rom (interpolating, negative lobes).
    CatmullRom,
    /// 4x4 texels, Mitchell-Netravali B = C = 1/3.
    Mitchell,
}

impl Reconstruction {
    /// Every filter, in the order the docs list them.
    pub const ALL: [Reconstruction; 4] = [
        Reconstruction::Bilinear,
        Reconstruction::CubicBspline,
        Reconstruction::CatmullRom,
        Reconstruction::Mitchell,
    ];

    /// The name in a hardware file.
    pub fn name(self) -> &'static str {
        match self {
            Reconstruction::Bilinear => "bilinear",
            Reconstruction::CubicBspline => "cubic_bspline",
            Reconstruction::CatmullRom => "catmull_rom",
            Reconstruction::Mitchell => "mitchell",
        }
    }

    /// The cubic's (B, C); `None` for bilinear.
    pub fn cubic(self) -> Option<crate::config::MitchellBc> {
        use crate::config::MitchellBc;
        match self {
            Reconstruction::Bilinear => None,
            Reconstruction::CubicBspline => Some(MitchellBc { b: 1.0, c: 0.0 }),
            Reconstruction::CatmullRom => Some(MitchellBc { b: 0.0, c: 0.5 }),
            Reconstruction::Mitchell => Some(MitchellBc::THIRD),
        }
    }

    /// Texels per axis of one reconstructed sample (2 or 4).
    pub fn texels(self) -> usize {
        if self == Reconstruction::Bilinear {
            2
        } else {
            4
        }
    }
}

/// `[dof.downsample]`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DownsampleCfg {
    /// Downsampling factor per axis (the small image has `1/factor^2` of the area).
    pub factor: u32,
    /// Poisson-disc taps besides the centre (even).
    pub taps: u32,
    /// Fraction bits of the Poisson offsets, signed `Q1.<offset_bits>`.
    pub offset_bits: u32,
    /// Fraction bits of the blend factors and tap weights, `UQ1.<blend_bits>` (1.0 included).
    pub blend_bits: u32,
    /// Depth-code bits indexing the blend ROM (`2^bits + 1` entries plus one for infinity).
    pub blend_rom_bits: u32,
    /// Guard fraction bits of the small image below the frame LSB.
    pub guard_bits: u32,
    /// Fraction bits of the reconstruction weights (bilinear `UQ1.<bilinear_bits>`, a cubic's
    /// signed and summing to exactly `2^bilinear_bits` per axis).
    pub bilinear_bits: u32,
    /// Weight of taps in front of the centre.
    pub leak_guard: LeakGuard,
    /// The upsampling filter of the blurred small image (its weights have `bilinear_bits`
    /// fraction bits).
    pub reconstruction: Reconstruction,
}

impl Default for DownsampleCfg {
    /// The presets' values: the paper's 4x4 downsampling, 12 taps, 8-bit offsets, blend
    /// factors and bilinear weights, a 257 + 1-entry blend ROM and 4 guard bits.
    fn default() -> Self {
        Self {
            factor: 4,
            taps: 12,
            offset_bits: 8,
            blend_bits: 8,
            blend_rom_bits: 8,
            guard_bits: 4,
            bilinear_bits: 8,
            leak_guard: LeakGuard::Difference,
            reconstruction: Reconstruction::Bilinear,
        }
    }
}

/// `2, 4 or 8`.
fn factors() -> String {
    let n: Vec<String> = DOWN_FACTORS.iter().map(|f| f.to_string()).collect();
    format!("{} or {}", n[..n.len() - 1].join(", "), n[n.len() - 1])
}

impl DownsampleCfg {
    /// Checks the fields; returns the failing field (without the `dof.downsample.` prefix) and
    /// the allowed range.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let err = |f: &str, m: String| Err((f.to_string(), m));
        if !DOWN_FACTORS.contains(&self.factor) {
            return err(
                "factor",
                format!(
                    "must be {} (the downsampling per axis), got {}",
                    factors(),
                    self.factor
                ),
            );
        }
        if !DOWN_TAPS.contains(&self.taps) || !self.taps.is_multiple_of(2) {
            return err(
                "taps",
                format!(
                    "must be an even integer in {}..={} (Poisson-disc taps besides the centre, a point-symmetric set), got {}",
                    DOWN_TAPS.start(),
                    DOWN_TAPS.end(),
                    self.taps
                ),
            );
        }
        let widths = [
            self.offset_bits,
            self.blend_bits,
            self.blend_rom_bits,
            self.guard_bits,
            self.bilinear_bits,
        ];
        for ((field, lo, hi), v) in DOWN_BITS.into_iter().zip(widths) {
            if !(lo..=hi).contains(&v) {
                return err(field, format!("must be in {lo}..={hi}, got {v}"));
            }
        }
        Ok(())
    }

    /// What a field (without the `dof.downsample.` prefix) expects: the message hint.
    pub(crate) fn hint(field: &str) -> Option<String> {
        Some(match field {
            "" => "a table [dof.downsample] with factor, taps, offset_bits, blend_bits, blend_rom_bits, guard_bits, bilinear_bits, leak_guard, reconstruction (each optional)".into(),
            "reconstruction" => format!(
                "one of {}",
                Reconstruction::ALL
                    .iter()
                    .map(|l| format!("\"{}\"", l.name()))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            "factor" => format!("{} (the downsampling per axis)", factors()),
            "taps" => format!(
                "an even integer in {}..={} (Poisson-disc taps besides the centre)",
                DOWN_TAPS.start(),
                DOWN_TAPS.end()
            ),
            "leak_guard" => format!(
                "one of {}",
                LeakGuard::ALL
                    .iter()
                    .map(|l| format!("\"{}\"", l.name()))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            f => {
                let (_, lo, hi) = DOWN_BITS.iter().find(|(n, _, _)| *n == f)?;
                format!("an integer in {lo}..={hi}")
            }
        })
    }
}

/// `[dof.downsample]` as written in the hardware file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawDownsample {
    factor: Option<u32>,
    taps: Option<u32>,
    offset_bits: Option<u32>,
    blend_bits: Option<u32>,
    blend_rom_bits: Option<u32>,
    guard_bits: Option<u32>,
    bilinear_bits: Option<u32>,
    leak_guard: Option<LeakGuard>,
    reconstruction: Option<Reconstruction>,
}

impl RawDownsample {
    /// Overrides the given fields.
    pub(crate) fn apply(self, c: &mut DownsampleCfg) {
        use crate::config::set;
        set(&mut c.factor, self.factor);
        set(&mut c.taps, self.taps);
        set(&mut c.offset_bits, self.offset_bits);
        set(&mut c.blend_bits, self.blend_bits);
        set(&mut c.blend_rom_bits, self.blend_rom_bits);
        set(&mut c.guard_bits, self.guard_bits);
        set(&mut c.bilinear_bits, self.bilinear_bits);
        set(&mut c.leak_guard, self.leak_guard);
        set(&mut c.reconstruction, self.reconstruction);
    }
}
