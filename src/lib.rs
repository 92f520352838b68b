//! # igemu: an emulator of fixed-point image-generator hardware
//!
//! The pipeline is a stage graph (`scene -> input -> setup -> raster -> visibility ->
//! accumulate -> gamma -> DAC`). Rules every stage follows:
//!
//! 1. A stage has a fixed-point model (integers only), a float reference (f64, same
//!    algorithm, ideal arithmetic), work counts for the cycle model and a cost model,
//!    side by side in one module under [`stage`].
//! 2. Every quantisation point names its format and its rounding and overflow modes
//!    ([`fixed`]); overflow is never silent: it follows the configured mode and is counted.
//! 3. The inner loops of rasterisation use additions and comparisons only; multiplications
//!    and divisions happen in per-primitive setup.
//! 4. Outputs are compared with the float reference integer code by code ([`compare`]).
//! 5. Results are deterministic: bit-identical on any thread count and any run.
//! 6. Only what the scene needs is modelled: stages, screen region and work.
//!
//! The library prints nothing; the `igemu` binary does.

pub mod analysis;
pub mod compare;
pub mod config;
pub mod cost;
pub mod cycles;
pub mod error;
pub mod files;
pub mod fixed;
pub mod fnv;
pub mod hdl;
pub mod output;
pub mod perceptual;
pub mod pipeline;
pub mod scene;
pub mod stage;
pub mod stage_id;
pub mod sweep;
