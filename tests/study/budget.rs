//! The error budget by counterfactual runs (`study::budget`), against figures computed
//! another way: the ideal machine's curve through a forward kinematics written out here, a
//! backlash row against the difference of two whole runs, the lost motion of a drive
//! against its closed form, and a gain mismatch that must own G.

use std::path::{Path, PathBuf};

use mtsim::input::scenario::Scenario;
use mtsim::measure::Direction;
use mtsim::report::run::{BudgetMechanism, BudgetRow, ErrorBudget};
use mtsim::study::param::evaluate::evaluate_group;
use mtsim::study::simulate::{run_ballbar, simulate, SimulationSummary};

use crate::common::{machine, scenario_text, scratch, trt_ac};

/// Writes and loads a scenario.
fn load(name: &str, text: &str) -> (Scenario, PathBuf) {
    let dir = scratch("budget", name);
    let path = dir.join("scenario.toml");
    std::fs::write(&path, text).unwrap();
    (Scenario::load(&path).unwrap(), dir)
}

/// Runs `simulate` on a scenario; its summary and output folder.
pub(super) fn run(name: &str, text: &str) -> (SimulationSummary, PathBuf) {
    let (scenario, dir) = load(name, text);
    let out = dir.join("out");
    let summary = simulate(&scenario, &out, false, &|_| {}).unwrap();
    (summary, out)
}

/// Overrides that leave every axis of `axes` (linear, rotary) without dry friction, with
/// `kv` (1/s) each and `extra` TOML lines appended.
pub(super) fn clean(linear: &[&str], rotary: &[&str], kv: &[(&str, f64)], extra: &str) -> String {
    let mut s = String::new();
    for a in linear.iter().chain(rotary) {
        let k = kv.iter().find(|(b, _)| b == a).map_or(30.0, |(_, k)| *k);
        let key = if rotary.contains(a) {
            "coulomb_nm"
        } else {
            "coulomb_n"
        };
        s += &format!(
            "[machine_overrides.axes.{a}.servo]\nmodel = \"cascade\"\nkv_per_s = {k}\n\
             [machine_overrides.axes.{a}.friction]\n{key} = 0.0\n"
        );
    }
    s + extra
}

pub(super) const CONE_AXES: (&[&str], &[&str]) = (&["X", "Y", "Z"], &["A", "C"]);

/// The bundled 15/10 cone (both directions) with `overrides`.
pub(super) fn cone(overrides: &str) -> String {
    scenario_text(
        &trt_ac(),
        &format!(
            "[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\ncenter_mm = [0.0, 0.0, 200.0]\n\
             ballbar_length_mm = 100.0\nsegments = 360\nfeed_mm_min = 1000.0\n{overrides}"
        ),
    )
}

/// An ISO 230-4 circle on the three-axis machine (r 50, F1000, both directions).
pub(super) fn circle(overrides: &str) -> String {
    scenario_text(
        &machine("vmc-3axis"),
        &format!(
            "[program.circle]\nplane = \"XY\"\nradius_mm = 50.0\nfeed_mm_min = 1000.0\n\
             directions = [\"ccw\", \"cw\"]\ncenter_mm = [0.0, 0.0, 100.0]\n{overrides}"
        ),
    )
}

pub(super) fn budget(s: &SimulationSummary) -> &ErrorBudget {
    s.error_budget.as_ref().expect("an error budget")
}

pub(super) fn rows<'b>(b: &'b ErrorBudget, m: BudgetMechanism) -> Vec<&'b BudgetRow> {
    b.rows.iter().filter(|r| r.mechanism == m).collect()
}

/// The direction whose revolution gives G (the first of equals).
pub(super) fn g_direction(s: &SimulationSummary) -> (usize, Direction) {
    let runs = &s.ballbar.as_ref().unwrap().runs;
    let k = (0..runs.len()).fold(0, |best, i| {
        if runs[i].circular_deviation_um > runs[best].circular_deviation_um {
            i
        } else {
            best
        }
    });
    (k, runs[k].direction)
}

