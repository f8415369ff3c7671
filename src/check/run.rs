//! `mtsim check`: does the program fit the machine? Travel, velocity and acceleration of
//! every axis on every sample, and collisions and near misses in the scene, continuously.
//!
//! The program is sampled at the planner's timing (the look-ahead interpolator with its jerk
//! limits, [`crate::motion::interpolation`]): what the control will command. With `programmed`
//! it is sampled at the timing its words ask for ([`crate::motion::sampling`]), what it
//! demands of the machine; with `dynamics` the samples are the actual axis positions from the
//! interpolator and the servo models, so that overshoot past a limit is caught too.

use std::cell::RefCell;
use std::collections::{BTreeMap, VecDeque};
use std::rc::Rc;

use serde::{Deserialize, Deserializer, Serialize};

use crate::check::limits::{AxisUsage, LimitsMonitor, Violation, ViolationKind};
use crate::check::scene::snapshot::{CollisionViews, TipPath};
use crate::check::scene::{
    DepthTolerance, EngagementSummary, EventKind, Scene, SceneMonitor, ToolConfig,
};
use crate::error::Result;
use crate::input::scenario::Scenario;
use crate::kinematics::Kinematics;
use crate::measure::CircleFrame;
use crate::motion::work;
use crate::motion::FeedReduction;
use crate::pipeline::{self, RunOptions, Sample, Sink, Timing};
use crate::program::{self, test_of};
use crate::{Axis, AxisVec};

pub use crate::pipeline::SETTLE_S;

/// How to check.
#[derive(Clone, Copy, Debug, Default)]
pub struct CheckOptions {
    /// Check the actual axis positions of the servo simulation instead of the commanded ones.
    pub dynamics: bool,
    /// Sample the program at its programmed timing instead of the planner's (ignored with
    /// `dynamics`).
    pub programmed: bool,
    /// Near-miss clearance, mm; the scenario's (or the machine's) when `None`.
    pub near_miss_mm: Option<f64>,
    /// Keep the scene at the deepest sample of this many of the deepest collisions, and the
    /// tool tip's path, for a picture ([`CheckReport::views`]); 0: none (the default).
    pub collision_poses: usize,
}

/// What `check` found.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CheckReport {
    /// In the order they started.
    pub violations: Vec<Violation>,
    /// Per axis: the used range against the travel, with the margin, and peak velocity and
    /// acceleration against the limits.
    #[serde(deserialize_with = "usage_by_axis")]
    pub axes: BTreeMap<String, AxisUsage>,
    /// Samples checked (one per interpolation period).
    pub samples: u64,
    /// Machine time covered, s.
    pub sim_time_s: f64,
    /// Geometric queries made by the collision scene (null without a scene).
    pub scene_queries: Option<u64>,
    /// Why the collisions were checked against a stand-in: the machine file gives no
    /// `[scene]`, so mtsim's default geometry took its place (left out when the file gives
    /// one, or collisions are off).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub scene_stand_in: Option<String>,
    /// Cutter engagement in the workpiece, per cutting pair.
    pub engagement: Vec<EngagementSummary>,
    /// Smallest clearance between bodies that must not touch, mm, and the pair.
    pub min_clearance_mm: Option<f64>,
    pub min_clearance_bodies: Option<[String; 2]>,
    /// A collision's `worst` (its deepest penetration `W`, mm) is the depth at one of its
    /// samples, and no sample of it is deeper than `W + mm + relative · W` (`[scene]
    /// depth_tolerance_mm` and `depth_tolerance_relative`; null without a scene).
    #[serde(default)]
    pub collision_depth_tolerance: Option<DepthTolerance>,
    /// Whether the samples were the actual (servo) positions.
    pub dynamics: bool,
    /// How the samples were timed.
    #[serde(default)]
    pub timing: CheckTiming,
    /// Feed blocks the planner ran below their F word, per axis and limit (left out when
    /// there is none, and at programmed timing).
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub feed_reductions: Vec<FeedReduction>,
    /// The scene at the deepest collisions and the tool tip's path, for `check --html`
    /// (only with [`CheckOptions::collision_poses`] and a collision scene; not in JSON).
    #[serde(skip)]
    pub views: Option<CollisionViews>,
}

