//! The pictures `check --html` draws from (`src/check/scene/snapshot.rs`): the scene at the
//! deepest sample of the deepest collisions, and the tool tip's path, against hand
//! computation on the bundled fork head.
//!
//! Fork head (machines/fork-head-ca.toml): A about +X through (0, 0, 200) above the gauge
//! point, the default tool's tip at the gauge point, the spindle housing a cylinder of
//! radius 70 mm from 140 to 320 mm along the tool, the table a cylinder about Z, top at
//! z = −200, 100 mm thick. At A = 90° the tool direction is Rx(90°) z = (0, −1, 0) and the
//! tip (0, 0, 0) − (0, 0, 200) turned and put back is (0, 200, 200) from (X, Y, Z): at
//! Y = 675, Z = −340 the tip is at (0, 875, −140), the housing's centre 230 mm along the
//! tool at (0, 645, −140), its axis along Y, its lowest line at z = −210: 10 mm into the
//! table. With A = 0 the tool points down and a plunge to Z = −200 − d puts the cutter d mm
//! into the table.

use crate::common;

use common::scratch;
use mtsim::check::scene::snapshot::{BodyShape, PATH_POINTS};
use mtsim::check::{check, CheckOptions, CheckReport};
use mtsim::input::scenario::Scenario;

/// `check` of `program` on the fork head, keeping the `shown` deepest collisions' scenes.
/// Collision depths are measured exactly (no depth tolerance, docs/scene.md), so that the
/// pictured sample is the deepest one the hand computation places.
fn fork_head(name: &str, program: &str, shown: usize) -> CheckReport {
    let dir = scratch("check-views", name);
    let scenario = Scenario::load(&common::fork_head_scenario(&dir, program)).unwrap();
    let options = CheckOptions {
        collision_poses: shown,
        ..CheckOptions::default()
    };
    check(&scenario, &options).unwrap()
}

fn near(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() < tol)
}

/// Rotates `v` by the unit quaternion (x, y, z, w).
fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let (u, w) = ([q[0], q[1], q[2]], q[3]);
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let t = cross(u, v).map(|c| 2.0 * c);
    let ut = cross(u, t);
    [0, 1, 2].map(|k| v[k] + w * t[k] + ut[k])
}

