//! Collision scene: shapes, hand-computed contacts, clean cone paths, near misses, and the
//! conservative-advancement monitor against brute force.

use std::path::Path;

use mtsim::check::scene::{
    z_cylinder, ConeSetup, PairKind, Scene, SceneMonitor, ToolConfig, WorkpieceConfig,
    WorkpieceKind,
};
use mtsim::input::machine::Machine;
use mtsim::{Axis, AxisVec};

/// A trt-ac machine with its pivot at the machine origin; `extra` holds `[scene]`/`[tool]`.
fn machine(extra: &str) -> Machine {
    let mut text = String::from(
        "name = \"test trt-ac\"\nkinematics = \"trt-ac\"\npivot_mm = [0.0, 0.0, 0.0]\n",
    );
    for (axis, min, max, v) in [
        ("X", -800, 800, 30000),
        ("Y", -800, 800, 30000),
        ("Z", -800, 800, 30000),
        ("A", -120, 120, 10000),
        ("C", -100000, 100000, 20000),
    ] {
        text += &format!("[axes.{axis}]\nmin = {min}.0\nmax = {max}.0\nmax_velocity = {v}.0\nmax_acceleration = 3000.0\nmax_jerk = 50000.0\n");
    }
    text += extra;
    Machine::from_toml(Path::new("test-machine.toml"), &text, None).expect("test machine parses")
}

fn q(x: f64, y: f64, z: f64, a: f64, c: f64) -> AxisVec {
    let mut q = AxisVec::ZERO;
    q[Axis::X] = x;
    q[Axis::Y] = y;
    q[Axis::Z] = z;
    q[Axis::A] = a;
    q[Axis::C] = c;
    q
}

/// Signed distance of the pair made of bodies `a` and `b` at axis positions `at`.
fn distance(scene: &mut Scene, at: AxisVec, a: &str, b: &str) -> f64 {
    scene.set_axes(&at);
    scene
        .clearances()
        .into_iter()
        .find(|p| (p.bodies[0] == a && p.bodies[1] == b) || (p.bodies[0] == b && p.bodies[1] == a))
        .unwrap_or_else(|| panic!("no monitored pair {a}/{b}"))
        .distance_mm
}

/// Largest `x` in `[lo, hi]` where `clear(x)` holds, given it holds at `lo` and not at `hi`
/// (or the reverse order of `lo`/`hi`), to `tol`.
fn bisect(mut clear_at: f64, mut hit_at: f64, tol: f64, mut clear: impl FnMut(f64) -> bool) -> f64 {
    assert!(
        clear(clear_at) && !clear(hit_at),
        "bisection needs a clear end and a contact end"
    );
    while (hit_at - clear_at).abs() > tol {
        let mid = 0.5 * (clear_at + hit_at);
        if clear(mid) {
            clear_at = mid;
        } else {
            hit_at = mid;
        }
    }
    0.5 * (clear_at + hit_at)
}

const NO_CRADLE: &str = "[scene]\ncradle = []\n";

#[test]
fn z_cylinder_extends_along_z() {
    let (shape, pose) = z_cylinder(10.0, 50.0, 7.0);
    let aabb = shape.compute_aabb(&pose);
    let extent = aabb.maxs - aabb.mins;
    assert!(
        (aabb.mins.z - 10.0).abs() < 1e-12 && (aabb.maxs.z - 50.0).abs() < 1e-12,
        "{aabb:?}"
    );
    assert!(
        (extent.x - 14.0).abs() < 1e-12 && (extent.y - 14.0).abs() < 1e-12,
        "{aabb:?}"
    );
}

/// Cone with a vertical axis (inclination 0) on the table's C axis, 30 mm high.
fn upright_frustum() -> WorkpieceConfig {
    WorkpieceConfig {
        kind: WorkpieceKind::ConeFrustum,
        top_height_mm: Some(30.0),
        cone: ConeSetup {
            half_apex_deg: 15.0,
            inclination_deg: 0.0,
            center_mm: [0.0, 0.0, 200.0],
            ballbar_length_mm: 100.0,
        },
        ..WorkpieceConfig::default()
    }
}

/// The tool beside the frustum: the cutter clears the frustum's widest circle (radius
/// (L - R) / cos(alpha)) by 3 mm, while the 50 mm holder overhangs the top face.
fn beside_frustum_x(tool: &ToolConfig) -> f64 {
    let r_cutter = 0.5 * tool.cutter_diameter_mm;
    (100.0 - r_cutter) / 15f64.to_radians().cos() + r_cutter + 3.0
}

