//! Log-domain intensity coding (Kovalev & Tokarev, docs/reference.md §1, eq. 11-15, Fig. 7).
//!
//! **The code.** A sample's linear intensity `x` in [0, 1] (fraction of full white) is shown
//! with luminance `B = B_min (1 + (K - 1) x)`, so `B / B_min = K^I` with
//! `I = log_K(1 + (K - 1) x)` in [0, 1] (eq. 13). The `b`-bit log code holds `c = round(G I)`
//! with `G = 2^b - 1` grades over the contrast range: adjacent codes differ in luminance by
//! `K^(1/G)`, which is below `1 + delta` whenever `G >= m = ln K / ln(1 + delta)` (eq. 11).
//! Code 0 is exactly black (`x = 0`, `B = B_min`): the explicit zero of the linear intensity;
//! an intensity below half the first grade rounds to it.
//!
//! **Where it sits.** The raster keeps interpolating linear intensity; the per-sample value is
//! encoded to the log code where the sample is stored (the sample buffer is what the narrow
//! code saves). The encoder is a comparator search over `G` thresholds ([`LogEncoder`]).
//!
//! * Structure (a), `log-potentiate`: a potentiation LUT turns the log code into a linear
//!   code `W (K^I - 1)/(K - 1)` (`W` = full white of the linear frame, data width = the
//!   frame's integer bits); the spine's linear accumulate and gamma LUT follow unchanged.
//! * Structure (b), `log-add`: each sample's term `S K^I` (relative luminance weighted by
//!   the filter weight) is formed in log code by an adder, `I + log_K S` (the weight ROM holds
//!   `log_K S`); terms are accumulated by the Gaussian-logarithm adder
//!   `log(a + b) = max + sb(|la - lb|)`, `sb(d) = log_K(1 + K^-d)`, into a log-coded frame
//!   memory; the gamma LUT of eq. 15, `V = ((K^I - 1)/(K - 1))^(1/gamma)`, follows. With an
//!   equal-energy filter the weights sum to 1, so the sum is exactly the pixel's
//!   `B / B_min = K^(I_F)` and the frame code is the pixel's log intensity. No multiplier.
//!
//! **Frame log word (b).** Unsigned; code 0 = zero (empty sum); code `a >= 1` holds
//! `L = (a - off) / (G 2^fa)` with `fa` = `coding.acc_frac_bits` extra fraction bits and `off`
//! chosen so the smallest term (smallest nonzero filter weight times black, `log_K(w_min/2^f)`)
//! is code >= 1 (a smaller term is floored to code 1, counted in the signal `logdomain.term`).
//! Full scale is full white (`L = 1`, code `max = off + G 2^fa`, not a power of two); sums
//! above it overflow (light points can exceed white): `coding.overflow = "SAT"` clamps them
//! to full white and counts them in the signal `logdomain.frame`, `"ERROR"` stops the render.
//!
//! **sb table.** `2^A` entries (`A` = `coding.table_addr_bits`, 4..=16) of `sb` in frame LSBs
//! with `coding.table_frac_bits` (0..=12) extra fraction bits (data width = the integer bits
//! of `sb(0)` plus those). The address is `d >> s` with the smallest `s` such that the table
//! reaches sb's essential zero (the first `d` where `sb` rounds to 0 in the data LSB); past
//! it `sb = 0`. Direct lookup rounds `d` to the nearest entry; linear interpolation uses
//! `s` low bits of `d` (one small multiplier, counted in the cost). The sum is rounded to the
//! frame LSB with `coding.quant` (default `RND`, half up).
//!
//! **ROMs.** Every ROM is built through [`crate::fixed::Quantizer`] with a named format and
//! its quantisation is recorded as a signal of the stage: `logdomain.threshold` (encoder),
//! `logdomain.potentiation` (structure a), `logdomain.log_w` and `logdomain.sb` (structure b).
//!
//! The float references are exact f64: `K^I`, `log_K` and sums with the exact quantised
//! inputs for the stage-local errors; end to end every coding is compared against the same
//! float image the spine computes (linear intensities, exact weights, no rounding).
//!
//! Files: `code.rs` (the log code, encoder, potentiation LUT), `adder.rs` (the log frame word
//! and the Gaussian-log adder), `sums.rs` (per-pixel accumulation, work and signals), `lut.rs`
//! (the eq. 15 gamma LUT), `stage.rs` (the stage contract: the encoder and, for structure
//! (a), the potentiation; the log-domain sums run in the accumulate stage, the eq. 15 LUT in
//! the gamma stage).

mod adder;
mod code;
mod lut;
mod stage;
mod sums;

pub use adder::{LOG_FRAME_MEMORY, LOG_WEIGHT_ROM, LogAdder, SB_TABLE, ZERO};
pub use code::{
    LogCode, LogEncoder, POTENTIATION_LUT, PotentiationLut, THRESHOLD_ROM, check_contrast,
};
pub use lut::{log_gamma_linear, log_gamma_lut, log_gamma_lut_extended};
pub use stage::{Logdomain, log_code};
pub use sums::{LogWork, accumulate_pixel, accumulate_pixel_f64, add_term, local_add};
