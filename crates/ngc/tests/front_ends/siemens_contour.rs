//! Sinumerik contour words (Fundamentals: "Circular interpolation with opening angle
//! (AR)", "Contour definitions: straight line with angle (ANG)", "Chamfer, rounding (CHF,
//! CHR, RND, RNDM)"): end points, centres and the inserted elements against geometry
//! worked by hand in the comments; and what is refused, by name.

use std::path::Path;

use ngc::{read_str_with, Dialect, Error, Motion, Move, Options};

fn options() -> Options {
    Options {
        dialect: Dialect::Siemens,
        ..Options::default()
    }
}

fn moves(text: &str) -> Vec<Move> {
    read_str_with(Path::new("k.mpf"), text, &options())
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("expected the program to read, got: {e}\n{text}"))
}

fn refusal(text: &str) -> (usize, String) {
    let err = read_str_with(Path::new("k.mpf"), text, &options())
        .find_map(|m| m.err())
        .unwrap_or_else(|| panic!("expected a refusal of {text:?}"));
    match err {
        Error::Syntax(s) => (s.line, s.message),
        other => panic!("expected a refusal at a line, got {other:?}"),
    }
}

fn near(a: [f64; 3], b: [f64; 3]) -> bool {
    a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-9)
}

/// Each move as (kind, end X Y Z, centre X Y Z or zeros): 'l' line, 'r' rapid, 'c'
/// clockwise arc, 'a' counter-clockwise arc.
fn path(m: &[Move]) -> Vec<(char, [f64; 3], [f64; 3])> {
    m.iter()
        .map(|m| {
            let e = m.end.to_xyzabc();
            let end = [e[0], e[1], e[2]];
            match m.motion {
                Motion::Arc {
                    clockwise,
                    center_mm,
                    ..
                } => (if clockwise { 'c' } else { 'a' }, end, center_mm),
                Motion::Rapid => ('r', end, [0.0; 3]),
                _ => ('l', end, [0.0; 3]),
            }
        })
        .collect()
}

fn assert_path(got: &[(char, [f64; 3], [f64; 3])], want: &[(char, [f64; 3], [f64; 3])]) {
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(want) {
        assert!(
            g.0 == w.0 && near(g.1, w.1) && near(g.2, w.2),
            "{g:?} != {w:?}\nin {got:?}"
        );
    }
}

/// AR with the end point: from (0,0) to (10,0), G3 AR=90: chord 10, centre the midpoint
/// (5,0) plus the chord's left normal (0,1) times 5 / tan 45° = 5: (5,5). G2 AR=270 from
/// (10,0) to (20,0): 5 / tan 135° = −5 times the right normal (0,−1): (15,5). AR with the
/// centre: G3 I−5 AR=90 from (20,0) turns (5,0) about (15,0) by +90°: end (15,5); G2 J−5
/// AR=180 from (15,5) about (15,0) by −180°: end (15,−5). Under G18 (plane Z, X): G3 Z10
/// AR=90 from Z0 X0: centre Z5 X5.
#[test]
fn ar_gives_the_centre_from_the_end_point_or_the_end_point_from_the_centre() {
    let m = moves(
        "G17 G90 F100\nG0 X0 Y0 Z0\nG3 X10 Y0 AR=90\nG2 X20 Y0 AR=270\nG3 I-5 J0 AR=90\n\
         G2 I0 J-5 AR=180\nG18 G0 X0 Y0 Z0\nG3 Z10 X0 AR=90\nM30\n",
    );
    assert_path(
        &path(&m),
        &[
            ('r', [0.0, 0.0, 0.0], [0.0; 3]),
            ('a', [10.0, 0.0, 0.0], [5.0, 5.0, 0.0]),
            ('c', [20.0, 0.0, 0.0], [15.0, 5.0, 0.0]),
            ('a', [15.0, 5.0, 0.0], [15.0, 0.0, 0.0]),
            ('c', [15.0, -5.0, 0.0], [15.0, 0.0, 0.0]),
            ('r', [0.0, 0.0, 0.0], [0.0; 3]),
            ('a', [0.0, 0.0, 10.0], [5.0, 0.0, 5.0]),
        ],
    );
}

