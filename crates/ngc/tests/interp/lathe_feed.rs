//! Feed per revolution on a Fanuc or Haas lathe (G99, G98 per minute: G-code system A) and
//! under constant surface speed (G96 S, the limit G50 S), and the lathe's other system A
//! codes (G50 X Z sets the coordinates; G90, G92, G94, G95 refused as the single cycles
//! they are). Every figure below is worked out by hand from the manuals' rules:
//!
//! - feed per revolution: F mm/min = f mm/rev × n rev/min;
//! - surface speed: n = 1000 v / (π D) rev/min for v m/min at diameter D mm (Fanuc lathe
//!   operator's manual, "Constant surface speed control"), clamped at G50 S;
//! - a move whose D changes takes t = ∫ ds / (f n(D)), and mtsim gives it F = L / t.
//!
//! The lathe: axes X and Z (no Y), X words diameters as written.

use std::f64::consts::PI;
use std::path::Path;

use ngc::{read_str_with, Axis, Dialect, Feed, Move, Options};

fn lathe(dialect: Dialect) -> Options {
    Options {
        dialect,
        axes: vec![Axis::X, Axis::Z],
        ..Options::default()
    }
}

fn moves_with(text: &str, o: &Options) -> Vec<Move> {
    read_str_with(Path::new("t.nc"), text, o)
        .collect::<Result<_, _>>()
        .unwrap_or_else(|e| panic!("expected the program to read, got: {e}"))
}

fn moves(text: &str) -> Vec<Move> {
    moves_with(text, &lathe(Dialect::Fanuc))
}

fn error_with(text: &str, o: &Options) -> String {
    match read_str_with(Path::new("t.nc"), text, o).find_map(Result::err) {
        Some(e) => e.to_string(),
        None => panic!("expected an error"),
    }
}

fn error(text: &str) -> String {
    error_with(text, &lathe(Dialect::Fanuc))
}

fn per_minute(m: &Move) -> f64 {
    match m.feed {
        Feed::PerMinute(f) => f,
        other => panic!("line {}: expected a feed per minute, got {other:?}", m.line),
    }
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1.0)
}

#[test]
fn g99_is_feed_per_revolution_and_g98_per_minute_on_a_fanuc_and_a_haas_lathe() {
    // G99 F0.2 at S1000: 0.2 × 1000 = 200 mm/min; the 52 mm cut Z2 → Z-50 takes
    // 52 / 200 = 0.26 min. G98 F100: 100 mm/min.
    for dialect in [Dialect::Fanuc, Dialect::Haas] {
        let m = moves_with(
            "G21 G18\nG99\nG97 S1000 M3\nG0 X40 Z2\nG1 Z-50 F0.2\nG98 G1 Z-60 F100\nM30\n",
            &lathe(dialect),
        );
        let cut = &m[1];
        assert!(
            close(per_minute(cut), 200.0, 1e-12),
            "{dialect:?}: {:?}",
            cut.feed
        );
        let minutes = (cut.start[Axis::Z] - cut.end[Axis::Z]) / per_minute(cut);
        assert!(close(minutes, 0.26, 1e-12), "{minutes}");
        assert!(close(per_minute(&m[2]), 100.0, 1e-12), "{:?}", m[2].feed);
    }
}

#[test]
fn g50_s_is_the_limit_not_the_spindle_speed() {
    // G50 S2000 alone leaves the spindle speed unknown: a G99 cut is refused, not fed at
    // 0.1 × 2000. With G97 S500 it is 0.1 × 500 = 50 mm/min.
    let e = error("G21 G18\nG50 S2000\nG99 G0 X40 Z2\nG1 Z-10 F0.1\nM30\n");
    assert!(e.contains("spindle speed zero") && e.contains("G99"), "{e}");
    let m = moves("G21 G18\nG50 S2000\nG97 S500 M3\nG99 G0 X40 Z2\nG1 Z-10 F0.1\nM30\n");
    assert!(close(per_minute(&m[1]), 50.0, 1e-12), "{:?}", m[1].feed);
}

/// The start of every constant-surface-speed program below: v = 200 m/min, limit 3000
/// rev/min, f = 0.2 mm/rev, the tool at X40 Z2.
const CSS: &str = "G21 G18\nG50 S3000\nG96 S200 M3\nG99 G0 X40 Z2\n";

