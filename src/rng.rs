//! The one seeded random generator of the project (random HDL vectors, the tests' random
//! scenes and inputs): `rand`'s ChaCha8, seeded from a `u64` with `SeedableRng::seed_from_u64`.
//! A fixed seed gives the same stream on every build and platform.
//!
//! It defines no output: the generators that do (the dither mask, the Poisson disc of the
//! DoF downsampler, the reference's aperture samples) stay written out where they are, so
//! golden hashes do not depend on a crate's version.

use rand::rngs::ChaCha8Rng;
use rand::{Rng as _, SeedableRng};

/// A seeded generator.
#[derive(Debug)]
pub struct Rng(ChaCha8Rng);

impl Rng {
    /// The generator of `seed`.
    pub fn new(seed: u64) -> Self {
        Rng(ChaCha8Rng::seed_from_u64(seed))
    }
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0.next_u64()
    }
    /// `b` random bits (`0 <= b <= 64`) in the low bits.
    pub fn bits(&mut self, b: u32) -> u64 {
        if b == 0 {
            0
        } else {
            self.next_u64() >> (64 - b.min(64))
        }
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}
