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
//!
//! A streamed reader ([`Lines`], `dof.schedule = "stream"`) is a chain head that starts a
//! row when the stages before its writer have finished and the writer's tokens holding the
//! rows it reads have left the writer's pipeline (seen in the same cycle, as a FIFO entry
//! is). The writer starts a token only when its rows fit the line buffers, as the reader's
//! served rows stood at the end of the cycle before (as a freed FIFO slot); until then it
//! is stalled while its pipeline drains.
//!
//! # Jumping over quiet cycles
//! [`simulate`] steps one clock exactly as the stepwise reference
//! ([`super::stepwise::simulate_stepwise`]) does, then jumps over the following cycles in
//! which no stage can change state or touch a FIFO. After a clock, each stage stays as it is
//! for a number of cycles it knows from its own counters alone, as long as no other stage
//! acts: a busy stage until its token's last service cycle (`remaining - 1` cycles), a
//! starved or idle one (or one stalled by full line buffers) until its pipeline's head
//! reaches the output, a stalled one for ever (until the next stage takes a token). The other stages can only end that by an action of
//! their own (entering a FIFO, taking from one, finishing), which their own count bounds, so
//! the smallest count over the stages is a run of cycles in which every state and FIFO
//! occupancy repeats: the counts grow in bulk, service counters and pipeline countdowns
//! shrink in bulk, and the next clock is stepped again. The trace receives only the stepped
//! clocks; the skipped ones repeat the last values, so a value-change dump is the same text.

use super::workload::{Lines, Workload};
use serde::Serialize;

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
    /// Service cycles of the current token still to come.
    remaining: u64,
    /// The tokens in the stage's pipeline (front: the oldest), each as the value of
    /// `clock` at which its countdown reaches 0.
    pipe: Pipe,
    /// The stage's pipeline clock: cycles in which its countdowns ran (every cycle but the
    /// frozen ones), so that a token's countdown is its entry less `clock`, and running
    /// every countdown is one add.
    clock: u64,
    latency: u32,
    /// FIFO to the next stage: occupancy and depth (`None` for a sink).
    occ: u32,
    depth: Option<u32>,
    feeder: Option<usize>,
    /// Tokens that have left the pipeline.
    out: usize,
    /// The line buffers it reads (a streamed reader).
    lines: Option<Lines>,
    /// The streamed reader of the rows it writes (a line-buffer writer).
    reader: Option<usize>,
    /// Whether it could not start a token in the last clock because the line buffers were
    /// full (stalled, its pipeline still drains).
    blocked: bool,
}

/// A FIFO of countdown ends: a list and the index of its front. Tokens leave in the order
/// they entered, so the list is emptied whenever the front passes its end.
#[derive(Default)]
struct Pipe {
    ends: Vec<u64>,
    front: usize,
}

impl Pipe {
    #[inline]
    fn front(&self) -> Option<&u64> {
        self.ends.get(self.front)
    }
    #[inline]
    fn is_empty(&self) -> bool {
        self.front == self.ends.len()
    }
    #[inline]
    fn pop_front(&mut self) {
        self.front += 1;
        if self.is_empty() {
            self.ends.clear();
            self.front = 0;
        }
    }
    #[inline]
    fn push_back(&mut self, end: u64) {
        self.ends.push(end);
    }
}

impl Sim {
    fn done(&self) -> bool {
        self.next == self.service.len() && self.remaining == 0 && self.pipe.is_empty()
    }

    /// Tokens whose service is complete.
    pub(super) fn served(next: usize, remaining: u64) -> usize {
        next - usize::from(remaining > 0)
    }

    /// After a clock in which the stage was in `state`: the cycles that follow in which it
    /// stays in `state` and touches no FIFO, as long as no other stage acts.
    fn quiet(&self, state: State) -> u64 {
        match state {
            // Waiting for line-buffer space: only the reader's action ends it; the pipeline
            // drains meanwhile.
            State::Stalled if self.blocked => self.head(),
            // Frozen until the next stage takes a token (its own action).
            State::Stalled => match self.depth {
                Some(d) if self.occ >= d => u64::MAX,
                _ => 0,
            },
            _ => {
                // The pipeline's head leaves (or stalls) in the cycle after it reaches 0.
                let head = self.head();
                if state == State::Busy {
                    // The last service cycle puts the token into the pipeline.
                    head.min(self.remaining.saturating_sub(1))
                } else {
                    // Starved: the feeder's FIFO (or the earlier stages) change only by an
                    // action of their own. Idle: only the pipeline drains.
                    head
                }
            }
        }
    }

    /// Advances `n` quiet cycles (`n <= self.quiet(state)`).
    fn skip(&mut self, state: State, n: u64) {
        if state == State::Stalled && !self.blocked {
            return;
        }
        if state == State::Busy {
            self.remaining -= n;
        }
        // n <= the head's countdown <= every countdown.
        self.clock += n;
    }

    /// The countdown of the pipeline's head (`u64::MAX`: empty).
    fn head(&self) -> u64 {
        self.pipe.front().map_or(u64::MAX, |&c| c - self.clock)
    }
}