/// Checks what must hold of any budget: the shares and the interplay add to 1, G is the
/// run's, and lost motion is told only of the axes that have it.
pub(super) fn assert_consistent(s: &SimulationSummary, lost_motion_axes: &[&str]) {
    let b = budget(s);
    let sum: f64 = b.rows.iter().map(|r| r.share).sum::<f64>() + b.interaction_share;
    assert!((sum - 1.0).abs() < 1e-9, "{b:?}");
    assert!(
        (b.g_um - s.ballbar.as_ref().unwrap().circular_deviation_um).abs() < 1e-12,
        "{b:?}"
    );
    for r in rows(b, BudgetMechanism::Backlash)
        .into_iter()
        .chain(rows(b, BudgetMechanism::Friction))
    {
        let axis = r.axis.as_deref().unwrap();
        assert!(
            lost_motion_axes.contains(&axis) || r.pv_um <= 0.3,
            "lost motion told of {axis}: {r:?}"
        );
    }
}

/// The clean machine's B: under 0.3 µm on every axis the bar sees.
fn assert_clean_b(s: &SimulationSummary) {
    assert!(!s.reversal_b.is_empty());
    eprintln!(
        "clean B: {:?}",
        s.reversal_b
            .iter()
            .map(|r| (&r.axis, r.b_um))
            .collect::<Vec<_>>()
    );
    for r in &s.reversal_b {
        if let Some(b) = r.b_um {
            assert!(b.abs() < 0.3, "{r:?}");
        }
    }
}

/// The `B_<axis>_um` columns `mtsim study` gives each of `texts`, run as one group of
/// points (side by side on one interpolation pass, as a study runs them).
fn study_b(name: &str, texts: &[&str]) -> Vec<Vec<(String, Option<f64>)>> {
    let scenarios: Vec<Scenario> = texts
        .iter()
        .enumerate()
        .map(|(i, t)| load(&format!("{name}-{i}"), t).0)
        .collect();
    evaluate_group(&scenarios, &|| {})
        .into_iter()
        .map(|f| f.unwrap().b_um)
        .collect()
}

/// The study's B of one point: under 0.3 µm on every axis but `lost` (which may be absent).
fn assert_study_b_clean_but(b: &[(String, Option<f64>)], lost: Option<&str>) {
    eprintln!("study B: {b:?}");
    assert!(b.iter().any(|(_, v)| v.is_some()), "{b:?}");
    for (axis, v) in b.iter().filter(|(a, _)| Some(a.as_str()) != lost) {
        assert!(v.is_none_or(|v| v.abs() < 0.3), "{axis}: {v:?}");
    }
}

/// The trace's rows of one direction: θ (deg) and the commanded X Y Z A C.
pub(super) fn commanded_rows(out: &Path, direction: Direction) -> Vec<(f64, [f64; 5])> {
    let mut r = csv::Reader::from_path(out.join("trace.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let col = |name: &str| h.iter().position(|c| c == name).unwrap();
    let name = format!("{direction:?}").to_lowercase();
    let cols = [
        col("X_cmd_mm"),
        col("Y_cmd_mm"),
        col("Z_cmd_mm"),
        col("A_cmd_deg"),
        col("C_cmd_deg"),
    ];
    let (d, t) = (col("direction"), col("theta_deg"));
    r.records()
        .map(|rec| rec.unwrap())
        .filter(|rec| rec[d] == name)
        .map(|rec| {
            (
                rec[t].parse().unwrap(),
                cols.map(|c| rec[c].parse().unwrap()),
            )
        })
        .collect()
}

/// The bar's reading of commanded positions on trt-ac, written out: the table ball
/// `p = (0, 0, 200)` (table frame) goes to `Rx(A) Rz(C) p` (the pivot at the origin), the
/// tool ball is at X Y Z, and `dL = |tool − ball| − L`, µm.
pub(super) fn trt_ac_reading([x, y, z, a, c]: [f64; 5], length_mm: f64) -> f64 {
    let (p_x, p_y, p_z) = (0.0, 0.0, 200.0);
    let (sc, cc) = c.to_radians().sin_cos();
    let (sa, ca) = a.to_radians().sin_cos();
    // Rz(C) p, then Rx(A).
    let (x1, y1, z1) = (cc * p_x - sc * p_y, sc * p_x + cc * p_y, p_z);
    let ball = (x1, ca * y1 - sa * z1, sa * y1 + ca * z1);
    let d = ((x - ball.0).powi(2) + (y - ball.1).powi(2) + (z - ball.2).powi(2)).sqrt();
    (d - length_mm) * 1e3
}

/// Peak-to-valley of `(θ deg, dL µm)` samples after removing their least-squares circle
/// centre `r0 + a cos θ + b sin θ`, over bins of 0.05°.
pub(super) fn centred_peak_to_valley(samples: &[(f64, f64)]) -> f64 {
    // Normal equations of (1, cos, sin).
    let mut m = [[0.0f64; 3]; 3];
    let mut v = [0.0f64; 3];
    for &(t, d) in samples {
        let phi = [1.0, t.to_radians().cos(), t.to_radians().sin()];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += phi[i] * phi[j];
            }
            v[i] += phi[i] * d;
        }
    }
    let fit = solve3(m, v);
    let mut bins = vec![(0.0, 0u32); 7200];
    for &(t, d) in samples {
        let r = d - fit[1] * t.to_radians().cos() - fit[2] * t.to_radians().sin();
        let i = ((t.rem_euclid(360.0) / 0.05) as usize).min(7199);
        bins[i].0 += r;
        bins[i].1 += 1;
    }
    let means: Vec<f64> = bins
        .iter()
        .filter(|b| b.1 > 0)
        .map(|b| b.0 / b.1 as f64)
        .collect();
    let (lo, hi) = means
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
            (l.min(x), h.max(x))
        });
    hi - lo
}

