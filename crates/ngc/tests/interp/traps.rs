//! Trap programs (`tests/data/traps/`): short programs, written for this test, of the
//! constructs a reader can get silently wrong (a reference point read as zero, the position
//! after a TCP cancel, a rotary-only block under a tilted plane, macro system variables, a
//! repeat count), in every dialect that has them. Each is either right, its moves checked
//! against positions worked out by hand below, or refused with a message that names what
//! is missing; none reads silently wrong. The Fanuc, Haas and lathe traps of programmable
//! data input, macro arguments, corner rounding and feed per revolution: traps_iso.rs.
//!
//! The machine: axes X Y Z A B C, a table-table AC with its pivot at the origin. Under TCP
//! its axes are `m = R_x(A) R_z(C) (x, y, z − L) + (0, 0, L)` (the table turns the part;
//! `R_x(90°) (0, 10, 0) = (0, 0, 10)` by the right-hand rule). Reference positions (machine):
//! G28 X0 Y0 Z450, G30 X−100 Y200 Z300, except where a trap leaves them out. Tools: T1, T3
//! and T7 of length 0, T2 of length 100 mm.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use ngc::{
    Axis, AxisVec, Dialect, Error, Move, MoveKind, Options, RotaryTable, TcpAxes, Tool, UserM,
};

const TOL: f64 = 1e-9;

pub(super) fn trap(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/traps")
        .join(name)
}

/// The test machine's TCP transform, from the table's rotation.
fn tcp_axes(table: RotaryTable) -> TcpAxes {
    TcpAxes(Arc::new(move |q: &AxisVec, l: f64| {
        let r = table.rotation(q);
        let tip = [q[Axis::X], q[Axis::Y], q[Axis::Z] - l];
        let mut out = *q;
        for (k, a) in [Axis::X, Axis::Y, Axis::Z].into_iter().enumerate() {
            out[a] = (0..3).map(|j| r[k][j] * tip[j]).sum::<f64>();
        }
        out[Axis::Z] += l;
        out
    }))
}

pub(super) fn options(name: &str, references: bool) -> Options {
    let dialect = match Path::new(name).extension().and_then(|e| e.to_str()) {
        Some("ngc") => Dialect::Linuxcnc,
        Some("h") => Dialect::Heidenhain,
        Some("mpf") => Dialect::Siemens,
        _ if name.starts_with("haas") => Dialect::Haas,
        _ => Dialect::Fanuc,
    };
    if name.starts_with("lathe-") {
        // A Fanuc lathe: X and Z, no Y (traps_iso.rs).
        return Options {
            dialect,
            axes: vec![Axis::X, Axis::Z],
            ..Options::default()
        };
    }
    let table = RotaryTable {
        tilt: Axis::A,
        pivot_mm: [0.0; 3],
    };
    let tool = |number, length_mm| Tool {
        number,
        length_mm,
        diameter_mm: 10.0,
    };
    let mut o = Options {
        dialect,
        tools: vec![tool(1, 0.0), tool(2, 100.0), tool(3, 0.0), tool(7, 0.0)],
        table: Some(table),
        tcp_axes: Some(tcp_axes(table)),
        ..Options::default()
    };
    o.user_m.insert(428, UserM::TcpOn);
    o.user_m.insert(429, UserM::TcpOff);
    if references {
        o.set_reference(false, AxisVec::xyzabc([0.0, 0.0, 450.0, 0.0, 0.0, 0.0]));
        o.set_reference(true, AxisVec::xyzabc([-100.0, 200.0, 300.0, 0.0, 0.0, 0.0]));
    } else {
        o.reference_missing = [
            Some("`g28_mm` in the machine file".into()),
            Some("`g30_mm` in the machine file".into()),
        ];
    }
    o
}

pub(super) fn read(name: &str, references: bool) -> Result<Vec<Move>, (usize, String)> {
    let moves = ngc::read_file_with(&trap(name), &options(name, references))
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut out = Vec::new();
    for m in moves {
        match m {
            Ok(m) => out.push(m),
            Err(Error::Syntax(s)) => return Err((s.line, s.message)),
            Err(e) => return Err((0, e.to_string())),
        }
    }
    Ok(out)
}

