//! Stage reuse in sweeps: everything before the post stage ([`Early`]: front, geometry,
//! accumulate, depth of field, the frame-memory and sample-buffer pack checks, the cycle
//! model's workload and simulation) is cached by a hash of everything it may depend on: the
//! scene, the render options and the whole hardware configuration except the late-only
//! sections `gamma` and `dither` (and the configuration's name). A sweep over gamma and
//! dither widths therefore runs the early phases once and only `post` (LUT, dither,
//! comparison) per configuration. The key is deliberately conservative: `cycles` stays in
//! it (the accumulate phase plans its tiles with `cycles.tile`; the simulation uses the
//! timings).
//!
//! The cache keeps the [`CAPACITY`] most recently inserted entries (each holds a frame and
//! a sample buffer), shared read-only: a render borrows them, so results are identical to
//! an uncached render.

use crate::config::HwConfig;
use crate::error::Result;
use crate::pipeline::{Early, RenderOptions};
use crate::scene::Scene;
use std::sync::{Arc, Mutex};

/// Entries kept.
pub const CAPACITY: usize = 4;

/// The cache (shared between threads).
#[derive(Default)]
pub struct PhaseCache {
    entries: Mutex<Vec<(u64, Arc<Early>)>>,
    hits: std::sync::atomic::AtomicU64,
    misses: std::sync::atomic::AtomicU64,
}

/// The key of the early phases: FNV-1a of the JSON of scene, options and the hardware
/// without its late-only sections.
pub fn early_key(scene: &Scene, hw: &HwConfig, opts: RenderOptions, dof_reference: bool) -> u64 {
    let mut h = serde_json::to_value(hw).unwrap_or_default();
    if let Some(o) = h.as_object_mut() {
        for late in ["name", "gamma", "dither"] {
            o.remove(late);
        }
    }
    let key = serde_json::json!({
        "scene": serde_json::to_value(scene).unwrap_or_default(),
        "hw": h,
        "stage_local": opts.stage_local,
        "dof_reference": dof_reference,
    });
    super::grid::fnv1a(key.to_string().as_bytes())
}

impl PhaseCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The early phases for this key: a clone of the cached ones, or `run()` (then cached).
    pub fn early(
        &self,
        scene: &Scene,
        hw: &HwConfig,
        opts: RenderOptions,
        dof_reference: bool,
        run: impl FnOnce() -> Result<Early>,
    ) -> Result<Arc<Early>> {
        use std::sync::atomic::Ordering::Relaxed;
        let key = early_key(scene, hw, opts, dof_reference);
        let found = {
            let e = self.entries.lock().unwrap_or_else(|e| e.into_inner());
            e.iter().find(|(k, _)| *k == key).map(|(_, v)| v.clone())
        };
        if let Some(v) = found {
            self.hits.fetch_add(1, Relaxed);
            return Ok(v);
        }
        self.misses.fetch_add(1, Relaxed);
        let v = Arc::new(run()?);
        let mut e = self.entries.lock().unwrap_or_else(|e| e.into_inner());
        if !e.iter().any(|(k, _)| *k == key) {
            if e.len() >= CAPACITY {
                e.remove(0);
            }
            e.push((key, v.clone()));
        }
        Ok(v)
    }

    /// (hits, misses) so far.
    pub fn stats(&self) -> (u64, u64) {
        use std::sync::atomic::Ordering::Relaxed;
        (self.hits.load(Relaxed), self.misses.load(Relaxed))
    }
}
