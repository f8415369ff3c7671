//! The feed held to the machine: which blocks of a scenario's program the interpolator plans
//! below their F word, and which axis limit holds them there (for `mtsim analyze`).
//!
//! The planner caps each block's cruise speed so that no axis exceeds its velocity limit,
//! and on curved paths its acceleration and jerk limits too (`motion::interpolation`, "Limits
//! along the path"). This plans the program with the same interpolator as `simulate`
//! (first direction, the scenario's TCP and lead-in) without sampling it, and collects what
//! it noted. Memory grows with the number of limited blocks only.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::error::Result;
use crate::input::program::Direction;
use crate::input::scenario::{Program, Scenario};
use crate::motion::interpolation::{FeedLimit, InterpolationOptions, Interpolator};
use crate::program;

/// The blocks whose feed the machine holds below the programmed one.
#[derive(Clone, Debug, Default, Serialize)]
pub struct FeedReport {
    /// Feed blocks (G01, G02, G03) planned.
    pub feed_blocks: u64,
    /// How many of them were limited, per axis (`"C"` → 12).
    pub limited_by_axis: BTreeMap<String, usize>,
    /// Every limited block, in program order.
    pub blocks: Vec<FeedLimit>,
}

/// Plans the scenario's program and reports where the feed was limited.
pub fn feed_limits(scenario: &Scenario) -> Result<FeedReport> {
    let direction = match &scenario.program {
        Program::Cone { directions, .. } | Program::Circle { directions, .. } => {
            directions.first().copied().unwrap_or(Direction::Ccw)
        }
        Program::File { .. } => Direction::Ccw,
    };
    let run = program::scenario_run(scenario, direction, scenario.simulate.lead_deg)?;
    plan_feed(run.moves, scenario)
}

/// Plans `moves` (the scenario's program, as [`program::scenario_run`] gives it) for the
/// scenario's machine and reports where the feed was limited. The blocks are planned, not
/// sampled: a block's cruise speed and the limit that holds it are set when it is planned.
pub fn plan_feed(
    moves: impl Iterator<Item = Result<program::Move>>,
    scenario: &Scenario,
) -> Result<FeedReport> {
    let mut feed_blocks = 0u64;
    let moves = moves.inspect(|m| {
        if let Ok(m) = m {
            if matches!(
                m.motion,
                program::Motion::Linear | program::Motion::Arc { .. }
            ) {
                feed_blocks += 1;
            }
        }
    });
    let options = InterpolationOptions {
        force_tcp: scenario.simulate.tcp,
        program_path: scenario.path.clone(),
        record_feed_limits: true,
        ..InterpolationOptions::default()
    };
    let mut interpolator = Interpolator::new(moves, &scenario.machine, options)?;
    interpolator.plan_to_end()?;
    let mut report = FeedReport {
        blocks: interpolator.take_feed_limits(),
        ..FeedReport::default()
    };
    drop(interpolator);
    for b in &report.blocks {
        *report
            .limited_by_axis
            .entry(b.axis.to_string())
            .or_default() += 1;
    }
    report.feed_blocks = feed_blocks;
    Ok(report)
}