#[test]
fn g96_turning_at_one_diameter_feeds_at_f_times_the_surface_speed_rpm() {
    // D = 40: n = 200 000 / (π 40) = 1591.549 rev/min, F = 0.2 n = 318.310 mm/min; the
    // 52 mm cut takes 52 / 318.310 = 0.16336 min.
    let m = moves(&format!("{CSS}G1 Z-50 F0.2\nM30\n"));
    let n = 200_000.0 / (PI * 40.0);
    assert!(close(n, 1591.549, 1e-6));
    assert!(close(per_minute(&m[1]), 0.2 * n, 1e-12), "{:?}", m[1].feed);
    assert!(close(52.0 / per_minute(&m[1]), 0.163363, 1e-5));
    // Above the limit the clamp holds: at D = 10, 200 000 / (π 10) = 6366 > 3000, so
    // F = 0.2 × 3000 = 600 mm/min.
    let m = moves(&format!("{CSS}G0 X10\nG1 Z-50 F0.2\nM30\n"));
    assert!(close(per_minute(&m[2]), 600.0, 1e-12), "{:?}", m[2].feed);
}

#[test]
fn g96_facing_to_the_centre_takes_the_time_of_the_clamped_spindle() {
    // X40 → X0 at Z2: the machine's X travels 40 mm while D = X falls from 40 to 0. Above
    // D_c = 200 000 / (π 3000) = 21.2207 the spindle turns at 200 000 / (π D), below it at
    // 3000: t = (1/f) [∫ π D / 200 000 dD from D_c to 40 + D_c / 3000]
    //         = 5 [π (40² − D_c²) / 400 000 + D_c / 3000] = 0.080516 min,
    // so F = 40 / t = 496.80 mm/min.
    let m = moves(&format!("{CSS}G1 X0 F0.2\nM30\n"));
    let dc = 200_000.0 / (PI * 3000.0);
    assert!(close(dc, 21.2207, 1e-5));
    let t = (PI * (40.0f64.powi(2) - dc * dc) / 400_000.0 + dc / 3000.0) / 0.2;
    assert!(close(t, 0.080516, 1e-5), "{t}");
    assert!(close(per_minute(&m[1]), 40.0 / t, 1e-9), "{:?}", m[1].feed);
    assert!(close(per_minute(&m[1]), 496.80, 1e-4));
}

#[test]
fn g96_on_an_arc_takes_the_time_of_the_surface_speed_along_it() {
    // G3 from (Z0, X20) to (Z-10, X30), R10: centre (Z-10, X20), X = 20 + 10 sin θ for θ
    // 0 → π/2, ds = 10 dθ, L = 5π. The limit 4000 stays above n at D ≥ 20 (3183).
    // ∫ X ds = 10 (20 π/2 + 10) = 100 π + 100, t = π (100 π + 100) / (0.2 · 200 000),
    // F = L / t = 5π · 40 000 / (π (100π + 100)) = 482.95 mm/min.
    let m = moves("G21 G18\nG50 S4000\nG96 S200 M3\nG99 G0 X20 Z0\nG3 X30 Z-10 R10 F0.2\nM30\n");
    let expected = 5.0 * PI * 40_000.0 / (PI * (100.0 * PI + 100.0));
    assert!(close(expected, 482.95, 1e-4), "{expected}");
    assert!(close(per_minute(&m[1]), expected, 1e-6), "{:?}", m[1].feed);
}

#[test]
fn g96_in_inches_reads_s_in_feet_per_minute_and_f_in_inches_per_revolution() {
    // The Haas lathe sample's roughing set-up: G50 S1600, G96 S1000 (ft/min), G99 F0.02
    // (in/rev) at X2. (D = 50.8 mm): 1000 × 304.8 / (π 50.8) = 1909.9 > 1600, so n = 1600
    // and F = 0.02 × 25.4 × 1600 = 812.8 mm/min.
    let m = moves_with(
        "G20 G18 G99\nG50 S1600\nG96 S1000 M3\nG0 X2. Z0.1\nG1 Z-5.2 F0.02\nM30\n",
        &lathe(Dialect::Haas),
    );
    assert!(close(per_minute(&m[1]), 812.8, 1e-12), "{:?}", m[1].feed);
}

#[test]
fn g97_without_s_keeps_the_speed_the_spindle_turns_at() {
    // G97 at D = 40 under v = 200: n = 1591.549 stays; F0.2 → 318.310 mm/min at D = 20 too.
    let m = moves(&format!("{CSS}G97\nG0 X20\nG1 Z-50 F0.2\nM30\n"));
    let n = 200_000.0 / (PI * 40.0);
    assert!(close(per_minute(&m[2]), 0.2 * n, 1e-12), "{:?}", m[2].feed);
}

