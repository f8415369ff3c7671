//! The cut cone (`measure::cut`) against the closed forms of the contract
//! (`cutting-test.md`, "Checks that hold exactly or to first order"): cutter positions made
//! here from the cone's nominal poses and the machine's inverse kinematics, the expected
//! depths from geometry written out in each test.

use std::path::Path;

use mtsim::input::scenario::Scenario;
use mtsim::input::{ConeTest, Direction};
use mtsim::kinematics::{Branch, Kinematics, ToolPose};
use mtsim::measure::cut::{CutOptions, CutSurface};
use mtsim::pipeline::{Sample, Sink};
use mtsim::{Axis, AxisVec};
use nalgebra::{Rotation3, Unit, Vector3};

use crate::common;

/// A scenario of `cone_body` on trt-ac with a cutter of `diameter_mm` and `flute_mm`.
pub(crate) fn scenario(name: &str, cone_body: &str, diameter_mm: f64, flute_mm: f64) -> Scenario {
    let dir = common::scratch("cut", name);
    let machine = std::fs::read_to_string(common::trt_ac()).unwrap();
    let machine_path = dir.join("m.toml");
    std::fs::write(
        &machine_path,
        format!(
            "{machine}\n[tool]\ncutter_diameter_mm = {diameter_mm}\nflute_length_mm = {flute_mm}\n"
        ),
    )
    .unwrap();
    let path = common::write_scenario(&dir, &machine_path.display().to_string(), cone_body);
    Scenario::load(Path::new(&path)).unwrap()
}

pub(crate) fn cone_body(alpha: f64, beta: f64, length: f64) -> String {
    format!(
        "[program.cone]\nhalf_apex_deg = {alpha}\ninclination_deg = {beta}\n\
         center_mm = [0.0, 0.0, 200.0]\nballbar_length_mm = {length}\n"
    )
}

pub(crate) fn the_cone(s: &Scenario) -> ConeTest {
    *mtsim::program::test_of(s).cone().unwrap()
}

/// Axis positions of `pose`, C unwrapped near `previous`.
fn joints(kin: &Kinematics, pose: &ToolPose, previous: &AxisVec) -> AxisVec {
    kin.inverse(pose, Branch::Primary, previous[Axis::C])
}

fn sample(k: u64, commanded: AxisVec, actual: AxisVec) -> Sample {
    Sample {
        index: k,
        time_s: k as f64 * 1e-3,
        line: 2,
        block_index: 1,
        commanded,
        actual,
        following_error: commanded - actual,
        linear: actual,
    }
}

/// The cut of `samples` (one counter-clockwise run).
fn cut(
    s: &Scenario,
    options: CutOptions,
    samples: &[Sample],
    reversals: Vec<(Axis, Vec<f64>)>,
) -> CutSurface {
    let mut surface = CutSurface::new(s, &the_cone(s), options, reversals).unwrap();
    surface.start_run(Direction::Ccw, None);
    for x in samples {
        surface.push(x).unwrap();
    }
    surface.end_run();
    surface
}

/// Every depth of row `i`, um, by column (None: not cut).
fn row(surface: &CutSurface, i: usize) -> Vec<Option<f64>> {
    let e = &surface.envelope;
    (0..e.column_count())
        .map(|j| Some(e.depth_um(j, i)).filter(|d| d.is_finite()))
        .collect()
}

/// A joint-space program of `blocks` G01 blocks over the revolution (each block's end on
/// the cone's nominal pose, the joints linear between), `per_block` samples a block:
/// commanded = actual. With the tip's radial deviation from the bar length, um, per sample
/// (what a ball bar on an error-free machine reads), and each sample's θ, deg.
fn joint_space(s: &Scenario, blocks: usize, per_block: usize) -> (Vec<Sample>, Vec<(f64, f64)>) {
    let cone = the_cone(s);
    let kin = s.machine.kinematics;
    let mut ends = Vec::with_capacity(blocks + 1);
    let mut previous = AxisVec::ZERO;
    for b in 0..=blocks {
        let theta = (b as f64 * 360.0 / blocks as f64).to_radians();
        previous = joints(&kin, &cone.pose(theta), &previous);
        ends.push(previous);
    }
    let (mut samples, mut e) = (Vec::new(), Vec::new());
    for b in 0..blocks {
        for m in 0..per_block {
            let f = m as f64 / per_block as f64;
            let q = ends[b] + (ends[b + 1] - ends[b]) * f;
            let pose = kin.forward(&q);
            let v = pose.tip - nalgebra::Point3::from(cone.center_mm);
            // θ in the cone frame: the table frame turned back by Ry(β).
            let local = cone.frame_rotation().inverse() * v;
            let theta = local.y.atan2(local.x).to_degrees().rem_euclid(360.0);
            e.push((theta, (v.norm() - cone.ballbar_length_mm) * 1e3));
            samples.push(sample(samples.len() as u64, q, q));
        }
    }
    (samples, e)
}

