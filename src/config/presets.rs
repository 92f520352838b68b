//! The hardware presets: the paper's configurations (docs/reference.md §1): 12-, 11- and
//! 8-bit linear accumulators, and 8- or 7-bit log codes with potentiation or log arithmetic.

use super::{
    AccumulateCfg, AlphaNorm, CodingCfg, CyclesCfg, DitherCfg, DofCfg, DofKernel, DofKind,
    DofSchedule, DownsampleCfg, FilterKind, GammaCfg, HwConfig, InputCfg, LuminanceCfg, MitchellBc,
    RasterCfg, SigmaForm, VisibilityCfg,
};
use crate::fixed::{Overflow, QFormat, Quant, Quantizer};

/// Preset names, the first is the default.
pub const PRESETS: &[&str] = &[
    "linear12",
    "linear11",
    "linear8",
    "log8-potentiate",
    "log8-logadd",
    "log7-logadd",
];

const fn q(signed: bool, i: u32, f: u32, quant: Quant, overflow: Overflow) -> Quantizer {
    Quantizer::new(QFormat::new(signed, i, f), quant, overflow)
}

/// A preset by name.
pub fn preset(name: &str) -> Option<HwConfig> {
    let (acc_bits, coding) = match name {
        "linear12" => (12, CodingCfg::linear()),
        "linear11" => (11, CodingCfg::linear()),
        "linear8" => (8, CodingCfg::linear()),
        _ => (12, CodingCfg::preset(name)?),
    };
    Some(HwConfig {
        name: name.to_string(),
        input: InputCfg {
            // Q13.4: +-4096 px at 1/16 px.
            coord: q(true, 13, 4, Quant::RndConv, Overflow::Sat),
            z: q(false, 0, 24, Quant::RndConv, Overflow::Sat),
            intensity: q(false, acc_bits, 4, Quant::RndConv, Overflow::Sat),
        },
        raster: RasterCfg {
            samples: 4,
            interp_guard_bits: 14,
            interp_quant: Quant::RndConv,
            guard_band: 64,
        },
        visibility: VisibilityCfg {
            z: q(false, 0, 24, Quant::Trn, Overflow::Sat),
        },
        accumulate: AccumulateCfg {
            filter: FilterKind::Tent,
            weight_bits: 10,
            gaussian_sigma: 0.5,
            mitchell: MitchellBc::THIRD,
            frame: q(false, acc_bits, 0, Quant::RndConv, Overflow::Sat),
        },
        gamma: GammaCfg {
            dac_bits: 8,
            quant: Quant::RndConv,
            gamma: None,
            correction: true,
        },
        cycles: CyclesCfg::default_for(acc_bits),
        dither: DitherCfg::default(),
        dof: DofCfg {
            kind: DofKind::Layered,
            kernel: DofKernel::Gaussian,
            schedule: DofSchedule::Stream,
            sigma: SigmaForm::Paper,
            sigma_rom_bits: 10,
            p: 0.1,
            k: 0.05,
            coef_bits: 12,
            alpha_bits: 12,
            alpha_norm: AlphaNorm::Behind,
            guard_bits: 4,
            // x * coverage ((2^acc - 1) * 16 < 2^(acc + 4) for 4x4 samples) times the 2^12 tap sum.
            line_bits: acc_bits + 4 + 12,
            acc_bits: acc_bits + 4 + 24,
            max_half_size: 32,
            quant: Quant::RndConv,
            overflow: Overflow::Sat,
            skip_uniform_tiles: false,
            luminance: LuminanceCfg::default(),
            downsample: DownsampleCfg::default(),
        },
        coding,
        source: crate::files::Source::preset(name),
        channels: None,
    })
}
