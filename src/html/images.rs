//! The pictures of the HTML report as inline PNG data (`data:image/png;base64,...`): DAC
//! codes as grey levels or, for a colour render, as RGB; the signed difference as a heat map
//! with its legend, the banding map, the depth-of-field layer map and the legend of the
//! CIEDE2000 heat map.

use base64::Engine;
use image::{ExtendedColorType, ImageEncoder, codecs::png::PngEncoder};
use serde::Serialize;

/// An encoded picture and what it shows.
#[derive(Clone, Debug, Serialize)]
pub struct Picture {
    /// Heading.
    pub title: String,
    /// How to read it.
    pub caption: String,
    /// `data:image/png;base64,...`
    pub uri: String,
    /// Width and height in pixels.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Colour keys (empty: a grey picture whose caption says what the levels are).
    pub legend: Vec<Key>,
}

impl Picture {
    /// A picture of 8-bit grey pixels (`rgb` false) or interleaved RGB ones, `size` = width
    /// and height.
    pub fn png(
        title: &str,
        caption: String,
        data: &[u8],
        size: (u32, u32),
        rgb: bool,
        legend: Vec<Key>,
    ) -> Picture {
        Picture {
            title: title.into(),
            caption,
            uri: png_uri(data, size.0, size.1, rgb),
            width: size.0,
            height: size.1,
            legend,
        }
    }

    /// The difference heat map of `fixed` minus `reference` codes with its legend; `caption`
    /// gets the largest `|diff|`.
    pub fn diff(
        title: &str,
        caption: impl Fn(i32) -> String,
        fixed: &[u16],
        reference: &[u16],
        size: (u32, u32),
    ) -> Picture {
        let (rgb, max) = diff_map(fixed, reference);
        Picture::png(title, caption(max), &rgb, size, true, diff_legend(max))
    }
}

/// One colour of a legend.
#[derive(Clone, Debug, Serialize)]
pub struct Key {
    /// CSS colour (`#rrggbb`).
    pub colour: String,
    /// What it stands for.
    pub label: String,
}

/// The banding map's caption and legend (the levels of [`crate::perceptual::banding_image`]):
/// the output dimmed to grey 0..=100, smooth regions (where contours are looked for) lifted by
/// 20, pixels beside a visible contour step white; `contour_px` such pixels. With none the
/// caption says so, so the lifted regions are not read as defects.
pub fn banding_legend(what: &str, contour_px: usize) -> (String, Vec<Key>) {
    let caption = if contour_px == 0 {
        format!(
            "{what}. 0 visible contour steps found: no white pixel; the lighter areas are the smooth regions searched for steps, not defects"
        )
    } else {
        format!("{what}. {contour_px} px beside a visible contour step (white)")
    };
    let key = |c: &str, l: &str| Key {
        colour: c.into(),
        label: l.into(),
    };
    (
        caption,
        vec![
            key(
                "#323232",
                "output dimmed to grey 0..100: not smooth (edges, texture)",
            ),
            key(
                "#464646",
                "lifted by 20: a smooth region, searched for contour steps",
            ),
            key("#ffffff", "white: beside a visible contour step"),
        ],
    )
}

/// A PNG of 8-bit grey or RGB pixels as a data URI.
pub fn png_uri(data: &[u8], width: u32, height: u32, rgb: bool) -> String {
    let mut png = Vec::new();
    let kind = if rgb {
        ExtendedColorType::Rgb8
    } else {
        ExtendedColorType::L8
    };
    PngEncoder::new(&mut png)
        .write_image(data, width, height, kind)
        .expect("a PNG encodes into memory when the buffer matches its size");
    format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(png)
    )
}

/// An SVG document as a data URI (the plots: an `<img>` of it decodes like a PNG).
pub fn svg_uri(svg: &str) -> String {
    format!(
        "data:image/svg+xml;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(svg)
    )
}

/// DAC codes of `bits` width as 8-bit grey levels (`round(code * 255 / (2^bits - 1))`).
pub fn grey(codes: &[u16], bits: u32) -> Vec<u8> {
    let max = ((1u32 << bits) - 1) as f64;
    codes
        .iter()
        .map(|&c| (c as f64 * 255.0 / max).round() as u8)
        .collect()
}