fn max_abs(surface: &CutSurface) -> f64 {
    surface
        .envelope
        .values
        .iter()
        .map(|d| {
            assert!(d.is_finite(), "every grid point on the flank is cut");
            d.abs()
        })
        .fold(0.0, f64::max)
}

/// The commanded cut of a joint-space program on the 20/15 cone (L 120 mm, 16 mm cutter):
/// its chord error falls as 1/n² and is below 0.02 um at 36,000 blocks; just above the tip
/// height d is the lower envelope of the tip's radial deviation e.
#[test]
fn an_ideal_machine_leaves_only_the_programs_chords_falling_as_one_over_n_squared() {
    let s = scenario("ideal", &cone_body(20.0, 15.0, 120.0), 16.0, 30.0);
    let options = CutOptions {
        commanded: true,
        ..CutOptions::default()
    };
    let mut worst = Vec::new();
    for (blocks, per_block) in [(720, 40), (1800, 16), (3600, 8), (36_000, 4)] {
        let (samples, e) = joint_space(&s, blocks, per_block);
        let surface = cut(&s, options.clone(), &samples, Vec::new());
        let d_max = max_abs(&surface);
        let e_max = e.iter().map(|x| x.1.abs()).fold(0.0, f64::max);
        println!("{blocks} blocks: max |d| = {d_max:.4} um, max |e| = {e_max:.4} um");
        worst.push((blocks, d_max, e_max));
        // Just above the tip: never above e at the same θ (+0.01 um; e linear between the
        // samples that bracket θ), never below its least.
        let tip = row(&surface, 0);
        let e_min = e.iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
        let e_top = e.iter().map(|x| x.1).fold(f64::NEG_INFINITY, f64::max);
        println!("  e from {e_min:.4} to {e_top:.4} um");
        let mut sorted = e.clone();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        let step = surface.envelope.step_deg;
        for (j, d) in tip.iter().enumerate() {
            let d = d.expect("cut");
            let theta = j as f64 * step;
            let k = sorted.partition_point(|x| x.0 < theta);
            if k > 0 && k < sorted.len() {
                let ((t0, e0), (t1, e1)) = (sorted[k - 1], sorted[k]);
                let e_at = e0 + (e1 - e0) * (theta - t0) / (t1 - t0);
                assert!(
                    d <= e_at + 0.01,
                    "{blocks} blocks, θ {theta}: d {d} above e {e_at}"
                );
            }
            assert!(
                d >= e_min - 0.01,
                "{blocks} blocks, θ {theta}: d {d} below min e {e_min}"
            );
        }
    }
    assert!(
        worst[3].1 < 0.02,
        "36,000 blocks: max |d| = {} um",
        worst[3].1
    );
    // The tip's joint-space sag falls as 1/n² (the cutter's envelope follows it less the
    // narrower its scallops, so d alone falls faster below 3,600 blocks).
    let ratio = worst[1].2 / worst[2].2;
    assert!(
        (3.8..=4.2).contains(&ratio),
        "e, 1,800 against 3,600 blocks: {ratio}"
    );
    let ratio = worst[2].2 / worst[3].2;
    assert!(
        (95.0..=105.0).contains(&ratio),
        "e, 3,600 against 36,000 blocks: {ratio}"
    );
    let ratio = worst[2].1 / worst[3].1;
    assert!(
        (80.0..=120.0).contains(&ratio),
        "d, 3,600 against 36,000 blocks: {ratio}"
    );
}