#[test]
fn holder_meets_the_frustum_top_where_the_stack_lengths_say() {
    let m = machine(NO_CRADLE);
    let tool = ToolConfig::default();
    let mut scene = Scene::new(&m, &tool, &upright_frustum(), 2.0).unwrap();
    let x = beside_frustum_x(&tool);
    // The top face is at table z = 200 + 30 (= machine z, as A = C = 0 and the pivot is at
    // the origin); the holder's bottom face is gauge - holder length = 80 mm above the tip,
    // so it lands on the top face when the tip is 80 mm below it.
    let contact_z = 230.0 - (tool.gauge_length_mm - tool.holder_length_mm);
    for gap in [0.5, 1.0, 5.0] {
        let d = distance(
            &mut scene,
            q(x, 0.0, contact_z + gap, 0.0, 0.0),
            "holder",
            "workpiece",
        );
        assert!((d - gap).abs() < 1e-6, "gap {gap}: distance {d}");
    }
    let found = bisect(contact_z + 10.0, contact_z - 10.0, 1e-9, |z| {
        distance(&mut scene, q(x, 0.0, z, 0.0, 0.0), "holder", "workpiece") > 0.0
    });
    assert!(
        (found - contact_z).abs() < 1e-6,
        "contact at Z = {found}, expected {contact_z}"
    );
    // Nothing else touches on the way down to the contact.
    scene.set_axes(&q(x, 0.0, contact_z + 1e-3, 0.0, 0.0));
    for pair in scene.clearances() {
        assert!(pair.distance_mm > 0.0, "{pair:?}");
    }
}

#[test]
fn tilting_the_table_swings_its_rim_into_the_cutter_at_the_closed_form_angle() {
    // Table: radius 200, top at z = 20, thickness 60. Cutter (radius 10) tip at (0, 190, 60).
    let m = machine("[scene]\ncradle = []\n[scene.table]\ntop_z_mm = 20.0\nradius_mm = 200.0\nthickness_mm = 60.0\n");
    let none = WorkpieceConfig {
        kind: WorkpieceKind::None,
        ..WorkpieceConfig::default()
    };
    let mut scene = Scene::new(&m, &ToolConfig::default(), &none, 2.0).unwrap();
    // Rx(A) lifts the rim point (0, 200, 20) to z = 200 sin A + 20 cos A; it meets the cutter's
    // bottom face (z = 60) when sqrt(200^2 + 20^2) sin(A + atan2(20, 200)) = 60, at machine
    // y = 200 cos A - 20 sin A, which lies under the face (180..200).
    let expected =
        (60.0 / 200f64.hypot(20.0)).asin().to_degrees() - 20f64.atan2(200.0).to_degrees();
    let a = expected.to_radians();
    let rim_y = 200.0 * a.cos() - 20.0 * a.sin();
    assert!((180.0..200.0).contains(&rim_y));
    let found = bisect(0.0, 30.0, 1e-7, |a| {
        distance(&mut scene, q(0.0, 190.0, 60.0, a, 0.0), "cutter", "table") > 0.0
    });
    assert!(
        (found - expected).abs() < 0.01,
        "first contact at A = {found} deg, expected {expected} deg"
    );
}

/// The cone test's commanded axes at `theta_deg`, by the spec's inverse kinematics (pivot at
/// the origin): P = O + Ry(-beta)(r cos, r sin, h), t = unit(apex - P), A = acos(k),
/// C = atan2(i, j) unwrapped near `prev_c`, (X, Y, Z) = Rx(A) Rz(C) P.
fn cone_axes(cone: &ConeSetup, theta_deg: f64, prev_c: f64) -> AxisVec {
    let (al, be, th) = (
        cone.half_apex_deg.to_radians(),
        cone.inclination_deg.to_radians(),
        theta_deg.to_radians(),
    );
    let l = cone.ballbar_length_mm;
    let ry = |v: [f64; 3]| {
        [
            v[0] * be.cos() - v[2] * be.sin(),
            v[1],
            v[0] * be.sin() + v[2] * be.cos(),
        ]
    };
    let o = cone.center_mm;
    let local = ry([
        l * al.cos() * th.cos(),
        l * al.cos() * th.sin(),
        l * al.sin(),
    ]);
    let p = [o[0] + local[0], o[1] + local[1], o[2] + local[2]];
    let apex_local = ry([0.0, 0.0, l / al.sin()]);
    let d = [
        o[0] + apex_local[0] - p[0],
        o[1] + apex_local[1] - p[1],
        o[2] + apex_local[2] - p[2],
    ];
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let t = [d[0] / n, d[1] / n, d[2] / n];
    let a = t[2].acos();
    let mut c = t[0].atan2(t[1]).to_degrees();
    c += 360.0 * ((prev_c - c) / 360.0).round();
    let cr = c.to_radians();
    let u = [
        p[0] * cr.cos() - p[1] * cr.sin(),
        p[0] * cr.sin() + p[1] * cr.cos(),
        p[2],
    ];
    q(
        u[0],
        u[1] * a.cos() - u[2] * a.sin(),
        u[1] * a.sin() + u[2] * a.cos(),
        a.to_degrees(),
        c,
    )
}

