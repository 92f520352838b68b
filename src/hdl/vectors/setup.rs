//! The bench of the edge stepper (`hdl-models/rtl/edge_stepper.v`): a triangle edge loaded
//! from its setup constants, then walked row by row, checked against [`Edge::step`].
//! Vectors: every triangle edge of the quantised scene over all its sample rows, until
//! `EDGE_ROWS` rows are reached; the word widths are the narrowest that hold them.

use super::{EDGE_ROWS, SceneTaps};
use crate::error::Result;
use crate::hdl::bench::Bench;
use crate::stage::StageId;
use crate::stage::input::QPrim;
use crate::stage::setup::Edge;
use std::hint::black_box;
use std::time::Instant;

/// Fills `b` with the edge stepper's parameters and vectors.
/// The edges are geometry, which the channels share: every channel's bench is the same.
pub(super) fn bench(b: &mut Bench, src: &SceneTaps) -> Result<()> {
    // Real scene edges: every triangle edge of the quantised scene, loaded and
    // walked over all its sample rows.
    let (plan, taps) = src.through(StageId::Input)?;
    let g = &plan.layout.grid;
    let mut edges = vec![];
    for p in &taps.fixed.prims().q {
        if let QPrim::Triangle(v) = p {
            let mut s = *v;
            s.sort_by_key(|p| (p.y, p.x));
            for (t, u) in [(0, 1), (1, 2), (0, 2)] {
                if s[u].y > s[t].y {
                    edges.push(Edge::new((s[t].x, s[t].y), (s[u].x, s[u].y), g));
                }
            }
        }
    }
    // Rows of each edge: (load, q, r, a, b, d) in, (q, r, carry) out.
    let mut rows: Vec<[i64; 9]> = vec![];
    let mut walked = 0usize;
    let mut used = 0usize;
    for e0 in &edges {
        if rows.len() >= EDGE_ROWS {
            break;
        }
        used += 1;
        let mut e = *e0;
        rows.push([1, e.q, e.r, e.a, e.b, e.d, e.q, e.r, 0]);
        for _ in e.k0 + 1..e.k1 {
            let c = e.step();
            rows.push([0, 0, 0, 0, 0, 0, e.q, e.r, c as i64]);
            walked += 1;
        }
    }
    edges.truncate(used);
    let bits = |v: i64| 64 - v.unsigned_abs().leading_zeros();
    let qb = rows
        .iter()
        .map(|r| bits(r[1]).max(bits(r[3])).max(bits(r[6])))
        .max()
        .unwrap_or(1)
        + 1;
    let db = rows
        .iter()
        .map(|r| bits(r[5]).max(bits(r[7])))
        .max()
        .unwrap_or(1)
        .max(1);
    let qm = (1u64 << qb) - 1;
    b.params = vec![("Q_BITS".into(), qb as i64), ("D_BITS".into(), db as i64)];
    b.fields = vec!["load", "q_in", "r_in", "a", "b", "d", "q", "r", "carry"];
    b.vectors = rows
        .iter()
        .map(|r| {
            let mut v: Vec<u64> = r.iter().map(|&x| x as u64).collect();
            for k in [1, 3, 6] {
                v[k] &= qm;
            }
            v
        })
        .collect();
    b.sources.push(("scene edges (loads)", used));
    b.sources.push(("scene edges (steps)", walked));
    let t = Instant::now();
    for e0 in &edges {
        let mut e = black_box(*e0);
        for _ in e.k0 + 1..e.k1 {
            black_box(e.step());
        }
    }
    b.model_ns = t.elapsed().as_nanos() as u64;
    Ok(())
}
