//! The thin-lens blur as a function of the depth code (docs/reference.md §2a, §2b): the
//! [`LensMap`] constants and the sigma code of a depth code, in one of two forms
//! ([`SigmaForm`]): the paper's (the object distance shifted by `deep` toward the focus,
//! read from a sigma ROM indexed by the top depth bits, interpolated) or the affine one
//! (the depth shifted in inverse depth, `sigma = G (z - z_e)`, one multiply).

use crate::config::SigmaForm;
use crate::fixed::{Overflow, QFormat, Quant, Quantizer, RoundShift, round_shift};
use crate::scene::{Camera, Lens, screen_z};
use serde::Serialize;
use std::sync::Arc;

/// Fraction bits of the per-pixel sigma code (pixels): `sigma = code * 2^-8`.
pub const SIGMA_FRAC: u32 = 8;
/// Fraction bits of the slope constant G (pixels per unit of screen z).
pub const G_FRAC: u32 = 16;

/// The thin-lens blur as a function of the depth code.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LensMap {
    /// How sigma is computed from the depth code.
    pub form: SigmaForm,
    /// `K = R H / (2 tan(fov/2))`: sigma in pixels is `K (1/U - 1/D)` before the band shift.
    pub k: f64,
    /// `1/U`, the inverse focus distance.
    pub inv_focus: f64,
    /// Half-width `deep` of the in-focus band, in scene units.
    pub deep: f64,
    /// `1/near`.
    pub inv_near: f64,
    /// `1/far`.
    pub inv_far: f64,
    /// Depth-code bits that index the sigma ROM (the paper form).
    pub rom_bits: u32,
    /// The sigma ROM (paper form; empty for the affine form), see [`LensMap::sigma_rom`].
    #[serde(skip)]
    pub rom: Arc<[i64]>,
    /// Pixels of sigma per unit of screen z (the affine form's slope `K (1/near - 1/far)`).
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
    /// The lens map of a scene's camera on `hw` (depth codes of the visibility stage's z,
    /// `dof.sigma`, `dof.sigma_rom_bits`) for an image `height` pixels high; `None` for a
    /// pinhole camera.
    pub fn of(
        scene: &crate::scene::Scene,
        hw: &crate::config::HwConfig,
        height: u32,
    ) -> Option<Self> {
        Self::from_camera(
            &scene.camera,
            height,
            hw.visibility.z.format.frac_bits,
            hw.dof.sigma,
            hw.dof.sigma_rom_bits,
        )
    }

    /// From a thin-lens camera, the image height, the depth codes' fraction bits, the sigma
    /// form and the sigma ROM's index bits; `None` for a pinhole camera.
    pub fn from_camera(
        cam: &Camera,
        height: u32,
        z_frac: u32,
        form: SigmaForm,
        rom_bits: u32,
    ) -> Option<Self> {
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
        let mut lens = Self {
            form,
            k,
            inv_focus: 1.0 / focus_distance,
            deep,
            inv_near: 1.0 / cam.near,
            inv_far: 1.0 / cam.far,
            rom_bits,
            g,
            z_far_edge: screen_z(cam, focus_distance + deep),
            z_near_edge: screen_z(cam, (focus_distance - deep).max(cam.near)).max(0.0),
            z_inf: 1.0 / (1.0 - cam.near / cam.far),
            z_frac,
            coc_px: coc * height as f64 / (2.0 * v0 * tan),
            rom: Arc::from(Vec::new()),
        };
        lens.rom = lens.build_rom();
        Some(lens)
    }

    /// Screen z of a depth code.
    pub fn z_of(&self, key: u32) -> f64 {
        if key == u32::MAX {
            self.z_inf
        } else {
            key as f64 / (1u64 << self.z_frac) as f64
        }
    }

    /// Inverse view depth `1/D` at screen z (0 at the background's `z_inf`, never negative).
    fn inv_depth(&self, z: f64) -> f64 {
        (self.inv_near - z * (self.inv_near - self.inv_far)).max(0.0)
    }

    /// Exact sigma (pixels, signed: negative in front of the focus) at screen z, in the
    /// configured form.
    pub fn sigma_z(&self, z: f64) -> f64 {
        match self.form {
            SigmaForm::Affine => {
                if z > self.z_far_edge {
                    self.g * (z - self.z_far_edge)
                } else if z < self.z_near_edge {
                    self.g * (z - self.z_near_edge)
                } else {
                    0.0
                }
            }
            SigmaForm::Paper => {
                // D shifted by deep toward the focus: 1/(D -+ deep) = w / (1 -+ deep w).
                let w = self.inv_depth(z);
                let u = self.inv_focus;
                let beyond = 1.0 / (1.0 / u + self.deep);
                let before = 1.0 / (1.0 / u - self.deep);
                if w < beyond {
                    self.k * (u - w / (1.0 - self.deep * w))
                } else if self.deep * u < 1.0 && w > before {
                    self.k * (u - w / (1.0 + self.deep * w))
                } else {
                    0.0
                }
            }
        }
    }

    /// Exact sigma of a depth code.
    pub fn sigma_f64(&self, key: u32) -> f64 {
        self.sigma_z(self.z_of(key))
    }

    /// Circle of confusion in pixels at a depth code, without the in-focus band: the blur
    /// circle's diameter `2 K |1/U - 1/D|` of the thin lens.
    pub fn coc_f64(&self, key: u32) -> f64 {
        2.0 * self.k * (self.inv_focus - self.inv_depth(self.z_of(key))).abs()
    }

    /// The depth codes (not the background's `u32::MAX`) whose [`LensMap::coc_f64`] is at
    /// most `coc_px`, as one range `(first, last)`, or `None`. Every operation of the CoC
    /// is monotone in its argument, so `1/U - 1/D` never falls as the code grows (the view
    /// volume has `near < far`) and the CoC falls to the focus and rises past it: the codes
    /// within the limit are a range, found by bisection, equal to a test of every code.
    pub fn focus_keys(&self) -> Option<(u32, u32)> {
        debug_assert!(self.inv_near >= self.inv_far);
        let end = u64::from(u32::MAX);
        // The first code in `lo..hi` where `p` stops holding (`p` holds, then does not).
        let split = |mut lo: u64, mut hi: u64, p: &dyn Fn(u32) -> bool| {
            while lo < hi {
                let m = lo + (hi - lo) / 2;
                if p(m as u32) { lo = m + 1 } else { hi = m }
            }
            lo
        };
        let behind = |k: u32| self.inv_focus - self.inv_depth(self.z_of(k)) >= 0.0;
        let within = |k: u32| self.coc_f64(k) <= self.coc_px;
        let c = split(0, end, &|k| !behind(k));
        let first = split(0, c, &|k| !within(k));
        let past = split(c, end, &within);
        (first < past).then(|| (first as u32, (past - 1) as u32))
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

    /// Fixed-point sigma code (`SIGMA_FRAC` fraction bits, signed) of a depth code
    /// (`u32::MAX`: the background at infinity). Affine form: one `z x G` multiply and a
    /// round-to-nearest shift (RND, the shared `round_shift`) of the exact product, with the
    /// constants as the hardware holds them ([`LensMap::z_quantizer`],
    /// [`LensMap::g_quantizer`]; the model quantises them on every call). Paper form: the
    /// sigma ROM ([`LensMap::sigma_rom`]) read at the top `rom_bits` of the code and
    /// interpolated linearly with the remaining bits (one multiply, RND shift); a code
    /// beyond the far plane (a layer's middle depth toward infinity) interpolates between
    /// the far-plane entry and the infinity entry.
    pub fn sigma_code(&self, key: u32) -> i64 {
        self.sigma_coder().code(key)
    }

    /// [`LensMap::sigma_code`] for many codes: the constants quantised once.
    pub fn sigma_coder(&self) -> SigmaCoder<'_> {
        let zq = self.z_quantizer();
        let code = |z: f64| zq.quantize_f64(z).code;
        let z_inf = code(self.z_inf);
        let affine = (self.form == SigmaForm::Affine).then(|| Affine {
            z_far: code(self.z_far_edge),
            z_near: code(self.z_near_edge),
            g: self.g_code(),
        });
        SigmaCoder {
            lens: self,
            z_inf,
            affine,
        }
    }

    /// The sigma ROM of the paper form: `2^rom_bits + 1` entries, the sigma code at screen
    /// z = `j / 2^rom_bits` (the last at the far plane), then one entry for infinity (the
    /// background); each through [`LensMap::sigma_rom_quantizer`]. Empty for the affine form.
    pub fn sigma_rom(&self) -> &[i64] {
        &self.rom
    }

    fn build_rom(&self) -> Arc<[i64]> {
        if self.form == SigmaForm::Affine {
            return Arc::from(Vec::new());
        }
        let n = 1u64 << self.rom_bits;
        let q = self.sigma_rom_quantizer();
        (0..=n)
            .map(|j| self.sigma_z(j as f64 / n as f64))
            .chain([self.sigma_z(self.z_inf)])
            .map(|s| q.quantize_f64(s).code)
            .collect()
    }

    /// The quantiser of the sigma ROM entries: `Q<i>.8` ([`SIGMA_FRAC`] fraction bits; `i`
    /// fitted to the extremes of sigma, at the near plane, the far plane and infinity, with a
    /// sign bit when the near plane lies before the in-focus band), RND_INF, SAT (the
    /// format holds every entry: sigma is monotone on each side of the band).
    pub fn sigma_rom_quantizer(&self) -> Quantizer {
        fitted(SIGMA_FRAC, &[0.0, 1.0, self.z_inf].map(|z| self.sigma_z(z)))
    }

    /// Width of a sigma ROM entry in bits.
    pub fn sigma_rom_bits_wide(&self) -> u32 {
        self.sigma_rom_quantizer().format.total_bits()
    }

    /// The paper form's sigma code: ROM entry at the top bits, linear interpolation.
    fn sigma_code_rom(&self, key: u32, z_inf_code: i64) -> i64 {
        let rom = &self.rom;
        let n = 1i64 << self.rom_bits;
        let inf = rom[rom.len() - 1];
        if key == u32::MAX {
            return inf;
        }
        let key = i64::from(key);
        let one = 1i64 << self.z_frac;
        if key >= one {
            // Beyond the far plane: between the far-plane entry and infinity.
            let span = z_inf_code - one;
            let far = rom[n as usize];
            if span <= 0 {
                return inf;
            }
            let t = (key - one).min(span);
            return far + round_div(i128::from(inf - far) * i128::from(t), i128::from(span));
        }
        if self.z_frac <= self.rom_bits {
            return rom[(key << (self.rom_bits - self.z_frac)) as usize];
        }
        let shift = self.z_frac - self.rom_bits;
        let j = (key >> shift) as usize;
        let f = key & ((1i64 << shift) - 1);
        let (a, b) = (rom[j], rom[j + 1]);
        a + round_product(b - a, f, shift)
    }

    /// Width of the G constant in bits (integer + `G_FRAC`): its quantiser's format.
    pub fn g_bits(&self) -> u32 {
        self.g_quantizer().format.total_bits()
    }
}