fn run_cone(alpha: f64, beta: f64) {
    let m = machine(""); // default [scene] and [tool]
    let cone = ConeSetup {
        half_apex_deg: alpha,
        inclination_deg: beta,
        center_mm: [0.0, 0.0, 200.0],
        ballbar_length_mm: 100.0,
    };
    let workpiece = WorkpieceConfig {
        cone,
        ..WorkpieceConfig::default()
    };
    let mut scene = Scene::new(&m, &m.tool, &workpiece, 2.0).unwrap();
    // 1-deg steps: every collision pair clear of the threshold; the flank tangent.
    let mut c = 0.0;
    let mut tightest = f64::INFINITY;
    for step in 0..=360 {
        let at = cone_axes(&cone, step as f64, c);
        c = at[Axis::C];
        scene.set_axes(&at);
        for pair in scene.clearances() {
            match pair.kind {
                PairKind::Cutting => assert!(
                    pair.distance_mm.abs() < 1e-4,
                    "{alpha}/{beta} at {step} deg: {pair:?}"
                ),
                PairKind::Collision => {
                    assert!(
                        pair.distance_mm > 2.0,
                        "{alpha}/{beta} at {step} deg: {pair:?}"
                    );
                    tightest = tightest.min(pair.distance_mm);
                }
            }
        }
    }
    // 1-ms stream at F1000 around the measured circle (chord 2 pi r per 360 deg).
    let circumference = 2.0 * std::f64::consts::PI * 100.0 * alpha.to_radians().cos();
    let samples = (circumference / 1000.0 * 60.0 * 1000.0).round() as usize;
    let mut monitor = SceneMonitor::new(Scene::new(&m, &m.tool, &workpiece, 2.0).unwrap(), &m);
    let mut c = 0.0;
    for k in 0..=samples {
        let theta = 360.0 * k as f64 / samples as f64;
        let at = cone_axes(&cone, theta, c);
        c = at[Axis::C];
        monitor.push(k as f64 * 1e-3, Some(theta), 1 + k * 360 / samples, &at);
    }
    let report = monitor.finish();
    eprintln!(
        "{alpha}/{beta}: {} samples, {} queries ({:.4} per sample), tightest clearance {tightest:.2} mm, max engagement {:.2e} mm",
        report.samples,
        report.queries,
        report.queries as f64 / report.samples as f64,
        report.engagement[0].max_depth_mm
    );
    assert!(report.events.is_empty(), "{:?}", report.events);
    assert_eq!(report.engagement.len(), 1);
    assert!(
        report.engagement[0].max_depth_mm < 1e-4,
        "{:?}",
        report.engagement
    );
    assert!(
        report.queries < report.samples / 5,
        "conservative advancement should skip most samples"
    );

    // Collision pairs alone (engagement tracking off): about one query per 40 samples or fewer.
    let collisions_only = machine("[scene]\nengagement_resolution_mm = 1e9\n");
    let mut monitor = SceneMonitor::new(
        Scene::new(&collisions_only, &m.tool, &workpiece, 2.0).unwrap(),
        &m,
    );
    let mut c = 0.0;
    for k in 0..=samples {
        let at = cone_axes(&cone, 360.0 * k as f64 / samples as f64, c);
        c = at[Axis::C];
        monitor.push(k as f64 * 1e-3, None, k, &at);
    }
    let report = monitor.finish();
    eprintln!(
        "{alpha}/{beta} collision pairs only: {} queries",
        report.queries
    );
    assert!(report.events.is_empty());
    assert!(
        report.queries < report.samples / 40,
        "{} queries for {} samples",
        report.queries,
        report.samples
    );
}

