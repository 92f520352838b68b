//! The cycle simulators side by side: the event-driven one against the stepwise reference
//! (results and VCD text), and synthetic streamed depth-of-field workloads.

use super::Rng;
use igemu::config::{CyclesCfg, DofSchedule};
use igemu::cycles::vcd::VcdWriter;
use igemu::cycles::{self, ScreenFacts, SimResult, State, Workload};
use igemu::stage::{RowStream, StageId, TokenKind, Tokens};

/// A simulation and its VCD text, by the event-driven simulator (`stepwise = false`) or the
/// one-clock-at-a-time reference.
pub fn sim_and_vcd(w: &Workload, stepwise: bool) -> (SimResult, String) {
    let mut vcd = VcdWriter::new(Vec::new(), w, 100.0).unwrap();
    let mut trace = |t, st: &[State], occ: &[u32]| vcd.cycle(t, st, occ);
    let r = if stepwise {
        cycles::simulate_stepwise(w, Some(&mut trace))
    } else {
        cycles::simulate(w, Some(&mut trace))
    };
    let text = String::from_utf8(vcd.finish(r.total_cycles).unwrap()).unwrap();
    (r, text)
}

/// The event-driven simulator gives the reference's result and VCD text on `w`, with and
/// without a trace.
pub fn assert_same_as_stepwise(w: &Workload, what: &str) -> SimResult {
    let (fast, fast_vcd) = sim_and_vcd(w, false);
    let (slow, slow_vcd) = sim_and_vcd(w, true);
    assert_eq!(fast, slow, "{what}");
    assert_eq!(cycles::simulate(w, None), slow, "{what}: without a trace");
    assert!(fast_vcd == slow_vcd, "{what}: the VCD texts differ");
    // Every token was served (no stage waits for ever, e.g. on line buffers).
    for (i, st) in slow.stages.iter().enumerate() {
        let work: u64 = w.services(i).0.iter().sum();
        assert_eq!(st.busy, work, "{what}: {}", st.name);
    }
    slow
}

/// A synthetic plan: accumulate tokens `acc` (first row of each, items), a streamed dof of
/// `dof_rows` items per row with `radius`, optionally gamma behind it.
pub fn streamed(
    acc: &[(u32, u64)],
    dof_rows: &[u64],
    radius: u32,
    tile: u32,
    gamma: bool,
    c: &CyclesCfg,
) -> Workload {
    let a = Tokens {
        kind: TokenKind::Tile,
        item: "MACs",
        items: acc.iter().map(|t| t.1).collect(),
        port_bits: vec![],
        rows: acc.iter().map(|t| t.0).collect(),
        stream: None,
    };
    let d = Tokens {
        kind: TokenKind::Layer,
        item: "pass outputs",
        items: vec![dof_rows.iter().sum()],
        port_bits: vec![],
        rows: vec![],
        stream: Some(RowStream {
            items: dof_rows.to_vec(),
            radius,
            read_bits: 7,
        }),
    };
    let g = Tokens {
        kind: TokenKind::Row,
        item: "pixels",
        items: vec![3; dof_rows.len()],
        port_bits: vec![],
        rows: vec![],
        stream: None,
    };
    let mut planned = vec![(StageId::Accumulate, Some(&a)), (StageId::Dof, Some(&d))];
    if gamma {
        planned.push((StageId::Gamma, Some(&g)));
    }
    let screen = ScreenFacts {
        tile_size: tile,
        screen_pixels: 5 * dof_rows.len() as u64,
        ..ScreenFacts::default()
    };
    Workload::new(&planned, c, screen, DofSchedule::Stream)
}

/// A random streamed plan: tile rows of random tiles (some tile rows unbinned), random
/// items per row, radius and timings (small FIFOs and long latencies among them).
pub fn random_streamed(rng: &mut Rng) -> Workload {
    let tile = 1 + (rng.next_u64() % 5) as u32;
    let height = 1 + (rng.next_u64() % 24) as u32;
    let mut acc = Vec::new();
    for ty in 0..height.div_ceil(tile) {
        if rng.next_u64().is_multiple_of(3) {
            continue;
        }
        for _ in 0..1 + rng.next_u64() % 3 {
            acc.push((ty * tile, rng.next_u64() % 200));
        }
    }
    let rows: Vec<u64> = (0..height).map(|_| rng.next_u64() % 60).collect();
    let radius = match rng.next_u64() % 4 {
        0 => 0,
        1 => height + (rng.next_u64() % 4) as u32,
        _ => (rng.next_u64() % 6) as u32,
    };
    let mut c = CyclesCfg::default_for(12);
    for id in igemu::config::TIMED {
        let t = c.timing_mut(id).unwrap();
        t.lanes = 1 + (rng.next_u64() % 8) as u32;
        t.latency = [0, 1, 5, 40][(rng.next_u64() % 4) as usize];
        t.ii = 1 + (rng.next_u64() % 2) as u32;
        t.fifo = 1 + (rng.next_u64() % 3) as u32;
    }
    streamed(
        &acc,
        &rows,
        radius,
        tile,
        rng.next_u64().is_multiple_of(2),
        &c,
    )
}