pub(super) fn right(name: &str) -> Vec<Move> {
    read(name, true).unwrap_or_else(|(line, e)| panic!("{name}:{line}: {e}"))
}

/// The refusal of `name` (without reference positions when `references` is false): its
/// line and message.
pub(super) fn refused(name: &str, references: bool) -> (usize, String) {
    match read(name, references) {
        Ok(m) => panic!("{name}: read ({} moves), expected a refusal", m.len()),
        Err(e) => e,
    }
}

pub(super) fn xyz(p: &AxisVec) -> [f64; 3] {
    [p[Axis::X], p[Axis::Y], p[Axis::Z]]
}

pub(super) fn near(a: [f64; 3], b: [f64; 3]) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() < TOL)
}

#[test]
fn g28_and_g30_without_a_reference_position_are_refused_naming_the_key() {
    for (name, line, key) in [
        ("g28-unset.nc", 4, "g28_mm"),
        ("g30-unset.nc", 4, "g30_mm"),
        ("mb-max-unset.h", 5, "g28_mm"),
    ] {
        let (at, message) = refused(name, false);
        assert_eq!(at, line, "{name}: {message}");
        assert!(message.contains(key), "{name}: {message}");
        assert!(message.contains("not given"), "{name}: {message}");
    }
}

#[test]
fn g28_and_g30_go_to_the_reference_positions() {
    // G91 G28 Z0 from (10, 20, 5): through the point itself, then Z to 450.
    let m = right("g28-set.nc");
    assert!(near(xyz(&m.last().unwrap().end), [10.0, 20.0, 450.0]));
    // G28 X50 Z100 (absolute): through (50, 20, 100), then X and Z to 0 and 450.
    let m = right("g28-via.nc");
    let n = m.len();
    assert!(near(xyz(&m[n - 2].end), [50.0, 20.0, 100.0]));
    assert!(near(xyz(&m[n - 1].end), [0.0, 20.0, 450.0]));
    // G91 G30 X0 Y0 from (10, 20, 5): X Y to (-100, 200), Z stays.
    let m = right("g30-set.nc");
    assert!(near(xyz(&m.last().unwrap().end), [-100.0, 200.0, 5.0]));
    // G28.1 at (5, 6, 70) stores the position: G28 goes back there, with no machine
    // setting.
    let m = read("g28-1-stored.ngc", false).unwrap();
    assert!(near(xyz(&m.last().unwrap().end), [5.0, 6.0, 70.0]));
}

#[test]
fn a_tcp_cancel_takes_the_axes_position_in_every_dialect() {
    // Under TCP the tip (0, 10, 0) at A90: the axes at R_x(90°)(0, 10, 0) = (0, 0, 10).
    // After the cancel `Z20` moves Z alone, from there to 20 (tool length 0).
    for name in [
        "tcp-cancel-fanuc.nc",
        "haas-tcp-cancel.nc",
        "tcp-cancel-linuxcnc.ngc",
        "tcp-cancel-m129.h",
        "tcp-cancel-reset.h",
        "tcp-cancel-trafoof.mpf",
    ] {
        let m = right(name);
        let last = m.last().unwrap();
        assert!(!last.tcp, "{name}: the last move still under TCP");
        assert!(
            near(xyz(&last.start), [0.0, 0.0, 10.0]) && near(xyz(&last.end), [0.0, 0.0, 20.0]),
            "{name}: {:?} -> {:?}",
            xyz(&last.start),
            xyz(&last.end)
        );
        assert!((last.end[Axis::A] - 90.0).abs() < TOL, "{name}");
    }
    // With a 100 mm tool (LinuxCNC M428/M429, G43 H2 stays): the axes at
    // R_x(90°)(0, 10, 0) + (0, 0, 100) = (0, 0, 110); Z20 is the tip at 20, axis Z 120.
    let m = right("tcp-cancel-length.ngc");
    let last = m.last().unwrap();
    assert!(
        near(xyz(&last.start), [0.0, 0.0, 110.0]),
        "{:?}",
        last.start
    );
    assert!(near(xyz(&last.end), [0.0, 0.0, 120.0]), "{:?}", last.end);
}

