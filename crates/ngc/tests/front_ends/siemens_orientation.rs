//! Sinumerik programs found by their file name or header, and the tool's direction vector
//! `A3= B3= C3=` under TRAORI (Job planning, "Orientation programming: direction vectors").
//! The rotary angles are worked by hand for a table-table AC machine (`R_t = Rx(A) Rz(C)`,
//! tilt = acos(t_z), C = 90° − atan2(t_y, t_x)), and checked independently: `R_t t` must be
//! the machine's +Z.

use std::path::Path;

use ngc::{read_str_with, Axis, Error, Move, Options, RotaryTable};

fn table_ac() -> Options {
    Options {
        table: Some(RotaryTable {
            tilt: Axis::A,
            pivot_mm: [0.0; 3],
        }),
        ..Options::default()
    }
}

/// The moves of `text` read as the file `name` with the default dialect (LinuxCNC), or its
/// refusal's (line, message).
fn read(name: &str, text: &str, o: &Options) -> Result<Vec<Move>, (usize, String)> {
    read_str_with(Path::new(name), text, o)
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| match e {
            Error::Syntax(s) => (s.line, s.message),
            other => panic!("{other}"),
        })
}

/// `Rx(a) Rz(c) v`, degrees.
fn rx_rz(a: f64, c: f64, v: [f64; 3]) -> [f64; 3] {
    let (sc, cc) = c.to_radians().sin_cos();
    let w = [cc * v[0] - sc * v[1], sc * v[0] + cc * v[1], v[2]];
    let (sa, ca) = a.to_radians().sin_cos();
    [w[0], ca * w[1] - sa * w[2], sa * w[1] + ca * w[2]]
}

const ORIENTED: &str = "N10 G90 G17 G71\nN20 TRAORI\nN30 G0 X0 Y0 Z50 A0 C0\n\
N40 G1 X10 Y0 Z5 A3=0.5 B3=0 C3=0.8660254038 F1000\nN50 X20 C3=1\n\
N60 X30 B3=-2 C3=2\nN70 TRAFOOF\nN80 M30\n";

#[test]
fn a_program_named_mpf_or_spf_or_with_a_sinumerik_header_is_read_as_sinumerik() {
    let body = "N10 G90 G0 X0 Y0 Z50\nN20 CYCLE800()\nN30 G1 X=AC(12.5) F500\nN40 M30\n";
    for (name, text) in [
        ("part.MPF", body.to_string()),
        ("sub.spf", body.to_string()),
        (
            "part.nc",
            format!("%_N_PART_MPF\n;$PATH=/_N_MPF_DIR\n{body}"),
        ),
        ("part.txt", format!("; %_N_PART1_MPF\n{body}")),
    ] {
        let m = read(name, &text, &Options::default()).unwrap_or_else(|e| panic!("{name}: {e:?}"));
        assert_eq!(m.last().unwrap().end[Axis::X], 12.5, "{name}");
    }
    // The same text in a file of another name and without the header: refused, the
    // language named at its first Sinumerik word.
    let (line, msg) = read("part.nc", body, &Options::default()).unwrap_err();
    assert_eq!(line, 2);
    assert!(msg.contains("Siemens Sinumerik"), "{msg}");
}

#[test]
fn a3_b3_c3_turn_the_table_so_the_tool_lies_along_the_vector() {
    let m = read("o.mpf", ORIENTED, &table_ac()).unwrap();
    let at = |line: usize| m.iter().rfind(|m| m.line == line).unwrap();
    // N40: t = (0.5, 0, cos 30°): tilt 30°, C = 90° − atan2(0, 0.5) = 90°.
    // N50: t = (0, 0, 1): tilt 0, C keeps 90°.
    // N60: t = (0, −2, 2)/|…| = (0, −sin 45°, cos 45°): tilt 45°, C = 90° + 90° = 180°
    // (next to 90°, not −180°).
    for (line, a, c, t) in [
        (4, 30.0, 90.0, [0.5, 0.0, 0.8660254038]),
        (5, 0.0, 90.0, [0.0, 0.0, 1.0]),
        (6, 45.0, 180.0, [0.0, -0.5f64.sqrt(), 0.5f64.sqrt()]),
    ] {
        let mv = at(line);
        assert!(mv.tcp, "line {line}");
        assert!(
            (mv.end[Axis::A] - a).abs() < 1e-6,
            "line {line}: {:?}",
            mv.end
        );
        assert!(
            (mv.end[Axis::C] - c).abs() < 1e-6,
            "line {line}: {:?}",
            mv.end
        );
        let up = rx_rz(mv.end[Axis::A], mv.end[Axis::C], t);
        assert!(
            up.iter()
                .zip([0.0, 0.0, 1.0])
                .all(|(u, z)| (u - z).abs() < 1e-9),
            "line {line}: R_t t = {up:?}"
        );
    }
    // Under TCP the move's X Y Z are the programmed tip.
    assert_eq!(
        [at(6).end[Axis::X], at(6).end[Axis::Y], at(6).end[Axis::Z]],
        [30.0, 0.0, 5.0]
    );
}

#[test]
fn a3_b3_c3_where_mtsim_cannot_tell_the_orientation_are_refused_by_name() {
    let cases = [
        ("N10 G1 X1 C3=1 F100\n", &table_ac(), 1, "without TRAORI"),
        (
            "N10 TRAORI\nN20 ORIMKS\nN30 G1 X1 C3=1 F100\n",
            &table_ac(),
            3,
            "ORIMKS",
        ),
        (
            "N10 TRAORI\nN20 ROT Z30\nN30 G1 X1 C3=1 F100\n",
            &table_ac(),
            3,
            "turns, scales or mirrors",
        ),
        (
            "N10 TRAORI\nN20 G1 X1 A10 C3=1 F100\n",
            &table_ac(),
            2,
            "gives the tool's orientation twice",
        ),
        (
            "N10 TRAORI\nN20 G1 X1 A3=0 B3=0 C3=0 F100\n",
            &table_ac(),
            2,
            "zero vector",
        ),
        (
            "N10 TRAORI\nN20 G1 X1 C3=1 F100\n",
            &Options::default(),
            2,
            "no rotary axes",
        ),
    ];
    for (body, o, want_line, want) in cases {
        let (line, msg) = read("r.mpf", body, o).expect_err(body);
        assert!(msg.contains(want), "{body}: {msg}");
        assert_eq!(line, want_line, "{body}: {msg}");
    }
}
