//! The Poisson-disc tap offsets: a deterministic, point-symmetric set in the open unit disc
//! (best-candidate sampling), and its quantisation to the offset ROM's signed `Q1.<o>`
//! words.

use crate::fixed::{Overflow, QFormat, Quant, Quantizer};
use serde::Serialize;

/// Candidates tried per placed point (best-candidate sampling: the one farthest from the
/// points placed so far wins).
const CANDIDATES: usize = 64;

/// Seed of the generator (any fixed value: the set is part of the design, like a ROM).
const SEED: u64 = 0x9e37_79b9_7f4a_7c15;

/// The tap offsets: tap 0 is the centre `(0, 0)`, then the pairs `p, -p`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Poisson {
    /// Exact offsets in the unit disc (`taps + 1` with the centre first).
    pub points: Vec<(f64, f64)>,
    /// Quantised offsets, `Q1.<frac>` codes (the same order).
    #[serde(skip)]
    pub codes: Vec<(i64, i64)>,
    /// Fraction bits of the codes.
    pub frac: u32,
    /// Smallest distance between two exact offsets, the centre included.
    pub min_distance: f64,
    /// Smallest distance between two quantised offsets, the centre included.
    pub min_distance_quantised: f64,
}

impl Poisson {
    /// The format of one offset component: signed `Q1.<frac>` (range `[-1, 1 - 2^-frac]`).
    pub fn format(frac: u32) -> QFormat {
        QFormat::new(true, 1, frac)
    }

    /// The quantiser of one component: `Q1.<frac>`, TRN_ZERO (toward zero, so
    /// `|code| <= |x| < 1` and `q(-x) = -q(x)`: the set stays point-symmetric and inside the
    /// disc), SAT (never acts: `|x| < 1`).
    pub fn quantizer(frac: u32) -> Quantizer {
        Quantizer::new(Self::format(frac), Quant::TrnZero, Overflow::Sat)
    }

    /// `taps` offsets (even) besides the centre, quantised to `frac` fraction bits.
    pub fn new(taps: usize, frac: u32) -> Self {
        let points = poisson_disc(taps);
        let q = Self::quantizer(frac);
        let codes: Vec<(i64, i64)> = points
            .iter()
            .map(|&(x, y)| (q.quantize_f64(x).code, q.quantize_f64(y).code))
            .collect();
        let one = (1u64 << frac) as f64;
        let as_f: Vec<(f64, f64)> = codes
            .iter()
            .map(|&(x, y)| (x as f64 / one, y as f64 / one))
            .collect();
        Self {
            min_distance: min_distance(&points),
            min_distance_quantised: min_distance(&as_f),
            points,
            codes,
            frac,
        }
    }

    /// The ROM's words: the first offset of each pair (the datapath negates it for the
    /// second), `(dx, dy)` as two's complement fields of `frac + 1` bits.
    pub fn rom_words(&self) -> Vec<(u64, u64)> {
        let mask = (1u64 << (self.frac + 1)) - 1;
        self.codes
            .iter()
            .skip(1)
            .step_by(2)
            .map(|&(x, y)| (x as u64 & mask, y as u64 & mask))
            .collect()
    }
}

/// Smallest pairwise distance of `p`.
fn min_distance(p: &[(f64, f64)]) -> f64 {
    let mut d = f64::INFINITY;
    for (i, a) in p.iter().enumerate() {
        for b in &p[i + 1..] {
            d = d.min((a.0 - b.0).hypot(a.1 - b.1));
        }
    }
    d
}

/// A deterministic point-symmetric Poisson-disc set: the centre, then `taps / 2` pairs
/// `p, -p` in the open unit disc. Each `p` is the best of [`CANDIDATES`] uniform candidates
/// (xorshift64*, fixed seed): the one farthest from the centre and from every point and
/// mirror placed so far (Mitchell's best-candidate sampling), which spreads the taps over the
/// disc with a large minimum distance.
pub fn poisson_disc(taps: usize) -> Vec<(f64, f64)> {
    let mut s = SEED;
    let mut next = move || {
        s ^= s >> 12;
        s ^= s << 25;
        s ^= s >> 27;
        (s.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut pts: Vec<(f64, f64)> = vec![(0.0, 0.0)];
    for _ in 0..taps / 2 {
        let mut best = (0.0, 0.0);
        let mut best_d = -1.0;
        let mut tried = 0;
        while tried < CANDIDATES {
            let (x, y) = (2.0 * next() - 1.0, 2.0 * next() - 1.0);
            if x * x + y * y >= 1.0 {
                continue;
            }
            tried += 1;
            // Distance to every placed point and its mirror, and to the candidate's own mirror.
            let mut d = 2.0 * x.hypot(y);
            for &(px, py) in &pts {
                d = d.min((x - px).hypot(y - py)).min((x + px).hypot(y + py));
            }
            if d > best_d {
                best_d = d;
                best = (x, y);
            }
        }
        pts.push(best);
        pts.push((-best.0, -best.1));
    }
    pts
}
