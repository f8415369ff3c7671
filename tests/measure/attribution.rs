//! The attribution scorecard: faults injected on one axis of four cone tests, with realistic
//! friction on every axis, must leave marks that carry that axis at every reversal where the
//! bar can see it, and no mark may be left without an axis.
//!
//! 4 cones (15/10 and 45/30 centred on C, 15/10 offset half-way between the coincidences,
//! 15/10 on the B-C machine) × every axis × {backlash 10 um / 0.005 deg, Coulomb friction
//! three times the machine's 150 N / 15 N m}, both directions, the rest of the machine as
//! bundled (150 N / 15 N m of Coulomb friction on every axis).

use std::path::Path;

use mtsim::input::scenario::Scenario;
use mtsim::input::Direction;
use mtsim::measure::attribution::{
    distance_to_arc_deg, ReversalSite, ATTRIBUTION_MAX_DEG, SENSITIVITY_MIN,
};
use mtsim::measure::ballbar::{EventKind, TraceEvent};
use mtsim::study::simulate::run_ballbar;
use mtsim::Axis;
use rayon::prelude::*;

use crate::common;

use common::{machine, scenario_text, scratch};

#[derive(Clone, Copy, Debug)]
enum Fault {
    Backlash,
    Friction,
}

struct Cone {
    name: &'static str,
    machine: &'static str,
    alpha: f64,
    beta: f64,
    center: [f64; 3],
}

const CONES: [Cone; 4] = [
    Cone {
        name: "15-10",
        machine: "trt-ac",
        alpha: 15.0,
        beta: 10.0,
        center: [0.0, 0.0, 200.0],
    },
    Cone {
        name: "45-30",
        machine: "trt-ac",
        alpha: 45.0,
        beta: 30.0,
        center: [0.0, 0.0, 200.0],
    },
    Cone {
        name: "15-10-offset",
        machine: "trt-ac",
        alpha: 15.0,
        beta: 10.0,
        center: [0.0, -49.8, 200.0],
    },
    Cone {
        name: "15-10-bc",
        machine: "trt-bc",
        alpha: 15.0,
        beta: 10.0,
        center: [0.0, 0.0, 200.0],
    },
];

fn axes_of(machine: &str) -> [Axis; 5] {
    let tilt = if machine == "trt-bc" {
        Axis::B
    } else {
        Axis::A
    };
    [Axis::X, Axis::Y, Axis::Z, tilt, Axis::C]
}

fn scenario(cone: &Cone, axis: Axis, fault: Fault) -> Scenario {
    let [x, y, z] = cone.center;
    let mut body = format!(
        "[program.cone]\nhalf_apex_deg = {}\ninclination_deg = {}\ncenter_mm = [{x}, {y}, {z}]\n\
         ballbar_length_mm = 100.0\ndirections = [\"ccw\", \"cw\"]\n",
        cone.alpha, cone.beta
    );
    body += &match (fault, axis.is_rotary()) {
        (Fault::Backlash, false) => {
            format!("[machine_overrides.axes.{axis}.drive]\nbacklash_mm = 0.010\n")
        }
        (Fault::Backlash, true) => {
            format!("[machine_overrides.axes.{axis}.drive]\nbacklash_deg = 0.005\n")
        }
        (Fault::Friction, false) => {
            format!("[machine_overrides.axes.{axis}.friction]\ncoulomb_n = 450.0\n")
        }
        (Fault::Friction, true) => {
            format!("[machine_overrides.axes.{axis}.friction]\ncoulomb_nm = 45.0\n")
        }
    };
    let dir = scratch("attr", &format!("{}-{axis}-{fault:?}", cone.name));
    let path = dir.join("s.toml");
    std::fs::write(&path, scenario_text(&machine(cone.machine), &body)).unwrap();
    Scenario::load(Path::new(&path)).unwrap()
}

/// The arc a mark covers, from onset to peak in increasing θ.
fn arc(e: &TraceEvent) -> (f64, f64) {
    let span = mtsim::study::reversals::angular_distance_deg(e.theta_deg, e.peak_deg);
    match (e.kind, e.direction) {
        (EventKind::Step, _) => (e.theta_deg, 0.0),
        (_, Direction::Ccw) => (e.theta_deg, span),
        (_, Direction::Cw) => (e.peak_deg, span),
    }
}

struct Score {
    case: String,
    expected: usize,
    hits: usize,
    marks: usize,
    false_marks: Vec<String>,
    misses: Vec<String>,
}

fn score(cone: &Cone, axis: Axis, fault: Fault) -> Score {
    let study = run_ballbar(&scenario(cone, axis, fault), None, &|_| {}).unwrap();
    let result = study.result().unwrap().unwrap();
    let visible: Vec<&ReversalSite> = study
        .sites
        .iter()
        .filter(|s| s.axis == axis && s.sensitivity.unwrap() >= SENSITIVITY_MIN)
        .collect();
    let (mut expected, mut hits, mut misses) = (0, 0, Vec::new());
    for dir in [Direction::Ccw, Direction::Cw] {
        for site in &visible {
            expected += 1;
            let hit = result.events.iter().any(|e| {
                let (from, span) = arc(e);
                e.direction == dir
                    && e.candidates.contains(axis)
                    && distance_to_arc_deg(site.theta_deg, from, span) <= ATTRIBUTION_MAX_DEG
            });
            if hit {
                hits += 1;
            } else {
                misses.push(format!("{dir:?} {:.2}", site.theta_deg));
            }
        }
    }
    // A false mark carries no axis: no axis the bar can see reverses there.
    let false_marks = result
        .events
        .iter()
        .filter(|e| e.axis.is_none() || e.candidates.is_empty())
        .map(|e| {
            format!(
                "{:?} {:?} at {:.2} deg, {:.2} um",
                e.direction, e.kind, e.theta_deg, e.height_um
            )
        })
        .collect();
    Score {
        case: format!("{} {axis} {fault:?}", cone.name),
        expected,
        hits,
        marks: result.events.len(),
        false_marks,
        misses,
    }
}

#[test]
fn every_visible_reversal_of_a_faulty_axis_is_marked_with_that_axis_and_no_mark_is_false() {
    let cases: Vec<(&Cone, Axis, Fault)> = CONES
        .iter()
        .flat_map(|c| {
            axes_of(c.machine)
                .into_iter()
                .flat_map(move |a| [(c, a, Fault::Backlash), (c, a, Fault::Friction)])
        })
        .collect();
    assert_eq!(cases.len(), 40);
    let scores: Vec<Score> = cases.par_iter().map(|(c, a, f)| score(c, *a, *f)).collect();
    let (expected, hits, marks, false_marks) = scores.iter().fold((0, 0, 0, 0), |acc, s| {
        (
            acc.0 + s.expected,
            acc.1 + s.hits,
            acc.2 + s.marks,
            acc.3 + s.false_marks.len(),
        )
    });
    let report: Vec<String> = scores
        .iter()
        .filter(|s| !s.misses.is_empty() || !s.false_marks.is_empty())
        .map(|s| {
            format!(
                "{}: {}/{} hits, missed {:?}; false {:?}",
                s.case, s.hits, s.expected, s.misses, s.false_marks
            )
        })
        .collect();
    println!("scorecard: {hits}/{expected} hits, {false_marks} false marks out of {marks}");
    assert!(
        report.is_empty(),
        "{hits}/{expected} hits, {false_marks} false of {marks} marks:\n{}",
        report.join("\n")
    );
    // Every cone has reversals the bar sees: the scorecard is not empty.
    assert!(expected >= 4 * 2 * 4, "only {expected} expected marks");
}
