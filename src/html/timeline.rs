//! Each stage's busy / stalled / starved / idle cycles over the frame, in bins of equal
//! length, from the cycle simulation's trace (the picture of where a stage waits).

use crate::cycles::{State, Workload, simulate};

/// Per stage, per bin, the cycles in each [`State`] (indexed by `State as usize`).
#[derive(Clone, Debug, PartialEq)]
pub struct Timeline {
    /// Cycles of the frame.
    pub total: u64,
    /// Cycles per bin (the last bin may be shorter).
    pub bin: u64,
    /// `[stage][bin][state]`.
    pub counts: Vec<Vec<[u64; 4]>>,
}

/// Simulates `w` once more with a trace and bins each stage's states into at most `bins`
/// bins. The simulator reports only the clocks it steps; a state holds until the next one.
pub fn timeline(w: &Workload, bins: usize) -> Timeline {
    let ns = w.stages.len();
    // Changes only: (cycle, states) whenever a state differs from the previous clock's.
    let mut changes: Vec<(u64, Vec<State>)> = Vec::new();
    let mut trace = |t: u64, states: &[State], _: &[u32]| {
        if changes.last().is_none_or(|(_, s)| s.as_slice() != states) {
            changes.push((t, states.to_vec()));
        }
    };
    let total = simulate(w, Some(&mut trace)).total_cycles;
    let bins = bins.max(1) as u64;
    let bin = total.div_ceil(bins).max(1);
    let nb = total.div_ceil(bin) as usize;
    let mut counts = vec![vec![[0u64; 4]; nb]; ns];
    for (k, (start, states)) in changes.iter().enumerate() {
        let end = changes.get(k + 1).map_or(total, |c| c.0).min(total);
        let mut a = *start;
        while a < end {
            let b = end.min((a / bin + 1) * bin);
            let j = (a / bin) as usize;
            for (i, s) in states.iter().enumerate() {
                counts[i][j][*s as usize] += b - a;
            }
            a = b;
        }
    }
    Timeline { total, bin, counts }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::CyclesCfg;
    use crate::cycles::ScreenFacts;
    use crate::stage::{StageId, TokenKind, Tokens};

    fn tokens(items: Vec<u64>) -> Tokens {
        Tokens {
            kind: TokenKind::Primitive,
            item: "items",
            items,
            port_bits: Vec::new(),
            rows: vec![],
            stream: None,
        }
    }

    #[test]
    fn the_bins_add_up_to_the_simulated_counts() {
        let cfg = CyclesCfg::default_for(12);
        let a = tokens(vec![3; 50]);
        let b = tokens((0..50).map(|i| 1 + (i % 7) * 9).collect());
        let w = Workload::new(
            &[(StageId::Setup, Some(&a)), (StageId::Raster, Some(&b))],
            &cfg,
            ScreenFacts::default(),
            crate::config::DofSchedule::Stream,
        );
        let r = simulate(&w, None);
        for bins in [1, 7, 64, 10_000] {
            let t = timeline(&w, bins);
            assert_eq!(t.total, r.total_cycles);
            assert!(t.counts[0].len() <= bins);
            for (i, s) in r.stages.iter().enumerate() {
                let sum = |st: State| t.counts[i].iter().map(|c| c[st as usize]).sum::<u64>();
                assert_eq!(sum(State::Busy), s.busy, "{} busy, {bins} bins", s.name);
                assert_eq!(sum(State::Stalled), s.stalled);
                assert_eq!(sum(State::Starved), s.starved);
                assert_eq!(sum(State::Idle), s.idle);
            }
        }
    }
}
