//! The luminance of a colour frame for the luminance-aware blur: BT.601
//! `Y = 0.299 R + 0.587 G + 0.114 B` (the matrix seed 001 takes its luminance from), in
//! integer weights of 1/256, `S = 77 R' + 150 G' + 29 B'`, kept with the pre-blur's `g`
//! guard bits: `Y = S / 2^(8 - g)` rounded half up (`Y` is `g` bits wider than a frame code).
//! `R'`, `G'`, `B'` are the channels' frame codes shifted left to the widest channel's word
//! (`total_bits`), so a 5-6-5 frame weighs R and B on the 6-bit scale of G (white 62 of 63
//! there: the shift is the hardware's bit alignment, not an exact renormalisation; the float
//! reference does the same shifts). The weights sum to 256, so three equal channels `x` of
//! one width give `Y = x 2^g` exactly; the luminance's pre-blur then divides without guard
//! bits and its mean is the grey pre-blur's to the bit: a grey scene in three channels blurs
//! exactly as in one.
//!
//! The bleed of a colour frame is not continuous in the luminance (a neighbour whose `Y`
//! rises just above the centre's brings its own colour with a weight near 0, but a
//! weight all the same), so the fixed luminance's rounding can flip a near tie that the
//! float reference resolves the other way: the error figures measure it.
//!
//! One luminance unit serves the three channel datapaths (the Y image is pre-blurred once and
//! its 3x3 window gives every channel's bleed weights); lane 0 charges it.

use crate::fixed::QFormat;

/// BT.601 luma weights of R, G, B in 1/256 (sum 256).
pub const BT601: [u64; 3] = [77, 150, 29];

/// The luminance of every pixel of a colour frame, fixed and float.
#[derive(Clone, Debug)]
pub struct Luma {
    /// The channel of the lane that runs the blur (0 R, 1 G, 2 B); lane 0 counts the shared
    /// luminance unit's work, signals and cost.
    pub lane: usize,
    /// The word of the Y codes: the widest channel's frame word with `g` more fraction bits.
    pub format: QFormat,
    /// Left shift of each channel's codes onto that word.
    pub shifts: [u32; 3],
    /// Y of the fixed frames, codes of [`Luma::format`].
    pub fixed: Vec<u32>,
    /// Y of the float frames (exact, after the same shifts), in LSBs of that word (empty
    /// on the fixed-only path).
    pub float: Vec<f64>,
    /// Y of the fixed frames' codes as reals (exact): the stage-local comparison's input.
    pub local: Vec<f64>,
}

impl Luma {
    /// The luminance of the channel frames `codes` (fixed) and `values` (float; `None` on
    /// the fixed-only path), each channel in its frame word `formats`, with `g` guard bits,
    /// for the lane of channel `lane`.
    pub fn of(
        lane: usize,
        codes: [&[u32]; 3],
        values: Option<[&[f64]; 3]>,
        formats: [QFormat; 3],
        g: u32,
    ) -> Self {
        let widest = formats
            .iter()
            .copied()
            .max_by_key(QFormat::total_bits)
            .expect("three channels");
        let shifts = formats.map(|f| widest.total_bits() - f.total_bits());
        let format = QFormat::new(false, widest.int_bits, widest.frac_bits + g);
        // S in units of 2^-8 frame LSBs to Y in units of 2^-g.
        let to_y = |s: u64| {
            if g >= 8 {
                s << (g - 8)
            } else {
                (s + (1 << (7 - g))) >> (8 - g)
            }
        };
        let unit = (g as f64 - 8.0).exp2();
        let n = codes[0].len();
        let mut fixed = Vec::with_capacity(n);
        let mut local = Vec::with_capacity(n);
        for ((&r, &g), &b) in codes[0].iter().zip(codes[1]).zip(codes[2]) {
            let sum: u64 = [r, g, b]
                .iter()
                .zip(BT601.iter().zip(shifts))
                .map(|(&v, (&k, s))| k * (u64::from(v) << s))
                .sum();
            fixed.push(to_y(sum) as u32);
            local.push(sum as f64 * unit);
        }
        let scale = shifts.map(|s| (1u64 << s) as f64);
        let float = values.map_or_else(Vec::new, |values| {
            (0..n)
                .map(|i| {
                    (0..3)
                        .map(|c| BT601[c] as f64 * values[c][i] * scale[c])
                        .sum::<f64>()
                        * unit
                })
                .collect()
        });
        Self {
            lane,
            format,
            shifts,
            fixed,
            float,
            local,
        }
    }

    /// Whether this lane counts and charges the shared luminance unit.
    pub fn charges(&self) -> bool {
        self.lane == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_channels_of_one_width_give_their_code() {
        let f = QFormat::new(false, 12, 0);
        let codes: Vec<u32> = (0..4096).collect();
        let vals: Vec<f64> = codes.iter().map(|&c| f64::from(c) + 0.25).collect();
        for g in [0, 4, 9] {
            let y = Luma::of(0, [&codes; 3], Some([&vals; 3]), [f; 3], g);
            let want: Vec<u32> = codes.iter().map(|&c| c << g).collect();
            assert_eq!(y.fixed, want);
            assert_eq!(y.shifts, [0; 3]);
            for (a, b) in y.float.iter().zip(&vals) {
                assert!((a - b * f64::from(1u32 << g)).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn a_565_frame_is_weighed_on_the_green_scale() {
        let (f5, f6) = (QFormat::new(false, 5, 0), QFormat::new(false, 6, 0));
        let y = Luma::of(
            1,
            [&[31], &[0], &[0]],
            Some([&[31.0], &[0.0], &[0.0]]),
            [f5, f6, f5],
            2,
        );
        assert_eq!(y.format, QFormat::new(false, 6, 2));
        assert_eq!(y.shifts, [1, 0, 1]);
        // 77 * 62 / 64 = 74.59 -> 75.
        assert_eq!(y.fixed, vec![75]);
        assert!((y.float[0] - 77.0 * 62.0 / 64.0).abs() < 1e-12);
        assert!(!y.charges());
    }
}