#[test]
fn g96_to_the_centre_without_a_limit_is_refused() {
    let e = error("G21 G18\nG96 S200 M3\nG99 G0 X40 Z2\nG1 X0 F0.2\nM30\n");
    assert!(
        e.contains("X 0") && e.contains("G50 S") && e.contains("t.nc:4:"),
        "{e}"
    );
}

#[test]
fn linuxcnc_g96_reads_x_as_a_radius_with_d_the_limit() {
    // X20 is a radius: D = 40, n = 100 000 / (π 40) = 795.775, G95 F0.1 → 79.5775 mm/min.
    let o = Options {
        dialect: Dialect::Linuxcnc,
        ..Options::default()
    };
    let m = moves_with(
        "G21 G18 G95\nG96 D2000 S100 M3\nG0 X20 Z2\nG1 Z-30 F0.1\nG0 X1\nG1 Z-40\nM2\n",
        &o,
    );
    let n = 100_000.0 / (PI * 40.0);
    assert!(close(per_minute(&m[1]), 0.1 * n, 1e-12), "{:?}", m[1].feed);
    // At X1 (D = 2) 100 000 / (2π) = 15 915 > 2000: F = 0.1 × 2000 = 200 mm/min.
    assert!(close(per_minute(&m[3]), 200.0, 1e-12), "{:?}", m[3].feed);
}

#[test]
fn g96_feed_per_revolution_on_a_fanuc_mill_is_refused() {
    let o = Options {
        dialect: Dialect::Fanuc,
        ..Options::default()
    };
    let e = error_with("G21 G95\nG92 S3000\nG96 S200 M3\nG1 X10 F0.1\nM30\n", &o);
    assert!(e.contains("not a lathe") && e.contains("3770"), "{e}");
}

#[test]
fn g50_with_x_and_z_sets_the_lathe_coordinates() {
    // At (X100, Z50), G50 X200 Z100 makes that point (200, 100): X210 is machine X110.
    let m = moves("G21 G18\nG0 X100 Z50\nG50 X200 Z100\nG0 X210\nM30\n");
    let last = m.last().unwrap();
    assert_eq!((last.end[Axis::X], last.end[Axis::Z]), (110.0, 50.0));
}

#[test]
fn the_lathe_single_cycles_and_g95_are_refused_as_what_they_are() {
    for (program, code, meaning) in [
        ("G0 X40 Z2\nG90 X30 Z-20 F0.2\n", "G90", "turning cycle"),
        ("G0 X40 Z2\nG92 X30 Z-20 F1.5\n", "G92", "threading cycle"),
        ("G0 X40 Z2\nG94 X10 Z-2 F0.2\n", "G94", "end face"),
        ("G95 G1 X30 F0.2\n", "G95", "G99"),
        ("G0 X40 Z2\nG90\nX30 Z-20 F0.2\n", "G90", "turning cycle"),
    ] {
        let e = error(&format!("G21 G18\nS500 M3\n{program}M30\n"));
        assert!(
            e.contains(&format!("`{code}`")) && e.contains(meaning) && e.contains("system A"),
            "{code}: {e}"
        );
    }
    // G90 alone (a mill's safety line) only selects the cycle; the G00 after it replaces it.
    let m = moves("G21 G18 G90 G40\nG0 X40 Z2\nM30\n");
    assert_eq!((m[0].end[Axis::X], m[0].end[Axis::Z]), (40.0, 2.0));
}

#[test]
fn a_lathe_program_that_feeds_before_g98_or_g99_is_warned_once() {
    let warned = |text: &str| {
        let mut it = read_str_with(Path::new("t.nc"), text, &lathe(Dialect::Fanuc));
        assert!(it.by_ref().all(|m| m.is_ok()));
        it.notices()
            .iter()
            .filter(|n| n.warning && n.message.contains("before it states G98 or G99"))
            .map(|n| n.line)
            .collect::<Vec<_>>()
    };
    let program = "G21 G18\nG97 S500 M3\nG0 X40 Z2\nG1 Z-10 F100\nZ-20\nM30\n";
    assert_eq!(warned(program), [4]);
    assert!(warned(&program.replace("G18", "G18 G98")).is_empty());
}
