//! The cut's error budget (`study::cut_budget`) against figures computed another way: a
//! backlash row against the difference of two whole cuts through the public API and the
//! contract's step `b |n_x|`, the program's row against the commanded cut, a location error's
//! row against the first-order form `d = (Δp + s Δt)·n` of `cutting-test.md` with the ball
//! bar's reading of the same error beside it, and a machine without lost motion.

use std::path::Path;

use mtsim::input::scenario::Scenario;
use mtsim::input::ConeTest;
use mtsim::kinematics::{Branch, LocationErrors};
use mtsim::measure::bar::deviation_mm;
use mtsim::measure::cut::{actual_tool, CutOptions};
use mtsim::report::cut_budget::{CutBudget, CutBudgetRow};
use mtsim::report::run::BudgetMechanism;
use mtsim::study::cut::{run_cut, CutRun};
use mtsim::{Axis, AxisVec};
use nalgebra::{Point3, Vector3};

use crate::common::{scenario_text, scratch, trt_ac};

/// The 15/10 cone (L 100 mm, O at (0, 0, 200)) in `segments` blocks on trt-ac (its default
/// 20 mm cutter, 40 mm flutes) with `overrides`, loaded.
fn cone(name: &str, segments: usize, overrides: &str) -> Scenario {
    let dir = scratch("cut-budget", name);
    let path = dir.join("scenario.toml");
    let text = scenario_text(
        &trt_ac(),
        &format!(
            "[program.cone]\nhalf_apex_deg = 15.0\ninclination_deg = 10.0\n\
             center_mm = [0.0, 0.0, 200.0]\nballbar_length_mm = 100.0\nsegments = {segments}\n\
             feed_mm_min = 1000.0\n{overrides}"
        ),
    );
    std::fs::write(&path, text).unwrap();
    Scenario::load(Path::new(&path)).unwrap()
}

/// Every axis a cascade of Kv 30/s without dry friction, then `extra` TOML lines.
fn clean(extra: &str) -> String {
    let mut s = String::new();
    for a in ["X", "Y", "Z", "A", "C"] {
        let key = if a == "A" || a == "C" {
            "coulomb_nm"
        } else {
            "coulomb_n"
        };
        s += &format!(
            "[machine_overrides.axes.{a}.servo]\nmodel = \"cascade\"\nkv_per_s = 30.0\n\
             [machine_overrides.axes.{a}.friction]\n{key} = 0.0\n"
        );
    }
    s + extra
}

fn cut(s: &Scenario, commanded: bool, budget: bool) -> CutRun {
    let options = CutOptions {
        commanded,
        ..CutOptions::default()
    };
    run_cut(s, options, budget, &|_| {}).unwrap()
}

fn budget(run: &CutRun) -> &CutBudget {
    run.budget.as_ref().expect("a budget")
}

fn rows(b: &CutBudget, m: BudgetMechanism) -> Vec<&CutBudgetRow> {
    b.rows.iter().filter(|r| r.mechanism == m).collect()
}

/// What holds of any budget: the shares and the interplay add to 1, and the rows added up
/// are the full cut's d but for the interplay (checked as an RMS against d's).
fn assert_adds_up(run: &CutRun, name: &str) {
    let b = budget(run);
    let total: f64 = b.rows.iter().map(|r| r.share).sum::<f64>() + b.interaction_share;
    assert!((total - 1.0).abs() < 1e-9, "{name}: {total}");
    let d = &run.surface.envelope.values;
    let (mut rr, mut dd) = (0.0, 0.0);
    for (p, &dp) in d.iter().enumerate() {
        let sum: f64 = b.rows.iter().map(|r| r.contribution_um[p]).sum();
        if sum.is_finite() && dp.is_finite() {
            rr += (sum - dp).powi(2);
            dd += dp * dp;
        }
    }
    let residual = (rr / dd).sqrt();
    eprintln!(
        "{name}: d RMS {:.3} µm, rows' sum off d by {:.2} % (RMS), interplay share {:.4}",
        b.rms_um,
        100.0 * residual,
        b.interaction_share
    );
    assert!(residual < 0.05, "{name}: the rows' sum is {residual} off d");
}

