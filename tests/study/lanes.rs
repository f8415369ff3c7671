//! Many points at once (`study::lanes`): every point's figures are those of its own single
//! run, bit for bit, whatever the grouping; points that differ in their program are not
//! grouped.

use std::path::{Path, PathBuf};

use mtsim::drive::DriveLanes;
use mtsim::input::scenario::Scenario;
use mtsim::input::Machine;
use mtsim::study::lanes::{passes, run_ballbar_lanes};
use mtsim::study::simulate::{run_ballbar, BallbarStudy};
use mtsim::{Axis, AxisVec};

use crate::common::{machine, scratch};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Loads `base` (a bundled scenario's text, or a body after `machine = ...`) with `extra`
/// appended, written as `dir/<name>.toml`.
fn load(dir: &Path, name: &str, base: &str, extra: &str) -> Scenario {
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, format!("{base}\n{extra}")).unwrap();
    Scenario::load(&path).unwrap()
}

/// A bundled scenario's text with its machine and program paths made absolute.
fn bundled(name: &str) -> String {
    let text = std::fs::read_to_string(root().join("scenarios").join(name)).unwrap();
    text.replace(
        "\"../machines/",
        &format!("\"{}/machines/", root().display()),
    )
    .replace(
        "\"programs/",
        &format!("\"{}/scenarios/programs/", root().display()),
    )
}

/// Overrides of one linear axis: backlash, Coulomb friction, kv, velocity feedforward.
fn axis(a: &str, backlash_mm: f64, coulomb_n: f64, kv: f64, vff: f64) -> String {
    format!(
        "[machine_overrides.axes.{a}.drive]\nbacklash_mm = {backlash_mm}\n\
         [machine_overrides.axes.{a}.friction]\ncoulomb_n = {coulomb_n}\n\
         [machine_overrides.axes.{a}.servo]\nkv_per_s = {kv}\nvelocity_feedforward = {vff}\n"
    )
}

/// The figures of a study that `result()` and the sites give, in full precision, with each
/// axis's reversal value B (`study::lost_motion`: in lanes, its fit's regressors are shared
/// by the points of a pass with the same lost-motion axes).
fn figures(s: &BallbarStudy) -> String {
    let traces: Vec<_> = s.runs.iter().map(|r| r.trace_um(false).unwrap()).collect();
    format!(
        "{:?}\n{:?}\n{:?}\n{:?}\n{:?}\n{:?} {:?} {:?}\n{:?}",
        s.result().unwrap(),
        s.lost_motion_b,
        s.sites,
        s.reversals,
        s.warnings,
        s.sim_time_s.to_bits(),
        s.setpoints,
        s.directions,
        traces
    )
}

/// Runs the batch both ways and asserts each point's figures are its single run's.
fn assert_lanes_equal_single_runs(scenarios: &[Scenario]) {
    let lanes = run_ballbar_lanes(scenarios, &|_| {});
    assert_eq!(lanes.len(), scenarios.len());
    for (i, (scenario, lane)) in scenarios.iter().zip(lanes).enumerate() {
        let single = run_ballbar(scenario, None, &|_| {}).unwrap();
        let lane = lane.unwrap();
        assert_eq!(figures(&lane), figures(&single), "point {i}");
        // The points differ: a G that did not move would test nothing.
        assert!(single.result().unwrap().is_some(), "point {i} measured");
    }
}

/// G of each point, µm.
fn g_um(scenarios: &[Scenario]) -> Vec<f64> {
    run_ballbar_lanes(scenarios, &|_| {})
        .into_iter()
        .map(|s| s.unwrap().result().unwrap().unwrap().circular_deviation_um)
        .collect()
}

fn cone_points(dir: &Path) -> Vec<Scenario> {
    let base = bundled("cone-15-10.toml");
    let sets = [
        (0.0, 0.0, 0.0, 150.0, 150.0, 30.0, 0.0, ""),
        (0.004, 0.0, 0.0, 150.0, 150.0, 30.0, 0.0, ""),
        (0.004, 0.002, 200.0, 150.0, 100.0, 30.0, 0.0, ""),
        (0.002, 0.006, 200.0, 250.0, 150.0, 45.0, 0.5, ""),
        (0.0, 0.003, 0.0, 0.0, 150.0, 25.0, 1.0, ""),
        (
            0.003,
            0.003,
            150.0,
            150.0,
            150.0,
            30.0,
            0.0,
            "[machine_overrides.location_errors]\nEX0C_um = 8.0\n",
        ),
        (0.001, 0.0, 300.0, 50.0, 100.0, 60.0, 0.8, ""),
    ];
    sets.iter()
        .enumerate()
        .map(|(i, &(bx, by, fx, fy, _fz, kv, vff, extra))| {
            let over = axis("X", bx, fx, kv, vff) + &axis("Y", by, fy, kv * 1.1, vff) + extra;
            load(dir, &format!("cone{i}"), &base, &over)
        })
        .collect()
}

