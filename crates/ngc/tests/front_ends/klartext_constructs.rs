//! Constructs the TNC 530/640 posts (Fusion, hyperMILL, NX, Mastercam) write, each read as
//! the Klartext programming manual says or refused by name: `F AUTO`, `M140 MB` with a
//! distance apart, `FUNCTION MODE`, `PLANE … STAY` with the angles in Q120-Q122, `SYM-`,
//! `PLANE AXIAL`, the pattern cycles 220/221.

use ngc::{Axis, Feed, Move, Options, RotaryTable};

use super::klartext_setup::{in_program, klartext_options, read_named, xyz};

fn run(body: &str) -> Result<Vec<Move>, (usize, String)> {
    read_named("t.h", &in_program(body), &klartext_options())
}

fn table_ac() -> Options {
    Options {
        table: Some(RotaryTable {
            tilt: Axis::A,
            pivot_mm: [0.0; 3],
        }),
        ..klartext_options()
    }
}

#[test]
fn f_auto_with_a_space_is_the_tool_calls_feed() {
    let m = run("2 TOOL CALL 1 Z S2000 F400\n3 L X+0 Y+0 Z+5 R0 FMAX\n4 L X+10 F AUTO").unwrap();
    let last = m.last().unwrap();
    assert_eq!(last.feed, Feed::PerMinute(400.0));
    assert_eq!(xyz(last), [10.0, 0.0, 5.0]);
}

#[test]
fn m140_mb_with_the_distance_apart_or_signed_retracts_by_it() {
    // From Z 5: MB 20 → Z 25; then MB+15 → Z 40.
    let m =
        run("2 L X+0 Y+0 Z+5 R0 FMAX\n3 M140 MB 20 F500\n4 L Z+5 FMAX\n5 L M140 MB+15").unwrap();
    let z: Vec<f64> = m.iter().map(|m| m.end[Axis::Z]).collect();
    assert!(z.windows(2).any(|w| w == [5.0, 25.0]), "{z:?}");
    assert!(z.windows(2).any(|w| w == [5.0, 20.0]), "{z:?}");
    // `MB` with nothing after it is refused, not taken as MAX.
    let (line, msg) = run("2 L X+0 Y+0 Z+5 R0 FMAX\n3 M140 MB").unwrap_err();
    assert_eq!(line, 4);
    assert!(msg.contains("MB") && msg.contains("distance"), "{msg}");
}

#[test]
fn function_mode_mill_is_read_and_turn_is_refused() {
    let m = run("2 FUNCTION MODE MILL\n3 L X+1 Y+2 Z+3 R0 FMAX").unwrap();
    assert_eq!(xyz(m.last().unwrap()), [1.0, 2.0, 3.0]);
    let (line, msg) = run("2 FUNCTION MODE TURN\n3 L X+1 FMAX").unwrap_err();
    assert_eq!(line, 3);
    assert!(
        msg.contains("FUNCTION MODE TURN") && msg.contains("turning"),
        "{msg}"
    );
}

#[test]
fn plane_stay_stores_the_rotary_angles_in_q120_to_q122() {
    // PLANE SPATIAL SPA+30: the plane's normal in the work frame is Rx(30°) ẑ = (0, −½,
    // √3/2). A table-table AC machine carries it onto +Z with A = 30°, C = ±180°
    // (Rz(180°) gives (0, ½, √3/2), Rx(30°) then (0, 0, 1)), by hand.
    let o = table_ac();
    let stay = read_named(
        "t.h",
        &in_program(
            "2 L X+0 Y+0 Z+50 A+0 C+0 R0 FMAX\n3 PLANE SPATIAL SPA+30 SPB+0 SPC+0 STAY\n\
             4 L A+Q120 C+Q122 R0 FMAX",
        ),
        &o,
    )
    .unwrap();
    let end = stay.last().unwrap().end;
    assert!((end[Axis::A] - 30.0).abs() < 1e-9, "{end:?}");
    assert!((end[Axis::C].abs() - 180.0).abs() < 1e-9, "{end:?}");
    // The same table position as TURN.
    let turn = read_named(
        "t.h",
        &in_program(
            "2 L X+0 Y+0 Z+50 A+0 C+0 R0 FMAX\n3 PLANE SPATIAL SPA+30 SPB+0 SPC+0 TURN FMAX",
        ),
        &o,
    )
    .unwrap();
    let t = turn.last().unwrap().end;
    assert!((t[Axis::A] - end[Axis::A]).abs() < 1e-9 && (t[Axis::C] - end[Axis::C]).abs() < 1e-9);
    // PLANE RESET STAY: 0 and 0.
    let reset = read_named(
        "t.h",
        &in_program(
            "2 L X+0 Y+0 Z+50 A+30 C+90 R0 FMAX\n3 PLANE RESET STAY\n4 L A+Q120 C+Q122 R0 FMAX",
        ),
        &o,
    )
    .unwrap();
    let r = reset.last().unwrap().end;
    assert_eq!((r[Axis::A], r[Axis::C]), (0.0, 0.0));
    // Without a rotary table the angles are not known: reading one is refused, not 0.
    let (line, msg) = run("2 PLANE SPATIAL SPA+30 SPB+0 SPC+0 STAY
3 L A+Q120 C+Q122 R0 FMAX")
    .unwrap_err();
    assert_eq!(line, 4);
    assert!(msg.contains("Q120") && msg.contains("STAY"), "{msg}");
}

#[test]
fn sym_minus_plane_axial_and_the_pattern_cycles_are_refused_by_name() {
    let o = table_ac();
    let (line, msg) = read_named(
        "t.h",
        &in_program("2 PLANE SPATIAL SPA+30 SPB+0 SPC+0 TURN MB MAX FMAX SYM- TABLE ROT"),
        &o,
    )
    .unwrap_err();
    assert_eq!(line, 3);
    assert!(msg.contains("SEQ-"), "{msg}");
    // SYM+ is read as the positive tilt.
    read_named(
        "t.h",
        &in_program("2 PLANE SPATIAL SPA+30 SPB+0 SPC+0 TURN MB MAX FMAX SYM+ TABLE ROT"),
        &o,
    )
    .unwrap();
    let (line, msg) =
        read_named("t.h", &in_program("2 PLANE AXIAL A+30 TURN FMAX"), &o).unwrap_err();
    assert_eq!(line, 3);
    assert!(
        msg.contains("PLANE AXIAL") && msg.contains("rotary axes"),
        "{msg}"
    );
    for (n, title) in [(220, "POLAR PATTERN"), (221, "CARTESIAN PATTERN")] {
        let (line, msg) =
            run(&format!("2 CYCL DEF {n} {title} ~\n Q216=+0 ~\n Q217=+0")).unwrap_err();
        assert_eq!(line, 3);
        assert!(
            msg.contains(&format!("cycle {n} {title}")) && msg.contains("pattern definitions"),
            "{msg}"
        );
    }
}