/// The X reversals of the program as the cut reads them.
fn x_reversals(run: &CutRun) -> Vec<f64> {
    run.surface
        .reversals()
        .iter()
        .find(|(a, _)| *a == Axis::X)
        .map(|(_, r)| r.clone())
        .unwrap_or_default()
}

/// 10 µm of X backlash on a machine otherwise clean: the budget's X backlash row is the cut
/// with the backlash less the cut without it (two whole runs through `run_cut`), point by
/// point, and it is `∓(b/2) n_x` either side of X's reversals within 5 % (so it steps by
/// `b |n_x|` across each).
#[test]
fn x_backlash_row_is_two_cuts_apart_and_steps_by_b_times_n_x() {
    let b_mm = 0.010;
    let with = cone(
        "backlash",
        720,
        &clean("[machine_overrides.axes.X.drive]\nbacklash_mm = 0.010\n"),
    );
    let without = cone("clean", 720, &clean(""));
    let run = cut(&with, false, true);
    assert_adds_up(&run, "X backlash");
    let b = budget(&run);
    let backlash = rows(b, BudgetMechanism::Backlash);
    assert_eq!(backlash.len(), 1, "{:?}", b.rows);
    assert_eq!(backlash[0].axis.as_deref(), Some("X"));
    assert!(rows(b, BudgetMechanism::Friction).is_empty());
    // The independent figure: two full cuts, with and without the backlash.
    let (a, z) = (
        cut(&with, false, false).surface.envelope.values,
        cut(&without, false, false).surface.envelope.values,
    );
    let (mut worst, mut largest) = (0.0f64, 0.0f64);
    for (p, c) in backlash[0].contribution_um.iter().enumerate() {
        let two = a[p] - z[p];
        if c.is_finite() && two.is_finite() {
            worst = worst.max((c - two).abs());
            largest = largest.max(two.abs());
        }
    }
    eprintln!("X backlash: row against two cuts: worst {worst:.4} µm of {largest:.3} µm");
    assert!(largest > 2.0, "the backlash shows: {largest} µm");
    assert!(
        worst <= 0.02 * largest + 0.02,
        "row against two cuts: {worst} µm"
    );
    // The closed form: away from its reversals the table lags its linear twin by b/2 in the
    // direction of motion, ΔX = −(b/2) sgn(v_x), which moves the surface along n by ΔX n_x
    // (n in the cone frame, into the table frame, then the machine frame at θ's pose), so
    // the row is ∓(b/2) n_x either side and steps by b |n_x| across a reversal. Checked
    // wherever X moves at a fifth of its top speed or more: the take-up after a reversal
    // (the motor crossing the gap, 2 to 5° of θ here) is left out, as the bar budget's B fit
    // leaves it out.
    let s = &with;
    let test = mtsim::program::test_of(s);
    let cone: &ConeTest = test.cone().unwrap();
    let kin = s.machine.kinematics;
    let alpha = cone.half_apex_deg.to_radians();
    let reversals = x_reversals(&run);
    assert_eq!(reversals.len(), 2, "{reversals:?}");
    let e = &run.surface.envelope;
    let middle = run.surface.evaluation_rows()[1];
    let columns = e.column_count();
    let mut previous_c = 0.0;
    let (mut x, mut n_x) = (Vec::new(), Vec::new());
    for j in 0..columns {
        let t = (j as f64 * e.step_deg).to_radians();
        let q = kin.inverse(&cone.pose(t), Branch::Primary, previous_c);
        previous_c = q[Axis::C];
        let n_cone = Vector3::new(alpha.cos() * t.cos(), alpha.cos() * t.sin(), alpha.sin());
        x.push(q[Axis::X]);
        n_x.push((kin.table_rotation(&q) * (cone.frame_rotation() * n_cone)).x);
    }
    let slope = |j: usize| (x[(j + 1) % columns] - x[(j + columns - 1) % columns]) / 2.0;
    let top = (0..columns).map(|j| slope(j).abs()).fold(0.0, f64::max);
    let (mut worst, mut checked) = (0.0f64, 0);
    for j in (0..columns).filter(|&j| slope(j).abs() >= 0.2 * top) {
        let v_sign = slope(j).signum() * run.surface.sense();
        let expected = -0.5 * b_mm * 1e3 * v_sign * n_x[j];
        let c = backlash[0].contribution_um[j * e.rows.len() + middle];
        worst = worst.max((c - expected).abs());
        checked += 1;
    }
    let n_max = n_x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let bound = 0.05 * 0.5 * b_mm * 1e3 * n_max;
    eprintln!(
        "X backlash: row against ∓(b/2) n_x at {checked} of {columns} columns: worst {worst:.4} µm \
         (5 % of b/2 |n_x|max: {bound:.4} µm)"
    );
    assert!(checked > columns / 5, "{checked} columns");
    assert!(worst <= bound, "row against ∓(b/2) n_x: {worst} µm");
    for &theta in &reversals {
        let j = (theta / e.step_deg).round() as usize % columns;
        eprintln!(
            "X at {theta:.2}°: the row steps by b |n_x| = {:.4} µm",
            b_mm * 1e3 * n_x[j].abs()
        );
    }
}