/// Solves a 3×3 system by Cramer's rule.
fn solve3(m: [[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(m);
    let mut x = [0.0; 3];
    for (k, xk) in x.iter_mut().enumerate() {
        let mut mk = m;
        for i in 0..3 {
            mk[i][k] = v[i];
        }
        *xk = det(mk) / d;
    }
    x
}

#[test]
fn a_clean_cone_tells_of_no_lost_motion_and_its_program_row_is_the_commanded_path() {
    let (linear, rotary) = CONE_AXES;
    let text = cone(&clean(linear, rotary, &[], ""));
    let (s, out) = run("clean-cone", &text);
    assert_consistent(&s, &[]);
    assert_clean_b(&s);
    // The study's columns too: the cone's own shape is no lost motion.
    assert_study_b_clean_but(&study_b("clean-cone-study", &[&text])[0], None);
    let b = budget(&s);
    // No backlash, no dry friction: no such rows at all.
    assert!(rows(b, BudgetMechanism::Backlash).is_empty(), "{b:?}");
    assert!(rows(b, BudgetMechanism::Friction).is_empty(), "{b:?}");
    // The program row against the commanded positions through the kinematics written out.
    let (_, direction) = g_direction(&s);
    let samples: Vec<(f64, f64)> = commanded_rows(&out, direction)
        .into_iter()
        .map(|(t, q)| (t, trt_ac_reading(q, 100.0)))
        .collect();
    assert!(samples.len() > 10_000, "{}", samples.len());
    let want = centred_peak_to_valley(&samples);
    let program = rows(b, BudgetMechanism::ProgramPath)[0];
    assert!(
        (program.pv_um - want).abs() <= 0.2,
        "program row {} µm, the commanded path {want} µm",
        program.pv_um
    );
    // The cone's own path is a sizeable part of G (a few µm of chord error at 360 segments).
    assert!(want > 1.0, "{want}");
    eprintln!(
        "clean cone: program row {} µm, commanded path {want} µm",
        program.pv_um
    );
    // The servos' common lag, and five servos, one row each; nothing else on this machine.
    let servo = rows(b, BudgetMechanism::Servo);
    assert_eq!(
        servo.iter().filter(|r| r.axis.is_none()).count(),
        1,
        "{b:?}"
    );
    assert_eq!(servo.len(), 6, "{b:?}");
    assert_eq!(b.rows.len(), 7, "{b:?}");
}

#[test]
fn a_clean_circle_tells_of_no_lost_motion() {
    let (s, _) = run(
        "clean-circle",
        &circle(&clean(&["X", "Y", "Z"], &[], &[], "")),
    );
    assert_consistent(&s, &[]);
    assert_clean_b(&s);
    let b = budget(&s);
    // Z does not move on an XY circle: no row for it.
    let servo: Vec<&str> = rows(b, BudgetMechanism::Servo)
        .iter()
        .filter_map(|r| r.axis.as_deref())
        .collect();
    assert_eq!(servo, ["X", "Y"], "{b:?}");
    // The circle's program part is a polygon of short chords: well under a micrometre.
    assert!(
        rows(b, BudgetMechanism::ProgramPath)[0].pv_um < 0.5,
        "{b:?}"
    );
}

/// The X backlash row against the difference of two whole runs, with and without it, over
/// the revolution that gives G; and B for X against the 10 µm gap.
fn backlash_row_is_the_difference_of_two_runs(name: &str, without: String, with: String) {
    let (s, _) = run(name, &with);
    assert_consistent(&s, &["X"]);
    let b = budget(&s);
    let row = rows(b, BudgetMechanism::Backlash);
    assert_eq!(row.len(), 1, "{b:?}");
    assert_eq!(row[0].axis.as_deref(), Some("X"));
    let (k, _) = g_direction(&s);
    let trace = |text: &str, tag: &str| {
        let (scenario, _) = load(&format!("{name}-{tag}"), text);
        let study = run_ballbar(&scenario, None, &|_| {}).unwrap();
        study.runs[k].trace_um(true).unwrap()
    };
    let (a, b0) = (trace(&with, "with"), trace(&without, "without"));
    let diff: Vec<f64> = a.iter().zip(&b0).map(|(a, b)| a - b).collect();
    let (lo, hi) = diff
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
            (l.min(x), h.max(x))
        });
    let want = hi - lo;
    eprintln!(
        "{name}: backlash row {} µm, two runs {want} µm",
        row[0].pv_um
    );
    assert!(
        (row[0].pv_um - want).abs() <= 0.05 * want,
        "{name}: backlash row {} µm, two runs {want} µm",
        row[0].pv_um
    );
    // B of X: the gap, 10 µm (the elastic part is the linear twin's, viscous only).
    let bx = s.reversal_b.iter().find(|r| r.axis == "X").unwrap();
    let bx = bx.b_um.unwrap();
    eprintln!("{name}: B of X {bx} µm");
    assert!((bx - 10.0).abs() <= 1.0, "{name}: B of X {bx} µm");
    for r in s.reversal_b.iter().filter(|r| r.axis != "X") {
        assert!(r.b_um.is_none_or(|b| b.abs() < 0.3), "{r:?}");
    }
    // The study's B of the same two machines, run side by side: the gap on X, and agreeing
    // with the budget's within half a micrometre; nothing on the clean one.
    let both = study_b(&format!("{name}-study"), &[&with, &without]);
    assert_study_b_clean_but(&both[0], Some("X"));
    assert_study_b_clean_but(&both[1], None);
    let study_bx = both[0].iter().find(|(a, _)| a == "X").unwrap().1.unwrap();
    eprintln!("{name}: study B of X {study_bx} µm, budget's {bx} µm");
    assert!(
        (study_bx - 10.0).abs() <= 1.0,
        "{name}: study B of X {study_bx} µm"
    );
    assert!(
        (study_bx - bx).abs() <= 0.5,
        "{name}: study {study_bx}, budget {bx}"
    );
}

