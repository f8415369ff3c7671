//! `mtsim batch`: many scenarios in parallel, one row each, whole or one shard.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::{print_stdout, progress_bar};
use crate::error::{Error, Result};
use crate::report::test_info::{files_hash, files_hash_of_paths, scenario_hash};
use crate::report::{write_atomic, RunDir};
use crate::study::batch::{run_scenario, to_csv, to_parquet, BatchRow};
use crate::study::shard::{Shard, ShardFile};

#[derive(Debug, clap::Args)]
pub struct BatchArgs {
    /// Scenario files (TOML).
    pub scenarios: Vec<PathBuf>,
    /// A file listing scenario files, one a line (relative to the list's folder; blank
    /// lines and lines starting with # are skipped); they come before the ones given as arguments.
    #[arg(long, value_name = "FILE")]
    pub list: Option<PathBuf>,
    /// Output folder: batch.csv and batch.parquet (or the shard file with --shard).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Simulate each scenario too (ball-bar G, F, H), writing its files to
    /// <output>/runs/<n>-<name>/.
    #[arg(long)]
    pub simulate: bool,
    /// Run only shard K of N (1 <= K <= N) of the scenarios and write
    /// <output>/batch.shard-K-of-N.json; join the N shards with `mtsim merge`.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<Shard>,
    /// Print the rows as one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// What identifies a batch: its work list and whether it simulates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct BatchHeader {
    pub scenarios: Vec<String>,
    pub simulate: bool,
}

pub fn run(args: &BatchArgs) -> Result<i32> {
    let mut work: Vec<(String, PathBuf)> = Vec::new();
    if let Some(list) = &args.list {
        let text = std::fs::read_to_string(list)
            .map_err(|e| Error::usage(format!("cannot read the list {}: {e}", list.display())))?;
        let base = list.parent().unwrap_or(Path::new(""));
        for line in text.lines().map(str::trim) {
            if !line.is_empty() && !line.starts_with('#') {
                work.push((line.to_string(), base.join(line)));
            }
        }
    }
    for s in &args.scenarios {
        work.push((s.display().to_string(), s.clone()));
    }
    if work.is_empty() {
        return Err(Error::usage(
            "mtsim batch needs scenario files: give them as arguments or with --list FILE",
        ));
    }
    let header = BatchHeader {
        scenarios: work.iter().map(|(s, _)| s.clone()).collect(),
        simulate: args.simulate,
    };
    let range = args.shard.unwrap_or(Shard::WHOLE).range(work.len());
    // A whole batch is one unit (with its runs/); a shard writes one file into a folder that
    // the other shards share.
    let run_dir = match args.shard {
        None => Some(RunDir::begin(&args.output)?),
        Some(_) => None,
    };
    let output = run_dir.as_ref().map_or(args.output.as_path(), RunDir::path);
    let bar = progress_bar(range.len() as u64, "batch");
    let rows: Vec<BatchRow> = range
        .into_par_iter()
        .map(|i| {
            let (listed, path) = &work[i];
            let dir = args.simulate.then(|| {
                let stem = path.file_stem().map(|s| s.to_string_lossy().to_string());
                output
                    .join("runs")
                    .join(format!("{:04}-{}", i + 1, stem.unwrap_or_default()))
            });
            let row = run_scenario(listed, path, dir.as_deref());
            bar.inc(1);
            row
        })
        .collect();
    bar.finish_and_clear();
    let Some(run_dir) = run_dir else {
        let shard = args
            .shard
            .expect("a batch without a staging folder is a shard");
        let file = ShardFile::new("batch", shard, work.len(), batch_hash(&work), header, rows);
        let path = file.write(output, "batch")?;
        super::note(&format!(
            "wrote {}: join the shards with `mtsim merge`",
            path.display()
        ));
        return Ok(0);
    };
    emit(&rows, args.json, run_dir, &args.output)
}

/// The scenario hash of a batch: [`files_hash`] of its scenarios' hashes (the raw file's
/// for a scenario that does not load), so that the shards of one batch agree on all of it.
fn batch_hash(work: &[(String, PathBuf)]) -> String {
    let hashes: Vec<String> = work
        .iter()
        .map(
            |(_, path)| match crate::input::scenario::Scenario::load(path) {
                Ok(scenario) => scenario_hash(&scenario),
                Err(_) => format!("{:016x}", files_hash_of_paths(&[path.as_path()])),
            },
        )
        .collect();
    let chunks: Vec<&[u8]> = hashes.iter().map(|h| h.as_bytes()).collect();
    format!("{:016x}", files_hash(&chunks))
}

/// Writes batch.csv and batch.parquet and prints the rows: the same for a whole run and for
/// merged shards, into `run_dir`, then put in place as `output`. Exit code 1 when any
/// scenario failed or has violations.
pub(crate) fn emit(
    rows: &[BatchRow],
    as_json: bool,
    run_dir: RunDir,
    output: &Path,
) -> Result<i32> {
    let (csv, parquet) = ("batch.csv", "batch.parquet");
    write_atomic(&run_dir.path().join(csv), &to_csv(rows)?)?;
    write_atomic(&run_dir.path().join(parquet), &to_parquet(rows)?)?;
    run_dir.commit()?;
    super::note(&format!(
        "wrote {} and {}",
        output.join(csv).display(),
        output.join(parquet).display()
    ));
    if as_json {
        let json = serde_json::json!({ "rows": rows });
        print_stdout(&format!("{json}\n"));
    } else {
        let mut out = format!(
            "{:<40} {:>10} {:>12} {:>14}  {}\n",
            "scenario", "violations", "margin", "clearance mm", "G um"
        );
        let f = |v: Option<f64>, p: usize| v.map_or("-".to_string(), |v| format!("{v:.p$}"));
        for r in rows {
            match &r.error {
                Some(e) => out.push_str(&format!("{:<40} error: {e}\n", r.scenario)),
                None => out.push_str(&format!(
                    "{:<40} {:>10} {:>12} {:>14}  {}\n",
                    r.scenario,
                    r.violations.unwrap_or(0),
                    match (&r.min_margin, &r.min_margin_axis) {
                        (Some(m), Some(a)) => format!("{m:.3} {a}"),
                        _ => "-".to_string(),
                    },
                    f(r.min_clearance_mm, 3),
                    f(r.circular_deviation_um, 2)
                )),
            }
        }
        let clean = rows.iter().filter(|r| r.is_clean()).count();
        out.push_str(&format!("{clean} of {} scenarios run clean\n", rows.len()));
        print_stdout(&out);
    }
    Ok(if rows.iter().all(BatchRow::is_clean) {
        0
    } else {
        1
    })
}
