//! The text reports of the commands: the render report, the cycle report, the width
//! validation table, the Pareto front of a sweep, and the work-count list they share.

use crate::out::outln;
use igemu::analysis::widths::RampCheck;
use igemu::cycles::CycleReport;
use igemu::error::Error;
use igemu::pipeline::Report;
use igemu::pipeline::fast::FastReport;
use igemu::pipeline::plan::PlanReport;
use igemu::pipeline::report::SceneInfo;
use std::collections::BTreeMap;

/// Prints the cycle report (plan, per-stage table, frame rate, cost, simulator speed).
pub fn print_cycles(c: &CycleReport) -> Result<(), Error> {
    let p = &c.plan;
    outln!(
        "plan: {} | tiles {}x{} px: {} of {} binned | pixels simulated {} of {} ({:.1}%){}",
        p.stages.join(" -> "),
        p.tile,
        p.tile,
        p.tiles_touched,
        p.tiles_total,
        p.pixels_simulated,
        p.pixels_total,
        100.0 * p.pixels_simulated as f64 / p.pixels_total.max(1) as f64,
        if p.unmodelled.is_empty() {
            String::new()
        } else {
            format!(" | no cycle model: {}", p.unmodelled.join(", "))
        }
    );
    outln!(
        "{:<11} {:>5} {:>4} {:>3} {:>5} {:>8} {:>12} {:>10} {:>10} {:>10} {:>9}  item",
        "stage",
        "lanes",
        "lat",
        "ii",
        "fifo",
        "tokens",
        "items",
        "busy",
        "stalled",
        "starved",
        "fifo max"
    );
    for s in &c.stages {
        outln!(
            "{:<11} {:>5} {:>4} {:>3} {:>5} {:>8} {:>12} {:>10} {:>10} {:>10} {:>9}  {}",
            s.name,
            s.lanes,
            s.latency,
            s.ii,
            s.fifo,
            s.tokens,
            s.items,
            s.busy,
            s.stalled,
            s.starved,
            s.fifo_max,
            s.item
        );
    }
    for line in c.summary_lines() {
        outln!("{line}");
    }
    let k = &c.cost;
    let list = |m: &BTreeMap<String, u64>| {
        m.iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    outln!(
        "cost: RAM {} bits ({}) | ROM {} bits ({}) | {} adders ({} bits) | {} multipliers ({} bit-products)",
        k.total_storage_bits,
        list(&k.storage_bits),
        k.total_rom_bits,
        list(&k.rom_bits),
        k.adders,
        k.adder_bits,
        k.multipliers,
        k.multiplier_bit_products
    );
    let packed: Vec<String> = k
        .packed
        .iter()
        .map(|p| match &p.problem {
            None => format!("{} {} bits ok", p.name, p.bits),
            Some(why) => format!("{} MISMATCH ({why})", p.name),
        })
        .collect();
    outln!("packed with bitvec and read back: {}", packed.join(", "));
    outln!(
        "simulator: {} cycles in {:.2} ms = {:.1} M cycles/s",
        c.total_cycles,
        c.sim.wall_ms,
        c.sim.cycles_per_s / 1e6
    );
    Ok(())
}

/// Prints the ramp validation of the recommended word widths.
pub fn print_width_checks(checks: &[RampCheck], weber: f64) -> Result<(), Error> {
    outln!(
        "validation by emulation: a {}-sample ramp over the full contrast, quantised and through the gamma LUT;",
        igemu::analysis::widths::RAMP_SAMPLES
    );
    outln!("  contours = adjacent output steps with a luminance ratio above 1 + {weber}");
    outln!(
        "  {:<7} {:>9} {:>8} {:>12} {:>8} {:>9}  verdict",
        "coding",
        "code bits",
        "DAC bits",
        "widths",
        "levels",
        "contours"
    );
    for c in checks {
        let verdict = match (c.recommended, c.disagrees) {
            (true, false) => "0 as theory predicts",
            (false, false) => "visible, as theory predicts",
            (true, true) => "DISAGREES with theory: contours at the recommended widths",
            (false, true) => "DISAGREES with theory: no visible contour one bit narrower",
        };
        outln!(
            "  {:<7} {:>9} {:>8} {:>12} {:>8} {:>9}  {verdict}",
            c.coding,
            c.code_bits,
            c.dac_bits,
            if c.recommended {
                "recommended"
            } else {
                "1 bit less"
            },
            c.levels,
            c.contours
        );
    }
    Ok(())
}

/// The non-zero work counts, `name count` comma separated.
fn fmt_work(w: &BTreeMap<String, u64>) -> String {
    w.iter()
        .filter(|(_, v)| **v > 0)
        .map(|(k, v)| format!("{k} {v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The head of a render report: the tool, scene and hardware line, the plan and its
/// decisions.
fn print_head(
    version: &str,
    scene: &SceneInfo,
    hw: &str,
    threads: usize,
    p: &PlanReport,
) -> Result<(), Error> {
    outln!(
        "igemu {} | scene `{}` {}x{} | hardware `{}` | {} threads",
        version,
        scene.name,
        scene.width,
        scene.height,
        hw,
        threads
    );
    outln!(
        "plan: {} | region x {}..{} y {}..{} ({:.1}% of the screen) | tiles {}x{} px: {} binned | {}x{} samples/pixel | gamma {}",
        p.stages.join(" -> "),
        p.region.x0,
        p.region.x1,
        p.region.y0,
        p.region.y1,
        100.0 * p.region_fraction,
        p.tiles.size,
        p.tiles.size,
        p.tiles.binned,
        p.samples,
        p.samples,
        p.gamma
    );
    for d in &p.decisions {
        outln!(
            "  {:<11} {:<3}  {}",
            d.stage.name(),
            if d.need.planned { "in" } else { "out" },
            d.need.reason
        );
    }
    for n in &p.notes {
        outln!("  note: {n}");
    }
    Ok(())
}

/// Prints the render report; `out` is the image written.
pub fn print_report(r: &Report, out: &str) -> Result<(), Error> {
    print_head(
        &r.igemu_version,
        &r.scene,
        &r.hardware.name,
        r.timing.threads,
        &r.plan,
    )?;
    if !r.reused.is_empty() {
        outln!("reused from the cache: {}", r.reused.join(", "));
    }
    outln!();
    outln!(
        "{:<11} {:>9} {:>9}  {:>10} {:>10} {:>9}  work",
        "stage",
        "fixed ms",
        "float ms",
        "max|err|",
        "mean err",
        "overflow"
    );
    for s in &r.stages {
        let (me, mean) = s.local.as_ref().map_or(("-".into(), "-".into()), |l| {
            (
                format!("{:.3}", l.max_abs_lsb),
                format!("{:+.4}", l.mean_lsb),
            )
        });
        let ov: u64 = s.signals.iter().map(|x| x.overflows).sum();
        outln!(
            "{:<11} {:>9.2} {:>9.2}  {:>10} {:>10} {:>9}  {}",
            s.name,
            s.fixed_ms,
            s.float_ms,
            me,
            mean,
            ov,
            fmt_work(&s.work)
        );
    }
    outln!(
        "{:<11} {:>9.2} {:>9.2}  (host front end {:.2} ms, f64, shared)",
        "total",
        r.timing.fixed_ms,
        r.timing.float_ms,
        r.timing.host_ms
    );
    let c = &r.end_to_end.codes;
    let w = &r.end_to_end.weber;
    outln!();
    if r.colour.is_some() {
        outln!(
            "colour render: R, G and B through one raster and one z-buffer; the figures below are channel R's, then each channel's"
        );
    }
    outln!(
        "end to end, DAC codes ({} bits), fixed vs float reference:",
        r.colour
            .as_ref()
            .map_or(r.hardware.gamma.dac_bits, |c| c.channels[0].dac_bits)
    );
    outln!(
        "  identical {:.4}% | max |diff| {} | mean diff {:+.5} | PSNR {}",
        100.0 * c.identical_fraction,
        c.max_abs_diff,
        c.mean_diff,
        c.psnr_db
            .map_or("inf (identical)".into(), |p| format!("{p:.2} dB"))
    );
    let hist: Vec<String> = c
        .histogram
        .iter()
        .map(|(d, n)| format!("{d:+}: {n}"))
        .collect();
    outln!("  histogram of differences: {}", hist.join(", "));
    outln!(
        "  luminance (display model): max Weber {:.4} | mean {:.6} | visible (> {}) {} px ({:.4}%)",
        w.max,
        w.mean,
        w.delta,
        w.over_delta,
        100.0 * w.over_delta_fraction
    );
    let k = &r.contours;
    outln!(
        "  visible contours (smooth regions, window {}x{} px per side, delta {}): {} steps ({} px) | float reference: {} steps | smooth steps {}",
        k.window[0],
        k.window[1],
        k.delta,
        k.contour_steps,
        k.contour_pixels,
        k.contour_steps_reference,
        k.smooth_steps
    );
    if let Some(col) = &r.colour {
        print_colour(col)?;
    }
    if let Some(pm) = r
        .stages
        .iter()
        .find_map(|s| s.notes.get("temporal_period_mean"))
    {
        outln!(
            "  temporal dither: static frame over a period of {} frames: {} of {} pixels average exactly to their input (max |error| {} LSB)",
            pm["period"],
            pm["exact_pixels"],
            pm["pixels"],
            pm["max_abs_error"]
        );
    }
    if let Some(t) = &r.dof_truth {
        print_truth(t)?;
    }
    print_tail((r.storage_bits, r.lut_bits, r.overflows), &r.cycles, out)
}

/// The `dof_truth` block: the truth's noise and the three-way split of the errors.
fn print_truth(t: &igemu::truth::TruthReport) -> Result<(), Error> {
    outln!("depth-of-field truth: {}", t.summary());
    outln!(
        "  vs truth, DAC codes mean |diff| / RMS / max, mean Weber   whole | depth-edge band ({} px, {} px wide) | interior",
        t.edge_pixels,
        t.edge_band_px
    );
    for (name, s) in t.rows() {
        outln!(
            "  {:<18} {} | {} | {}",
            name,
            s.whole.brief(),
            s.edge.brief(),
            s.interior.brief()
        );
    }
    Ok(())
}

/// Prints the Pareto front of sweep rows on `axes` (`igemu sweep`, `igemu sweep merge`): per
/// scene, ordered by the first axis, with each row's configuration.
pub fn print_front(
    rows: &[igemu::sweep::Row],
    axes: &[igemu::sweep::pareto::Axis],
) -> Result<(), Error> {
    use crate::out::out;
    let front = igemu::sweep::pareto::front(rows, axes);
    outln!(
        "Pareto front on {} ({} of {} rows):",
        axes.iter()
            .map(|x| x.name())
            .collect::<Vec<_>>()
            .join(" x "),
        front.len(),
        rows.len()
    );
    out!("  {:>5}  {:<16}", "index", "scene");
    for x in axes {
        out!("  {:>18}", x.name());
    }
    outln!("  configuration");
    for &i in &front {
        let r = &rows[i];
        out!("  {:>5}  {:<16}", r.index, r.scene);
        for x in axes {
            out!("  {:>18}", x.show(x.value(r)));
        }
        let cfg: Vec<String> = r.config.iter().map(|(k, v)| format!("{k}={v}")).collect();
        outln!("  {}", cfg.join(" "));
    }
    Ok(())
}

/// The per-channel lines of a colour render.
fn print_colour(col: &igemu::pipeline::colour::ColourReport) -> Result<(), Error> {
    outln!(
        "  per channel (frame word, DAC bits): identical | max |diff| | visible Weber px | contour steps fixed/float | overflows | storage bits | LUT bits | cycles (bottleneck)"
    );
    for ch in &col.channels {
        let (c, w, k) = (&ch.end_to_end.codes, &ch.end_to_end.weber, &ch.contours);
        outln!(
            "    {} ({}, {} bits): {:.4}% | {} | {} | {}/{} | {} | {} | {} | {} ({})",
            ch.name,
            ch.frame,
            ch.dac_bits,
            100.0 * c.identical_fraction,
            c.max_abs_diff,
            w.over_delta,
            k.contour_steps,
            k.contour_steps_reference,
            ch.overflows,
            ch.storage_bits,
            ch.lut_bits,
            ch.cycles,
            ch.bottleneck
        );
    }
    let (e, hue) = (&col.delta_e, &col.hue_shift);
    outln!(
        "  colour (CIEDE2000 through the display, sRGB primaries): mean {:.4} | p99 {:.4} | max {:.4} | > 1: {} px | > {}: {} px (Delta E*ab > {}: {} px)",
        e.mean,
        e.p99,
        e.max,
        e.over_1,
        igemu::colour::JND,
        e.over_jnd,
        igemu::colour::JND,
        e.over_jnd_ab
    );
    outln!(
        "  hue shift on smooth chromatic surfaces (chroma >= {}): {} of {} smooth px | mean {:.3} deg | p99 {:.3} deg | max {:.3} deg | contour steps over R, G, B {} (float {})",
        igemu::colour::MIN_CHROMA,
        hue.pixels,
        hue.smooth_pixels,
        hue.mean_deg,
        hue.p99_deg,
        hue.max_deg,
        col.contour_steps[0],
        col.contour_steps[1]
    );
    Ok(())
}

/// Prints the report of a fixed-only run (`render --no-reference`): the plan, the fixed
/// stages' times, work and overflows, each channel's lane, the cost and the cycle model.
pub fn print_fast(r: &FastReport, out: &str) -> Result<(), Error> {
    print_head(
        &r.igemu_version,
        &r.scene,
        &r.hardware.name,
        r.timing.threads,
        &r.plan,
    )?;
    outln!("  fixed only (--no-reference): no float reference ran, nothing is compared");
    outln!();
    outln!("{:<11} {:>9} {:>9}  work", "stage", "fixed ms", "overflow");
    for s in &r.stages {
        let ov: u64 = s.signals.iter().map(|x| x.overflows).sum();
        outln!(
            "{:<11} {:>9.2} {:>9}  {}",
            s.name,
            s.fixed_ms,
            ov,
            fmt_work(&s.work)
        );
    }
    outln!(
        "{:<11} {:>9.2}  (host front end {:.2} ms, f64)",
        "total",
        r.timing.fixed_ms,
        r.timing.host_ms
    );
    if !r.channels.is_empty() {
        outln!("  per channel (frame word, DAC bits): overflows | storage bits | LUT bits");
        for ch in &r.channels {
            outln!(
                "    {} ({}, {} bits): {} | {} | {}",
                ch.name,
                ch.frame,
                ch.dac_bits,
                ch.overflows,
                ch.storage_bits,
                ch.lut_bits
            );
        }
    }
    print_tail((r.storage_bits, r.lut_bits, r.overflows), &r.cycles, out)
}

/// The end of a render report: the cost line, the cycle report and the image written.
fn print_tail(
    (storage, lut, overflows): (u64, u64, u64),
    cycles: &CycleReport,
    out: &str,
) -> Result<(), Error> {
    outln!(
        "cost: storage {storage} bits ({:.1} KiB), LUT/ROM {lut} bits | overflows {overflows}",
        storage as f64 / 8192.0
    );
    outln!();
    print_cycles(cycles)?;
    outln!("wrote {out}");
    Ok(())
}
