//! The truth frame: the float frame of every lens point, averaged, with the standard error
//! of the average from the interleaved groups. Its pixels are sampled the same way whatever
//! the hardware under test ([`truth_hw`]): a [`TRUTH_GRID`]² grid, moved by a different
//! sub-pixel jitter at every lens point ([`pixel_jitter`]), and the box filter, so over the
//! lens points each pixel integrates its own area (an ideal sensor pixel). The truth thus
//! ranks sample counts and filters too. Values are linear intensity, 1 = full white.

use super::aperture::{lens_offsets, pixel_jitter};
use super::{GROUPS, check_samples};
use crate::config::{FilterKind, HwConfig};
use crate::error::{Error, FileError, Result};
use crate::scene::{GuardBand, Lens, LensPoint, Scene, front_end_through};
use crate::stage::accumulate::{Kernel, float_frame, kernel, regions};
use crate::stage::gamma::frame_white;
use crate::stage::raster::float_frags;
use crate::stage::visibility::float_samples;
use crate::stage::{Grid, input};
use rayon::prelude::*;

/// The lens-averaged frame of a thin-lens scene.
#[derive(Clone, Debug, PartialEq)]
pub struct TruthFrame {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// The average over the lens points of the float frame, linear intensity (1 = full
    /// white), row-major.
    pub mean: Vec<f64>,
    /// Per pixel, the standard error of `mean` estimated from the groups, same units.
    pub se: Vec<f64>,
    /// Lens points averaged.
    pub lens_samples: u32,
    /// Wall time, ms.
    pub ms: f64,
}

/// Samples per pixel axis of the truth's float path (each lens point moves them by its
/// jitter, so over the lens points they cover the pixel's area).
pub const TRUTH_GRID: u32 = 4;

/// The hardware whose float path renders the truth's lens points, the same for every
/// hardware under test: the default configuration with a [`TRUTH_GRID`]² grid and the box
/// filter (the float path reads only the sample grid, the filter and the frame's full
/// white; no fixed-point format of it matters).
pub fn truth_hw() -> HwConfig {
    let mut hw = HwConfig::default_config();
    hw.raster.samples = TRUTH_GRID;
    hw.accumulate.filter = FilterKind::Box;
    hw
}

/// A truth frame ready to compute: the scene (with a thin lens), the lens points and their
/// sub-pixel jitters.
pub struct TruthSetup<'a> {
    scene: &'a Scene,
    hw: HwConfig,
    focus: f64,
    offsets: Vec<(f64, f64)>,
    jitter: Vec<(f64, f64)>,
}

impl<'a> TruthSetup<'a> {
    /// Checks the scene (a thin lens) and the lens-sample count ([`check_samples`]).
    pub fn new(scene: &'a Scene, lens_samples: u32) -> Result<Self> {
        let Lens::ThinLens {
            lens_radius,
            focus_distance,
            ..
        } = scene.camera.lens
        else {
            return Err(Error::File(FileError {
                file: scene.name.clone(),
                line: None,
                col: None,
                field: "camera.lens".into(),
                msg: "the depth-of-field truth needs a thin lens; this camera is a pinhole (everything in focus)".into(),
            }));
        };
        check_samples(lens_samples).map_err(|msg| {
            Error::File(FileError {
                file: "--lens-samples".into(),
                line: None,
                col: None,
                field: String::new(),
                msg,
            })
        })?;
        Ok(Self {
            scene,
            hw: truth_hw(),
            focus: focus_distance,
            offsets: lens_offsets(lens_samples, lens_radius),
            jitter: pixel_jitter(lens_samples, TRUTH_GRID),
        })
    }

    /// Renders every lens point (in parallel, [`batch_size`] at a time) and
    /// averages them. Each frame is added to its group's sum in sample order, and the sums
    /// are combined in group order, so the result is bit-identical on any thread count.
    pub fn run(&self) -> TruthFrame {
        let t = std::time::Instant::now();
        let (w, h) = (self.scene.image.width, self.scene.image.height);
        let hw = &self.hw;
        let guard = GuardBand::around(w, h, f64::from(hw.raster.guard_band));
        let grid = Grid::new(hw.raster.samples, hw.subpixel_bits(), w, h);
        let k = kernel(hw);
        let npix = w as usize * h as usize;
        let g = GROUPS as usize;
        let mut sums = vec![vec![0.0f64; npix]; g];
        let n = self.offsets.len();
        let batch = batch_size(n as u32);
        for start in (0..n).step_by(batch) {
            let end = (start + batch).min(n);
            let frames: Vec<Vec<f64>> = (start..end)
                .into_par_iter()
                .map(|i| {
                    let (a, b) = self.offsets[i];
                    let lens = LensPoint {
                        a,
                        b,
                        focus: self.focus,
                        jitter: self.jitter[i],
                    };
                    lens_frame(self.scene, hw, &guard, &grid, &k, lens)
                })
                .collect();
            for (i, f) in (start..end).zip(frames) {
                for (s, v) in sums[i % g].iter_mut().zip(f) {
                    *s += v;
                }
            }
        }
        let white = frame_white(hw);
        for v in sums.iter_mut().flatten() {
            *v /= white;
        }
        let (mean, se) = mean_and_error(&sums, n);
        TruthFrame {
            width: w,
            height: h,
            mean,
            se,
            lens_samples: n as u32,
            ms: crate::stage::ms_since(t),
        }
    }
}

/// Lens points rendered at a time (and at most in memory at once): twice the threads, at
/// most `lens_samples`.
pub fn batch_size(lens_samples: u32) -> usize {
    (2 * rayon::current_num_threads().max(1)).min(lens_samples.max(1) as usize)
}

/// The mean of `n` frames from the sums of `groups.len()` equal groups, and per pixel the
/// standard error of that mean from the spread of the group means:
/// `sqrt(sum_g (m_g - m)^2 / (G (G - 1)))`.
pub fn mean_and_error(groups: &[Vec<f64>], n: usize) -> (Vec<f64>, Vec<f64>) {
    let g = groups.len();
    let npix = groups.first().map_or(0, Vec::len);
    let per = (n / g.max(1)) as f64;
    let mut mean = vec![0.0; npix];
    let mut se = vec![0.0; npix];
    for p in 0..npix {
        let total: f64 = groups.iter().map(|s| s[p]).sum();
        let m = total / n as f64;
        let ss: f64 = groups.iter().map(|s| (s[p] / per - m).powi(2)).sum();
        mean[p] = m;
        se[p] = if g > 1 {
            (ss / (g * (g - 1)) as f64).sqrt()
        } else {
            0.0
        };
    }
    (mean, se)
}

/// The float frame (frame LSBs) of the view through one lens point: the host front end from
/// the moved eye with the shear, then the float references of input, raster, visibility and
/// accumulate (the fixed models do not run), over the region the primitives touch.
pub fn lens_frame(
    scene: &Scene,
    hw: &HwConfig,
    guard: &GuardBand,
    grid: &Grid,
    k: &Kernel,
    lens: LensPoint,
) -> Vec<f64> {
    let host = front_end_through(scene, guard, Some(lens));
    let prims = input::float_prims(&host, hw);
    let (region, reg) = regions(&input::footprints(&host, hw), k, grid.width, grid.height);
    let frags = float_frags(&prims.f, grid, &reg, 0);
    let samples = float_samples(&prims, &frags, reg, 1).swap_remove(0);
    drop(frags);
    float_frame(&samples, k, hw, (grid.width, grid.height), &region)
}
