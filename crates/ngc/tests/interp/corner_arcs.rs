//! Fanuc and Haas corner rounding `,R` between a line and an arc and between two arcs
//! (Fanuc 0i-MF operator's manual, "Optional chamfering and corner R"). The fillet of
//! radius r lies inside the turn, its centre r from both moves: on the line offset by r,
//! and on the arc's circle of radius R − r (the arc's inside) or R + r (its outside). The
//! tangent points are the centre's foot on a line and `C + R (F − C)/|F − C|` on an arc.
//! Every figure below is worked by hand from that rule.

use super::corner_polar::{centre, close, read as read_in, xy};
use ngc::{Axis, Dialect, Move};

/// A Fanuc program's moves (the helpers are `corner_polar`'s).
fn read(text: &str) -> Result<Vec<Move>, String> {
    read_in(Dialect::Fanuc, text)
}

const HEAD: &str = "G21 G90 G17\nG0 X0. Y0. Z0.\n";

#[test]
fn a_line_into_a_quarter_arc_about_the_origin() {
    // (0,0) → (10,0), then G03 about (0,0) to (0,10): the arc leaves (10,0) along +Y, a
    // left turn. Offsets: the line y = 2, the arc's inside circle of radius 8; they meet
    // at (√60, 2). T1 = (√60, 0); T2 = 10 (√60, 2) / 8 = (1.25 √60, 2.5).
    let m = read(&format!("{HEAD}G1 X10. ,R2. F500\nG3 X0. Y10. R10.\nM30\n")).unwrap();
    let s60 = 60f64.sqrt();
    assert_eq!(m.len(), 4, "{m:?}");
    close(xy(m[1].end), [s60, 0.0]);
    close(xy(m[2].start), [s60, 0.0]);
    close(xy(m[2].end), [1.25 * s60, 2.5]);
    close(centre(&m[2]).0, [s60, 2.0]);
    assert!(!centre(&m[2]).1, "a left turn: G03");
    close(xy(m[3].start), [1.25 * s60, 2.5]);
    close(xy(m[3].end), [0.0, 10.0]);
    close(centre(&m[3]).0, [0.0, 0.0]);
    // The fillet is r = 2 from both tangent points.
    for p in [m[2].start, m[2].end] {
        assert!(((p[Axis::X] - s60).hypot(p[Axis::Y] - 2.0) - 2.0).abs() < 1e-12);
    }
}

#[test]
fn a_line_into_the_outside_of_an_arc_and_the_same_corner_backwards() {
    // (0,0) → (10,0), then G03 about (20,0) from (10,0) to (30,0): the arc leaves
    // (10,0) along −Y, a right turn; the fillet lies right of both, outside the arc.
    // Offsets: y = −2 and the circle about (20,0) of radius 12: x = 20 − √140 (nearest
    // the corner). F = (20 − √140, −2), T1 = (20 − √140, 0), T2 = (20,0) + 10 (−√140, −2)/12.
    let s140 = 140f64.sqrt();
    let f = [20.0 - s140, -2.0];
    let t1 = [20.0 - s140, 0.0];
    let t2 = [20.0 - 10.0 * s140 / 12.0, -20.0 / 12.0];
    let m = read(&format!(
        "{HEAD}G1 X10. ,R2. F500\nG3 X30. Y0. I10. J0.\nM30\n"
    ))
    .unwrap();
    close(xy(m[1].end), t1);
    assert!(centre(&m[2]).1, "a right turn: G02");
    close(centre(&m[2]).0, f);
    close(xy(m[2].end), t2);
    close(xy(m[3].start), t2);
    // Backwards: G02 from (30,0) about (20,0) to (10,0), then the line to (0,0): the same
    // fillet, from T2 to T1, now a left turn (G03).
    let m = read("G21 G90 G17\nG0 X30. Y0. Z0.\nG2 X10. Y0. I-10. J0. ,R2. F500\nG1 X0.\nM30\n")
        .unwrap();
    close(xy(m[1].end), t2);
    close(centre(&m[1]).0, [20.0, 0.0]);
    close(xy(m[2].start), t2);
    close(xy(m[2].end), t1);
    close(centre(&m[2]).0, f);
    assert!(!centre(&m[2]).1);
    close(xy(m[3].start), t1);
    close(xy(m[3].end), [0.0, 0.0]);
}

#[test]
fn two_arcs_meet_at_a_fillet_outside_the_first_and_inside_the_second() {
    // G03 about (0,0) from (6,−8) to (8,6), then G02 about (16,0) to (16,10). At (8,6) the
    // first leaves along (−0.6, 0.8), the second along (0.6, 0.8): a right turn. Offsets:
    // the circle about (0,0) of radius 12 (outside the G03) and about (16,0) of radius 8
    // (inside the G02): x = (16² + 12² − 8²)/32 = 10.5, y = √(144 − 10.5²) = √33.75.
    // T1 = 10 (10.5, √33.75)/12, T2 = (16,0) + 10 (−5.5, √33.75)/8.
    let h = 33.75f64.sqrt();
    let m = read(
        "G21 G90 G17\nG0 X6. Y-8. Z0.\nG3 X8. Y6. I-6. J8. ,R2. F500\nG2 X16. Y10. I8. J-6.\nM30\n",
    )
    .unwrap();
    let t1 = [8.75, 10.0 * h / 12.0];
    let t2 = [16.0 - 6.875, 10.0 * h / 8.0];
    close(xy(m[1].end), t1);
    assert_eq!(centre(&m[1]), ([0.0, 0.0], false));
    close(xy(m[2].start), t1);
    close(xy(m[2].end), t2);
    assert!(centre(&m[2]).1);
    close(centre(&m[2]).0, [10.5, h]);
    close(xy(m[3].start), t2);
    close(xy(m[3].end), [16.0, 10.0]);
    assert_eq!(centre(&m[3]), ([16.0, 0.0], true));
}

#[test]
fn what_is_not_modelled_next_to_an_arc_is_refused() {
    for (tail, says) in [
        // A chamfer next to an arc: chord or arc length, the manuals do not say.
        (
            "G1 X10. ,C2. F500\nG3 X0. Y10. R10.\nM30\n",
            "next to an arc",
        ),
        // r = 12 > R = 10 on the arc's inside: no circle fits.
        (
            "G1 X10. ,R12. F500\nG3 X0. Y10. R10.\nM30\n",
            "does not fit",
        ),
        // r = 6 fits the circle but its tangent point is past the 3 mm line.
        ("G1 X3. ,R6. F500\nG3 X-7. Y0. R10.\nM30\n", "does not fit"),
        // A helix moves off the plane.
        ("G1 X10. ,R2. F500\nG3 X0. Y10. Z-2. R10.\nM30\n", "off the"),
        // A full circle after the corner.
        (
            "G1 X10. ,R2. F500\nG3 X10. Y0. I-5. J0.\nM30\n",
            "full circle",
        ),
    ] {
        let e = read(&format!("{HEAD}{tail}")).unwrap_err();
        assert!(e.contains(says), "{tail:?}: {e}");
        assert!(e.contains("t.nc:4:"), "{tail:?}: {e}");
    }
}
