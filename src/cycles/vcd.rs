//! A VCD (IEEE 1364 value change dump) writer for the cycle simulation, for GTKWave.
//!
//! One time unit is one clock cycle (`$timescale 1 ns`: read "ns" as "cycles"). Per stage
//! `<stage>_state` (2 bits: 0 idle, 1 busy, 2 stalled, 3 starved) and, for a stage that
//! feeds a FIFO, `<stage>_fifo` (its occupancy in tokens). The value at time `t` holds
//! during cycle `t`; the dump ends with a time stamp equal to the frame's total cycles.

use super::{State, Workload};
use std::io::{self, Write};

/// Streams value changes to `out`.
pub struct VcdWriter<W: Write> {
    out: W,
    fifo: Vec<bool>,
    last_state: Vec<u8>,
    last_occ: Vec<u32>,
    started: bool,
    err: Option<io::Error>,
}

fn id(i: usize, fifo: bool) -> String {
    let c = (b'!' + (2 * i + fifo as usize) as u8) as char;
    c.to_string()
}

impl<W: Write> VcdWriter<W> {
    /// Writes the header for the stages of `w` (a `_fifo` signal for each stage with a FIFO).
    pub fn new(mut out: W, w: &Workload, clock_mhz: f64) -> io::Result<Self> {
        let fifo: Vec<bool> = (0..w.stages.len()).map(|i| w.has_fifo(i)).collect();
        writeln!(
            out,
            "$comment igemu cycle trace: 1 time unit = 1 clock cycle at {clock_mhz} MHz; state 0 idle, 1 busy, 2 stalled, 3 starved $end"
        )?;
        writeln!(out, "$timescale 1 ns $end")?;
        writeln!(out, "$scope module igemu $end")?;
        for (i, s) in w.stages.iter().enumerate() {
            let name = s.id.name();
            writeln!(out, "$var wire 2 {} {name}_state $end", id(i, false))?;
            if fifo[i] {
                writeln!(out, "$var wire 32 {} {name}_fifo $end", id(i, true))?;
            }
        }
        writeln!(out, "$upscope $end")?;
        writeln!(out, "$enddefinitions $end")?;
        Ok(Self {
            out,
            fifo,
            last_state: vec![u8::MAX; w.stages.len()],
            last_occ: vec![u32::MAX; w.stages.len()],
            started: false,
            err: None,
        })
    }

    fn write_cycle(&mut self, t: u64, states: &[State], occ: &[u32]) -> io::Result<()> {
        let mut stamped = false;
        for i in 0..states.len() {
            let s = states[i] as u8;
            let o = occ[i];
            let changed_s = s != self.last_state[i];
            let changed_o = self.fifo[i] && o != self.last_occ[i];
            if (changed_s || changed_o) && !stamped {
                writeln!(self.out, "#{t}")?;
                if !self.started {
                    writeln!(self.out, "$dumpvars")?;
                }
                stamped = true;
            }
            if changed_s {
                writeln!(self.out, "b{:b} {}", s, id(i, false))?;
                self.last_state[i] = s;
            }
            if changed_o {
                writeln!(self.out, "b{:b} {}", o, id(i, true))?;
                self.last_occ[i] = o;
            }
        }
        if stamped && !self.started {
            writeln!(self.out, "$end")?;
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
        writeln!(self.out, "#{total}")?;
        self.out.flush()?;
        Ok(self.out)
    }
}
