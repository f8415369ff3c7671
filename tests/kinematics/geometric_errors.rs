//! Geometric errors of the rotary axes (docs/geometric-errors.md): closed forms, and
//! an independent implementation of the spec against `mtsim simulate`.
//!
//! The reference below is written from the spec's equations alone (its own Rodrigues
//! rotation, its own chain); it calls nothing of mtsim's kinematics.

use crate::common;
use crate::common::CsvTable as Trace;

use std::path::Path;

use mtsim::kinematics::error_table::{ErrorTable, PositionErrors};
use mtsim::kinematics::{Kinematics, Layout, LocationErrors, LocationParam as P};
use mtsim::measure::ballbar::deviation_mm;
use mtsim::{Axis, AxisVec};
use nalgebra::{Point3, Vector3};

// ---------- the independent reference: the spec's equations, nothing else ----------

pub(crate) type V = [f64; 3];

pub(crate) fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(crate) fn add(a: V, b: V) -> V {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
pub(crate) fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(crate) fn cross(a: V, b: V) -> V {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
pub(crate) fn scale(a: V, s: f64) -> V {
    [a[0] * s, a[1] * s, a[2] * s]
}
pub(crate) fn norm(a: V) -> f64 {
    dot(a, a).sqrt()
}

/// Rodrigues: rotate `x` by `theta` (rad) about unit `u`, right-hand rule.
pub(crate) fn rodrigues(u: V, theta: f64, x: V) -> V {
    let (s, c) = theta.sin_cos();
    add(
        add(scale(x, c), scale(cross(u, x), s)),
        scale(u, dot(u, x) * (1.0 - c)),
    )
}

/// One rotary axis's actual line per the spec: point p = pivot + position errors, direction
/// u = unit(n + eps × n). Errors in um and urad.
struct Line {
    p: V,
    u: V,
}

fn line(n: V, pivot: V, pos_um: V, rot_urad: V) -> Line {
    let e = cross(scale(rot_urad, 1e-6), n);
    let u = add(n, e);
    Line {
        p: add(pivot, scale(pos_um, 1e-3)),
        u: scale(u, 1.0 / norm(u)),
    }
}

fn turn(l: &Line, deg: f64, x: V) -> V {
    add(rodrigues(l.u, deg.to_radians(), sub(x, l.p)), l.p)
}

/// Spec errors by name (um / urad); absent = 0.
fn e(errors: &[(&str, f64)], name: &str) -> f64 {
    errors
        .iter()
        .find(|(n, _)| *n == name)
        .map_or(0.0, |(_, v)| *v)
}

/// Machine coordinates of table point `x_table` (relative to the pivot) at tilt `t` and
/// `c` (deg): m = T_tilt(t) T_C(c) (pivot + x).
fn reference_table_point(
    bc: bool,
    pivot: V,
    errors: &[(&str, f64)],
    t: f64,
    c: f64,
    x_table: V,
) -> V {
    let g = |n| e(errors, n);
    let tilt = if bc {
        line(
            [0.0, 1.0, 0.0],
            pivot,
            [g("EX0B"), 0.0, g("EZ0B")],
            [g("EA0B"), 0.0, g("EC0B")],
        )
    } else {
        line(
            [1.0, 0.0, 0.0],
            pivot,
            [0.0, g("EY0A"), g("EZ0A")],
            [0.0, g("EB0A"), g("EC0A")],
        )
    };
    let cl = line(
        [0.0, 0.0, 1.0],
        pivot,
        [g("EX0C"), g("EY0C"), 0.0],
        [g("EA0C"), g("EB0C"), 0.0],
    );
    turn(&tilt, t, turn(&cl, c, add(pivot, x_table)))
}

// ---------- closed forms ----------

fn q(x: f64, y: f64, z: f64, tilt: (Axis, f64), c: f64) -> AxisVec {
    let mut q = AxisVec::ZERO;
    q[Axis::X] = x;
    q[Axis::Y] = y;
    q[Axis::Z] = z;
    q[tilt.0] = tilt.1;
    q[Axis::C] = c;
    q
}

/// A C-axis centre offset e, a ball on the C axis and a tool ball on a horizontal circle of
/// radius L about it (C turning with theta, A = 0): dL = e_x − e_x cos θ − e_y sin θ, a
/// once-per-revolution sinusoid of amplitude |e| on a circle centred on C.
#[test]
fn c_axis_offset_gives_a_once_per_revolution_sinusoid() {
    let pivot = Vector3::new(10.0, -20.0, 30.0);
    let (ex, ey) = (8.0, -5.0); // um
    let k = Kinematics::new(Layout::TrtAc, pivot).with_location_errors(
        LocationErrors::default()
            .with(P::EX0C, ex)
            .with(P::EY0C, ey),
    );
    let (l, h) = (100.0, 80.0);
    for i in 0..36 {
        let th = i as f64 * 10.0;
        let (s, c) = th.to_radians().sin_cos();
        let qq = q(
            pivot.x + l * c,
            pivot.y + l * s,
            pivot.z + h,
            (Axis::A, 0.0),
            th,
        );
        let dl_um = deviation_mm(&k, &qq, &Point3::new(0.0, 0.0, h), l) * 1e3;
        let expected = ex - ex * c - ey * s;
        // first order: the neglected term is |delta|^2 / 2L ~ 2e-3 um
        assert!(
            (dl_um - expected).abs() < 5e-3,
            "theta {th}: {dl_um} um against {expected} um"
        );
    }
}

/// A tilt of the C axis (EA0C, EB0C) seen by a ball at height h on the C axis adds
/// h (EB0C, −EA0C) to the centre offset (to first order: error ~ h eps^2).
#[test]
fn c_axis_tilt_at_ball_height_adds_to_the_offset() {
    let (ex, ey, ea, eb) = (3.0, 2.0, -15.0, 25.0); // um, urad
    let h = 200.0;
    let tilted = Kinematics::new(Layout::TrtAc, Vector3::zeros()).with_location_errors(
        LocationErrors::default()
            .with(P::EX0C, ex)
            .with(P::EY0C, ey)
            .with(P::EA0C, ea)
            .with(P::EB0C, eb),
    );
    // the same with the tilt folded into the offset: e + h (EB0C, -EA0C), um = mm * urad
    let offset = Kinematics::new(Layout::TrtAc, Vector3::zeros()).with_location_errors(
        LocationErrors::default()
            .with(P::EX0C, ex + h * eb * 1e-3)
            .with(P::EY0C, ey - h * ea * 1e-3),
    );
    let ball = Point3::new(0.0, 0.0, h);
    for (a, c) in [(0.0, 0.0), (0.0, 90.0), (20.0, 137.0), (45.0, -250.0)] {
        let qq = q(0.0, 0.0, 0.0, (Axis::A, a), c);
        let d =
            tilted.actual_table_to_machine(&qq, &ball) - offset.actual_table_to_machine(&qq, &ball);
        // horizontal parts agree; the tilt alone also lifts the ball by ~h eps^2
        assert!(d.norm() < 1e-6, "A {a} C {c}: differ by {} mm", d.norm());
    }
}

/// The C-axis offset moves a table point by exactly R_A (I − R_C) e (exact, no linearisation).
#[test]
fn c_axis_offset_moves_the_table_by_the_closed_form() {
    let e = Vector3::new(0.012, -0.007, 0.0); // mm
    let k = Kinematics::new(Layout::TrtAc, Vector3::zeros()).with_location_errors(
        LocationErrors::default()
            .with(P::EX0C, e.x * 1e3)
            .with(P::EY0C, e.y * 1e3),
    );
    let p = Point3::new(30.0, -40.0, 120.0);
    for (a, c) in [(10.0, 30.0), (-20.0, 200.0), (75.0, -45.0)] {
        let qq = q(0.0, 0.0, 0.0, (Axis::A, a), c);
        let ra = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), f64::to_radians(a));
        let rc = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), f64::to_radians(c));
        let expected = ra * (e - rc * e);
        let got = k.actual_table_to_machine(&qq, &p) - k.table_to_machine(&qq, &p);
        assert!((got - expected).norm() < 1e-12, "{got} vs {expected}");
    }
}