#[test]
fn cone_15_10_runs_clean_with_a_tangent_flank() {
    run_cone(15.0, 10.0);
}

#[test]
fn cone_45_30_runs_clean_with_a_tangent_flank() {
    run_cone(45.0, 30.0);
}

#[test]
fn near_miss_threshold_is_honoured() {
    let m = machine(NO_CRADLE);
    let tool = ToolConfig::default();
    let x = beside_frustum_x(&tool);
    let at = q(x, 0.0, 150.0 + 1.5, 0.0, 0.0); // holder 1.5 mm above the frustum top
    let near_misses = |threshold: f64| {
        let scene = Scene::new(&m, &tool, &upright_frustum(), threshold).unwrap();
        let mut monitor = SceneMonitor::new(scene, &m);
        for k in 0..5 {
            monitor.push(k as f64 * 1e-3, None, 7, &at);
        }
        let report = monitor.finish();
        assert_eq!(report.collisions().count(), 0);
        report.near_misses().cloned().collect::<Vec<_>>()
    };
    let at_2 = near_misses(2.0);
    assert_eq!(at_2.len(), 1, "{at_2:?}");
    assert_eq!(
        at_2[0].bodies,
        ["holder".to_string(), "workpiece".to_string()]
    );
    assert!((at_2[0].worst_mm - 1.5).abs() < 1e-6);
    assert_eq!(
        (at_2[0].time_start_s, at_2[0].time_end_s, at_2[0].line),
        (0.0, 4e-3, 7)
    );
    assert!(near_misses(1.0).is_empty());
}

#[test]
fn monitor_finds_the_brute_force_first_contact_with_fewer_queries() {
    let m = machine(NO_CRADLE);
    let tool = ToolConfig::default();
    let x0 = beside_frustum_x(&tool);
    // 2 s at 1 ms: the tool comes down 21 mm and in 4 mm while C turns 30 deg; the holder
    // meets the frustum top (tip Z = 150) on the way.
    let path = |k: usize| {
        let s = k as f64 / 2000.0;
        q(
            x0 + 4.0 * (1.0 - s),
            0.0,
            150.0 + 20.0 - 21.0 * s,
            0.0,
            30.0 * s,
        )
    };
    let mut brute = Scene::new(&m, &tool, &upright_frustum(), 2.0).unwrap();
    let pairs = brute.pair_names().len() as u64;
    let first_contact = (0..=2000)
        .find(|&k| {
            brute.set_axes(&path(k));
            brute
                .clearances()
                .iter()
                .any(|p| p.kind == PairKind::Collision && p.distance_mm <= 0.0)
        })
        .expect("the path collides");
    let mut monitor =
        SceneMonitor::new(Scene::new(&m, &tool, &upright_frustum(), 2.0).unwrap(), &m);
    for k in 0..=2000 {
        monitor.push(k as f64 * 1e-3, None, k, &path(k));
    }
    let report = monitor.finish();
    let first = report
        .collisions()
        .next()
        .expect("monitor reports the collision");
    assert_eq!(first.line, first_contact);
    assert_eq!(
        first.bodies,
        ["holder".to_string(), "workpiece".to_string()]
    );
    let brute_queries = 2001 * pairs;
    eprintln!(
        "first contact at sample {first_contact}: monitor {} queries, brute force {brute_queries}",
        report.queries
    );
    assert!(
        report.queries < brute_queries / 5,
        "{} vs {brute_queries}",
        report.queries
    );
}

#[test]
fn contact_between_two_clear_samples_is_found() {
    // A = 15 deg lifts the table rim into the cutter's height at X = 0, but not at X = +-150:
    // one sample on each side, clear at both, with the cutter sweeping through the rim between.
    let m = machine("[scene]\ncradle = []\n[scene.table]\ntop_z_mm = 20.0\nradius_mm = 200.0\n");
    let none = WorkpieceConfig {
        kind: WorkpieceKind::None,
        ..WorkpieceConfig::default()
    };
    let mut scene = Scene::new(&m, &ToolConfig::default(), &none, 2.0).unwrap();
    let (before, after) = (
        q(-150.0, 190.0, 60.0, 15.0, 0.0),
        q(150.0, 190.0, 60.0, 15.0, 0.0),
    );
    assert!(distance(&mut scene, before, "cutter", "table") > 2.0);
    assert!(distance(&mut scene, after, "cutter", "table") > 2.0);
    assert!(
        distance(
            &mut scene,
            q(0.0, 190.0, 60.0, 15.0, 0.0),
            "cutter",
            "table"
        ) < 0.0
    );
    let mut monitor = SceneMonitor::new(scene, &m);
    monitor.push(0.0, None, 1, &before);
    monitor.push(1e-3, None, 2, &after);
    let report = monitor.finish();
    let hit = report.collisions().next().expect("swept contact found");
    assert_eq!(hit.bodies, ["table".to_string(), "cutter".to_string()]);
    assert!(hit.time_start_s > 0.0 && hit.time_start_s < 1e-3, "{hit:?}");
}

