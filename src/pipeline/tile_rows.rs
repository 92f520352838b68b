//! Keys of tile rows: what one band of a banded run ([`super::bands`]) depends on, so that
//! a sequence's frame keeps the results of every tile row whose primitives did not change
//! since an earlier frame ([`super::Cache::tile_rows`]) and emulates only the others.
//!
//! A band's raster, visibility and accumulate results (fragments, samples, frame rows,
//! work, signals, per-primitive tokens) depend on the configuration, the plan's screen
//! layout, the band's rows and tiles, the background and the primitives whose sample rows
//! meet the rows the band reads: its own rows and the rows before them that its filter
//! windows reach. The key holds exactly these, each primitive by its index (the tokens are
//! per primitive) and its quantised (and, with a reference, float) vertices. The first band
//! also counts the rows the raster walks above the sample region, so it keys every
//! primitive that starts above its end. `tests/sequence_tiles.rs` checks that frames with
//! reused tile rows give the codes and the reports of a full emulation.

use crate::config::HwConfig;
use crate::fnv::Fnv;
use crate::stage::input::{QPrim, QVertex};
use crate::stage::raster::float::{FPrim, FVertex};
use crate::stage::setup::Setup;
use crate::stage::{Band, Layout, RunOptions, Taps};

/// The per-primitive parts of the keys of one frame's bands.
pub struct Keys {
    /// Everything but the primitives and the band.
    base: u64,
    /// Per primitive: the sample rows it may touch (half-open), `None` for none.
    rows: Vec<Option<(i64, i64)>>,
    /// Per primitive: the hash of its index and vertices.
    prims: Vec<u64>,
}

fn vertex(h: Fnv, v: &QVertex) -> Fnv {
    [v.x, v.y, v.z, v.i[0], v.i[1], v.i[2]]
        .iter()
        .fold(h, |h, &x| h.u64(x as u64))
}

fn vertex_f(h: Fnv, v: &FVertex) -> Fnv {
    [v.x, v.y, v.z, v.i[0], v.i[1], v.i[2]]
        .iter()
        .fold(h, |h, x| h.u64(x.to_bits()))
}

fn hash_q(h: Fnv, p: &QPrim) -> Fnv {
    match p {
        QPrim::Triangle(v) => v.iter().fold(h.u64(0), vertex),
        QPrim::Line { a, b, width } => vertex(vertex(h.u64(1), a), b).u64(*width as u64),
        QPrim::Point { v, size } => vertex(h.u64(2), v).u64(*size as u64),
    }
}

fn hash_f(h: Fnv, p: &FPrim) -> Fnv {
    match p {
        FPrim::Triangle(v) => v.iter().fold(h.u64(3), vertex_f),
        FPrim::Line { a, b, width } => vertex_f(vertex_f(h.u64(4), a), b).u64(width.to_bits()),
        FPrim::Point { v, size } => vertex_f(h.u64(5), v).u64(size.to_bits()),
    }
}

/// The sample rows a set-up primitive's raster touches.
fn setup_rows(s: &Setup) -> Option<(i64, i64)> {
    match s {
        Setup::Tri(t) => Some((t.long.k0, t.long.k1)),
        Setup::Line(pair) => {
            let [a, b] = &**pair;
            Some((a.long.k0.min(b.long.k0), a.long.k1.max(b.long.k1)))
        }
        Setup::Point(p) => Some(p.k),
        Setup::Degenerate => None,
    }
}

/// The sample rows a float primitive may touch (`n` sample rows per pixel), with a row of
/// margin on each side.
fn float_rows(p: &FPrim, n: f64) -> (i64, i64) {
    let (ys, grow): (Vec<f64>, f64) = match p {
        FPrim::Triangle(v) => (v.iter().map(|v| v.y).collect(), 0.0),
        FPrim::Line { a, b, width } => (vec![a.y, b.y], width.abs()),
        FPrim::Point { v, size } => (vec![v.y], size.abs()),
    };
    let lo = ys.iter().copied().fold(f64::INFINITY, f64::min) - grow;
    let hi = ys.iter().copied().fold(f64::NEG_INFINITY, f64::max) + grow;
    let row = |y: f64| (y * n).clamp(-1e15, 1e15) as i64;
    (
        row(lo.floor()) - n as i64 - 1,
        row(hi.ceil()) + n as i64 + 1,
    )
}