#[test]
fn a_rotary_alone_under_a_tilted_plane_moves_no_other_axis() {
    for name in ["tilt-rotary-only-fanuc.nc", "tilt-rotary-only.h"] {
        let m = right(name);
        let last = m.last().unwrap();
        assert_eq!(
            xyz(&last.start),
            xyz(&last.end),
            "{name}: X Y Z moved in the C block"
        );
        assert!((last.end[Axis::C] - 90.0).abs() < TOL, "{name}");
    }
}

#[test]
fn macro_alarms_stop_with_their_text() {
    let (line, message) = refused("macro-alarm.nc", true);
    assert_eq!(line, 4);
    assert!(
        message.contains("alarm 7") && message.contains("SPINDLE NOT READY"),
        "{message}"
    );
    let (line, message) = refused("macro-alarm-if.nc", true);
    assert_eq!(line, 4);
    assert!(
        message.contains("alarm 12") && message.contains("TOO MANY PARTS"),
        "{message}"
    );
}

#[test]
fn macro_system_variables_read_the_modal_state_or_are_refused() {
    // #4003 = 90 then 91, #4006 = 21, #4120 = 7.
    let m = right("macro-modal.nc");
    let end = m.last().unwrap().end;
    assert!(
        near(xyz(&end), [90.0, 91.0, 21.0]) && end[Axis::A] == 7.0,
        "{end:?}"
    );
    // #5001 #5002 = 12.5, -3: X13.5 Y-6.
    let m = right("macro-position.nc");
    assert!(near(xyz(&m.last().unwrap().end), [13.5, -6.0, 4.0]));
    // #4014 = 55 in G55 (offset zero here), #4001 = 2 after G2.
    let m = right("macro-work-system.nc");
    let end = xyz(&m.last().unwrap().end);
    assert!(near(end, [55.0, 2.0, 10.0]), "{end:?}");
    // Haas #3026: the tool in the spindle, 3.
    let m = right("haas-tool-in-spindle.nc");
    assert!(near(xyz(&m.last().unwrap().end), [3.0, 0.0, 10.0]));
    for (name, what) in [
        ("macro-date.nc", "date"),
        ("macro-tool-offset.nc", "tool offset"),
    ] {
        let (line, message) = refused(name, true);
        assert_eq!(line, 3, "{name}");
        assert!(
            message.contains(what) && message.contains("not model"),
            "{name}: {message}"
        );
    }
}

#[test]
fn repeat_counts_repeat() {
    // Fanuc G91 G81 X10 … K3 from X0 Z20: R at 20 − 18 = 2, the bottom 2 − 12 = −10; holes
    // at X10, 20, 30.
    let m = right("fanuc-g81-k.nc");
    let bottoms: Vec<[f64; 3]> = m
        .iter()
        .filter(|m| m.kind() == MoveKind::Feed)
        .map(|m| xyz(&m.end))
        .collect();
    assert_eq!(bottoms.len(), 3, "{bottoms:?}");
    for (k, b) in bottoms.iter().enumerate() {
        assert!(near(*b, [10.0 * (k + 1) as f64, 0.0, -10.0]), "{bottoms:?}");
    }
    // Sinumerik REPEAT LAB1 LAB2 P=3: the section once, then three more times: X10 … X40.
    let m = right("siemens-repeat.mpf");
    let xs: Vec<f64> = m
        .iter()
        .filter(|m| m.kind() == MoveKind::Feed)
        .map(|m| m.end[Axis::X])
        .collect();
    assert_eq!(xs, [10.0, 20.0, 30.0, 40.0]);
}

