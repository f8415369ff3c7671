//! The Klartext slot and stud cycles 253, 254, 256, 257 against paths worked out by hand
//! from the TNC 640 cycle programming manual's definitions (Q parameters, the order of
//! roughing, side and floor finishing) and the path docs/gcode.md gives: a tool Ø10
//! (ρ = 5), every point listed here computed on paper, not taken from a run.

use ngc::{Axis, Feed, Motion, Move};

use super::klartext_setup::{in_program, klartext_options, read_named};

fn run(body: &str) -> Result<Vec<Move>, (usize, String)> {
    read_named("t.h", &in_program(body), &klartext_options())
}

/// One move as (kind, end X Y Z): 'R' rapid, 'L' feed line, 'A' counter-clockwise arc,
/// 'C' clockwise arc.
fn path(m: &[Move]) -> Vec<(char, [f64; 3])> {
    m.iter()
        .map(|m| {
            let k = match m.motion {
                Motion::Rapid => 'R',
                Motion::Linear => 'L',
                Motion::Arc { clockwise, .. } => {
                    if clockwise {
                        'C'
                    } else {
                        'A'
                    }
                }
                Motion::Dwell { .. } => 'D',
            };
            (k, [m.end[Axis::X], m.end[Axis::Y], m.end[Axis::Z]])
        })
        .collect()
}

/// The arcs as (counter-clockwise, centre X Y, radius, sweep in degrees).
fn arcs(m: &[Move]) -> Vec<(bool, [f64; 2], f64, f64)> {
    m.iter()
        .filter_map(|m| match m.motion {
            Motion::Arc {
                clockwise,
                center_mm,
                ..
            } => {
                let c = [center_mm[0], center_mm[1]];
                let r = (m.start[Axis::X] - c[0]).hypot(m.start[Axis::Y] - c[1]);
                Some((!clockwise, c, r, m.arc_sweep_rad().unwrap().to_degrees()))
            }
            _ => None,
        })
        .collect()
}

fn same(got: &[(char, [f64; 3])], want: &[(char, [f64; 3])]) {
    assert_eq!(got.len(), want.len(), "\n got {got:?}\nwant {want:?}");
    for (g, w) in got.iter().zip(want) {
        let near = g.1.iter().zip(w.1).all(|(a, b)| (a - b).abs() < 1e-9);
        assert!(g.0 == w.0 && near, "\n got {got:?}\nwant {want:?}");
    }
}

fn same_arcs(got: &[(bool, [f64; 2], f64, f64)], want: &[(bool, [f64; 2], f64, f64)]) {
    assert_eq!(got.len(), want.len(), "\n got {got:?}\nwant {want:?}");
    for (g, w) in got.iter().zip(want) {
        let ok = g.0 == w.0
            && (g.1[0] - w.1[0]).abs() < 1e-9
            && (g.1[1] - w.1[1]).abs() < 1e-9
            && (g.2 - w.2).abs() < 1e-9
            && (g.3 - w.3).abs() < 1e-7;
        assert!(ok, "\n got {got:?}\nwant {want:?}");
    }
}

fn slot(call: &str, q: &str) -> String {
    format!(
        "2 L {call} Z+20 R0 FMAX\n3 CYCL DEF 253 SLOT MILLING ~\n {q} ~\n Q207=+500 ~\n \
         Q206=+150 ~\n Q200=+2 ~\n Q203=+0 ~\n Q204=+50 ~\n Q366=+0 ~\n Q385=+300 ~\n Q439=+0\n\
         4 CYCL CALL"
    )
}

