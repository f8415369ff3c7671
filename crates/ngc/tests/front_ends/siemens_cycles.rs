//! Sinumerik drilling cycles CYCLE83 (deep-hole drilling), CYCLE86 (boring with an
//! oriented spindle stop and lift-off), CYCLE87/CYCLE88 (boring with a program stop): each
//! move's end point, kind and feed against the sequence of the SINUMERIK 840D sl
//! Programming Manual Cycles, worked by hand in the comments; and the values the reader
//! refuses, each named.

use std::path::Path;

use ngc::{read_str_with, Dialect, Error, Motion, Move, Options};

fn options() -> Options {
    Options {
        dialect: Dialect::Siemens,
        ..Options::default()
    }
}

fn moves(text: &str) -> Vec<Move> {
    read_str_with(Path::new("c.mpf"), text, &options())
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("expected the program to read, got: {e}\n{text}"))
}

fn refusal(text: &str) -> (usize, String) {
    let err = read_str_with(Path::new("c.mpf"), text, &options())
        .find_map(|m| m.err())
        .unwrap_or_else(|| panic!("expected a refusal of {text:?}"));
    match err {
        Error::Syntax(s) => (s.line, s.message),
        other => panic!("expected a refusal at a line, got {other:?}"),
    }
}

/// One move of `line`: `'r'` rapid, `'f'` feed, `'d'` dwell; X Y Z (dwell: seconds in X);
/// the feed (0 for rapids and dwells). Rounded to 1e-9.
fn steps(m: &[Move], line: usize) -> Vec<(char, [f64; 3], f64)> {
    let r = |v: f64| (v * 1e9).round() / 1e9 + 0.0;
    m.iter()
        .filter(|m| m.line == line)
        .map(|m| {
            let e = m.end.to_xyzabc();
            let xyz = [r(e[0]), r(e[1]), r(e[2])];
            match m.motion {
                Motion::Dwell { seconds } => ('d', [seconds, 0.0, 0.0], 0.0),
                Motion::Rapid => ('r', xyz, 0.0),
                _ => ('f', xyz, m.feed.rate().unwrap_or(f64::NAN)),
            }
        })
        .collect()
}

/// Along Z at X80 Y120 only: the kind, Z and feed of each move.
fn z_only(m: &[Move], line: usize) -> Vec<(char, f64, f64)> {
    steps(m, line)
        .into_iter()
        .map(|(k, p, f)| {
            if k != 'd' {
                assert_eq!([p[0], p[1]], [80.0, 120.0], "a move off the hole's axis");
            }
            (k, if k == 'd' { p[0] } else { p[2] }, f)
        })
        .collect()
}

/// Chip removal (VARI 1), the manual's example values: RTP 155, RFP 150, SDIS 1, DP 5,
/// FDEP 100, DAM 20, FRF 1. Strokes (depth 145 below RFP): 50 to Z100; 50 − 20 = 30
/// (> DAM) to Z70; then DAM while more than 2 × 20 is left: 20 (65 left) to Z50, 20 (45
/// left) to Z30; 25 left ≤ 40: two equal strokes of 12.5 to Z17.5 and Z5. After each
/// stroke G0 out to RFP + SDIS = 151 and G0 back to the depth reached less the
/// anticipation distance: depth/50 beyond 30 mm (50 → 1, 80 → 1.6, 100 → 2, 120 → 2.4,
/// 132.5 → 2.65), then G1 at F on; G0 to RTP 155 at the end.
#[test]
fn cycle83_chip_removal_strokes_by_the_degression_amount_with_the_anticipation_distance() {
    let m = moves(
        "G17 G90 F100\nG0 X80 Y120 Z160\nCYCLE83(155,150,1,5,,100,,20,0,0,1,1)\nG1 X90\nM30\n",
    );
    let want = [
        ('r', 151.0, 0.0),
        ('f', 100.0, 100.0),
        ('r', 151.0, 0.0),
        ('r', 101.0, 0.0),
        ('f', 70.0, 100.0),
        ('r', 151.0, 0.0),
        ('r', 71.6, 0.0),
        ('f', 50.0, 100.0),
        ('r', 151.0, 0.0),
        ('r', 52.0, 0.0),
        ('f', 30.0, 100.0),
        ('r', 151.0, 0.0),
        ('r', 32.4, 0.0),
        ('f', 17.5, 100.0),
        ('r', 151.0, 0.0),
        ('r', 20.15, 0.0),
        ('f', 5.0, 100.0),
        ('r', 155.0, 0.0),
    ];
    assert_eq!(z_only(&m, 3), want);
}

