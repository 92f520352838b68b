//! Visible colour contours: the banding metric of [`crate::perceptual`] on each channel.
//!
//! Each channel's plane is measured as the one channel of a grey image is: its codes through
//! that channel's transfer (the display's `B_min`, `B_max`, gamma and Weber fraction, the
//! channel's `max_code`), against the channel's ideal (unquantised) values. A contour in any
//! one primary is a visible colour contour; the channels' luminances are not weighted by
//! their share of the white (a step in blue counts as one in green), which keeps the metric
//! the one that is already calibrated on grey images.

use super::{ColourDisplay, RgbCodes, check_pair};
use crate::perceptual::{self, ContourReport, IdealImage};
use serde::Serialize;
use std::sync::Arc;

/// The colour contour report: each channel's banding report and their sums.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ColourContourReport {
    /// The R, G and B channels' banding reports.
    pub channels: [ContourReport; 3],
    /// Visible contour steps of the fixed output, summed over the channels.
    pub contour_steps: u64,
    /// Visible contour steps of the reference's DAC codes, summed over the channels.
    pub contour_steps_reference: u64,
    /// Pixels next to a visible contour step in at least one channel (fixed output).
    pub contour_pixels: u64,
}

/// The colour contour report and each channel's per-pixel map.
pub struct ColourContours {
    /// The report.
    pub report: ColourContourReport,
    /// Per channel, per pixel (row-major): 0 not smooth, 1 smooth, 2 next to a visible
    /// contour step of the fixed output (as [`perceptual::Contours::map`]).
    pub maps: [Vec<u8>; 3],
}

/// The three channels' ideal images for [`colour_contours`]: `powers[c]` holds channel
/// `c`'s ideal values normalised to `[0, 1]` of full scale (the float frame through the
/// gamma curve, before the DAC scale), row-major `width * height`. As with
/// [`IdealImage::new`], they do not depend on the DAC widths and can be shared by every
/// width of a sweep.
pub fn ideal_images(
    powers: [Arc<Vec<f64>>; 3],
    d: &ColourDisplay,
    width: u32,
    height: u32,
) -> [IdealImage; 3] {
    let [r, g, b] = powers;
    [(0, r), (1, g), (2, b)].map(|(c, p)| IdealImage::new(p, d.channel(c), width, height))
}

/// Visible contours of each channel of `fixed` (and of `reference`, its float reference
/// rounded to the same codes) against the channels' ideal images ([`ideal_images`], of the
/// same size), on the display `d`. Panics if the images differ in size or their DAC widths
/// are not the display's.
pub fn colour_contours(
    fixed: &RgbCodes,
    reference: &RgbCodes,
    ideal: [&IdealImage; 3],
    d: &ColourDisplay,
) -> ColourContours {
    check_pair(fixed, reference, d);
    let per = [0, 1, 2].map(|c| {
        perceptual::contours(fixed.planes[c], reference.planes[c], ideal[c], d.channel(c))
    });
    let contour_pixels = (0..fixed.pixels())
        .filter(|&i| per.iter().any(|p| p.map[i] == 2))
        .count() as u64;
    let [r, g, b] = per;
    let channels = [r.report, g.report, b.report];
    let report = ColourContourReport {
        contour_steps: channels.iter().map(|c| c.contour_steps).sum(),
        contour_steps_reference: channels.iter().map(|c| c.contour_steps_reference).sum(),
        contour_pixels,
        channels,
    };
    ColourContours {
        report,
        maps: [r.map, g.map, b.map],
    }
}
