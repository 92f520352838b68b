//! Banded runs: raster, visibility and accumulate, fixed and float, band by band of pixel
//! rows, so that the sample buffers and the fragment lists hold one band and the peak
//! memory follows the band, not the screen. The frame memory, the float frame and every
//! later stage stay whole-frame; the cost model still charges the hardware's full-frame
//! memories (the stages' costs read the plan's grid, not the band).
//!
//! Each band owns a range of sample rows; the bands' own rows partition the plan's sample
//! region, so every sample is rasterised and resolved exactly once and the work counts,
//! signals and tokens of the bands add up to the whole-region run's. The accumulate stage
//! of a band reads its pixel rows' filter windows: the band's own sample rows plus the
//! rows just before them, which the band before resolved (kept as the tail of its buffer).
//!
//! A small plan (the sample-side memory under [`ONE_BAND_MAX`]) runs in one band, which is
//! the whole-region code path. A plan with the logdomain stage runs in one band too.

use super::band_tail::{Tail, join};
use super::cache::Cache;
use super::plan::Plan;
use super::run::{Outcome, execute_keep};
use super::tile_rows::Keys;
use crate::cost::{PackCheck, pack};
use crate::error::Result;
use crate::stage::accumulate::Frame;
use crate::stage::taps::FrameTap;
use crate::stage::{
    self, AnyFixed, Band, Cx, Layout, LocalError, Memo, Region, RunOptions, SampleRegion, StageId,
    StageReport, Taps, TokenKind, Tokens,
};
use std::sync::Arc;

/// Sample-side bytes (sample buffers and fragment lists, from the plan's estimate) up to
/// which a plan runs in one band.
pub const ONE_BAND_MAX: u64 = 512 << 20;
/// Sample-side bytes one band aims at (at least one tile row).
pub const BAND_BYTES: u64 = 64 << 20;

/// Whether a banded run runs stage `id` band by band.
pub fn is_banded(id: StageId) -> bool {
    matches!(
        id,
        StageId::Raster | StageId::Visibility | StageId::Accumulate
    )
}

/// Pixel rows per band (a multiple of the tile size) of `plan` under `opts`; `None`: one
/// band (the whole-region run).
pub fn rows(plan: &Plan, opts: RunOptions) -> Option<u32> {
    let l = &plan.layout;
    if l.has(StageId::Logdomain) || l.region.is_empty() || !l.has(StageId::Accumulate) {
        return None;
    }
    let tile = l.tiles.size;
    let r = match opts.band_rows {
        Some(r) => r.max(1).div_ceil(tile) * tile,
        None => {
            let (buffers, frags) = super::estimate::sample_side(plan, opts);
            let bytes = buffers + frags;
            if bytes <= ONE_BAND_MAX as f64 {
                return None;
            }
            let per_row = bytes / f64::from((l.region.y1 - l.region.y0).max(1));
            let r = (BAND_BYTES as f64 / per_row).floor() as u32;
            (r / tile).max(1) * tile
        }
    };
    (r < l.grid.height).then_some(r)
}

/// The bands of `rows` pixel rows over a `height`-row screen.
pub fn bands(rows: u32, height: u32) -> Vec<Band> {
    (0..height.div_ceil(rows))
        .map(|b| Band {
            y0: b * rows,
            y1: ((b + 1) * rows).min(height),
            first: b == 0,
        })
        .collect()
}

/// Sample rows of the plan's sample region a band owns, and the first row its pixels'
/// filter windows read.
struct Rows {
    own: (i64, i64),
    read: i64,
}

fn band_rows(l: &Layout, b: &Band, last: bool) -> Rows {
    let g = l.samples;
    let n = i64::from(l.grid.n);
    // The window of pixel row p reads sample rows [p n - off, (p + 1) n + after).
    let off = i64::from(l.region.y0) * n - g.k0;
    let after = g.k1 - i64::from(l.region.y1) * n;
    let clamp = |k: i64| k.clamp(g.k0, g.k1);
    let lo = if b.first {
        g.k0
    } else {
        clamp(i64::from(b.y0) * n + after)
    };
    let hi = if last {
        g.k1
    } else {
        clamp(i64::from(b.y1) * n + after)
    };
    Rows {
        own: (lo, hi),
        read: clamp(i64::from(b.y0) * n - off).min(lo),
    }
}