/// ANG with one plane coordinate: from (15,−5), X10 ANG=30 gives Y = −5 + (10 − 15) tan 30°
/// = −7.886751345948129; then Y0 ANG=45 gives X = 10 + (0 + 7.886751345948129) / tan 45°;
/// under G91, X10 ANG=−45 goes 10 along X and −10 along Y.
#[test]
fn ang_gives_the_missing_coordinate_on_the_line_at_that_angle() {
    let m = moves("G17 G90 F100\nG0 X15 Y-5 Z0\nG1 X10 ANG=30\nY0 ANG=45\nG91 X10 ANG=-45\nM30\n");
    let y1 = -5.0 - 5.0 * 30f64.to_radians().tan();
    let x2 = 10.0 - y1;
    assert_path(
        &path(&m)[1..],
        &[
            ('l', [10.0, y1, 0.0], [0.0; 3]),
            ('l', [x2, 0.0, 0.0], [0.0; 3]),
            ('l', [x2 + 10.0, -10.0, 0.0], [0.0; 3]),
        ],
    );
}

/// RND=2 at a right-angle left turn (0,0)→(10,0)→(10,10): tangent points 2·tan 45° = 2
/// from the corner, (8,0) and (10,2), centre (8,2), counter-clockwise. CHR=2: the chamfer
/// (8,0)→(10,2). CHF=2 at the same corner: legs 2 / (2 cos 45°) = √2. CHF=1 at a 45° turn
/// (0,0)→(10,0)→(20,10): legs 1 / (2 cos 22.5°) = 0.541196100146197, the chamfer from
/// (10 − 0.5412, 0) to (10 + 0.5412 cos 45°, 0.5412 sin 45°), which is 1 long.
#[test]
fn rnd_chr_and_chf_insert_the_arc_or_chamfer_at_the_corner() {
    let corner = |word: &str| {
        let m = moves(&format!(
            "G17 G90 F100\nG0 X0 Y0 Z0\nG1 X10 {word}\nY10\nM30\n"
        ));
        path(&m)[1..].to_vec()
    };
    assert_path(
        &corner("RND=2"),
        &[
            ('l', [8.0, 0.0, 0.0], [0.0; 3]),
            ('a', [10.0, 2.0, 0.0], [8.0, 2.0, 0.0]),
            ('l', [10.0, 10.0, 0.0], [0.0; 3]),
        ],
    );
    assert_path(
        &corner("CHR=2"),
        &[
            ('l', [8.0, 0.0, 0.0], [0.0; 3]),
            ('l', [10.0, 2.0, 0.0], [0.0; 3]),
            ('l', [10.0, 10.0, 0.0], [0.0; 3]),
        ],
    );
    let r2 = 2f64.sqrt();
    assert_path(
        &corner("CHF=2"),
        &[
            ('l', [10.0 - r2, 0.0, 0.0], [0.0; 3]),
            ('l', [10.0, r2, 0.0], [0.0; 3]),
            ('l', [10.0, 10.0, 0.0], [0.0; 3]),
        ],
    );
    let m = moves("G17 G90 F100\nG0 X0 Y0 Z0\nG1 X10 CHF=1\nX20 Y10\nM30\n");
    let leg = 1.0 / (2.0 * 22.5f64.to_radians().cos());
    let h = leg / 2f64.sqrt();
    let p = path(&m);
    assert_path(
        &p[1..],
        &[
            ('l', [10.0 - leg, 0.0, 0.0], [0.0; 3]),
            ('l', [10.0 + h, h, 0.0], [0.0; 3]),
            ('l', [20.0, 10.0, 0.0], [0.0; 3]),
        ],
    );
    let (a, b) = (p[1].1, p[2].1);
    assert!(((b[0] - a[0]).hypot(b[1] - a[1]) - 1.0).abs() < 1e-12);
}

/// RNDM=1 rounds the corner at the end of its own block and of each later line until
/// RNDM=0 (whose block's corner is not rounded): a square's first two corners are rounded
/// with centres (9,1) and (9,9), the third is sharp.
#[test]
fn rndm_rounds_every_corner_until_it_is_switched_off() {
    let m = moves("G17 G90 F100\nG0 X0 Y0 Z0\nG1 X10 RNDM=1\nY10\nX0 RNDM=0\nY0\nM30\n");
    assert_path(
        &path(&m)[1..],
        &[
            ('l', [9.0, 0.0, 0.0], [0.0; 3]),
            ('a', [10.0, 1.0, 0.0], [9.0, 1.0, 0.0]),
            ('l', [10.0, 9.0, 0.0], [0.0; 3]),
            ('a', [9.0, 10.0, 0.0], [9.0, 9.0, 0.0]),
            ('l', [0.0, 10.0, 0.0], [0.0; 3]),
            ('l', [0.0, 0.0, 0.0], [0.0; 3]),
        ],
    );
}

