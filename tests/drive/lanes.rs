//! A study's drives stepped together (`drive::DriveLanes`, its linear twins in SIMD lane
//! groups, `drive::lane_servo`) against each point's own drives (`drive::Drives`) on the
//! same setpoints: every output the same bits, for 1 to 9 points (lane groups of 8 and a
//! ragged one), with and without dry friction and backlash, with a point whose drives fail
//! mid-block and one whose twin leaves the map (force beyond half its limit) for a while.

use mtsim::drive::{AxisServo, DriveLanes, Drives};
use mtsim::input::Machine;
use mtsim::{Axis, AxisVec};

/// The axes at `phase` (rad) of the path: X and Y on a circle of 25 mm, Z, A and C
/// moving with it.
fn at_phase(phase: f64) -> AxisVec {
    let mut q = AxisVec::ZERO;
    q[Axis::X] = 25.0 * phase.cos() - 25.0;
    q[Axis::Y] = 25.0 * phase.sin();
    q[Axis::Z] = 3.0 * (0.5 * phase).sin();
    q[Axis::A] = -10.0 * (0.5 * phase).sin();
    q[Axis::C] = 40.0 * phase;
    q
}

/// A setpoint stream: the axes' positions (mm, deg) at `t` s.
type Path = fn(f64) -> AxisVec;

/// Interpolation periods of the run (the bundled machine's period is 1 ms): 6 s.
const PERIODS: usize = 6_000;

fn trt_ac() -> Machine {
    Machine::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/trt-ac.toml"))
        .unwrap()
}

/// A cone-like path of the five axes at `t` s: X and Y on a circle of 25 mm at about
/// 1,500 mm/min entered from rest (the speed ramps up over 0.5 s, so the feedforward's
/// acceleration jumps), Z, A and C moving with it. X and Y reverse every half turn.
fn setpoint(t: f64) -> AxisVec {
    // ω = 1 rad/s reached at 0.5 s: the phase is ∫ω dt.
    let phase = if t < 0.5 { t * t } else { t - 0.25 };
    at_phase(phase)
}

/// `n` points that differ in X's and Y's kv (so every X and Y twin is distinct) and, with
/// `nonlinear`, in backlash; without it, no axis has dry friction. Point 2 has a following
/// error limit on X that the circle passes (its drive and twin fail), point 4 an X force
/// limit its twin's circle exceeds by half (its twin runs periods by substeps).
fn machines(n: usize, nonlinear: bool) -> Vec<Machine> {
    (0..n)
        .map(|i| {
            let mut m = trt_ac();
            for (a, kv) in [(Axis::X, 25.0 + i as f64), (Axis::Y, 34.0 - 0.5 * i as f64)] {
                let d = m.drive(a).with_kv_per_s(kv).unwrap();
                let backlash_mm = if nonlinear { 0.001 * i as f64 } else { 0.0 };
                let mut d = d.with_backlash_mm_or_deg(backlash_mm).unwrap();
                if i == 2 {
                    d.following_error_limit_m_or_rad = 0.4 * 1e-3; // 0.4 mm, as resolved
                }
                if i == 4 && a == Axis::X {
                    d.force_limit_n_or_nm = FORCE_LIMIT_N;
                }
                m.axis_mut(a).drive = d;
            }
            if !nonlinear {
                for a in [Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::C] {
                    m.axis_mut(a).drive.coulomb_n_or_nm = 0.0;
                }
            }
            m
        })
        .collect()
}

/// Point 4's X force limit, N.
const FORCE_LIMIT_N: f64 = 60.0;

/// One point alone: per setpoint, each axis's actual position and following error of its
/// drive and its twin's actual position, until the first of them fails.
fn single(machine: &Machine, q0: &AxisVec, path: Path) -> Vec<Vec<(Axis, f64, f64, f64)>> {
    let mut drives = Drives::new(machine, q0, false).unwrap();
    let mut twins = Drives::new(machine, q0, true).unwrap();
    let mut out = Vec::new();
    for k in 1..=PERIODS {
        let t = k as f64 * 1e-3;
        let q = path(t);
        let (Ok(d), Ok(linear)) = (drives.step(&q, t), twins.step_actual(&q, t)) else {
            break;
        };
        let axes = machine.axes().iter();
        out.push(
            axes.map(|&a| (a, d.actual[a], d.following_error[a], linear[a]))
                .collect(),
        );
    }
    out
}