/// A machine without backlash and dry friction has no lost-motion row; its program row is
/// the commanded cut (`--commanded`), point by point.
#[test]
fn a_clean_machine_has_no_lost_motion_row_and_its_program_row_is_the_commanded_cut() {
    let s = cone("no-lost-motion", 360, &clean(""));
    let run = cut(&s, false, true);
    assert_adds_up(&run, "clean");
    let b = budget(&run);
    assert!(
        rows(b, BudgetMechanism::Backlash).is_empty(),
        "{:?}",
        b.rows
    );
    assert!(
        rows(b, BudgetMechanism::Friction).is_empty(),
        "{:?}",
        b.rows
    );
    assert!(rows(b, BudgetMechanism::Geometric).is_empty());
    let program = rows(b, BudgetMechanism::ProgramPath);
    assert_eq!(program.len(), 1);
    let commanded = cut(&s, true, true);
    assert!(commanded.budget.is_none(), "a commanded cut has no budget");
    let mut worst = 0.0f64;
    for (c, d) in program[0]
        .contribution_um
        .iter()
        .zip(&commanded.surface.envelope.values)
    {
        assert_eq!(c.is_finite(), d.is_finite());
        if c.is_finite() {
            worst = worst.max((c - d).abs());
        }
    }
    eprintln!(
        "program row against the commanded cut: worst {worst:e} µm (row RMS {:.3} µm)",
        program[0].rms_um
    );
    assert!(worst < 1e-9, "{worst}");
    assert!(cut(&s, false, false).budget.is_none(), "--no-budget");
}

