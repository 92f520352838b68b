//! Cost of the dof datapath (docs/reference.md §7b) and its overflow-count signals.

use super::layers::LayerPlan;
use super::lens::LensMap;
use crate::config::{AlphaNorm, DofCfg, DofKernel, SigmaForm};
use crate::fixed::{QFormat, SignalStats};
use crate::stage::{Cost, MemImage, Memory, Unit};
use std::sync::Arc;

/// Name of the line buffers.
pub const LINE_BUFFERS: &str = "dof line buffers";
/// Name of the composite buffer.
pub const COMPOSITE: &str = "dof composite buffer";
/// Name of the coefficient ROM.
pub const COEF_ROM: &str = "dof coefficient ROM";
/// Name of the sigma ROM (the paper's blur form).
pub const SIGMA_ROM: &str = "dof sigma ROM";

/// Cost of the blur per depth code: the sigma ROM and its interpolating multiplier (the
/// paper form) or one `z x G` multiplier (the affine form).
pub fn lens_cost(lens: &LensMap) -> Cost {
    match lens.form {
        SigmaForm::Paper => {
            let width = lens.sigma_rom_bits_wide();
            let frac = lens.z_frac.saturating_sub(lens.rom_bits);
            let mut muls = vec![];
            if frac > 0 {
                muls.push(Unit::mul("sigma ROM interpolation", 1, width + 1, frac));
            }
            Cost::new(
                vec![Memory::rom(SIGMA_ROM, lens.sigma_rom().len() as u64, width)],
                vec![Unit::adder("sigma ROM interpolation", 1, width + 1)],
                muls,
            )
        }
        SigmaForm::Affine => Cost::new(
            vec![],
            vec![],
            vec![Unit::mul(
                "sigma = G (z - z_e)",
                1,
                lens.z_frac + 1,
                lens.g_bits(),
            )],
        ),
    }
}

/// The sigma ROM's contents (two's complement entries), or none (the affine form).
pub fn sigma_rom_image(lens: &LensMap) -> Option<MemImage> {
    let rom = lens.sigma_rom();
    if rom.is_empty() {
        return None;
    }
    let width = lens.sigma_rom_bits_wide();
    let mask = if width >= 64 {
        u64::MAX
    } else {
        (1u64 << width) - 1
    };
    let words: Vec<u64> = rom.iter().map(|&c| c as u64 & mask).collect();
    Some(MemImage::table(SIGMA_ROM, width, Arc::new(words)))
}

/// Cost of the layered datapath: line buffers for the largest mask, the composite buffer,
/// the coefficient ROM and the arithmetic units by width, plus the blur per depth code
/// ([`lens_cost`]).
pub fn cost(
    plan: &LayerPlan,
    p: &DofCfg,
    width: u64,
    height: u64,
    code_bits: u32,
    n2: u32,
    lens: &LensMap,
) -> Cost {
    if p.kernel == DofKernel::Disc {
        return disc_cost(plan, p, width, height, code_bits, n2).merge(lens_cost(lens));
    }
    let m_max = plan.layers.iter().map(|l| l.m).max().unwrap_or(0) as u64;
    let a_bits = n2.next_power_of_two().trailing_zeros() + 1;
    let alpha_line = a_bits + p.coef_bits + 1;
    let rom_words: u64 = plan.layers.iter().map(|l| l.m as u64 + 1).sum();
    let taps = (2 * m_max + 1) as u32;
    let xm_bits = code_bits + a_bits;
    // With alpha_norm = behind the behind share is a third plane: a line-buffer field, tap
    // multipliers and adders as the alpha's.
    let behind = p.alpha_norm == AlphaNorm::Behind;
    let alpha_planes = if behind { 2 } else { 1 };
    let mut cost = Cost::new(
        vec![
            Memory::ram(
                LINE_BUFFERS,
                (2 * m_max + 1) * width,
                p.line_bits + alpha_planes * alpha_line,
            ),
            Memory::ram(COMPOSITE, width * height, code_bits + p.guard_bits),
            Memory::rom(COEF_ROM, rom_words, p.coef_bits + 1),
        ],
        vec![
            Unit::adder("horizontal tap sum (intensity)", taps, p.line_bits),
            Unit::adder("vertical tap sum (intensity)", taps, p.acc_bits),
            Unit::adder("alpha tap sums", 2 * taps, 2 * p.coef_bits + a_bits + 1),
            Unit::adder(
                "composite (over)",
                1,
                code_bits + p.guard_bits + p.alpha_bits,
            ),
        ],
        vec![
            Unit::mul("premultiply x * coverage", 1, code_bits, a_bits),
            Unit::mul("horizontal taps", taps, xm_bits, p.coef_bits + 1),
            Unit::mul("vertical taps", taps, p.line_bits, p.coef_bits + 1),
            Unit::mul("alpha taps", 2 * taps, alpha_line, p.coef_bits + 1),
            Unit::mul(
                "layer colour (divide acc / alpha)",
                1,
                p.acc_bits + p.guard_bits,
                2 * p.coef_bits + a_bits + 1,
            ),
            Unit::mul(
                "composite (colour x alpha, back x (1-alpha))",
                2,
                code_bits + p.guard_bits,
                p.alpha_bits + 1,
            ),
        ],
    );
    if behind {
        cost = cost.merge(Cost::new(
            vec![],
            vec![Unit::adder(
                "behind tap sums",
                2 * taps,
                2 * p.coef_bits + a_bits + 1,
            )],
            vec![Unit::mul(
                "behind taps",
                2 * taps,
                alpha_line,
                p.coef_bits + 1,
            )],
        ));
    }
    cost.merge(lens_cost(lens)).merge(if p.skip_uniform_tiles {
        uniform_cost(m_max, width, height, code_bits, a_bits, p)
    } else {
        Cost::new(vec![], vec![], vec![])
    })
}