/// Samples on the cone's exact poses (no chords), `count` over the revolution, the actual
/// pose `actual(θ rad, nominal pose)`.
fn exact_poses(
    s: &Scenario,
    count: usize,
    actual: &dyn Fn(f64, &ToolPose) -> ToolPose,
) -> Vec<Sample> {
    let cone = the_cone(s);
    let kin = s.machine.kinematics;
    let (mut previous, mut previous_actual) = (AxisVec::ZERO, AxisVec::ZERO);
    (0..count)
        .map(|k| {
            let theta = (k as f64 * 360.0 / count as f64).to_radians();
            let pose = cone.pose(theta);
            previous = joints(&kin, &pose, &previous);
            previous_actual = joints(&kin, &actual(theta, &pose), &previous_actual);
            sample(k as u64, previous, previous_actual)
        })
        .collect()
}

/// A constant tilt δ of the tool axis in the generatrix plane (its top leaning out of the
/// part) leaves `d = δ s` with s the distance along the generatrix from the tip's contact,
/// `s = (z − z_tip) / cos α`, to first order.
#[test]
fn a_constant_tool_axis_tilt_gives_d_linear_along_the_height() {
    let s = scenario("tilt", &cone_body(15.0, 10.0, 100.0), 20.0, 40.0);
    let cone = the_cone(&s);
    let delta = 100e-6;
    let samples = exact_poses(&s, 36_000, &|_, pose| {
        // Turn the axis about the circle's tangent (the bar O→P is normal to the
        // generatrix, so it and the axis span the generatrix plane), its top out of the part.
        let out = (pose.tip - nalgebra::Point3::from(cone.center_mm)).normalize();
        let tangent = Unit::new_normalize(pose.axis.cross(&out));
        let tilted = Rotation3::from_axis_angle(&tangent, delta) * pose.axis;
        assert!(tilted.dot(&out) > 0.0, "the top leans out");
        ToolPose {
            tip: pose.tip,
            axis: tilted,
        }
    });
    let surface = cut(&s, CutOptions::default(), &samples, Vec::new());
    let alpha = cone.half_apex_deg.to_radians();
    let z_tip = (cone.ballbar_length_mm - 10.0) * alpha.sin();
    for (i, r) in surface.envelope.rows.iter().enumerate() {
        let expected = delta * (r.z_mm - z_tip) / alpha.cos() * 1e3;
        for (j, d) in row(&surface, i).into_iter().enumerate() {
            let d = d.expect("cut");
            assert!(
                (d - expected).abs() <= 0.02 * expected.abs() + 0.02,
                "z {} θ {}: d {d} um, expected {expected} um",
                r.z_mm,
                j as f64 * surface.envelope.step_deg
            );
        }
    }
}

/// A step b of X where X reverses (as lost motion leaves it) leaves a step of `b |n_x|` in d,
/// with n_x the surface normal's component along the machine's X at that pose, within 5 %.
#[test]
fn a_step_of_x_at_its_reversal_leaves_a_step_of_b_times_the_normals_x() {
    let s = scenario("step", &cone_body(15.0, 10.0, 100.0), 20.0, 40.0);
    let cone = the_cone(&s);
    let kin = s.machine.kinematics;
    // X's reversals: where the commanded X turns, scanned on the nominal path.
    let count = 36_000;
    let nominal = exact_poses(&s, count, &|_, p| *p);
    let x: Vec<f64> = nominal.iter().map(|q| q.commanded[Axis::X]).collect();
    let reversals: Vec<f64> = (1..count - 1)
        .filter(|&k| (x[k] - x[k - 1]) * (x[k + 1] - x[k]) < 0.0)
        .map(|k| k as f64 * 360.0 / count as f64)
        .collect();
    assert_eq!(
        reversals.len(),
        2,
        "X reverses twice on the 15/10 cone: {reversals:?}"
    );
    let b_mm = 0.005;
    let stepped: Vec<Sample> = nominal
        .iter()
        .enumerate()
        .map(|(k, q)| {
            let theta = k as f64 * 360.0 / count as f64;
            let mut actual = q.commanded;
            if (reversals[0]..reversals[1]).contains(&theta) {
                actual[Axis::X] += b_mm;
            }
            // The step is X's lost motion: its linear twin follows the command.
            let mut x = sample(k as u64, q.commanded, actual);
            x.linear = q.commanded;
            x
        })
        .collect();
    let surface = cut(
        &s,
        CutOptions::default(),
        &stepped,
        vec![(Axis::X, reversals.clone())],
    );
    let figures = surface.figures();
    assert_eq!(figures.marks.len(), 2);
    let alpha = cone.half_apex_deg.to_radians();
    for (mark, &theta) in figures.marks.iter().zip(&reversals) {
        // n in the cone frame, turned into the table frame, then into the machine frame.
        let t = theta.to_radians();
        let n_cone = Vector3::new(alpha.cos() * t.cos(), alpha.cos() * t.sin(), alpha.sin());
        let q = nominal[(theta / 360.0 * count as f64).round() as usize].commanded;
        let n_machine = kin.table_rotation(&q) * (cone.frame_rotation() * n_cone);
        let expected = b_mm * 1e3 * n_machine.x.abs();
        println!(
            "X at {theta:.2} deg: step {:.4} um, b |n_x| = {expected:.4} um",
            mark.step_um
        );
        assert_eq!(mark.axis, "X");
        assert!(
            (mark.step_um.abs() - expected).abs() <= 0.05 * expected,
            "θ {theta}: step {} um against b |n_x| = {expected} um",
            mark.step_um
        );
    }
}

