//! Lathe codes of the LinuxCNC dialect: the feed of spindle-synchronised moves (G33, G33.1)
//! is pitch × S, worked out by hand here; end points are checked against rs274 by the
//! conformance test (tests/data/conformance/g7_*, g33_*). The lathe cycles G70-G72 and G76
//! are left out: a program using one is refused with the code named.

use std::path::Path;

use ngc::{read_str_with, Axis, Dialect, Feed, MoveKind, Options};

fn opts() -> Options {
    Options {
        dialect: Dialect::Linuxcnc,
        ..Options::default()
    }
}

fn moves(text: &str) -> Vec<ngc::Move> {
    read_str_with(Path::new("t.ngc"), text, &opts())
        .collect::<Result<_, _>>()
        .unwrap_or_else(|e| panic!("expected the program to read, got: {e}"))
}

fn error(text: &str) -> String {
    match read_str_with(Path::new("t.ngc"), text, &opts()).find_map(Result::err) {
        Some(e) => e.to_string(),
        None => panic!("expected an error"),
    }
}

/// G33 K1.5 at S500: 1.5 mm/rev × 500 rev/min = 750 mm/min, whatever F says; under G20
/// K0.05 in at S200 is 0.05 × 25.4 × 200 = 254 mm/min.
#[test]
fn g33_feeds_at_pitch_times_spindle_speed() {
    let m = moves(
        "G21 G18 F100\nS500 M3\nG0 X10 Z5\nG33 Z-20 K1.5\nG1 X12\nG20 S200\nG33 Z-1 K0.05\nM2\n",
    );
    assert_eq!(m[1].kind(), MoveKind::Feed);
    assert_eq!(m[1].feed, Feed::PerMinute(750.0));
    assert_eq!(m[1].end[Axis::Z], -20.0);
    // The ordinary feed is untouched.
    assert_eq!(m[2].feed, Feed::PerMinute(100.0));
    assert!(matches!(m[3].feed, Feed::PerMinute(f) if (f - 254.0).abs() < 1e-9));
    assert!((m[3].end[Axis::Z] + 25.4).abs() < 1e-12);
}

/// G33.1 taps to the end point and back to the start at K × S both ways; G7 halves X.
#[test]
fn rigid_tap_goes_and_returns_and_g7_halves_x() {
    let m = moves("G21 G18\nS400 M4\nG7 G0 X20 Z10\nG33.1 Z-8 K0.8\nG0 X30\nM2\n");
    assert_eq!(m[0].end[Axis::X], 10.0);
    assert_eq!(
        (m[1].end[Axis::Z], m[1].feed),
        (-8.0, Feed::PerMinute(320.0))
    );
    assert_eq!(
        (m[2].end[Axis::Z], m[2].feed),
        (10.0, Feed::PerMinute(320.0))
    );
    assert_eq!(m[3].end[Axis::X], 15.0);
}

#[test]
fn synchronised_motion_needs_the_spindle_and_a_pitch() {
    assert!(error("G18\nG0 X1 Z1\nG33 Z-5 K1\n").contains("spindle not turning in G33"));
    assert!(error("G18 S100 M3\nT1 M6\nG33.1 Z-5 K1\n").contains("spindle not turning in G33.1"));
    assert!(error("G18 S100 M3\nG33 Z-5 K1\nZ-6\n").contains("without K"));
    assert!(error("G18 S0 M3\nG33 Z-5 K1\n").contains("speed zero"));
    assert!(error("G18 S100 M3\nG33 Z-5 K-1\n").contains("pitch K greater than zero"));
    // Fanuc and Haas lathes use other cycles under these numbers.
    let fanuc = read_str_with(Path::new("t.nc"), "G33 Z-5 K1\n", &Options::default())
        .find_map(Result::err)
        .unwrap()
        .to_string();
    assert!(fanuc.contains("G33"), "{fanuc}");
}

/// Each lathe cycle left out is refused at its word, named with what it does, in every
/// dialect (G76: in the linuxcnc dialect), after the moves before it; the Fanuc family's
/// G70-G72 with P and Q are run (tests/interp/lathe_cycles.rs).
#[test]
fn each_dropped_lathe_cycle_is_refused_with_its_name() {
    let cases = [
        ("G70 Q1 X10 Z2 D1 P2", "G70 (lathe finishing cycle)"),
        ("G71 Q1 X10 Z2 I2 R0.5", "G71 (lathe roughing cycle)"),
        ("G71.1 Q1 X10 Z2 I2 R0.5", "G71.1 (lathe roughing cycle)"),
        ("G71.2 Q1 X10 Z2 I2 R0.5", "G71.2 (lathe roughing cycle)"),
        ("G72 Q1 X10 Z2 I2 R0.5", "G72 (lathe facing cycle)"),
        ("G72.1 Q1 X10 Z2 I2 R0.5", "G72.1 (lathe facing cycle)"),
        ("G72.2 Q1 X10 Z2 I2 R0.5", "G72.2 (lathe facing cycle)"),
        ("G76 P2 Z-10 I-1 J0.25 K0.75", "G76 (lathe threading cycle)"),
    ];
    for (block, name) in cases {
        let program = format!("G21 G18 F100 S300 M3\nG0 X10 Z2\n{block}\nM2\n");
        let e = error(&program);
        assert!(
            e.contains(&format!("{name} is not supported by mtsim")),
            "{e}"
        );
        assert!(e.contains("t.ngc:3:1"), "{e}");
        let before: Vec<_> = read_str_with(Path::new("t.ngc"), &program, &opts())
            .take_while(Result::is_ok)
            .collect();
        assert_eq!(before.len(), 1, "{block}: the rapid before it is kept");
        // On a Fanuc or Haas mill G76 is the fine boring cycle (tests/fanuc_haas.rs).
        let mills: &[Dialect] = if block.starts_with("G76") {
            &[]
        } else {
            &[Dialect::Fanuc, Dialect::Haas]
        };
        for &dialect in mills {
            let o = Options {
                dialect,
                ..Options::default()
            };
            let e = read_str_with(Path::new("t.nc"), &program, &o)
                .find_map(Result::err)
                .unwrap()
                .to_string();
            // Haas names both of its meanings (lathe cycle, mill bolt pattern): G70 and G71
            // with P Q are refused as the lathe's cycle, G72 by both names.
            let code = name.split(' ').next().unwrap();
            let named = match dialect {
                // With P and Q, G70 is the Fanuc family's finishing cycle, which mtsim runs
                // (tests/interp/lathe_cycles.rs): here its shape's block N2 is missing.
                _ if code == "G70" => e.contains("no block N2 for P2"),
                Dialect::Haas if code == "G71" => {
                    e.contains(&format!("on a Haas lathe {code} P Q is the"))
                        && e.contains("bolt-hole pattern")
                }
                Dialect::Haas if code == "G72" => {
                    e.contains("`G72` (Haas lathe:") && e.contains("Haas mill: bolt")
                }
                _ => e.contains(name),
            };
            assert!(named, "{dialect:?}: {e}");
        }
    }
}