/// The same points in lanes, block by block: each point's outputs until it stops.
fn in_lanes(machines: &[Machine], q0: &AxisVec) -> Vec<Vec<Vec<(Axis, f64, f64, f64)>>> {
    in_lanes_counted(machines, q0, setpoint).0
}

/// Servos a lane group of this host steps side by side (16 with AVX-512, else 8).
fn host_width() -> usize {
    DriveLanes::new(&[], &AxisVec::ZERO).unwrap().lane_width()
}

/// [`in_lanes`] with [`DriveLanes::lane_periods`] and
/// [`DriveLanes::lane_substep_periods`] at the end, in this host's lane groups; the same
/// points in lane groups of 8 ([`DriveLanes::narrow`], the groups and code of a host
/// without AVX-512) give the same outputs, bit for bit.
#[allow(clippy::type_complexity)]
fn in_lanes_counted(
    machines: &[Machine],
    q0: &AxisVec,
    path: Path,
) -> (Vec<Vec<Vec<(Axis, f64, f64, f64)>>>, [(u64, u64); 2], u64) {
    let refs: Vec<&Machine> = machines.iter().collect();
    let host = step_in_lanes(DriveLanes::new(&refs, q0).unwrap(), path);
    let narrow = step_in_lanes(DriveLanes::narrow(&refs, q0).unwrap(), path);
    assert_eq!(narrow.1, 8, "narrow lane groups");
    for (i, (a, b)) in host.0.iter().zip(&narrow.0).enumerate() {
        assert!(bits(a) == bits(b), "point {i}: 8-lane groups differ");
    }
    (host.0, host.2, host.3)
}

/// Each point's outputs from `lanes` until it stops, with the lane width and the counts of
/// [`in_lanes_counted`].
#[allow(clippy::type_complexity)]
fn step_in_lanes(
    mut lanes: DriveLanes,
    path: Path,
) -> (
    Vec<Vec<Vec<(Axis, f64, f64, f64)>>>,
    usize,
    [(u64, u64); 2],
    u64,
) {
    let points = lanes.len();
    let mut out = vec![Vec::new(); points];
    let mut alive = vec![true; points];
    // Blocks of 256 and a ragged last one.
    let times: Vec<f64> = (1..=PERIODS).map(|k| k as f64 * 1e-3).collect();
    for block_t in times.chunks(mtsim::drive::lanes::BLOCK) {
        let block_q: Vec<AxisVec> = block_t.iter().map(|&t| path(t)).collect();
        lanes.step_block(&block_q, block_t);
        for (i, point) in out.iter_mut().enumerate() {
            if !alive[i] {
                assert_eq!(lanes.completed(i), 0, "point {i} failed before");
                continue;
            }
            let completed = lanes.completed(i).min(block_t.len());
            alive[i] = completed == block_t.len();
            let outputs: Vec<_> = lanes.outputs(i).collect();
            for j in 0..completed {
                point.push(
                    outputs
                        .iter()
                        .map(|(a, actual, fe, linear)| (*a, actual[j], fe[j], linear[j]))
                        .collect(),
                );
            }
        }
    }
    let counts = lanes.lane_periods();
    let width = lanes.lane_width();
    (out, width, counts, lanes.lane_substep_periods())
}

fn bits(run: &[Vec<(Axis, f64, f64, f64)>]) -> Vec<Vec<(Axis, u64, u64, u64)>> {
    run.iter()
        .map(|step| {
            step.iter()
                .map(|&(a, x, fe, l)| (a, x.to_bits(), fe.to_bits(), l.to_bits()))
                .collect()
        })
        .collect()
}

#[test]
fn lane_groups_of_1_point_to_more_than_a_group_give_each_points_own_drives_bit_for_bit() {
    let q0 = setpoint(0.0);
    for nonlinear in [false, true] {
        // Groups too small to be groups, ragged ones, a full one and a full one with a
        // ragged one (or a servo alone) beside it.
        let w = host_width();
        for n in (1..=9).chain([w - 1, w, w + 1, w + 3]) {
            let machines = machines(n, nonlinear);
            let lanes = in_lanes(&machines, &q0);
            for (i, (machine, lane)) in machines.iter().zip(&lanes).enumerate() {
                let single = single(machine, &q0, setpoint);
                let what = format!("{n} points, nonlinear {nonlinear}, point {i}");
                // Point 2's following error passes its limit within the first turn, in
                // the middle of a block; the others run to the end.
                if i == 2 {
                    assert!(single.len() > 100 && single.len() < PERIODS, "{what}");
                    assert_ne!(single.len() % 256, 0, "{what}: fails mid-block");
                } else {
                    assert_eq!(single.len(), PERIODS, "{what}");
                }
                assert_eq!(lane.len(), single.len(), "{what}: setpoints completed");
                assert!(bits(lane) == bits(&single), "{what}: outputs differ");
            }
        }
    }
}

