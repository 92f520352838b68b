//! The downsample method's plan for one frame: the largest blur in the frame, the small
//! image's Gaussian, the blend ROM, the Poisson taps and the blend window's reach.

use super::poisson::Poisson;
use crate::config::{DofCfg, DofKernel, MAX_HALF_SIZE_LIMIT};
use crate::fixed::{Quant, round_shift};
use crate::stage::dof::{LensMap, SIGMA_FRAC, gaussian_sigma, half_size, taps_f64, taps_fixed};
use serde::Serialize;

/// The blur of a depth code as the method reads it (implemented by [`LensMap`]; tests may
/// give their own).
pub trait Blur: Sync {
    /// Signed sigma code of a depth code (pixels, [`SIGMA_FRAC`] fraction bits; `u32::MAX`
    /// is the background at infinity).
    fn sigma_code(&self, key: u32) -> i64;
    /// Exact signed sigma of a depth code (pixels).
    fn sigma_f64(&self, key: u32) -> f64;
    /// Fraction bits of the depth codes.
    fn z_frac(&self) -> u32;
}

impl Blur for LensMap {
    fn sigma_code(&self, key: u32) -> i64 {
        LensMap::sigma_code(self, key)
    }
    fn sigma_f64(&self, key: u32) -> f64 {
        LensMap::sigma_f64(self, key)
    }
    fn z_frac(&self) -> u32 {
        self.z_frac
    }
}

/// Rounding of the blend ROM's entries (host-built constants): RND_INF, as the lens
/// constants.
pub const ROM_QUANT: Quant = Quant::RndInf;

/// The plan of one frame.
#[derive(Clone, Debug, Serialize)]
pub struct DownPlan {
    /// Frame width.
    pub width: usize,
    /// Frame height.
    pub height: usize,
    /// Downsampling factor per axis.
    pub factor: usize,
    /// `log2(factor)`.
    pub factor_log2: u32,
    /// Small image width, `ceil(width / factor)`.
    pub small_width: usize,
    /// Small image height, `ceil(height / factor)`.
    pub small_height: usize,
    /// Largest `|sigma|` code over the frame's depth codes ([`SIGMA_FRAC`] fraction bits):
    /// the blend factor 1 and the largest CoC radius.
    pub sigma_max_code: i64,
    /// Exact largest `|sigma|` over the frame (pixels), for the float reference.
    pub sigma_max: f64,
    /// The blur the blurred copy stands for and the blend factors' scale (pixels, a
    /// [`SIGMA_FRAC`] code): `max(sigma_max_code, `[`blend_floor`]`)`, an absolute scale, so
    /// a frame's small blurs blend in little of the copy however small its largest blur is.
    pub scale_code: i64,
    /// The same from the exact `sigma_max` (the float reference's).
    pub scale: f64,
    /// Sigma of the small image's Gaussian in small pixels: the Gaussian that brings the
    /// copy's inherent blur (the box average and the bilinear read) up to `scale_code`
    /// ([`small_sigma_px`]), divided by `factor`.
    pub small_sigma: f64,
    /// The same from the exact `sigma_max` (the float reference's).
    pub small_sigma_f64: f64,
    /// Half-size of the small Gaussian (small pixels).
    pub m: usize,
    /// Quantised 1-D Gaussian taps (`UQ0.<coef_bits>`, sum `2^coef_bits`).
    #[serde(skip)]
    pub coef: Vec<u64>,
    /// Float 1-D Gaussian taps of `small_sigma_f64` (sum 1).
    #[serde(skip)]
    pub coef_f: Vec<f64>,
    /// Depth-code bits indexing the blend ROM (`dof.downsample.blend_rom_bits`, at most the
    /// depth codes' fraction bits).
    pub rom_bits: u32,
    /// `z_frac - rom_bits`: the depth bits interpolated between two entries.
    pub rom_shift: u32,
    /// Blend ROM: `2^rom_bits + 1` entries at depth codes `i 2^rom_shift`, then infinity;
    /// `UQ1.<blend_bits>`, `min(round(|sigma| / scale 2^b), 2^b)`.
    #[serde(skip)]
    pub blend_rom: Vec<u64>,
    /// Depth codes at or above this are clamped to it before the ROM lookup (the largest
    /// code of the z buffer, `2^z_frac - 1`).
    pub key_max: u32,
    /// The Poisson taps.
    pub taps: Poisson,
    /// Largest distance (pixels, per axis) from a pixel to a sharp tap it reads: the blend
    /// window's half-height.
    pub reach: usize,
    /// The blurred small image the fixed model left (small format codes, raster order):
    /// the contents of the blurred-image RAM, for its memory image.
    #[serde(skip)]
    pub blurred: std::sync::Arc<Vec<u64>>,
}

