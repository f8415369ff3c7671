//! Sinumerik words that name machine data: `G75 FP=n` (fixed point approach, Fundamentals
//! "Fixed point approach (G75)"), taken from the machine's reference positions (FP=1 the
//! G28 position, FP=2 the G30 position), refused where they are not given; and `SPOS`
//! (spindle positioning), which moves no axis of the path.

use std::path::Path;

use ngc::{read_str_with, Axis, AxisVec, Dialect, Error, Motion, Move, Options};

fn options(references: bool) -> Options {
    let mut o = Options {
        dialect: Dialect::Siemens,
        ..Options::default()
    };
    if references {
        o.set_reference(false, AxisVec::xyzabc([-100.0, 0.0, 450.0, 0.0, 0.0, 0.0]));
        o.set_reference(true, AxisVec::xyzabc([0.0, 200.0, 300.0, 0.0, 0.0, 0.0]));
    } else {
        o.reference_missing = [Some("g28_mm".into()), Some("g30_mm".into())];
    }
    o
}

fn read(text: &str, o: &Options) -> Result<Vec<Move>, (usize, String)> {
    read_str_with(Path::new("m.mpf"), text, o)
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| match e {
            Error::Syntax(s) => (s.line, s.message),
            other => panic!("{other}"),
        })
}

#[test]
fn g75_takes_the_named_axes_to_the_fixed_point_at_rapid_and_keeps_g90() {
    let m = read(
        "N10 G90 G0 X10 Y20 Z30\nN20 G75 FP=1 Z1=0\nN30 G75 FP=2 X1=0 Y1=0\nN40 G0 X5\n",
        &options(true),
    )
    .unwrap();
    let ends = |line: usize| -> Vec<[f64; 3]> {
        m.iter()
            .filter(|m| m.line == line)
            .map(|m| {
                assert_eq!(m.motion, Motion::Rapid, "line {line}");
                [m.end[Axis::X], m.end[Axis::Y], m.end[Axis::Z]]
            })
            .collect()
    };
    // FP=1: only Z, to the G28 position's 450; X Y stay.
    assert_eq!(*ends(2).last().unwrap(), [10.0, 20.0, 450.0]);
    // FP=2: X and Y to the G30 position's 0, 200; Z stays at 450.
    assert_eq!(*ends(3).last().unwrap(), [0.0, 200.0, 450.0]);
    // Still absolute after it: X5 is X 5, not 5 more.
    assert_eq!(*ends(4).last().unwrap(), [5.0, 200.0, 450.0]);
}

#[test]
fn g75_without_the_fixed_point_in_the_machine_file_or_beyond_fp2_is_refused() {
    for (text, o, line, want) in [
        ("N10 G75 FP=1 Z1=0\n", options(false), 1, "set g28_mm"),
        ("N10 G75 FP=2 Z1=0\n", options(false), 1, "set g30_mm"),
        (
            "N10 G75 FP=3 Z1=0\n",
            options(true),
            1,
            "fixed points 3 and 4",
        ),
        (
            "N10 G0 X1\nN20 G75 FP=1\n",
            options(true),
            2,
            "G75 without axes",
        ),
        (
            "N10 G74 Z1=0\n",
            options(true),
            1,
            "reference point approach",
        ),
    ] {
        let (l, msg) = read(text, &o).expect_err(text);
        assert!(msg.contains(want), "{text}: {msg}");
        assert_eq!(l, line, "{text}: {msg}");
    }
}

#[test]
fn spos_turns_the_spindle_and_moves_no_axis() {
    let with = read(
        "N10 G0 X10 Y5 Z20\nN20 SPOS=90\nN30 SPOS[1]=IC(45)\nN40 G0 X0\n",
        &options(true),
    )
    .unwrap();
    let without = read("N10 G0 X10 Y5 Z20\nN40 G0 X0\n", &options(true)).unwrap();
    let ends = |m: &[Move]| -> Vec<[f64; 3]> {
        m.iter()
            .map(|m| [m.end[Axis::X], m.end[Axis::Y], m.end[Axis::Z]])
            .collect()
    };
    assert_eq!(ends(&with), ends(&without));
    assert_eq!(ends(&with), [[10.0, 5.0, 20.0], [0.0, 5.0, 20.0]]);
}

/// System variables the program reads take the values the options (the scenario's
/// `[reader] system_variables`) give, with their indices; one not given is refused by name.
#[test]
fn system_variables_read_the_values_given_and_are_refused_by_name_otherwise() {
    let text = "N10 R1=$MN_USER_DATA_HEX[0]+$A_DBB[10]*2\nN20 IF $MN_SCALING_SYSTEM_IS_METRIC==1\nN30 G0 X=R1\nN40 ENDIF\nN50 M30\n";
    let mut o = options(true);
    o.system_variables = vec![
        ("$MN_USER_DATA_HEX[0]".into(), 3.0),
        ("$A_DBB[10]".into(), 4.5),
    ];
    let m = read(text, &o).unwrap();
    assert_eq!(m.last().unwrap().end[Axis::X], 12.0);
    o.system_variables.pop();
    let (line, msg) = read(text, &o).unwrap_err();
    assert_eq!(line, 1);
    assert!(
        msg.contains("`$A_DBB[10]`") && msg.contains("PLC data"),
        "{msg}"
    );
}