/// The equality above would hold if the lane groups handed every period to the scalar
/// servo: here they must step most periods themselves. Eight points of distinct X and Y
/// drives make one group of X drives and one of Y drives, and as many of twins.
#[test]
fn the_lane_groups_step_most_periods_themselves() {
    let q0 = setpoint(0.0);
    let machines = machines(8, true);
    let (_, [drives, twins], _) = in_lanes_counted(&machines, &q0, setpoint);
    for (what, (stepped, handed_back)) in [("drives", drives), ("twins", twins)] {
        // Two groups (X and Y) of 8 live lanes over the periods, less the failing point's
        // (its servo of one axis or both stops after more than 100 setpoints).
        let periods = PERIODS as u64;
        assert!(
            (14 * periods + 200..=16 * periods).contains(&stepped),
            "{what}: {stepped} lane periods"
        );
        assert!(
            handed_back * 4 < stepped,
            "{what}: {handed_back} of {stepped} lane periods handed to the scalar servo"
        );
    }
}

/// Point 4's X twin does leave the map: its force passes half its limit in some periods
/// (which the lane group then runs through the scalar servo), and takes it in most.
#[test]
fn the_force_limited_twin_leaves_the_map_for_some_periods() {
    let machine = &machines(5, false)[4];
    let twin = machine.drive(Axis::X).linear_twin();
    let mut servo = AxisServo::new(
        &twin,
        machine.interpolation_period_s,
        setpoint(0.0)[Axis::X],
    )
    .unwrap();
    for k in 1..=PERIODS {
        let t = k as f64 * 1e-3;
        servo.advance_twin(setpoint(t)[Axis::X], t).unwrap();
    }
    let (mapped, substepped) = servo.period_counts();
    assert!(
        substepped > 10 && mapped > 2 * substepped,
        "{mapped} {substepped}"
    );
}

/// Uniform draws in `[lo, hi)` from xorshift64* seeded with `seed`: fixed and reproducible.
fn uniform_draws(mut seed: u64) -> impl FnMut(f64, f64) -> f64 {
    move |lo, hi| {
        seed ^= seed >> 12;
        seed ^= seed << 25;
        seed ^= seed >> 27;
        let r = seed.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        lo + (hi - lo) * (r as f64 / (1u64 << 53) as f64)
    }
}

