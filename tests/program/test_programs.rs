//! The tests behind one trait (`program::tests`): what each bundled test answers, against
//! values worked out from its scenario by hand.

use std::f64::consts::PI;
use std::path::Path;

use mtsim::input::budget::SampleEstimate;
use mtsim::input::program::Direction;
use mtsim::input::scenario::Scenario;
use mtsim::program::test_of;
use nalgebra::{Point3, Vector3};

fn bundled(name: &str) -> Scenario {
    Scenario::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenarios")
            .join(name),
    )
    .unwrap()
}

/// The ISO 230-4 circle of `circle-iso230-4.toml` (r 50 mm, F1000, XY, centre (0, 0, 100),
/// both directions): its directions, its revolution and sample budget, and its ball bar (the
/// bar's length is the radius, the table ball at the centre, θ counter-clockwise from +X).
#[test]
fn the_circle_answers_its_scenario() {
    let s = bundled("circle-iso230-4.toml");
    let test = test_of(&s);
    assert_eq!(test.table(), "[program.circle]");
    assert_eq!(test.directions(), [Direction::Ccw, Direction::Cw]);
    assert!(test.file().is_none() && test.generated_cone().is_none());
    assert_eq!(test.circle().unwrap().radius_mm, 50.0);
    let rev = test.revolution().unwrap();
    assert_eq!((rev.radius_mm, rev.feed_mm_min), (50.0, 1000.0));
    // n = 2π r (1 + lead/180) / (F/60) / Δt.
    let lead = s.simulate.lead_deg;
    let dt = s.machine.interpolation_period_s;
    let expected = 2.0 * PI * 50.0 * (1.0 + lead / 180.0) / (1000.0 / 60.0) / dt;
    let estimate = SampleEstimate::of(&s, &rev, lead);
    assert!((estimate.samples - expected).abs() < 1e-9 * expected);
    let bar = test.bar(&s.machine.kinematics).unwrap();
    assert_eq!(bar.length_mm, 50.0);
    let centre = Vector3::new(0.0, 0.0, 100.0) - s.machine.kinematics.pivot_mm;
    assert!((bar.pivot_table_mm.coords - centre).norm() < 1e-12);
    for (offset, theta) in [
        ([50.0, 0.0], 0.0),
        ([0.0, 50.0], 90.0),
        ([-50.0, 0.0], 180.0),
    ] {
        let p = Point3::from(centre + Vector3::new(offset[0], offset[1], 0.0));
        assert!((bar.frame.theta_deg(&p) - theta).abs() < 1e-9);
    }
}

/// The generated 15/10 cone of `cone-15-10.toml` (L 100 mm): its measured circle has the
/// radius L cos 15°, and θ of the tool ball's P(θ) on it is θ itself.
#[test]
fn the_generated_cone_answers_its_scenario() {
    let s = bundled("cone-15-10.toml");
    let test = test_of(&s);
    assert_eq!(test.table(), "[program.cone]");
    let (cone, _) = test.generated_cone().unwrap();
    let rev = test.revolution().unwrap();
    assert!((rev.radius_mm - 100.0 * 15f64.to_radians().cos()).abs() < 1e-12);
    let bar = test.bar(&s.machine.kinematics).unwrap();
    assert_eq!(bar.length_mm, 100.0);
    assert_eq!(bar.pivot_table_mm, Point3::from(cone.center_mm));
    for theta in [10.0, 95.0, 200.0, 333.0] {
        let p = cone.point(f64::to_radians(theta));
        assert!((bar.frame.theta_deg(&p) - theta).abs() < 1e-9, "{theta}");
        // The tool ball sits L from the table ball.
        assert!(((p - bar.pivot_table_mm).norm() - 100.0).abs() < 1e-9);
    }
    assert!(test
        .title("cone-15-10")
        .starts_with("cone-15-10: cone 15/10 deg"));
}

/// A G-code file runs once as written, has no closed-form revolution (it is counted while it
/// runs), and is measured on the cone its scenario gives.
#[test]
fn a_file_runs_as_written_on_its_given_cone() {
    let s = bundled("file-cone-15-10-yt25.toml");
    let test = test_of(&s);
    assert!(test.planned_directions().is_none());
    assert_eq!(test.directions(), [Direction::Ccw]);
    assert!(test.revolution().is_none());
    assert!(test
        .file()
        .unwrap()
        .ends_with("programs/cone-15-10-yt25.nc"));
    assert!(test.starts_unsettled());
    let bar = test.bar(&s.machine.kinematics).unwrap();
    assert_eq!(bar.pivot_table_mm, Point3::new(0.0, -25.0, 200.0));
    let d = test.description(s.simulate.lead_deg);
    assert_eq!(d.feed_mm_min, None);
    assert_eq!(d.start_arc_deg, None);
}
