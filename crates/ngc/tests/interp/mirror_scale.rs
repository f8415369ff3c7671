//! Programmable mirror image and scaling: Fanuc G51.1/G50.1 and G51/G50, Haas G101/G100.
//! The expected positions are worked out by hand from the manuals' rule: mirror about
//! `m`, `v' = 2m − v`; scale about `c` by `s`, `v' = c + s (v − c)`; an increment scaled by
//! `s` (negated when mirrored); an arc that the map turns over runs the other way.

use std::path::Path;

use ngc::{read_str_with, Axis, Dialect, Motion, Move, Options};

fn read(dialect: Dialect, text: &str) -> Result<Vec<Move>, String> {
    let options = Options {
        dialect,
        ..Options::default()
    };
    read_str_with(Path::new("t.nc"), text, &options)
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| e.to_string())
}

fn xy(m: &Move) -> (f64, f64) {
    (m.end[Axis::X], m.end[Axis::Y])
}

fn at(moves: &[Move], line: usize) -> &Move {
    moves
        .iter()
        .find(|m| m.line == line)
        .unwrap_or_else(|| panic!("no move of line {line}"))
}

#[test]
fn a_fanuc_mirror_about_x50_reflects_x_and_turns_g2_into_g3() {
    let text = "G21 G90 G17 G54\nG0 X0. Y0. Z10.\nG51.1 X50.\nG1 X10. Y5. F500\n\
                G2 X20. Y15. I10. J0.\nG91 G1 X5.\nG50.1 X0\nG90 G1 X10. Y5.\nM30\n";
    let moves = read(Dialect::Fanuc, text).unwrap();
    assert_eq!(xy(at(&moves, 4)), (90.0, 5.0));
    let arc = at(&moves, 5);
    assert_eq!(xy(arc), (80.0, 15.0));
    match arc.motion {
        Motion::Arc {
            clockwise,
            center_mm,
            ..
        } => {
            assert!(
                !clockwise,
                "a G2 mirrored in one axis runs counter-clockwise"
            );
            assert_eq!((center_mm[0], center_mm[1]), (80.0, 5.0));
        }
        ref m => panic!("expected an arc, got {m:?}"),
    }
    // G91 X5. mirrored: 5 mm towards −X.
    assert_eq!(xy(at(&moves, 6)), (75.0, 15.0));
    assert_eq!(xy(at(&moves, 8)), (10.0, 5.0));
}

#[test]
fn fanuc_scaling_multiplies_about_its_centre_and_g50_ends_it() {
    let text = "G21 G90 G17 G54\nG0 X0. Y0. Z10.\nG51 X0. Y0. P2000\nG1 X10. Y5. F500\n\
                G91 X1.\nG50\nG90\nG51 X10. Y10. P0.5\nG1 X20. Y20.\n\
                G2 X30. Y10. R10.\nG50\nG1 X10. Y5.\nM30\n";
    let moves = read(Dialect::Fanuc, text).unwrap();
    assert_eq!(xy(at(&moves, 4)), (20.0, 10.0));
    assert_eq!(xy(at(&moves, 5)), (22.0, 10.0));
    assert_eq!(xy(at(&moves, 9)), (15.0, 15.0));
    // From (15, 15) to 10 + 0.5·(30 − 10) = 20, 10 + 0.5·0 = 10 with R 5: the centre is at
    // distance 5 from both, (15, 10) for the short clockwise arc.
    let arc = at(&moves, 10);
    assert_eq!(xy(arc), (20.0, 10.0));
    match arc.motion {
        Motion::Arc {
            clockwise,
            center_mm,
            ..
        } => {
            assert!(clockwise);
            assert!((center_mm[0] - 15.0).abs() < 1e-9 && (center_mm[1] - 10.0).abs() < 1e-9);
        }
        ref m => panic!("expected an arc, got {m:?}"),
    }
    assert_eq!(xy(at(&moves, 12)), (10.0, 5.0));
}

#[test]
fn a_drilling_cycle_under_scaling_scales_its_position_depth_and_r_level() {
    // Scale 2 about the origin: the hole at X20, depth Z−10, R level 4.
    let text = "G21 G90 G17 G54\nG0 X0. Y0. Z50.\nG51 X0. Y0. Z0. P2.\n\
                G98 G81 X10. Y0. Z-5. R2. F100\nG80\nM30\n";
    let moves = read(Dialect::Fanuc, text).unwrap();
    let zs: Vec<f64> = moves
        .iter()
        .filter(|m| m.line == 4)
        .map(|m| m.end[Axis::Z])
        .collect();
    assert!(zs.contains(&4.0), "{zs:?}");
    assert!(zs.contains(&-10.0), "{zs:?}");
    assert!(moves
        .iter()
        .filter(|m| m.line == 4)
        .any(|m| m.end[Axis::X] == 20.0));
}

#[test]
fn a_haas_mirror_in_x_and_y_keeps_the_arc_direction() {
    let text = "G21 G90 G17 G54\nG0 X0. Y0. Z10.\nG101 X0. Y0.\nG1 X10. Y5. F500\n\
                G2 X20. Y15. I10. J0.\nG100\nG1 X10. Y5.\nM30\n";
    let moves = read(Dialect::Haas, text).unwrap();
    assert_eq!(xy(at(&moves, 4)), (-10.0, -5.0));
    match at(&moves, 5).motion {
        Motion::Arc {
            clockwise,
            center_mm,
            ..
        } => {
            assert!(clockwise, "mirrored in both axes: the same direction");
            assert_eq!((center_mm[0], center_mm[1]), (-20.0, -5.0));
        }
        ref m => panic!("expected an arc, got {m:?}"),
    }
    assert_eq!(xy(at(&moves, 7)), (10.0, 5.0));
}

#[test]
fn what_the_map_cannot_do_is_refused_by_name() {
    let no_factor = read(Dialect::Fanuc, "G21 G90\nG51 X0. Y0.\nG1 X1. F100\n").unwrap_err();
    assert!(no_factor.contains("parameter 5411"), "{no_factor}");
    let ellipse = read(
        Dialect::Fanuc,
        "G21 G90 G17\nG51 X0. Y0. I2. J1.\nG2 X10. Y0. R5. F100\n",
    )
    .unwrap_err();
    assert!(ellipse.contains("different scale factors"), "{ellipse}");
    let modal = read(
        Dialect::Fanuc,
        "G21 G90 G17\nG0 X0. Y0.\nG2 X10. Y0. R5. F100\nG51.1 X0.\nX20. Y0. R5.\n",
    )
    .unwrap_err();
    assert!(
        modal.contains("modal G2/G3 across a change of the mirror"),
        "{modal}"
    );
}
