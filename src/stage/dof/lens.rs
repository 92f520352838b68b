//! The thin-lens blur as a function of the depth code (docs/reference.md §2a, §2b): the
//! [`LensMap`] constants and the per-pixel sigma code `sigma = G (z - z_e)`.

use crate::fixed::{Overflow, QFormat, Quant, Quantizer, round_shift};
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

    /// The quantiser of the slope constant G: `UQ<i>.16` (`G_FRAC` fraction bits, `i` the
    /// integer bits of G after rounding, at least 1), RND_INF, SAT (the format holds G, so SAT
    /// does not act below 62 bits).
    pub fn g_quantizer(&self) -> Quantizer {
        fitted(G_FRAC, &[self.g])
    }

    /// G as the hardware holds it: a code with `G_FRAC` fraction bits.
    pub fn g_code(&self) -> i64 {
        self.g_quantizer().quantize_f64(self.g).code
    }

    /// The quantiser of the screen-z constants (the in-focus band edges, infinity and the
    /// layers' middle depths) as depth codes: `UQ<i>.<z_frac>` with `i` the integer bits of
    /// `z_inf > 1` rounded (`UQ1.24` with the default z buffer), signed `Q<i+1>.<z_frac>` when
    /// the band's far edge lies before the near plane (negative z); RND_INF, SAT (the format
    /// holds every constant, so SAT does not act below 62 bits).
    pub fn z_quantizer(&self) -> Quantizer {
        fitted(
            self.z_frac,
            &[self.z_inf, self.z_far_edge, self.z_near_edge],
        )
    }

    /// The depth code of a screen z in `[min(z_far_edge, 0), z_inf]`, quantised with
    /// [`LensMap::z_quantizer`].
    pub fn z_code(&self, z: f64) -> i64 {
        self.z_quantizer().quantize_f64(z).code
    }

    /// Fixed-point sigma code (`SIGMA_FRAC` fraction bits, signed): one `z x G` multiply and
    /// a round-to-nearest shift (RND, the shared `round_shift`) of the exact product, with the
    /// constants as the hardware holds them ([`LensMap::z_quantizer`],
    /// [`LensMap::g_quantizer`]; the model quantises them on every call).
    pub fn sigma_code(&self, key: u32) -> i64 {
        let zq = self.z_quantizer();
        let code = |z: f64| zq.quantize_f64(z).code;
        let z = if key == u32::MAX {
            code(self.z_inf)
        } else {
            key as i64
        };
        let (zf, zn) = (code(self.z_far_edge), code(self.z_near_edge));
        let d = if z > zf {
            z - zf
        } else if z < zn {
            z - zn
        } else {
            return 0;
        };
        let g = self.g_code() as i128;
        round_shift(d as i128 * g, self.z_frac + G_FRAC - SIGMA_FRAC, Quant::Rnd) as i64
    }

    /// Width of the G constant in bits (integer + `G_FRAC`): its quantiser's format.
    pub fn g_bits(&self) -> u32 {
        self.g_quantizer().format.total_bits()
    }
}

/// Rounding of the lens constants: RND_INF, to nearest with ties away from zero, which is
/// `f64::round` for every sign.
const CONST_QUANT: Quant = Quant::RndInf;

/// Widest word of a lens constant (the quantiser is exact up to 62 bits; the 32-bit limit of
/// the configurable formats does not bind these internal words).
const CONST_MAX_BITS: u32 = 62;

/// The quantiser of the constants `xs`: `frac` fraction bits, [`CONST_QUANT`], SAT and the
/// fewest integer bits (at least 1, plus a sign bit when one of `xs` is negative) that hold
/// every `xs` after rounding, so SAT acts only beyond [`CONST_MAX_BITS`] (no overflow to
/// count). The estimate from the largest magnitude is short by one bit at most, when
/// rounding carries into the next power of two.
fn fitted(frac: u32, xs: &[f64]) -> Quantizer {
    let signed = xs.iter().any(|&x| x < 0.0);
    let m = xs.iter().fold(1.0f64, |a, &x| a.max(x.abs()));
    let int_max = CONST_MAX_BITS.saturating_sub(frac).max(1);
    let q = |int: u32| {
        let f = QFormat::new(signed, int.min(int_max), frac);
        Quantizer::new(f, CONST_QUANT, Overflow::Sat)
    };
    let int = (m.log2().floor() as u32).min(CONST_MAX_BITS) + 1 + u32::from(signed);
    let first = q(int);
    if xs.iter().any(|&x| first.quantize_f64(x).overflow) {
        q(int + 1)
    } else {
        first
    }
}