/// Three planes of DAC codes, each of its own width `bits`, as interleaved 8-bit RGB (each
/// channel scaled as in [`grey`]).
pub fn rgb(planes: [&[u16]; 3], bits: [u32; 3]) -> Vec<u8> {
    let grey: Vec<Vec<u8>> = (0..3).map(|c| grey(planes[c], bits[c])).collect();
    crate::output::interleave(&grey)
}

fn hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// The colour of a difference `d` on a scale of `-max..=max`: grey at 0, towards red where
/// the fixed pipeline is brighter and towards blue where it is darker.
pub fn diff_colour(d: i32, max: i32) -> [u8; 3] {
    const ZERO: [f64; 3] = [236.0, 236.0, 236.0];
    const UP: [f64; 3] = [178.0, 24.0, 43.0];
    const DOWN: [f64; 3] = [33.0, 102.0, 172.0];
    if d == 0 {
        return ZERO.map(|v| v as u8);
    }
    // A difference of one code is already clearly coloured.
    let t = 0.35 + 0.65 * (d.unsigned_abs() as f64 / max.max(1) as f64).min(1.0);
    let end = if d > 0 { UP } else { DOWN };
    std::array::from_fn(|i| (ZERO[i] + (end[i] - ZERO[i]) * t).round() as u8)
}

/// The difference heat map of fixed minus reference codes (RGB) and its largest `|diff|`.
pub fn diff_map(fixed: &[u16], reference: &[u16]) -> (Vec<u8>, i32) {
    let max = fixed
        .iter()
        .zip(reference)
        .map(|(&a, &b)| (a as i32 - b as i32).abs())
        .max()
        .unwrap_or(0);
    let mut rgb = Vec::with_capacity(fixed.len() * 3);
    for (&a, &b) in fixed.iter().zip(reference) {
        rgb.extend_from_slice(&diff_colour(a as i32 - b as i32, max));
    }
    (rgb, max)
}

/// The legend of a difference map whose largest `|diff|` is `max`: every value when there
/// are at most 17, else 9 evenly spaced ones.
pub fn diff_legend(max: i32) -> Vec<Key> {
    let values: Vec<i32> = if max <= 8 {
        (-max..=max).collect()
    } else {
        (-4..=4).map(|k| k * max / 4).collect()
    };
    values
        .into_iter()
        .map(|d| Key {
            colour: hex(diff_colour(d, max)),
            label: format!("{d:+}"),
        })
        .collect()
}

/// The legend of the CIEDE2000 heat map ([`crate::colour::HEAT_STOPS`]): one key per stop,
/// the colour in between interpolated.
pub fn delta_e_legend() -> Vec<Key> {
    let stops = crate::colour::HEAT_STOPS;
    stops
        .iter()
        .enumerate()
        .map(|(i, &(e, c))| Key {
            colour: hex(c),
            label: if i + 1 == stops.len() {
                format!("{e} and above")
            } else if (f64::from(e) - crate::colour::JND).abs() < 1e-6 {
                format!("{e}: the JND")
            } else {
                e.to_string()
            },
        })
        .collect()
}

/// A palette of distinguishable colours for layer `i` (the background layer is dark grey).
pub fn layer_colour(i: usize) -> [u8; 3] {
    const P: [[u8; 3]; 12] = [
        [230, 159, 0],
        [86, 180, 233],
        [0, 158, 115],
        [240, 228, 66],
        [0, 114, 178],
        [213, 94, 0],
        [204, 121, 167],
        [120, 190, 60],
        [160, 110, 60],
        [150, 150, 230],
        [250, 130, 130],
        [90, 200, 190],
    ];
    P[i % P.len()]
}

/// Background layer colour.
pub const BACKGROUND: [u8; 3] = [60, 60, 60];

