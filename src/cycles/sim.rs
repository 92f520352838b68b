//! The cycle-counting simulation of a [`Workload`]: bounded FIFOs, back-pressure, and each
//! stage's busy / stalled / starved / idle cycles.
//!
//! A stage serves one token at a time for its service cycles ([`Workload::services`]), then
//! the token spends `latency` cycles in the stage's pipeline before it enters the FIFO to
//! the next stage (depth `fifo` tokens). When the FIFO is full the pipeline head cannot
//! leave and the whole stage freezes (stalled). Evaluation order within a cycle is upstream
//! first: a token leaving a stage's pipeline at the start of cycle `t` can be taken by the
//! next stage in the same cycle; a FIFO slot freed in cycle `t` is seen upstream in cycle
//! `t + 1`. A single token through a chain therefore takes exactly `sum(service + latency)`
//! cycles. A chain head (no feeder) starts when every stage before it has finished.

use super::workload::Workload;
use serde::Serialize;
use std::collections::VecDeque;

/// What a stage does in a cycle (the VCD `state` code).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum State {
    /// Every token served (its pipeline may still drain); nothing left to do.
    Idle = 0,
    /// Serving a token.
    Busy = 1,
    /// Frozen: its pipeline's head cannot enter the full FIFO.
    Stalled = 2,
    /// Tokens are still to come but none is available.
    Starved = 3,
}

/// Cycle counts of one stage.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct StageCycles {
    /// Stage name.
    pub name: String,
    /// What one item is.
    pub item: String,
    /// Timing used.
    pub lanes: u32,
    /// Latency used.
    pub latency: u32,
    /// Initiation interval used.
    pub ii: u32,
    /// FIFO depth to the next stage (0: the stage is a chain's sink).
    pub fifo: u32,
    /// Tokens served.
    pub tokens: u64,
    /// Items served.
    pub items: u64,
    /// Cycles serving (= the stage's work in cycles).
    pub busy: u64,
    /// Cycles frozen by back-pressure.
    pub stalled: u64,
    /// Cycles waiting for input while tokens were still to come.
    pub starved: u64,
    /// Cycles with nothing left to do.
    pub idle: u64,
    /// Largest occupancy of the FIFO to the next stage.
    pub fifo_max: u32,
}

/// Simulation result.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SimResult {
    /// Cycles of the frame.
    pub total_cycles: u64,
    /// Per stage, in run order.
    pub stages: Vec<StageCycles>,
    /// Cycles a stage was limited by the frame-memory port rather than its lanes.
    pub frame_port_bound_cycles: u64,
}

impl SimResult {
    /// The stage with the most busy cycles (first on a tie).
    pub fn bottleneck(&self) -> &str {
        let mut best: Option<&StageCycles> = None;
        for s in &self.stages {
            if best.is_none_or(|b| s.busy > b.busy) {
                best = Some(s);
            }
        }
        best.map_or("-", |s| s.name.as_str())
    }
    /// Analytic bounds: (largest stage work, sum of works + latencies).
    pub fn bounds(&self) -> (u64, u64) {
        let lo = self.stages.iter().map(|s| s.busy).max().unwrap_or(0);
        let hi = self
            .stages
            .iter()
            .map(|s| s.busy + if s.tokens > 0 { s.latency as u64 } else { 0 })
            .sum();
        (lo, hi)
    }
}

struct Sim {
    service: Vec<u64>,
    next: usize,
    remaining: u64,
    pipe: VecDeque<u32>,
    latency: u32,
    /// FIFO to the next stage: occupancy and depth (`None` for a sink).
    occ: u32,
    depth: Option<u32>,
}

impl Sim {
    fn done(&self) -> bool {
        self.next == self.service.len() && self.remaining == 0 && self.pipe.is_empty()
    }
}

/// Receives every cycle: the cycle, each stage's state and each stage's FIFO occupancy.
pub type Trace<'a> = dyn FnMut(u64, &[State], &[u32]) + 'a;

/// Runs the cycle-counting simulation; `trace` receives every cycle's stage states and
/// FIFO occupancies (for the VCD writer).
pub fn simulate(w: &Workload, mut trace: Option<&mut Trace>) -> SimResult {
    let mut port_bound = 0;
    let mut sims: Vec<Sim> = (0..w.stages.len())
        .map(|i| {
            let (service, pb) = w.services(i);
            port_bound += pb;
            Sim {
                service,
                next: 0,
                remaining: 0,
                pipe: VecDeque::new(),
                latency: w.stages[i].timing.latency,
                occ: 0,
                depth: w.stages[i].fifo,
            }
        })
        .collect();
    let ns = sims.len();
    let feeder: Vec<Option<usize>> = w.stages.iter().map(|s| s.feeder).collect();
    let mut counts = vec![[0u64; 4]; ns];
    let mut fifo_max = vec![0u32; ns];
    let mut states = vec![State::Idle; ns];
    let mut occ = vec![0u32; ns];
    let mut t = 0u64;
    loop {
        for i in 0..ns {
            // Leave the pipeline into the FIFO (or the sink).
            let s = &sims[i];
            if s.pipe.front() == Some(&0) {
                match s.depth {
                    Some(d) if s.occ >= d => {
                        states[i] = State::Stalled;
                        continue;
                    }
                    Some(_) => {
                        sims[i].occ += 1;
                        sims[i].pipe.pop_front();
                    }
                    None => {
                        sims[i].pipe.pop_front();
                    }
                }
            }
            for r in sims[i].pipe.iter_mut() {
                *r = r.saturating_sub(1);
            }
            let available = match feeder[i] {
                Some(f) => sims[f].occ > 0,
                // A chain head starts when every stage before it has finished.
                None => sims[..i].iter().all(Sim::done),
            };
            let s = &mut sims[i];
            let state = if s.remaining > 0 {
                s.remaining -= 1;
                State::Busy
            } else if s.next < s.service.len() {
                if available {
                    s.remaining = s.service[s.next] - 1;
                    s.next += 1;
                    if let Some(f) = feeder[i] {
                        sims[f].occ -= 1;
                    }
                    State::Busy
                } else {
                    State::Starved
                }
            } else {
                State::Idle
            };
            let s = &mut sims[i];
            if state == State::Busy && s.remaining == 0 {
                s.pipe.push_back(s.latency);
            }
            states[i] = state;
        }
        if sims.iter().all(Sim::done) {
            break;
        }
        for i in 0..ns {
            counts[i][states[i] as usize] += 1;
            occ[i] = sims[i].occ;
            fifo_max[i] = fifo_max[i].max(occ[i]);
        }
        if let Some(f) = trace.as_mut() {
            f(t, &states, &occ);
        }
        t += 1;
    }
    let stages = w
        .stages
        .iter()
        .enumerate()
        .map(|(i, s)| StageCycles {
            name: s.id.name().to_string(),
            item: s.item.into(),
            lanes: s.timing.lanes,
            latency: s.timing.latency,
            ii: s.timing.ii,
            fifo: s.fifo.unwrap_or(0),
            tokens: sims[i].service.len() as u64,
            items: s.items.iter().sum(),
            busy: counts[i][State::Busy as usize],
            stalled: counts[i][State::Stalled as usize],
            starved: counts[i][State::Starved as usize],
            idle: counts[i][State::Idle as usize],
            fifo_max: fifo_max[i],
        })
        .collect();
    SimResult {
        total_cycles: t,
        stages,
        frame_port_bound_cycles: port_bound,
    }
}