/// What the bands of one stage add up to.
#[derive(Default)]
struct Merge {
    report: Option<StageReport>,
    tokens: Option<Tokens>,
    packs: Vec<PackCheck>,
    /// Unfinished local errors (mean fields hold sums), the report's and the notes'.
    local: Option<LocalError>,
    note_locals: std::collections::BTreeMap<String, LocalError>,
}

fn unfinish(e: &LocalError) -> LocalError {
    LocalError {
        mean_lsb: e.mean_lsb * e.values as f64,
        ..e.clone()
    }
}

/// A note that is a local error (e.g. the raster's `depth_local`).
fn local_of(v: &serde_json::Value) -> Option<LocalError> {
    let o = v.as_object()?;
    if o.len() != 5 {
        return None;
    }
    let u = |k: &str| o.get(k).and_then(|x| x.as_u64());
    let f = |k: &str| o.get(k).and_then(|x| x.as_f64());
    Some(LocalError {
        values: u("values")?,
        identical: u("identical")?,
        max_abs_lsb: f("max_abs_lsb")?,
        mean_lsb: f("mean_lsb")?,
        mismatched_items: u("mismatched_items")?,
    })
}

impl Merge {
    /// Adds a band's outcome; `y0`: the band's first screen row (its tokens' rows are the
    /// band's own).
    fn add(&mut self, o: &Outcome, pack_images: bool, y0: u32) {
        let r = &o.report;
        match &mut self.report {
            None => self.report = Some(r.clone()),
            Some(m) => {
                m.fixed_ms += r.fixed_ms;
                m.float_ms += r.float_ms;
                m.local_ms += r.local_ms;
                for (k, v) in &r.work {
                    *m.work.entry(k.clone()).or_insert(0) += v;
                }
                for (a, b) in m.signals.iter_mut().zip(&r.signals) {
                    a.merge(b);
                }
                // Counts add up; a width or a memory's size (`*_bits`) is the band's own.
                for (k, v) in r.notes.iter().filter(|(k, _)| !k.ends_with("_bits")) {
                    if let (Some(a), Some(b)) =
                        (m.notes.get(k).and_then(|x| x.as_u64()), v.as_u64())
                    {
                        m.notes.insert(k.clone(), (a + b).into());
                    }
                }
            }
        }
        if let Some(e) = &r.local {
            self.local
                .get_or_insert_with(LocalError::default)
                .merge(&unfinish(e));
        }
        for (k, v) in &r.notes {
            if let Some(e) = local_of(v) {
                self.note_locals
                    .entry(k.clone())
                    .or_default()
                    .merge(&unfinish(&e));
            }
        }
        if let Some(t) = &o.tokens {
            let mut t = t.clone();
            for r in &mut t.rows {
                *r += y0;
            }
            let t = &t;
            match &mut self.tokens {
                None => self.tokens = Some(t.clone()),
                Some(m) if m.kind == TokenKind::Primitive => {
                    for (a, b) in m.items.iter_mut().zip(&t.items) {
                        *a += b;
                    }
                    for (a, b) in m.port_bits.iter_mut().zip(&t.port_bits) {
                        *a += b;
                    }
                }
                Some(m) => {
                    m.items.extend_from_slice(&t.items);
                    m.port_bits.extend_from_slice(&t.port_bits);
                    m.rows.extend_from_slice(&t.rows);
                }
            }
        }
        if pack_images {
            for p in &o.packs {
                match self.packs.iter_mut().find(|q| q.name == p.name) {
                    None => self.packs.push(p.clone()),
                    Some(q) => {
                        q.words += p.words;
                        q.cost_bits += p.cost_bits;
                        q.bits += p.bits;
                        q.verified &= p.verified;
                        if q.problem.is_none() {
                            q.problem.clone_from(&p.problem);
                        }
                    }
                }
            }
        }
    }

