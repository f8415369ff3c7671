//! Measurements behind one trait: the ball bar read as a `Measurement`, on a deviation known
//! in closed form.

use mtsim::input::Direction;
use mtsim::kinematics::{Kinematics, Layout};
use mtsim::measure::{BallbarSink, BarGeometry, CircleFrame, Measurement};
use mtsim::pipeline::Sample;
use mtsim::{Axis, AxisVec, Plane};
use nalgebra::{Point3, Vector3};

/// A bar of L = 100 mm about (0, −25, 200), the rotaries at 0 (table frame = machine frame),
/// whose tool ball runs a circle of radius `L + r0 + a cos θ`: the bar reads
/// `dL = r0 + a cos θ` exactly, so the run's centring is (r0, a, 0) and its centred trace is
/// flat (G = 0). The measurement's document says so.
#[test]
fn the_ball_bar_as_a_measurement_reads_its_centring() {
    const L: f64 = 100.0;
    let centre = [0.0, -25.0, 200.0];
    let (r0_um, a_um) = (3.0, -2.0);
    let geometry = BarGeometry {
        kinematics: Kinematics::new(Layout::TrtAc, Vector3::zeros()),
        frame: CircleFrame::planar(centre, Plane::XY),
        pivot_table_mm: Point3::from(centre),
        length_mm: L,
    };
    let mut sink = BallbarSink::new(geometry, Direction::Ccw, None);
    let m: &mut dyn Measurement = &mut sink;
    assert_eq!(m.name(), "ballbar");
    m.start_run(Direction::Ccw, None);
    let n = 36_000u64;
    for k in 0..n {
        let theta = (k as f64 + 0.5) * 360.0 / n as f64;
        let (s, c) = theta.to_radians().sin_cos();
        let at = |r: f64| {
            let mut q = AxisVec::ZERO;
            q[Axis::X] = centre[0] + r * c;
            q[Axis::Y] = centre[1] + r * s;
            q[Axis::Z] = centre[2];
            q
        };
        let commanded = at(L);
        let actual = at(L + 1e-3 * (r0_um + a_um * c));
        m.push(&Sample {
            index: k,
            time_s: k as f64 * 1e-3,
            line: 2,
            block_index: 1,
            commanded,
            actual,
            following_error: commanded - actual,
            linear: actual,
        })
        .unwrap();
    }
    m.end_run().unwrap();
    let doc = m.finish().unwrap();
    let run = &doc[0];
    assert_eq!(run["samples"], n);
    let centring = &run["centring"];
    let close = |v: &serde_json::Value, x: f64| (v.as_f64().unwrap() - x).abs() < 1e-6;
    assert!(close(&centring["r0_um"], r0_um), "{centring}");
    assert!(close(&centring["a_um"], a_um), "{centring}");
    assert!(close(&centring["b_um"], 0.0), "{centring}");
    assert!(close(&run["circular_deviation_um"], 0.0), "{run}");
    assert!(close(&run["radial_max_um"], r0_um - a_um), "{run}");
}