#[test]
fn the_turned_fork_heads_spindle_is_pictured_where_it_enters_the_table() {
    let report = fork_head(
        "turn",
        "G21 G90 G17\nG0 X0 Y675 Z-340 C0 A0\nG1 A90 F1800\nG1 A0\nG0 Z-100\nG0 Y0\n\
         G1 Z-205 F600\nG0 Z0\nM2\n",
        20,
    );
    let views = report.views.expect("pictures were asked for");
    assert_eq!(views.collisions.len(), 2, "{:#?}", report.violations);
    let [turn, plunge] = [&views.collisions[0], &views.collisions[1]];
    // Deepest first: the housing 10 mm in (line 3), then the cutter 5 mm (line 7).
    let mut pair = turn.bodies.to_vec();
    pair.sort();
    assert_eq!(pair, ["spindle", "table"]);
    assert_eq!(turn.line, 3);
    assert!((turn.depth_mm - 10.0).abs() < 1e-3, "{}", turn.depth_mm);
    assert!(
        plunge.bodies.contains(&"cutter".to_string()),
        "{:?}",
        plunge.bodies
    );
    assert_eq!(plunge.line, 7);
    assert!((plunge.depth_mm - 5.0).abs() < 1e-3, "{}", plunge.depth_mm);
    // The bodies where the hand computation puts them at the pictured sample's A (the
    // deepest sample the monitor measured, at the end of the turn): the tip at
    // (0, Y, Z + 200) + Rx(A) (0, 0, −200) = (0, Y + 200 sin A, Z + 200 − 200 cos A), the
    // tool direction Rx(A) z = (0, −sin A, cos A), the housing's centre 230 mm along it.
    let a = turn.axes.iter().find(|(n, _)| n == "A").unwrap().1;
    assert!((a - 90.0).abs() < 1e-3, "A {a}");
    let (sa, ca) = a.to_radians().sin_cos();
    let tip = [0.0, 675.0 + 200.0 * sa, -340.0 + 200.0 - 200.0 * ca];
    assert!(near(turn.tip_mm, tip, 1e-9), "{:?} vs {tip:?}", turn.tip_mm);
    assert!(near(tip, [0.0, 875.0, -140.0], 1e-3));
    let body = |name: &str| {
        turn.bodies_placed
            .iter()
            .find(|b| b.name == name)
            .unwrap_or_else(|| panic!("no {name}"))
    };
    let spindle = body("spindle");
    let centre = [0.0, tip[1] - 230.0 * sa, tip[2] + 230.0 * ca];
    assert!(
        near(spindle.position_mm, centre, 1e-9),
        "{:?} vs {centre:?}",
        spindle.position_mm
    );
    assert!(near(centre, [0.0, 645.0, -140.0], 1e-3));
    let BodyShape::Cylinder {
        half_height_mm,
        radius_mm,
    } = spindle.shape
    else {
        panic!("{:?}", spindle.shape)
    };
    assert!((half_height_mm - 90.0).abs() < 1e-9 && (radius_mm - 70.0).abs() < 1e-9);
    // The cylinder's own axis (its frame's Y) lies along the tool.
    let axis = rotate(spindle.rotation_xyzw, [0.0, 1.0, 0.0]);
    let along = axis[1] * -sa + axis[2] * ca;
    assert!((along.abs() - 1.0).abs() < 1e-9, "{axis:?}");
    let table = body("table");
    assert!(
        near(table.position_mm, [0.0, 0.0, -250.0], 1e-9),
        "{:?}",
        table.position_mm
    );
    // The plunge: the tip straight down at (0, 0, −200 − depth), the depth its own.
    let z = -200.0 - plunge.depth_mm;
    assert!(
        near(plunge.tip_mm, [0.0, 0.0, z], 1e-9),
        "{:?}",
        plunge.tip_mm
    );
    // The tip's path: every stride-th sample of the run, no more than PATH_POINTS.
    let n = views.tip_path_mm.len() as u64;
    assert!(n as usize <= PATH_POINTS);
    assert_eq!(
        n,
        report.samples.div_ceil(views.path_stride),
        "stride {}",
        views.path_stride
    );
    assert!(
        views.path_stride > 1,
        "{} samples kept whole",
        report.samples
    );
    // It starts at the program's first point and passes through both collisions' tips.
    assert!(near(
        views.tip_path_mm[0],
        [0.0, 875.0 - 200.0, -140.0 - 200.0],
        1e-6
    ));
    let passes = |p: [f64; 3]| views.tip_path_mm.iter().any(|q| near(*q, p, 5.0));
    assert!(passes(turn.tip_mm) && passes(plunge.tip_mm));
}

#[test]
fn only_the_deepest_collisions_are_kept() {
    // Five plunges 3, 1, 5, 2 and 4 mm into the table at different places; three kept.
    let depths = [3.0, 1.0, 5.0, 2.0, 4.0];
    let mut program = String::from("G21 G90 G17\nG0 X0 Y0 Z-100 C0 A0\n");
    for (k, d) in depths.iter().enumerate() {
        let y = -200.0 + 100.0 * k as f64;
        program.push_str(&format!("G0 Y{y}\nG1 Z{} F600\nG0 Z-100\n", -200.0 - d));
    }
    program.push_str("M2\n");
    let report = fork_head("plunges", &program, 3);
    let views = report.views.unwrap();
    let collisions = report
        .violations
        .iter()
        .filter(|v| v.kind == mtsim::check::limits::ViolationKind::Collision)
        .count();
    assert!(collisions >= 5, "{:#?}", report.violations);
    let kept: Vec<f64> = views.collisions.iter().map(|c| c.depth_mm).collect();
    assert_eq!(kept.len(), 3);
    for (got, want) in kept.iter().zip([5.0, 4.0, 3.0]) {
        assert!((got - want).abs() < 1e-3, "{kept:?}");
    }
    // Each at its plunge's bottom: Y of the plunge, Z = −200 − its depth.
    for c in &views.collisions {
        let k = depths
            .iter()
            .position(|d| (d - c.depth_mm).abs() < 1e-3)
            .unwrap();
        let y = -200.0 + 100.0 * k as f64;
        assert!(
            near(c.tip_mm, [0.0, y, -200.0 - c.depth_mm], 1e-9),
            "{:?}",
            c.tip_mm
        );
        // Line of the plunge's G1: header line 2, three lines per plunge.
        assert_eq!(c.line, 4 + 3 * k, "{c:?}");
    }
}
