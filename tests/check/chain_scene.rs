//! The collision scene on a kinematic chain: the bodies ride on the chain's links, so the
//! 45° nutating head of the bundled head-table machine, turned to B = 180°, lays its
//! spindle housing horizontal, and lowering it brings the housing into the C table, where
//! the same descent with the head at B = 0 clears the table.
//!
//! Hand computation (machines/head-table-b45-c.toml): B's line runs along d = (0, s, s),
//! s = 1/√2, through p = (0, 0, 150); the [tool]'s tip sits at the gauge point (the origin
//! at home), the spindle housing is a cylinder of radius 80 mm from 140 to 340 mm along
//! the tool, the table a cylinder of radius 250 mm about Z, its top at z = −150, 80 mm
//! thick. Rodrigues at B = 180°: `Rot(d, π) v = 2 (d·v) d − v`, so the tip goes to
//! `Rot (0 − p) + p = (0, −150, 150)` and the tool direction z to `2 s d − z = (0, 1, 0)`:
//! the housing's axis is the line z = Z + 150 over y ∈ [Y − 10, Y + 190], and its lowest
//! generatrix z = Z + 70. At Y = −335 it overhangs the table for y ∈ [−250, −145], so it
//! touches the top when Z = −220 and is 10 mm into it at Z = −230.

use crate::common;

use std::path::Path;

use common::scratch;
use mtsim::check::limits::ViolationKind;
use mtsim::check::{check, check_reference, check_with, CheckOptions, CheckReport, SceneQueries};
use mtsim::input::scenario::Scenario;

const Y: f64 = -335.0;
const Z_END: f64 = -230.0;
const FEED_MM_PER_MIN: f64 = 600.0;

/// Lowers the head from Z = 0 to Z_END at X = 0, Y = Y with B = `b_deg`, at programmed
/// timing (so Z is linear in time within the block).
fn lower(name: &str, b_deg: f64, near_miss_mm: Option<f64>) -> CheckReport {
    let program =
        format!("G21 G90 G17\nG0 X0 Y{Y} Z0 B{b_deg} C0\nG1 Z{Z_END} F{FEED_MM_PER_MIN}\nM2\n");
    let scenario = scenario(name, "head-table-b45-c", &program);
    let options = CheckOptions {
        programmed: true,
        near_miss_mm,
        ..CheckOptions::default()
    };
    check(&scenario, &options).unwrap()
}

/// A scenario running `program` on the bundled `machine`, with no workpiece.
fn scenario(name: &str, machine: &str, program: &str) -> Scenario {
    let dir = scratch("chain-scene", name);
    std::fs::write(dir.join("p.ngc"), program).unwrap();
    let machine = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("machines/{machine}.toml"));
    let text = format!(
        "machine = {:?}\n[program]\nfile = \"p.ngc\"\n[reader]\ndialect = \"linuxcnc\"\n[workpiece]\nkind = \"none\"\n",
        machine.display().to_string()
    );
    std::fs::write(dir.join("s.toml"), text).unwrap();
    Scenario::load(&dir.join("s.toml")).unwrap()
}

/// The tip and tool direction at B (deg) relative to (X, Y, Z), by Rodrigues about the
/// nutating line (written out here, not the crate's chain).
fn head_at(b_deg: f64) -> ([f64; 3], [f64; 3]) {
    let s = 0.5f64.sqrt();
    let d = [0.0, s, s];
    let (sb, cb) = b_deg.to_radians().sin_cos();
    let rot = |v: [f64; 3]| {
        let dv = d[0] * v[0] + d[1] * v[1] + d[2] * v[2];
        let c = [
            d[1] * v[2] - d[2] * v[1],
            d[2] * v[0] - d[0] * v[2],
            d[0] * v[1] - d[1] * v[0],
        ];
        [0, 1, 2].map(|i| v[i] * cb + c[i] * sb + d[i] * dv * (1.0 - cb))
    };
    let p = [0.0, 0.0, 150.0];
    let r = rot([-p[0], -p[1], -p[2]]);
    (
        [r[0] + p[0], r[1] + p[1], r[2] + p[2]],
        rot([0.0, 0.0, 1.0]),
    )
}