#[test]
fn ten_micrometres_of_x_backlash_on_a_circle_is_its_row() {
    let backlash = "[machine_overrides.axes.X.drive]\nbacklash_mm = 0.010\n";
    let axes = ["X", "Y", "Z"];
    backlash_row_is_the_difference_of_two_runs(
        "backlash-circle",
        circle(&clean(&axes, &[], &[], "")),
        circle(&clean(&axes, &[], &[], backlash)),
    );
}

#[test]
fn ten_micrometres_of_x_backlash_on_a_cone_is_its_row() {
    let backlash = "[machine_overrides.axes.X.drive]\nbacklash_mm = 0.010\n";
    let (linear, rotary) = CONE_AXES;
    backlash_row_is_the_difference_of_two_runs(
        "backlash-cone",
        cone(&clean(linear, rotary, &[], "")),
        cone(&clean(linear, rotary, &[], backlash)),
    );
}

/// The servo rows' shares added.
fn servo_share(s: &SimulationSummary) -> f64 {
    rows(budget(s), BudgetMechanism::Servo)
        .iter()
        .map(|r| r.share)
        .sum()
}

#[test]
fn a_gain_mismatch_on_a_circle_is_the_servos() {
    let (s, _) = run(
        "kv-circle",
        &circle(&clean(
            &["X", "Y", "Z"],
            &[],
            &[("X", 30.0), ("Y", 27.0)],
            "",
        )),
    );
    assert_consistent(&s, &[]);
    let share = servo_share(&s);
    eprintln!("gain mismatch: servo share {share}");
    assert!(share > 0.8, "servo share {share}: {:?}", budget(&s));
}