#[test]
fn cone_points_in_lanes_give_their_single_runs_figures_bit_for_bit() {
    let dir = scratch("lanes", "cone");
    let points = cone_points(&dir);
    // Six of the seven share the program; the one with a location error is its own group.
    let groups = passes(&points, 1);
    assert_eq!(groups, vec![vec![0, 1, 2, 3, 4, 6], vec![5]]);
    assert_lanes_equal_single_runs(&points);
    // Backlash on X moves G: the points are not the same point.
    let g = g_um(&points[..2]);
    assert!(g[1] > g[0] + 1.0, "G {g:?}");
}

#[test]
fn circle_points_in_lanes_give_their_single_runs_figures() {
    let dir = scratch("lanes", "circle");
    let base = bundled("circle-iso230-4.toml");
    let points: Vec<Scenario> = [
        (0.0, 150.0, 30.0, 0.0),
        (0.005, 150.0, 30.0, 0.0),
        (0.005, 0.0, 30.0, 0.5),
        (0.002, 250.0, 30.0, 1.0),
        (0.01, 100.0, 35.0, 0.0),
    ]
    .iter()
    .enumerate()
    .map(|(i, &(b, fc, kv, vff))| {
        let over = axis("X", b, fc, kv, vff) + &axis("Y", b / 2.0, fc, kv, vff);
        load(&dir, &format!("circle{i}"), &base, &over)
    })
    .collect();
    // A circle's lead-in holds time constants of its loops (`input::lead_in`): another kv
    // is another lead arc, another program, so the last point is a group of its own.
    assert_eq!(passes(&points, 1), vec![vec![0, 1, 2, 3], vec![4]]);
    assert_lanes_equal_single_runs(&points);
}

#[test]
fn g_code_file_points_in_lanes_give_their_single_runs_figures() {
    let dir = scratch("lanes", "file");
    let base = bundled("file-cone-15-10-yt25.toml");
    let points: Vec<Scenario> = [(0.0, 150.0, 30.0), (0.004, 200.0, 30.0), (0.002, 0.0, 45.0)]
        .iter()
        .enumerate()
        .map(|(i, &(b, fc, kv))| {
            let over = axis("X", b, fc, kv, 0.0) + &axis("Y", b, fc, kv, 0.0);
            load(&dir, &format!("file{i}"), &base, &over)
        })
        .collect();
    assert_eq!(passes(&points, 1).len(), 1);
    assert_lanes_equal_single_runs(&points);
}

/// Scenarios that differ in feed or geometry run different setpoints: they are not grouped,
/// and a mixed batch of 11 points (no multiple of 4 or 8) still gives every single result,
/// on a pool of one thread and on two.
#[test]
fn points_that_differ_in_feed_or_geometry_are_not_grouped_and_a_mixed_batch_is_exact() {
    let dir = scratch("lanes", "split");
    let cone = bundled("cone-15-10.toml");
    let slow = cone.replace("feed_mm_min = 1000.0", "feed_mm_min = 800.0");
    let moved = cone.replace(
        "center_mm = [0.0, 0.0, 200.0]",
        "center_mm = [0.0, 10.0, 200.0]",
    );
    assert_ne!(slow, cone);
    assert_ne!(moved, cone);
    let circle = bundled("circle-iso230-4.toml");
    let vmc = format!("machine = {:?}\n", machine("vmc-3axis"));
    assert!(circle.contains("vmc-3axis"), "{vmc}");
    let mut points = Vec::new();
    for (i, b) in [0.0, 0.003, 0.006].iter().enumerate() {
        let over = axis("X", *b, 150.0, 30.0, 0.0);
        points.push(load(&dir, &format!("c{i}"), &cone, &over));
        points.push(load(&dir, &format!("s{i}"), &slow, &over));
        points.push(load(&dir, &format!("m{i}"), &moved, &over));
    }
    for (i, b) in [0.0, 0.004].iter().enumerate() {
        let over = axis("Y", *b, 150.0, 30.0, 0.0);
        points.push(load(&dir, &format!("r{i}"), &circle, &over));
    }
    assert_eq!(points.len(), 11);
    assert_eq!(
        passes(&points, 1),
        vec![vec![0, 3, 6], vec![1, 4, 7], vec![2, 5, 8], vec![9, 10]]
    );
    // Two threads cut a group of three into passes of two and one.
    assert_eq!(passes(&points, 2)[..2], [vec![0, 3], vec![6]]);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| assert_lanes_equal_single_runs(&points));
    }
    // The slower feed is a different test: its G differs from the grouped cone's.
    let g = g_um(&points[..2]);
    assert!(g[0] != g[1], "G {g:?}");
}

