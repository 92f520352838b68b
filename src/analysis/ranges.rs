//! Observed ranges of the instrumented signals and the narrowest formats holding them,
//! and an export of a configuration's formats as HLS / SystemC typedefs and Verilog parameters.
//!
//! A colour render lists every channel: the geometry stages once (their vertex intensity
//! per channel), then each stage after visibility once per channel; its export has a
//! typedef per channel of each per-channel format (suffixed `_r`, `_g`, `_b`).

use crate::config::HwConfig;
use crate::fixed::{Overflow, QFormat, Quantizer, SignalStats};
use crate::pipeline::Report;
use crate::pipeline::colour::NAMES;
use crate::stage::input::intensity_signal;
use serde::Serialize;

/// One signal's observed range.
#[derive(Clone, Debug, Serialize)]
pub struct SignalRange {
    /// Stage.
    pub stage: String,
    /// The channel, `R`, `G` or `B`, of a colour render's per-channel signal (absent for a
    /// grey render and for a colour render's shared geometry signals).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub channel: Option<&'static str>,
    /// Signal name.
    pub signal: String,
    /// Configured format.
    pub format: String,
    /// Values recorded.
    pub count: u64,
    /// Smallest and largest value seen, in the format's LSBs (before overflow handling).
    pub min: Option<i128>,
    /// Largest value.
    pub max: Option<i128>,
    /// Narrowest format with the same LSB that holds [min, max] (`None` when nothing was seen).
    pub narrowest: Option<String>,
    /// Overflows counted.
    pub overflows: u64,
    /// Whether the signal is an overflow counter only (its datapath records no values, so
    /// `count`, `min` and `max` stay empty): [`SignalStats::overflow_counter`].
    pub overflow_only: bool,
}

/// Bits of the narrowest word with `frac` fraction bits holding `[min, max]` LSBs, as a format.
/// Integer bits never go below 0 (the LSB is kept); as everywhere in igemu, a signed
/// format's integer bits count the sign bit.
pub fn narrowest(min: i128, max: i128, frac: u32) -> QFormat {
    let signed = min < 0;
    let bits_for = |v: i128| 128 - v.leading_zeros();
    let w = if signed {
        // -2^(w-1) <= min and max <= 2^(w-1) - 1.
        let need_neg = bits_for(-(min + 1)) + 1;
        let need_pos = bits_for(max.max(0)) + 1;
        need_neg.max(need_pos)
    } else {
        bits_for(max).max(1)
    };
    QFormat::new(signed, w.saturating_sub(frac), frac)
}

/// Ranges of every instrumented signal of the stages, in stage order.
pub fn ranges(stages: &[crate::stage::StageReport]) -> Vec<SignalRange> {
    let mut out = Vec::new();
    for st in stages {
        for s in &st.signals {
            out.push(range_of(&st.name, None, s));
        }
    }
    out
}

/// Ranges of every instrumented signal of a render, in stage order: a grey render's as
/// [`ranges`]; for a colour render the geometry stages' signals (each vertex intensity with
/// its channel), then every stage after visibility once per channel, R, G, B.
pub fn ranges_of(report: &Report) -> Vec<SignalRange> {
    let Some(colour) = &report.colour else {
        return ranges(&report.stages);
    };
    let lane = colour.channels.first().map_or(0, |c| c.stages.len());
    let shared = report.stages.len().saturating_sub(lane);
    let mut out = Vec::new();
    for st in &report.stages[..shared] {
        for s in &st.signals {
            let channel = (0..NAMES.len())
                .find(|&c| s.name == intensity_signal(NAMES.len(), c))
                .map(|c| NAMES[c]);
            out.push(range_of(&st.name, channel, s));
        }
    }
    for k in 0..lane {
        for ch in &colour.channels {
            let st = &ch.stages[k];
            for s in &st.signals {
                out.push(range_of(&st.name, Some(ch.name), s));
            }
        }
    }
    out
}

fn range_of(stage: &str, channel: Option<&'static str>, s: &SignalStats) -> SignalRange {
    SignalRange {
        stage: stage.to_string(),
        channel,
        signal: s.name.clone(),
        format: s.format.to_string(),
        count: s.count,
        min: s.min,
        max: s.max,
        narrowest: match (s.min, s.max) {
            (Some(a), Some(b)) => Some(narrowest(a, b, s.format.frac_bits).to_string()),
            _ => None,
        },
        overflows: s.overflows,
        overflow_only: s.overflow_only,
    }
}