/// How `check` timed its samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CheckTiming {
    /// The planner's setpoints (look-ahead, jerk-limited): what the control commands.
    #[default]
    Planned,
    /// The timing the program's words ask for; a junction is a velocity step, so
    /// accelerations and jerks at junctions are not measured.
    Programmed,
    /// The servo models' actual positions on the planner's setpoints.
    Dynamics,
    /// The commanded positions of `simulate`'s own run (every direction, the lead arcs),
    /// from each run's first move's end, each run on its own clock
    /// ([`crate::check::of_run`]).
    Run,
}

impl CheckTiming {
    /// What the samples are, for a person.
    pub fn describe(self) -> &'static str {
        match self {
            CheckTiming::Planned => "commanded positions at the planner's timing",
            CheckTiming::Programmed => {
                "commanded positions at programmed timing (accelerations at junctions between blocks are not measured)"
            }
            CheckTiming::Dynamics => "actual (servo) positions",
            CheckTiming::Run => {
                "commanded positions of the simulated run itself (every direction, the lead arcs) at the planner's timing"
            }
        }
    }
}

impl CheckReport {
    pub fn is_clean(&self) -> bool {
        self.violations.is_empty()
    }
}

/// The axes' usage read from JSON, each with the axis its key names.
fn usage_by_axis<'de, D: Deserializer<'de>>(
    d: D,
) -> std::result::Result<BTreeMap<String, AxisUsage>, D::Error> {
    let mut axes = BTreeMap::<String, AxisUsage>::deserialize(d)?;
    for (name, usage) in &mut axes {
        usage.axis = Axis::deserialize(serde::de::value::StrDeserializer::<D::Error>::new(name))?;
    }
    Ok(axes)
}

/// The limits monitor and the collision scene as one sink: each sample to both, in that
/// order, with one call per sample.
pub(crate) struct Monitors<'a> {
    pub(crate) limits: LimitsMonitor<'a>,
    pub(crate) scene: Option<SceneSink>,
}

impl Monitors<'_> {
    /// Starts another run on its own clock ([`LimitsMonitor::restart`],
    /// [`SceneMonitor::restart`]); its block indices count from 0 again.
    pub(crate) fn restart(&mut self) {
        self.limits.restart();
        if let Some(scene) = self.scene.as_mut() {
            scene.monitor.restart();
            scene.changes_applied_at = u64::MAX;
        }
    }
}

impl Sink for Monitors<'_> {
    #[inline]
    fn push(&mut self, s: &Sample) -> Result<()> {
        self.limits.push(s);
        match self.scene.as_mut() {
            Some(scene) => scene.push(s),
            None => Ok(()),
        }
    }
}

/// Tool changes read from the move stream ahead of the samples: (block index, tool number).
pub(crate) type ToolChanges = Rc<RefCell<VecDeque<(u64, u32)>>>;

/// The collision scene as a sink: each sample's axis positions (θ computed where reported),
/// with the tool in the spindle changed when the samples reach the block that changed it.
pub(crate) struct SceneSink {
    monitor: SceneMonitor,
    changes: ToolChanges,
    /// Stack and tip offset below the Z point (mm) of each tool-table tool.
    stacks: BTreeMap<u32, (ToolConfig, f64)>,
    /// The scenario's `[tool]`: tool 0 and tools not in the table.
    reference: ToolConfig,
    active: u32,
    /// The tool tip's path, when a picture is asked for.
    path: Option<TipPath>,
    /// The block index whose tool changes were applied last (`u64::MAX`: none yet). Move
    /// `k` is read before any sample of block `k`, so no change at or before `k` can arrive
    /// once the samples of `k` have begun: the queue is looked at once per block.
    changes_applied_at: u64,
}

impl Sink for SceneSink {
    #[inline]
    fn push(&mut self, s: &Sample) -> Result<()> {
        if s.block_index != self.changes_applied_at {
            self.changes_applied_at = s.block_index;
            self.apply_tool_changes(s.block_index);
        }
        self.monitor.push_at(s.time_s, s.line, &s.actual);
        if let Some(path) = self.path.as_mut() {
            if path.wants_next() {
                path.push(self.monitor.tip_mm(&s.actual));
            }
        }
        Ok(())
    }
}