/// Chip breaking (VARI 0): RTP 10, RFP 0, SDIS 2, DP −25, FDPR 8 (first depth −8), DAM 3,
/// DTB 1 s, FRF 0.5, _VRT 0.5, _DTD 2 s, F200. Strokes (25 deep): 8; 8 − 3 = 5 (> 3) to
/// −13; 3 to −16 (9 left), 3 to −19 (6 left, not more than 6); then 6 in two strokes of 3 to
/// −22 and −25. The first stroke at 200 × 0.5 = 100, then back 0.5 and on at F200, a 1 s
/// dwell at each depth and 2 s (_DTD) at the last; G0 to RTP; F200 again after.
#[test]
fn cycle83_chip_breaking_backs_off_by_vrt_at_the_programmed_feed() {
    let m = moves(
        "G17 G90 F200\nG0 X80 Y120 Z20\nCYCLE83(10,0,2,-25,,,8,3,1,0,0.5,0,,,0.5,2)\nG1 X90\nM30\n",
    );
    let mut want = vec![('r', 2.0, 0.0), ('f', -8.0, 100.0), ('d', 1.0, 0.0)];
    for depth in [-13.0, -16.0, -19.0, -22.0, -25.0] {
        let reached = depth + if depth == -13.0 { 5.0 } else { 3.0 };
        want.extend([('f', reached + 0.5, 200.0), ('f', depth, 200.0)]);
        want.push(('d', if depth == -25.0 { 2.0 } else { 1.0 }, 0.0));
    }
    want.push(('r', 10.0, 0.0));
    assert_eq!(z_only(&m, 3), want);
    assert_eq!(steps(&m, 4), [('f', [90.0, 120.0, 10.0], 200.0)]);
}

/// DAM 0 (no degression): strokes of the first depth (10) and the rest (5); the
/// anticipation distance 0.6 mm up to a depth of 30 mm; a 0.5 s DTS dwell at RFP + SDIS
/// after each chip removal; `_DIS1` 1.5 sets the distance. DPR 25 (not 0) over DP: the
/// final depth is RFP − 25 = −25.
#[test]
fn cycle83_without_degression_and_with_a_programmed_anticipation_distance() {
    let m = moves(
        "G17 G90 F100\nG0 X80 Y120 Z20\nCYCLE83(10,0,2,-99,25,-10,,0,0,0.5,1,1)\n\
         CYCLE83(10,0,2,-25,,-10,,0,0,0,1,1,,,,,1.5)\nM30\n",
    );
    assert_eq!(
        z_only(&m, 3),
        [
            ('r', 2.0, 0.0),
            ('f', -10.0, 100.0),
            ('r', 2.0, 0.0),
            ('d', 0.5, 0.0),
            ('r', -9.4, 0.0),
            ('f', -20.0, 100.0),
            ('r', 2.0, 0.0),
            ('d', 0.5, 0.0),
            ('r', -19.4, 0.0),
            ('f', -25.0, 100.0),
            ('r', 10.0, 0.0),
        ]
    );
    let reapproach: Vec<f64> = z_only(&m, 4)
        .iter()
        .filter(|(k, z, _)| *k == 'r' && *z < 0.0)
        .map(|s| s.1)
        .collect();
    assert_eq!(reapproach, [-8.5, -18.5]);
}