    fn finish(mut self, taps: Taps, packs: Option<Vec<PackCheck>>) -> Outcome {
        let mut report = self.report.take().unwrap_or_default();
        report.local = self.local.map(LocalError::finish);
        for (k, e) in self.note_locals {
            report
                .notes
                .insert(k, serde_json::to_value(e.finish()).unwrap_or_default());
        }
        Outcome {
            taps,
            report,
            tokens: self.tokens,
            packs: packs.unwrap_or(self.packs),
            images: Vec::new(),
        }
    }
}

/// One channel lane's accumulate on one band.
struct LaneBand {
    /// The accumulate stage's outcome, without taps.
    outcome: Outcome,
    /// The band's frame rows.
    frame: Arc<FrameTap>,
    /// Its float frame rows (with a reference).
    float: Option<Arc<Vec<f64>>>,
    /// The accumulate stage's private result (its cost and memories read it).
    acc: Arc<AnyFixed>,
    /// The rows the next band reads before its own (`None` for the last band).
    tail: Option<Tail>,
}

/// What one band gave: the outcomes (no taps) of the stages before accumulate, and each
/// channel lane's accumulate: its outcome, frame rows and the sample rows the next band's
/// filter windows read. A sequence's stage cache keeps it for the next frame
/// ([`super::Cache::tile_row`], keyed by [`super::tile_rows::Keys`]).
pub struct BandResult {
    outcomes: Vec<Outcome>,
    lanes: Vec<LaneBand>,
}

/// A channel lane's accumulate: its configuration ([`crate::config::HwConfig::channel`])
/// and input key (channel 0's is the visibility stage's key).
pub struct LaneIn {
    /// The lane's configuration.
    pub hw: crate::config::HwConfig,
    /// Its accumulate stage's input key.
    pub key: u64,
}

/// One lane's merged accumulate over the bands.
struct LaneFrame {
    merge: Merge,
    frame: Frame,
    float: Vec<f64>,
    coding: Option<crate::stage::taps::FrameCoding>,
    acc: Option<Arc<AnyFixed>>,
    tail: Option<Tail>,
}

