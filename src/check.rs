//! `mtsim check`: does the program fit the machine? Travel, velocity and acceleration of
//! every axis on every sample, and collisions and near misses in the scene, continuously.
//!
//! The program is sampled at its programmed timing ([`crate::sampling`]), which is what it
//! demands of the machine; with `dynamics` the samples are instead the actual axis positions
//! from the interpolator and the servo models, so that overshoot past a limit is caught too.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::axis::AxisVec;
use crate::ballbar::CircleFrame;
use crate::circle;
use crate::cone::{self, ConePath, NcOptions};
use crate::error::Result;
use crate::gcode::{self, Block};
use crate::interpolation::{InterpolationOptions, Interpolator, Setpoint};
use crate::limits::{AxisUsage, LimitsMonitor, Violation, ViolationKind};
use crate::sampling::NominalSampler;
use crate::scenario::{Program, Scenario};
use crate::scene::{EngagementSummary, EventKind, Scene, SceneMonitor, WorkpieceKind};
use crate::simulation::machine_servos;

/// Longest time the drives are given to settle after the last setpoint, s.
pub const SETTLE_S: f64 = 2.0;

/// How to check.
#[derive(Clone, Copy, Debug, Default)]
pub struct CheckOptions {
    /// Check the actual axis positions of the servo simulation instead of the commanded ones.
    pub dynamics: bool,
    /// Near-miss clearance, mm; the scenario's (or the machine's) when `None`.
    pub near_miss_mm: Option<f64>,
}

/// What `check` found.
#[derive(Clone, Debug, Serialize)]
pub struct CheckReport {
    /// In the order they started.
    pub violations: Vec<Violation>,
    /// Per axis: the used range against the travel, with the margin, and peak velocity and
    /// acceleration against the limits.
    pub axes: BTreeMap<String, AxisUsage>,
    /// Samples checked (one per interpolation period).
    pub samples: u64,
    /// Machine time covered, s.
    pub sim_time_s: f64,
    /// Geometric queries made by the collision scene (null without a scene).
    pub scene_queries: Option<u64>,
    /// Cutter engagement in the workpiece, per cutting pair.
    pub engagement: Vec<EngagementSummary>,
    /// Smallest clearance between bodies that must not touch, mm, and the pair.
    pub min_clearance_mm: Option<f64>,
    pub min_clearance_bodies: Option<[String; 2]>,
    /// Whether the samples were the actual (servo) positions.
    pub dynamics: bool,
}

impl CheckReport {
    pub fn is_clean(&self) -> bool {
        self.violations.is_empty()
    }
}