/// Cost of the direct 2-D filter of `dof.kernel = "disc"`: `2M` input lines of `x m` and
/// `m` words (the window's rows above the current one), a multiplier per non-zero weight of
/// the largest mask for each plane (the weights are symmetric, so a chip could pre-add
/// mirrored samples; counted here without), their adder trees into `dof.acc`, the
/// coefficient ROM of one quadrant per layer, the divide and the composite.
fn disc_cost(
    plan: &LayerPlan,
    p: &DofCfg,
    width: u64,
    height: u64,
    code_bits: u32,
    n2: u32,
) -> Cost {
    let m_max = plan.layers.iter().map(|l| l.m).max().unwrap_or(0) as u64;
    let taps = plan
        .layers
        .iter()
        .filter_map(|l| l.disc.as_ref().map(|d| d.nonzero()))
        .max()
        .unwrap_or(1) as u32;
    let a_bits = n2.next_power_of_two().trailing_zeros() + 1;
    let xm_bits = code_bits + a_bits;
    let w_bits = 2 * p.coef_bits + 1;
    let rom_words: u64 = plan.layers.iter().map(|l| (l.m as u64 + 1).pow(2)).sum();
    // With alpha_norm = behind the behind share is a third plane (as the alpha's).
    let behind = p.alpha_norm == AlphaNorm::Behind;
    let planes_a = if behind { 2 } else { 1 };
    let mut cost = Cost::new(
        vec![
            Memory::ram(LINE_BUFFERS, 2 * m_max * width, xm_bits + planes_a * a_bits),
            Memory::ram(COMPOSITE, width * height, code_bits + p.guard_bits),
            Memory::rom(COEF_ROM, rom_words, w_bits),
        ],
        vec![
            Unit::adder("2-D tap sum (intensity)", taps, p.acc_bits),
            Unit::adder("2-D tap sum (alpha)", taps, w_bits + a_bits),
            Unit::adder(
                "composite (over)",
                1,
                code_bits + p.guard_bits + p.alpha_bits,
            ),
        ],
        vec![
            Unit::mul("premultiply x * coverage", 1, code_bits, a_bits),
            Unit::mul("2-D taps (intensity)", taps, xm_bits, w_bits),
            Unit::mul("2-D taps (alpha)", taps, a_bits, w_bits),
            Unit::mul(
                "layer colour (divide acc / alpha)",
                1,
                p.acc_bits + p.guard_bits,
                w_bits + a_bits,
            ),
            Unit::mul(
                "composite (colour x alpha, back x (1-alpha))",
                2,
                code_bits + p.guard_bits,
                p.alpha_bits + 1,
            ),
        ],
    );
    if behind {
        cost = cost.merge(Cost::new(
            vec![],
            vec![Unit::adder("2-D tap sum (behind)", taps, w_bits + a_bits)],
            vec![Unit::mul("2-D taps (behind)", taps, a_bits, w_bits)],
        ));
    }
    cost
}

/// Name of the uniform-run line buffer (`dof.skip_uniform_tiles`).
pub const UNIFORM_RUNS: &str = "dof uniform-run line buffer";
/// Name of the uniform tile flags (`dof.skip_uniform_tiles`).
pub const UNIFORM_FLAGS: &str = "dof uniform tile flags";