/// Runs the banded stages `group` (raster, visibility, accumulate in flow order) of `plan`
/// band by band of `rows` pixel rows on the taps `input`, and returns each stage's merged
/// outcome: work, signals, tokens, local errors and timings added up over the bands; the
/// taps after raster and visibility without fragment lists and sample buffers (no stage
/// keeps a whole-screen one); the whole frame and float frame after accumulate. The
/// accumulate stage runs once per lane of `lanes` (one for grey; R, G, B for colour, each
/// on its channel's samples): the group's last outcome is lane 0's, the second list holds
/// the other lanes' (their taps carry their lane's frame). With a `cache` that keeps tile
/// rows, a band whose key is in it is not run again.
#[allow(clippy::too_many_arguments)]
pub fn run(
    group: &[StageId],
    scene: &crate::scene::Scene,
    hw: &crate::config::HwConfig,
    plan: &Plan,
    opts: RunOptions,
    (memo, pool, cache): (&dyn Memo, &stage::Pool, Option<&Cache>),
    (input_keys, lanes): (&[u64], &[LaneIn]),
    input: &Taps,
    rows: u32,
) -> Result<(Vec<Outcome>, Vec<Outcome>)> {
    let l = &plan.layout;
    let (width, height) = (l.grid.width, l.grid.height);
    let npix = width as usize * height as usize;
    let mut frames: Vec<LaneFrame> = lanes
        .iter()
        .map(|_| LaneFrame {
            merge: Merge::default(),
            frame: Frame {
                width,
                height,
                acc: vec![0; npix],
                depth: vec![0; npix],
                coverage: vec![0; npix],
            },
            float: if opts.reference {
                vec![0.0; npix]
            } else {
                Vec::new()
            },
            coding: None,
            acc: None,
            tail: None,
        })
        .collect();
    let before = group.len() - 1;
    let mut merged: Vec<Merge> = (0..before).map(|_| Merge::default()).collect();
    let list = bands(rows, height);
    let keys = cache.filter(|c| c.keeps_tile_rows()).map(|_| {
        let names: Vec<&str> = group.iter().map(|g| g.name()).collect();
        Keys::new(&names, hw, l, opts, input)
    });
    let one = OneBand {
        group,
        scene,
        hw,
        plan,
        opts,
        memo,
        pool,
        input_keys,
        lanes,
        input,
    };
    let mut all_reused = true;
    for (bi, b) in list.iter().enumerate() {
        let last = bi + 1 == list.len();
        let r = band_rows(l, b, last);
        let next = list
            .get(bi + 1)
            .map(|nb| band_rows(l, nb, bi + 2 == list.len()).read);
        let tails: Vec<Option<&Tail>> = frames.iter().map(|f| f.tail.as_ref()).collect();
        let run = || one.run(b, &r, &tails, next);
        let res = match (cache, &keys) {
            (Some(c), Some(k)) => {
                let touched = l.tiles.band(b.y0, b.y1).touched;
                let (res, reused) =
                    c.tile_row(k.band(b, last, (r.read, r.own.1), &touched), run)?;
                all_reused &= reused;
                res
            }
            _ => Arc::new(run()?),
        };
        for (m, o) in merged.iter_mut().zip(&res.outcomes) {
            m.add(o, true, b.y0);
        }
        let at = b.y0 as usize * width as usize;
        for (f, lb) in frames.iter_mut().zip(&res.lanes) {
            f.merge.add(&lb.outcome, false, b.y0);
            let band = &lb.frame.frame;
            let len = band.acc.len();
            f.frame.acc[at..at + len].copy_from_slice(&band.acc);
            f.frame.depth[at..at + len].copy_from_slice(&band.depth);
            f.frame.coverage[at..at + len].copy_from_slice(&band.coverage);
            if let Some(x) = &lb.float {
                f.float[at..at + len].copy_from_slice(x);
            }
            f.coding = Some(lb.frame.coding.clone());
            f.acc = Some(lb.acc.clone());
            f.tail.clone_from(&lb.tail);
        }
    }
    if let Some(c) = cache.filter(|c| c.keeps_tile_rows()) {
        c.count_banded(group.len() as u64, all_reused);
    }
    // The taps after each stage: no fragment lists or sample buffers; the whole frame.
    let mut taps = input.clone();
    let mut out = Vec::with_capacity(group.len());
    for m in merged {
        out.push(m.finish(taps.clone(), None));
    }
    let mut accs = Vec::with_capacity(lanes.len());
    for (c, (f, lane)) in frames.into_iter().zip(lanes).enumerate() {
        let mut t = taps.clone();
        t.lane = c;
        t.fixed.frame = Some(Arc::new(FrameTap {
            frame: f.frame,
            coding: f.coding.expect("a band ran"),
        }));
        t.float.frame = opts.reference.then(|| Arc::new(f.float));
        t.float.frame_content = None;
        // The memories of the whole frame, packed once.
        let cx = Cx {
            scene,
            hw: &lane.hw,
            layout: l,
            opts,
            input_key: lane.key,
            memo,
            pool,
        };
        let st = stage::get(StageId::Accumulate);
        let fixed = f.acc.expect("a band ran");
        let cost = st.cost(&cx, &fixed);
        let images = if opts.pack_check {
            st.memories(&cx, &fixed, &t)
        } else {
            Vec::new()
        };
        let packs = pack::check(&cost, &images);
        if c == 0 {
            taps = t.clone();
        }
        accs.push(f.merge.finish(t, Some(packs)));
    }
    let mut accs = accs.into_iter();
    out.extend(accs.next());
    drop(taps);
    Ok((out, accs.collect()))
}

