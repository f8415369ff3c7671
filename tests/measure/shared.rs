//! Readings shared by the points of a study pass: the single run's readings bit for bit,
//! and the bar's length where it is known in closed form.

use std::cell::RefCell;

use mtsim::input::program::MeasuredLines;
use mtsim::input::Direction;
use mtsim::kinematics::location::{LocationErrors, LocationParam};
use mtsim::kinematics::{Kinematics, Layout};
use mtsim::measure::shared::{SharedBallbar, SharedReadings, SLOTS};
use mtsim::measure::{BallbarSink, BarGeometry, CircleFrame};
use mtsim::pipeline::{Sample, Sink};
use mtsim::{Axis, AxisVec};
use nalgebra::{Point3, Vector3};

const CENTER: [f64; 3] = [0.0, -25.0, 200.0];
const L: f64 = 100.0;

fn geometry(kinematics: Kinematics) -> BarGeometry {
    BarGeometry {
        kinematics,
        frame: CircleFrame::cone(CENTER, 10.0),
        pivot_table_mm: Point3::from(CENTER),
        length_mm: L,
    }
}

fn q(x: f64, y: f64, z: f64, a: f64, c: f64) -> AxisVec {
    let mut q = AxisVec::ZERO;
    (q[Axis::X], q[Axis::Y], q[Axis::Z], q[Axis::A], q[Axis::C]) = (x, y, z, a, c);
    q
}

/// Sample `k` of point `point`: a setpoint swept around the table (A and C turning), every
/// point off it by its own X Y lag; the rotaries' lag is the same for all points but point
/// 3's, whose rotaries lag on their own; the twin lags less.
fn sample(k: u64, point: usize) -> Sample {
    let t = k as f64 * 1e-3;
    let c = 40.0 * t.sin() - 5.0;
    let a = 12.0 + 3.0 * (0.7 * t).cos();
    let commanded = q(
        80.0 * (0.9 * t).cos(),
        70.0 * (0.9 * t).sin() - 20.0,
        150.0 + 10.0 * t,
        a,
        c,
    );
    let lag = 1e-3 * (point as f64 + 1.0);
    let rotary_lag = if point == 3 { 2e-4 } else { 1e-4 };
    let actual = q(
        commanded[Axis::X] - lag,
        commanded[Axis::Y] + 0.5 * lag,
        commanded[Axis::Z],
        a - rotary_lag,
        c + rotary_lag,
    );
    let linear = q(
        commanded[Axis::X] - 0.9 * lag,
        commanded[Axis::Y] + 0.4 * lag,
        commanded[Axis::Z],
        a - 0.5 * rotary_lag,
        c + 0.5 * rotary_lag,
    );
    Sample {
        index: k,
        time_s: t,
        line: 1,
        block_index: 1,
        commanded,
        actual,
        following_error: commanded - actual,
        linear,
    }
}

/// Five points read block by block, as a study pass hands them their samples, give their
/// single readings bit for bit, on the named chain and with location errors.
#[test]
fn shared_readings_are_each_points_own_bit_for_bit() {
    let plain = Kinematics::new(Layout::TrtAc, Vector3::new(1.0, -2.0, 3.0));
    let errors = LocationErrors::default()
        .with(LocationParam::EX0C, 12.0)
        .with(LocationParam::EB0A, -7.0);
    for kinematics in [plain, plain.with_location_errors(errors)] {
        let g = geometry(kinematics);
        let mut shared = SharedReadings::new(g);
        let block = 100;
        for start in (0..3 * SLOTS as u64).step_by(block) {
            for point in 0..5 {
                for k in start..start + block as u64 {
                    let s = sample(k, point);
                    let (mine, alone) = (shared.read(&s), g.read(&s));
                    assert_eq!(format!("{mine:?}"), format!("{alone:?}"), "point {point}");
                    for (a, b) in [
                        (mine.deviation_um, alone.deviation_um),
                        (mine.nonlinear_um, alone.nonlinear_um),
                        (mine.theta_deg, alone.theta_deg),
                    ] {
                        assert_eq!(a.to_bits(), b.to_bits(), "point {point}, sample {k}");
                    }
                }
            }
        }
    }
}

