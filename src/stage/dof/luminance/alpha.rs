//! The blend factor alpha of the luminance-aware method (docs/reference.md §2b, §4): the
//! normalised blur factor `C / C_max` of the thin lens at the pixel's depth, scaled inside the
//! depth-of-field band, exact per depth code ([`AlphaMap::alpha_f64`]) and as the hardware
//! holds it, a ROM indexed by the top bits of the depth code ([`AlphaMap::code`]).

use crate::config::LuminanceCfg;
use crate::fixed::{Overflow, QFormat, Quant, Quantizer};
use crate::stage::dof::LensMap;
use serde::Serialize;

/// Rounding of the ROM entries: to nearest (alpha >= 0, so ties go up).
pub const ROM_QUANT: Quant = Quant::Rnd;

/// The alpha of every depth code: the formula's constants and the ROM built from it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AlphaMap {
    /// `C_max`: the larger circle of confusion (pixels) of the near (z = 0) and far (z = 1)
    /// clip planes.
    pub c_max: f64,
    /// Circle of confusion (pixels) at the band's far edge.
    pub c_far_edge: f64,
    /// Circle of confusion (pixels) at the band's near edge.
    pub c_near_edge: f64,
    /// Factor of alpha inside the band.
    pub focus_scale: f64,
    /// Width of the factor's ramp beyond the band, pixels of circle of confusion.
    pub ramp: f64,
    /// Depth-code bits (the z buffer's fraction bits).
    pub z_bits: u32,
    /// Depth-code bits the ROM is indexed by: `min(alpha_rom_bits, z_bits)`.
    pub index_bits: u32,
    /// Fraction bits of alpha: the entries are `UQ1.<alpha_bits>`, 1.0 = `2^alpha_bits`.
    pub alpha_bits: u32,
    /// The ROM: `2^index_bits` entries by the top bits of the depth code, then the entry of
    /// infinity (the background).
    #[serde(skip)]
    pub rom: Vec<u32>,
}

/// The depth code nearest screen z (clamped to the codes `0..u32::MAX`; `u32::MAX` is
/// infinity).
fn key_of(z: f64, z_bits: u32) -> u32 {
    (z * (1u64 << z_bits) as f64)
        .round()
        .clamp(0.0, (u32::MAX - 1) as f64) as u32
}

impl AlphaMap {
    /// The constants of `lens` and `cfg` and the ROM.
    pub fn new(lens: &LensMap, cfg: &LuminanceCfg) -> Self {
        let z_bits = lens.z_frac;
        let c_max = lens
            .coc_f64(0)
            .max(lens.coc_f64(key_of(1.0, z_bits)))
            .max(0.0);
        let mut a = Self {
            c_max,
            c_far_edge: lens.coc_f64(key_of(lens.z_far_edge, z_bits)),
            c_near_edge: lens.coc_f64(key_of(lens.z_near_edge, z_bits)),
            focus_scale: cfg.focus_scale,
            ramp: cfg.ramp,
            z_bits,
            index_bits: cfg.alpha_rom_bits.min(z_bits),
            alpha_bits: cfg.alpha_bits,
            rom: Vec::new(),
        };
        let q = a.quantizer();
        a.rom = (0..=1usize << a.index_bits)
            .map(|i| q.quantize_f64(a.alpha_f64(lens, a.entry_key(i))).code as u32)
            .collect();
        a
    }

    /// The quantiser of the entries: `UQ1.<alpha_bits>`, [`ROM_QUANT`], SAT (alpha is in
    /// [0, 1], so SAT does not act).
    pub fn quantizer(&self) -> Quantizer {
        Quantizer::new(
            QFormat::new(false, 1, self.alpha_bits),
            ROM_QUANT,
            Overflow::Sat,
        )
    }

    /// Bits of one entry.
    pub fn entry_bits(&self) -> u32 {
        self.alpha_bits + 1
    }

    /// Alpha = 1 as a code: `2^alpha_bits`.
    pub fn one(&self) -> u32 {
        1 << self.alpha_bits
    }

    /// The ROM address of a depth code: its top `index_bits` bits, or the last entry for
    /// infinity (`u32::MAX`).
    #[inline]
    pub fn index(&self, key: u32) -> usize {
        if key == u32::MAX {
            1 << self.index_bits
        } else {
            (key >> (self.z_bits - self.index_bits)) as usize
        }
    }

    /// The depth code entry `i` is computed at: the middle of the codes it serves (their
    /// first code when it serves one), infinity for the last entry.
    pub fn entry_key(&self, i: usize) -> u32 {
        if i == 1 << self.index_bits {
            return u32::MAX;
        }
        let s = self.z_bits - self.index_bits;
        let mid = if s == 0 { 0 } else { 1u64 << (s - 1) };
        ((i as u64) << s | mid) as u32
    }

    /// Alpha as the hardware reads it: the ROM entry of the depth code (`UQ1.<alpha_bits>`).
    #[inline]
    pub fn code(&self, key: u32) -> u32 {
        self.rom[self.index(key)]
    }

    /// Whether the depth code lies in the depth-of-field band `[U - deep, U + deep]`.
    pub fn in_band(lens: &LensMap, key: u32) -> bool {
        let z = lens.z_of(key);
        z >= lens.z_near_edge && z <= lens.z_far_edge
    }

    /// The factor on the normalised blur: `focus_scale` inside the band, ramping linearly
    /// to 1 as the circle of confusion grows by `ramp` pixels beyond the band's edge on
    /// that side (a step when `ramp` is 0).
    pub fn factor(&self, lens: &LensMap, key: u32) -> f64 {
        let s = self.focus_scale;
        if Self::in_band(lens, key) {
            return s;
        }
        let edge = if lens.z_of(key) > lens.z_far_edge {
            self.c_far_edge
        } else {
            self.c_near_edge
        };
        let t = if self.ramp > 0.0 {
            ((lens.coc_f64(key) - edge) / self.ramp).clamp(0.0, 1.0)
        } else {
            1.0
        };
        s + (1.0 - s) * t
    }

    /// The exact alpha of a depth code: `min(1, C / C_max)` times [`AlphaMap::factor`] (0
    /// when `C_max` is 0).
    pub fn alpha_f64(&self, lens: &LensMap, key: u32) -> f64 {
        if self.c_max <= 0.0 {
            return 0.0;
        }
        (lens.coc_f64(key) / self.c_max).min(1.0) * self.factor(lens, key)
    }
}