#[test]
fn a_gain_mismatch_on_a_cone_is_the_servos() {
    let (linear, rotary) = CONE_AXES;
    let (s, _) = run(
        "kv-cone",
        &cone(&clean(linear, rotary, &[("X", 24.0), ("Y", 30.0)], "")),
    );
    assert_consistent(&s, &[]);
    let share = servo_share(&s);
    eprintln!("gain mismatch: servo share {share}");
    assert!(share > 0.8, "servo share {share}: {:?}", budget(&s));
}

#[test]
fn friction_alone_makes_the_drive_s_elastic_lost_motion() {
    // The stock three-axis machine's friction on X only: B of X is the wind-up 2 Fc / k of
    // the spec (150 N over 200 N/µm: 1.5 µm), and no other axis tells of lost motion.
    let (s, _) = run(
        "friction-circle",
        &circle(&clean(
            &["Y", "Z"],
            &[],
            &[],
            "[machine_overrides.axes.X.servo]\nmodel = \"cascade\"\n\
             [machine_overrides.axes.X.friction]\ncoulomb_n = 150.0\n",
        )),
    );
    assert_consistent(&s, &["X"]);
    let b = budget(&s);
    let friction = rows(b, BudgetMechanism::Friction);
    assert_eq!(friction.len(), 1, "{b:?}");
    let want = 2.0 * 150.0 / 200.0; // µm
    let bx = s.reversal_b.iter().find(|r| r.axis == "X").unwrap();
    let bx = bx.b_um.unwrap();
    eprintln!("friction alone: B of X {bx} µm, 2 Fc/k {want} µm");
    assert!(
        (bx - want).abs() <= 0.2 * want,
        "B of X {bx} µm, 2 Fc/k {want} µm"
    );
}

/// The stock machine (dry friction on all five axes) with 10 µm of X and 6 µm of Y
/// backlash, on the cone: a study's B of each axis, from the run's lost-motion signature,
/// against the budget's, from each axis's own runs. Five lost-motion terms whose
/// sensitivities swing with θ: the joint fit must keep each axis's part its own.
#[test]
fn a_study_s_b_on_a_cone_with_lost_motion_on_every_axis_is_the_budget_s() {
    let backlash = "[machine_overrides.axes.X.drive]\nbacklash_mm = 0.010\n\
                    [machine_overrides.axes.Y.drive]\nbacklash_mm = 0.006\n";
    let text = cone(backlash);
    let (s, _) = run("lost-everywhere", &text);
    let study = study_b("lost-everywhere-study", &[&text]).remove(0);
    let mut compared = 0;
    for r in &s.reversal_b {
        let theirs = study.iter().find(|(a, _)| *a == r.axis).unwrap().1;
        eprintln!("{}: budget {:?}, study {theirs:?}", r.axis, r.b_um);
        assert_eq!(r.b_um.is_some(), theirs.is_some(), "{}", r.axis);
        if let (Some(want), Some(got)) = (r.b_um, theirs) {
            assert!(
                (got - want).abs() <= 0.5_f64.max(0.05 * want.abs()),
                "{}: study {got} µm, budget {want} µm",
                r.axis
            );
            compared += 1;
        }
    }
    assert!(compared >= 3, "{compared}");
    // Against the closed form, B = b + 2 Fc/k: 150 N at the default 200 N/µm is 1.5 µm on
    // X and Y; A's 15 N m at 3e6 N m/rad is 1e-5 rad, 1 µm of arc at the 100 mm bar.
    let b = |axis: &str| study.iter().find(|(a, _)| a == axis).unwrap().1.unwrap();
    for (axis, want) in [("X", 11.5), ("Y", 7.5), ("A", 1.0)] {
        assert!(
            (b(axis) - want).abs() <= 0.2,
            "{axis}: {} µm, {want} µm",
            b(axis)
        );
    }
}

