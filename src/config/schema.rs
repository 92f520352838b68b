//! What every field of a hardware file accepts, by dotted path: the hints that messages from
//! the TOML layer name (`accumulate.weight_bits` expects `an integer in 2 log2(samples)..=16`).
//! Built from the same constants as the sections' validation.

use super::accumulate::{FilterKind, GAUSSIAN_SIGMA, MAX_WEIGHT_BITS, MITCHELL_BC};
use super::coding::{ACC_FRAC_BITS, MAX_LOG_BITS, MIN_LOG_BITS, TABLE_ADDR_BITS, TABLE_FRAC_BITS};
use super::cycles::{CLOCK_MHZ, FRAME_PORT_BITS, TILE, TIMED, TIMING_RANGES};
use super::dither::{BLUE_NOISE_SIZES, ERROR_INT_BITS, FRAC_BITS, MAX_ERROR_FRAC_BITS};
use super::dof::{
    AlphaNorm, DOF_BITS, DofKernel, DofKind, DofSchedule, DownsampleCfg, LuminanceCfg,
    MAX_HALF_SIZE_LIMIT, SIGMA_ROM_BITS,
};
use super::gamma::{DAC_BITS, MAX_GAMMA};
use super::raster::{INTERP_GUARD_BITS, MAX_GUARD_BAND};
use super::{MAX_LUT_ADDRESS_BITS, MAX_SUBPIXEL_BITS, PRESETS};
use crate::fixed::{Overflow, Quant};

fn range(r: &std::ops::RangeInclusive<u32>) -> String {
    format!("an integer in {}..={}", r.start(), r.end())
}