/// A tilt of the C axis (EA0C 100 µrad, EB0C −60 µrad) tilts the table, and so the tool axis
/// against the workpiece. Its geometric row is the contract's first-order form at every grid
/// point, `c(θ, z) = (Δp + s Δt)·n` with Δp, Δt the tip's and the axis's change at θ's pose
/// (the chain with the errors against the nominal one), `s = (z − z_tip) / cos α` along the
/// generatrix. The ball bar reads `Δp·n` alone (its dL, the tip's distance from the table
/// ball): the row equals it at the tip, and differs from it by `s Δt·n` above, which only
/// the cut shows.
#[test]
fn a_c_axis_tilt_gives_a_row_linear_along_the_height_that_the_ball_bar_reads_only_at_the_tip() {
    let s = cone(
        "tilt",
        3600,
        &clean("[machine_overrides.location_errors]\nEA0C_urad = 100.0\nEB0C_urad = -60.0\n"),
    );
    let run = cut(&s, false, true);
    assert_adds_up(&run, "C tilt");
    let b = budget(&run);
    let geometric = rows(b, BudgetMechanism::Geometric);
    assert_eq!(geometric.len(), 1, "{:?}", b.rows);
    let row = geometric[0];
    let test = mtsim::program::test_of(&s);
    let cone: &ConeTest = test.cone().unwrap();
    let actual = s.machine.kinematics;
    let nominal = actual.with_location_errors(LocationErrors::default());
    let alpha = cone.half_apex_deg.to_radians();
    let z_tip = (cone.ballbar_length_mm - 10.0) * alpha.sin();
    let pivot = Point3::from(cone.center_mm);
    let e = &run.surface.envelope;
    let rows_n = e.rows.len();
    let (mut worst, mut worst_bar, mut largest_tilt) = (0.0f64, 0.0f64, 0.0f64);
    let mut previous_c = 0.0;
    for j in 0..e.column_count() {
        let t = (j as f64 * e.step_deg).to_radians();
        let q: AxisVec = nominal.inverse(&cone.pose(t), Branch::Primary, previous_c);
        previous_c = q[Axis::C];
        let (p0, p1) = (nominal.forward(&q), actual_tool(&actual, &q));
        let n = cone.frame_rotation()
            * Vector3::new(alpha.cos() * t.cos(), alpha.cos() * t.sin(), alpha.sin());
        let tip_um = (p1.tip - p0.tip).dot(&n) * 1e3;
        let tilt = (p1.axis - p0.axis).dot(&n);
        // The ball bar's reading of the same error: dL with the errors less dL without.
        let bar_um = (deviation_mm(&actual, &q, &pivot, cone.ballbar_length_mm)
            - deviation_mm(&nominal, &q, &pivot, cone.ballbar_length_mm))
            * 1e3;
        worst_bar = worst_bar.max((bar_um - tip_um).abs());
        for (i, r) in e.rows.iter().enumerate() {
            let s_mm = (r.z_mm - z_tip) / alpha.cos();
            let expected = tip_um + tilt * s_mm * 1e3;
            let c = row.contribution_um[j * rows_n + i];
            assert!(c.is_finite(), "θ column {j}, row {i} cut");
            worst = worst.max((c - expected).abs());
            if i == rows_n - 1 {
                largest_tilt = largest_tilt.max((tilt * s_mm * 1e3).abs());
            }
            if i == 0 {
                assert!(
                    (c - bar_um).abs() <= 0.1,
                    "θ {:.1}°: the row at the tip {c} µm, the bar's {bar_um} µm",
                    t.to_degrees()
                );
            }
        }
    }
    eprintln!(
        "C tilt: row against (Δp + s Δt)·n: worst {worst:.4} µm; bar against Δp·n: worst \
         {worst_bar:.2e} µm; tilt part at the top up to {largest_tilt:.3} µm; row's change \
         along the height {:.3} µm",
        row.height_change_um
    );
    // To first order: the second-order part is `|Δp⊥|² / 2L`, about 0.01 µm here.
    assert!(worst_bar < 0.03, "the bar reads Δp·n: {worst_bar}");
    assert!(largest_tilt > 2.0, "the tilt shows: {largest_tilt} µm");
    assert!(
        worst <= 0.02 * largest_tilt + 0.05,
        "row against the first-order form: {worst} µm"
    );
    assert!(
        (row.height_change_um - largest_tilt).abs() <= 0.05 * largest_tilt + 0.05,
        "the row's change along the height {} µm, the tilt's {largest_tilt} µm",
        row.height_change_um
    );
}

/// The ball bar beside the cut (item 5), on the bundled 15/10 cone (720 blocks, trt-ac as
/// bundled). With the commanded motion the cut's d just above the tip is never above the
/// bar's dL at the same θ (the contract's lower envelope; dL is a 0.05° bin's mean,
/// interpolated to the column, which blurs a scallop by up to 0.08 µm: hence 0.1 µm) and equal to it within 0.1 µm over most of the
/// revolution. With the actual motion the bar bins dL by the commanded tip's θ while the
/// cutter cuts where the actual tip is, a servo lag behind: read at the θ the tip actually
/// had (the bar's θ less the lag's angle `ω τ`), the envelope holds again.
#[test]
fn the_cut_at_the_tip_is_the_lower_envelope_of_the_ball_bar_of_the_same_run() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let s = Scenario::load(&root.join("scenarios/cone-15-10.toml")).unwrap();
    for commanded in [true, false] {
        let run = cut(&s, commanded, false);
        let bar = run.ballbar_um.as_ref().expect("the bar's reading");
        let e = &run.surface.envelope;
        let bin = mtsim::measure::theta::BIN_DEG;
        let at = |theta: f64| {
            // Linear between bin centres (i + ½) bin, wrapping.
            let u = theta / bin - 0.5;
            let i = u.floor();
            let f = u - i;
            let n = bar.len() as i64;
            let v = |k: i64| bar[k.rem_euclid(n) as usize];
            v(i as i64) * (1.0 - f) + v(i as i64 + 1) * f
        };
        // The lag's angle: the velocity lag 1/Kv of trt-ac's axes (30/s, no feedforward) at
        // the revolution's mean rate, the cut's samples over 360° at 1 ms.
        let lag_deg = match commanded {
            true => 0.0,
            false => 360.0 / (run.surface.figures().samples as f64 * 1e-3) / 30.0,
        };
        let (mut above, mut close, mut worst_above) = (0, 0, 0.0f64);
        let columns = e.column_count();
        for j in 0..columns {
            let theta = j as f64 * e.step_deg;
            let d = e.depth_um(j, 0);
            let dl = at(theta + run.surface.sense() * lag_deg);
            worst_above = worst_above.max(d - dl);
            above += usize::from(d > dl + 0.1);
            close += usize::from((d - dl).abs() <= 0.1);
        }
        eprintln!(
            "cone-15-10 (commanded {commanded}, bar read {lag_deg:.3}° on): d at the tip above \
             dL by at most {worst_above:.3} µm ({above} columns over 0.1), within 0.1 µm of dL \
             at {close} of {columns} columns"
        );
        assert!(
            above <= columns / 100,
            "d above the bar's dL at {above} columns"
        );
        if commanded {
            assert_eq!(above, 0, "d above the bar's dL");
            assert!(close * 10 >= columns * 8, "{close} of {columns}");
        }
    }
}