/// ac_fixed overflow mode (ac_fixed has no ERROR mode: the Rust model raises it, the type wraps).
fn ac_overflow(o: Overflow) -> &'static str {
    match o {
        Overflow::Wrap | Overflow::Error => "WRAP",
        Overflow::Sat => "SAT",
        Overflow::SatZero => "SAT_ZERO",
        Overflow::SatSym => "SAT_SYM",
    }
}

/// The configuration's quantisation points: (identifier, quantizer). With `channels` = 3
/// (a colour render) each per-channel point (intensity, frame, DAC) comes once per channel,
/// its identifier suffixed `_r`, `_g`, `_b`, with that channel's word.
pub fn formats(hw: &HwConfig, channels: usize) -> Vec<(String, Quantizer)> {
    let lanes: Vec<(String, HwConfig)> = match channels {
        1 => vec![(String::new(), hw.clone())],
        _ => (0..channels)
            .map(|c| (format!("_{}", NAMES[c].to_lowercase()), hw.channel(c)))
            .collect(),
    };
    let per_channel = |id: &str, q: fn(&HwConfig) -> Quantizer| {
        lanes
            .iter()
            .map(|(suffix, h)| (format!("{id}{suffix}"), q(h)))
            .collect::<Vec<_>>()
    };
    let mut v = vec![
        ("input_coord".to_string(), hw.input.coord),
        ("input_z".to_string(), hw.input.z),
    ];
    v.extend(per_channel("input_intensity", |h| h.input.intensity));
    v.push(("visibility_z".to_string(), hw.visibility.z));
    v.extend(per_channel("accumulate_frame", |h| h.accumulate.frame));
    v.extend(per_channel("gamma_dac", |h| {
        Quantizer::new(
            QFormat::new(false, h.gamma.dac_bits, 0),
            h.gamma.quant,
            Overflow::Sat,
        )
    }));
    v
}

/// Export languages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Export {
    /// Algorithmic C `ac_fixed`.
    AcFixed,
    /// Vitis HLS `ap_fixed`.
    ApFixed,
    /// SystemC `sc_fixed`.
    SystemC,
    /// Verilog `localparam`s (width and fraction bits).
    Verilog,
}

/// The typedefs / parameters of a configuration for a render of `channels` channels
/// ([`formats`]). `I` counts the sign bit, as in all three C++ libraries; the overflow mode
/// `ERROR` has no C++ equivalent and is exported as WRAP.
pub fn export(hw: &HwConfig, lang: Export, channels: usize) -> String {
    let mut s = format!("// igemu formats of `{}`", hw.name);
    if channels > 1 {
        s.push_str(" (colour: R, G and B each have their intensity, frame and DAC words)");
    }
    s.push('\n');
    for (id, q) in formats(hw, channels) {
        let f = q.format;
        let (w, i) = (f.total_bits(), f.int_bits);
        let (qm, om) = (q.quant.name(), ac_overflow(q.overflow));
        let line = match lang {
            Export::AcFixed => format!(
                "typedef ac_fixed<{w}, {i}, {}, AC_{qm}, AC_{om}> {id}_t;  // {f}\n",
                f.signed
            ),
            Export::ApFixed => format!(
                "typedef {}<{w}, {i}, AP_{qm}, AP_{om}> {id}_t;  // {f}\n",
                if f.signed { "ap_fixed" } else { "ap_ufixed" }
            ),
            Export::SystemC => format!(
                "typedef sc_dt::{}<{w}, {i}, sc_dt::SC_{qm}, sc_dt::SC_{om}> {id}_t;  // {f}\n",
                if f.signed { "sc_fixed" } else { "sc_ufixed" }
            ),
            Export::Verilog => {
                let up = id.to_uppercase();
                format!(
                    "localparam integer {up}_W = {w};  // {f}\nlocalparam integer {up}_F = {};\nlocalparam integer {up}_SIGNED = {};\n",
                    f.frac_bits,
                    u8::from(f.signed)
                )
            }
        };
        s.push_str(&line);
    }
    s
}
