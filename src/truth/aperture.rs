//! The points on the lens: `n` samples of the aperture disc in [`GROUPS`] interleaved
//! groups, each group a randomly rotated Vogel (golden-angle) spiral stratified in radius.

use super::GROUPS;

/// The golden angle, `pi (3 - sqrt 5)` radians.
const GOLDEN_ANGLE: f64 = 2.399_963_229_728_653;

/// The fixed seed of the groups' rotations and radial offsets.
const SEED: u64 = 0x6967_656d_7574_7275; // "igemutru"

/// SplitMix64: the `k`-th value of the stream of `seed`.
fn splitmix(seed: u64, k: u64) -> u64 {
    let mut z = seed.wrapping_add(k.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A uniform number in `[0, 1)` from 53 random bits.
fn unit(bits: u64) -> f64 {
    (bits >> 11) as f64 / (1u64 << 53) as f64
}

/// The lens offsets `(a, b)` (scene units, along the camera's right and up axes) of `n`
/// samples on the disc of radius `r`; `n` is a multiple of [`GROUPS`].
///
/// Sample `i = k GROUPS + g` is point `k` of group `g` (the groups interleave). Group `g`
/// has `m = n / GROUPS` points: point `k` at radius `r sqrt((k + u_g) / m)` and angle
/// `theta_g + k golden_angle`, with `u_g` in `[0, 1)` and `theta_g` in `[0, 2 pi)` drawn from
/// a fixed seed. Point `k` thus lies uniformly in the `k`-th of `m` annuli of equal area
/// (over the random `u_g`, `theta_g`): every group is an unbiased, stratified estimate of
/// the average over the disc on its own, and the groups are independent, so their spread
/// estimates the error of their mean.
pub fn lens_offsets(n: u32, r: f64) -> Vec<(f64, f64)> {
    let m = (n / GROUPS).max(1);
    (0..n)
        .map(|i| {
            let (k, g) = (i / GROUPS, i % GROUPS);
            let u = unit(splitmix(SEED, 2 * g as u64));
            let theta0 = std::f64::consts::TAU * unit(splitmix(SEED, 2 * g as u64 + 1));
            let rho = r * ((k as f64 + u) / m as f64).sqrt();
            let theta = theta0 + k as f64 * GOLDEN_ANGLE;
            (rho * theta.cos(), rho * theta.sin())
        })
        .collect()
}

/// The sub-pixel jitter `(x, y)` (pixels) of each of `n` lens points for a `grid`² sample
/// grid: uniform over one sample cell `[-1/(2 grid), 1/(2 grid))²`, so the grid's samples
/// sweep the whole pixel. Point `k` of group `g` (as in [`lens_offsets`]) takes the `k`-th
/// point of the R2 sequence (additive recurrence on the plastic number) shifted by a random
/// offset of the group: each group is uniform over the cell and stratified on its own, and
/// the groups are independent.
pub fn pixel_jitter(n: u32, grid: u32) -> Vec<(f64, f64)> {
    // 1/p and 1/p^2, p the plastic number (the real root of x^3 = x + 1).
    const A1: f64 = 0.754_877_666_246_692_7;
    const A2: f64 = 0.569_840_290_998_053_2;
    let cell = 1.0 / f64::from(grid.max(1));
    (0..n)
        .map(|i| {
            let (k, g) = (f64::from(i / GROUPS), u64::from(i % GROUPS));
            let u = (unit(splitmix(SEED ^ 0x6a69_7474, 2 * g)) + k * A1).fract();
            let v = (unit(splitmix(SEED ^ 0x6a69_7474, 2 * g + 1)) + k * A2).fract();
            ((u - 0.5) * cell, (v - 0.5) * cell)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_lie_on_the_disc_in_equal_area_annuli_per_group() {
        let (n, r) = (64, 2.0);
        let p = lens_offsets(n, r);
        assert_eq!(p.len(), 64);
        let m = n / GROUPS;
        for (i, &(a, b)) in p.iter().enumerate() {
            let k = i as u32 / GROUPS;
            let q = (a * a + b * b) / (r * r) * m as f64;
            assert!(
                q >= k as f64 - 1e-9 && q < (k + 1) as f64 + 1e-9,
                "{i}: {q}"
            );
        }
        // The centroid of the whole set is near the centre (a well-spread pattern).
        let (sa, sb) = p.iter().fold((0.0, 0.0), |s, &(a, b)| (s.0 + a, s.1 + b));
        assert!((sa / 64.0).hypot(sb / 64.0) < 0.1 * r, "{sa} {sb}");
        // Fixed seed: the same points every call.
        assert_eq!(p, lens_offsets(n, r));
        // Groups differ (independent rotations).
        assert_ne!(p[0], p[1]);
    }

    #[test]
    fn jitter_stays_in_one_sample_cell_and_covers_it_evenly() {
        let (n, grid) = (256, 4);
        let j = pixel_jitter(n, grid);
        assert_eq!(j.len(), 256);
        assert!(
            j.iter()
                .all(|&(x, y)| (-0.125..0.125).contains(&x) && (-0.125..0.125).contains(&y))
        );
        // Each group of 32 puts points in every quarter of the cell (a 2x2 split).
        for g in 0..GROUPS as usize {
            let mut q = [0u32; 4];
            for &(x, y) in j.iter().skip(g).step_by(GROUPS as usize) {
                q[usize::from(x >= 0.0) + 2 * usize::from(y >= 0.0)] += 1;
            }
            assert!(q.iter().all(|&c| (5..=11).contains(&c)), "group {g}: {q:?}");
        }
        let (sx, sy) = j.iter().fold((0.0, 0.0), |s, &(x, y)| (s.0 + x, s.1 + y));
        assert!((sx / 256.0).abs() < 0.01 && (sy / 256.0).abs() < 0.01);
        assert_eq!(j, pixel_jitter(n, grid));
    }
}
