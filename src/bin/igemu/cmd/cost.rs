//! `igemu cost`: hardware cost per stage, the analytic model, and with `--synth` the yosys
//! cell counts of the HDL models at the configured widths.

use crate::args::SceneArgs;
use crate::out::outln;
use clap::Args;
use igemu::error::Error;
use igemu::hdl;
use igemu::pipeline;
use igemu::stage::RunOptions;
use igemu::stage_id::StageId;
use std::process::ExitCode;

#[derive(Args)]
pub struct CostArgs {
    #[command(flatten)]
    pub s: SceneArgs,
    /// Synthesise each HDL model with yosys at the configured widths (cached in target/hdl-synth).
    #[arg(long)]
    pub synth: bool,
}

/// Runs `igemu cost`; returns the exit code.
pub fn run(a: CostArgs) -> Result<ExitCode, Error> {
    let scene = a.s.scene()?;
    let hw = a.s.hw()?;
    let r = pipeline::render(&scene, &hw, a.s.opts(RunOptions::FAST))?;
    outln!(
        "cost | hardware `{}` | scene `{}`{}",
        hw.name,
        scene.name,
        if a.synth {
            " | yosys synth (generic gates)"
        } else {
            ""
        }
    );
    outln!(
        "{:<11} {:>12} {:>10} {:>7} {:>6}  HDL model: yosys cells (flip-flops)",
        "stage",
        "storage_bits",
        "lut_bits",
        "adders",
        "mults"
    );
    let cache = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("target")
        .join("hdl-synth");
    for st in &r.report.stages {
        let c = &st.cost;
        let adders: u32 = c.adders.iter().map(|u| u.count).sum();
        let mults: u32 = c.multipliers.iter().map(|u| u.count).sum();
        let model = StageId::parse(&st.name).and_then(|id| Some((id, hdl::module_of(id)?)));
        let synth = match model {
            Some((id, m)) if a.synth => match hdl::vectors(id, &scene, &hw) {
                Ok(b) => match hdl::synth::synth(&b, &cache) {
                    Ok(s) => format!(
                        "{m}: {} cells ({} FF){}",
                        s.cells,
                        s.flip_flops(),
                        if s.cached { ", cached" } else { "" }
                    ),
                    Err(e) => format!("{m}: synthesis failed: {e}"),
                },
                Err(e) => format!("{m}: {e}"),
            },
            Some((_, m)) => format!("{m} (use --synth)"),
            None => "-".into(),
        };
        outln!(
            "{:<11} {:>12} {:>10} {:>7} {:>6}  {synth}",
            st.name,
            c.storage_bits,
            c.lut_bits,
            adders,
            mults
        );
    }
    Ok(ExitCode::SUCCESS)
}