/// The distinct servos a pass steps per axis, drives and twins, for these scenarios.
fn distinct(points: &[Scenario]) -> Vec<(Axis, usize, usize)> {
    let machines: Vec<&Machine> = points.iter().map(|s| &s.machine).collect();
    DriveLanes::new(&machines, &AxisVec::ZERO)
        .unwrap()
        .distinct()
}

/// Points that differ on one axis only step one servo per point on that axis and one for
/// all on every other, and still give their single runs' figures; a kv that differs on X
/// alone gives X one twin per kv, the other axes one.
#[test]
fn points_that_differ_on_one_axis_share_the_others_servos_and_are_exact() {
    let dir = scratch("lanes", "one-axis");
    let base = bundled("cone-15-10.toml");
    let backlash: Vec<Scenario> = [0.0, 0.002, 0.005]
        .iter()
        .enumerate()
        .map(|(i, &b)| {
            let over = format!("[machine_overrides.axes.Y.drive]\nbacklash_mm = {b}\n");
            load(&dir, &format!("y{i}"), &base, &over)
        })
        .collect();
    assert_eq!(
        distinct(&backlash),
        vec![
            (Axis::X, 1, 1),
            (Axis::Y, 3, 1),
            (Axis::Z, 1, 1),
            (Axis::A, 1, 1),
            (Axis::C, 1, 1)
        ]
    );
    assert_lanes_equal_single_runs(&backlash);
    let kv: Vec<Scenario> = [25.0, 30.0, 30.0, 35.0]
        .iter()
        .enumerate()
        .map(|(i, &kv)| {
            let over = format!("[machine_overrides.axes.X.servo]\nkv_per_s = {kv}\n");
            load(&dir, &format!("x{i}"), &base, &over)
        })
        .collect();
    assert_eq!(distinct(&kv)[0], (Axis::X, 3, 3));
    assert!(distinct(&kv)[1..].iter().all(|&(_, d, t)| (d, t) == (1, 1)));
    assert_lanes_equal_single_runs(&kv);
    // Y's backlash moves G: the shared servos did not hide the differing one.
    let g = g_um(&backlash);
    assert!(g[2] > g[0] + 1.0, "G {g:?}");
}

/// A point whose drive on one axis fails (its following error passes its limit) is run
/// alone and gives its single run's error, and so do the points that share that drive; the
/// points beside them that share the other axes' servos keep their single runs' figures.
#[test]
fn a_point_whose_drive_fails_on_one_axis_gives_its_single_runs_error() {
    let dir = scratch("lanes", "fail");
    // The cone at 1000 mm/min lags X by about v / kv = 0.5 mm: a 1 µm limit fails.
    let tight = "[machine_overrides.axes.X.servo]\nfollowing_error_limit_mm = 0.001\n";
    let rotary = "[machine_overrides.axes.C.servo]\nfollowing_error_limit_deg = 0.0001\n";
    let points = [
        (0.0, ""),
        (0.002, tight),
        (0.004, tight),
        (0.003, ""),
        (0.001, rotary),
    ];
    let (points, lanes) = y_backlash_pass(&dir, &points);
    for (i, (scenario, lane)) in points.iter().zip(lanes).enumerate() {
        let single = run_ballbar(scenario, None, &|_| {});
        match (i, lane, single) {
            (0 | 3, Ok(lane), Ok(single)) => assert_eq!(figures(&lane), figures(&single)),
            (1 | 2 | 4, Err(lane), Err(single)) => {
                let (lane, single) = (lane.to_string(), single.to_string());
                assert_eq!(lane, single, "point {i}");
                let axis = if i == 4 { "C" } else { "X" };
                assert!(
                    lane.contains("following error") && lane.contains(axis),
                    "{lane}"
                );
            }
            (i, lane, single) => panic!(
                "point {i}: lanes {:?}, single {:?}",
                lane.map(|_| ()),
                single.map(|_| ())
            ),
        }
    }
}

/// Points of the bundled 15/10 cone with Y backlash (mm) and extra overrides, one pass, and
/// their lanes' studies.
fn y_backlash_pass(
    dir: &Path,
    sets: &[(f64, &str)],
) -> (Vec<Scenario>, Vec<mtsim::Result<BallbarStudy>>) {
    let base = bundled("cone-15-10.toml");
    let points: Vec<Scenario> = sets
        .iter()
        .enumerate()
        .map(|(i, &(b, extra))| {
            let over = format!("[machine_overrides.axes.Y.drive]\nbacklash_mm = {b}\n{extra}");
            load(dir, &format!("f{i}"), &base, &over)
        })
        .collect();
    assert_eq!(passes(&points, 1).len(), 1);
    let lanes = run_ballbar_lanes(&points, &|_| {});
    (points, lanes)
}

