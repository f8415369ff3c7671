//! `mtsim merge`: the shard files of one study joined into what the unsharded run writes.

use std::path::PathBuf;

use super::batch::BatchHeader;
use super::sweep::{emit_placement, emit_sweep, PlacementHeader, SweepHeader};
use crate::error::{Error, Result};
use crate::study::batch::BatchRow;
use crate::study::placement::{PlacementCell, PlacementMap};
use crate::study::shard::{join, study_of};
use crate::study::sweep::{SweepPart, SweepResult};

#[derive(Debug, clap::Args)]
pub struct MergeArgs {
    /// The N shard files (<name>.shard-K-of-N.json) of one run, in any order.
    #[arg(required = true)]
    pub shards: Vec<PathBuf>,
    /// Output folder for the joined files (as the unsharded run's -o).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print one JSON object, as the unsharded run with --json.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &MergeArgs) -> Result<i32> {
    let study = study_of(&args.shards[0])?;
    let out = Some(args.output.as_path());
    match study.as_str() {
        "sweep" => {
            let (header, _, parts) = join::<SweepHeader, SweepPart>(&args.shards)?;
            let result = SweepResult::join(header.param.name(), parts);
            emit_sweep(&header, &result, args.json, out)
        }
        "placement" => {
            let (header, _, parts) = join::<PlacementHeader, Vec<PlacementCell>>(&args.shards)?;
            let cells: Vec<PlacementCell> = parts.into_iter().flatten().collect();
            let map = PlacementMap {
                params: header.params.map(|p| p.name().to_string()),
                cells,
                scenario_at: header.scenario_at,
                table_radius_mm: header.table_radius_mm,
            };
            emit_placement(&header, &map, args.json, out)
        }
        "batch" => {
            let (_, _, parts) = join::<BatchHeader, Vec<BatchRow>>(&args.shards)?;
            let rows: Vec<BatchRow> = parts.into_iter().flatten().collect();
            let run_dir = crate::report::RunDir::begin(&args.output)?.reads(&args.shards);
            super::batch::emit(&rows, args.json, run_dir, &args.output)
        }
        "study" => {
            let (header, _, parts) =
                join::<crate::study::param::StudyHeader, Vec<crate::study::param::evaluate::Row>>(
                    &args.shards,
                )?;
            let rows: Vec<_> = parts.into_iter().flatten().collect();
            let run_dir = crate::report::RunDir::begin(&args.output)?.reads(&args.shards);
            super::study::emit(&header, &rows, args.json, run_dir, &args.output)
        }
        other => Err(Error::usage(format!(
            "{}: unknown study {other:?} (this mtsim merges sweep, placement, batch and study shards)",
            args.shards[0].display()
        ))),
    }
}