/// What every band of one banded run shares.
struct OneBand<'a> {
    group: &'a [StageId],
    scene: &'a crate::scene::Scene,
    /// The geometry stages' configuration (every channel's).
    hw: &'a crate::config::HwConfig,
    plan: &'a Plan,
    opts: RunOptions,
    memo: &'a dyn Memo,
    pool: &'a stage::Pool,
    input_keys: &'a [u64],
    lanes: &'a [LaneIn],
    input: &'a Taps,
}

impl OneBand<'_> {
    fn cx<'b>(
        &'b self,
        hw: &'b crate::config::HwConfig,
        layout: &'b Layout,
        input_key: u64,
    ) -> Cx<'b> {
        Cx {
            scene: self.scene,
            hw,
            layout,
            opts: self.opts,
            input_key,
            memo: self.memo,
            pool: self.pool,
        }
    }

    /// Runs the group on band `b` (its rows `r`), each lane's filter windows reading its
    /// `tails`' rows before its own; keeps the rows from `next` on for the next band.
    fn run(
        &self,
        b: &Band,
        r: &Rows,
        tails: &[Option<&Tail>],
        next: Option<i64>,
    ) -> Result<BandResult> {
        let l = &self.plan.layout;
        let (width, height) = (l.grid.width, l.grid.height);
        let n = i64::from(l.grid.n);
        let own = SampleRegion {
            k0: r.own.0,
            k1: r.own.1,
            ..l.samples
        };
        let geo = Layout {
            samples: own,
            band: Some(*b),
            ..l.clone()
        };
        let mut taps = self.input.clone();
        let mut outcomes = Vec::with_capacity(self.group.len());
        let before = self.group.len() - 1;
        for (&id, &key) in self.group[..before].iter().zip(self.input_keys) {
            let (o, _) = execute_keep(stage::get(id), &self.cx(self.hw, &geo, key), &taps)?;
            taps = o.taps;
            outcomes.push(Outcome {
                taps: Taps::default(),
                images: Vec::new(),
                ..o
            });
        }
        let rows = Region {
            y0: b.y0,
            y1: b.y1,
            ..Region::screen(width, height)
        };
        let c = l.region.clip(&rows);
        let region = if c.is_empty() {
            Region::default()
        } else {
            Region {
                y0: c.y0 - b.y0,
                y1: c.y1 - b.y0,
                ..c
            }
        };
        let multi = self.lanes.len() > 1;
        let mut lanes = Vec::with_capacity(self.lanes.len());
        for (k, (lane, tail)) in self.lanes.iter().zip(tails).enumerate() {
            let mut t = if multi { taps.lane(k) } else { taps.clone() };
            let joined = join(
                *tail,
                r.read,
                i64::from(b.y0) * n,
                t.fixed.samples(),
                t.float.samples.as_deref(),
            );
            let layout = Layout {
                region,
                samples: joined.fixed.samples.reg,
                tiles: l.tiles.band(b.y0, b.y1),
                ..geo.clone()
            };
            t.fixed.samples = Some(joined.fixed.clone());
            t.float.samples.clone_from(&joined.float);
            let st = stage::get(StageId::Accumulate);
            let (o, fixed) = execute_keep(st, &self.cx(&lane.hw, &layout, lane.key), &t)?;
            lanes.push(LaneBand {
                frame: o
                    .taps
                    .fixed
                    .frame
                    .clone()
                    .expect("accumulate wrote the band's frame"),
                float: o.taps.float.frame.clone(),
                outcome: Outcome {
                    taps: Taps::default(),
                    images: Vec::new(),
                    ..o
                },
                acc: Arc::new(fixed),
                tail: next.map(|k| joined.from(k)),
            });
        }
        Ok(BandResult { outcomes, lanes })
    }
}
