//! `mtsim study`: the servo simulation over any key of a scenario and its machine, whole or
//! one shard.

use std::path::{Path, PathBuf};

use super::{note, print_stdout, progress_bar};
use crate::error::Result;
use crate::report::test_info::scenario_hash;
use crate::report::RunDir;
use crate::study::param::evaluate::Row;
use crate::study::param::{write_outputs, Study, StudyHeader, StudySummary};
use crate::study::shard::{Shard, ShardFile};

#[derive(Debug, clap::Args)]
pub struct StudyArgs {
    /// Study file (TOML): the base scenario and the keys it varies (docs/studies.md).
    pub study: PathBuf,
    /// Output folder: rows.csv, rows.parquet, study.json, the plots and study.html (or the
    /// shard file with --shard).
    #[arg(short, long)]
    pub output: PathBuf,
    /// The G limit, um: the share of points with G below it, with its 95 % interval
    /// (overrides the study file's `g_limit_um`).
    #[arg(long, value_name = "UM")]
    pub g_limit_um: Option<f64>,
    /// Points of a random study, in place of the study file's `samples` (e.g. a trial run).
    #[arg(long, value_name = "N")]
    pub samples: Option<usize>,
    /// Run only shard K of N (1 <= K <= N) of the points and write
    /// <output>/study.shard-K-of-N.json; join the N shards with `mtsim merge`.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<Shard>,
    /// Print study.json to standard output.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &StudyArgs) -> Result<i32> {
    if let Some(g) = args.g_limit_um {
        if !(g.is_finite() && g > 0.0) {
            return Err(crate::error::Error::usage(format!(
                "--g-limit-um {g}: expected a G limit > 0 um"
            )));
        }
    }
    let study = Study::load(&args.study, args.g_limit_um, args.samples)?;
    let range = args.shard.unwrap_or(Shard::WHOLE).range(study.points.len());
    let run_dir = match args.shard {
        None => Some(RunDir::begin(&args.output)?),
        Some(_) => None,
    };
    let bar = progress_bar(range.len() as u64, "study");
    let rows = study.run(range, &|| bar.inc(1));
    bar.finish_and_clear();
    let Some(run_dir) = run_dir else {
        let shard = args
            .shard
            .expect("a study without a staging folder is a shard");
        let base = crate::input::scenario::Scenario::load(&study.spec.scenario)?;
        let file = ShardFile::new(
            "study",
            shard,
            study.points.len(),
            scenario_hash(&base),
            study.header.clone(),
            rows,
        );
        let path = file.write(&args.output, "study")?;
        note(&format!(
            "wrote {}: join the shards with `mtsim merge`",
            path.display()
        ));
        return Ok(0);
    };
    emit(&study.header, &rows, args.json, run_dir, &args.output)
}

/// Writes the study's files into `run_dir`, puts it in place as `output` and prints the
/// summary: the same for a whole run and for merged shards.
pub(crate) fn emit(
    header: &StudyHeader,
    rows: &[Row],
    as_json: bool,
    run_dir: RunDir,
    output: &Path,
) -> Result<i32> {
    let summary = write_outputs(run_dir.path(), header, rows)?;
    run_dir.commit()?;
    note(&format!(
        "wrote {}: rows.csv, rows.parquet, study.json, study.html",
        output.display()
    ));
    if as_json {
        let json = serde_json::to_string_pretty(&summary).expect("plain data serializes");
        print_stdout(&format!("{json}\n"));
    } else {
        print_stdout(&describe(&summary));
    }
    // As `batch`: a point that failed to run makes the exit code 1, its row says why.
    Ok(if summary.failed > 0 { 1 } else { 0 })
}

fn describe(s: &StudySummary) -> String {
    let mut out = format!(
        "{} study of {} points: {} ran ({} clean), {} failed\n",
        s.kind, s.points, s.ok, s.clean, s.failed
    );
    if let (Some(lo), Some(hi)) = (s.g_min_um, s.g_max_um) {
        out.push_str(&format!("G from {lo:.3} to {hi:.3} um\n"));
    }
    if let (Some(limit), Some(share)) = (s.g_limit_um, &s.g_below_limit) {
        out.push_str(&format!(
            "G < {limit} um: {} of {} points, {:.2} % (95 % CI {:.2} to {:.2} %)\n",
            share.hits,
            share.points,
            100.0 * share.share,
            100.0 * share.low,
            100.0 * share.high
        ));
    }
    for k in &s.sensitivity {
        out.push_str(&format!(
            "rank correlation of G with {}: {:+.3}\n",
            k.key, k.spearman_g
        ));
    }
    out
}