/// MCALL CYCLE83 drills at each later position (the second reached at RTP 10, where the
/// first hole left the tool); a first depth past the final one drills the whole depth in
/// one stroke (the final depth is never passed).
#[test]
fn cycle83_by_mcall_drills_every_hole() {
    let m = moves(
        "G17 G90 F100\nG0 X0 Y0 Z20\nMCALL CYCLE83(10,0,2,-5,,-30,,1,0,0,1,1)\nG0 X10\nX20\nMCALL\nG0 X30\nM30\n",
    );
    for (line, x, z) in [(4, 10.0, 20.0), (5, 20.0, 10.0)] {
        assert_eq!(
            steps(&m, line),
            [
                ('r', [x, 0.0, z], 0.0),
                ('r', [x, 0.0, 2.0], 0.0),
                ('f', [x, 0.0, -5.0], 100.0),
                ('r', [x, 0.0, 10.0], 0.0),
            ]
        );
    }
    assert_eq!(steps(&m, 7).len(), 1);
}

/// CYCLE86 at X10 Y10 (G17): in at F to −20, dwell 0.5 s, the spindle oriented, lift-off
/// by RPA −1 (X), RPO 0.5 (Y), RPAP 1 (Z) with G0 to (9, 10.5, −19), G0 out to RFP + SDIS
/// = 2 still lifted off, G0 to RTP 10 over the hole. Under G18 (drilling along Y, the
/// plane's axes Z then X): RPA 1 on Z, RPO −2 on X, RPAP 1 on Y.
#[test]
fn cycle86_lifts_off_the_wall_before_it_retracts() {
    let m = moves(
        "G17 G90 F100 S500 M3\nG0 X10 Y10 Z20\nCYCLE86(10,0,2,-20,,0.5,3,-1,0.5,1,0)\n\
         G18\nG0 X10 Y30 Z5\nCYCLE86(20,10,2,-10,,0,4,1,-2,1,90)\nM30\n",
    );
    assert_eq!(
        steps(&m, 3),
        [
            ('r', [10.0, 10.0, 2.0], 0.0),
            ('f', [10.0, 10.0, -20.0], 100.0),
            ('d', [0.5, 0.0, 0.0], 0.0),
            ('r', [9.0, 10.5, -19.0], 0.0),
            ('r', [9.0, 10.5, 2.0], 0.0),
            ('r', [10.0, 10.0, 10.0], 0.0),
        ]
    );
    assert_eq!(
        steps(&m, 6),
        [
            ('r', [10.0, 12.0, 5.0], 0.0),
            ('f', [10.0, -10.0, 5.0], 100.0),
            ('r', [8.0, -9.0, 6.0], 0.0),
            ('r', [8.0, 12.0, 6.0], 0.0),
            ('r', [10.0, 20.0, 5.0], 0.0),
        ]
    );
}

/// CYCLE88 (dwell 1 s) and CYCLE87: in at F, spindle and program stop, then G0 to RTP as
/// after NC start; the stop is named in a notice.
#[test]
fn cycle87_and_cycle88_stop_at_the_depth_and_retract_after_nc_start() {
    let text = "G17 G90 F80 S400 M3\nG0 X5 Y5 Z20\nCYCLE88(10,0,2,-15,,1,3)\nCYCLE87(10,0,2,-12,,4)\nM30\n";
    let m = moves(text);
    assert_eq!(
        steps(&m, 3),
        [
            ('r', [5.0, 5.0, 2.0], 0.0),
            ('f', [5.0, 5.0, -15.0], 80.0),
            ('d', [1.0, 0.0, 0.0], 0.0),
            ('r', [5.0, 5.0, 10.0], 0.0),
        ]
    );
    assert_eq!(
        steps(&m, 4),
        [
            ('r', [5.0, 5.0, 2.0], 0.0),
            ('f', [5.0, 5.0, -12.0], 80.0),
            ('r', [5.0, 5.0, 10.0], 0.0),
        ]
    );
    let mut r = read_str_with(Path::new("c.mpf"), text, &options());
    let _: Vec<Move> = r.by_ref().collect::<Result<_, _>>().unwrap();
    assert!(
        r.notices().iter().any(|n| n.message.contains("M0")),
        "no notice of the program stop"
    );
}