#[test]
fn cycle_253_plunges_at_the_left_arc_and_runs_the_slot_contour_counter_clockwise() {
    // 60 × 20 slot about the call position (50, 40), climb: the centre line from
    // (50 − 20, 40) to (50 + 20, 40) (h = (60 − 20)/2), the wall path 20/2 − 5 = 5 from it.
    // One stepover (ρ = 5) reaches the wall: the contour d = 5 alone, which covers the
    // centre line (5 = ρ from it).
    let m = run(&slot(
        "X+50 Y+40",
        "Q215=+0 ~\n Q218=+60 ~\n Q219=+20 ~\n Q368=+0 ~\n Q374=+0 ~\n Q367=+0 ~\n \
         Q351=+1 ~\n Q201=-4 ~\n Q202=+4 ~\n Q369=+0 ~\n Q338=+0",
    ))
    .unwrap();
    same(
        &path(&m[1..]),
        &[
            ('R', [50.0, 40.0, 2.0]),
            ('R', [30.0, 40.0, 2.0]),
            ('L', [30.0, 40.0, -4.0]),
            ('L', [30.0, 35.0, -4.0]),
            ('L', [70.0, 35.0, -4.0]),
            ('A', [70.0, 45.0, -4.0]),
            ('L', [30.0, 45.0, -4.0]),
            ('A', [30.0, 35.0, -4.0]),
            ('L', [30.0, 40.0, -4.0]),
            ('R', [30.0, 40.0, 2.0]),
            ('R', [30.0, 40.0, 50.0]),
        ],
    );
    same_arcs(
        &arcs(&m),
        &[
            (true, [70.0, 40.0], 5.0, 180.0),
            (true, [30.0, 40.0], 5.0, 180.0),
        ],
    );
    assert_eq!(m[3].feed, Feed::PerMinute(150.0));
    assert!(m[4..9].iter().all(|m| m.feed == Feed::PerMinute(500.0)));
}

#[test]
fn cycle_253_from_its_left_end_turned_90_degrees_as_wide_as_the_tool_mills_the_centre_line() {
    // Called at (0, 0), the slot's left end (Q367 = 1), turned 90°: the centre (0, 20), the
    // centre line from (0, 5) to (0, 35) (40/2 − 10/2 = 15 each side). Width 10 = the
    // tool: the centre line there and back at each level −3, −6, up-cut (no contour).
    let m = run(&slot(
        "X+0 Y+0",
        "Q215=+0 ~\n Q218=+40 ~\n Q219=+10 ~\n Q368=+0 ~\n Q374=+90 ~\n Q367=+1 ~\n \
         Q351=-1 ~\n Q201=-6 ~\n Q202=+3 ~\n Q369=+0 ~\n Q338=+0",
    ))
    .unwrap();
    same(
        &path(&m[1..]),
        &[
            ('R', [0.0, 0.0, 2.0]),
            ('R', [0.0, 5.0, 2.0]),
            ('L', [0.0, 5.0, -3.0]),
            ('L', [0.0, 35.0, -3.0]),
            ('L', [0.0, 5.0, -3.0]),
            ('L', [0.0, 5.0, -6.0]),
            ('L', [0.0, 35.0, -6.0]),
            ('L', [0.0, 5.0, -6.0]),
            ('R', [0.0, 5.0, 2.0]),
            ('R', [0.0, 5.0, 50.0]),
        ],
    );
}

#[test]
fn cycle_253_with_allowances_roughs_short_of_the_wall_then_finishes_wall_and_floor() {
    // 50 × 30 at (0, 0), up-cut (clockwise), side allowance 1, floor 0.5, one level (Q202
    // 10 > 3): roughing at −3 + 0.5 = −2.5, the wall path 15 − 5 = 10 less 1 = 9: contours
    // d = 5 and 9 about the centre line (−10, 0)-(10, 0), after the centre line there and
    // back. Then the wall d = 10 at −3 (F Q385 300), then the floor at −3: centre line,
    // d = 5, d = 10.
    let m = run(&slot(
        "X+0 Y+0",
        "Q215=+0 ~\n Q218=+50 ~\n Q219=+30 ~\n Q368=+1 ~\n Q374=+0 ~\n Q367=+0 ~\n \
         Q351=-1 ~\n Q201=-3 ~\n Q202=+10 ~\n Q369=+0.5 ~\n Q338=+0",
    ))
    .unwrap();
    // Clockwise: each contour d from (−10, −d) up the left end arc first.
    let contour = |d: f64, z: f64| {
        vec![
            ('L', [-10.0, -d, z]),
            ('C', [-10.0, d, z]),
            ('L', [10.0, d, z]),
            ('C', [10.0, -d, z]),
            ('L', [-10.0, -d, z]),
        ]
    };
    let mut want = vec![
        ('R', [0.0, 0.0, 2.0]),
        ('R', [-10.0, 0.0, 2.0]),
        ('L', [-10.0, 0.0, -2.5]),
        ('L', [10.0, 0.0, -2.5]),
        ('L', [-10.0, 0.0, -2.5]),
    ];
    want.extend(contour(5.0, -2.5));
    want.extend(contour(9.0, -2.5));
    want.push(('L', [-10.0, 0.0, -2.5]));
    // The wall finishing: down at the start, the wall alone, back.
    want.push(('L', [-10.0, 0.0, -3.0]));
    want.extend(contour(10.0, -3.0));
    want.push(('L', [-10.0, 0.0, -3.0]));
    // The floor.
    want.extend([('L', [10.0, 0.0, -3.0]), ('L', [-10.0, 0.0, -3.0])]);
    want.extend(contour(5.0, -3.0));
    want.extend(contour(10.0, -3.0));
    want.push(('L', [-10.0, 0.0, -3.0]));
    want.extend([('R', [-10.0, 0.0, 2.0]), ('R', [-10.0, 0.0, 50.0])]);
    same(&path(&m[1..]), &want);
    // Wall and floor at F Q385.
    let wall = m
        .iter()
        .position(|m| m.end[Axis::Z] == -3.0 && m.motion == Motion::Linear)
        .unwrap();
    assert_eq!(m[wall].feed, Feed::PerMinute(150.0));
    assert!(m[wall + 1..m.len() - 2]
        .iter()
        .all(|m| m.feed == Feed::PerMinute(300.0)));
}

