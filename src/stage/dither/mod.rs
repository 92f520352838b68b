//! Dithering: hides the bits the DAC (or the gamma-LUT address) does not have.
//!
//! Kinds: `none`; ordered Bayer 2x2 / 4x4 / 8x8 (matrices from the recursive rule
//! `M2n = [[4M, 4M+2], [4M+3, 4M+1]]`); a blue-noise mask generated in the crate by
//! Ulichney's void-and-cluster method (seeded, integer energies, so it is the same on every
//! machine); and Floyd-Steinberg error diffusion in fixed point. Ordered and blue-noise
//! masks have temporal variants indexed by the frame number.
//!
//! Placement:
//! * `after_lut` (the default, as display hardware does it): the gamma LUT emits DAC bits
//!   plus `f` extra fraction bits (format `UQd.f`), the dither removes the `f` bits.
//! * `before_lut`: the dither removes `f` bits of the frame code, so the LUT has
//!   `2^(A - f)` entries instead of `2^A` (A = accumulator integer bits). Address `a` stands
//!   for the frame value `a * 2^f` (normalised by the frame's full white and clamped to 1);
//!   the dithered address saturates at `2^(A-f) - 1`, which costs the top `2^f - 1` frame
//!   codes their mean (counted as saturations).
//!
//! Arithmetic (the input `x` has `s` fraction bits; output max `omax`):
//! * Ordered, mask rank `m` of an `N x N` mask (`N^2 = 2^b`), zero-mean threshold
//!   `t = (m + 0.5) / N^2`: `y = floor(x / 2^s + t)`, computed exactly as
//!   `((x << (b+1)) + ((2m+1) << s)) >> (s + b + 1)`, then saturated to `omax`.
//!   Averaged over the mask, `y` equals `x / 2^s` exactly whenever `s <= b`, and rounds
//!   `x / 2^s` to the nearest multiple of `1/N^2` otherwise.
//! * Floyd-Steinberg, error format `Qi.fe` (output LSBs, `fe >= s`): `v = x * 2^(fe-s) + e`,
//!   `y = floor(v / 2^fe + 1/2)` saturated to `[0, omax]`, residual `r = v - y * 2^fe`.
//!   The shares `7r/16`, `3r/16`, `5r/16` are rounded half up (`RND`, never truncated toward
//!   zero) to the error format and the last share is `r` minus the other three, so no error is
//!   lost inside the image (only at its borders).
//!   Serpentine scanning reverses odd rows. Accumulated errors saturate to the error format
//!   (counted as overflows).
//! * Temporal masks: frame `t` shifts the mask by the position of rank `t mod N^2` in the
//!   mask, so over one period of `N^2` frames every pixel sees every rank exactly once.
//!
//! The float reference applies the same patterns to the ideal (unquantised) value, so fixed
//! and float are comparable code by code; stage-locally (the float dither fed the fixed
//! dither's input) ordered dithers are identical (the arithmetic above is exact).
//! Floyd-Steinberg's float reference diffuses exact shares: every step adds 4 fraction bits
//! to the error, so no finite error format is exact and the two diverge where a rounded share
//! tips a decision (the stage-local report counts those pixels; the image mean is kept).
//!
//! Files: `mask` (Bayer and blue-noise masks, temporal offsets), `ordered` (ordered dither,
//! fixed and float), `diffusion` (Floyd-Steinberg, fixed and float), `unit` (the configured
//! [`Dither`], its cost, the temporal period-mean check), `stage` (the stage contract). The gamma LUTs
//! of the two placements are in [`crate::stage::gamma`].

mod diffusion;
mod mask;
mod ordered;
mod stage;
mod unit;

pub use diffusion::{FsParams, floyd_steinberg, floyd_steinberg_f64};
pub use mask::Mask;
pub use ordered::{
    Input, Run, apply_ordered, apply_ordered_f64, apply_ordered_from, apply_ordered_with,
    ordered_code, ordered_f64, rank_threshold,
};
pub use stage::DitherStage;
pub use unit::{Dither, ERROR_LINE, MASK_ROM, PeriodMean, period_mean};