/// With the table at A = C = 0 the table ball sits at pivot + its table position: dL is the
/// plain distance to the tool ball less L.
#[test]
fn a_shared_reading_is_the_distance_between_the_balls_less_the_length() {
    let pivot = [5.0, -4.0, 2.0];
    let g = geometry(Kinematics::new(Layout::TrtAc, Vector3::from(pivot)));
    let ball = [
        pivot[0] + CENTER[0],
        pivot[1] + CENTER[1],
        pivot[2] + CENTER[2],
    ];
    let commanded = q(ball[0] + 60.0, ball[1] + 80.0, ball[2], 0.0, 0.0);
    let actual = q(ball[0] + 60.006, ball[1] + 80.008, ball[2], 0.0, 0.0);
    let s = Sample {
        index: 7,
        time_s: 0.007,
        line: 1,
        block_index: 1,
        commanded,
        actual,
        following_error: commanded - actual,
        linear: commanded,
    };
    let r = SharedReadings::new(g).read(&s);
    // |(60.006, 80.008, 0)| = 100.01 mm; the twin at the setpoint reads 0.
    assert!((r.deviation_um - 10.0).abs() < 1e-6, "{}", r.deviation_um);
    assert!((r.nonlinear_um - 10.0).abs() < 1e-6, "{}", r.nonlinear_um);
}

/// A point's ball bar fed through the shared readings holds its single run's figures.
#[test]
fn a_shared_ballbar_runs_as_its_single_one() {
    let g = geometry(Kinematics::new(Layout::TrtAc, Vector3::zeros()));
    let readings = RefCell::new(SharedReadings::new(g));
    let mut bars: Vec<BallbarSink> = (0..3)
        .map(|_| BallbarSink::new(g, Direction::Ccw, None))
        .collect();
    let mut alone: Vec<BallbarSink> = (0..3)
        .map(|_| BallbarSink::new(g, Direction::Ccw, None))
        .collect();
    for start in (0..6300u64).step_by(256) {
        for (point, (bar, single)) in bars.iter_mut().zip(&mut alone).enumerate() {
            let mut sink = SharedBallbar {
                bar,
                readings: &readings,
            };
            for k in start..(start + 256).min(6300) {
                let s = sample(k, point);
                sink.push(&s).unwrap();
                single.push(&s).unwrap();
            }
        }
    }
    for (bar, single) in bars.iter().zip(&alone) {
        assert!(bar.run.samples() > 6000);
        // Every bin, sum and map of the sink.
        assert_eq!(format!("{bar:?}"), format!("{single:?}"));
    }
}

/// The command maps kept once for the bars of a pass are each bar's own, bit for bit, also
/// when the first bar stops early (its drives failed) and the next one takes over; samples
/// before the measured lines count only as a speed's previous sample.
#[test]
fn maps_kept_once_are_every_bars_own() {
    let g = geometry(Kinematics::new(Layout::TrtAc, Vector3::zeros()));
    let measured = Some(MeasuredLines { first: 2, last: 2 });
    let sample_at = |k: u64, point: usize| Sample {
        line: if k < 300 { 1 } else { 2 },
        ..sample(k, point)
    };
    let readings = RefCell::new(SharedReadings::new(g).with_maps());
    let mut bars: Vec<BallbarSink> = (0..3)
        .map(|_| BallbarSink::new(g, Direction::Ccw, measured).without_maps())
        .collect();
    let mut alone = BallbarSink::new(g, Direction::Ccw, measured);
    // Bar 0 stops at sample 1,000 (in the fourth block), as a failed point does.
    let stop = 1000;
    for start in (0..6300u64).step_by(256) {
        for (point, bar) in bars.iter_mut().enumerate() {
            let mut sink = SharedBallbar {
                bar,
                readings: &readings,
            };
            let end = (start + 256).min(if point == 0 { stop } else { 6300 });
            for k in start..end {
                sink.push(&sample_at(k, point)).unwrap();
            }
        }
        for k in start..(start + 256).min(6300) {
            alone.push(&sample_at(k, 1)).unwrap();
        }
    }
    assert!(bars.iter().all(|b| b.maps.is_none()));
    let kept = readings.into_inner().into_maps().expect("maps kept");
    let own = alone.maps.expect("the single bar's maps");
    let filled = |m: &mtsim::measure::attribution::ThetaMap| {
        (0..72).filter(|&i| m.at(i as f64 * 5.0).is_some()).count()
    };
    assert!(filled(&own.commanded) > 10 && filled(&own.speed) > 10);
    assert_eq!(format!("{kept:?}"), format!("{own:?}"));
}

