//! Lathe codes of the LinuxCNC dialect: the feed of spindle-synchronised moves (G33, G33.1,
//! G76) is pitch × S, worked out by hand here; end points are checked against rs274 by
//! the conformance test (tests/data/conformance/g7_*, g33_*, g76_*).

use std::path::Path;

use ngc::{read_str_with, Axis, Dialect, FeedMode, MoveKind, Options};

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
    assert_eq!(m[1].feed, Some(750.0));
    assert_eq!(m[1].feed_mode, FeedMode::PerMinute);
    assert_eq!(m[1].end[Axis::Z], -20.0);
    // The ordinary feed is untouched.
    assert_eq!(m[2].feed, Some(100.0));
    assert!((m[3].feed.unwrap() - 254.0).abs() < 1e-9);
    assert!((m[3].end[Axis::Z] + 25.4).abs() < 1e-12);
}

/// G33.1 taps to the end point and back to the start at K × S both ways; G7 halves X.
#[test]
fn rigid_tap_goes_and_returns_and_g7_halves_x() {
    let m = moves("G21 G18\nS400 M4\nG7 G0 X20 Z10\nG33.1 Z-8 K0.8\nG0 X30\nM2\n");
    assert_eq!(m[0].end[Axis::X], 10.0);
    assert_eq!((m[1].end[Axis::Z], m[1].feed), (-8.0, Some(320.0)));
    assert_eq!((m[2].end[Axis::Z], m[2].feed), (10.0, Some(320.0)));
    assert_eq!(m[3].end[Axis::X], 15.0);
}

/// G76 P2 at S300: the cutting passes feed at 600 mm/min; with an entry taper E1 of a
/// K0.75 thread, the taper moves at 2·√(1² + 0.75²)/1 × 300 = 750 mm/min.
#[test]
fn g76_passes_feed_at_pitch_and_taper_pitch() {
    let m = moves("G21 G18\nS300 M3\nG0 X10 Z2\nG76 P2 Z-10 I-1 J0.25 K0.75 E1 L1\nM2\n");
    let feeds: Vec<f64> = m
        .iter()
        .filter(|m| m.kind() == MoveKind::Feed)
        .map(|m| m.feed.unwrap())
        .collect();
    // Depths 1.25, 1.5 (< 1.75), then 1.75 once: 3 passes of taper in, taper, over.
    assert_eq!(feeds.len(), 9);
    for pass in feeds.chunks(3) {
        assert!((pass[0] - 750.0).abs() < 1e-9 && (pass[1] - 750.0).abs() < 1e-9);
        assert_eq!(pass[2], 600.0);
    }
    assert_eq!(m.last().unwrap().end[Axis::Z], -10.0);
}

#[test]
fn synchronised_motion_needs_the_spindle_and_a_pitch() {
    assert!(error("G18\nG0 X1 Z1\nG33 Z-5 K1\n").contains("spindle not turning in G33"));
    assert!(error("G18 S100 M3\nT1 M6\nG76 Z-5 P1 I-1 J0.1 K0.5\n").contains("spindle not turning"));
    assert!(error("G18 S100 M3\nG33 Z-5 K1\nZ-6\n").contains("without K"));
    assert!(error("G18 S100 M3\nG76 Z-5 I-1 J0.1 K0.5\n").contains("G76 without P"));
    assert!(error("G18 S100 M3\nG76 Z-5 P1 I-1 J0.5 K0.5\n").contains("K greater than J"));
    assert!(error("G18 S100 M3\nG76 Z-5 P1 I-1 J0.0000001 K50 R10\n").contains("passes"));
    // Fanuc and Haas lathes use other cycles under these numbers.
    let fanuc = read_str_with(Path::new("t.nc"), "G33 Z-5 K1\n", &Options::default())
        .find_map(Result::err)
        .unwrap()
        .to_string();
    assert!(fanuc.contains("G33"), "{fanuc}");
}
