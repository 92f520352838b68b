//! Reuse of unchanged stages: the pipeline's cache of stage outcomes, keyed by the stage's
//! key (its config section, options and plan parts, chained with its input's key), so a
//! sweep recomputes only from the first stage whose inputs changed. It also keeps values
//! stages share through [`Memo`] (e.g. the float gamma curve of one frame) and cycle
//! simulations (keyed by their workload).
//!
//! A cache made with [`Cache::with_tile_rows`] (a sequence's) also keeps the bands of a
//! banded run, one tile row each, keyed by the primitives they read
//! ([`super::tile_rows::Keys`]): a frame emulates only the tile rows whose primitives
//! changed since an earlier frame.
//!
//! Entries are shared read-only (`Arc`), so a reused result is identical to a recomputed
//! one. No lock is held while a stage runs; the least recently used entries beyond the
//! capacity are dropped.

use super::bands::BandResult;
use super::run::Outcome;
use crate::cycles::SimResult;
use crate::error::Result;
use crate::stage::Memo;
use std::any::Any;
use std::collections::HashMap;
use std::convert::Infallible;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, Mutex};

/// Stage outcomes kept.
pub const STAGE_CAPACITY: usize = 64;
/// Memo values kept.
pub const MEMO_CAPACITY: usize = 32;
/// Simulations kept.
pub const SIM_CAPACITY: usize = 64;
/// Tile rows kept (two frames of a 2048-row screen in 16-pixel tile rows).
pub const TILE_ROW_CAPACITY: usize = 256;

/// A map with least-recently-used eviction.
struct Lru<T> {
    map: Mutex<HashMap<u64, (T, u64)>>,
    tick: AtomicU64,
    capacity: usize,
}

impl<T: Clone> Lru<T> {
    fn new(capacity: usize) -> Self {
        Self {
            map: Mutex::new(HashMap::new()),
            tick: AtomicU64::new(0),
            capacity,
        }
    }

    /// The value under `key` (and `true`), or `make()`'s (then stored) and `false`. Errors
    /// are not stored. No lock is held while `make` runs: it may itself use the cache, and a
    /// rayon worker waiting in it may run another job that asks for the same key. Two
    /// threads may then compute the same key; the first value stored wins (the two are
    /// identical: a stage's result depends only on its key).
    fn get_or<E>(
        &self,
        key: u64,
        make: impl FnOnce() -> std::result::Result<T, E>,
    ) -> std::result::Result<(T, bool), E> {
        let lock = || self.map.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((v, used)) = lock().get_mut(&key) {
            *used = self.tick.fetch_add(1, Relaxed);
            return Ok((v.clone(), true));
        }
        let x = make()?;
        let mut m = lock();
        let now = self.tick.fetch_add(1, Relaxed);
        let v = m.entry(key).or_insert((x, now)).0.clone();
        if m.len() > self.capacity
            && let Some(&old) = m.iter().min_by_key(|(_, (_, u))| *u).map(|(k, _)| k)
        {
            m.remove(&old);
        }
        Ok((v, false))
    }
}

/// The pipeline's cache (shared between threads).
pub struct Cache {
    stages: Lru<Arc<Outcome>>,
    memo: Lru<Arc<dyn Any + Send + Sync>>,
    sims: Lru<Arc<(SimResult, f64)>>,
    hits: AtomicU64,
    misses: AtomicU64,
    /// `None`: tile rows are not kept.
    tile_rows: Option<Lru<Arc<BandResult>>>,
    row_hits: AtomicU64,
    row_misses: AtomicU64,
}

impl Default for Cache {
    fn default() -> Self {
        Self::new()
    }
}

impl Cache {
    /// An empty cache.
    pub fn new() -> Self {
        Self {
            stages: Lru::new(STAGE_CAPACITY),
            memo: Lru::new(MEMO_CAPACITY),
            sims: Lru::new(SIM_CAPACITY),
            hits: AtomicU64::new(0),
            misses: AtomicU64::new(0),
            tile_rows: None,
            row_hits: AtomicU64::new(0),
            row_misses: AtomicU64::new(0),
        }
    }

    /// An empty cache that also keeps the tile rows of banded runs (a sequence's frames;
    /// a sweep's rows differ in configuration, not in primitives, and a banded sweep runs
    /// bands to bound its memory, so [`Cache::new`] keeps none).
    pub fn with_tile_rows() -> Self {
        Self {
            tile_rows: Some(Lru::new(TILE_ROW_CAPACITY)),
            ..Self::new()
        }
    }

    /// Whether the cache keeps tile rows.
    pub fn keeps_tile_rows(&self) -> bool {
        self.tile_rows.is_some()
    }

    /// The band with key `key`: kept (and `true`), or `run()` (then kept when the cache
    /// keeps tile rows).
    pub fn tile_row(
        &self,
        key: u64,
        run: impl FnOnce() -> Result<BandResult>,
    ) -> Result<(Arc<BandResult>, bool)> {
        let Some(rows) = &self.tile_rows else {
            return Ok((Arc::new(run()?), false));
        };
        let (v, hit) = rows.get_or(key, || run().map(Arc::new))?;
        let n = if hit {
            &self.row_hits
        } else {
            &self.row_misses
        };
        n.fetch_add(1, Relaxed);
        Ok((v, hit))
    }

    /// Counts the `n` stages of a banded run as reused (every tile row was) or emulated.
    pub fn count_banded(&self, n: u64, reused: bool) {
        let c = if reused { &self.hits } else { &self.misses };
        c.fetch_add(n, Relaxed);
    }

    /// Tile rows (reused, emulated) so far.
    pub fn tile_row_stats(&self) -> (u64, u64) {
        (self.row_hits.load(Relaxed), self.row_misses.load(Relaxed))
    }

    /// The outcome of the stage with key `key`: cached (and `true`), or `run()` (then cached).
    pub fn stage(
        &self,
        key: u64,
        run: impl FnOnce() -> Result<Outcome>,
    ) -> Result<(Arc<Outcome>, bool)> {
        let r = self.stages.get_or(key, || run().map(Arc::new))?;
        if r.1 {
            self.hits.fetch_add(1, Relaxed);
        } else {
            self.misses.fetch_add(1, Relaxed);
        }
        Ok(r)
    }

    /// The simulation of the workload with key `key` and its wall time (s): cached, or
    /// `run()`.
    pub fn sim(
        &self,
        key: u64,
        run: impl FnOnce() -> (SimResult, f64),
    ) -> (Arc<(SimResult, f64)>, bool) {
        match self
            .sims
            .get_or(key, || Ok::<_, Infallible>(Arc::new(run())))
        {
            Ok(v) => v,
            Err(e) => match e {},
        }
    }

    /// Stage (hits, misses) so far.
    pub fn stats(&self) -> (u64, u64) {
        (self.hits.load(Relaxed), self.misses.load(Relaxed))
    }
}

impl Memo for Cache {
    fn get_or_make(
        &self,
        key: u64,
        make: &mut dyn FnMut() -> Arc<dyn Any + Send + Sync>,
    ) -> Arc<dyn Any + Send + Sync> {
        match self.memo.get_or(key, || Ok::<_, Infallible>(make())) {
            Ok((v, _)) => v,
            Err(e) => match e {},
        }
    }
}