/// Checks a scenario's program against its machine.
pub fn check(scenario: &Scenario, options: &CheckOptions) -> Result<CheckReport> {
    let machine = &scenario.machine;
    let kin = machine.kinematics;
    // The position before the program is unknown (the reader assumes zero), so the first
    // block, which brings the machine to the program's start, is not checked: sampling
    // starts at its end.
    let (blocks, frame) = program_blocks(scenario)?;
    let blocks = blocks.skip(1);
    let theta_of = move |q: &AxisVec| frame.map(|f| f.theta_deg(&kin.forward(q).tip));
    let mut limits = LimitsMonitor::new(machine, &theta_of);
    let mut scene = match scenario.workpiece.kind {
        WorkpieceKind::None if !scenario.check.collisions => None,
        _ if !scenario.check.collisions => None,
        _ => {
            let near_miss = options.near_miss_mm.unwrap_or(
                scenario
                    .check
                    .near_miss_mm
                    .unwrap_or(machine.scene.near_miss_mm),
            );
            Some(SceneMonitor::new(
                Scene::new(machine, &scenario.tool, &scenario.workpiece, near_miss)?,
                machine,
            ))
        }
    };
    let mut samples = 0u64;
    let mut last_time = 0.0;
    let mut visit = |s: &Setpoint| {
        limits.push(s);
        if let Some(scene) = scene.as_mut() {
            let theta = theta_of(&s.q);
            scene.push(s.time_s, theta, s.line, &s.q);
        }
        samples += 1;
        last_time = s.time_s;
    };
    if options.dynamics {
        let options = InterpolationOptions {
            force_tcp: scenario.simulate.tcp,
            program_path: scenario.path.clone(),
            ..Default::default()
        };
        let mut setpoints = Interpolator::new(blocks, machine, options)?.peekable();
        if let Some(first) = setpoints.peek().and_then(|s| s.as_ref().ok()).map(|s| s.q) {
            let axes = machine.axes();
            let mut servos = machine_servos(machine, &first, false)?;
            let mut last = None;
            for sp in setpoints {
                let mut sp = sp?;
                last = Some(sp);
                for (servo, &a) in servos.iter_mut().zip(axes) {
                    sp.q[a] = servo.step(sp.q[a], sp.time_s)?.actual;
                }
                visit(&sp);
            }
            // The setpoints end at rest, the axes not yet: hold the last setpoint until every
            // axis has settled (following error below 0.1 um or 0.1 mdeg and at rest), for at
            // most SETTLE_S, so that an overshoot at the end is checked too.
            if let Some(end) = last {
                let period = machine.interpolation_period_s;
                for k in 1..=(SETTLE_S / period).round() as u64 {
                    let mut sp = Setpoint {
                        time_s: end.time_s + k as f64 * period,
                        ..end
                    };
                    let mut settled = true;
                    for (servo, &a) in servos.iter_mut().zip(axes) {
                        let state = servo.step(end.q[a], sp.time_s)?;
                        sp.q[a] = state.actual;
                        settled &=
                            state.following_error.abs() < 1e-4 && state.velocity.abs() < 1e-3;
                    }
                    visit(&sp);
                    if settled {
                        break;
                    }
                }
            }
        }
    } else {
        for s in NominalSampler::new(blocks, machine, machine.interpolation_period_s) {
            visit(&s?);
        }
    }
    let (usage, mut violations) = limits.finish();
    let mut scene_queries = None;
    let mut engagement = Vec::new();
    let (mut min_clearance_mm, mut min_clearance_bodies) = (None, None);
    if let Some(scene) = scene {
        let report = scene.finish();
        scene_queries = Some(report.queries);
        engagement = report.engagement;
        min_clearance_mm = report
            .min_clearance_mm
            .is_finite()
            .then_some(report.min_clearance_mm);
        min_clearance_bodies = report.min_clearance_bodies;
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
            });
        }
        violations.sort_by(|a, b| a.time_start_s.total_cmp(&b.time_start_s));
    }
    Ok(CheckReport {
        violations,
        axes: usage.into_iter().map(|u| (u.axis.to_string(), u)).collect(),
        samples,
        sim_time_s: last_time,
        scene_queries,
        engagement,
        min_clearance_mm,
        min_clearance_bodies,
        dynamics: options.dynamics,
    })
}

/// The program's blocks and the frame that gives θ (a cone or circle), if any. A cone is
/// checked as the post-processor writes it: one revolution, counter-clockwise.
fn program_blocks(
    scenario: &Scenario,
) -> Result<(Box<dyn Iterator<Item = Result<Block>>>, Option<CircleFrame>)> {
    let machine = &scenario.machine;
    Ok(match &scenario.program {
        Program::Cone { cone, nc, .. } => {
            let path = ConePath::new(*cone, machine);
            let (text, _) = cone::write_program(
                &path,
                &machine.name,
                &NcOptions {
                    lead_deg: 0.0,
                    clockwise: false,
                    ..*nc
                },
            );
            (
                Box::new(
                    gcode::read_str(&scenario.path, &text, AxisVec::ZERO)
                        .collect::<Vec<_>>()
                        .into_iter(),
                ),
                Some(cone.circle_frame()),
            )
        }
        Program::Circle { circle, .. } => {
            let (text, _) = circle::write_program(circle, false, 0.0);
            let center = nalgebra::Vector3::from(circle.center_mm) - machine.kinematics.pivot_mm;
            (
                Box::new(
                    gcode::read_str(&scenario.path, &text, AxisVec::ZERO)
                        .collect::<Vec<_>>()
                        .into_iter(),
                ),
                Some(CircleFrame::planar(center.into(), circle.plane)),
            )
        }
        Program::File { path, cone } => (
            Box::new(gcode::read_file(path, AxisVec::ZERO)?),
            cone.map(|c| c.circle_frame()),
        ),
    })
}
