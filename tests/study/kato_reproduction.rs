//! The cone-frustum motion-simulator results of Kato, Tsutsumi and Sato (IJMTM 2012/2013),
//! reproduced: friction of the linear axes gives the spikes of the ball-bar trace, backlash
//! of the tilting table gives steps ("trace features") at the tilt axis's reversals, of the
//! height the bar's lever on the tilt axis predicts. 15/10 cone, O = (0, 0, 200) mm, L = 100
//! mm, F1000, both directions (the paper's Fig. 5 set-up), trt-ac machine.

use std::path::Path;

use mtsim::input::scenario::Scenario;
use mtsim::measure::ballbar::EventKind;
use mtsim::study::simulate::run_ballbar;
use mtsim::Axis;
use nalgebra::{Rotation3, Vector3};

use crate::common;

fn scenario(name: &str, overrides: &str) -> Scenario {
    let dir = common::scratch("kato", name);
    let body = format!(
        "{}directions = [\"ccw\", \"cw\"]\n{overrides}",
        common::CONE_15_10
    );
    let path = common::write_scenario(&dir, &common::trt_ac(), &body);
    Scenario::load(Path::new(&path)).unwrap()
}

fn coulomb(linear_n: f64, rotary_nm: f64) -> String {
    let mut s = String::new();
    for a in ["X", "Y", "Z"] {
        s += &format!("[machine_overrides.axes.{a}.friction]\ncoulomb_n = {linear_n}\n");
    }
    for a in ["A", "C"] {
        s += &format!("[machine_overrides.axes.{a}.friction]\ncoulomb_nm = {rotary_nm}\n");
    }
    s
}

/// ∂L/∂A at θ, mm/rad, from the spec's inverse kinematics written out here: the table ball O
/// turns about machine X, `δO = δA x̂ × O_M`, and the bar reads `-u · δO`.
fn bar_lever_on_a(theta_deg: f64) -> f64 {
    let (alpha, beta, l) = (15f64.to_radians(), 10f64.to_radians(), 100.0);
    let o = Vector3::new(0.0, 0.0, 200.0);
    let ry = Rotation3::from_axis_angle(&Vector3::y_axis(), -beta);
    let t = theta_deg.to_radians();
    let (r, h) = (l * alpha.cos(), l * alpha.sin());
    let p = o + ry * Vector3::new(r * t.cos(), r * t.sin(), h);
    let apex = o + ry * Vector3::new(0.0, 0.0, l / alpha.sin());
    let tool = (apex - p).normalize();
    let (a, c) = (tool.z.acos(), tool.x.atan2(tool.y));
    let rot = Rotation3::from_axis_angle(&Vector3::x_axis(), a)
        * Rotation3::from_axis_angle(&Vector3::z_axis(), c);
    let (p_m, o_m) = (rot * p, rot * o);
    let u = (p_m - o_m).normalize();
    -u.dot(&Vector3::x().cross(&o_m))
}

#[test]
fn friction_of_the_linear_axes_gives_the_spikes() {
    let study = run_ballbar(&scenario("friction", &coulomb(300.0, 0.0)), None, &|_| {}).unwrap();
    let result = study.result().unwrap().unwrap();
    let spikes: Vec<_> = result
        .events
        .iter()
        .filter(|e| e.kind == EventKind::Spike)
        .collect();
    // Every mark comes from a linear axis; X's reversals (131.15, 228.85 deg) and Y's own
    // (151.07, 208.93 deg) each carry a spike in both directions.
    for e in &result.events {
        assert!(
            e.candidates.iter().any(|a| !a.is_rotary()),
            "a mark without a linear candidate: {e:?}"
        );
    }
    for (axis, theta) in [
        (Axis::X, 131.15),
        (Axis::X, 228.85),
        (Axis::Y, 151.07),
        (Axis::Y, 208.93),
    ] {
        for dir in [mtsim::input::Direction::Ccw, mtsim::input::Direction::Cw] {
            let best = spikes
                .iter()
                .filter(|e| {
                    e.direction == dir
                        && e.candidates.contains(axis)
                        && mtsim::study::reversals::angular_distance_deg(e.peak_deg, theta) < 3.0
                })
                .map(|e| e.height_um.abs())
                .fold(0.0, f64::max);
            println!("{axis} {theta} {dir:?}: spike {best:.2} um");
            assert!(best > 1.0, "{axis} at {theta} deg {dir:?}: no spike");
        }
    }
}

#[test]
fn backlash_of_the_tilting_table_steps_the_trace_by_the_bar_lever_times_the_gap() {
    // A worm table: b 0.005 deg, Coulomb 15 N m, stiffness 3e6 N m/rad (the defaults); no
    // friction on the linear axes. The lost motion is b + 2 Fc / k = 0.005573 deg.
    let b_deg: f64 = 0.005;
    let lost_deg = b_deg + (2.0 * 15.0 / 3.0e6_f64).to_degrees();
    let overrides = format!(
        "{}[machine_overrides.axes.A.drive]\nbacklash_deg = {b_deg}\n",
        coulomb(0.0, 15.0)
    );
    let study = run_ballbar(&scenario("backlash", &overrides), None, &|_| {}).unwrap();
    let result = study.result().unwrap().unwrap();
    for theta in [0.0, 180.0] {
        // mtsim's own sensitivity at the reversal (central differences through its
        // kinematics, normalised by L = 100 mm) agrees with the lever written out here.
        let site = study
            .sites
            .iter()
            .find(|s| {
                s.axis == Axis::A
                    && mtsim::study::reversals::angular_distance_deg(s.theta_deg, theta) < 1e-6
            })
            .unwrap();
        let lever = bar_lever_on_a(theta).abs() / 100.0;
        assert!(
            (site.sensitivity.unwrap() - lever).abs() < 1e-4 * lever,
            "{site:?} vs {lever}"
        );
        let want = bar_lever_on_a(theta).abs() * lost_deg.to_radians() * 1e3; // um
        for dir in [mtsim::input::Direction::Ccw, mtsim::input::Direction::Cw] {
            let step = result
                .events
                .iter()
                .find(|e| {
                    e.kind == EventKind::Step
                        && e.direction == dir
                        && e.candidates.contains(Axis::A)
                        && mtsim::study::reversals::angular_distance_deg(e.theta_deg, theta) < 3.0
                })
                .unwrap_or_else(|| panic!("no A step at {theta} {dir:?}: {:?}", result.events));
            println!(
                "A backlash {b_deg} deg at {theta} deg {dir:?}: step {:.2} um, lever {:.1} mm/rad -> {want:.2} um",
                step.height_um,
                bar_lever_on_a(theta)
            );
            assert!(
                (step.height_um.abs() - want).abs() < 0.1 * want,
                "{} um vs {want} um",
                step.height_um
            );
        }
    }
}
