//! Trap programs of the Fanuc family (`tests/data/traps/`, set-up in traps.rs): G10's L
//! numbers, which mean otherwise than LinuxCNC's, under G90 and G91; G65's argument
//! specification II; a tool change without G43; G92 before G28; M99 in the main program;
//! `,R` / `,C` next to an arc; and a lathe's feed per revolution (G99), constant surface
//! speed (G96 with the G50 S limit) and single cycles. Each is right, checked against
//! figures worked by hand below, or refused naming what it is.

use std::f64::consts::PI;

use ngc::{Axis, Feed};

use super::traps::{near, options, read, refused, right, trap, xyz};

fn feed(m: &ngc::Move) -> f64 {
    match m.feed {
        Feed::PerMinute(f) => f,
        other => panic!("line {}: {other:?}", m.line),
    }
}

#[test]
fn g10_l2_under_g91_adds_to_the_work_offset() {
    // G54 = (100, 0, 0), then G91 adds (10, -5): G54 X0 Y0 is machine (110, -5), Z stays 0.
    for name in ["fanuc-g10-l2-g91.nc", "haas-g10-l2-g91.nc"] {
        let m = right(name);
        let end = xyz(&m.last().unwrap().end);
        assert!(near(end, [110.0, -5.0, 0.0]), "{name}: {end:?}");
    }
}

#[test]
fn g10_l20_sets_the_extended_work_offset() {
    // G10 L20 P1 X50 Y20: G54.1 P1 (Fanuc) and G154 P1 (Haas) X0 Y0 are machine (50, 20).
    for name in ["fanuc-g10-l20.nc", "haas-g10-l20-g154.nc"] {
        let m = right(name);
        let end = xyz(&m.last().unwrap().end);
        assert!(near(end, [50.0, 20.0, 0.0]), "{name}: {end:?}");
    }
}

#[test]
fn g10_l10_and_l11_set_the_tool_length_geometry_and_wear() {
    // Geometry 120 (the table's 100 replaced), wear -0.5, then G91 adds -0.2: 119.3 mm;
    // G43 H2 Z10 is machine Z 10 + 119.3 = 129.3.
    let m = right("fanuc-g10-l10-length.nc");
    let last = m.last().unwrap();
    assert!((last.tool_length_mm - 119.3).abs() < 1e-9, "{last:?}");
    assert!((last.end[Axis::Z] - 129.3).abs() < 1e-9, "{last:?}");
    // L12 (cutter radius offset): a radius or a diameter by a control setting, refused.
    let (line, message) = refused("fanuc-g10-l12.nc", true);
    assert_eq!(line, 4);
    assert!(
        message.contains("L12") && message.contains("cutter radius offset"),
        "{message}"
    );
}

#[test]
fn g65_repeated_i_j_k_are_argument_specification_ii() {
    // I1 J2 K3 I4 J5: #4 #5 #6 #7 #8 = 1 2 3 4 5, so `G0 X#7 Y#8 Z#6` goes to (4, 5, 3).
    let m = right("fanuc-g65-ijk.nc");
    assert!(near(xyz(&m.last().unwrap().end), [4.0, 5.0, 3.0]));
}

#[test]
fn a_tool_change_keeps_the_length_offset_and_g28_after_g92_goes_to_the_reference() {
    // G43 H2 (100 mm) Z10: 110. T1 M6 without G43: H2 stays (Fanuc: the offset changes
    // with the next H), so Z20 is 120.
    let m = right("fanuc-g43-keep.nc");
    let last = m.last().unwrap();
    assert!((last.end[Axis::Z] - 120.0).abs() < 1e-9 && last.tool_length_mm == 100.0);
    // G92 zeros at (10, 20, 5); G91 G28 Z0 goes to Z450; X0 Y0 is G92's origin (10, 20).
    let m = right("fanuc-g92-g28.nc");
    assert!(near(xyz(&m.last().unwrap().end), [10.0, 20.0, 450.0]));
}

