//! The VCD (IEEE 1364 value change dump) trace of the cycle simulation, for GTKWave, written
//! with the `vcd` crate's writer.
//!
//! Time stamps are real time at the configured clock: `$timescale` is 1 of the largest unit
//! (s, ms, us, ns, ps, fs) that divides the clock period (rounded to the femtosecond), and
//! cycle `t` is at time `t * P`, `P` the period in that unit ([`cycle_time`]; 100 MHz: `1 ns`,
//! `P` = 10); the header's comment says the same. Per stage
//! `<stage>_state` (2 bits: 0 idle, 1 busy, 2 stalled, 3 starved) and, for a stage that
//! feeds a FIFO, `<stage>_fifo` (its occupancy in tokens). The value at time `t * P` holds
//! during cycle `t`; the dump ends with the time stamp of the frame's total cycles.

use super::{State, Workload};
use std::io::{self, Write};
use vcd::{IdCode, SimulationCommand, TimescaleUnit, Value, VarType};

/// The VCD time of one clock cycle at `clock_mhz`: (time units per cycle, the unit of
/// `$timescale 1 <unit>`), the largest unit that divides the period in femtoseconds.
pub fn cycle_time(clock_mhz: f64) -> (u64, TimescaleUnit) {
    let fs = (1e9 / clock_mhz).round().max(1.0) as u64;
    [
        (1_000_000_000_000_000, TimescaleUnit::S),
        (1_000_000_000_000, TimescaleUnit::MS),
        (1_000_000_000, TimescaleUnit::US),
        (1_000_000, TimescaleUnit::NS),
        (1_000, TimescaleUnit::PS),
    ]
    .into_iter()
    .find(|(d, _)| fs.is_multiple_of(*d))
    .map_or((fs, TimescaleUnit::FS), |(d, u)| (fs / d, u))
}

/// Streams value changes to `out`.
pub struct VcdWriter<W: Write> {
    out: W,
    /// Time units per clock cycle ([`cycle_time`]).
    per_cycle: u64,
    fifo: Vec<bool>,
    last_state: Vec<u8>,
    last_occ: Vec<u32>,
    started: bool,
    err: Option<io::Error>,
}

/// The identifier code of stage `i`'s state (or FIFO) signal: `!`, `"`, `#`, ... as before
/// the `vcd` crate wrote the traces (stage `i` owns codes `2i` and `2i + 1`).
fn id(i: usize, fifo: bool) -> IdCode {
    IdCode::from((2 * i + fifo as usize) as u64)
}

/// The bits of `v`, most significant first, without leading zeros (`0` is one bit).
fn bits(v: u64) -> impl Iterator<Item = Value> {
    let n = (64 - v.leading_zeros()).max(1);
    (0..n).rev().map(move |k| {
        if v >> k & 1 == 1 {
            Value::V1
        } else {
            Value::V0
        }
    })
}

impl<W: Write> VcdWriter<W> {
    /// Writes the header for the stages of `w` (a `_fifo` signal for each stage with a FIFO).
    pub fn new(mut out: W, w: &Workload, clock_mhz: f64) -> io::Result<Self> {
        let fifo: Vec<bool> = (0..w.stages.len()).map(|i| w.has_fifo(i)).collect();
        let mut v = vcd::Writer::new(&mut out);
        let (per_cycle, unit) = cycle_time(clock_mhz);
        v.comment(&format!(
            "igemu cycle trace at {clock_mhz} MHz: 1 clock cycle = {per_cycle} x $timescale 1 {unit} (cycle t at time {per_cycle} t); state 0 idle, 1 busy, 2 stalled, 3 starved"
        ))?;
        v.timescale(1, unit)?;
        v.add_module("igemu")?;
        for (i, s) in w.stages.iter().enumerate() {
            let name = s.id.name();
            v.var_def(
                VarType::Wire,
                2,
                id(i, false),
                &format!("{name}_state"),
                None,
            )?;
            if fifo[i] {
                v.var_def(
                    VarType::Wire,
                    32,
                    id(i, true),
                    &format!("{name}_fifo"),
                    None,
                )?;
            }
        }
        v.upscope()?;
        v.enddefinitions()?;
        Ok(Self {
            out,
            per_cycle,
            fifo,
            last_state: vec![u8::MAX; w.stages.len()],
            last_occ: vec![u32::MAX; w.stages.len()],
            started: false,
            err: None,
        })
    }

    fn write_cycle(&mut self, t: u64, states: &[State], occ: &[u32]) -> io::Result<()> {
        // The crate's writer only formats commands: borrowing the sink per cycle keeps `W`
        // ours to hand back in `finish` (it has no `into_inner`).
        let mut v = vcd::Writer::new(&mut self.out);
        let mut stamped = false;
        for i in 0..states.len() {
            let s = states[i] as u8;
            let o = occ[i];
            let changed_s = s != self.last_state[i];
            let changed_o = self.fifo[i] && o != self.last_occ[i];
            if (changed_s || changed_o) && !stamped {
                v.timestamp(t * self.per_cycle)?;
                if !self.started {
                    v.begin(SimulationCommand::Dumpvars)?;
                }
                stamped = true;
            }
            if changed_s {
                v.change_vector(id(i, false), bits(s.into()))?;
                self.last_state[i] = s;
            }
            if changed_o {
                v.change_vector(id(i, true), bits(o.into()))?;
                self.last_occ[i] = o;
            }
        }
        if stamped && !self.started {
            v.end()?;
            self.started = true;
        }
        Ok(())
    }

    /// Records cycle `t` (errors are kept and returned by `finish`).
    pub fn cycle(&mut self, t: u64, states: &[State], occ: &[u32]) {
        if self.err.is_none()
            && let Err(e) = self.write_cycle(t, states, occ)
        {
            self.err = Some(e);
        }
    }

    /// Ends the dump at `total` cycles and flushes.
    pub fn finish(mut self, total: u64) -> io::Result<W> {
        if let Some(e) = self.err.take() {
            return Err(e);
        }
        vcd::Writer::new(&mut self.out).timestamp(total * self.per_cycle)?;
        self.out.flush()?;
        Ok(self.out)
    }
}
