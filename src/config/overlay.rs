//! The TOML overlay: a hardware file names a preset (`linear12` unless it names another) and
//! overrides single fields of it, section by section.

use super::accumulate::RawAccumulate;
use super::coding::RawCoding;
use super::cycles::RawCycles;
use super::dither::RawDither;
use super::dof::RawDof;
use super::gamma::RawGamma;
use super::input::RawInput;
use super::raster::RawRaster;
use super::visibility::RawVisibility;
use super::{HwConfig, PRESETS};
use crate::error::FileError;
use crate::files::TomlFile;
use serde::Deserialize;

/// A hardware file as written (every section and field optional).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHw {
    preset: Option<String>,
    input: Option<RawInput>,
    raster: Option<RawRaster>,
    visibility: Option<RawVisibility>,
    accumulate: Option<RawAccumulate>,
    gamma: Option<RawGamma>,
    cycles: Option<RawCycles>,
    dither: Option<RawDither>,
    dof: Option<RawDof>,
    coding: Option<RawCoding>,
}

/// Parses a hardware file onto its preset (not yet validated).
pub(super) fn apply_file(file: &TomlFile) -> Result<HwConfig, FileError> {
    let raw: RawHw = file.parse_with(&super::schema::hint)?;
    let base = raw.preset.as_deref().unwrap_or(PRESETS[0]);
    let mut hw = HwConfig::preset(base).ok_or_else(|| {
        file.error(
            "preset",
            format!("unknown preset `{base}`; allowed: {}", PRESETS.join(", ")),
        )
    })?;
    hw.name = file.name.clone();
    hw.source = crate::files::Source::file(file, Some(base));
    let intensity_given = raw.input.as_ref().is_some_and(|i| i.intensity.is_some());
    // Per-channel widths: any of the three fields given as an array of three.
    let intensity3 = raw.input.as_ref().and_then(|i| i.intensity?.three());
    let frame3 = raw.accumulate.as_ref().and_then(|a| a.frame?.three());
    let dac3 = raw.gamma.as_ref().and_then(|g| g.dac_bits?.three());
    if let Some(i) = raw.input {
        i.apply(&mut hw.input);
    }
    if let Some(r) = raw.raster {
        r.apply(&mut hw.raster);
    }
    if let Some(v) = raw.visibility {
        v.apply(&mut hw.visibility);
    }
    if let Some(a) = raw.accumulate {
        let frame_given = a.frame.is_some();
        a.apply(&mut hw.accumulate);
        // The vertex intensity follows the accumulator's integer width unless given.
        if frame_given && !intensity_given {
            hw.input.intensity.format.int_bits = hw.accumulate.frame.format.int_bits;
        }
    }
    if let Some(g) = raw.gamma {
        g.apply(&mut hw.gamma);
    }
    if let Some(c) = raw.cycles {
        c.apply(&mut hw.cycles);
    }
    if let Some(d) = raw.dither {
        d.apply(&mut hw.dither);
    }
    if let Some(d) = raw.dof {
        d.apply(&mut hw.dof);
    }
    if let Some(c) = raw.coding {
        c.apply(&mut hw.coding);
    }
    if intensity3.is_some() || frame3.is_some() || dac3.is_some() {
        let frame = frame3.unwrap_or([hw.accumulate.frame.format; 3]);
        let intensity = intensity3.unwrap_or_else(|| {
            // Each channel's vertex intensity follows its frame word's integer bits.
            frame.map(|f| {
                let mut i = hw.input.intensity.format;
                if !intensity_given {
                    i.int_bits = f.int_bits;
                }
                i
            })
        });
        hw.channels = Some(super::ChannelWidths {
            intensity,
            frame,
            dac_bits: dac3.unwrap_or([hw.gamma.dac_bits; 3]),
        });
    }
    Ok(hw)
}
