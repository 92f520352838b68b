//! Depth of field: layered adaptive convolution of the depth image (docs/reference.md §2, §3).
//!
//! **Blur per pixel.** With the thin lens (lens radius R, focus distance U) the blur of a
//! point at view depth D is `sigma = R V0 (1/U - 1/D)` on the image plane (docs/reference.md §2a,
//! `V0 = F U / (U - F)`). The image plane `V0` behind the lens spans `2 V0 tan(fov/2)` units
//! over the image height H, so in pixels `sigma_px = K (1/U - 1/D)` with
//! `K = R H / (2 tan(fov/2))`: V0 and F cancel, and the scene's length unit is the unit of
//! R and U. The in-focus band `[U - deep, U + deep]` has sigma = 0; outside it the depth is
//! shifted to the band's edge, in one of two forms (`dof.sigma`, [`LensMap`]):
//! * `paper` (the default, the paper's eq. 3): D itself is shifted,
//!   `sigma = K (1/U - 1/(D - deep))` beyond the band and `K (1/U - 1/(D + deep))` before
//!   it; the background at infinity blurs at `K/U`. Not affine in the depth code, so the
//!   hardware reads it from a sigma ROM of `2^sigma_rom_bits + 1` entries over screen z in
//!   [0, 1] (plus one for infinity) and interpolates linearly with the code's low bits
//!   (one multiply); entries are `Q<i>.8`, rounded RND_INF;
//! * `affine` (the first version's): the depth is shifted in inverse depth (`z_e` is the
//!   screen z of `U + deep` behind the band and of `U - deep` in front of it); screen z is
//!   affine in 1/D (`1/D = 1/near - z (1/near - 1/far)`), so `sigma = G (z - z_e)` with
//!   `G = K (1/near - 1/far)`: one multiplier per pixel, no ROM.
//!
//! The circle of confusion (docs/reference.md §2b) of the same lens is
//! `C = F^2/(U - F) |L - U| / (N L)`, in pixels `2 K |1/U - 1/D|` (no band).
//!
//! **Mask.** The paper's Gaussian is read as `exp(-(x^2 + y^2) / sigma^2)`, the form for which
//! its cut rule (edge/centre = k) gives exactly `M = ceil(sqrt(-ln k) |sigma|)` (1.731 sigma
//! for k = 0.05). The 1-D taps are quantised to `coef_bits` fraction bits by largest
//! remainder so they sum to exactly `2^f`: the separable 2-D mask sums to `2^2f`, DC gain 1.
//!
//! **Layers.** The distinct depth codes are sorted far to near; a layer grows from its
//! farthest code while the difference degree `S(A, B) = sum|A - B| / sum(|A| + |B|)`
//! between the 2-D masks of its ends, and between each end and the mask of the layer's
//! middle depth (and sigma = 0 when the layer straddles the focus) stays below P. Each layer
//! is convolved with the mask of its middle depth.
//!
//! **Fixed-point constants of the affine form** ([`LensMap`]), each through a shared
//! [`Quantizer`](crate::fixed::Quantizer) with mode RND_INF (to nearest, ties away from
//! zero: `f64::round` for every sign) and overflow SAT, in a format fitted to the constant
//! (the fewest integer bits that hold it after rounding), so SAT does not act (below a 62-bit
//! word) and there is no overflow to count; these internal words may be wider than the 32
//! bits of a configurable format (G >= 2^16 px per unit of z):
//! * the slope G: `UQ<i>.16` ([`G_FRAC`] fraction bits, `i` the integer bits of G;
//!   `UQ5.16` for the embedded scenes, G = 18.99 and 25.32 px per unit of z);
//! * the depth codes of the in-focus band edges, of infinity (the background) and of each
//!   layer's middle depth: `UQ<i>.<z_frac>` with the z buffer's fraction bits and `i` the
//!   integer bits of `z_inf = 1 / (1 - near/far) > 1` (`UQ1.24` with the default `UQ0.24`
//!   z buffer); signed `Q<i+1>.<z_frac>` when the band's far edge lies before the near plane.
//!
//! The sigma code is signed `Q<i>.8` ([`SIGMA_FRAC`] fraction bits): affine, the product
//! `(z - z_e) G`, exact, rounded by the shared `round_shift` with RND over `z_frac + 8` bits;
//! paper, the ROM entry plus the interpolation product rounded by `round_shift` (RND). It is
//! not saturated (`i` follows the largest |sigma|; a layer whose mask would exceed
//! `dof.max_half_size` stops the plan with an error).
//!
//! **Fixed-point datapath** (per layer, only over the layer's bounding box plus M):
//! * input planes: premultiplied intensity `x * m` and alpha `m`, with `m` the pixel's
//!   coverage in `1/n^2` units; the uncovered share `n^2 - coverage` of every pixel goes to
//!   the background layer (the farthest layer, depth "infinity"), so the shares sum to the
//!   pixel's value exactly;
//! * horizontal pass into the line buffer and vertical pass into the accumulator, exact
//!   integer sums (`line_bits`, `acc_bits` wide; a sum that does not fit is saturated and
//!   counted, signals `dof.line` and `dof.acc`, or stops the run with overflow mode ERROR);
//! * the layer's colour `C = round(F 2^g / A)` (normalised convolution: one divide per
//!   pixel, renormalises image borders and holes left by nearer layers alike);
//! * its alpha `a = round(A 2^q / (n^2 Wx Wy))` with `Wx Wy` the in-image tap sum (border
//!   renormalisation), `q = alpha_bits`, at most `2^q`;
//! * colour and alpha are integer divides with half-up rounding (`ceil(floor(2 N / D) / 2)`),
//!   not quantiser operations; a sigma = 0 layer is passed through with the exact colour
//!   `x m 2^g / m` and the alpha `floor(m 2^q / n^2)`;
//! * back-to-front "over": `out = round((C a + out (2^q - a)) / 2^q)` (shared `round_shift`,
//!   mode `quant`), i.e. `f = f_front + f_back (1 - a_front)` with the back already opaque;
//!   the farthest layer covering a pixel initialises it. A flat field of any code is
//!   therefore bit-identical at any depths, and a sigma = 0 layer passes its pixels through
//!   untouched.
//! * the result, with `g = guard_bits` below the frame LSB, goes through a `Quantizer` of the
//!   frame format with mode `quant` and SAT (to full white); the saturated pixels are counted
//!   ([`DofWork::out_overflows`]) and reported as the signal `dof.out` in the frame format.
//!
//! **Float references.** (1) [`layered_f64`]: the same layers and masks (untruncated
//! coefficients), f64. (2) [`per_pixel_scatter`]: every source pixel spreads its value with
//! the mask of its own depth, restricted to the image and renormalised (energy preserving),
//! summed; cost `O(N^2 M^2)`. [`additive_layered`] is the theorem's form: every pixel
//! spread with its layer's middle mask, summed, no compositing.
//!
//! Files: `lens` (blur per depth code, the sigma ROM), `mask` (taps, difference degree),
//! `kernel` (the mask shape of `dof.kernel`), `disc` (a disc layer's direct 2-D filter),
//! `method` (the interface of the methods behind `dof.kind`), `layered` (the layered method
//! through it), `luminance/` (the luminance-aware method), `layers` (the layer plan), `fixed`
//! (the fixed datapath, `row_mac`), `float` (the layered float reference), `reference`
//! (per-pixel scatter, theorem form, error split, depth-edge bands), `potentiate` (a log-coded
//! frame made linear for DoF), `cost` (cost, memories, signals), `stage` (the stage contract).

