//! Cost of the downsample datapath (docs/reference.md §7b, docs/dof-downsample.md), its
//! ROM images for the pack check and its cycle-model tokens.

use super::fixed::small_format;
use super::plan::DownPlan;
use crate::config::{DofCfg, LeakGuard};
use crate::fixed::QFormat;
use crate::stage::dof::SIGMA_FRAC;
use crate::stage::{Cost, MemImage, Memory, TokenKind, Tokens, Unit};
use std::sync::Arc;

/// The running box sums of the small row being built.
pub const BOX_ROW: &str = "dof down box accumulators";
/// The small row and the Gaussian's line buffers.
pub const LINE_BUFFERS: &str = "dof down line buffers";
/// The blurred small image.
pub const BLURRED: &str = "dof down blurred image";
/// The full-resolution rows the taps read (code, depth code, blend factor).
pub const WINDOW: &str = "dof down blend window";
/// The Poisson offsets.
pub const OFFSET_ROM: &str = "dof down offset ROM";
/// The blend factors by depth.
pub const BLEND_ROM: &str = "dof down blend ROM";
/// The small Gaussian's taps.
pub const COEF_ROM: &str = "dof down coefficient ROM";
/// Name of a cubic reconstruction's weight ROM (`2^bilinear_bits + 1` entries of four signed
/// weights).
pub const RECON_ROM: &str = "dof down reconstruction ROM";

/// `ceil(log2(n))`.
fn clog2(n: u64) -> u32 {
    n.next_power_of_two().trailing_zeros()
}

/// Cost of the datapath for frame codes in `frame_fmt` and `z_bits`-bit depth codes.
pub fn cost(plan: &DownPlan, p: &DofCfg, frame_fmt: QFormat, z_bits: u32) -> Cost {
    let d = &p.downsample;
    let (w, sw, sh) = (
        plan.width as u64,
        plan.small_width as u64,
        plan.small_height as u64,
    );
    let fb = frame_fmt.total_bits();
    let sb = small_format(frame_fmt, d.guard_bits).total_bits();
    let (b, o, bb, c) = (d.blend_bits, d.offset_bits, d.bilinear_bits, p.coef_bits);
    let n = d.taps;
    // Texels per reconstructed sample and the width of a weight (a cubic's are signed).
    let rt = d.reconstruction.texels().pow(2) as u32;
    let wb = if d.reconstruction.cubic().is_some() {
        bb + 2
    } else {
        bb + 1
    };
    let gt = plan.coef.len() as u32;
    let lg = clog2(n as u64 + 1);
    // sigma_max, the CoC radius (SIGMA_FRAC + b fraction bits) and the full-resolution
    // positions (sign, pixel index,
    // SIGMA_FRAC + offset fraction bits).
    let s_bits = (64 - (plan.sigma_max_code as u64).leading_zeros()).max(1);
    let r_bits = s_bits + b + 1;
    let pos_bits = 1 + clog2(plan.width.max(plan.height) as u64 + 1) + SIGMA_FRAC + b + o;
    let tap_bits = sb + b + 1;
    let mut adders = vec![
        Unit::adder("box sums", 1, fb + 2 * plan.factor_log2),
        Unit::adder("Gaussian tap sums (horizontal)", gt, sb + c),
        Unit::adder("Gaussian tap sums (vertical)", gt, sb + c),
        Unit::adder("blend ROM interpolation", 1, b + 2),
        Unit::adder("tap positions", 2 * n, pos_bits),
        Unit::adder(
            &format!("{} sums", d.reconstruction.name()),
            (rt - 1) * (n + 1),
            sb + 2 * bb + 2,
        ),
        Unit::adder("depth comparisons (tap in front)", n, z_bits),
        Unit::adder("tap mixes", n + 1, tap_bits),
        Unit::adder("weighted tap sum", n, tap_bits + b + 1 + lg),
        Unit::adder("weight sum", n, b + 1 + lg),
    ];
    if d.leak_guard == LeakGuard::Difference {
        adders.push(Unit::adder("leak weights 1 - (b_c - b_t)+", 2 * n, b + 1));
    }
    let mut multipliers = vec![
        Unit::mul("Gaussian taps (horizontal)", gt, sb, c + 1),
        Unit::mul("Gaussian taps (vertical)", gt, sb, c + 1),
        Unit::mul("CoC radius beta x sigma_max", 1, b + 1, s_bits),
        Unit::mul("tap offsets r x d", n, r_bits, o + 1),
        Unit::mul(
            &format!("{} weight products", d.reconstruction.name()),
            rt * (n + 1),
            wb,
            wb,
        ),
        Unit::mul(
            &format!("{} taps", d.reconstruction.name()),
            rt * (n + 1),
            sb,
            2 * wb - 1,
        ),
        Unit::mul("tap mixes", 2 * (n + 1), sb, b + 1),
        Unit::mul("tap weight x value", n, tap_bits, b + 1),
        Unit::mul("normaliser divide", 1, tap_bits + b + 1 + lg, b + 1 + lg),
    ];
    if plan.rom_shift > 0 {
        multipliers.push(Unit::mul(
            "blend ROM interpolation",
            1,
            b + 2,
            plan.rom_shift,
        ));
    }
    let mut memories = vec![
        Memory::ram(BOX_ROW, sw, fb + 2 * plan.factor_log2),
        Memory::ram(LINE_BUFFERS, (gt as u64 + 1) * sw, sb),
        Memory::ram(BLURRED, sw * sh, sb),
        Memory::ram(WINDOW, (2 * plan.reach as u64 + 1) * w, fb + z_bits + b + 1),
        Memory::rom(OFFSET_ROM, n as u64 / 2, 2 * (o + 1)),
        Memory::rom(BLEND_ROM, plan.blend_rom.len() as u64, b + 1),
        Memory::rom(COEF_ROM, plan.m as u64 + 1, c + 1),
    ];
    if d.reconstruction.cubic().is_some() {
        memories.push(Memory::rom(RECON_ROM, (1u64 << bb) + 1, 4 * wb));
    }
    Cost::new(memories, adders, multipliers)
}

