//! Threshold masks of the ordered dithers: the Bayer matrices (recursive rule), the
//! void-and-cluster blue-noise mask, and the temporal offset of a frame.

use crate::config::{DitherCfg, DitherKind};

/// A threshold mask: ranks `0..N^2` (a permutation) on an `N x N` tile.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mask {
    /// Side `N` (a power of two).
    pub n: u32,
    /// `log2(N^2)`: bits of a rank.
    pub bits: u32,
    /// Ranks, row-major.
    pub rank: Vec<u32>,
}

impl Mask {
    /// The Bayer matrix of side `n` (1, 2, 4, 8, ...) by the recursive rule.
    pub fn bayer(n: u32) -> Mask {
        assert!(n.is_power_of_two(), "Bayer side must be a power of two");
        let mut m = vec![0u32];
        let mut s = 1usize;
        while (s as u32) < n {
            let t = 2 * s;
            let mut next = vec![0u32; t * t];
            for y in 0..s {
                for x in 0..s {
                    let v = 4 * m[y * s + x];
                    next[y * t + x] = v;
                    next[y * t + x + s] = v + 2;
                    next[(y + s) * t + x] = v + 3;
                    next[(y + s) * t + x + s] = v + 1;
                }
            }
            m = next;
            s = t;
        }
        Mask {
            n,
            bits: 2 * n.trailing_zeros(),
            rank: m,
        }
    }

    /// A blue-noise mask of side `n` by void-and-cluster (Ulichney 1993), Gaussian
    /// sigma 1.5 on the torus, energies in integers (kernel `round(exp(-d^2/2s^2) * 2^20)`),
    /// ties broken by the lowest index, initial pattern of `n^2/10` seeded random points.
    pub fn blue_noise(n: u32, seed: u64) -> Mask {
        let nn = n as usize;
        let size = nn * nn;
        let sigma2 = 2.0 * 1.5f64 * 1.5;
        let mut kern = vec![0i64; size];
        for dy in 0..nn {
            for dx in 0..nn {
                let (ax, ay) = (dx.min(nn - dx) as f64, dy.min(nn - dy) as f64);
                kern[dy * nn + dx] =
                    ((-(ax * ax + ay * ay) / sigma2).exp() * 1048576.0).round() as i64;
            }
        }
        let mut energy = vec![0i64; size];
        let mut on = vec![false; size];
        let toggle = |on: &mut [bool], energy: &mut [i64], q: usize, add: bool| {
            on[q] = add;
            let (qx, qy) = (q % nn, q / nn);
            for py in 0..nn {
                let dy = (py + nn - qy) % nn;
                for px in 0..nn {
                    let dx = (px + nn - qx) % nn;
                    let k = kern[dy * nn + dx];
                    energy[py * nn + px] += if add { k } else { -k };
                }
            }
        };
        let cluster = |on: &[bool], energy: &[i64]| {
            (0..size)
                .filter(|&i| on[i])
                .max_by(|&a, &b| energy[a].cmp(&energy[b]).then(b.cmp(&a)))
        };
        let void = |on: &[bool], energy: &[i64]| {
            (0..size)
                .filter(|&i| !on[i])
                .min_by(|&a, &b| energy[a].cmp(&energy[b]).then(a.cmp(&b)))
        };
        // Initial pattern: seeded random points (xorshift64*).
        let mut state = seed ^ 0x9E37_79B9_7F4A_7C15;
        let ones = (size / 10).max(1);
        let mut placed = 0;
        while placed < ones {
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            let r = (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 33) as usize % size;
            if !on[r] {
                toggle(&mut on, &mut energy, r, true);
                placed += 1;
            }
        }
        // Relax: move the tightest cluster into the largest void until they coincide.
        for _ in 0..4 * size {
            let c = cluster(&on, &energy).expect("ones exist");
            toggle(&mut on, &mut energy, c, false);
            let v = void(&on, &energy).expect("zeros exist");
            toggle(&mut on, &mut energy, v, true);
            if v == c {
                break;
            }
        }
        let (proto_on, proto_e) = (on.clone(), energy.clone());
        let mut rank = vec![0u32; size];
        // Phase 1: remove the tightest clusters, ranks ones-1 down to 0.
        for r in (0..ones).rev() {
            let c = cluster(&on, &energy).expect("ones exist");
            rank[c] = r as u32;
            toggle(&mut on, &mut energy, c, false);
        }
        // Phases 2 and 3: fill the largest voids, ranks ones.. size. (The tightest cluster
        // of zeros is the largest void of ones: the torus kernel sums to a constant.)
        let (mut on, mut energy) = (proto_on, proto_e);
        for r in ones..size {
            let v = void(&on, &energy).expect("zeros exist");
            rank[v] = r as u32;
            toggle(&mut on, &mut energy, v, true);
        }
        Mask {
            n,
            bits: 2 * n.trailing_zeros(),
            rank,
        }
    }

    /// The mask of a configuration (`None` for error diffusion and no dither).
    pub fn of(cfg: &DitherCfg) -> Option<Mask> {
        match cfg.kind {
            DitherKind::Bayer2 => Some(Mask::bayer(2)),
            DitherKind::Bayer4 => Some(Mask::bayer(4)),
            DitherKind::Bayer8 => Some(Mask::bayer(8)),
            DitherKind::BlueNoise => Some(Mask::blue_noise(cfg.blue_noise_size, cfg.seed)),
            _ => None,
        }
    }

    /// Frames in one temporal period (`N^2`).
    pub fn period(&self) -> u32 {
        self.n * self.n
    }

    /// The mask offset of frame `t`: the position of rank `t mod N^2`.
    pub fn offset(&self, t: u32) -> (u32, u32) {
        let r = t % self.period();
        let i = self
            .rank
            .iter()
            .position(|&v| v == r)
            .expect("a permutation") as u32;
        (i % self.n, i / self.n)
    }

    /// The rank at pixel `(x, y)` with offset `off`.
    #[inline]
    pub fn at(&self, x: u32, y: u32, off: (u32, u32)) -> u32 {
        let m = self.n - 1;
        self.rank[(((y + off.1) & m) * self.n + ((x + off.0) & m)) as usize]
    }
}