mod cost;
mod disc;
pub mod downsample;
mod fast;
mod fixed;
mod float;
mod kernel;
mod keys;
mod layered;
mod layers;
mod lens;
pub mod luminance;
mod mask;
mod method;
mod potentiate;
mod reference;
mod scratch;
mod stage;
mod strip;
mod stripes;
mod uniform;

pub use cost::{
    COEF_ROM, COMPOSITE, LINE_BUFFERS, SIGMA_ROM, coefficient_image, cost, lens_cost,
    overflow_signal, overflow_signal_in, reachable_bits, sigma_rom_image, width_note,
};
pub use fixed::{
    DofWork, Exec, FixedRun, LayerPlanes, MacOut, STRIP_ROWS, border_sum, layered_fixed,
    layered_fixed_exec, layered_fixed_observed, row_mac,
};
pub use float::{layered_f64, layered_f64_exec, layered_f64_key};
pub use kernel::{FITTED_SCALE, Mask2, disc_f64, disc_half_size, gaussian_sigma, kernel_half_size};
pub use layers::{
    DepthImage, Layer, LayerPlan, LayerWork, layer_work, plan_layers, plan_layers_in,
};
pub use lens::{G_FRAC, LensMap, SIGMA_FRAC};
pub use mask::{difference_degree, half_size, mask_difference, taps_f64, taps_fixed};
pub use method::Method;
pub use potentiate::{FramePotentiation, POT_LUT};
pub use reference::{
    RegionError, additive_layered, depth_edge_band, edge_band, local_error, per_pixel_scatter,
    region_error, weber_linear,
};
pub use stage::Dof;
pub use uniform::UNIFORM_TILE;