/// The pass's first point fails in its first block: the others' reversal sites (from the
/// command maps their pass keeps once) are still their single runs'.
#[test]
fn a_pass_whose_first_point_fails_gives_the_others_their_single_runs_sites() {
    let dir = scratch("lanes", "fail-first");
    let tight = "[machine_overrides.axes.X.servo]\nfollowing_error_limit_mm = 0.001\n";
    let (points, lanes) = y_backlash_pass(&dir, &[(0.002, tight), (0.0, ""), (0.003, "")]);
    assert!(lanes[0].is_err());
    for (i, (scenario, lane)) in points.iter().zip(lanes).enumerate().skip(1) {
        let single = run_ballbar(scenario, None, &|_| {}).unwrap();
        let lane = lane.unwrap();
        assert!(!single.sites.is_empty(), "point {i} has sites");
        assert_eq!(figures(&lane), figures(&single), "point {i}");
    }
}

/// A grid of X and Y backlash (10 × 10) at 10 kv values, kv outermost, on 2 threads: 20
/// passes of 50 points, each within one kv (its X and Y drives 10 and 5), not 16 of 62-63
/// of which half straddle two kv (20 X drives).
#[test]
fn a_grid_is_cut_into_passes_that_each_hold_one_kv() {
    let dir = scratch("lanes", "grid-passes");
    let base = load(&dir, "base", &bundled("cone-15-10.toml"), "");
    let points: Vec<Scenario> = (0..1000)
        .map(|i| {
            let mut s = base.clone();
            for (axis, b) in [(Axis::X, i % 10), (Axis::Y, (i / 10) % 10)] {
                let d = s.machine.drive(axis);
                let d = d.with_backlash_mm_or_deg(b as f64 * 1e-3).unwrap();
                s.machine.axis_mut(axis).drive = d.with_kv_per_s(25.0 + (i / 100) as f64).unwrap();
            }
            s
        })
        .collect();
    let expected: Vec<Vec<usize>> = (0..20).map(|k| (50 * k..50 * k + 50).collect()).collect();
    assert_eq!(passes(&points, 2), expected);
    // One thread: 16 passes are the fewest; 20 of one kv each are still cheaper.
    assert_eq!(passes(&points, 1), expected);
}

/// Points on a machine with position-error tables (pitch on X and Y, a worm-gear error on
/// C): each point's errors, applied for its own direction of motion, are its single run's.
#[test]
fn points_with_position_error_tables_give_their_single_runs_figures() {
    let dir = scratch("lanes", "tables");
    std::fs::write(
        dir.join("x.comp"),
        "-200 -0.004 0.003\n0 0 0.002\n200 0.006 0.001\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("c.comp"),
        "0 0 0.001\n180 0.002 -0.001\n360 0 0.001\n",
    )
    .unwrap();
    let machine_text = std::fs::read_to_string(root().join("machines/trt-ac.toml")).unwrap();
    let machine_path = dir.join("m.toml");
    std::fs::write(
        &machine_path,
        format!("{machine_text}\n[error_tables]\nX = \"x.comp\"\nY = \"x.comp\"\nC = \"c.comp\"\n"),
    )
    .unwrap();
    let base = bundled("cone-15-10.toml").replace(
        &format!("\"{}/machines/trt-ac.toml\"", root().display()),
        &format!("{:?}", machine_path.display().to_string()),
    );
    assert!(base.contains("m.toml"), "{base}");
    let points: Vec<Scenario> = [(0.0, 150.0), (0.003, 150.0), (0.003, 0.0), (0.006, 300.0)]
        .iter()
        .enumerate()
        .map(|(i, &(b, fc))| load(&dir, &format!("t{i}"), &base, &axis("Y", b, fc, 30.0, 0.0)))
        .collect();
    assert_eq!(passes(&points, 1).len(), 1);
    assert_lanes_equal_single_runs(&points);
    // The tables are read: G moves against the same point without them.
    let plain = load(
        &dir,
        "plain",
        &bundled("cone-15-10.toml"),
        &axis("Y", 0.0, 150.0, 30.0, 0.0),
    );
    let with = g_um(&points[..2])[0];
    let without = g_um(&[plain.clone(), plain])[0];
    assert!(
        (with - without).abs() > 0.5,
        "G {with} with the tables, {without} without"
    );
}