/// `n / d` rounded to nearest, ties away from zero (`d > 0`).
/// `a b 2^-shift` rounded to nearest (RND), in 64 bits when the product fits.
#[inline]
fn round_product(a: i64, b: i64, shift: u32) -> i64 {
    match a.checked_mul(b) {
        Some(p) if shift < 63 => RoundShift::new(shift, Quant::Rnd).apply(p),
        _ => round_shift(i128::from(a) * i128::from(b), shift, Quant::Rnd) as i64,
    }
}

fn round_div(n: i128, d: i128) -> i64 {
    let q = (2 * n.abs() + d) / (2 * d);
    (if n < 0 { -q } else { q }) as i64
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

/// The affine form's constants as the hardware holds them (depth codes of the in-focus
/// band's edges, G).
#[derive(Clone, Copy, Debug)]
struct Affine {
    z_far: i64,
    z_near: i64,
    g: i64,
}

/// The sigma code of depth codes ([`LensMap::sigma_coder`]).
#[derive(Clone, Copy, Debug)]
pub struct SigmaCoder<'a> {
    lens: &'a LensMap,
    /// The depth code of infinity.
    z_inf: i64,
    affine: Option<Affine>,
}

impl SigmaCoder<'_> {
    /// [`LensMap::sigma_code`] of `key`.
    #[inline]
    pub fn code(&self, key: u32) -> i64 {
        let Some(a) = self.affine else {
            return self.lens.sigma_code_rom(key, self.z_inf);
        };
        // The affine form: `(z - z_e) G`, exact, rounded.
        let z = if key == u32::MAX {
            self.z_inf
        } else {
            key as i64
        };
        let d = if z > a.z_far {
            z - a.z_far
        } else if z < a.z_near {
            z - a.z_near
        } else {
            return 0;
        };
        let sh = self.lens.z_frac + G_FRAC - SIGMA_FRAC;
        round_product(d, a.g, sh)
    }
}