/// What is not read is refused at its line, naming the word.
#[test]
fn contour_words_mtsim_does_not_read_are_refused_by_name() {
    for (text, line, words) in [
        (
            "G1 X10 Y5 ANG=30",
            3,
            &["ANG=30", "both", "two or more lines"][..],
        ),
        ("G1 ANG=30", 3, &["ANG=30", "neither"]),
        ("G1 X10 ANG=90", 3, &["ANG=90", "parallel"]),
        ("G2 X10 Y0 CR=5 AR=90", 3, &["AR=90", "CR="]),
        ("G3 X10 Y0 AR=0", 3, &["AR=0", "opening angle"]),
        ("G1 X10 AR=90", 3, &["AR=90", "G2 or G3"]),
        (
            "G1 X10 CHF=1\nG2 X20 Y0 CR=5",
            4,
            &["CHF=1", "next to an arc", "chord"],
        ),
        ("G1 X10 RND=2", 4, &["RND=2", "program ends"]),
        ("G0 X10 RND=2\nG1 Y5", 3, &["RND=2", "not a G1 line"]),
        ("G1 X10 RND=20\nY5", 4, &["RND=20", "does not fit"]),
        ("G1 X10 CHF=0\nY5", 3, &["CHF=0", "over 0"]),
        (
            "G1 X10 CHF=1 FRC=50\nY5",
            3,
            &["`FRC`", "feed of a chamfer"],
        ),
    ] {
        let (at, msg) = refusal(&format!("G17 G90 F100\nG0 X0 Y0 Z0\n{text}\nM30\n"));
        assert_eq!(at, line, "{text}: {msg}");
        for w in words {
            assert!(msg.contains(w), "{text}: {msg:?} does not name {w}");
        }
        assert!(
            !msg.contains("Fanuc") && !msg.contains("`,"),
            "{text}: {msg}"
        );
    }
}

/// The element is part of the programmed contour, so the frame maps it with the lines:
/// under ROT Z90 the corner (10, 0) → (10, 10) becomes (0, 0) → (0, 10) → (−10, 10), RND=2
/// touching at (0, 8) and (−2, 10) about (−2, 8); under SCALE X2 Y2 the corner is at (20, 0)
/// and the radius 4: (16, 0), (20, 4) about (16, 4).
#[test]
fn a_rotating_or_scaling_frame_maps_the_rounding_with_the_contour() {
    let rot = moves("G17 G90 F100\nG0 X0 Y0 Z0\nROT Z90\nG1 X10 Y0 RND=2\nY10\nM30\n");
    assert_path(
        &path(&rot)[1..],
        &[
            ('l', [0.0, 8.0, 0.0], [0.0; 3]),
            ('a', [-2.0, 10.0, 0.0], [-2.0, 8.0, 0.0]),
            ('l', [-10.0, 10.0, 0.0], [0.0; 3]),
        ],
    );
    let scaled = moves("G17 G90 F100\nG0 X0 Y0 Z0\nSCALE X2 Y2\nG1 X10 Y0 RND=2\nY10\nM30\n");
    assert_path(
        &path(&scaled)[1..],
        &[
            ('l', [16.0, 0.0, 0.0], [0.0; 3]),
            ('a', [20.0, 4.0, 0.0], [16.0, 4.0, 0.0]),
            ('l', [20.0, 20.0, 0.0], [0.0; 3]),
        ],
    );
}

/// RND= between a line and an arc (Fundamentals, "Chamfer, rounding (CHF, CHR, RND, RNDM)":
/// a rounding between any two contour elements). The line along +X to (10, 0), then G2 to
/// (20, 0) with CR=5 (centre (15, 0), the path turning left onto it): the rounding circle of
/// radius 2 lies left of the path, outside the arc's circle, so its centre c = (x, 2) is
/// 5 + 2 from (15, 0): x = 15 − √45. It touches the line at (15 − √45, 0) and the arc at
/// (15, 0) + 5 (c − (15, 0))/7.
#[test]
fn rnd_between_a_line_and_an_arc_rounds_tangent_to_both() {
    let m = moves("G17 G90 F100\nG0 X0 Y0 Z0\nG1 X10 RND=2\nG2 X20 Y0 CR=5\nM30\n");
    let x = 15.0 - 45f64.sqrt();
    let on_arc = [15.0 + 5.0 * (x - 15.0) / 7.0, 5.0 * 2.0 / 7.0, 0.0];
    assert_path(
        &path(&m),
        &[
            ('r', [0.0; 3], [0.0; 3]),
            ('l', [x, 0.0, 0.0], [0.0; 3]),
            ('a', on_arc, [x, 2.0, 0.0]),
            ('c', [20.0, 0.0, 0.0], [15.0, 0.0, 0.0]),
        ],
    );
}
