//! # igemu: an emulator of fixed-point image-generator hardware
//!
//! The pipeline is a stage graph: `scene -> (host front end, f64) -> input -> setup ->
//! raster -> visibility -> [logdomain] -> accumulate -> [dof] -> gamma -> [dither] -> DAC`,
//! the bracketed stages only when the scene and hardware need them. A plan
//! ([`pipeline::plan`]) decides, before anything runs, which stages run and why, the screen
//! region and the tiles; the runner executes it through the stage contract
//! ([`stage::Stage`]) and reuses every stage whose inputs did not change
//! ([`pipeline::cache`]). Rules every stage follows:
//!
//! 1. A stage has a fixed-point model (integers only), a float reference (f64, same
//!    algorithm, ideal arithmetic), its stage-local comparison, the tokens of the cycle
//!    model and a cost model, side by side in one module under [`stage`].
//! 2. Every quantisation point names its format and its rounding and overflow modes
//!    ([`fixed`]); overflow is never silent: it follows the configured mode and is counted.
//! 3. The inner loops of rasterisation use additions and comparisons only; multiplications
//!    and divisions happen in per-primitive setup.
//! 4. Outputs are compared with the float reference integer code by code ([`compare`]).
//! 5. Results are deterministic: bit-identical on any thread count and any run.
//! 6. Only what the scene needs is modelled: stages, screen region and work.
//!
//! The library prints nothing; the `igemu` binary does. Modules depend on each other in one
//! direction only (docs/STRUCTURE.md).

pub mod analysis;
pub mod colour;
pub mod compare;
pub mod config;
pub mod cost;
pub mod cycles;
pub mod error;
pub mod files;
pub mod fixed;
pub mod fnv;
pub mod hdl;
pub mod html;
pub mod output;
pub mod perceptual;
pub mod pipeline;
pub mod rng;
pub mod scene;
pub mod sequence;
pub mod shard;
pub mod stage;
pub mod stage_id;
pub mod sweep;
pub mod truth;
