//! `igemu sequence merge`: the part files of a sharded sequence run (one per task of a Slurm
//! array or a Kubernetes indexed Job, `igemu sequence --shard K/N --part FILE`) checked and
//! joined into the report of the whole run (docs/sequence.md); and [`SequenceCmd`], the
//! `sequence` command with that subcommand.

use super::sequence::{SequenceArgs, print};
use crate::guard::Inputs;
use crate::out::outln;
use clap::Args;
use igemu::error::Error;
use igemu::output::write_file;
use igemu::sequence::merge;
use std::io::Write;
use std::process::ExitCode;

/// `igemu sequence SCENE ...` or `igemu sequence merge PART.json...`.
pub type SequenceCmd = crate::with_merge::WithMerge<SequenceArgs, SequenceMergeArgs>;

#[derive(Args)]
#[command(
    about = "Merge the part files of a sharded sequence run: check that they come from one run and that their frames tile it (else name the missing or overlapping frames, exit 2), join the frames in order and compute the summary and the temporal figures of the whole run"
)]
pub struct SequenceMergeArgs {
    /// The part files (each task's --part), in any order.
    #[arg(required = true, value_name = "PART.json")]
    pub parts: Vec<String>,
    /// Write the merged report as JSON to this file.
    #[arg(long, value_name = "FILE.json")]
    pub out: Option<String>,
    /// Write the HTML report of the whole run: the plots and the per-frame table (no animation: the parts carry no images; each shard's own --apng or -o has its frames).
    #[arg(long, value_name = "FILE.html")]
    pub html: Option<String>,
    /// Print the merged report as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `igemu sequence` or `igemu sequence merge`.
pub fn run(c: SequenceCmd) -> Result<ExitCode, Error> {
    match c {
        SequenceCmd::Run(a) => super::sequence::run(a),
        SequenceCmd::Merge(a) => run_merge(a),
    }
}

fn run_merge(a: SequenceMergeArgs) -> Result<ExitCode, Error> {
    // Everything is checked before an output is touched.
    let mut inputs = Inputs::default();
    for p in &a.parts {
        inputs.add("a part file", Some(p));
    }
    inputs.check_outputs(&[("--out", a.out.as_deref()), ("--html", a.html.as_deref())])?;
    let parts = a
        .parts
        .iter()
        .map(|p| merge::read(p).map(|part| (p.clone(), part)))
        .collect::<Result<Vec<_>, _>>()?;
    let n = parts.len();
    let r = merge::merge(parts)?;
    let json = serde_json::to_string_pretty(&r).expect("serialisable");
    if let Some(p) = &a.out {
        write_file(p, format!("{json}\n"))?;
    }
    if let Some(p) = &a.html {
        write_file(p, igemu::html::sequence_page(&r, None, p)?)?;
    }
    let _ = writeln!(
        std::io::stderr(),
        "igemu sequence merge: {} frames ({}..{}) from {n} parts{}",
        r.summary.frames,
        r.first,
        r.first + r.summary.frames,
        a.out.as_ref().map_or(String::new(), |p| format!(" -> {p}"))
    );
    if a.json {
        outln!("{json}");
    } else {
        print(&r)?;
    }
    Ok(ExitCode::SUCCESS)
}