/// Receives the clocks the simulator steps, in order: the cycle, each stage's state and
/// each stage's FIFO occupancy. A cycle not passed repeats the values of the one before
/// (the simulator jumped over it); every change of a value is passed.
pub type Trace<'a> = dyn FnMut(u64, &[State], &[u32]) + 'a;

/// One clock of every stage, upstream first (the semantics of the module doc).
fn clock(sims: &mut [Sim], states: &mut [State]) {
    for i in 0..sims.len() {
        // Leave the pipeline into the FIFO (or the sink).
        let s = &mut sims[i];
        s.blocked = false;
        if s.pipe.front() == Some(&s.clock) {
            match s.depth {
                Some(d) if s.occ >= d => {
                    states[i] = State::Stalled;
                    continue;
                }
                Some(_) => {
                    s.occ += 1;
                    s.pipe.pop_front();
                }
                None => {
                    s.pipe.pop_front();
                }
            }
            s.out += 1;
        }
        // Every countdown runs (none is 0 behind the head: each entered in its own cycle).
        s.clock += 1;
        let state = if s.remaining > 0 {
            s.remaining -= 1;
            State::Busy
        } else if s.next < s.service.len() {
            let s = &sims[i];
            let available = match (s.feeder, &s.lines) {
                (Some(f), _) => sims[f].occ > 0,
                // A streamed reader: the writer's chain has started and its rows are there.
                (None, Some(l)) => {
                    sims[..l.source].iter().all(Sim::done)
                        && l.readable(s.next, l.complete(sims[l.source].out))
                }
                // A chain head starts when every stage before it has finished.
                (None, None) => sims[..i].iter().all(Sim::done),
            };
            let fits = s.reader.is_none_or(|r| {
                let (l, rd) = (&sims[r].lines, &sims[r]);
                l.as_ref()
                    .is_none_or(|l| l.fits(s.next, Sim::served(rd.next, rd.remaining)))
            });
            if available && !fits {
                sims[i].blocked = true;
                State::Stalled
            } else if available {
                let s = &mut sims[i];
                s.remaining = s.service[s.next] - 1;
                s.next += 1;
                if let Some(f) = s.feeder {
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
            s.pipe.push_back(s.clock + u64::from(s.latency));
        }
        states[i] = state;
    }
}

/// Runs the cycle-counting simulation, jumping over quiet cycles (module doc); `trace`
/// receives the stepped clocks' stage states and FIFO occupancies (for the VCD writer).
/// The counts are those of one clock at a time ([`super::stepwise::simulate_stepwise`]). A
/// workload that can never finish (a stage waiting for tokens its feeder never sends) ends
/// at the first cycle from which nothing can change, instead of looping for ever.
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
                pipe: Pipe::default(),
                clock: 0,
                latency: w.stages[i].timing.latency,
                occ: 0,
                depth: w.stages[i].fifo,
                feeder: w.stages[i].feeder,
                out: 0,
                lines: w.stages[i].lines.clone(),
                reader: w.reader(i),
                blocked: false,
            }
        })
        .collect();
    let ns = sims.len();
    let mut counts = vec![[0u64; 4]; ns];
    let mut fifo_max = vec![0u32; ns];
    let mut states = vec![State::Idle; ns];
    let mut occ = vec![0u32; ns];
    let mut t = 0u64;
    loop {
        clock(&mut sims, &mut states);
        // One pass: whether every stage is done, the FIFO occupancies and the quiet run.
        let (mut all_done, mut quiet) = (true, u64::MAX);
        for (i, s) in sims.iter().enumerate() {
            all_done &= s.done();
            occ[i] = s.occ;
            quiet = quiet.min(s.quiet(states[i]));
        }
        if all_done {
            break;
        }
        if let Some(f) = trace.as_mut() {
            f(t, &states, &occ);
        }
        // This clock and the quiet cycles after it (none when every stage waits for
        // another for ever: a chain whose stages pass different numbers of tokens, which
        // no run produces and the stepwise reference would loop on; the frame ends here).
        let run = if quiet == u64::MAX { 1 } else { 1 + quiet };
        for i in 0..ns {
            counts[i][states[i] as usize] += run;
            fifo_max[i] = fifo_max[i].max(occ[i]);
        }
        t += run;
        if quiet == u64::MAX {
            break;
        }
        for (s, &st) in sims.iter_mut().zip(&states) {
            s.skip(st, quiet);
        }
    }
    let tokens: Vec<u64> = sims.iter().map(|s| s.service.len() as u64).collect();
    assemble(w, &tokens, &counts, &fifo_max, t, port_bound)
}

/// The result of a simulation of `w`: tokens, per-state counts and FIFO maxima per stage.
pub(super) fn assemble(
    w: &Workload,
    tokens: &[u64],
    counts: &[[u64; 4]],
    fifo_max: &[u32],
    total_cycles: u64,
    frame_port_bound_cycles: u64,
) -> SimResult {
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
            tokens: tokens[i],
            items: s.items.iter().sum(),
            busy: counts[i][State::Busy as usize],
            stalled: counts[i][State::Stalled as usize],
            starved: counts[i][State::Starved as usize],
            idle: counts[i][State::Idle as usize],
            fifo_max: fifo_max[i],
        })
        .collect();
    SimResult {
        total_cycles,
        stages,
        frame_port_bound_cycles,
    }
}
