//! The control's parameters (`[control]` in a machine file, [`ControlParameters`]): the G73
//! retract (Fanuc parameter 5114, Haas Setting 22), the G83 re-approach clearance (Fanuc
//! parameter 5115) and retract above R (Haas Setting 52), and what G28 without axis words
//! moves. The peck levels are written out by hand from the cycle's definition: feed to
//! `R - k·Q`, back off (G73) or rise to R (G83), come down to the clearance above the depth.

use std::path::Path;

use ngc::{read_str_with, Axis, ControlParameters, Dialect, Motion, Options};

fn options(dialect: Dialect, control: ControlParameters) -> Options {
    let mut o = Options {
        dialect,
        control,
        ..Options::default()
    };
    o.set_reference(
        false,
        ngc::AxisVec::xyzabc([10.0, 20.0, 300.0, 0.0, 0.0, 0.0]),
    );
    o
}

/// The moves' (motion, end Z) to 1e-9 mm, and the notices' texts.
fn run(text: &str, o: &Options) -> (Vec<(Motion, f64)>, Vec<String>) {
    let mut it = read_str_with(Path::new("t.nc"), text, o);
    let mut z = Vec::new();
    for m in it.by_ref() {
        let m = m.unwrap_or_else(|e| panic!("expected the program to read, got: {e}"));
        z.push((m.motion, (m.end[Axis::Z] * 1e9).round() / 1e9 + 0.0));
    }
    let notes = it.notices().iter().map(|n| n.message.clone()).collect();
    (z, notes)
}

/// A 3-peck hole from R2 to Z-7 with Q3: its Z levels after the approach to R.
const HOLE: &str = "G21 G90 G17\nG0 X0 Y0 Z50.\nG98 G{c} X5. Y0 Z-7. R2. Q3. F100\nG80\n";

fn hole(code: u32, o: &Options) -> (Vec<(Motion, f64)>, Vec<String>) {
    let (z, notes) = run(&HOLE.replace("{c}", &code.to_string()), o);
    // Skip the rapid to Z50, the move over the hole and the rapid down to R.
    let from_r = z
        .iter()
        .position(|&(m, z)| m == Motion::Rapid && z == 2.0)
        .unwrap();
    (z[from_r + 1..].to_vec(), notes)
}

use Motion::{Linear as F, Rapid as G0};

#[test]
fn fanuc_g83_comes_back_down_to_parameter_5115_above_each_peck() {
    let control = ControlParameters {
        g83_clearance_mm: Some(1.0),
        ..ControlParameters::default()
    };
    let (z, notes) = hole(83, &options(Dialect::Fanuc, control));
    // Pecks at 2-3 = -1 and -4, then the bottom -7; R = 2; clearance 1 mm.
    let expected = [
        (F, -1.0),
        (G0, 2.0),
        (G0, 0.0),
        (F, -4.0),
        (G0, 2.0),
        (G0, -3.0),
        (F, -7.0),
        (G0, 50.0),
    ];
    assert_eq!(z, expected);
    assert!(
        notes.iter().all(|n| !n.contains("parameter 5115")),
        "{notes:?}"
    );
}

#[test]
fn fanuc_g83_without_the_parameter_uses_0_254_mm_and_says_so() {
    let (z, notes) = hole(83, &options(Dialect::Fanuc, ControlParameters::default()));
    assert_eq!(z[2], (G0, -1.0 + 0.254));
    let note = notes
        .iter()
        .find(|n| n.contains("parameter 5115"))
        .expect("a notice");
    assert!(
        note.contains("0.254 mm") && note.contains("g83_clearance_mm"),
        "{note}"
    );
}

#[test]
fn g73_backs_off_by_its_retract_and_haas_names_setting_22() {
    let control = ControlParameters {
        g73_retract_mm: Some(0.5),
        ..ControlParameters::default()
    };
    let (z, _) = hole(73, &options(Dialect::Haas, control));
    let expected = [
        (F, -1.0),
        (G0, -0.5),
        (F, -4.0),
        (G0, -3.5),
        (F, -7.0),
        (G0, 50.0),
    ];
    assert_eq!(z, expected);
    let (_, notes) = hole(73, &options(Dialect::Haas, ControlParameters::default()));
    assert!(notes.iter().any(|n| n.contains("Setting 22")), "{notes:?}");
}

#[test]
fn haas_setting_52_lifts_each_g83_retract_above_r() {
    let control = ControlParameters {
        g83_clearance_mm: Some(0.5),
        g83_above_r_mm: 3.0,
        ..ControlParameters::default()
    };
    let (z, _) = hole(83, &options(Dialect::Haas, control));
    let expected = [
        (F, -1.0),
        (G0, 5.0),
        (G0, -0.5),
        (F, -4.0),
        (G0, 5.0),
        (G0, -3.5),
        (F, -7.0),
        (G0, 50.0),
    ];
    assert_eq!(z, expected);
}

#[test]
fn linuxcnc_pecks_at_its_fixed_clearance_without_a_notice() {
    let (z, notes) = hole(
        83,
        &options(Dialect::Linuxcnc, ControlParameters::default()),
    );
    assert_eq!(z[2], (G0, -1.0 + 0.254));
    assert!(notes.iter().all(|n| !n.contains("G83")), "{notes:?}");
}

#[test]
fn g28_without_axis_words_moves_nothing_on_a_fanuc_and_everything_on_a_haas() {
    let program = "G21 G90\nG0 X1. Y2. Z3.\nG28\nG0 X4.\n";
    let ends = |o: &Options| -> Vec<[f64; 3]> {
        read_str_with(Path::new("t.nc"), program, o)
            .map(|m| m.unwrap())
            .map(|m| [m.end[Axis::X], m.end[Axis::Y], m.end[Axis::Z]])
            .collect()
    };
    // Fanuc: the G28 moves no axis; a notice says so and names the key.
    let fanuc = options(Dialect::Fanuc, ControlParameters::default());
    assert_eq!(ends(&fanuc), [[1.0, 2.0, 3.0], [4.0, 2.0, 3.0]]);
    let (_, notes) = run(program, &fanuc);
    assert!(
        notes.iter().any(|n| n.contains("g28_without_axes")),
        "{notes:?}"
    );
    // Haas, and a Fanuc whose builder set it: every axis to the reference (10, 20, 300).
    let haas = options(Dialect::Haas, ControlParameters::default());
    assert_eq!(
        ends(&haas),
        [[1.0, 2.0, 3.0], [10.0, 20.0, 300.0], [4.0, 20.0, 300.0]]
    );
    let all = ControlParameters {
        reference_all_without_axes: Some(true),
        ..ControlParameters::default()
    };
    assert_eq!(ends(&options(Dialect::Fanuc, all)), ends(&haas));
}