/// An A-axis offset (EY0A, EZ0A) moves every table point by (I − R_A) p_A; an A-axis tilt
/// (EB0A, EC0A) moves a point at height h on the C axis by h (EB0A (cos A − 1) + EC0A sin A)
/// along X (first order).
#[test]
fn a_axis_errors_follow_their_closed_forms() {
    let (ey, ez, eb, ec) = (6.0, -4.0, 20.0, -30.0);
    let h = 150.0;
    let k = Kinematics::new(Layout::TrtAc, Vector3::zeros()).with_location_errors(
        LocationErrors::default()
            .with(P::EY0A, ey)
            .with(P::EZ0A, ez)
            .with(P::EB0A, eb)
            .with(P::EC0A, ec),
    );
    let ball = Point3::new(0.0, 0.0, h);
    for a in [5.0_f64, 25.0, 60.0, -30.0] {
        let qq = q(0.0, 0.0, 0.0, (Axis::A, a), 33.0);
        let (s, c) = a.to_radians().sin_cos();
        let p = Vector3::new(0.0, ey, ez) * 1e-3;
        let ra = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), a.to_radians());
        let offset_part = p - ra * p;
        let tilt_part = Vector3::new(h * (eb * (c - 1.0) + ec * s) * 1e-6, 0.0, 0.0);
        let got = k.actual_table_to_machine(&qq, &ball) - k.table_to_machine(&qq, &ball);
        let d = got - offset_part - tilt_part;
        // first order: the neglected terms are ~ h eps^2 ~ 2e-7 mm
        assert!(d.norm() < 1e-6, "A {a}: off by {} mm", d.norm());
    }
}