/// One layer of the legend of a layer map.
#[derive(Clone, Debug)]
pub struct LayerKey {
    /// Nearest and farthest depth code of the layer (`u32::MAX`: the background).
    pub keys: (u32, u32),
    /// Legend text.
    pub label: String,
}

/// The layer map: each pixel coloured by the layer whose depth codes hold its nearest depth
/// (`u32::MAX` = nothing covers it: the background layer).
pub fn layer_map(depth: &[u32], layers: &[LayerKey]) -> (Vec<u8>, Vec<Key>) {
    let colour = |l: usize| {
        if layers[l].keys.0 == u32::MAX {
            BACKGROUND
        } else {
            layer_colour(l)
        }
    };
    // Layers hold disjoint code ranges sorted far to near: a binary search by the far end.
    let mut order: Vec<usize> = (0..layers.len()).collect();
    order.sort_by_key(|&l| layers[l].keys.1);
    let mut rgb = Vec::with_capacity(depth.len() * 3);
    for &k in depth {
        let i = order.partition_point(|&l| layers[l].keys.1 < k);
        let c = match order.get(i) {
            Some(&l) if layers[l].keys.0 <= k => colour(l),
            // Between layers (a code no pixel of the plan had): none.
            _ => [255, 255, 255],
        };
        rgb.extend_from_slice(&c);
    }
    let legend = (0..layers.len())
        .map(|l| Key {
            colour: hex(colour(l)),
            label: layers[l].label.clone(),
        })
        .collect();
    (rgb, legend)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_png_uri_decodes_back_to_its_pixels() {
        let px: Vec<u8> = (0..12u8).collect();
        let uri = png_uri(&px, 4, 3, false);
        let b64 = uri.strip_prefix("data:image/png;base64,").unwrap();
        let png = base64::engine::general_purpose::STANDARD
            .decode(b64)
            .unwrap();
        let img = image::load_from_memory(&png).unwrap().into_luma8();
        assert_eq!((img.width(), img.height()), (4, 3));
        assert_eq!(img.into_raw(), px);
    }

    #[test]
    fn differences_keep_their_sign_and_zero_is_neutral() {
        let (rgb, max) = diff_map(&[10, 11, 9, 14], &[10, 10, 10, 10]);
        assert_eq!(max, 4);
        assert_eq!(&rgb[0..3], &[236, 236, 236]);
        assert!(rgb[3] > rgb[5], "fixed brighter is red");
        assert!(rgb[8] > rgb[6], "fixed darker is blue");
        assert_eq!(
            &rgb[9..12],
            &[178, 24, 43],
            "the largest difference is the end colour"
        );
        let legend = diff_legend(max);
        assert_eq!(legend.len(), 9);
        assert_eq!(legend[4].label, "+0");
        assert_eq!(diff_legend(100).len(), 9);
    }

    #[test]
    fn rgb_scales_each_channel_from_its_own_width() {
        let rgb = rgb([&[31, 0], &[0, 32], &[0, 31]], [5, 6, 5]);
        assert_eq!(rgb, [255, 0, 0, 0, 130, 255]);
        let legend = delta_e_legend();
        let labels: Vec<&str> = legend.iter().map(|k| k.label.as_str()).collect();
        assert_eq!(labels, ["0", "1", "2.3: the JND", "5 and above"]);
        assert_eq!(legend[1].colour, "#0000ff");
    }

    #[test]
    fn a_pixel_takes_the_layer_holding_its_depth_code() {
        let layers = [
            LayerKey {
                keys: (u32::MAX, u32::MAX),
                label: "background".into(),
            },
            LayerKey {
                keys: (500, 900),
                label: "far".into(),
            },
            LayerKey {
                keys: (10, 200),
                label: "near".into(),
            },
        ];
        let (rgb, legend) = layer_map(&[u32::MAX, 700, 10, 300], &layers);
        assert_eq!(&rgb[0..3], &BACKGROUND);
        assert_eq!(&rgb[3..6], &layer_colour(1));
        assert_eq!(&rgb[6..9], &layer_colour(2));
        assert_eq!(&rgb[9..12], &[255, 255, 255]);
        assert_eq!(legend.len(), 3);
    }
}
