//! Depth of field against physical truth: a thin-lens image by accumulation over the lens,
//! in f64, through the project's own geometry and float references (docs/dof-truth.md).
//!
//! **The truth.** A thin lens of radius R focused at distance U images a scene point as the
//! average of the pinhole views from every point of its aperture, each sheared so the focus
//! plane stays put. For each of N points `(a, b)` on the aperture disc
//! ([`lens_offsets`]) the camera (position and look-at point) moves by `a right + b up` and
//! the host front end projects, culls, shades and clips from there
//! ([`crate::scene::front_end_through`]); every projected vertex is sheared by
//! `f_px (a, -b) / U` pixels (`f_px = H / (2 tan(fov/2))`; screen y points down), so a
//! point at view depth D moves by `f_px (a, -b) (1/U - 1/D)`: not at all on the focus
//! plane, and by `f_px R |1/U - 1/D|` at the aperture's rim, the blur radius of the model
//! (`sigma_px = K (1/U - 1/D)`, `K = R f_px`, docs/reference.md §2a). The view then goes
//! through the float references of input, raster, visibility and accumulate at the
//! configured `raster.samples` and filter (the fixed models do not run), and the N float
//! frames (frame LSBs, linear light) are averaged ([`TruthSetup::run`]). The truth has no
//! in-focus band: `deep` is a modelling approximation of the method, not physics. Shading
//! is per lens point, from the moved eye. The guard-band clip follows the shear, so each
//! view is clipped in its own screen and no lens point uncovers the screen's edge.
//!
//! **Noise.** The N points form [`GROUPS`] interleaved groups (sample `i` is in group
//! `i mod GROUPS`), each an independent, randomly rotated, radially stratified spiral: each
//! group's average is an unbiased estimate, and the spread of the group averages gives the
//! per-pixel standard error of the truth ([`TruthFrame::se`]), reported in frame LSBs and
//! in DAC codes ([`Noise`]).
//!
//! **Errors.** [`assess`] compares DAC codes with the truth's (the truth frame through the
//! float reference's gamma curve and DAC, no dither): **total** (fixed pipeline vs truth),
//! **algorithm** (float reference pipeline vs truth: what the depth-of-field method, whatever
//! `dof.kind` is, leaves out) and **quantisation** (fixed vs float reference), each over the
//! whole image, the depth-edge band and the interior, in codes and as Weber fractions of the
//! displayed luminance.
//!
//! **Determinism.** The lens points come from a fixed seed; frames are rendered in parallel
//! and each is added to its group's sum in sample order, so the truth is bit-identical on
//! any thread count.

mod aperture;
mod errors;
mod frame;

pub use crate::stage::gamma::frame_white;
pub use aperture::{lens_offsets, pixel_jitter};
pub use errors::{
    Diff, Images, Noise, Split, Spread, TruthReport, assess, dac_codes, dac_error, edge_band,
    truth_dac,
};
pub use frame::{
    TRUTH_GRID, TruthFrame, TruthSetup, batch_size, lens_frame, mean_and_error, truth_hw,
};

/// Interleaved groups of lens points; the lens-sample count is a multiple of it.
pub const GROUPS: u32 = 8;

/// Fewest lens samples (one point per group).
pub const MIN_SAMPLES: u32 = GROUPS;

/// Most lens samples (each is a float render of the scene).
pub const MAX_SAMPLES: u32 = 4096;

/// The lens samples of `render --dof-truth` without `--lens-samples`.
pub const DEFAULT_SAMPLES: u32 = 256;

/// Checks a lens-sample count: a multiple of [`GROUPS`] in
/// [`MIN_SAMPLES`]`..=`[`MAX_SAMPLES`]; the message names the range (the caller names the
/// flag, `--lens-samples`). Any integer is checked (a negative count from the command line
/// too), so the message says the number given.
pub fn check_samples(n: impl Into<i64>) -> Result<(), String> {
    let n: i64 = n.into();
    let (lo, hi, g) = (
        i64::from(MIN_SAMPLES),
        i64::from(MAX_SAMPLES),
        i64::from(GROUPS),
    );
    if (lo..=hi).contains(&n) && n % g == 0 {
        Ok(())
    } else {
        Err(format!(
            "must be a multiple of {GROUPS} (the noise estimate's interleaved groups) in {MIN_SAMPLES}..={MAX_SAMPLES}, got {n}"
        ))
    }
}