/// What the reader does not read is refused at its line with the value named.
#[test]
fn cycle_values_mtsim_does_not_read_are_refused_by_name() {
    for (text, words) in [
        (
            "CYCLE83(10,0,2,-25,,-5,,-0.8,0,0,1,1,,2)",
            &["DAM -0.8", "factor"][..],
        ),
        ("CYCLE83(10,0,2,-25,,-5,,2,0,0,1,2)", &["VARI 2"]),
        (
            "CYCLE83(10,0,2,-25,,-5,,2,-3,0,1,1)",
            &["DTB -3", "revolutions"],
        ),
        ("CYCLE83(10,0,2,-25,,5,,2,0,0,1,1)", &["61107"]),
        ("CYCLE83(10,0,2,-25,,-5,,2,0,0,1,1,1)", &["_AXN 1"]),
        ("CYCLE83(10,0,2,-25,,,,2,0,0,1,1)", &["FDEP", "FDPR"]),
        (
            "CYCLE83(10,0,2,-25,,-5,,2,0,0,1,1,,,,,,,,1001)",
            &["_AMODE"],
        ),
        ("CYCLE83(10,0,2,-25,,-5,,2,0,0,1.5,1)", &["FRF 1.5"]),
        ("CYCLE86(10,0,2,-20,,0,5,0,0,0,0)", &["SDIR 5", "61102"]),
        ("CYCLE87(10,0,2,-20)", &["SDIR 0"]),
        // Operate arguments that change the values' meaning (a DMG post's call).
        (
            "CYCLE82(-300,-350,5,-400,,0.5,0,1,12)",
            &["CYCLE82 _AMODE 12", "alternative mode"],
        ),
        (
            "CYCLE84(-300,-350,5,-400,,1,3,,5,3,200,100,0,1,0,1,5,1.4,,,,,1000,1001002)",
            &["CYCLE84 _AMODE 1001002"],
        ),
        (
            "CYCLE84(10,0,2,-20,,0,3,,0.5,0,200,,,,,1)",
            &["CYCLE84 _VARI 1", "deep-hole tapping"],
        ),
        (
            "CYCLE84(10,0,2,-20,,0,3,,0.5,0,200,,,2)",
            &["_PTAB 2", "TPI"],
        ),
        ("CYCLE81(10,0,2,-20,,1)", &["CYCLE81 _GMODE 1"]),
    ] {
        let (line, msg) = refusal(&format!("G17 G90 F100\nG0 X0 Y0 Z20\n{text}\nM30\n"));
        assert_eq!(line, 3, "{text}: {msg}");
        for w in words {
            assert!(msg.contains(w), "{text}: {msg:?} does not name {w}");
        }
    }
}

/// DPR 0 is a left-out DPR (the control's cycles read a left-out value as 0): DP holds.
#[test]
fn a_dpr_of_zero_leaves_the_depth_to_dp() {
    let m = moves("G17 G90 F100\nG0 X0 Y0 Z20\nCYCLE81(10,0,2,-5,0)\nM30\n");
    let z: Vec<f64> = steps(&m, 3).iter().map(|s| s.1[2]).collect();
    assert_eq!(z, [2.0, -5.0, 10.0]);
}

/// The positioning moves (rapids in the plane) of `line`: X Y Z rounded to 1e-9.
fn positions(m: &[Move], line: usize) -> Vec<[f64; 3]> {
    let s = steps(m, line);
    // Each hole: the G0 in the plane, then CYCLE81's G0, G1, G0.
    s.chunks(4).map(|c| c[0].1).collect()
}