/// The mtsim chain equals the independent reference for every layout and parameter.
#[test]
fn actual_chain_equals_the_reference_for_every_parameter() {
    let pivot = [5.0, -7.0, 11.0];
    for (layout, tilt, bc) in [
        (Layout::TrtAc, Axis::A, false),
        (Layout::TrtBc, Axis::B, true),
    ] {
        for param in P::ALL
            .into_iter()
            .filter(|p| layout.axes().contains(&p.axis()))
        {
            let v = 37.0;
            let k = Kinematics::new(layout, Vector3::from(pivot))
                .with_location_errors(LocationErrors::default().with(param, v));
            let x = [40.0, -25.0, 150.0];
            for (t, c) in [(17.0, 211.0), (-40.0, -75.0)] {
                let got =
                    k.actual_table_to_machine(&q(0.0, 0.0, 0.0, (tilt, t), c), &Point3::from(x));
                let want = reference_table_point(bc, pivot, &[(param.name(), v)], t, c, x);
                let d = norm(sub([got.x, got.y, got.z], want));
                assert!(d < 1e-10, "{} at {t}/{c}: {d} mm", param.name());
            }
        }
    }
}

// ---------- position-dependent errors ----------

#[test]
fn error_table_interpolates_per_direction_and_wraps_a_full_turn() {
    let text = "# worm gear of C\n0 0.000 0.002\n90 0.004 0.006\n180 0 0.002 # half turn\n270 -0.004 -0.002\n360 0 0.002\n";
    let t = ErrorTable::parse(Path::new("c.comp"), text, true).unwrap();
    assert!((t.error_at(45.0, true) - 0.002).abs() < 1e-15);
    assert!((t.error_at(45.0, false) - 0.004).abs() < 1e-15);
    // periodic: 405 deg is 45 deg, -315 deg too
    assert!((t.error_at(405.0, true) - 0.002).abs() < 1e-15);
    assert!((t.error_at(-315.0, true) - 0.002).abs() < 1e-15);
    // a linear axis holds the end values
    let x = ErrorTable::parse(
        Path::new("x.comp"),
        "-100 -0.01 -0.012\n100 0.01 0.008\n",
        false,
    )
    .unwrap();
    assert_eq!(x.error_at(-500.0, true), -0.01);
    assert_eq!(x.error_at(500.0, false), 0.008);
    assert!((x.error_at(50.0, true) - 0.005).abs() < 1e-15);
}

#[test]
fn error_table_follows_the_direction_of_motion() {
    let x = ErrorTable::parse(
        Path::new("x.comp"),
        "0 0.001 -0.001\n10 0.001 -0.001\n",
        false,
    )
    .unwrap();
    let mut pe = PositionErrors::new([(Axis::X, &x)]);
    let at = |v: f64| {
        let mut q = AxisVec::ZERO;
        q[Axis::X] = v;
        q
    };
    assert_eq!(pe.apply(&at(1.0))[Axis::X], 1.001); // forward before the first move
    assert_eq!(pe.apply(&at(2.0))[Axis::X], 2.001);
    assert_eq!(pe.apply(&at(1.5))[Axis::X], 1.499); // reversed
    assert_eq!(pe.apply(&at(1.5))[Axis::X], 1.499); // at rest: keeps the direction
    assert_eq!(pe.apply_mean(&at(1.5))[Axis::X], 1.5);
}