/// Per-lane regime switches on random drives: 16 points (two lane groups of X and two of
/// Y drives) whose X and Y drives differ in kv, backlash (0-8 µm, some none), Coulomb
/// friction (0-300 N, some none), static over Coulomb friction (1-1.6) and Stribeck
/// velocity (0.5-5 mm/s), on a path that stops and dwells (the table sticks), creeps at
/// 1.25 mm/s inside the Stribeck zone and reverses (the backlash is taken up). Each point
/// in lanes gives its single run's bits, and the lanes step every period themselves: by
/// their maps, or where no map applies (sticking, in the gap) by substeps in the lanes.
#[test]
fn random_drives_switching_regimes_in_lanes_give_their_single_runs_bit_for_bit() {
    let q0 = stop_and_go(0.0);
    let mut uniform = uniform_draws(0x2545_f491_4f6c_dd1d);
    let machines: Vec<Machine> = (0..16)
        .map(|i| {
            let mut m = trt_ac();
            for a in [Axis::X, Axis::Y] {
                let backlash_mm = if i % 5 == 0 { 0.0 } else { uniform(0.0, 0.008) };
                let d = m.drive(a).with_kv_per_s(uniform(20.0, 40.0)).unwrap();
                let mut d = d.with_backlash_mm_or_deg(backlash_mm).unwrap();
                d.coulomb_n_or_nm = if i % 7 == 3 {
                    0.0
                } else {
                    uniform(20.0, 300.0)
                };
                d.static_ratio = uniform(1.0, 1.6);
                d.stribeck_m_or_rad_per_s = uniform(0.5e-3, 5e-3);
                m.axis_mut(a).drive = d;
            }
            m
        })
        .collect();
    let (lanes, [drives, _], substepped) = in_lanes_counted(&machines, &q0, stop_and_go);
    let (mut stuck, mut rest) = (0, Vec::new());
    for (i, (machine, lane)) in machines.iter().zip(&lanes).enumerate() {
        let single = single(machine, &q0, stop_and_go);
        assert_eq!(single.len(), PERIODS, "point {i}");
        assert_eq!(lane.len(), single.len(), "point {i}: setpoints completed");
        assert!(bits(lane) == bits(&single), "point {i}: outputs differ");
        // X's table at rest (within 0.1 nm a period: the pre-sliding bristle creeps) over
        // ten periods of the dwell while friction holds it.
        let x = |k: usize| single[k].iter().find(|o| o.0 == Axis::X).unwrap().1;
        let resting = (2000..2400)
            .filter(|&k| (x(k) - x(k - 1)).abs() < 1e-7)
            .count();
        rest.push(resting);
        if machine.drive(Axis::X).coulomb_n_or_nm > 0.0 && resting >= 10 {
            stuck += 1;
        }
    }
    assert!(
        stuck >= 5,
        "{stuck} points' X tables stuck in the dwell: {rest:?}"
    );
    let (stepped, handed_back) = drives;
    assert!(
        handed_back == 0 && substepped * 20 > stepped && substepped * 2 < stepped,
        "{handed_back} of {stepped} lane periods handed to the scalar servo, \
         {substepped} by substeps in the lanes"
    );
}

/// The cone-like path of [`setpoint`] with its angular speed ω (rad/s) piecewise linear
/// through `(t, ω)`: from rest to 1 by 0.5 s, to rest at 2.0 s, a dwell to 2.4 s, back to
/// 1 at 2.6 s, down to 0.05 (X and Y at 1.25 mm/s) from 3.7 to 4.5 s, and 1 from 4.7 s.
/// The phase is ∫ω dt, exact by the trapezoids of the linear pieces.
fn stop_and_go(t: f64) -> AxisVec {
    const KNOTS: [(f64, f64); 10] = [
        (0.0, 0.0),
        (0.5, 1.0),
        (1.8, 1.0),
        (2.0, 0.0),
        (2.4, 0.0),
        (2.6, 1.0),
        (3.5, 1.0),
        (3.7, 0.05),
        (4.5, 0.05),
        (4.7, 1.0),
    ];
    let mut phase = 0.0;
    for w in KNOTS.windows(2) {
        let ((t0, w0), (t1, w1)) = (w[0], w[1]);
        let end = t.min(t1);
        if end <= t0 {
            break;
        }
        let w_end = w0 + (w1 - w0) * (end - t0) / (t1 - t0);
        phase += 0.5 * (w0 + w_end) * (end - t0);
    }
    phase += (t - 4.7).max(0.0);
    at_phase(phase)
}

/// Creeping drives inside their Stribeck zones, where each lane's friction slope (hence its
/// period map on the slope grid) is its own: 8 points whose X and Y drives differ in kv,
/// Coulomb friction (50-300 N), static over Coulomb friction (1.2-2) and Stribeck velocity
/// (2-5 mm/s), on a path that creeps at 3 mm/s along X and -2.5 mm/s along Y for 6 s
/// (`|v|/vs` from 0.5 to 1.5: slopes from about a fifth to all of the grid's largest).
/// Each point in lanes gives its single run's bits, and the lanes step almost every period
/// themselves, at their own slopes: a lane that took a period by another slope's map, or by
/// another lane's map, would give other bits; one that handed every period off the slope-0
/// map to the scalar servo would hand back most of them.
#[test]
fn creeping_drives_step_in_lanes_by_their_own_slopes_maps_bit_for_bit() {
    fn creep(t: f64) -> AxisVec {
        let mut q = AxisVec::ZERO;
        q[Axis::X] = 3.0 * t; // 3 mm/s
        q[Axis::Y] = -2.5 * t; // -2.5 mm/s
        q
    }
    let q0 = creep(0.0);
    let machines: Vec<Machine> = (0..8)
        .map(|i| {
            let mut m = trt_ac();
            let f = i as f64 / 7.0;
            for (a, g) in [(Axis::X, f), (Axis::Y, 1.0 - f)] {
                let mut d = m.drive(a).with_kv_per_s(25.0 + 10.0 * g).unwrap();
                d.coulomb_n_or_nm = 50.0 + 250.0 * (1.0 - g);
                d.static_ratio = 1.2 + 0.8 * g;
                d.stribeck_m_or_rad_per_s = (2.0 + 3.0 * g) * 1e-3;
                m.axis_mut(a).drive = d;
            }
            m
        })
        .collect();
    let (lanes, [drives, _], _) = in_lanes_counted(&machines, &q0, creep);
    for (i, (machine, lane)) in machines.iter().zip(&lanes).enumerate() {
        let single = single(machine, &q0, creep);
        assert_eq!(single.len(), PERIODS, "point {i}");
        assert_eq!(lane.len(), single.len(), "point {i}: setpoints completed");
        assert!(bits(lane) == bits(&single), "point {i}: outputs differ");
    }
    let (stepped, handed_back) = drives;
    assert!(
        stepped >= 16 * PERIODS as u64 && handed_back * 50 < stepped,
        "{handed_back} of {stepped} lane periods handed to the scalar servo"
    );
}