/// Each row's RMS, peak-to-valley and share, and the budget's RMS, peak-to-valley and points,
/// against their definitions (`study::cut_budget`) recomputed here from the rows'
/// contributions and the full cut's d over the points where every one is cut; with and
/// without points left out (location errors of a millimetre leave 1.6 % of the grid uncut
/// by some run, so the figures are taken over a part of the grid; without them, over all
/// of it, which `assemble` takes without copying).
#[test]
fn the_rows_figures_are_their_definitions_over_the_points_every_run_cut() {
    let offsets = "[machine_overrides.location_errors]\nEZ0A_um = 1000.0\nEY0C_um = 1000.0\n\
                   EX0C_um = 1000.0\nEA0C_urad = 1000.0\n";
    for (name, extra, some_left_out) in [("offsets", offsets, true), ("clean", "", false)] {
        let s = cone(name, 360, &clean(extra));
        let run = cut(&s, false, true);
        let b = budget(&run);
        let d = &run.surface.envelope.values;
        let used: Vec<usize> = (0..d.len())
            .filter(|&p| {
                d[p].is_finite() && b.rows.iter().all(|r| r.contribution_um[p].is_finite())
            })
            .collect();
        assert_eq!(b.points, used.len(), "{name}");
        eprintln!(
            "{name}: {} of {} points cut by every run",
            used.len(),
            d.len()
        );
        assert_eq!(
            used.len() < d.len(),
            some_left_out,
            "{name}: {} of {}",
            used.len(),
            d.len()
        );
        let close = |got: f64, want: f64, what: &str| {
            assert!(
                (got - want).abs() <= 1e-9 * want.abs().max(1e-3),
                "{name} {what}: {got} against {want}"
            )
        };
        let rms = |v: &dyn Fn(usize) -> f64| {
            (used.iter().map(|&p| v(p) * v(p)).sum::<f64>() / used.len() as f64).sqrt()
        };
        let pv = |v: &dyn Fn(usize) -> f64| {
            let lo = used.iter().map(|&p| v(p)).fold(f64::INFINITY, f64::min);
            let hi = used.iter().map(|&p| v(p)).fold(f64::NEG_INFINITY, f64::max);
            hi - lo
        };
        close(b.rms_um, rms(&|p| d[p]), "d's RMS");
        close(b.pv_um, pv(&|p| d[p]), "d's peak-to-valley");
        let dd: f64 = used.iter().map(|&p| d[p] * d[p]).sum();
        assert!(b.rows.len() >= 5, "{name}: {:?}", b.rows.len());
        for r in &b.rows {
            let c = |p: usize| r.contribution_um[p];
            let what = format!("{:?} {:?}", r.mechanism, r.axis);
            close(r.rms_um, rms(&c), &format!("{what} RMS"));
            close(r.pv_um, pv(&c), &format!("{what} peak-to-valley"));
            let cd: f64 = used.iter().map(|&p| c(p) * d[p]).sum();
            close(r.share, cd / dd, &format!("{what} share"));
        }
    }
}