/// The contents of the memories that hold more than transient values (names as in
/// [`cost`]): the blurred small image (one small-format word per texel, as the fixed model
/// left it), the offset ROM (two `offset_bits + 1`-bit two's complement fields per word),
/// the blend ROM and the Gaussian's centre and one-side taps. The box accumulators, the
/// Gaussian's line buffers and the blend window hold transient values and have none.
pub fn memories(plan: &DownPlan, p: &DofCfg, frame_fmt: QFormat) -> Vec<MemImage> {
    let d = &p.downsample;
    let sb = small_format(frame_fmt, d.guard_bits).total_bits();
    let words = Arc::new(plan.taps.rom_words());
    let offsets = MemImage {
        name: OFFSET_ROM.into(),
        fields: vec![d.offset_bits + 1, d.offset_bits + 1],
        words: words.len(),
        region_only: false,
        get: Arc::new(move |w, f| if f == 0 { words[w].0 } else { words[w].1 }),
    };
    let mut v = vec![
        MemImage::table(BLURRED, sb, plan.blurred.clone()),
        offsets,
        MemImage::table(
            BLEND_ROM,
            d.blend_bits + 1,
            Arc::new(plan.blend_rom.clone()),
        ),
        MemImage::table(
            COEF_ROM,
            p.coef_bits + 1,
            Arc::new(plan.coef[plan.m..].to_vec()),
        ),
    ];
    if let Some(bc) = d.reconstruction.cubic() {
        // Four two's-complement fields of `bilinear_bits + 2` bits per entry.
        let wb = d.bilinear_bits + 2;
        let rom = Arc::new(super::recon::rom(bc, d.bilinear_bits));
        v.push(MemImage {
            name: RECON_ROM.into(),
            fields: vec![wb; 4],
            words: rom.len(),
            region_only: false,
            get: Arc::new(move |w, f| (rom[w][f] as u64) & ((1u64 << wb) - 1)),
        });
    }
    v
}

/// One token per full-resolution row (the blend streams rows to gamma): its blend outputs,
/// plus, on the row that completes a small row, that row's box output and its two Gaussian
/// pass outputs (the passes' row latency is not modelled).
pub fn tokens(plan: &DownPlan) -> Tokens {
    let (f, h) = (plan.factor, plan.height);
    let items = (0..h)
        .map(|y| {
            let completes = y % f == f - 1 || y + 1 == h;
            (plan.width + if completes { 3 * plan.small_width } else { 0 }) as u64
        })
        .collect();
    Tokens {
        kind: TokenKind::Row,
        item: "outputs",
        items,
        port_bits: vec![],
        rows: vec![],
        stream: None,
    }
}