#[test]
fn the_turned_heads_spindle_housing_hits_the_table_where_the_upright_head_clears_it() {
    // The hand computation: at B = 180° the tool lies along +Y, the tip 150 mm up and
    // 150 mm back; the housing's lowest generatrix is Z + 150 − 80.
    let (tip, t) = head_at(180.0);
    assert!(
        (tip[0]).abs() < 1e-9 && (tip[1] + 150.0).abs() < 1e-9 && (tip[2] - 150.0).abs() < 1e-9
    );
    assert!((t[1] - 1.0).abs() < 1e-12);
    let (radius, table_top) = (80.0, -150.0);
    let touch_z = table_top - (tip[2] - radius); // the housing's bottom reaches the top
    assert!((touch_z + 220.0).abs() < 1e-9);
    let depth = touch_z - Z_END;
    let seconds_in_contact = depth / (FEED_MM_PER_MIN / 60.0);

    let turned = lower("turned", 180.0, None);
    let collisions: Vec<_> = turned
        .violations
        .iter()
        .filter(|v| v.kind == ViolationKind::Collision)
        .collect();
    assert_eq!(collisions.len(), 1, "{:#?}", turned.violations);
    let c = collisions[0];
    let mut bodies = c.bodies.clone().unwrap().to_vec();
    bodies.sort();
    assert_eq!(bodies, ["spindle", "table"]);
    assert_eq!(c.line, 3, "the G1 Z move");
    assert!(
        (c.worst - depth).abs() < 1e-3,
        "depth {} mm, by hand {depth}",
        c.worst
    );
    // Contact from Z = −220 to the block's end at Z = −230, at 10 mm/s; samples every 1 ms.
    let span = c.time_end_s - c.time_start_s;
    assert!(
        (span - seconds_in_contact).abs() < 2e-3,
        "in contact {span} s, by hand {seconds_in_contact} s"
    );

    // B = 0: the tool upright over y = −335. The nearest body is the holder (radius 25 mm,
    // from 80 to 140 mm above the tip): at Z = −230 its bottom is level with the table top
    // and its side 335 − 25 − 250 = 60 mm from the table's. No collision; with a near-miss
    // threshold of 100 mm every pair that near is measured at every sample, so the
    // smallest clearance reported is the one at the last sample.
    let upright = lower("upright", 0.0, None);
    assert!(upright.violations.is_empty(), "{:#?}", upright.violations);
    let upright = lower("upright-near", 0.0, Some(100.0));
    assert!(
        upright
            .violations
            .iter()
            .all(|v| v.kind == ViolationKind::NearMiss),
        "{:#?}",
        upright.violations
    );
    let clearance = upright.min_clearance_mm.unwrap();
    assert!((clearance - 60.0).abs() < 1e-3, "clearance {clearance} mm");
    let mut nearest = upright.min_clearance_bodies.unwrap().to_vec();
    nearest.sort();
    assert_eq!(nearest, ["holder", "table"]);
}

/// Turning the head into the table: the bounded check (conservative advancement with the
/// chain's lever arms, `src/check/scene/linked.rs`) finds the same events at the same
/// samples as the reference that measures every pair at every sample. Head-table: B from 0
/// to 180° at Z = −230 (the housing ends 10 mm into the table, as above). Fork head (A about
/// +X through (0, 0, 200), the table top at z = −200, radius 600): A from 0 to 90° at
/// Y = 675, Z = −340 lays the tool along −Y, the tip at (0, Y + 200, Z + 200) and the
/// housing (radius 70, 140 to 320 mm along the tool) over y ∈ [Y − 120, Y + 60] at
/// z = Z + 200 ± 70: 10 mm into the table where it overhangs it (y < 600).
#[test]
fn turning_the_head_into_the_table_is_found_by_the_bounded_check_as_by_the_reference() {
    let cases = [
        (
            "head-table-b45-c",
            format!("G21 G90 G17\nG0 X0 Y{Y} Z{Z_END} B0 C0\nG1 B180 F3600\nM2\n"),
        ),
        (
            "fork-head-ca",
            "G21 G90 G17\nG0 X0 Y675 Z-340 C0 A0\nG1 A90 F1800\nM2\n".to_string(),
        ),
    ];
    // With exact depths, and with the default depth tolerance.
    for ((machine, program), exact) in cases.iter().flat_map(|case| [(case, true), (case, false)]) {
        let mut s = scenario(&format!("turn-{machine}"), machine, program);
        if exact {
            s.machine.scene.depth_tolerance_mm = 0.0;
            s.machine.scene.depth_tolerance_relative = 0.0;
        }
        let options = CheckOptions::default();
        let slow = check_reference(&s, &options).unwrap();
        let fast = check_with(&s, &options, SceneQueries::Bounded).unwrap();
        // The same events at the same samples; the worst values within GJK's warm-start
        // noise (the two paths query different samples: 2.6e-9 mm seen), a collision's depth
        // `W` short of the reference's by at most the tolerance's `at(W)` (0 when exact).
        let tolerance = fast.collision_depth_tolerance.unwrap();
        assert_eq!(fast.violations.len(), slow.violations.len(), "{machine}");
        for (a, b) in fast.violations.iter().zip(&slow.violations) {
            assert_eq!(
                (a.kind, &a.bodies, a.line, a.time_start_s, a.time_end_s),
                (b.kind, &b.bodies, b.line, b.time_start_s, b.time_end_s),
                "{machine}"
            );
            let short = match a.kind {
                ViolationKind::Collision => tolerance.at(a.worst),
                _ => 0.0,
            };
            assert!(
                a.worst <= b.worst + 1e-6 && b.worst <= a.worst + short + 1e-6,
                "{machine} {tolerance:?}: {a:?} {b:?}"
            );
        }
        let (events, ratio) = (
            fast.violations.len(),
            fast.scene_queries.unwrap() as f64 / slow.scene_queries.unwrap() as f64,
        );
        let c = fast
            .violations
            .iter()
            .find(|v| v.kind == ViolationKind::Collision)
            .unwrap_or_else(|| panic!("{machine}: {:#?}", fast.violations));
        let mut bodies = c.bodies.clone().unwrap().to_vec();
        bodies.sort();
        assert_eq!(bodies, ["spindle", "table"], "{machine}");
        assert_eq!(c.line, 3, "{machine}");
        // The deepest point is at the block's end, where the hand computation gives 10 mm.
        assert!(
            c.worst <= 10.0 + 1e-3 && 10.0 <= c.worst + tolerance.at(c.worst) + 1e-3,
            "{machine} {tolerance:?}: depth {}",
            c.worst
        );
        eprintln!(
            "{machine} {tolerance:?}: {events} events, {:.3} of the reference's queries, depth {}",
            ratio, c.worst
        );
    }
}