/// G70 I20 J0 L4 after `G81 Z-5 R2 L0` at the origin: G81 at (20, 0), (0, 20), (−20, 0),
/// (0, −20), each down to Z−5.
#[test]
fn haas_g70_drills_the_bolt_hole_circle() {
    let m = right("haas-bolt-circle.nc");
    let bottoms: Vec<[f64; 3]> = m
        .iter()
        .filter(|m| m.motion == ngc::Motion::Linear)
        .map(|m| xyz(&m.end))
        .collect();
    let want = [
        [20.0, 0.0, -5.0],
        [0.0, 20.0, -5.0],
        [-20.0, 0.0, -5.0],
        [0.0, -20.0, -5.0],
    ];
    assert_eq!(bottoms.len(), want.len(), "{bottoms:?}");
    for (got, want) in bottoms.iter().zip(want) {
        assert!(near(*got, want), "{got:?} against {want:?}");
    }
}

/// `Z-5` on a Fanuc (parameter 3401#0 = 0) or a Haas (Setting 162 off) is -0.005 mm: a
/// dimension without a decimal point is in the least input increment (0.001 mm, 0.0001 in
/// under G20), `G4 X1500` is 1,500 ms, and the first word so scaled is named in a warning;
/// with the machine set to whole units (`[control] whole_numbers = "units"`) the same
/// words are mm, in and s, with no warning.
#[test]
fn dimensions_without_a_decimal_point_are_read_in_the_controls_increment() {
    for name in ["fanuc-no-decimal-point.nc", "haas-no-decimal-point.nc"] {
        for (whole, z, x, dwell_s, x_inch) in [
            (ngc::WholeNumbers::Increments, -0.005, 25.0, 1.5, 0.1),
            (ngc::WholeNumbers::Units, -5.0, 25000.0, 1500.0, 1000.0),
        ] {
            let mut o = options(name, true);
            o.control.whole_numbers = (whole == ngc::WholeNumbers::Units).then_some(whole);
            let mut it = ngc::read_file_with(&trap(name), &o).unwrap();
            let moves: Vec<Move> = it.by_ref().map(|m| m.unwrap()).collect();
            let at = |line: usize| moves.iter().find(|m| m.line == line).unwrap();
            assert!((at(5).end[Axis::Z] - z).abs() < TOL, "{name} {whole:?}");
            assert!((at(6).end[Axis::X] - x).abs() < TOL, "{name} {whole:?}");
            assert!(
                matches!(at(7).motion, ngc::Motion::Dwell { seconds } if (seconds - dwell_s).abs() < TOL),
                "{name} {whole:?}: {:?}",
                at(7).motion
            );
            assert!(
                (at(9).end[Axis::X] - x_inch * 25.4).abs() < TOL,
                "{name} {whole:?}"
            );
            let warned = it.notices().iter().any(|n| {
                n.warning && n.line == 5 && n.message.contains("`Z-5` has no decimal point")
            });
            assert_eq!(
                warned,
                whole == ngc::WholeNumbers::Increments,
                "{name} {whole:?}: {:?}",
                it.notices()
            );
        }
    }
}

/// Fanuc `M98 P30100` runs O0100 three times (the repeat count, then the 4-digit
/// program number): X steps 1, 2, 3 mm.
#[test]
fn fanuc_m98_p_holds_the_repeat_count_before_the_program_number() {
    let moves = right("fanuc-m98-repeats.nc");
    let xs: Vec<f64> = moves
        .iter()
        .filter(|m| m.line == 8)
        .map(|m| m.end[Axis::X])
        .collect();
    assert_eq!(xs, [1.0, 2.0, 3.0]);
}

/// Every file of the folder is one of the traps above, so none is left unchecked.
#[test]
fn every_trap_file_is_checked() {
    let this = [include_str!("traps.rs"), include_str!("traps_iso.rs")].concat();
    for e in std::fs::read_dir(trap("")).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(
            this.contains(&format!("\"{name}\"")),
            "{name} is not checked"
        );
    }
}
