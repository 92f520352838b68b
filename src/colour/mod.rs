//! Colour error metrics of an RGB image of DAC codes against its float reference.
//!
//! **Displayed colour.** Each channel's DAC code goes through that channel's transfer, the
//! display model of [`crate::compare`] (`B = B_min + (B_max - B_min) (code / max_code)^gamma`,
//! `max_code` from the channel's own DAC width), normalised by `B_max`: full-scale code gives
//! 1.0, code 0 the stray-light floor `B_min / B_max = 1 / K`. The three normalised values are
//! the linear sRGB components (sRGB / ITU-R BT.709 primaries, D65 white); they go to CIE XYZ
//! and to CIELAB with the display white (full-scale code in every channel, `Y = 1`) as the
//! reference white. The colour-space conversions and the colour difference are the `palette`
//! crate's (`LinSrgb -> Xyz -> Lab`, `Ciede2000`), not written again here.
//!
//! **Metrics.** [`delta_e`]: the per-pixel CIEDE2000 difference `Delta E_00` and its
//! statistics; [`hue_shift`]: the hue angle error on smooth chromatic surfaces, the
//! colour-mix distortion of too-narrow words; [`delta_e_image`]: an RGB8 heat map of the
//! per-pixel `Delta E_00`. Visible contours are measured per channel by the banding metric
//! of [`crate::perceptual`] on each channel's lane (`pipeline::colour`).
//!
//! Everything here is a pure function over integer code planes; nothing depends on the
//! pipeline's types.

mod delta_e;
mod heat;
mod hue;

pub use delta_e::{DeltaE, JND, delta_e};
pub use heat::{HEAT_STOPS, delta_e_image, heat_colour};
pub use hue::{HueShift, MIN_CHROMA, WINDOW_RADIUS, hue_shift, smooth_mask};

use crate::compare::DisplayModel;
use crate::scene::Display;
use palette::white_point::{D65, WhitePoint};
use palette::{FromColor, Lab, Lch, LinSrgb, Xyz};

/// One RGB image of DAC codes: three planes (R, G, B), each row-major `width * height`, and
/// each channel's DAC width in bits (the channels may differ, as in 5-6-5).
#[derive(Clone, Copy, Debug)]
pub struct RgbCodes<'a> {
    /// The R, G and B code planes, row-major, `width * height` codes each.
    pub planes: [&'a [u16]; 3],
    /// Each channel's DAC width in bits, `1..=16`.
    pub bits: [u32; 3],
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl RgbCodes<'_> {
    /// Pixels of the image, `width * height`.
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// The three codes of pixel `i` (row-major index).
    #[inline]
    pub fn pixel(&self, i: usize) -> [u16; 3] {
        self.planes.map(|p| p[i])
    }

    /// Panics unless every plane holds `width * height` codes and the channels' widths are
    /// the display's `bits` (a caller's mistake, not a data condition).
    fn check(&self, bits: [u32; 3], what: &str) {
        let n = self.pixels();
        for (c, p) in self.planes.iter().enumerate() {
            assert_eq!(
                p.len(),
                n,
                "{what} image: plane {c} holds {} codes, not width * height = {n}",
                p.len()
            );
        }
        assert_eq!(
            self.bits, bits,
            "{what} image: DAC widths {:?} are not the display's {bits:?}",
            self.bits
        );
    }
}

/// Checks that `fixed` and `reference` are images of the display `d` of the same size.
fn check_pair(fixed: &RgbCodes, reference: &RgbCodes, d: &ColourDisplay) {
    assert_eq!(
        (fixed.width, fixed.height),
        (reference.width, reference.height),
        "fixed and reference images of different size"
    );
    fixed.check(d.bits, "fixed");
    reference.check(d.bits, "reference");
}

/// The primaries and white point of the display's linear RGB.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Primaries {
    /// sRGB / ITU-R BT.709 primaries with a D65 white: the default, and the only one for now.
    #[default]
    Srgb,
}

/// The colour display: each channel's transfer (a [`DisplayModel`] per channel: `b_min`,
/// `b_max`, `gamma` of the scene's display, `max_code` of that channel's DAC width) and the
/// primaries of its linear RGB.
#[derive(Clone, Debug)]
pub struct ColourDisplay {
    channels: [DisplayModel; 3],
    bits: [u32; 3],
    primaries: Primaries,
    /// Per channel, indexed by code: the displayed luminance over `B_max`.
    linear: [Vec<f64>; 3],
    /// Per XYZ component: the D65 white's over the display white's, which makes the
    /// display white exactly the CIELAB reference white.
    white_scale: [f64; 3],
}