impl SceneSink {
    /// Puts in the spindle the tool of the last change noted at or before `block_index`.
    fn apply_tool_changes(&mut self, block_index: u64) {
        loop {
            let next = self.changes.borrow().front().copied();
            match next {
                Some((index, tool)) if index <= block_index => {
                    self.changes.borrow_mut().pop_front();
                    if tool != self.active {
                        self.active = tool;
                        match self.stacks.get(&tool) {
                            Some((stack, below)) => self.monitor.set_tool(stack, *below),
                            None => self.monitor.set_tool(&self.reference, 0.0),
                        }
                    }
                }
                _ => break,
            }
        }
    }
}

/// The scene stack of every tool of the scenario's tool table (see
/// [`ToolConfig::for_table_tool`]) with its tip offset below the Z point, mm.
fn tool_stacks(scenario: &Scenario) -> Result<BTreeMap<u32, (ToolConfig, f64)>> {
    let mut stacks = BTreeMap::new();
    for t in &scenario.reader.tools {
        let shape = scenario
            .tool_shapes
            .get(&t.number)
            .copied()
            .unwrap_or_default();
        let stack = scenario.tool.for_table_tool(
            &scenario.path,
            t.number,
            t.length_mm,
            t.diameter_mm,
            &shape,
        )?;
        stacks.insert(t.number, (stack, t.length_mm));
    }
    Ok(stacks)
}

/// `moves` unchanged, noting in `changes` the index of each move whose tool differs from
/// the one before (the first move's tool when it is not 0).
pub(crate) fn note_tool_changes<'a>(
    moves: program::Moves<'a>,
    changes: ToolChanges,
) -> program::Moves<'a> {
    let (mut index, mut active) = (0u64, 0u32);
    Box::new(moves.inspect(move |m| {
        if let Ok(m) = m {
            if m.tool != active {
                active = m.tool;
                changes.borrow_mut().push_back((index, m.tool));
            }
            index += 1;
        }
    }))
}

/// Checks a scenario's program against its machine. A cone or circle is checked as the
/// generator writes it: one revolution, counter-clockwise, with no lead.
pub fn check(scenario: &Scenario, options: &CheckOptions) -> Result<CheckReport> {
    check_with(scenario, options, SceneQueries::Bounded)
}

/// The stand-in note of [`CheckReport::scene_stand_in`], when collisions are checked on a
/// machine whose file gives no `[scene]`.
fn scene_stand_in(scenario: &Scenario) -> Option<String> {
    let machine = &scenario.machine;
    (scenario.check.collisions && !machine.scene_given).then(|| {
        format!(
            "collisions were checked against a stand-in: {} has no [scene], so mtsim's default \
             geometry (docs/scene.md: a table, on the named layouts a trunnion, a spindle) took the place of this \
             machine's; give its [scene] for a check of its own geometry",
            machine.path.display()
        )
    })
}

/// [`check`] with the scene queried for every pair at every sample, no motion bound
/// skipping any: the slow, unoptimised reference the bounded check is tested against.
pub fn check_reference(scenario: &Scenario, options: &CheckOptions) -> Result<CheckReport> {
    check_with(scenario, options, SceneQueries::Every)
}

/// When the collision scene is queried.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneQueries {
    /// Conservative advancement on lever-arm bounds (what [`check`] does).
    Bounded,
    /// The same, with the tighter relative-motion bound for tool/table pairs as well.
    BoundedRelative,
    /// Every pair at every sample.
    Every,
}

/// [`check`] with the scene queried as `queries` says.
pub fn check_with(
    scenario: &Scenario,
    options: &CheckOptions,
    queries: SceneQueries,
) -> Result<CheckReport> {
    check_observed(scenario, options, queries, &|_, _| {})
}