#[test]
fn cycle_254_mills_each_slot_on_its_pitch_circle_between_two_end_arcs() {
    // Pitch circle Ø80 about (0, 0), slot 20 wide from 0° over 90°, twice, 180° apart:
    // the wall path 10 − 5 = 5 from the centre arc of radius 40; one contour (d = 5): the
    // outer arc R 45 (+90°), the end arc about (0, 40) (+180°), the inner arc R 35 back
    // (−90°), the end arc about (40, 0) (+180°). The second slot from 180° to 270°.
    let m = run(
        "2 L X+0 Y+0 Z+20 R0 FMAX\n3 CYCL DEF 254 CIRCULAR SLOT ~\n Q215=+0 ~\n Q219=+20 ~\n \
         Q368=+0 ~\n Q375=+80 ~\n Q367=+0 ~\n Q216=+0 ~\n Q217=+0 ~\n Q376=+0 ~\n Q248=+90 ~\n \
         Q378=+180 ~\n Q377=+2 ~\n Q207=+500 ~\n Q351=+1 ~\n Q201=-3 ~\n Q202=+3 ~\n \
         Q369=+0 ~\n Q206=+150 ~\n Q338=+0 ~\n Q200=+2 ~\n Q203=+0 ~\n Q204=+50 ~\n \
         Q366=+0 ~\n Q385=+500 ~\n Q439=+0\n4 CYCL CALL",
    )
    .unwrap();
    same(
        &path(&m[1..]),
        &[
            ('R', [0.0, 0.0, 2.0]),
            ('R', [40.0, 0.0, 2.0]),
            ('L', [40.0, 0.0, -3.0]),
            ('L', [45.0, 0.0, -3.0]),
            ('A', [0.0, 45.0, -3.0]),
            ('A', [0.0, 35.0, -3.0]),
            ('C', [35.0, 0.0, -3.0]),
            ('A', [45.0, 0.0, -3.0]),
            ('L', [40.0, 0.0, -3.0]),
            ('R', [40.0, 0.0, 2.0]),
            ('R', [-40.0, 0.0, 2.0]),
            ('L', [-40.0, 0.0, -3.0]),
            ('L', [-45.0, 0.0, -3.0]),
            ('A', [0.0, -45.0, -3.0]),
            ('A', [0.0, -35.0, -3.0]),
            ('C', [-35.0, 0.0, -3.0]),
            ('A', [-45.0, 0.0, -3.0]),
            ('L', [-40.0, 0.0, -3.0]),
            ('R', [-40.0, 0.0, 2.0]),
            ('R', [-40.0, 0.0, 50.0]),
        ],
    );
    same_arcs(
        &arcs(&m)[..4],
        &[
            (true, [0.0, 0.0], 45.0, 90.0),
            (true, [0.0, 40.0], 5.0, 180.0),
            (false, [0.0, 0.0], 35.0, -90.0),
            (true, [40.0, 0.0], 5.0, 180.0),
        ],
    );
}

