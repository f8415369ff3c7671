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

use crate::error::{Error, Result};
use crate::input::program::Direction;
use crate::input::scenario::Scenario;
use crate::motion::interpolation::{FeedLimit, InterpolationOptions, Interpolator};
use crate::program;
use crate::program::test_of;

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
    let direction = test_of(scenario)
        .directions()
        .first()
        .copied()
        .unwrap_or(Direction::Ccw);
    let run = program::scenario_run(scenario, direction, scenario.simulate.lead_deg)?;
    plan_feed(run.moves, scenario)
}

/// Plans `moves` (the scenario's program, as [`program::scenario_run`] gives it) for the
/// scenario's machine and reports where the feed was limited. The blocks are planned, not
/// sampled: a block's cruise speed and the limit that holds it are set when it is planned.
/// The first error, of a move or of its planning, ends it.
pub fn plan_feed(
    moves: impl Iterator<Item = Result<program::Move>>,
    scenario: &Scenario,
) -> Result<FeedReport> {
    let mut planner = FeedPlanner::new(scenario)?;
    for m in moves {
        planner.push(&m?);
        if planner.failed.is_some() {
            break;
        }
    }
    planner.finish()
}

/// The planning of [`plan_feed`], one move at a time, given by reference (no copy of a move):
/// also the moves of a file program planned beside another pass over them. The first error
/// stops the planning; it is [`FeedPlanner::finish`]'s result.
pub struct FeedPlanner {
    interpolator: Interpolator<std::iter::Empty<Result<program::Move>>>,
    feed_blocks: u64,
    failed: Option<Error>,
}

impl FeedPlanner {
    pub fn new(scenario: &Scenario) -> Result<FeedPlanner> {
        Ok(FeedPlanner {
            interpolator: Interpolator::new(
                std::iter::empty(),
                &scenario.machine,
                planner_options(scenario),
            )?,
            feed_blocks: 0,
            failed: None,
        })
    }

    /// Plans the next move of the program.
    pub fn push(&mut self, m: &program::Move) {
        if self.failed.is_none() {
            self.feed_blocks += u64::from(is_feed(m));
            self.failed = self.interpolator.plan_block(m).err();
        }
    }

    /// The report of the moves pushed, or the first block that could not be planned.
    pub fn finish(mut self) -> Result<FeedReport> {
        match self.failed {
            Some(e) => Err(e),
            None => Ok(report(
                self.interpolator.take_feed_limits(),
                self.feed_blocks,
            )),
        }
    }
}

/// G01, G02 and G03: the blocks an F word applies to.
fn is_feed(m: &program::Move) -> bool {
    matches!(
        m.motion,
        program::Motion::Linear | program::Motion::Arc { .. }
    )
}

/// The interpolator's options for `analyze`'s planning: the scenario's TCP, limits noted.
fn planner_options(scenario: &Scenario) -> InterpolationOptions {
    InterpolationOptions {
        force_tcp: scenario.simulate.tcp,
        program_path: scenario.path.clone(),
        record_feed_limits: true,
        ..InterpolationOptions::for_machine(&scenario.machine)
    }
}

/// The report of the limited `blocks` among `feed_blocks` feed blocks.
fn report(blocks: Vec<FeedLimit>, feed_blocks: u64) -> FeedReport {
    let mut limited_by_axis = BTreeMap::new();
    for b in &blocks {
        *limited_by_axis.entry(b.axis.to_string()).or_default() += 1;
    }
    FeedReport {
        feed_blocks,
        limited_by_axis,
        blocks,
    }
}