fn union(a: Option<(i64, i64)>, b: Option<(i64, i64)>) -> Option<(i64, i64)> {
    match (a, b) {
        (Some(x), Some(y)) => Some((x.0.min(y.0), x.1.max(y.1))),
        (x, None) | (None, x) => x,
    }
}

impl Keys {
    /// The keys' parts for the band group `stages` (their names) run on `input` (the taps
    /// after setup) with `hw`, `layout` (the whole plan's) and `opts`.
    pub fn new(
        stages: &[&str],
        hw: &HwConfig,
        layout: &Layout,
        opts: RunOptions,
        input: &Taps,
    ) -> Self {
        let q = &input.fixed.prims().q;
        let setups = input.fixed.setups();
        let float = opts.reference.then(|| &input.float.prims().f);
        let n = f64::from(layout.grid.n);
        let mut base = Fnv::new()
            .str("tile rows")
            .str(&serde_json::to_string(hw).unwrap_or_default())
            .str(&serde_json::to_string(&opts).unwrap_or_default())
            .str(&serde_json::to_string(&layout.grid).unwrap_or_default())
            .str(&serde_json::to_string(&layout.region).unwrap_or_default())
            .str(&serde_json::to_string(&layout.samples).unwrap_or_default())
            .u64(u64::from(layout.tiles.size))
            .u64(layout.channels as u64)
            .u64(q.len() as u64);
        for s in stages {
            base = base.str(s);
        }
        let bg = input.fixed.prims().bg;
        base = bg.iter().fold(base, |h, &b| h.u64(u64::from(b)));
        if let Some(f) = float {
            let bgf = input.float.prims().bg;
            base = bgf.iter().fold(base, |h, b| h.u64(b.to_bits()));
            base = base.u64(f.len() as u64);
        }
        // The processing order (surfaces, then light points) orders the tokens.
        for p in q {
            base = base.u64(u64::from(matches!(p, QPrim::Point { .. })));
        }
        let rows = (0..q.len())
            .map(|i| {
                let r = setups.get(i).and_then(setup_rows);
                match float.and_then(|f| f.get(i)) {
                    Some(p) => union(r, Some(float_rows(p, n))),
                    None => r,
                }
            })
            .collect();
        let prims = (0..q.len())
            .map(|i| {
                let h = hash_q(Fnv::new().u64(i as u64), &q[i]);
                match float.and_then(|f| f.get(i)) {
                    Some(p) => hash_f(h, p),
                    None => h,
                }
                .finish()
            })
            .collect();
        Self {
            base: base.finish(),
            rows,
            prims,
        }
    }

    /// The key of band `b` whose results depend on the sample rows `rows` (half-open) and
    /// whose tiles are `touched`.
    pub fn band(&self, b: &Band, last: bool, rows: (i64, i64), touched: &[bool]) -> u64 {
        let mut h = Fnv::new()
            .u64(self.base)
            .u64(u64::from(b.y0))
            .u64(u64::from(b.y1))
            .u64(u64::from(b.first))
            .u64(u64::from(last))
            .u64(rows.0 as u64)
            .u64(rows.1 as u64);
        for &t in touched {
            h = h.u64(u64::from(t));
        }
        for (r, &p) in self.rows.iter().zip(&self.prims) {
            if let Some((k0, k1)) = *r
                && k0 < rows.1
                && (b.first || k1 > rows.0)
            {
                h = h.u64(p);
            }
        }
        h.finish()
    }
}
