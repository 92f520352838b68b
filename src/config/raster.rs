//! `[raster]`: the sample grid, the incremental interpolators and the guard band (setup and
//! raster read it).

use super::set;
use crate::fixed::Quant;
use serde::{Deserialize, Serialize};

/// Largest guard band beyond the screen edge, in pixels (the scene bounds line widths and
/// light-point sizes with it).
pub use crate::scene::MAX_GUARD_BAND;

/// `raster.interp_guard_bits`: extra fraction bits of the interpolators.
pub const INTERP_GUARD_BITS: std::ops::RangeInclusive<u32> = 0..=24;

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

/// `[raster]` as written in the hardware file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRaster {
    samples: Option<u32>,
    interp_guard_bits: Option<u32>,
    interp_quant: Option<Quant>,
    guard_band: Option<u32>,
}

impl RawRaster {
    /// Overrides the given fields.
    pub(super) fn apply(self, c: &mut RasterCfg) {
        set(&mut c.samples, self.samples);
        set(&mut c.interp_guard_bits, self.interp_guard_bits);
        set(&mut c.interp_quant, self.interp_quant);
        set(&mut c.guard_band, self.guard_band);
    }
}