#[test]
fn m99_in_the_main_program_is_one_pass_with_a_warning() {
    let mut it = ngc::read_file_with(
        &trap("fanuc-m99-main.nc"),
        &options("fanuc-m99-main.nc", true),
    )
    .unwrap();
    let m: Vec<ngc::Move> = it.by_ref().map(|m| m.unwrap()).collect();
    assert_eq!(m.last().unwrap().end[Axis::X], 2.0);
    assert!(
        it.notices()
            .iter()
            .any(|n| n.warning && n.line == 6 && n.message.contains("one pass")),
        "{:?}",
        it.notices()
    );
}

#[test]
fn corner_rounding_next_to_an_arc_is_right_and_a_chamfer_there_refused() {
    // (0,0) → (10,0) ,R2 then G03 R10 about (0,0): the line y = 2 meets the circle of
    // radius 8 at (√60, 2); the tangent points are (√60, 0) and 10/8 (√60, 2).
    let m = right("fanuc-corner-r-arc.nc");
    let s60 = 60f64.sqrt();
    let n = m.len();
    assert!(near(xyz(&m[n - 3].end), [s60, 0.0, 0.0]));
    assert!(near(xyz(&m[n - 2].end), [1.25 * s60, 2.5, 0.0]));
    assert!(near(xyz(&m[n - 1].end), [0.0, 10.0, 0.0]));
    let (line, message) = refused("fanuc-corner-c-arc.nc", true);
    assert_eq!(line, 6);
    assert!(message.contains("next to an arc"), "{message}");
}

#[test]
fn a_lathe_feeds_per_revolution_under_g99_and_at_the_surface_speed_under_g96() {
    // G99 F0.2 at S1000: 200 mm/min; G98 F100: 100 mm/min.
    let m = right("lathe-g99.nc");
    let n = m.len();
    assert!((feed(&m[n - 2]) - 200.0).abs() < 1e-9 && (feed(&m[n - 1]) - 100.0).abs() < 1e-9);
    // G96 S200 at D = 40: 200 000 / (π 40) rev/min × 0.2 = 318.31 mm/min. Facing X40 → X0
    // under G50 S3000: t = 5 [π (40² − D_c²) / 400 000 + D_c / 3000], D_c = 200 000 /
    // (π 3000), and F = 40 / t = 496.80 mm/min.
    let m = right("lathe-g96-css.nc");
    let n = m.len();
    assert!((feed(&m[n - 2]) - 0.2 * 200_000.0 / (PI * 40.0)).abs() < 1e-9);
    let dc = 200_000.0 / (PI * 3000.0);
    let t = 5.0 * (PI * (1600.0 - dc * dc) / 400_000.0 + dc / 3000.0);
    assert!(
        (feed(&m[n - 1]) - 40.0 / t).abs() < 1e-6,
        "{:?}",
        m[n - 1].feed
    );
    assert!((40.0 / t - 496.80).abs() < 0.01);
}

#[test]
fn a_lathe_t_word_indexes_the_turret_to_its_leading_digits() {
    // T0202 with no M6: the moves after it are tool 2's (a mill would take tool 202 at M6).
    let m = read("lathe-t-word.nc", true).unwrap_err();
    assert_eq!(m.0, 7, "{m:?}");
    let it =
        ngc::read_file_with(&trap("lathe-t-word.nc"), &options("lathe-t-word.nc", true)).unwrap();
    let tools: Vec<u32> = it.map_while(Result::ok).map(|m| m.tool).collect();
    assert_eq!(tools, [2, 2], "{tools:?}");
}

#[test]
fn lathe_codes_that_would_read_silently_wrong_are_refused() {
    for (name, line, says) in [
        ("lathe-g90-cycle.nc", 6, "turning cycle"),
        ("lathe-g50-s-only.nc", 7, "spindle speed zero"),
        ("lathe-g96-no-limit.nc", 6, "X 0"),
        // T3 on a lathe: tool 0 offset 3 or tool 3? Two digits each are expected.
        ("lathe-t-word.nc", 7, "four digits"),
    ] {
        let (at, message) = refused(name, true);
        assert_eq!(at, line, "{name}: {message}");
        assert!(message.contains(says), "{name}: {message}");
    }
}