/// The depth (um) a cutter (tip `p`, unit axis `t`, radius `r`, flutes `flute`, all mm)
/// cuts along the ray `s + d n`, found numerically: the ray's closest approach to the axis
/// from the two lines' common normal, then bisection on `|s + d n − axis| = r` below it.
/// None where the ray misses the flutes or meets the cutter from across the part.
fn reference_depth(
    s: &Vector3<f64>,
    n: &Vector3<f64>,
    p: &Vector3<f64>,
    t: &Vector3<f64>,
    (r, flute): (f64, f64),
) -> Option<f64> {
    let distance = |d: f64| {
        let x = s + n * d - p;
        (x - t * x.dot(t)).norm()
    };
    // Closest approach of the lines s + d n and p + u t.
    let w0 = s - p;
    let (b, dn, dt) = (n.dot(t), n.dot(&w0), t.dot(&w0));
    let denominator = 1.0 - b * b;
    if denominator < 1e-12 {
        return None;
    }
    let d_close = (b * dt - dn) / denominator;
    if d_close <= 0.0 || distance(d_close) > r {
        return None;
    }
    let (mut lo, mut hi) = (d_close - 4.0 * r, d_close);
    if distance(lo) <= r {
        return None;
    }
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if distance(mid) > r {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let along = (s + n * hi - p).dot(t);
    (0.0..=flute).contains(&along).then_some(hi * 1e3)
}

/// The actual cut of a cone on a machine with backlash (X, Y), Coulomb friction (every
/// axis), a position-gain mismatch (Y) and location errors of C, through the whole pipeline,
/// against the depths found here from the same samples (every grid point within 0.2 um,
/// and the roundness per height).
#[test]
fn the_cut_of_a_machine_with_errors_agrees_with_an_independent_computation() {
    let body = format!(
        "{}segments = 360\nfeed_mm_min = 1000.0\n\
         [machine_overrides.axes.X.drive]\nbacklash_mm = 0.006\n\
         [machine_overrides.axes.Y.drive]\nbacklash_mm = 0.004\n\
         [machine_overrides.axes.Y.servo]\nkv_per_s = 26.0\n",
        cone_body(15.0, 10.0, 100.0)
    );
    let dir = common::scratch("cut", "independent");
    let machine = std::fs::read_to_string(common::trt_ac()).unwrap();
    let machine_path = dir.join("m.toml");
    std::fs::write(
        &machine_path,
        format!(
            "{machine}\n[tool]\ncutter_diameter_mm = 20.0\nflute_length_mm = 40.0\n\
             [location_errors]\nEX0C_um = 8.0\nEY0C_um = -5.0\nEA0C_urad = -15.0\n"
        ),
    )
    .unwrap();
    let path = common::write_scenario(&dir, &machine_path.display().to_string(), &body);
    let s = Scenario::load(Path::new(&path)).unwrap();
    let cone = the_cone(&s);
    let options = CutOptions {
        theta_step_deg: 0.5,
        ..CutOptions::default()
    };
    let mut surface = CutSurface::new(&s, &cone, options, Vec::new()).unwrap();
    let run = mtsim::program::scenario_run(&s, Direction::Ccw, s.simulate.lead_deg).unwrap();
    surface.start_run(Direction::Ccw, run.measured);
    // The measured samples' actual positions, kept for the reference.
    struct Both<'a> {
        surface: &'a mut CutSurface,
        measured: Option<mtsim::input::MeasuredLines>,
        kept: Vec<AxisVec>,
    }
    impl Sink for Both<'_> {
        fn push(&mut self, x: &Sample) -> mtsim::error::Result<()> {
            if mtsim::measure::is_measured(x, self.measured) {
                self.kept.push(x.actual);
            }
            self.surface.push(x)
        }
    }
    let mut both = Both {
        surface: &mut surface,
        measured: run.measured,
        kept: Vec::new(),
    };
    let options = mtsim::pipeline::RunOptions {
        timing: mtsim::pipeline::Timing::Planned {
            twins: false,
            settle: false,
        },
        force_tcp: false,
        start_time_s: 0.0,
        program_path: path.clone(),
        max_samples: 10_000_000,
    };
    mtsim::pipeline::run(run.moves, &s.machine, &options, &mut [&mut both], &|_| {}).unwrap();
    let kept = std::mem::take(&mut both.kept);
    surface.end_run();

    // The reference: each sample's cutter in the cone frame (the table through the actual
    // chain, the tool at the machine's X Y Z along its +Z), then every grid point's least depth.
    let kin = s.machine.kinematics;
    let to_cone = cone.frame_rotation().inverse();
    let lines: Vec<(f64, Vector3<f64>, Vector3<f64>)> = kept
        .iter()
        .map(|q| {
            let table = kin.actual_table_pose(q);
            let tip = table.inverse_transform_point(&nalgebra::Point3::new(
                q[Axis::X],
                q[Axis::Y],
                q[Axis::Z],
            ));
            let axis = table.rotation.inverse_transform_vector(&Vector3::z());
            let p = to_cone * (tip.coords - cone.center_mm);
            (p.y.atan2(p.x).to_degrees(), p, to_cone * axis)
        })
        .collect();
    let alpha = cone.half_apex_deg.to_radians();
    let (r, flute) = (10.0, 40.0);
    let apex_z = (cone.ballbar_length_mm - r) / alpha.sin();
    let e = &surface.envelope;
    let mut worst: f64 = 0.0;
    for (i, row) in e.rows.iter().enumerate() {
        let rho = (apex_z - row.z_mm) * alpha.tan();
        let mut profile = Vec::new();
        for j in 0..e.column_count() {
            let theta = j as f64 * e.step_deg;
            let (sn, cs) = theta.to_radians().sin_cos();
            let point = Vector3::new(rho * cs, rho * sn, row.z_mm);
            let n = Vector3::new(alpha.cos() * cs, alpha.cos() * sn, alpha.sin());
            let reference = lines
                .iter()
                .filter(|(phi, _, _)| ((phi - theta + 180.0).rem_euclid(360.0) - 180.0).abs() < 1.5)
                .filter_map(|(_, p, t)| reference_depth(&point, &n, p, t, (r, flute)))
                .fold(f64::INFINITY, f64::min);
            let got = e.depth_um(j, i);
            assert!(
                reference.is_finite() && got.is_finite(),
                "z {} θ {theta}: not cut",
                row.z_mm
            );
            worst = worst.max((got - reference).abs());
            assert!(
                (got - reference).abs() <= 0.2,
                "z {} θ {theta}: {got} um against {reference} um",
                row.z_mm
            );
            profile.push((theta.to_radians(), rho + reference * 1e-3 / alpha.cos()));
        }
        if let Some(k) = surface.evaluation_rows().iter().position(|&x| x == i) {
            // The least-squares circle of the reference profile (normal equations, nalgebra).
            let a = nalgebra::DMatrix::from_fn(profile.len(), 3, |m, c| match c {
                0 => 1.0,
                1 => profile[m].0.cos(),
                _ => profile[m].0.sin(),
            });
            let y = nalgebra::DVector::from_iterator(profile.len(), profile.iter().map(|x| x.1));
            let fit = (a.transpose() * &a)
                .lu()
                .solve(&(a.transpose() * &y))
                .unwrap();
            let residual = y - a * fit;
            let roundness_um = (residual.max() - residual.min()) * 1e3;
            let got = surface.figures().heights[k].roundness_um;
            println!(
                "z {:.3}: roundness {got:.4} um, reference {roundness_um:.4} um",
                row.z_mm
            );
            assert!((got - roundness_um).abs() <= 0.2);
        }
    }
    println!("largest difference at a grid point: {worst:.5} um");
}