/// The θ sums and feed kept once for the bars of a pass complete each bar to its single
/// run bit for bit (every bin, sum, count and the feed meter): with samples before the
/// measured lines, a setpoint whose θ is not finite (rejected by every bar alike), and the
/// first bar stopping early (its drives failed) so that the next one takes over the sums.
#[test]
fn theta_sums_kept_once_complete_every_bar_to_its_own() {
    let g = geometry(Kinematics::new(Layout::TrtAc, Vector3::zeros()));
    let measured = Some(MeasuredLines { first: 2, last: 2 });
    let sample_at = |k: u64, point: usize| {
        let mut s = Sample {
            line: if k < 300 { 1 } else { 2 },
            ..sample(k, point)
        };
        if k == 2000 {
            s.commanded[Axis::X] = f64::NAN;
        }
        s
    };
    let readings = RefCell::new(SharedReadings::new(g).with_theta_sums(Direction::Ccw));
    let mut bars: Vec<BallbarSink> = (0..3)
        .map(|_| BallbarSink::new(g, Direction::Ccw, measured).without_maps())
        .collect();
    let mut alone: Vec<BallbarSink> = (0..3)
        .map(|_| BallbarSink::new(g, Direction::Ccw, measured).without_maps())
        .collect();
    let stop = 1000;
    for start in (0..6300u64).step_by(256) {
        for (point, (bar, single)) in bars.iter_mut().zip(&mut alone).enumerate() {
            let mut sink = SharedBallbar {
                bar,
                readings: &readings,
            };
            let end = (start + 256).min(if point == 0 { stop } else { 6300 });
            let samples: Vec<Sample> = (start..end).map(|k| sample_at(k, point)).collect();
            sink.push_many(&samples).unwrap();
            for s in &samples {
                single.push(s).unwrap();
            }
        }
    }
    let readings = readings.into_inner();
    for (point, (bar, single)) in bars.iter_mut().zip(&alone).enumerate().skip(1) {
        assert!(readings.complete(bar), "point {point}");
        assert!(bar.run.samples() > 5000 && bar.run.rejected() == 1);
        assert_eq!(format!("{bar:?}"), format!("{single:?}"), "point {point}");
    }
}

/// A bar one of whose deviations is not finite where θ is (its own runs reject a sample
/// the others take) cannot take the shared θ sums: its point must run alone.
#[test]
fn a_bar_with_a_deviation_not_finite_is_not_completed() {
    let g = geometry(Kinematics::new(Layout::TrtAc, Vector3::zeros()));
    let readings = RefCell::new(SharedReadings::new(g).with_theta_sums(Direction::Ccw));
    let mut bars: Vec<BallbarSink> = (0..3)
        .map(|_| BallbarSink::new(g, Direction::Ccw, None).without_maps())
        .collect();
    for (point, bar) in bars.iter_mut().enumerate() {
        let mut sink = SharedBallbar {
            bar,
            readings: &readings,
        };
        for k in 0..2000u64 {
            let mut s = sample(k, point);
            if point == 1 && k == 700 {
                s.actual[Axis::Y] = f64::INFINITY;
            }
            sink.push(&s).unwrap();
        }
    }
    let readings = readings.into_inner();
    let completed: Vec<bool> = bars.iter_mut().map(|b| readings.complete(b)).collect();
    assert_eq!(completed, [true, false, true]);
}
