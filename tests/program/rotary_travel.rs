//! The generated cone keeps a rotary of limited travel within it by where the turn starts,
//! as a post-processor does: on the fork head (C of ±360 deg) the 15/10 cone at O = 0 turns
//! C through one whole revolution from −90 deg at θ = 0. Counter-clockwise that is
//! −90 → 270 deg; clockwise, started at the same −90, it would end at −450 deg, past the
//! travel, so the clockwise turn starts one turn up, at 270 deg, and ends at −90 deg.

use std::path::Path;

use mtsim::input::machine::Machine;
use mtsim::input::NcOptions;
use mtsim::program::cone::{ConePath, ConeProgram};
use mtsim::Axis;

use crate::common;

/// C of every block of the cone (α 15, β 10 deg, O = 0, bar 100 mm) on `machine`.
fn c_words(machine: &Machine, clockwise: bool, lead_deg: f64) -> Vec<f64> {
    let mut cone = common::cone(15.0, 10.0, 0.0, 100.0);
    cone.center_mm.z = 0.0;
    let path = ConePath::new(cone, machine);
    let options = NcOptions {
        segments: 360,
        feed_mm_min: 2000.0,
        inverse_time: false,
        tcp: false,
        lead_deg,
        clockwise,
    };
    ConeProgram::new(&path, &machine.name, &options)
        .moves()
        .map(|m| m.end[Axis::C])
        .collect()
}

fn fork_head() -> Machine {
    Machine::load(Path::new(&common::machine("fork-head-ca"))).unwrap()
}

fn within(c: &[f64], min: f64, max: f64) -> bool {
    c.iter().all(|v| (min..=max).contains(v))
}

#[test]
fn a_clockwise_revolution_on_c_of_360_deg_travel_starts_a_turn_up() {
    let m = fork_head();
    let ccw = c_words(&m, false, 0.0);
    let cw = c_words(&m, true, 0.0);
    // Counter-clockwise as before: −90 → 270 deg.
    assert!((ccw[0] + 90.0).abs() < 1e-6, "{}", ccw[0]);
    assert!(
        (ccw[ccw.len() - 1] - 270.0).abs() < 1e-6,
        "{}",
        ccw[ccw.len() - 1]
    );
    // Clockwise: 270 → −90 deg, within ±360.
    assert!((cw[0] - 270.0).abs() < 1e-6, "{}", cw[0]);
    assert!(
        (cw[cw.len() - 1] + 90.0).abs() < 1e-6,
        "{}",
        cw[cw.len() - 1]
    );
    assert!(within(&cw, -360.0, 360.0));
}

#[test]
fn the_lead_arcs_stay_within_travel_too() {
    let m = fork_head();
    // 10 deg of lead each side: C turns about 380 deg. Clockwise runs the counter-clockwise
    // path backwards, θ from 370 down to −10 deg against −10 up to 370 deg: the same poses.
    let (ccw, cw) = (c_words(&m, false, 10.0), c_words(&m, true, 10.0));
    assert!(within(&ccw, -360.0, 360.0) && within(&cw, -360.0, 360.0));
    assert!(
        (cw[0] - ccw[ccw.len() - 1]).abs() < 1e-9,
        "{} {}",
        cw[0],
        ccw[ccw.len() - 1]
    );
    assert!(
        (cw[cw.len() - 1] - ccw[0]).abs() < 1e-9,
        "{} {}",
        cw[cw.len() - 1],
        ccw[0]
    );
}

#[test]
fn a_continuous_c_keeps_the_start_it_had() {
    // trt-ac's C is continuous: no turn is added, both directions start at θ = 0's C.
    let m = common::load_trt_ac();
    let (ccw, cw) = (c_words(&m, false, 0.0), c_words(&m, true, 0.0));
    assert_eq!(ccw[0].to_bits(), cw[0].to_bits());
}