/// [`check_with`], telling `progress` now and then the machine time reached and the run's
/// least machine time (s; the up-front estimate, which the planner's ramps exceed).
pub fn check_observed(
    scenario: &Scenario,
    options: &CheckOptions,
    queries: SceneQueries,
    progress: &dyn Fn(f64, f64),
) -> Result<CheckReport> {
    let machine = &scenario.machine;
    let kin = machine.kinematics;
    let frame = theta_frame(scenario);
    let changes = ToolChanges::default();
    let theta_of = move |q: &AxisVec| frame.map(|f| f.theta_deg(&kin.forward(q).tip));
    let mut limits = LimitsMonitor::new(machine, &theta_of);
    let scene = scene_sink(
        scenario,
        options,
        queries,
        changes.clone(),
        Box::new(theta_of),
    )?;
    let (timing, check_timing) = if options.dynamics {
        let t = Timing::Planned {
            twins: false,
            settle: true,
        };
        (t, CheckTiming::Dynamics)
    } else if options.programmed {
        limits = limits.within_blocks();
        (Timing::Programmed, CheckTiming::Programmed)
    } else {
        (Timing::Setpoints, CheckTiming::Planned)
    };
    let (max_samples, least_s) = work::check_up_front_timed(scenario, 0.0)?;
    let mut monitors = Monitors { limits, scene };
    // Every direction the scenario runs (a generated test's planned ones; a file once), one
    // after the other, each on its own clock from where the one before ended.
    let directions = test_of(scenario).directions();
    let least_s = least_s * directions.len() as f64;
    let progress = |t: f64| progress(t, least_s);
    let mut stats = pipeline::RunStats {
        samples: 0,
        end_time_s: 0.0,
        feed_reductions: Vec::new(),
    };
    for (k, &direction) in directions.iter().enumerate() {
        let run = program::scenario_run(scenario, direction, 0.0)?;
        // The position before the program is unknown (the reader assumes zero), so the path
        // of the first move, which brings the machine to the program's start, is not
        // checked: sampling starts at its end, which must lie within the machine's reach
        // like every other point. A reader error, wherever it comes, passes through and ends
        // the check.
        let mut moves = from_first_end(run.moves, kin);
        if scenario.check.collisions {
            moves = note_tool_changes(moves, changes.clone());
        }
        if k > 0 {
            monitors.restart();
        }
        let run_options = RunOptions {
            timing,
            force_tcp: scenario.simulate.tcp,
            start_time_s: stats.end_time_s,
            program_path: scenario.path.clone(),
            max_samples,
        };
        let run_stats = pipeline::run(
            moves,
            machine,
            &run_options,
            &mut [&mut monitors],
            &progress,
        )?;
        stats.samples += run_stats.samples;
        stats.end_time_s = run_stats.end_time_s;
        stats.feed_reductions.extend(run_stats.feed_reductions);
    }
    let mut report = report_of(scenario, monitors, &stats);
    report.dynamics = options.dynamics;
    report.timing = check_timing;
    Ok(report)
}