#[test]
fn bad_error_tables_name_the_line() {
    for (text, needle) in [
        ("0 0 0\n10 x 0\n", ":2:"),
        ("0 0 0\n10 0\n", ":2:"),
        ("0 0 0\n", "at least two"),
        ("0 0 0\n10 0 0\n5 0 0\n", "ascend"),
        ("0 0 0 0\n", "three numbers"),
        ("0 0 NaN\n1 0 0\n", "finite"),
    ] {
        let err = ErrorTable::parse(Path::new("t.comp"), text, false).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains(needle), "{text:?}: {msg}");
    }
}

// ---------- end to end: simulate against the reference ----------

/// A deterministic "hidden" value in [-1, 1) from a seed (LCG), so that the errors are not
/// chosen by hand to be easy.
fn hidden(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// Runs `simulate` on a cone with location errors and checks every row of trace.csv against
/// the reference computed from the row's actual axis positions. Returns the largest
/// difference and the peak-to-peak of the geometric part, um.
fn simulate_against_reference(
    name: &str,
    bc: bool,
    cone: (f64, f64, V, f64),
    errors: &[(&str, f64)],
) -> (f64, f64) {
    let dir = common::scratch("geo", name);
    let base = common::machine(if bc { "trt-bc" } else { "trt-ac" });
    let mut text = std::fs::read_to_string(&base).unwrap();
    text.push_str("\n[location_errors]\n");
    for (n, v) in errors {
        let unit = if n.as_bytes()[1] == b'X' || n.as_bytes()[1] == b'Y' || n.as_bytes()[1] == b'Z'
        {
            "um"
        } else {
            "urad"
        };
        text.push_str(&format!("{n}_{unit} = {v:.6}\n"));
    }
    let machine = dir.join("m.toml");
    std::fs::write(&machine, text).unwrap();
    let (alpha, beta, o, l) = cone;
    let body = format!(
        "[program.cone]\nhalf_apex_deg = {alpha}\ninclination_deg = {beta}\ncenter_mm = [{}, {}, {}]\nballbar_length_mm = {l}\nfeed_mm_min = 3000.0\n[simulate]\ntrace_every = 7\n",
        o[0], o[1], o[2]
    );
    let scenario = common::write_scenario(&dir, &machine.display().to_string(), &body);
    let out = dir.join("out");
    let run = common::mtsim(&[
        "simulate",
        scenario.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--no-timing",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let t = Trace::read(&out.join("trace.csv"));
    let tilt = if bc { "B" } else { "A" };
    let c = |n: &str| t.col(n);
    let (cx, cy, cz, ct, cc, cd) = (
        c("X_act_mm"),
        c("Y_act_mm"),
        c("Z_act_mm"),
        c(&format!("{tilt}_act_deg")),
        c("C_act_deg"),
        c("deviation_um"),
    );
    let (mut worst, mut lo, mut hi) = (0.0_f64, f64::MAX, f64::MIN);
    assert!(t.rows.len() > 500);
    for r in &t.rows {
        let table_ball = reference_table_point(bc, [0.0; 3], errors, r[ct], r[cc], o);
        let nominal_ball = reference_table_point(bc, [0.0; 3], &[], r[ct], r[cc], o);
        let tool = [r[cx], r[cy], r[cz]];
        let dl_um = (norm(sub(tool, table_ball)) - l) * 1e3;
        let geometric_um = dl_um - (norm(sub(tool, nominal_ball)) - l) * 1e3;
        worst = worst.max((dl_um - r[cd]).abs());
        lo = lo.min(geometric_um);
        hi = hi.max(geometric_um);
    }
    (worst, hi - lo)
}

/// The "done when": an independent implementation of the spec agrees with
/// `simulate` to 0.2 um, on cones and errors the code was not tuned on.
#[test]
fn simulate_agrees_with_the_independent_reference_on_hidden_cones() {
    let mut seed = 0x5eed_f6e0_u64;
    // (name, BC layout, (alpha, beta, O, L))
    type Case = (&'static str, bool, (f64, f64, V, f64));
    let cases: [Case; 3] = [
        (
            "ac-15-10-offset",
            false,
            (15.0, 10.0, [20.0, -35.0, 180.0], 100.0),
        ),
        ("ac-45-30", false, (45.0, 30.0, [0.0, 10.0, 150.0], 150.0)),
        ("bc-20-15", true, (20.0, 15.0, [-30.0, 10.0, 220.0], 120.0)),
    ];
    for (name, bc, cone) in cases {
        let names: &[&str] = if bc {
            &[
                "EX0B", "EZ0B", "EA0B", "EC0B", "EX0C", "EY0C", "EA0C", "EB0C",
            ]
        } else {
            &[
                "EY0A", "EZ0A", "EB0A", "EC0A", "EX0C", "EY0C", "EA0C", "EB0C",
            ]
        };
        let errors: Vec<(&str, f64)> = names
            .iter()
            .map(|n| {
                let scale = if matches!(n.as_bytes()[1], b'X' | b'Y' | b'Z') {
                    20.0
                } else {
                    40.0
                };
                (*n, (scale * hidden(&mut seed) * 1e3).round() / 1e3)
            })
            .collect();
        let (worst, p2p) = simulate_against_reference(name, bc, cone, &errors);
        println!("{name}: worst difference {worst:.4} um, geometric part {p2p:.1} um p-p");
        assert!(
            worst < 0.2,
            "{name}: simulate differs from the reference by {worst} um"
        );
        assert!(
            p2p > 5.0,
            "{name}: the errors barely show ({p2p} um): the test is vacuous"
        );
    }
}

// ---------- machine files ----------

fn machine_with(extra: &str, dir: &Path) -> Result<mtsim::input::Machine, String> {
    let mut text = std::fs::read_to_string(common::trt_ac()).unwrap();
    text.push_str(extra);
    let path = dir.join("m.toml");
    std::fs::write(&path, &text).unwrap();
    mtsim::input::Machine::load(&path).map_err(|e| e.to_string())
}

#[test]
fn machine_files_carry_location_errors_and_error_tables() {
    let dir = common::scratch("geo", "machine-files");
    std::fs::write(dir.join("c.comp"), "0 0 0\n360 0.36 0.36\n").unwrap();
    let m = machine_with(
        "\n[location_errors]\nEX0C_um = 8\nEA0C_urad = -15.5\n[error_tables]\nC = \"c.comp\"\n",
        &dir,
    )
    .unwrap();
    assert_eq!(m.kinematics.location_errors.get(P::EX0C), 8.0);
    assert_eq!(m.kinematics.location_errors.get(P::EA0C), -15.5);
    assert_eq!(m.geometry.tables[&Axis::C].error_at(90.0, true), 0.09);

    for (extra, needle) in [
        (
            "\n[location_errors]\nEX0D_um = 1\n",
            "unknown location error",
        ),
        (
            "\n[location_errors]\nEX0C_mm = 1\n",
            "unknown location error",
        ),
        ("\n[location_errors]\nEX0B_um = 1\n", "no B axis"),
        ("\n[location_errors]\nEX0C_um = nan\n", "finite"),
        ("\n[location_errors]\nEX0C_um = 5000.0\n", "within"),
        ("\n[error_tables]\nB = \"c.comp\"\n", "no axis `B`"),
        ("\n[error_tables]\nC = \"missing.comp\"\n", "cannot read"),
    ] {
        let err = machine_with(extra, &dir).unwrap_err();
        assert!(err.contains(needle), "{extra:?}: {err}");
        assert!(err.contains("m.toml:"), "{extra:?} names no line: {err}");
    }
}

/// A worm-gear table on C moves the actual C position by its error: with a table linear in
/// C (slope k), actual − servo position = k · servo position on every traced sample.
#[test]
fn simulate_applies_the_error_table_to_the_actual_position() {
    let dir = common::scratch("geo", "table-sim");
    let k = 1e-4; // deg per deg
    std::fs::write(
        dir.join("c.comp"),
        format!(
            "-1000 {} {}\n1000 {} {}\n",
            -1000.0 * k,
            -1000.0 * k,
            1000.0 * k,
            1000.0 * k
        ),
    )
    .unwrap();
    let mut text = std::fs::read_to_string(common::trt_ac()).unwrap();
    text.push_str("\n[error_tables]\nC = \"c.comp\"\n");
    std::fs::write(dir.join("m.toml"), text).unwrap();
    let body = format!(
        "{}feed_mm_min = 3000.0\n[simulate]\ntrace_every = 11\n",
        common::CONE_15_10
    );
    let scenario = common::write_scenario(&dir, "m.toml", &body);
    let out = dir.join("out");
    let run = common::mtsim(&[
        "simulate",
        scenario.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--no-timing",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let t = Trace::read(&out.join("trace.csv"));
    let (cmd, act, ferr) = (t.col("C_cmd_deg"), t.col("C_act_deg"), t.col("C_ferr_deg"));
    for r in &t.rows {
        let servo = r[cmd] - r[ferr];
        let expected = servo + k * servo;
        assert!((r[act] - expected).abs() < 3e-6, "{} vs {expected}", r[act]);
    }
}

/// Worm-gear error of the tilting table (Kato, Tsutsumi and Sato's pitch-error mechanism):
/// an A-axis table δA(A) = a sin(2π A / p) (one period per worm turn). The ball on the C
/// axis at height h turns about X with A, so to first order the trace changes by
/// `dL = h cos A · u_y · δA` (u: unit bar direction, horizontal in this test), a ripple with
/// one period per worm turn of A. Checked against simulate with and without the table.
#[test]
fn worm_gear_error_of_the_tilting_axis_gives_the_closed_form_ripple() {
    let dir = common::scratch("geo", "worm");
    let (amp_deg, period_deg) = (5.0 / 3600.0, 4.0); // 5 arcsec, a 90-tooth wheel
    let mut table = String::from("# A worm gear: 5 arcsec, one period per worm turn (4 deg)\n");
    // 80 points per period, so that linear interpolation follows the sine to 0.08 %
    for i in 0..=1000 {
        let a = -10.0 + i as f64 * 0.05;
        let e = amp_deg * (2.0 * std::f64::consts::PI * a / period_deg).sin();
        table.push_str(&format!("{a:.3} {e:.9} {e:.9}\n"));
    }
    std::fs::write(dir.join("a-worm.comp"), table).unwrap();
    let base = std::fs::read_to_string(common::trt_ac()).unwrap();
    std::fs::write(dir.join("plain.toml"), &base).unwrap();
    std::fs::write(
        dir.join("worm.toml"),
        format!("{base}\n[error_tables]\nA = \"a-worm.comp\"\n"),
    )
    .unwrap();
    let body = format!(
        "{}feed_mm_min = 3000.0\n[simulate]\ntrace_every = 5\n",
        common::CONE_15_10
    );
    let mut traces = Vec::new();
    for m in ["plain", "worm"] {
        let sub_dir = dir.join(m);
        std::fs::create_dir_all(&sub_dir).unwrap();
        let s = common::write_scenario(&sub_dir, &format!("../{m}.toml"), &body);
        let out = sub_dir.join("out");
        let run = common::mtsim(&[
            "simulate",
            s.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--no-timing",
        ]);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        traces.push(Trace::read(&out.join("trace.csv")));
    }
    let (plain, worm) = (&traces[0], &traces[1]);
    assert_eq!(plain.rows.len(), worm.rows.len());
    let (h, l) = (200.0, 100.0);
    let c = |n: &str| worm.col(n);
    let (mut worst, mut peak) = (0.0_f64, 0.0_f64);
    for (p, w) in plain.rows.iter().zip(&worm.rows) {
        // The servo runs identically in both; A's table acts after it.
        let a_servo = w[c("A_cmd_deg")] - w[c("A_ferr_deg")];
        let d_a = amp_deg * (2.0 * std::f64::consts::PI * a_servo / period_deg).sin();
        // bar direction from the plain run's actual positions (nominal chain, ball on C at h)
        let a = p[c("A_act_deg")].to_radians();
        let ball = [0.0, -h * a.sin(), h * a.cos()];
        let u = scale(
            sub([p[c("X_act_mm")], p[c("Y_act_mm")], p[c("Z_act_mm")]], ball),
            1.0 / l,
        );
        let expected_um = h * a.cos() * u[1] * d_a.to_radians() * 1e3;
        let got_um = w[c("deviation_um")] - p[c("deviation_um")];
        worst = worst.max((got_um - expected_um).abs());
        peak = peak.max(expected_um.abs());
    }
    println!("worm-gear ripple: peak {peak:.2} um, closed form within {worst:.4} um");
    assert!(peak > 2.0, "the ripple is too small to test: {peak} um");
    assert!(
        worst < 0.02 * peak + 0.01,
        "closed form off by {worst} um (peak {peak} um)"
    );
}

/// `analyze` reports the geometric errors' share of the trace; it equals the reference's
/// trace on the exact cone path (spec inverse kinematics, written out here).
#[test]
fn analyze_reports_the_geometric_trace_of_the_reference() {
    let dir = common::scratch("geo", "analyze");
    let errors = [
        ("EX0C", 8.0),
        ("EY0C", -5.0),
        ("EZ0A", 10.0),
        ("EC0A", -30.0),
        ("EA0C", 12.0),
    ];
    let mut text = std::fs::read_to_string(common::trt_ac()).unwrap();
    text.push_str("\n[location_errors]\n");
    for (n, v) in errors {
        let unit = if matches!(n.as_bytes()[1], b'X' | b'Y' | b'Z') {
            "um"
        } else {
            "urad"
        };
        text.push_str(&format!("{n}_{unit} = {v}\n"));
    }
    std::fs::write(dir.join("m.toml"), text).unwrap();
    let (alpha, beta, o, l) = (15.0_f64, 10.0_f64, [0.0, -25.0, 200.0], 100.0);
    let body = format!(
        "[program.cone]\nhalf_apex_deg = {alpha}\ninclination_deg = {beta}\ncenter_mm = [{}, {}, {}]\nballbar_length_mm = {l}\nsegments = 720\n",
        o[0], o[1], o[2]
    );
    let s = common::write_scenario(&dir, "m.toml", &body);
    let v = common::stdout_json(&common::mtsim(&["analyze", s.to_str().unwrap(), "--json"]));
    let g = &v["geometric_trace"];
    // The reference on the exact path: P(θ), t = unit(apex − P), A = acos(t_z),
    // C = atan2(t_x, t_y) (spec), tool in the machine frame = Rx(A) Rz(C) P.
    let (a, b) = (alpha.to_radians(), beta.to_radians());
    let ry = |v: V| {
        [
            v[0] * b.cos() - v[2] * b.sin(),
            v[1],
            v[0] * b.sin() + v[2] * b.cos(),
        ]
    };
    let apex = add(o, ry([0.0, 0.0, l / a.sin()]));
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    for i in 0..1440 {
        let th = (i as f64 * 0.25).to_radians();
        let p = add(
            o,
            ry([l * a.cos() * th.cos(), l * a.cos() * th.sin(), l * a.sin()]),
        );
        let t = scale(sub(apex, p), 1.0 / norm(sub(apex, p)));
        let (ta, tc) = (t[2].acos().to_degrees(), t[0].atan2(t[1]).to_degrees());
        let tool = reference_table_point(false, [0.0; 3], &[], ta, tc, p);
        let ball = reference_table_point(false, [0.0; 3], &errors, ta, tc, o);
        let dl_um = (norm(sub(tool, ball)) - l) * 1e3;
        lo = lo.min(dl_um);
        hi = hi.max(dl_um);
    }
    let (glo, ghi) = (g["min_um"].as_f64().unwrap(), g["max_um"].as_f64().unwrap());
    println!("reference {lo:.3} .. {hi:.3} um, analyze {glo:.3} .. {ghi:.3} um");
    assert!(hi - lo > 10.0);
    assert!(
        (glo - lo).abs() < 0.05 && (ghi - hi).abs() < 0.05,
        "analyze {glo}..{ghi} against {lo}..{hi}"
    );
    // A perfect machine reports none.
    let plain = common::write_scenario(&dir, &common::trt_ac(), &body);
    let v = common::stdout_json(&common::mtsim(&[
        "analyze",
        plain.to_str().unwrap(),
        "--json",
    ]));
    assert!(v["geometric_trace"].is_null());
}

/// `check` acts on the real pose: a pitch error of +10 um on X pushes the cone's X extreme
/// (67.093 mm, spec table) past a limit 5 um beyond it; without the table the program fits.
#[test]
fn check_sees_the_pitch_error_at_the_travel_limit() {
    let dir = common::scratch("geo", "check-limit");
    std::fs::write(dir.join("x.comp"), "-500 0.010 0.010\n500 0.010 0.010\n").unwrap();
    let base = std::fs::read_to_string(common::trt_ac()).unwrap();
    std::fs::write(dir.join("plain.toml"), &base).unwrap();
    std::fs::write(
        dir.join("pitch.toml"),
        format!("{base}\n[error_tables]\nX = \"x.comp\"\n"),
    )
    .unwrap();
    let body = format!(
        "{}[machine_overrides.axes.X]\nmax = 67.098\n[check]\ncollisions = false\n",
        common::CONE_15_10
    );
    let mut codes = Vec::new();
    for m in ["plain", "pitch"] {
        let sub_dir = dir.join(m);
        std::fs::create_dir_all(&sub_dir).unwrap();
        let s = common::write_scenario(&sub_dir, &format!("../{m}.toml"), &body);
        let out = common::mtsim(&["check", s.to_str().unwrap(), "--json"]);
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap_or_default();
        codes.push((out.status.code(), v["violations"].to_string()));
    }
    assert_eq!(codes[0].0, Some(0), "plain: {:?}", codes[0]);
    assert_eq!(codes[1].0, Some(1), "pitch: {:?}", codes[1]);
    assert!(codes[1].1.contains("\"X\""), "{:?}", codes[1]);
}

/// The collision scene moves the table with the actual chain: an A-axis offset EZ0A = 0.5 mm
/// shifts the table and cradle at A = 25 deg by |(I − R_A) p_A| = 2 · 0.5 · sin(12.5 deg) =
/// 0.216 mm, so clearances between table-side and spindle-side bodies change, by at most that.
/// (The pose here is the cone's start; X = 0.)
#[test]
fn the_collision_scene_sees_the_location_errors() {
    use mtsim::check::scene::Scene;
    let dir = common::scratch("geo", "scene");
    let body = format!(
        "{}[machine_overrides.location_errors]\nEZ0A_um = 500.0\n",
        common::CONE_15_10
    );
    let with = common::write_scenario(&dir, &common::trt_ac(), &body);
    let with = mtsim::input::Scenario::load(&with).unwrap();
    let plain = common::write_scenario(&dir, &common::trt_ac(), common::CONE_15_10);
    let plain = mtsim::input::Scenario::load(&plain).unwrap();
    let mut q = AxisVec::ZERO;
    q[Axis::A] = 25.0;
    q[Axis::C] = -90.0;
    q[Axis::Y] = -184.5;
    q[Axis::Z] = 181.3;
    let clearances = |s: &mtsim::input::Scenario| {
        let mut scene = Scene::new(&s.machine, &s.tool, &s.workpiece, 1.0).unwrap();
        scene.set_axes(&q);
        scene.clearances()
    };
    let (a, b) = (clearances(&plain), clearances(&with));
    assert_eq!(a.len(), b.len());
    let bound = 2.0 * 0.5 * 12.5_f64.to_radians().sin();
    let mut largest = 0.0_f64;
    // The table and cradle pairs (plain convex shapes). The riser's hull query is not
    // continuous at the 0.01 mm level (nudging A by 1e-6 deg moves its clearance by 0.01 mm),
    // so it cannot bound a 0.2 mm shift.
    let carried = |n: &str| n == "table" || n.starts_with("cradle");
    for (x, y) in a.iter().zip(&b).filter(|(x, _)| carried(&x.bodies[0])) {
        let d = (x.distance_mm - y.distance_mm).abs();
        assert!(
            d <= bound + 1e-6,
            "{:?}: changed by {d} mm > {bound}",
            x.bodies
        );
        largest = largest.max(d);
    }
    println!("largest clearance change {largest:.4} mm (bound {bound:.4})");
    // The tool hangs above the table: the vertical part of the shift, 0.5 (1 − cos 25°) =
    // 0.0468 mm, shows at least.
    let dz = 0.5 * (1.0 - 25.0_f64.to_radians().cos());
    assert!(
        largest > dz - 1e-3,
        "the scene did not move: {largest} mm (expected >= {dz})"
    );
}
