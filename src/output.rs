//! Writing images: DAC codes, raw stage codes and difference maps as PNG.

use crate::error::{Error, Result};
use image::{ImageBuffer, Luma};

fn save<P: image::Pixel<Subpixel = S> + image::PixelWithColorType, S: image::Primitive>(
    img: ImageBuffer<P, Vec<S>>,
    path: &str,
) -> Result<()>
where
    [S]: image::EncodableLayout,
{
    img.save(path).map_err(|e| Error::Image {
        path: path.into(),
        msg: e.to_string(),
    })
}

/// Writes DAC codes of `bits` width: 8-bit PNG for `bits <= 8`, else 16-bit, each code
/// scaled to the PNG's full range by `round(code * (2^png - 1) / (2^bits - 1))`
/// (exact identity for 8 and 16 bits).
pub fn write_dac(path: &str, codes: &[u16], width: u32, height: u32, bits: u32) -> Result<()> {
    let max = ((1u32 << bits) - 1) as f64;
    if bits <= 8 {
        let data: Vec<u8> = codes
            .iter()
            .map(|&c| (c as f64 * 255.0 / max).round() as u8)
            .collect();
        save(
            ImageBuffer::<Luma<u8>, _>::from_raw(width, height, data).expect("size matches"),
            path,
        )
    } else {
        let data: Vec<u16> = codes
            .iter()
            .map(|&c| (c as f64 * 65535.0 / max).round() as u16)
            .collect();
        save(
            ImageBuffer::<Luma<u16>, _>::from_raw(width, height, data).expect("size matches"),
            path,
        )
    }
}

/// Writes raw codes (unscaled) as a 16-bit grey PNG; codes above 65535 are an error.
pub fn write_raw16(path: &str, codes: &[u32], width: u32, height: u32) -> Result<()> {
    if let Some(&c) = codes.iter().find(|&&c| c > u16::MAX as u32) {
        return Err(Error::Image {
            path: path.into(),
            msg: format!("code {c} does not fit a 16-bit PNG"),
        });
    }
    let data: Vec<u16> = codes.iter().map(|&c| c as u16).collect();
    save(
        ImageBuffer::<Luma<u16>, _>::from_raw(width, height, data).expect("size matches"),
        path,
    )
}

/// Writes a signed difference map: 128 = identical, each code of difference is 32 grey
/// levels (fixed above the reference is brighter), clamped.
pub fn write_diff(
    path: &str,
    fixed: &[u16],
    reference: &[u16],
    width: u32,
    height: u32,
) -> Result<()> {
    let data: Vec<u8> = fixed
        .iter()
        .zip(reference)
        .map(|(&a, &b)| (128 + 32 * (a as i32 - b as i32)).clamp(0, 255) as u8)
        .collect();
    save(
        ImageBuffer::<Luma<u8>, _>::from_raw(width, height, data).expect("size matches"),
        path,
    )
}

/// Writes 8-bit grey values as they are.
pub fn write_raw8(path: &str, data: &[u8], width: u32, height: u32) -> Result<()> {
    save(
        ImageBuffer::<Luma<u8>, _>::from_raw(width, height, data.to_vec()).expect("size matches"),
        path,
    )
}