/// The report of what `monitors` saw over a run (or runs) of `stats`; timed as planned,
/// not dynamics (the caller says otherwise).
pub(crate) fn report_of(
    scenario: &Scenario,
    monitors: Monitors<'_>,
    stats: &pipeline::RunStats,
) -> CheckReport {
    let (samples, last_time) = (stats.samples, stats.end_time_s);
    let feed_reductions = stats.feed_reductions.clone();
    let Monitors { limits, scene } = monitors;
    let (scene, path) = match scene {
        Some(s) => (Some(s.monitor), s.path),
        None => (None, None),
    };
    let mut views = None;
    let (usage, mut violations) = limits.finish();
    if violations.iter().any(|v| v.kind == ViolationKind::Travel) {
        if let Some(note) = crate::check::units::other_unit_note(scenario, &usage) {
            for v in violations
                .iter_mut()
                .filter(|v| v.kind == ViolationKind::Travel)
            {
                v.other_unit = Some(note.clone());
            }
        }
    }
    let mut scene_queries = None;
    let mut engagement = Vec::new();
    let (mut min_clearance_mm, mut min_clearance_bodies) = (None, None);
    let mut collision_depth_tolerance = None;
    if let Some(scene) = scene {
        let report = scene.finish();
        scene_queries = Some(report.queries);
        collision_depth_tolerance = Some(report.depth_tolerance);
        engagement = report.engagement;
        min_clearance_mm = report
            .min_clearance_mm
            .is_finite()
            .then_some(report.min_clearance_mm);
        min_clearance_bodies = report.min_clearance_bodies;
        if let Some(path) = path {
            let (tip_path_mm, path_stride) = path.finish();
            views = Some(CollisionViews {
                collisions: report.collision_poses,
                tip_path_mm,
                path_stride,
            });
        }
        for e in report.events {
            let (kind, limit) = match e.kind {
                EventKind::Collision => (ViolationKind::Collision, None),
                EventKind::NearMiss => (ViolationKind::NearMiss, Some(report.near_miss_mm)),
            };
            violations.push(Violation {
                kind,
                axis: None,
                bodies: Some(e.bodies),
                theta_start_deg: e.theta_start_deg,
                theta_end_deg: e.theta_end_deg,
                time_start_s: e.time_start_s,
                time_end_s: e.time_end_s,
                line: e.line,
                worst: e.worst_mm,
                limit,
                other_unit: None,
            });
        }
        violations.sort_by(|a, b| a.time_start_s.total_cmp(&b.time_start_s));
    }
    CheckReport {
        violations,
        axes: usage.into_iter().map(|u| (u.axis.to_string(), u)).collect(),
        samples,
        sim_time_s: last_time,
        scene_queries,
        scene_stand_in: scene_stand_in(scenario),
        engagement,
        min_clearance_mm,
        min_clearance_bodies,
        collision_depth_tolerance,
        dynamics: false,
        timing: CheckTiming::Planned,
        feed_reductions,
        views,
    }
}

/// The collision scene as a sink for `check_observed` (None when collisions are off), its
/// tool changes read from `changes`, θ from `theta_of`.
pub(crate) fn scene_sink(
    scenario: &Scenario,
    options: &CheckOptions,
    queries: SceneQueries,
    changes: ToolChanges,
    theta_of: crate::check::scene::monitor::ThetaFn,
) -> Result<Option<SceneSink>> {
    if !scenario.check.collisions {
        return Ok(None);
    }
    let machine = &scenario.machine;
    let near_miss = options.near_miss_mm.unwrap_or(scenario.check.near_miss_mm);
    let mut monitor = SceneMonitor::new(
        Scene::new(machine, &scenario.tool, &scenario.workpiece, near_miss)?,
        machine,
    )
    .with_theta(theta_of)
    .with_collision_poses(options.collision_poses);
    match queries {
        SceneQueries::Bounded => {}
        SceneQueries::BoundedRelative => monitor = monitor.with_relative_bounds(true),
        SceneQueries::Every => monitor = monitor.exhaustive(),
    }
    Ok(Some(SceneSink {
        monitor,
        changes,
        stacks: tool_stacks(scenario)?,
        reference: scenario.tool.clone(),
        active: 0,
        path: (options.collision_poses > 0).then(TipPath::default),
        changes_applied_at: u64::MAX,
    }))
}

/// `moves` with the first move replaced by a standstill at its end (a dwell of 0 s at the
/// machine axis positions of its end point), so that the program's start point is sampled
/// and checked but not the unknown path to it. Errors pass through unchanged.
fn from_first_end<'a>(moves: program::Moves<'a>, kin: Kinematics) -> program::Moves<'a> {
    let mut first = true;
    Box::new(moves.map(move |m| {
        if !std::mem::take(&mut first) {
            return m;
        }
        m.map(|m| {
            let mut end = m.end;
            if m.tcp {
                // X Y Z are the tool tip in the table frame.
                end = kin.tcp_axes(&m.end, m.tool_length_mm);
            }
            program::Move {
                motion: program::Motion::Dwell { seconds: 0.0 },
                start: end,
                end,
                tcp: false,
                ..m
            }
        })
    }))
}

/// The frame that gives θ: the measured circle of a cone or circle test, if any.
fn theta_frame(scenario: &Scenario) -> Option<CircleFrame> {
    test_of(scenario).theta_frame(&scenario.machine.kinematics)
}
