//! HDL co-simulation: test vectors from the Rust model for the Verilog models in
//! `hdl-models/rtl/`, the parameter file that carries the widths of a hardware config,
//! running the self-checking testbenches under Icarus Verilog, parsing their verdict, and
//! yosys synthesis cell counts.
//!
//! A bench directory holds `params.vh` (`` `define``s: vector count, fields per vector and
//! the module's parameters), `vectors.hex` (one 64-bit hex word per field, `N_FIELDS`
//! words per vector: inputs then expected outputs) and the ROM files the module loads
//! with `$readmemh`. The testbench prints exactly one verdict line,
//! `TESTBENCH OK <n> vectors` or `TESTBENCH FAILED: ...`.

use crate::config::CodingKind;
use crate::config::HwConfig;
use crate::error::{Error, FileError, Result};
use crate::pipeline::{self, RenderOptions};
use crate::scene::Scene;
use crate::stage::accumulate::AccParams;
use crate::stage::dither::{Mask, extended_lut, ordered_code};
use crate::stage::gamma::{GammaLut, GammaSpec};
use crate::stage::input::QPrim;
use crate::stage::setup::Edge;
use std::fmt::Write as _;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

pub mod exhaustive;
pub mod synth;
pub mod verilator;

/// Stages with an HDL model: (stage name, Verilog module).
pub const MODULES: &[(&str, &str)] = &[
    ("gamma", "gamma_lut"),
    ("accumulate", "acc_mac"),
    ("dither", "dither_ordered"),
    ("logdomain", "log_adder"),
    ("setup", "edge_stepper"),
    ("dof", "dof_row_mac"),
];

mod dof;

/// The Verilog module of a stage name, if it has one.
pub fn module_of(stage: &str) -> Option<&'static str> {
    MODULES.iter().find(|m| m.0 == stage).map(|m| m.1)
}

/// The `hdl-models/` directory of the source tree.
pub fn models_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("hdl-models")
}

/// A testbench's inputs: parameters, ROMs and vectors.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Bench {
    /// Stage name.
    pub stage: String,
    /// Verilog module.
    pub module: &'static str,
    /// Module parameters (`P_<NAME>` defines).
    pub params: Vec<(String, i64)>,
    /// ROM files: (file name, entries).
    pub roms: Vec<(String, Vec<u64>)>,
    /// Field names of one vector (inputs then expected outputs).
    pub fields: Vec<&'static str>,
    /// The vectors, `fields.len()` values each.
    pub vectors: Vec<Vec<u64>>,
    /// Vectors from each source: (source, count).
    pub sources: Vec<(&'static str, usize)>,
    /// Wall time of the Rust model re-evaluating every vector once (nanoseconds; the
    /// per-vector model call, including building its output row).
    pub model_ns: u64,
}

/// A testbench's verdict.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// All vectors agree.
    Ok(u64),
    /// The testbench's failure line (without the `TESTBENCH FAILED: ` prefix).
    Failed(String),
}

/// Finds the single verdict line in a testbench's output.
pub fn parse_verdict(out: &str) -> Option<Verdict> {
    let mut found = None;
    for l in out.lines() {
        let l = l.trim();
        if let Some(r) = l.strip_prefix("TESTBENCH OK ") {
            let n = r.strip_suffix(" vectors")?.trim().parse().ok()?;
            if found.is_some() {
                return None;
            }
            found = Some(Verdict::Ok(n));
        } else if let Some(r) = l.strip_prefix("TESTBENCH FAILED:") {
            if found.is_some() {
                return None;
            }
            found = Some(Verdict::Failed(r.trim().to_string()));
        }
    }
    found
}

/// A small deterministic generator (splitmix64) for random vectors.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn bits(&mut self, b: u32) -> u64 {
        if b == 0 {
            0
        } else {
            self.next() >> (64 - b.min(64))
        }
    }
}

pub(crate) fn bad(hw: &HwConfig, field: &str, msg: String) -> Error {
    Error::File(FileError {
        file: hw.name.clone(),
        line: None,
        col: None,
        field: field.into(),
        msg,
    })
}

/// Up to `max` frame codes from the scene's fixed render, evenly spread over the image.
fn frame_taps(scene: &Scene, hw: &HwConfig, max: usize) -> Result<Vec<(u32, u32, u32)>> {
    let r = pipeline::render(scene, hw, RenderOptions { stage_local: false })?;
    let w = r.frame.width.max(1) as usize;
    let n = r.frame.acc.len();
    let step = n.div_ceil(max).max(1);
    Ok((0..n)
        .step_by(step)
        .map(|p| ((p % w) as u32, (p / w) as u32, r.frame.acc[p]))
        .collect())
}