#[test]
fn cycle_257_roughs_from_outside_the_blank_inward_and_ends_at_its_start_point() {
    // Stud Ø40 from a blank Ø60 at (0, 0), climb (clockwise outside), Q370 1: stepover 5,
    // material 10 per side: passes at e = 10 and e = 5 outside Ø40 (circles R 30, R 25).
    // Start S 2 mm + ρ outside the blank at 0°: (30 + 2 + 5, 0) = (37, 0). Each pass: a
    // counter-clockwise semicircle from S to (20 + e, 0), the circle, a semicircle back.
    let m = run(
        "2 L X+0 Y+0 Z+20 R0 FMAX\n3 CYCL DEF 257 CIRCULAR STUD ~\n Q223=+40 ~\n Q222=+60 ~\n \
         Q368=+0 ~\n Q207=+500 ~\n Q351=+1 ~\n Q201=-5 ~\n Q202=+5 ~\n Q206=+150 ~\n \
         Q200=+2 ~\n Q203=+0 ~\n Q204=+50 ~\n Q370=+1 ~\n Q376=+0 ~\n Q215=+0 ~\n Q369=+0 ~\n \
         Q338=+0 ~\n Q385=+500\n4 CYCL CALL",
    )
    .unwrap();
    same(
        &path(&m[1..]),
        &[
            ('R', [0.0, 0.0, 2.0]),
            ('R', [37.0, 0.0, 2.0]),
            ('L', [37.0, 0.0, -5.0]),
            ('A', [30.0, 0.0, -5.0]),
            ('C', [30.0, 0.0, -5.0]),
            ('A', [37.0, 0.0, -5.0]),
            ('A', [25.0, 0.0, -5.0]),
            ('C', [25.0, 0.0, -5.0]),
            ('A', [37.0, 0.0, -5.0]),
            ('R', [37.0, 0.0, 2.0]),
            ('R', [37.0, 0.0, 50.0]),
        ],
    );
    same_arcs(
        &arcs(&m),
        &[
            (true, [33.5, 0.0], 3.5, 180.0),
            (false, [0.0, 0.0], 30.0, -360.0),
            (true, [33.5, 0.0], 3.5, 180.0),
            (true, [31.0, 0.0], 6.0, 180.0),
            (false, [0.0, 0.0], 25.0, -360.0),
            (true, [31.0, 0.0], 6.0, 180.0),
        ],
    );
}

#[test]
fn cycle_256_roughs_to_the_allowance_then_finishes_the_wall_at_q385() {
    // Stud 40 × 20, corner R2, blank 50 × 30, at (100, 50), allowance 0.5, climb: material
    // 5 − 0.5 = 4.5 per side, one pass (stepover 5) at e = 5.5: half sides 25.5 × 15.5,
    // corner radius 7.5; the finishing pass at e = 5: 25 × 15, corner 7. Both corner arcs'
    // centres are the stud's corner centres (100 ± 18, 50 ± 8). S at 20 + 5 + 2 + 5 = 32
    // right of the centre: (132, 50).
    let m = run(
        "2 L X+100 Y+50 Z+20 R0 FMAX\n3 CYCL DEF 256 RECTANGULAR STUD ~\n Q218=+40 ~\n \
         Q424=+50 ~\n Q219=+20 ~\n Q425=+30 ~\n Q220=+2 ~\n Q368=+0.5 ~\n Q224=+0 ~\n \
         Q367=+0 ~\n Q207=+500 ~\n Q351=+1 ~\n Q201=-4 ~\n Q202=+4 ~\n Q206=+150 ~\n \
         Q200=+2 ~\n Q203=+0 ~\n Q204=+50 ~\n Q370=+1 ~\n Q437=+0 ~\n Q215=+0 ~\n Q369=+0 ~\n \
         Q338=+0 ~\n Q385=+300\n4 CYCL CALL",
    )
    .unwrap();
    let corners = [[118.0, 42.0], [82.0, 42.0], [82.0, 58.0], [118.0, 58.0]];
    let mut want = vec![(true, [128.75, 50.0], 3.25, 180.0)];
    want.extend(corners.iter().map(|c| (false, *c, 7.5, -90.0)));
    want.push((true, [128.75, 50.0], 3.25, 180.0));
    want.push((true, [128.5, 50.0], 3.5, 180.0));
    want.extend(corners.iter().map(|c| (false, *c, 7.0, -90.0)));
    want.push((true, [128.5, 50.0], 3.5, 180.0));
    same_arcs(&arcs(&m), &want);
    // The rough pass's straight sides: from (125.5, 50) down to (125.5, 42), …
    let p = path(&m[1..]);
    let rough: Vec<[f64; 3]> = p[4..14].iter().map(|s| s.1).collect();
    let want_rough = [
        [125.5, 42.0, -4.0],
        [118.0, 34.5, -4.0],
        [82.0, 34.5, -4.0],
        [74.5, 42.0, -4.0],
        [74.5, 58.0, -4.0],
        [82.0, 65.5, -4.0],
        [118.0, 65.5, -4.0],
        [125.5, 58.0, -4.0],
        [125.5, 50.0, -4.0],
        [132.0, 50.0, -4.0],
    ];
    for (g, w) in rough.iter().zip(want_rough) {
        assert!(
            g.iter().zip(w).all(|(a, b)| (a - b).abs() < 1e-9),
            "{rough:?}"
        );
    }
    // Feeds: roughing 500, finishing 300; the end over S at Q204.
    let feeds: Vec<Feed> = m
        .iter()
        .filter(|m| matches!(m.motion, Motion::Arc { .. }))
        .map(|m| m.feed)
        .collect();
    assert!(feeds[..6].iter().all(|f| *f == Feed::PerMinute(500.0)));
    assert!(feeds[6..].iter().all(|f| *f == Feed::PerMinute(300.0)));
    let last = m.last().unwrap();
    assert_eq!(
        [last.end[Axis::X], last.end[Axis::Y], last.end[Axis::Z]],
        [132.0, 50.0, 50.0]
    );
}