impl DownPlan {
    /// The blend ROM entry for an exact `|sigma|` (pixels), `blend_bits` fraction bits.
    pub fn rom_entry(sigma_abs: f64, scale_code: i64, blend_bits: u32) -> u64 {
        if scale_code <= 0 {
            return 0;
        }
        let one = 1u64 << blend_bits;
        let smax = scale_code as f64 / (1u64 << SIGMA_FRAC) as f64;
        // RND_INF of a non-negative value is f64::round.
        ((sigma_abs / smax * one as f64).round() as u64).min(one)
    }

    /// The depth code of blend ROM entry `i` (`i <= 2^rom_bits`; the last one, one past the
    /// largest code, is clamped to `u32::MAX - 1` for a 32-bit z buffer).
    pub fn rom_key(&self, i: usize) -> u32 {
        ((i as u64) << self.rom_shift).min(u32::MAX as u64 - 1) as u32
    }

    /// The blend factor of a depth code, fixed (`UQ1.<blend_bits>`): the ROM entries around
    /// the code's top bits, interpolated linearly over the low `rom_shift` bits (the product
    /// rounded with `quant`); the infinity entry for the background.
    #[inline]
    pub fn blend_fixed(&self, key: u32, quant: Quant) -> u64 {
        if key == u32::MAX {
            return self.blend_rom[self.blend_rom.len() - 1];
        }
        let key = key.min(self.key_max);
        let i = (key >> self.rom_shift) as usize;
        let lo = key & ((1u64 << self.rom_shift) - 1) as u32;
        let (a, b) = (self.blend_rom[i] as i128, self.blend_rom[i + 1] as i128);
        (a + round_shift((b - a) * lo as i128, self.rom_shift, quant)) as u64
    }

    /// The exact blend factor of a depth code: `|sigma| / scale`, 0 where the fixed
    /// factor `fixed` is 0: the reference makes the fixed path's decision to pass a pixel
    /// through (an in-focus pixel's exact sigma may be 1e-6 px where its code is 0; the
    /// reference must not blur what the method keeps sharp, docs/dof-downsample.md).
    #[inline]
    pub fn blend_f64(&self, blur: &dyn Blur, key: u32, fixed: u64) -> f64 {
        if self.scale > 0.0 && fixed > 0 {
            (blur.sigma_f64(key).abs() / self.scale).min(1.0)
        } else {
            0.0
        }
    }

    /// The CoC radius of a blend factor, fixed: `beta scale_code`, exact (pixels with
    /// [`SIGMA_FRAC`]` + blend_bits` fraction bits, unsigned).
    #[inline]
    pub fn radius_fixed(&self, beta: u64) -> i64 {
        beta as i64 * self.scale_code
    }
}

/// The blurred copy's inherent blur as a Gaussian `exp(-x^2 / s^2)`: the `f x f` box
/// average (variance `f^2 / 12`) and the bilinear read (a tent of half-width `f`, variance
/// `f^2 / 6`) give a standard deviation `f / 2`, i.e. `s = f / sqrt 2` px.
pub fn inherent_blur(factor: usize) -> f64 {
    factor as f64 / std::f64::consts::SQRT_2
}

/// The smallest blur the copy can stand for (pixels of `sigma`): the inherent blur, as the
/// blur radius whose kernel's Gaussian it is (`fitted_gaussian` and `disc` read `sigma` as a
/// disc radius whose fitted Gaussian is `FITTED_SCALE sigma`).
pub fn blend_floor(factor: usize, kernel: DofKernel) -> f64 {
    inherent_blur(factor) / gaussian_sigma(kernel, 1.0)
}