fn names(xs: impl Iterator<Item = &'static str>) -> String {
    xs.map(|n| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ")
}

/// What a hardware field expects, by dotted path: the message hint of the TOML layer. `None`
/// for a path that is not a field.
pub(crate) fn hint(path: &str) -> Option<String> {
    let quant = || format!("one of {}", names(Quant::ALL.iter().map(|q| q.name())));
    let overflow = || format!("one of {}", names(Overflow::ALL.iter().map(|o| o.name())));
    let boolean = || "true or false".to_string();
    let s = |x: &str| x.to_string();
    let (section, field) = path.split_once('.').unwrap_or((path, ""));
    let table = |fields: &str| format!("a table [{section}] with {fields} (each optional)");
    Some(match (section, field) {
        ("", "") => s(
            "a hardware file: an optional preset and the sections [input], [raster], [visibility], [accumulate], [gamma], [cycles], [dither], [dof], [coding]",
        ),
        ("preset", "") => format!("one of {}", names(PRESETS.iter().copied())),
        ("input", "") => table("coord, z, intensity, quant, overflow"),
        ("input", "coord") => format!(
            "a signed format \"Q<int>.<frac>\" (e.g. \"Q13.4\"): frac (the sub-pixel bits) in log2(raster.samples) + 1..={MAX_SUBPIXEL_BITS}, int + frac in 1..=32"
        ),
        ("input", "z") | ("visibility", "z") => s(
            "an unsigned format \"UQ0.<frac>\" (e.g. \"UQ0.24\", depth in [0, 1)), frac in 1..=32; visibility.z no wider than input.z",
        ),
        ("input", "intensity") => s(
            "an unsigned format \"UQ<int>.<frac>\" with the accumulator's integer bits (e.g. \"UQ12.4\"), int + frac in 1..=32",
        ),
        ("raster", "") => table("samples, interp_guard_bits, interp_quant, guard_band"),
        ("raster", "samples") => s("1, 2, 4 or 8 (an n x n sample grid per pixel)"),
        ("raster", "interp_guard_bits") => range(&INTERP_GUARD_BITS),
        ("raster", "guard_band") => format!("an integer in 0..={MAX_GUARD_BAND} (pixels)"),
        ("visibility", "") => table("z, quant"),
        ("accumulate", "") => {
            table("filter, weight_bits, gaussian_sigma, mitchell, frame, quant, overflow")
        }
        ("accumulate", "filter") => {
            format!("one of {}", names(FilterKind::ALL.iter().map(|f| f.name())))
        }
        ("accumulate", "mitchell") => format!(
            "a table {{ b = <B>, c = <C> }} of the Mitchell-Netravali family, each a finite number in [{:?}, {:?}] (used by filter = \"mitchell\")",
            MITCHELL_BC.start(),
            MITCHELL_BC.end()
        ),
        ("accumulate", "mitchell.b") | ("accumulate", "mitchell.c") => format!(
            "a finite number in [{:?}, {:?}]",
            MITCHELL_BC.start(),
            MITCHELL_BC.end()
        ),
        ("accumulate", "weight_bits") => {
            format!("an integer in 2 log2(raster.samples)..={MAX_WEIGHT_BITS}")
        }
        ("accumulate", "gaussian_sigma") => format!(
            "a finite number in [{:?}, {:?}] (pixels)",
            GAUSSIAN_SIGMA.start(),
            GAUSSIAN_SIGMA.end()
        ),
        ("accumulate", "frame") => format!(
            "an unsigned format \"UQ<int>.<frac>\" (e.g. \"UQ12.0\"), int (the gamma LUT address) in 1..={MAX_LUT_ADDRESS_BITS}, int + frac in 1..=32"
        ),
        ("gamma", "") => table("dac_bits, quant, gamma, correction"),
        ("gamma", "dac_bits") => range(&DAC_BITS),
        ("gamma", "gamma") => format!("a finite number in (0, {MAX_GAMMA}]"),
        ("cycles", "") => table(&format!(
            "clock_mhz, tile, frame_port_bits and a table per stage ({})",
            names(TIMED.iter().map(|t| t.name()))
        )),
        ("cycles", "clock_mhz") => format!(
            "a finite number in [{}, {}] (MHz)",
            CLOCK_MHZ.start(),
            CLOCK_MHZ.end()
        ),
        ("cycles", "tile") => format!(
            "a power of two in {}..={} (pixels)",
            TILE.start(),
            TILE.end()
        ),
        ("cycles", "frame_port_bits") => range(&FRAME_PORT_BITS),
        ("cycles", f) => {
            let (stage, leaf) = f.split_once('.').unwrap_or((f, ""));
            TIMED.iter().find(|t| t.name() == stage)?;
            if leaf.is_empty() {
                format!("a table [cycles.{stage}] with lanes, latency, ii, fifo (each optional)")
            } else {
                let (_, lo, hi) = TIMING_RANGES.iter().find(|(n, _, _)| *n == leaf)?;
                format!("an integer in {lo}..={hi}")
            }
        }
        ("dither", "") => table(
            "kind, placement, frac_bits, serpentine, error, blue_noise_size, seed, temporal, frame",
        ),
        ("dither", "kind") => s(
            "one of \"none\", \"bayer2\", \"bayer4\", \"bayer8\", \"blue_noise\", \"floyd_steinberg\"",
        ),
        ("dither", "placement") => s("one of \"after_lut\", \"before_lut\""),
        ("dither", "frac_bits") => range(&FRAC_BITS),
        ("dither", "error") => format!(
            "a signed format \"Q<int>.<frac>\" (e.g. \"Q2.8\"), int in {}..={}, frac in dither.frac_bits..={MAX_ERROR_FRAC_BITS}",
            ERROR_INT_BITS.start(),
            ERROR_INT_BITS.end()
        ),
        ("dither", "blue_noise_size") => format!(
            "one of {}",
            BLUE_NOISE_SIZES.map(|n| n.to_string()).join(", ")
        ),
        ("dither", "seed") => s("an integer in 0..=18446744073709551615"),
        ("dither", "frame") => s("an integer in 0..=4294967295 (the frame number)"),
        ("dof", "") => table(
            "kind, kernel, schedule, sigma, sigma_rom_bits, p, k, coef_bits, alpha_bits, alpha_norm, guard_bits, line_bits, acc_bits, max_half_size, quant, overflow, skip_uniform_tiles, and the tables [dof.luminance], [dof.downsample]",
        ),
        ("dof", "kind") => format!("one of {}", names(DofKind::ALL.iter().map(|k| k.name()))),
        ("dof", "kernel") => format!("one of {}", names(DofKernel::ALL.iter().map(|k| k.name()))),
        ("dof", "schedule") => format!(
            "one of {}",
            names(DofSchedule::ALL.iter().map(|k| k.name()))
        ),
        ("dof", "sigma") => s("one of \"paper\", \"affine\""),
        ("dof", "alpha_norm") => {
            format!("one of {}", names(AlphaNorm::ALL.iter().map(|k| k.name())))
        }
        ("dof", "sigma_rom_bits") => range(&SIGMA_ROM_BITS),
        ("dof", f) if f == "luminance" || f.starts_with("luminance.") => LuminanceCfg::hint(
            f.strip_prefix("luminance")
                .unwrap_or("")
                .trim_start_matches('.'),
        )?,
        ("dof", f) if f == "downsample" || f.starts_with("downsample.") => DownsampleCfg::hint(
            f.strip_prefix("downsample")
                .unwrap_or("")
                .trim_start_matches('.'),
        )?,
        ("dof", "p") => s("a finite number in (0, 1) (the layer difference-degree threshold)"),
        ("dof", "k") => s("a finite number in (0, 1) (the mask's edge/centre ratio)"),
        ("dof", "max_half_size") => {
            format!("an integer in 1..={MAX_HALF_SIZE_LIMIT} (pixels)")
        }
        ("dof", "skip_uniform_tiles") => {
            s("true or false (a chip that skips 16x16 tiles of uniform mask windows)")
        }
        ("dof", "overflow") | ("coding", "overflow") => s("one of \"SAT\", \"ERROR\""),
        ("dof", f) if DOF_BITS.iter().any(|(n, _, _)| *n == f) => {
            let (_, lo, hi) = DOF_BITS.iter().find(|(n, _, _)| *n == f)?;
            format!("an integer in {lo}..={hi}")
        }
        ("coding", "") => table(
            "kind, log_bits, acc_frac_bits, table_addr_bits, table_frac_bits, interpolate, quant, overflow",
        ),
        ("coding", "kind") => s("one of \"linear\", \"log-potentiate\", \"log-add\""),
        ("coding", "log_bits") => format!("an integer in {MIN_LOG_BITS}..={MAX_LOG_BITS}"),
        ("coding", "acc_frac_bits") => range(&ACC_FRAC_BITS),
        ("coding", "table_addr_bits") => range(&TABLE_ADDR_BITS),
        ("coding", "table_frac_bits") => range(&TABLE_FRAC_BITS),
        (_, "quant" | "interp_quant") => quant(),
        (_, "overflow") => overflow(),
        (_, "correction" | "serpentine" | "temporal" | "interpolate") => boolean(),
        _ => return None,
    })
}
