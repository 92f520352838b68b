//! Accumulate: filtering and sampling in one step, into the frame memory.
//!
//! For every pixel a filter is centred on it; each primitive `j` visible in the filter's
//! window gets the weight `S_j` (the sum of the filter weights of its samples) and the
//! frame memory accumulates `I_F += I_j * S_j` (Kovalev & Tokarev, eq. 2-3). With
//! Gouraud shading the intensity varies per sample, so the product is the exact sum
//! `sum_s w_s * I_s` over the primitive's samples in the window, rounded once to the
//! frame format (its rounding mode), then added with the frame's overflow mode.
//! Primitives are accumulated in arrival order (the background first), light points
//! last, as additive `I * S` terms.
//!
//! Filter weights are quantised to `weight_bits` fraction bits with their sum kept
//! exact: for the equal-energy filters (box, tent) by largest remainder *within each
//! sample's group* (the weights one sub-pixel sample gives to the pixels around it), so
//! every sample gives exactly `2^f / n^2` and the filters stay equal-energy bit for bit;
//! for the Gaussian by largest remainder over the whole kernel (sum `2^f`).
//!
//! Files: `kernel` (the quantised [`Kernel`]), `fixed` (the fixed model into the frame
//! memory), `points` (light points and the sample region), `float` (the float reference),
//! `cost` (the stage's hardware cost), `stage` (the stage contract), `window` (the
//! per-pixel window sums of the fixed model), `span` (the fixed model's pixel loop),
//! `stats` (the product statistics of a row of pixels).

mod cost;
mod fixed;
mod float;
mod kernel;
mod points;
mod span;
mod stage;
mod stats;
mod window;

pub use cost::{FRAME_MEMORY, WEIGHT_ROM, cost};
pub use fixed::{AccParams, AccWork, Frame, accumulate, accumulate_tiles, own_depth_coverage};
pub use float::{AccRef, accumulate_f64};
pub use kernel::Kernel;
pub use points::{PointFrags, point_weights, regions, sample_region};
pub use stage::{Accumulate, float_frame, kernel};