/// Random vectors of each bench.
const RANDOM: usize = 2000;
/// Edge-stepper rows: whole edges are added until this many rows are reached.
const EDGE_ROWS: usize = 40_000;
/// Scene taps of each bench.
const TAPS: usize = 2000;

/// Builds the bench of `stage` for the hardware config, with taps from the scene.
pub fn vectors(stage: &str, scene: &Scene, hw: &HwConfig) -> Result<Bench> {
    let module = module_of(stage).ok_or_else(|| {
        bad(
            hw,
            "--stage",
            format!(
                "no HDL model of stage `{stage}`; allowed: {}",
                MODULES.iter().map(|m| m.0).collect::<Vec<_>>().join(", ")
            ),
        )
    })?;
    let frame = hw.accumulate.frame;
    if frame.format.signed {
        return Err(bad(
            hw,
            "accumulate.frame",
            format!(
                "the HDL models take an unsigned frame word, not {}",
                frame.format
            ),
        ));
    }
    let acc_bits = frame.format.total_bits();
    let frac = frame.format.frac_bits;
    let int_bits = frame.format.int_bits;
    let gamma_value = hw.gamma.gamma.unwrap_or(scene.display.gamma);
    let spec = GammaSpec::new(
        gamma_value,
        hw.gamma.correction,
        hw.gamma.dac_bits,
        hw.gamma.quant,
    );
    let mut rng = Rng(0x1D1_5EED ^ acc_bits as u64);
    let mut b = Bench {
        stage: stage.into(),
        module,
        params: vec![],
        roms: vec![],
        fields: vec![],
        vectors: vec![],
        sources: vec![],
        model_ns: 0,
    };
    match stage {
        "gamma" => {
            if hw.coding.kind == CodingKind::LogAdd {
                return Err(bad(
                    hw,
                    "coding.kind",
                    "the gamma model holds the linear frame's LUT; log-add uses the eq. 15 LUT (not modelled in HDL)".into(),
                ));
            }
            let lut = GammaLut::build(&spec, int_bits);
            b.params = vec![
                ("ACC_BITS".into(), acc_bits as i64),
                ("FRAC_BITS".into(), frac as i64),
                ("DAC_BITS".into(), hw.gamma.dac_bits as i64),
            ];
            b.roms = vec![(
                "gamma_rom.hex".into(),
                lut.table.iter().map(|&v| v as u64).collect(),
            )];
            b.fields = vec!["acc", "dac"];
            let one = |a: u32| {
                let mut o = [0u16];
                lut.apply(&[a], frac, &mut o);
                vec![a as u64, o[0] as u64]
            };
            let taps = frame_taps(scene, hw, TAPS)?;
            b.vectors.extend(taps.iter().map(|t| one(t.2)));
            b.sources.push(("scene", taps.len()));
            for a in 0..1u64 << int_bits {
                let f = rng.bits(frac) as u32;
                b.vectors.push(one(((a << frac) as u32) | f));
            }
            b.sources.push(("exhaustive", 1 << int_bits));
            for _ in 0..RANDOM {
                b.vectors.push(one(rng.bits(acc_bits) as u32));
            }
            b.sources.push(("random", RANDOM));
            let t = Instant::now();
            for v in &b.vectors {
                black_box(one(black_box(v[0] as u32)));
            }
            b.model_ns = t.elapsed().as_nanos() as u64;
        }
        "accumulate" => {
            let f = pipeline::front(scene, hw)?;
            let i_fmt = hw.input.intensity.format;
            let ap = AccParams {
                kernel: f.kernel.clone(),
                i_frac: i_fmt.frac_bits,
                frame,
            };
            let quant = match frame.quant {
                crate::fixed::Quant::Trn | crate::fixed::Quant::TrnZero => 0,
                crate::fixed::Quant::Rnd | crate::fixed::Quant::RndInf => 1,
                crate::fixed::Quant::RndZero | crate::fixed::Quant::RndMinInf => 2,
                crate::fixed::Quant::RndConv => 3,
            };
            let ovf = match frame.overflow {
                crate::fixed::Overflow::Wrap => 0,
                crate::fixed::Overflow::SatZero => 2,
                _ => 1,
            };
            let wb = 32
                - f.kernel
                    .w
                    .iter()
                    .max()
                    .copied()
                    .unwrap_or(1)
                    .leading_zeros();
            let wb = wb.max(f.kernel.f + 1);
            let ib = i_fmt.total_bits();
            b.params = vec![
                ("W_BITS".into(), wb as i64),
                ("I_BITS".into(), ib as i64),
                ("F_BITS".into(), acc_bits as i64),
                ("SHIFT".into(), ap.product_shift() as i64),
                ("QUANT".into(), quant),
                ("OVF".into(), ovf),
            ];
            b.fields = vec!["w", "i", "acc_in", "acc_out", "ovf"];
            let one = |w: u32, i: u32, a: u32| {
                let (c, o) = ap.mac_code(a as i64, w, i);
                vec![w as u64, i as u64, a as u64, c as u64, o as u64]
            };
            // Scene taps: the kernel's weights, the scene's vertex intensity codes and
            // the rendered frame codes as the running sum.
            let taps = frame_taps(scene, hw, TAPS)?;
            let ws: Vec<u32> = f.kernel.w.clone();
            let is: Vec<u32> = f
                .qprims
                .iter()
                .flat_map(|p| match p {
                    QPrim::Triangle(v) => vec![v[0].i, v[1].i, v[2].i],
                    QPrim::Line { a, b, .. } => vec![a.i, b.i],
                    QPrim::Point { v, .. } => vec![v.i],
                })
                .map(|i| i.max(0) as u32)
                .chain(std::iter::once(f.bg.0))
                .collect();
            for (k, t) in taps.iter().enumerate() {
                let w = ws[k % ws.len()];
                let i = is[(k / ws.len() + k) % is.len()];
                b.vectors.push(one(w, i, t.2));
            }
            b.sources.push(("scene", taps.len()));
            // Edge cases: full weight x full intensity onto every frame boundary.
            let wmax = (1u64 << wb) - 1;
            let imax = (1u64 << ib) - 1;
            let amax = (1u64 << acc_bits) - 1;
            let mut edge = 0;
            for w in [0, 1, 1u64 << f.kernel.f, wmax] {
                for i in [0, 1, imax / 2, imax] {
                    for a in [0, 1, amax / 2, amax - 1, amax] {
                        b.vectors.push(one(w as u32, i as u32, a as u32));
                        edge += 1;
                    }
                }
            }
            b.sources.push(("edge", edge));
            for _ in 0..RANDOM {
                // Random weight up to 2^f (a weight sum never exceeds it), random operands.
                let w = rng.bits(wb) as u32;
                b.vectors
                    .push(one(w, rng.bits(ib) as u32, rng.bits(acc_bits) as u32));
            }
            b.sources.push(("random", RANDOM));
            let t = Instant::now();
            for v in &b.vectors {
                black_box(one(v[0] as u32, v[1] as u32, black_box(v[2] as u32)));
            }
            b.model_ns = t.elapsed().as_nanos() as u64;
        }
        "dither" => {
            // The configured mask; without an ordered dither configured, Bayer 4x4.
            let cfg = &hw.dither;
            let mask = Mask::of(cfg).unwrap_or_else(|| Mask::bayer(4));
            let s = cfg.frac_bits;
            let dac = hw.gamma.dac_bits;
            let omax = (1u32 << dac) - 1;
            let xb = dac + s;
            let log_n = mask.n.trailing_zeros();
            b.params = vec![
                ("X_BITS".into(), xb as i64),
                ("S".into(), s as i64),
                ("LOG_N".into(), log_n as i64),
                ("O_BITS".into(), dac as i64),
                ("OMAX".into(), omax as i64),
            ];
            b.roms = vec![(
                "dither_rom.hex".into(),
                mask.rank.iter().map(|&v| v as u64).collect(),
            )];
            b.fields = vec!["x", "px", "py", "ox", "oy", "c", "sat"];
            let m = mask.n - 1;
            let one = |x: u32, px: u32, py: u32, off: (u32, u32)| {
                let c = ordered_code(x, s, mask.at(px, py, off), mask.bits);
                vec![
                    x as u64,
                    (px & m) as u64,
                    (py & m) as u64,
                    off.0 as u64,
                    off.1 as u64,
                    c.min(omax as u64),
                    (c > omax as u64) as u64,
                ]
            };
            let lut = extended_lut(&spec, int_bits, s);
            let amax = lut.len() - 1;
            let taps = frame_taps(scene, hw, TAPS)?;
            let off = mask.offset(cfg.frame);
            for t in &taps {
                let x = lut[((t.2 >> frac) as usize).min(amax)];
                b.vectors.push(one(x, t.0, t.1, off));
            }
            b.sources.push(("scene", taps.len()));
            // Exhaustive: every input code at every mask phase (offset of frame 0).
            let off0 = mask.offset(0);
            for x in 0..1u32 << xb {
                for p in 0..mask.n * mask.n {
                    b.vectors.push(one(x, p % mask.n, p / mask.n, off0));
                }
            }
            b.sources
                .push(("exhaustive", (1usize << xb) * (mask.n * mask.n) as usize));
            for _ in 0..RANDOM {
                let t = rng.bits(32) as u32;
                let off = mask.offset(t);
                b.vectors.push(one(
                    rng.bits(xb) as u32,
                    rng.bits(log_n) as u32,
                    rng.bits(log_n) as u32,
                    off,
                ));
            }
            b.sources.push(("random", RANDOM));
            let t = Instant::now();
            for v in &b.vectors {
                let off = (v[3] as u32, v[4] as u32);
                black_box(one(black_box(v[0] as u32), v[1] as u32, v[2] as u32, off));
            }
            b.model_ns = t.elapsed().as_nanos() as u64;
        }
        "logdomain" => {
            let add = exhaustive::log_adder_of(scene, hw)?;
            let fb = add.frame_bits();
            let td = add.table_data_bits().max(1);
            b.params = vec![
                ("FB".into(), fb as i64),
                ("TD".into(), td as i64),
                ("TF".into(), add.tf as i64),
                ("ADDR_BITS".into(), add.addr_bits as i64),
                ("SHIFT".into(), add.shift as i64),
                ("INTERP".into(), add.interpolate as i64),
                ("MAX".into(), add.max),
            ];
            b.roms = vec![
                (
                    "log_rom.hex".into(),
                    add.sb.iter().map(|&v| v as u64).collect(),
                ),
                // The full pair space, for tb_log_adder_exhaustive: one signature per row.
                (
                    exhaustive::SIG_FILE.into(),
                    exhaustive::row_signatures(fb, |a, c| add.add(a, c)),
                ),
            ];
            b.fields = vec!["a", "b", "s"];
            let one = |a: i64, c: i64| vec![a as u64, c as u64, add.add(a, c) as u64];
            // Exhaustive over all pairs of 8-bit codes (the zero code, the smallest sums).
            let small = add.max.min(255);
            for a in 0..=small {
                for c in 0..=small {
                    b.vectors.push(one(a, c));
                }
            }
            b.sources.push(("exhaustive 8-bit pairs", b.vectors.len()));
            // Every difference (every table address and the essential zero) at a random
            // larger operand, both operand orders.
            let mut n = 0;
            for d in 0..=add.max {
                let m = d + rng.bits(fb) as i64 % (add.max - d + 1);
                b.vectors.push(one(m, m - d));
                b.vectors.push(one(m - d, m));
                n += 2;
            }
            b.sources.push(("every difference", n));
            let taps = frame_taps(scene, hw, TAPS)?;
            for w in taps.windows(2) {
                b.vectors.push(one(w[0].2 as i64, w[1].2 as i64));
            }
            b.sources.push(("scene", taps.len().saturating_sub(1)));
            for _ in 0..RANDOM {
                let a = rng.bits(fb) as i64 % (add.max + 1);
                let c = rng.bits(fb) as i64 % (add.max + 1);
                b.vectors.push(one(a, c));
            }
            b.sources.push(("random", RANDOM));
            let t = Instant::now();
            for v in &b.vectors {
                black_box(one(black_box(v[0] as i64), v[1] as i64));
            }
            b.model_ns = t.elapsed().as_nanos() as u64;
        }
        "setup" => {
            // Real scene edges: every triangle edge of the quantised scene, loaded and
            // walked over all its sample rows.
            let f = pipeline::front(scene, hw)?;
            let g = &f.grid;
            let mut edges = vec![];
            for p in &f.qprims {
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
        }
        "dof" => dof::bench(&mut b, scene, hw, &mut rng)?,
        _ => unreachable!("module_of checked the name"),
    }
    Ok(b)
}

impl Bench {
    /// The `params.vh` text.
    pub fn params_vh(&self) -> String {
        let mut s = format!(
            "// Generated by igemu hdl vectors --stage {} (module {}).\n`define N_VECTORS {}\n`define N_FIELDS {}\n",
            self.stage,
            self.module,
            self.vectors.len(),
            self.fields.len()
        );
        for (k, v) in &self.params {
            let _ = writeln!(s, "`define P_{k} {v}");
        }
        s
    }

    /// Writes `params.vh`, `vectors.hex` and the ROM files into `dir` (created).
    pub fn write(&self, dir: &Path) -> Result<()> {
        let io = |p: &Path, e: std::io::Error| Error::Io {
            path: p.display().to_string(),
            source: e,
        };
        std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
        let put = |name: &str, text: String| {
            let p = dir.join(name);
            std::fs::write(&p, text).map_err(|e| io(&p, e))
        };
        put("params.vh", self.params_vh())?;
        let mut v = String::with_capacity(self.vectors.len() * self.fields.len() * 17);
        for row in &self.vectors {
            for x in row {
                let _ = writeln!(v, "{x:016x}");
            }
        }
        put("vectors.hex", v)?;
        for (name, rom) in &self.roms {
            let mut r = String::with_capacity(rom.len() * 9);
            for x in rom {
                let _ = writeln!(r, "{x:x}");
            }
            put(name, r)?;
        }
        Ok(())
    }
}

/// Whether a program runs (`prog -V` or `--version`).
pub fn available(prog: &str) -> bool {
    Command::new(prog)
        .arg(if prog == "iverilog" {
            "-V"
        } else {
            "--version"
        })
        .output()
        .is_ok()
}

/// A testbench run: verdict and wall times.
#[derive(Clone, Debug, PartialEq)]
pub struct SimRun {
    /// The verdict.
    pub verdict: Verdict,
    /// iverilog compile time (seconds).
    pub compile_s: f64,
    /// vvp simulation time, including reading the vector file (seconds).
    pub sim_s: f64,
}

/// Compiles and runs the testbench of `module` on the bench in `dir` under Icarus Verilog;
/// returns the verdict, or the simulator's output when there is none.
pub fn run_icarus(module: &str, dir: &Path) -> std::result::Result<Verdict, String> {
    run_icarus_timed(module, dir).map(|r| r.verdict)
}

/// [`run_icarus`] with the compile and simulation wall times.
pub fn run_icarus_timed(module: &str, dir: &Path) -> std::result::Result<SimRun, String> {
    run_icarus_tb(&format!("tb_{module}"), module, dir)
}

/// [`run_icarus_timed`] of testbench `tb` (`hdl-models/tb/<tb>.v`) of `module`.
pub fn run_icarus_tb(tb: &str, module: &str, dir: &Path) -> std::result::Result<SimRun, String> {
    let m = models_dir();
    let sim = dir.join("sim.vvp");
    let t = Instant::now();
    let c = Command::new("iverilog")
        .arg("-g2005")
        .arg("-I")
        .arg(dir)
        .arg("-o")
        .arg(&sim)
        .arg(m.join("tb").join(format!("{tb}.v")))
        .arg(m.join("rtl").join(format!("{module}.v")))
        .output()
        .map_err(|e| format!("iverilog: {e}"))?;
    if !c.status.success() {
        return Err(format!(
            "iverilog failed: {}",
            String::from_utf8_lossy(&c.stderr)
        ));
    }
    let compile_s = t.elapsed().as_secs_f64();
    let mut vvp = Command::new("vvp");
    vvp.arg("-n").arg(&sim).current_dir(dir);
    run_simulation(vvp, "vvp", compile_s)
}

/// Runs a built simulation (`what` names it in errors), times it and parses its verdict.
pub(crate) fn run_simulation(
    mut cmd: Command,
    what: &str,
    compile_s: f64,
) -> std::result::Result<SimRun, String> {
    let t = Instant::now();
    let r = cmd.output().map_err(|e| format!("{what}: {e}"))?;
    let sim_s = t.elapsed().as_secs_f64();
    let out = String::from_utf8_lossy(&r.stdout).to_string();
    let verdict = parse_verdict(&out).ok_or_else(|| {
        format!(
            "no single verdict line in the {what} output: {out}{}",
            String::from_utf8_lossy(&r.stderr)
        )
    })?;
    Ok(SimRun {
        verdict,
        compile_s,
        sim_s,
    })
}