#[test]
fn scene_tables_reject_unknown_keys_and_bad_lengths() {
    let text = "name = \"m\"\nkinematics = \"xyz\"\n[axes.X]\nmin=-1.0\nmax=1.0\nmax_velocity=1.0\nmax_acceleration=1.0\nmax_jerk=1.0\n[axes.Y]\nmin=-1.0\nmax=1.0\nmax_velocity=1.0\nmax_acceleration=1.0\nmax_jerk=1.0\n[axes.Z]\nmin=-1.0\nmax=1.0\nmax_velocity=1.0\nmax_acceleration=1.0\nmax_jerk=1.0\n";
    let unknown = format!("{text}[scene.table]\nradius = 3.0\n");
    let err = Machine::from_toml(Path::new("m.toml"), &unknown, None)
        .unwrap_err()
        .to_string();
    assert!(err.contains("radius"), "{err}");
    let bad = format!("{text}[tool]\ncutter_diameter_mm = -4.0\n");
    let err = Machine::from_toml(Path::new("m.toml"), &bad, None)
        .unwrap_err()
        .to_string();
    let line = bad
        .lines()
        .position(|l| l.starts_with("cutter_diameter_mm"))
        .unwrap()
        + 1;
    assert!(
        err.starts_with(&format!("m.toml:{line}:"))
            && err.contains("cutter_diameter_mm")
            && err.contains("positive"),
        "{err}"
    );
    let short_shank = format!("{text}[tool]\nshank_length_mm = 10.0\n");
    let err = Machine::from_toml(Path::new("m.toml"), &short_shank, None)
        .unwrap_err()
        .to_string();
    assert!(err.contains("do not reach the holder"), "{err}");
    let m = Machine::from_toml(Path::new("m.toml"), text, None).unwrap();
    let nan_cone = WorkpieceConfig {
        cone: ConeSetup {
            half_apex_deg: f64::NAN,
            ..ConeSetup::default()
        },
        ..WorkpieceConfig::default()
    };
    assert!(Scene::new(&m, &ToolConfig::default(), &nan_cone, 2.0).is_err());
    assert!(Scene::new(
        &m,
        &ToolConfig::default(),
        &WorkpieceConfig::default(),
        f64::NAN
    )
    .is_err());
}

#[test]
fn ball_bar_pairs_join_the_balls_to_the_bar_and_run_clean_on_both_cones() {
    let m = machine("");
    for (alpha, beta) in [(15.0, 10.0), (45.0, 30.0)] {
        let cone = ConeSetup {
            half_apex_deg: alpha,
            inclination_deg: beta,
            center_mm: [0.0, 0.0, 200.0],
            ballbar_length_mm: 100.0,
        };
        let workpiece = WorkpieceConfig {
            kind: WorkpieceKind::BallBar,
            cone,
            ..WorkpieceConfig::default()
        };
        let mut scene = Scene::new(&m, &m.tool, &workpiece, 2.0).unwrap();
        let names = scene.pair_names();
        let has = |a: &str, b: &str| {
            names
                .iter()
                .any(|n| (n[0] == a && n[1] == b) || (n[0] == b && n[1] == a))
        };
        assert!(has("bar", "holder") && has("bar", "spindle") && has("bar", "table"));
        assert!(has("tool ball", "table") && has("holder", "pivot ball"));
        assert!(
            !has("bar", "pivot ball") && !has("bar", "tool ball") && !has("shank", "tool ball")
        );
        assert!(!names.iter().any(|n| n.contains(&"cutter".to_string())));
        let mut c = 0.0;
        for step in 0..=360 {
            let at = cone_axes(&cone, step as f64, c);
            c = at[Axis::C];
            scene.set_axes(&at);
            for pair in scene.clearances() {
                assert_eq!(pair.kind, PairKind::Collision);
                assert!(
                    pair.distance_mm > 2.0,
                    "{alpha}/{beta} at {step} deg: {pair:?}"
                );
            }
        }
    }
}