/// The substep periods in lanes (`drive::lane_drive`'s substeps) through every branch of
/// the scalar substep period: two lane groups' points (twice the host's width) whose X and Y drives
/// differ in kv, backlash (some
/// none), dry friction (some none), semi- or fully-closed loops, and force limits low
/// enough that the force command saturates (the clamp and the anti-windup act) when the
/// stop-and-go path accelerates (point 5's, at 90 N, long enough for the integral to
/// wind up); point 7's force limit is too low for the path and its following error limit
/// tight, so that its drives fail. The second lane group of each
/// axis has a drive of 3 substeps among drives of 2: it cannot step its substeps in lanes
/// and hands those periods to the scalar servo. Every point in lanes gives its single run's
/// bits, and the first groups step all their periods themselves, thousands by substeps.
#[test]
fn substep_periods_in_lanes_give_the_scalar_servos_periods_bit_for_bit() {
    let q0 = stop_and_go(0.0);
    let mut uniform = uniform_draws(0x9e37_79b9_7f4a_7c15);
    let w = host_width();
    let machines: Vec<Machine> = (0..2 * w)
        .map(|i| {
            let mut m = trt_ac();
            for a in [Axis::X, Axis::Y] {
                let backlash_mm = if i % 4 == 1 { 0.0 } else { uniform(0.0, 0.008) };
                let d = m.drive(a).with_kv_per_s(uniform(20.0, 40.0)).unwrap();
                let mut d = d.with_backlash_mm_or_deg(backlash_mm).unwrap();
                d.coulomb_n_or_nm = if i % 6 == 2 {
                    0.0
                } else {
                    uniform(50.0, 250.0)
                };
                d.static_ratio = uniform(1.0, 1.6);
                d.fully_closed = i % 3 == 0;
                d.force_limit_n_or_nm = uniform(400.0, 900.0);
                if i == 5 {
                    d.coulomb_n_or_nm = 40.0;
                    d.force_limit_n_or_nm = 90.0;
                }
                if i == 7 {
                    d.force_limit_n_or_nm = 120.0;
                    d.following_error_limit_m_or_rad = 0.05e-3;
                }
                if i == w + 4 {
                    d.substeps = 3;
                }
                m.axis_mut(a).drive = d;
            }
            m
        })
        .collect();
    let (lanes, [drives, _], substepped) = in_lanes_counted(&machines, &q0, stop_and_go);
    for (i, (machine, lane)) in machines.iter().zip(&lanes).enumerate() {
        let single = single(machine, &q0, stop_and_go);
        if i == 7 {
            assert!(single.len() < PERIODS, "point 7 fails");
        } else {
            assert_eq!(single.len(), PERIODS, "point {i}");
        }
        assert_eq!(lane.len(), single.len(), "point {i}: setpoints completed");
        assert!(bits(lane) == bits(&single), "point {i}: outputs differ");
    }
    let (stepped, handed_back) = drives;
    assert!(
        substepped > 2_000 && handed_back > 0,
        "{handed_back} of {stepped} lane periods handed to the scalar servo, \
         {substepped} by substeps in the lanes"
    );
}