impl ColourDisplay {
    /// From the scene's display block (`[display]`: contrast, gamma, peak luminance, Weber
    /// fraction, the same for the three channels) and each channel's DAC width in bits
    /// (`1..=16`), with sRGB primaries and a D65 white.
    pub fn new(d: &Display, bits: [u32; 3]) -> Self {
        let channels = bits.map(|b| DisplayModel::new(d, b));
        let linear: [Vec<f64>; 3] = channels.map(|m| {
            m.luminance_table()
                .into_iter()
                .map(|b| b / m.b_max)
                .collect()
        });
        // The display white (full-scale code in every channel) in XYZ, from the primaries'
        // matrix; palette's D65 constant differs from it by about 1e-5, which scaling XYZ by
        // the ratio removes (the CIELAB definition's X / X_n with X_n the display's white).
        let [r, g, b] = [0, 1, 2].map(|c| linear[c][linear[c].len() - 1]);
        let w = Xyz::<D65, f64>::from_color(LinSrgb::new(r, g, b));
        let n = <D65 as WhitePoint<f64>>::get_xyz();
        Self {
            channels,
            bits,
            primaries: Primaries::Srgb,
            linear,
            white_scale: [n.x / w.x, n.y / w.y, n.z / w.z],
        }
    }

    /// The display model of channel `c` (0 R, 1 G, 2 B).
    pub fn channel(&self, c: usize) -> &DisplayModel {
        &self.channels[c]
    }

    /// Each channel's DAC width in bits.
    pub fn bits(&self) -> [u32; 3] {
        self.bits
    }

    /// The primaries and white point.
    pub fn primaries(&self) -> Primaries {
        self.primaries
    }

    /// The linear sRGB components of a pixel's codes: each channel's luminance over `B_max`,
    /// in `[1 / K, 1]`. Panics on a code above its channel's largest code.
    #[inline]
    pub fn linear(&self, rgb: [u16; 3]) -> [f64; 3] {
        [0, 1, 2].map(|c| self.linear[c][rgb[c] as usize])
    }

    /// The CIE XYZ colour of a pixel's codes, scaled so that the display white is the D65
    /// white (`Y = 1`).
    #[inline]
    pub fn xyz(&self, rgb: [u16; 3]) -> Xyz<D65, f64> {
        let [r, g, b] = self.linear(rgb);
        let v = Xyz::<D65, f64>::from_color(LinSrgb::new(r, g, b));
        let [sx, sy, sz] = self.white_scale;
        Xyz::new(v.x * sx, v.y * sy, v.z * sz)
    }

    /// The CIELAB colour of a pixel's codes, against the display white (`L* = 100`,
    /// `a* = b* = 0` at full-scale code in every channel).
    #[inline]
    pub fn lab(&self, rgb: [u16; 3]) -> Lab<D65, f64> {
        Lab::from_color(self.xyz(rgb))
    }

    /// The CIE LCh(ab) colour of a pixel's codes: lightness, chroma `C*ab` and hue `h_ab`.
    #[inline]
    pub fn lch(&self, rgb: [u16; 3]) -> Lch<D65, f64> {
        Lch::from_color(self.lab(rgb))
    }
}

/// The nearest-rank `q`-quantile (`q` in `(0, 1]`) of `values`, reordering them; 0 when
/// there are none.
fn quantile(values: &mut [f32], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let rank = ((q * values.len() as f64).ceil() as usize).clamp(1, values.len());
    let (_, v, _) = values.select_nth_unstable_by(rank - 1, f32::total_cmp);
    *v as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantile_is_nearest_rank() {
        let mut v: Vec<f32> = (1..=100).rev().map(|x| x as f32).collect();
        assert_eq!(quantile(&mut v, 0.99), 99.0);
        assert_eq!(quantile(&mut v, 1.0), 100.0);
        assert_eq!(quantile(&mut [3.0], 0.99), 3.0);
        assert_eq!(quantile(&mut [], 0.99), 0.0);
    }

    #[test]
    fn white_is_the_reference_white() {
        let d = ColourDisplay::new(&Display::default(), [8, 8, 8]);
        let w = d.lab([255, 255, 255]);
        assert!((w.l - 100.0).abs() < 1e-12, "{w:?}");
        assert!(w.a.abs() < 1e-12 && w.b.abs() < 1e-12, "{w:?}");
        let k = Display::default().contrast;
        assert!(
            d.linear([0, 0, 0])
                .iter()
                .all(|&v| (v - 1.0 / k).abs() < 1e-15)
        );
    }
}