#[test]
fn slot_and_stud_options_not_modelled_are_refused_naming_the_q_parameter() {
    let stud = |extra: &str| {
        format!(
            "2 L X+0 Y+0 Z+20 R0 FMAX\n3 CYCL DEF 256 RECTANGULAR STUD ~\n Q218=+40 ~\n \
             Q424=+50 ~\n Q219=+20 ~\n Q425=+30 ~\n Q368=+0 ~\n Q224=+0 ~\n Q367=+0 ~\n \
             Q207=+500 ~\n Q351=+1 ~\n Q201=-4 ~\n Q202=+4 ~\n Q206=+150 ~\n Q200=+2 ~\n \
             Q203=+0 ~\n Q204=+50 ~\n Q370=+1 ~\n {extra}\n4 CYCL CALL"
        )
    };
    for (body, needles) in [
        (
            stud("Q220=+0 ~\n Q437=+1"),
            vec!["Q437", "Cycle 256", "corner"],
        ),
        (stud("Q220=-3 ~\n Q437=+0"), vec!["Q220", "chamfer"]),
        (
            stud("Q220=+0 ~\n Q437=+0").replace("Q424=+50", "Q424=+40"),
            vec!["Q424", "not larger"],
        ),
        (
            slot(
                "X+0 Y+0",
                "Q215=+0 ~\n Q218=+40 ~\n Q219=+8 ~\n Q368=+0 ~\n Q374=+0 ~\n Q367=+0 ~\n \
                 Q351=+1 ~\n Q201=-3 ~\n Q202=+3 ~\n Q369=+0 ~\n Q338=+0",
            ),
            vec!["Q219", "narrower than the tool"],
        ),
        (
            slot(
                "X+0 Y+0",
                "Q215=+0 ~\n Q218=+40 ~\n Q219=+20 ~\n Q368=+0 ~\n Q374=+0 ~\n Q367=+0 ~\n \
                 Q351=+1 ~\n Q201=-3 ~\n Q202=+3 ~\n Q369=+0 ~\n Q338=+0",
            )
            .replace("Q366=+0", "Q366=+1"),
            vec!["Q366", "ANGLE", "Cycle 253"],
        ),
        (
            "2 L X+0 Y+0 Z+20 R0 FMAX\n3 CYCL DEF 254 CIRCULAR SLOT ~\n Q219=+20 ~\n \
             Q375=+80 ~\n Q367=+2 ~\n Q248=+90 ~\n Q207=+500 ~\n Q351=+1 ~\n Q201=-3 ~\n \
             Q202=+3 ~\n Q206=+150 ~\n Q200=+2 ~\n Q203=+0 ~\n Q204=+50\n4 CYCL CALL"
                .to_string(),
            vec!["Q367", "Cycle 254"],
        ),
    ] {
        let (line, msg) = run(&body).unwrap_err();
        assert_eq!(
            line,
            3 + body.lines().position(|l| l.contains("CYCL CALL")).unwrap()
        );
        for n in needles {
            assert!(msg.contains(n), "{n} not in: {msg}");
        }
    }
}