/// HOLES1(SPCA 10, SPCO 20, STA1 30°, FDIS 5, DBH 10, NUM 3) with MCALL CYCLE81: holes at
/// (10, 20) + (5, 15, 25)·(cos 30°, sin 30°) = (14.330127019, 22.5), (22.990381057, 27.5),
/// (31.650635095, 32.5); from (0, 0) the first hole is nearer, from (40, 40) the last, and
/// the row runs from there. Each hole after the first is reached at RTP 10. HOLES2(CPA 0,
/// CPO 0, RAD 10, STA1 90°, INDA −45°, NUM 3): (0, 10), (7.0710678, 7.0710678), (10, 0);
/// INDA 0 with NUM 4: 90° apart from STA1 0.
#[test]
fn holes1_and_holes2_drill_by_the_modal_call_at_each_position() {
    let c = 30f64.to_radians().cos();
    let row = [
        [10.0 + 5.0 * c, 22.5],
        [10.0 + 15.0 * c, 27.5],
        [10.0 + 25.0 * c, 32.5],
    ];
    let r = |v: f64| (v * 1e9).round() / 1e9 + 0.0;
    for (start, order) in [([0.0, 0.0], [0, 1, 2]), ([40.0, 40.0], [2, 1, 0])] {
        let m = moves(&format!(
            "G17 G90 F100\nG0 X{} Y{} Z20\nMCALL CYCLE81(10,0,2,-5)\nHOLES1(10,20,30,5,10,3)\nMCALL\nM30\n",
            start[0], start[1]
        ));
        let want: Vec<[f64; 3]> = order
            .iter()
            .enumerate()
            .map(|(k, &h)| [r(row[h][0]), r(row[h][1]), if k == 0 { 20.0 } else { 10.0 }])
            .collect();
        assert_eq!(positions(&m, 4), want, "from {start:?}");
        assert_eq!(steps(&m, 4).len(), 12);
        assert!(steps(&m, 4)
            .iter()
            .filter(|s| s.0 == 'f')
            .all(|s| s.1[2] == -5.0));
    }
    let h = r(10.0 / 2f64.sqrt());
    let m = moves(
        "G17 G90 F100\nG0 X0 Y0 Z20\nMCALL CYCLE81(10,0,2,-5)\nHOLES2(0,0,10,90,-45,3)\nMCALL\n\
         HOLES2(0,0,10,0,0,4)\nM30\n",
    );
    assert_eq!(
        positions(&m, 4),
        [[0.0, 10.0, 20.0], [h, h, 10.0], [10.0, 0.0, 10.0]]
    );
    // Without a modal call the holes are only approached.
    let only: Vec<[f64; 3]> = steps(&m, 6).iter().map(|s| s.1).collect();
    assert_eq!(
        only,
        [
            [10.0, 0.0, 10.0],
            [0.0, 10.0, 10.0],
            [-10.0, 0.0, 10.0],
            [0.0, -10.0, 10.0]
        ]
    );
}

/// Pattern and milling cycles mtsim does not read are refused naming what they are and
/// their manual section.
#[test]
fn pattern_and_pocket_cycles_not_read_are_named_with_their_section() {
    for (text, words) in [
        ("HOLES1(10,20,30,5,10,0)", &["HOLES1 NUM 0"][..]),
        (
            "CYCLE801(0,0,0,10,10,3,2)",
            &["`CYCLE801`", "grid of holes", "Cycles"],
        ),
        (
            "POCKET3(10,0,2,-5,40,30,5)",
            &["`POCKET3`", "rectangular pocket", "POCKET3)"],
        ),
        (
            "MCALL CYCLE801(0,0,0,10,10,3,2)",
            &["`CYCLE801`", "grid of holes"],
        ),
        ("LONGHOLE(10,0,2,-5)", &["`LONGHOLE`", "elongated holes"]),
        ("SLOT2(10,0,2,-5)", &["`SLOT2`", "circumferential slots"]),
    ] {
        let (line, msg) = refusal(&format!("G17 G90 F100\nG0 X0 Y0 Z20\n{text}\nM30\n"));
        assert_eq!(line, 3, "{text}: {msg}");
        for w in words {
            assert!(msg.contains(w), "{text}: {msg:?} does not name {w}");
        }
    }
}

/// `_DMODE` (the display mode, 1 here) changes no move: CYCLE82(RTP 10, RFP 0, SDIS 2,
/// DP −4, DTB 0.5, _GMODE 0, _DMODE 1, _AMODE 0) drills as CYCLE82 without them.
#[test]
fn the_display_mode_of_an_operate_cycle_call_changes_nothing() {
    let m = moves("G17 G90 F100\nG0 X0 Y0 Z20\nCYCLE82(10,0,2,-4,,0.5,0,1,0)\nM30\n");
    assert_eq!(
        steps(&m, 3),
        [
            ('r', [0.0, 0.0, 2.0], 0.0),
            ('f', [0.0, 0.0, -4.0], 100.0),
            ('d', [0.5, 0.0, 0.0], 0.0),
            ('r', [0.0, 0.0, 10.0], 0.0),
        ]
    );
}
