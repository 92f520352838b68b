//! The stepwise reference of the cycle simulation: one token step per stage per clock, the
//! simulator as it was before [`super::simulate`] learnt to jump over quiet cycles. Kept as
//! the reference the event-driven simulator is tested against (identical [`SimResult`] and
//! identical VCD text, `tests/cycles.rs`) and as the baseline of `cargo bench --bench cycles`.
//! Same semantics as [`super::sim`]; `trace` receives every cycle.

use super::sim::{SimResult, State, Trace};
use super::workload::Workload;
use std::collections::VecDeque;

struct Sim {
    service: Vec<u64>,
    next: usize,
    remaining: u64,
    pipe: VecDeque<u32>,
    latency: u32,
    /// FIFO to the next stage: occupancy and depth (`None` for a sink).
    occ: u32,
    depth: Option<u32>,
    /// Tokens that have left the pipeline.
    out: usize,
}

impl Sim {
    fn done(&self) -> bool {
        self.next == self.service.len() && self.remaining == 0 && self.pipe.is_empty()
    }
}

/// Runs the cycle-counting simulation one clock at a time; `trace` receives every cycle's
/// stage states and FIFO occupancies.
pub fn simulate_stepwise(w: &Workload, mut trace: Option<&mut Trace>) -> SimResult {
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
                out: 0,
            }
        })
        .collect();
    let ns = sims.len();
    let feeder: Vec<Option<usize>> = w.stages.iter().map(|s| s.feeder).collect();
    let reader: Vec<Option<usize>> = (0..ns).map(|i| w.reader(i)).collect();
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
                sims[i].out += 1;
            }
            for r in sims[i].pipe.iter_mut() {
                *r = r.saturating_sub(1);
            }
            let next = sims[i].next;
            let available = match (feeder[i], &w.stages[i].lines) {
                (Some(f), _) => sims[f].occ > 0,
                // A streamed reader: the writer's chain has started and its rows are there.
                (None, Some(l)) => {
                    sims[..l.source].iter().all(Sim::done)
                        && l.readable(next, l.complete(sims[l.source].out))
                }
                // A chain head starts when every stage before it has finished.
                (None, None) => sims[..i].iter().all(Sim::done),
            };
            // A line-buffer writer waits for the space its next token's rows need.
            let fits = match reader[i].map(|r| (&w.stages[r].lines, &sims[r])) {
                Some((Some(l), rd)) if next < sims[i].service.len() => {
                    l.fits(next, rd.next - usize::from(rd.remaining > 0))
                }
                _ => true,
            };
            let s = &mut sims[i];
            let state = if s.remaining > 0 {
                s.remaining -= 1;
                State::Busy
            } else if s.next < s.service.len() {
                if available && !fits {
                    State::Stalled
                } else if available {
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
    let tokens: Vec<u64> = sims.iter().map(|s| s.service.len() as u64).collect();
    super::sim::assemble(w, &tokens, &counts, &fifo_max, t, port_bound)
}
