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

/// G71 on a shoulder (approach to X4 Z1, the diameter X4 to Z-10, the face out to X10),
/// from X10 Z2 with layers I2 and escape R0.5, no allowance. Worked out by hand: layers at
/// X10, 8, 6 start on the approach line `Z = 1 + (X - 4)/6`, feed to the face at Z-10,
/// escape by R in X and Z at 45°, rapid back to R before the layer start and to it; then the
/// profile itself (X4 from Z1 to Z-10, the face to X10).
#[test]
fn g71_roughs_a_shoulder_in_layers_then_follows_the_profile() {
    let m = moves(
        "G21 G18 F100\nO1 SUB\nG0 X4 Z1\nG1 Z-10\nG1 X10\nO1 ENDSUB\nG0 X10 Z2\nG71 Q1 X10 Z2 I2 R0.5\nM2\n",
    );
    let got: Vec<(MoveKind, f64, f64)> = m
        .iter()
        .map(|m| (m.kind(), m.end[Axis::X], m.end[Axis::Z]))
        // Moves of length zero (rapids to where the tool is) carry nothing.
        .filter(|&(_, x, z)| x.is_finite() && z.is_finite())
        .collect();
    let (r, f) = (MoveKind::Rapid, MoveKind::Feed);
    let mut want = vec![(r, 10.0, 2.0)];
    for x in [10.0, 8.0, 6.0] {
        let z0 = 1.0 + (x - 4.0) / 6.0;
        want.extend([
            (r, x, z0),
            (f, x, -10.0),
            (r, x + 0.5, -9.5),
            (r, x + 0.5, z0 - 0.5),
            (r, x, z0),
        ]);
    }
    want.extend([(r, 4.0, 1.0), (f, 4.0, -10.0), (f, 10.0, -10.0)]);
    // Drop repeated points (the cycle's first rapids go to where the tool already is).
    let dedup = |v: &[(MoveKind, f64, f64)]| {
        let mut out: Vec<(MoveKind, f64, f64)> = Vec::new();
        for &p in v {
            if out
                .last()
                .is_none_or(|q| (q.1 - p.1).abs() + (q.2 - p.2).abs() > 1e-9)
            {
                out.push(p);
            }
        }
        out
    };
    let (got, want) = (dedup(&got), dedup(&want));
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(&want) {
        assert_eq!(g.0, w.0, "{got:?}");
        assert!(
            (g.1 - w.1).abs() < 1e-9 && (g.2 - w.2).abs() < 1e-9,
            "{g:?} vs {w:?}"
        );
    }
}

/// G70 with P2 from D1 to E0 cuts at distances (n-1)(D-E)/P + E for n = 2, 1: 0.5 mm off
/// the profile, then on it. Profile: approach to X4 Z1, X4 to Z-10, the face out to X10; the
/// stock is outside and to +Z, so the first pass runs at X4.5 down to Z-9.5 and out along
/// the face at Z-9.5; the second on the profile itself. Each pass starts with a rapid to
/// the cycle's X Z and one to the (offset) approach point.
#[test]
fn g70_passes_step_from_d_to_e() {
    let m = moves(
        "G21 G18 F100\nO1 SUB\nG0 X4 Z1\nG1 Z-10\nG1 X10\nO1 ENDSUB\nG0 X12 Z2\nG70 Q1 X12 Z2 D1 E0 P2\nM2\n",
    );
    let got: Vec<(MoveKind, f64, f64)> = m
        .iter()
        .skip(1)
        .map(|m| (m.kind(), m.end[Axis::X], m.end[Axis::Z]))
        .collect();
    let (r, f) = (MoveKind::Rapid, MoveKind::Feed);
    let want = [
        (r, 12.0, 2.0),
        (r, 12.0, 2.0),
        (r, 4.5, 1.0),
        (f, 4.5, -9.5),
        (f, 10.0, -9.5),
        (r, 12.0, 2.0),
        (r, 4.0, 1.0),
        (f, 4.0, -10.0),
        (f, 10.0, -10.0),
    ];
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(&want) {
        assert_eq!(g.0, w.0, "{got:?}");
        assert!(
            (g.1 - w.1).abs() < 1e-9 && (g.2 - w.2).abs() < 1e-9,
            "{g:?} vs {w:?}"
        );
    }
    // Roughing needs a Q and an I above zero.
    assert!(error("G18 F100\nG71 X1 Z1\n").contains("without Q"));
    assert!(error("G18 F100\nG71 Q1 X1 Z1 I0\n").contains("I (the depth of cut)"));
    assert!(error("G17 F100\nG71 Q1 X1 Z1\n").contains("G18"));
}