/// The budget runs whose servo the full run steps too (the machine's own drive, or its
/// linear twin, on an axis without a position-error table) read it from the run's samples.
/// Every run's positions are those of a budget that steps each servo itself, bit for bit:
/// on a machine with backlash and friction on X (whose friction run, without the backlash,
/// is not the machine's drive) and a position-error table on C (whose samples carry the
/// table's errors).
#[test]
fn the_servos_the_full_run_steps_are_read_from_its_samples() {
    use std::cell::RefCell;

    use mtsim::pipeline::{self, RunOptions, Sample, Sink, Timing};
    use mtsim::study::budget::{BudgetPlan, BudgetRun, BudgetStepper};

    let dir = scratch("budget", "in-run-machine");
    std::fs::write(dir.join("c.comp"), "0 0 0\n180 0.018 0.009\n360 0 0\n").unwrap();
    let machine = std::fs::read_to_string(trt_ac()).unwrap() + "\n[error_tables]\nC = \"c.comp\"\n";
    let machine_path = dir.join("m.toml");
    std::fs::write(&machine_path, machine).unwrap();
    let text = cone("[machine_overrides.axes.X.drive]\nbacklash_mm = 0.010\n").replacen(
        &format!("machine = {:?}", trt_ac()),
        &format!("machine = {:?}", machine_path.display().to_string()),
        1,
    );
    let (scenario, _) = load("in-run", &text);
    assert!(scenario
        .machine
        .geometry
        .tables
        .contains_key(&mtsim::Axis::C));
    let plan = BudgetPlan::for_positions(&scenario).unwrap();
    let options = RunOptions {
        timing: Timing::Planned {
            twins: true,
            settle: false,
        },
        force_tcp: false,
        start_time_s: 0.0,
        program_path: scenario.path.clone(),
        max_samples: u64::MAX,
    };
    let read = RefCell::new(plan.start(Direction::Ccw, options.timing));
    // Told that the samples carry no servo, it steps every one itself.
    let stepped = RefCell::new(plan.start(Direction::Ccw, Timing::Setpoints));

    struct Compare<'a, 'p> {
        runs: [&'a RefCell<BudgetRun<'p>>; 2],
        positions: [Vec<mtsim::AxisVec>; 2],
        samples: usize,
        /// Largest |actual - setpoint| over the runs, mm or deg: the runs move.
        lag: f64,
    }
    impl Sink for Compare<'_, '_> {
        fn push(&mut self, s: &Sample) -> mtsim::error::Result<()> {
            for (run, out) in self.runs.iter().zip(&mut self.positions) {
                run.borrow_mut()
                    .measured_positions(&s.commanded, out)
                    .unwrap();
            }
            let [a, b] = &self.positions;
            for (k, (a, b)) in a.iter().zip(b).enumerate() {
                for axis in mtsim::Axis::ALL {
                    assert_eq!(
                        a[axis].to_bits(),
                        b[axis].to_bits(),
                        "sample {}, run {k}, axis {axis:?}: {} read, {} stepped",
                        s.index,
                        a[axis],
                        b[axis]
                    );
                    self.lag = self.lag.max((a[axis] - s.commanded[axis]).abs());
                }
            }
            self.samples += 1;
            Ok(())
        }
    }
    let mut compare = Compare {
        runs: [&read, &stepped],
        positions: [Vec::new(), Vec::new()],
        samples: 0,
        lag: 0.0,
    };
    let run = mtsim::program::scenario_run(&scenario, Direction::Ccw, 0.0).unwrap();
    let (mut step_read, mut step_stepped) = (BudgetStepper(&read), BudgetStepper(&stepped));
    let mut sinks: Vec<&mut dyn Sink> = vec![&mut step_read, &mut step_stepped, &mut compare];
    pipeline::run(run.moves, &scenario.machine, &options, &mut sinks, &|_| {}).unwrap();
    drop(sinks);
    assert!(compare.samples > 10_000, "{} samples", compare.samples);
    assert!(
        compare.lag > 1e-3,
        "the runs' largest lag {} is not a servo's",
        compare.lag
    );
    assert_eq!(compare.positions[0].len(), plan.cases().len());
}