/// The Gaussian (full-resolution pixels, `exp(-x^2 / s^2)`) the copy's small blur adds so
/// that the copy's total blur is the kernel's Gaussian of blur radius `scale`: variances add,
/// `s^2 = g(scale)^2 - f^2 / 2` (0 at the floor).
pub fn small_sigma_px(scale: f64, factor: usize, kernel: DofKernel) -> f64 {
    let t = gaussian_sigma(kernel, scale);
    (t * t - inherent_blur(factor).powi(2)).max(0.0).sqrt()
}

/// Plans the method for a frame of depth codes `key` (`width x height`): the largest
/// `|sigma|` over the codes present, the small Gaussian (`sigma_max / factor` small pixels),
/// the blend ROM and the taps. Errors name the limit exceeded (`dof.max_half_size`).
pub fn plan_downsample(
    key: &[u32],
    width: usize,
    height: usize,
    blur: &dyn Blur,
    p: &DofCfg,
) -> Result<DownPlan, String> {
    let d = &p.downsample;
    let mut keys: Vec<u32> = key.to_vec();
    keys.sort_unstable();
    keys.dedup();
    let (mut smax_code, mut smax) = (0i64, 0.0f64);
    for &k in &keys {
        smax_code = smax_code.max(blur.sigma_code(k).abs());
        smax = smax.max(blur.sigma_f64(k).abs());
    }
    let factor = d.factor as usize;
    let one = (1u64 << SIGMA_FRAC) as f64;
    let floor = blend_floor(factor, p.kernel);
    let scale_code = smax_code.max((floor * one).round() as i64);
    let scale = smax.max(floor);
    let sigma_fixed = smax_code as f64 / one;
    let small_sigma = small_sigma_px(scale_code as f64 / one, factor, p.kernel) / factor as f64;
    let small_sigma_f64 = small_sigma_px(scale, factor, p.kernel) / factor as f64;
    let m = half_size(small_sigma, p.k).max(half_size(small_sigma_f64, p.k));
    let reach = (sigma_fixed.max(smax) + 0.5).floor() as usize;
    let worst = m.max(reach);
    if worst > p.max_half_size as usize {
        let advice = if worst <= MAX_HALF_SIZE_LIMIT as usize {
            format!("raise dof.max_half_size to {worst} (at most {MAX_HALF_SIZE_LIMIT})")
        } else {
            format!(
                "that is beyond the largest configurable half-size {MAX_HALF_SIZE_LIMIT}: reduce camera.lens.lens_radius or move the focus"
            )
        };
        return Err(format!(
            "the largest blur in the frame is sigma {smax:.2} px: the downsample method's blend window reaches {reach} px and its small Gaussian (sigma {small_sigma:.2} small px) has half-size M = {m}, more than dof.max_half_size = {}; {advice}",
            p.max_half_size
        ));
    }
    let coef_f = taps_f64(small_sigma_f64, p.k);
    let coef = taps_fixed(&taps_f64(small_sigma, p.k), p.coef_bits);
    let z_frac = blur.z_frac();
    let rom_bits = d.blend_rom_bits.min(z_frac);
    let mut plan = DownPlan {
        width,
        height,
        factor,
        factor_log2: factor.trailing_zeros(),
        small_width: width.div_ceil(factor),
        small_height: height.div_ceil(factor),
        sigma_max_code: smax_code,
        sigma_max: smax,
        scale_code,
        scale,
        small_sigma,
        small_sigma_f64,
        m: coef.len() / 2,
        coef,
        coef_f,
        rom_bits,
        rom_shift: z_frac - rom_bits,
        blend_rom: vec![],
        key_max: if z_frac >= 32 {
            u32::MAX - 1
        } else {
            (1u32 << z_frac) - 1
        },
        taps: Poisson::new(d.taps as usize, d.offset_bits),
        reach,
        blurred: Default::default(),
    };
    let entry = |k: u32| DownPlan::rom_entry(blur.sigma_f64(k).abs(), scale_code, d.blend_bits);
    let mut rom: Vec<u64> = (0..=(1usize << rom_bits))
        .map(|i| entry(plan.rom_key(i)))
        .collect();
    rom.push(entry(u32::MAX));
    plan.blend_rom = rom;
    Ok(plan)
}
