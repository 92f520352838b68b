//! The colour parts of a colour render's page: the fixed and float images in RGB (each
//! channel scaled from its own DAC width), each channel's difference map, the banding map
//! with one plane per channel, the CIEDE2000 heat map with its legend, and the colour
//! figures the text report prints (CIEDE2000, hue shift, contour steps, and per channel the
//! code comparison, overflows and storage). A grey render has none of them.

use super::images::{self, Picture};
use crate::colour::{JND, MIN_CHROMA, delta_e_image};
use crate::output::interleave;
use crate::perceptual::banding_image;
use crate::pipeline::colour::{ColourReport, NAMES};
use crate::pipeline::{ColourRender, Render};
use serde::Serialize;

/// The colour section of the page (the template's `page.colour`).
#[derive(Serialize)]
pub struct ColourSection {
    /// What the section and the rest of the page show of the channels.
    pub note: String,
    /// The CIEDE2000 heat map and its legend.
    pub delta_e: Picture,
    /// The colour figures: name, value.
    pub figures: Vec<(String, String)>,
    /// One row per channel, R, G, B.
    pub channels: Vec<ChannelRow>,
}

/// One channel's line of the colour section.
#[derive(Serialize)]
pub struct ChannelRow {
    /// `R`, `G` or `B`.
    pub name: String,
    /// Frame-memory word.
    pub frame: String,
    /// DAC width.
    pub dac_bits: u32,
    /// Identical DAC codes, percent.
    pub identical: String,
    /// Largest |fixed - reference|, codes.
    pub max_diff: u32,
    /// Pixels with a visible Weber difference.
    pub visible: u64,
    /// Visible contour steps, fixed / float reference.
    pub contours: String,
    /// Overflows over the signals of the channel's lane.
    pub overflows: u64,
    /// RAM bits of the channel's lane.
    pub storage_bits: u64,
    /// ROM bits of the channel's lane.
    pub lut_bits: u64,
}

/// The pictures of colour render `c` of `size` pixels: the fixed and float images, each
/// channel's difference map, the banding map.
pub fn pictures(c: &ColourRender, size: (u32, u32)) -> Vec<Picture> {
    let ch = &c.channels;
    let bits = [0, 1, 2].map(|k| ch[k].bits);
    let caption = format!(
        "R, G and B DAC codes ({} bits), each channel scaled from its own width to 8 bits",
        bits.map(|b| b.to_string()).join("-")
    );
    let image = |title: &str, reference: bool| {
        let planes = [0, 1, 2].map(|k| {
            if reference {
                ch[k].dac_ref.as_slice()
            } else {
                ch[k].dac.as_slice()
            }
        });
        let px = images::rgb(planes, bits);
        Picture::png(title, caption.clone(), &px, size, true, Vec::new())
    };
    let mut v = vec![
        image("fixed pipeline", false),
        image("float reference", true),
    ];
    for (name, k) in NAMES.iter().zip(ch) {
        v.push(Picture::diff(
            &format!("difference, channel {name}"),
            |max| format!("channel {name}: fixed minus reference, DAC codes (largest |diff| {max}): red where the fixed pipeline is brighter"),
            &k.dac,
            &k.dac_ref,
            size,
        ));
    }
    let band: Vec<Vec<u8>> = ch
        .iter()
        .map(|k| banding_image(&k.dac, &k.contour_map, (1u32 << k.bits) - 1))
        .collect();
    let (caption, legend) = super::images::banding_legend(
        "each channel's banding map in its own colour plane: the output dimmed, smooth regions lifted, a channel's visible contour steps at full level in its plane (white where all three step)",
        ch.iter()
            .map(|k| k.contour_map.iter().filter(|&&m| m == 2).count())
            .sum(),
    );
    v.push(Picture::png(
        "banding map",
        caption,
        &interleave(&band),
        size,
        true,
        legend,
    ));
    v
}

/// The one-line colour figure under the page's title.
pub fn headline(c: &ColourReport) -> String {
    format!(
        "CIEDE2000 mean {:.4}, max {:.2}, {} px over {JND}; mean hue shift {:.3} deg",
        c.delta_e.mean, c.delta_e.max, c.delta_e.over_jnd, c.hue_shift.mean_deg
    )
}

/// The colour section of render `r` of `size` pixels (`None`: a grey render).
pub fn section(r: &Render, size: (u32, u32)) -> Option<ColourSection> {
    let (c, rep) = (r.colour.as_ref()?, r.report.colour.as_ref()?);
    let (e, hue) = (&rep.delta_e, &rep.hue_shift);
    let delta_e = Picture::png(
        "CIEDE2000 heat map",
        format!(
            "per pixel CIEDE2000 of the fixed against the float image through the display (each channel's transfer, sRGB primaries, D65 white): black 0, blue 1, yellow {JND} (the just-noticeable difference), red 5 and above"
        ),
        &delta_e_image(&c.delta_e, size.0, size.1),
        size,
        true,
        images::delta_e_legend(),
    );
    let deg = |v: f64| format!("{v:.3} deg");
    let figures = vec![
        ("CIEDE2000 mean".into(), format!("{:.4}", e.mean)),
        ("CIEDE2000 p99".into(), format!("{:.4}", e.p99)),
        ("CIEDE2000 max".into(), format!("{:.4}", e.max)),
        (
            "pixels over 1".into(),
            format!("{} of {}", e.over_1, e.pixels),
        ),
        (
            format!("pixels over {JND} (the JND)"),
            e.over_jnd.to_string(),
        ),
        (
            format!("pixels over {JND} as Delta E*ab"),
            e.over_jnd_ab.to_string(),
        ),
        (
            "hue shift: pixels".into(),
            format!(
                "{} of {} smooth px (chroma >= {MIN_CHROMA})",
                hue.pixels, hue.smooth_pixels
            ),
        ),
        ("hue shift mean".into(), deg(hue.mean_deg)),
        ("hue shift p99".into(), deg(hue.p99_deg)),
        ("hue shift max".into(), deg(hue.max_deg)),
        (
            "contour steps over R, G, B".into(),
            format!(
                "{} (float reference {})",
                rep.contour_steps[0], rep.contour_steps[1]
            ),
        ),
    ];
    let channels = rep
        .channels
        .iter()
        .map(|ch| {
            let (codes, k) = (&ch.end_to_end.codes, &ch.contours);
            ChannelRow {
                name: ch.name.into(),
                frame: ch.frame.clone(),
                dac_bits: ch.dac_bits,
                identical: format!("{:.4}%", 100.0 * codes.identical_fraction),
                max_diff: codes.max_abs_diff,
                visible: ch.end_to_end.weber.over_delta,
                contours: format!("{}/{}", k.contour_steps, k.contour_steps_reference),
                overflows: ch.overflows,
                storage_bits: ch.storage_bits,
                lut_bits: ch.lut_bits,
            }
        })
        .collect();
    Some(ColourSection {
        note: "R, G and B run through one raster and one z-buffer, then one lane each. The facts marked channel R, the stage table, the signals and the plots are channel R's (the geometry stages are shared); the overflows and the cycle model's cost count every channel.".into(),
        delta_e,
        figures,
        channels,
    })
}
