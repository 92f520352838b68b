//! The thin-lens blur as a function of the depth code (docs/reference.md §2a, §2b): the
//! [`LensMap`] constants and the per-pixel sigma code `sigma = G (z - z_e)`.

use crate::fixed::{Quant, round_shift};
use crate::scene::{Camera, Lens, screen_z};
use serde::Serialize;

/// Fraction bits of the per-pixel sigma code (pixels): `sigma = code * 2^-8`.
pub const SIGMA_FRAC: u32 = 8;
/// Fraction bits of the slope constant G (pixels per unit of screen z).
pub const G_FRAC: u32 = 16;

/// The thin-lens blur as a function of the depth code: `sigma = G (z - z_e)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LensMap {
    /// Pixels of sigma per unit of screen z.
    pub g: f64,
    /// Screen z of the far edge of the in-focus band.
    pub z_far_edge: f64,
    /// Screen z of the near edge of the in-focus band.
    pub z_near_edge: f64,
    /// Screen z of infinity (the background), `> 1`.
    pub z_inf: f64,
    /// Fraction bits of the depth codes (`u32::MAX` = background).
    pub z_frac: u32,
    /// Permissible circle of confusion in pixels (docs/reference.md §2b), for the in-focus count.
    pub coc_px: f64,
}

impl LensMap {
    /// From a thin-lens camera and the image height; `None` for a pinhole camera.
    pub fn from_camera(cam: &Camera, height: u32, z_frac: u32) -> Option<Self> {
        let Lens::ThinLens {
            focal_length,
            lens_radius,
            focus_distance,
            deep,
            coc,
        } = cam.lens
        else {
            return None;
        };
        let tan = (cam.fov_y_deg.to_radians() / 2.0).tan();
        let k = lens_radius * height as f64 / (2.0 * tan);
        let g = k * (1.0 / cam.near - 1.0 / cam.far);
        let v0 = focal_length * focus_distance / (focus_distance - focal_length);
        Some(Self {
            g,
            z_far_edge: screen_z(cam, focus_distance + deep),
            z_near_edge: screen_z(cam, (focus_distance - deep).max(cam.near)).max(0.0),
            z_inf: 1.0 / (1.0 - cam.near / cam.far),
            z_frac,
            coc_px: coc * height as f64 / (2.0 * v0 * tan),
        })
    }

    /// Screen z of a depth code.
    pub fn z_of(&self, key: u32) -> f64 {
        if key == u32::MAX {
            self.z_inf
        } else {
            key as f64 / (1u64 << self.z_frac) as f64
        }
    }

    /// Exact sigma (pixels, signed: negative in front of the focus) at screen z.
    pub fn sigma_z(&self, z: f64) -> f64 {
        if z > self.z_far_edge {
            self.g * (z - self.z_far_edge)
        } else if z < self.z_near_edge {
            self.g * (z - self.z_near_edge)
        } else {
            0.0
        }
    }

    /// Exact sigma of a depth code.
    pub fn sigma_f64(&self, key: u32) -> f64 {
        self.sigma_z(self.z_of(key))
    }

    /// Circle of confusion in pixels at a depth code, without the in-focus band: `2 |sigma|`.
    pub fn coc_f64(&self, key: u32) -> f64 {
        2.0 * self.g * (self.z_of(key) - (self.z_far_edge + self.z_near_edge) / 2.0).abs()
    }

    fn code(&self, z: f64) -> i64 {
        (z * (1u64 << self.z_frac) as f64).round() as i64
    }

    /// Fixed-point sigma code (`SIGMA_FRAC` fraction bits): one `z x G` multiply and a
    /// round-to-nearest shift, with the constants quantised once.
    pub fn sigma_code(&self, key: u32) -> i64 {
        let z = if key == u32::MAX {
            self.code(self.z_inf)
        } else {
            key as i64
        };
        let (zf, zn) = (self.code(self.z_far_edge), self.code(self.z_near_edge));
        let d = if z > zf {
            z - zf
        } else if z < zn {
            z - zn
        } else {
            return 0;
        };
        let g = (self.g * (1u64 << G_FRAC) as f64).round() as i128;
        round_shift(d as i128 * g, self.z_frac + G_FRAC - SIGMA_FRAC, Quant::Rnd) as i64
    }

    /// Width of the G constant in bits (integer + `G_FRAC`).
    pub fn g_bits(&self) -> u32 {
        (self.g.max(1.0).log2().floor() as u32 + 1) + G_FRAC
    }
}