/// The uniform-tile detection (`dof.skip_uniform_tiles`, docs/dof.md): per pixel a compare
/// of code and layer share with the left and upper neighbours, a horizontal run counter and
/// a per-column vertical run counter (a line of `width` counters up to `2M + 1`), the tile
/// flags of two layers (one being scanned, one being blurred), and the multiplier that
/// writes a uniform line word `x W_x` without taps.
fn uniform_cost(
    m_max: u64,
    width: u64,
    height: u64,
    code_bits: u32,
    a_bits: u32,
    p: &DofCfg,
) -> Cost {
    let run_bits = 64 - (2 * m_max + 1).leading_zeros();
    let t = super::UNIFORM_TILE as u64;
    let tiles = width.div_ceil(t) * height.div_ceil(t);
    Cost::new(
        vec![
            Memory::ram(UNIFORM_RUNS, width, run_bits + code_bits),
            Memory::ram(UNIFORM_FLAGS, 2 * tiles, 1),
        ],
        vec![
            Unit::adder("uniform compare (code, share)", 2, code_bits + a_bits),
            Unit::adder("uniform run counters", 2, run_bits),
        ],
        vec![Unit::mul(
            "uniform line word x * W_x",
            1,
            code_bits + a_bits,
            p.coef_bits + 1,
        )],
    )
}

/// The coefficient ROM's contents: per layer (far to near) the centre tap and the taps on
/// one side (the masks are symmetric), `coef_bits + 1` bits each.
/// With `dof.kernel = "disc"`: per layer the quadrant `dx, dy >= 0` of its 2-D mask (row by
/// row, `(M + 1)^2` words of `2 coef_bits + 1` bits; an identity layer is its one weight).
pub fn coefficient_image(plan: &LayerPlan, p: &DofCfg) -> MemImage {
    if p.kernel == DofKernel::Disc {
        let one = 1u64 << (2 * p.coef_bits);
        let words: Vec<u64> = plan
            .layers
            .iter()
            .flat_map(|l| match &l.disc {
                Some(d) => {
                    let (m, n) = (d.m, d.side());
                    (m..n)
                        .flat_map(|y| d.w[y * n + m..(y + 1) * n].to_vec())
                        .collect::<Vec<_>>()
                }
                None => vec![one],
            })
            .collect();
        return MemImage::table(COEF_ROM, 2 * p.coef_bits + 1, Arc::new(words));
    }
    let words: Vec<u64> = plan
        .layers
        .iter()
        .flat_map(|l| l.coef[l.m..].iter().copied())
        .collect();
    MemImage::table(COEF_ROM, p.coef_bits + 1, Arc::new(words))
}

/// Stats record for an overflow count of an integer word of `bits` bits (`UQ<bits>.0`).
pub fn overflow_signal(name: &str, bits: u32, n: u64) -> SignalStats {
    overflow_signal_in(name, QFormat::new(false, bits, 0), n)
}

/// The widths the layered passes' sums can reach: (line, accumulator) bits of the largest
/// horizontal sum, a full-white frame code (`frame` bits) of full coverage (`n2` samples)
/// under taps summing to `2^coef_bits`, and of the largest vertical sum of saturated line
/// words (`line_bits` at most). A bright region of one layer reaches them.
pub fn reachable_bits(frame: QFormat, n2: u32, p: &DofCfg) -> (u32, u32) {
    let bits = |v: u128| 128 - v.leading_zeros();
    let white = (1u128 << frame.total_bits()) - 1;
    let line = bits((white * u128::from(n2)) << p.coef_bits);
    (line, line.min(p.line_bits) + p.coef_bits)
}

/// A note when the configured `dof.line_bits` or `dof.acc_bits` is narrower than what the
/// layered passes can reach ([`reachable_bits`]): such sums saturate (or wrap, or stop an
/// `ERROR` run) and are counted as `dof.line` / `dof.acc` overflows.
pub fn width_note(frame: QFormat, n2: u32, p: &DofCfg) -> Option<String> {
    let (line, acc) = reachable_bits(frame, n2, p);
    let short: Vec<String> = [
        ("line_bits", p.line_bits, line),
        ("acc_bits", p.acc_bits, acc),
    ]
    .iter()
    .filter(|(_, have, need)| have < need)
    .map(|(name, have, need)| format!("dof.{name} = {have} < {need}"))
    .collect();
    (!short.is_empty()).then(|| {
        format!(
            "{}: the layered blur's sums of a bright region (frame code {} of {n2} covered samples, taps summing to 2^{}) do not fit; they overflow (mode {}) and are counted as dof.line / dof.acc overflows; every sum fits dof.line_bits = {line}, dof.acc_bits = {}",
            short.join(", "),
            (1u64 << frame.total_bits()) - 1,
            p.coef_bits,
            p.overflow,
            line + p.coef_bits
        )
    })
}

/// Stats record for an overflow count of a signal in `format`.
pub fn overflow_signal_in(name: &str, format: QFormat, n: u64) -> SignalStats {
    SignalStats::overflow_counter(name, format, n)
}
