//! The Klartext thread milling cycles 262, 263, 265, 267 against helices worked out by
//! hand from the TNC 640 cycle programming manual's rules: a tool Ø10 (ρ = 5) on a helix of
//! radius Q335/2 − ρ (inside) or Q335/2 + ρ (outside), Q239 per turn, its direction and
//! work direction from the manual's table of pitch sign and climb/up-cut.

use ngc::{Axis, Feed, Motion, Move};

use super::klartext_setup::{in_program, klartext_options, read_named};

fn run(body: &str) -> Result<Vec<Move>, (usize, String)> {
    read_named("t.h", &in_program(body), &klartext_options())
}

/// One move as (kind, end X Y Z): 'R' rapid, 'L' feed line, 'A' counter-clockwise arc,
/// 'C' clockwise arc, with the arc's centre X Y (or the end's for other moves).
fn path(m: &[Move]) -> Vec<(char, [f64; 3], [f64; 2])> {
    m.iter()
        .map(|m| {
            let end = [m.end[Axis::X], m.end[Axis::Y], m.end[Axis::Z]];
            match m.motion {
                Motion::Rapid => ('R', end, [end[0], end[1]]),
                Motion::Arc {
                    clockwise,
                    center_mm,
                    ..
                } => (
                    if clockwise { 'C' } else { 'A' },
                    end,
                    [center_mm[0], center_mm[1]],
                ),
                _ => ('L', end, [end[0], end[1]]),
            }
        })
        .collect()
}

fn same(got: &[(char, [f64; 3], [f64; 2])], want: &[(char, [f64; 3], [f64; 2])]) {
    assert_eq!(got.len(), want.len(), "\n got {got:?}\nwant {want:?}");
    for (g, w) in got.iter().zip(want) {
        let near = g.1.iter().zip(w.1).all(|(a, b)| (a - b).abs() < 1e-9)
            && g.2.iter().zip(w.2).all(|(a, b)| (a - b).abs() < 1e-9);
        assert!(g.0 == w.0 && near, "\n got {got:?}\nwant {want:?}");
    }
}

fn thread(n: u32, call: &str, q: &str) -> String {
    format!(
        "2 L {call} Z+20 R0 FMAX\n3 CYCL DEF {n} THREAD ~\n {q} ~\n Q253=+750 ~\n Q200=+2 ~\n \
         Q203=+0 ~\n Q204=+20 ~\n Q207=+300\n4 CYCL CALL"
    )
}

#[test]
fn cycle_262_right_hand_climb_mills_from_the_depth_up_in_one_continuous_helix() {
    // M20 × 2 right-hand, climb, Q355 = 1, depth 6, at (10, 10): radius 10 − 5 = 5,
    // counter-clockwise, from −6 up (the table: right-hand, +1, Z+), 3 turns to 0. At Q253
    // down to −6 at the centre, a semicircle about (12.5, 10) to (15, 10), three turns,
    // the semicircle back to the centre, FMAX to 2 and 20.
    let m = run(&thread(
        262,
        "X+10 Y+10",
        "Q335=+20 ~\n Q239=+2 ~\n Q201=-6 ~\n Q355=+1 ~\n Q351=+1",
    ))
    .unwrap();
    let c = [10.0, 10.0];
    let half = [12.5, 10.0];
    same(
        &path(&m[1..]),
        &[
            ('R', [10.0, 10.0, 2.0], c),
            ('L', [10.0, 10.0, -6.0], c),
            ('A', [15.0, 10.0, -6.0], half),
            ('A', [15.0, 10.0, -4.0], c),
            ('A', [15.0, 10.0, -2.0], c),
            ('A', [15.0, 10.0, 0.0], c),
            ('A', [10.0, 10.0, 0.0], half),
            ('R', [10.0, 10.0, 2.0], c),
            ('R', [10.0, 10.0, 20.0], c),
        ],
    );
    assert_eq!(m[2].feed, Feed::PerMinute(750.0));
    assert!(m[3..8].iter().all(|m| m.feed == Feed::PerMinute(300.0)));
    // Full turns: each helix arc sweeps 360° and rises one pitch.
    for mv in &m[4..7] {
        assert!((mv.arc_sweep_rad().unwrap() - std::f64::consts::TAU).abs() < 1e-9);
        assert!((mv.end[Axis::Z] - mv.start[Axis::Z] - 2.0).abs() < 1e-9);
    }
}

#[test]
fn cycle_262_left_hand_up_cut_with_q355_0_mills_one_turn_up_from_the_depth() {
    // Left-hand (Q239 −1.5), up-cut: clockwise, Z+ (the table), one 360° helix to the
    // thread depth: from −6 up to −4.5.
    let m = run(&thread(
        262,
        "X+10 Y+10",
        "Q335=+20 ~\n Q239=-1.5 ~\n Q201=-6 ~\n Q355=+0 ~\n Q351=-1",
    ))
    .unwrap();
    let (c, half) = ([10.0, 10.0], [12.5, 10.0]);
    same(
        &path(&m[1..]),
        &[
            ('R', [10.0, 10.0, 2.0], c),
            ('L', [10.0, 10.0, -6.0], c),
            ('C', [15.0, 10.0, -6.0], half),
            ('C', [15.0, 10.0, -4.5], c),
            ('C', [10.0, 10.0, -4.5], half),
            ('R', [10.0, 10.0, 2.0], c),
            ('R', [10.0, 10.0, 20.0], c),
        ],
    );
}

#[test]
fn cycle_262_right_hand_up_cut_mills_down_and_a_part_turn_ends_off_the_start() {
    // Right-hand, up-cut: clockwise, Z− from the surface: 5 mm at 2 per turn = 2.5 turns;
    // two full turns to −2, −4, then half a turn to −5 at (5, 10); off on a semicircle
    // about (7.5, 10) back to the centre.
    let m = run(&thread(
        262,
        "X+10 Y+10",
        "Q335=+20 ~\n Q239=+2 ~\n Q201=-5 ~\n Q355=+1 ~\n Q351=-1",
    ))
    .unwrap();
    let c = [10.0, 10.0];
    same(
        &path(&m[1..]),
        &[
            ('R', [10.0, 10.0, 2.0], c),
            ('L', [10.0, 10.0, 0.0], c),
            ('C', [15.0, 10.0, 0.0], [12.5, 10.0]),
            ('C', [15.0, 10.0, -2.0], c),
            ('C', [15.0, 10.0, -4.0], c),
            ('C', [5.0, 10.0, -5.0], c),
            ('C', [10.0, 10.0, -5.0], [7.5, 10.0]),
            ('R', [10.0, 10.0, 2.0], c),
            ('R', [10.0, 10.0, 20.0], c),
        ],
    );
}

#[test]
fn cycle_267_outside_right_hand_climb_mills_down_from_beside_the_stud() {
    // M20 × 1.5 outside, right-hand, climb: clockwise outside, Z− (the table); radius
    // 10 + 5 = 15; the start 2 mm + ρ outside Ø20: (17, 0); 3 mm = 2 turns. On: a
    // counter-clockwise semicircle about (16, 0) to (15, 0); off the same way back out.
    let m = run(&thread(
        267,
        "X+0 Y+0",
        "Q335=+20 ~\n Q239=+1.5 ~\n Q201=-3 ~\n Q355=+1 ~\n Q351=+1 ~\n Q358=+0 ~\n Q359=+0",
    ))
    .unwrap();
    let (c, half) = ([0.0, 0.0], [16.0, 0.0]);
    same(
        &path(&m[1..]),
        &[
            ('R', [0.0, 0.0, 2.0], c),
            ('R', [17.0, 0.0, 2.0], [17.0, 0.0]),
            ('L', [17.0, 0.0, 0.0], [17.0, 0.0]),
            ('A', [15.0, 0.0, 0.0], half),
            ('C', [15.0, 0.0, -1.5], c),
            ('C', [15.0, 0.0, -3.0], c),
            ('A', [17.0, 0.0, -3.0], half),
            ('R', [17.0, 0.0, 2.0], [17.0, 0.0]),
            ('R', [17.0, 0.0, 20.0], [17.0, 0.0]),
        ],
    );
}

#[test]
fn cycle_265_drills_the_thread_down_from_the_surface_by_its_hand() {
    // Right-hand M20 × 2 from solid: clockwise, down from the surface 0 to −4 (2 turns).
    let m = run(&thread(
        265,
        "X+10 Y+10",
        "Q335=+20 ~\n Q239=+2 ~\n Q201=-4 ~\n Q358=+0 ~\n Q359=+0 ~\n Q360=+0 ~\n \
         Q254=+200 ~\n Q206=+150",
    ))
    .unwrap();
    let (c, half) = ([10.0, 10.0], [12.5, 10.0]);
    same(
        &path(&m[1..]),
        &[
            ('R', [10.0, 10.0, 2.0], c),
            ('L', [10.0, 10.0, 0.0], c),
            ('C', [15.0, 10.0, 0.0], half),
            ('C', [15.0, 10.0, -2.0], c),
            ('C', [15.0, 10.0, -4.0], c),
            ('C', [10.0, 10.0, -4.0], half),
            ('R', [10.0, 10.0, 2.0], c),
            ('R', [10.0, 10.0, 20.0], c),
        ],
    );
}

#[test]
fn cycle_263_without_countersinking_is_one_turn_and_with_it_is_refused() {
    // Right-hand, climb, inside: Z+, one 360° helix from the depth −8 to −6.
    let body = |sink: &str| {
        thread(
            263,
            "X+0 Y+0",
            &format!(
                "Q335=+20 ~\n Q239=+2 ~\n Q201=-8 ~\n Q356=-{sink} ~\n Q351=+1 ~\n \
                 Q357=+0.2 ~\n Q358=+0 ~\n Q359=+0 ~\n Q254=+200"
            ),
        )
    };
    let m = run(&body("0")).unwrap();
    let arcs: Vec<(char, [f64; 3], [f64; 2])> = path(&m)
        .into_iter()
        .filter(|p| p.0 != 'R' && p.0 != 'L')
        .collect();
    same(
        &arcs,
        &[
            ('A', [5.0, 0.0, -8.0], [2.5, 0.0]),
            ('A', [5.0, 0.0, -6.0], [0.0, 0.0]),
            ('A', [0.0, 0.0, -6.0], [2.5, 0.0]),
        ],
    );
    let (line, msg) = run(&body("10")).unwrap_err();
    assert_eq!(
        line,
        3 + body("10")
            .lines()
            .position(|l| l.contains("CYCL CALL"))
            .unwrap()
    );
    assert!(msg.contains("Q356") && msg.contains("Cycle 263"), "{msg}");
}

#[test]
fn thread_options_not_modelled_are_refused_naming_the_q_parameter() {
    for (n, q, needle) in [
        (
            262,
            "Q335=+20 ~\n Q239=+2 ~\n Q201=-6 ~\n Q355=+2 ~\n Q351=+1",
            "Q355",
        ),
        (
            262,
            "Q335=+8 ~\n Q239=+2 ~\n Q201=-6 ~\n Q355=+1 ~\n Q351=+1",
            "Q335",
        ),
        (
            262,
            "Q335=+20 ~\n Q239=+0 ~\n Q201=-6 ~\n Q355=+1 ~\n Q351=+1",
            "Q239",
        ),
        (
            267,
            "Q335=+20 ~\n Q239=+2 ~\n Q201=-6 ~\n Q355=+1 ~\n Q351=+1 ~\n Q358=-1 ~\n Q359=+0.5",
            "Q358",
        ),
    ] {
        let body = thread(n, "X+0 Y+0", q);
        let (line, msg) = run(&body).unwrap_err();
        assert_eq!(
            line,
            3 + body.lines().position(|l| l.contains("CYCL CALL")).unwrap()
        );
        assert!(
            msg.contains(needle) && msg.contains(&format!("cycle {n}")),
            "{msg}"
        );
    }
}

#[test]
fn cycle_264_drills_the_hole_in_infeeds_then_mills_one_turn() {
    // Hole to −12 by 5 (Q206 150): −5, FMAX up to 2, FMAX to −5 + Q258 0.5, −10, up, −9.5,
    // −12. Then at Q253 up to the thread's start plane −8 (right-hand, climb: Z+) and one
    // 360° turn of radius 5 to −6.
    let m = run(&thread(
        264,
        "X+0 Y+0",
        "Q335=+20 ~\n Q239=+2 ~\n Q201=-8 ~\n Q356=-12 ~\n Q351=+1 ~\n Q202=+5 ~\n \
         Q258=+0.5 ~\n Q257=+0 ~\n Q256=+0.2 ~\n Q358=+0 ~\n Q359=+0 ~\n Q206=+150",
    ))
    .unwrap();
    let c = [0.0, 0.0];
    let z = |k: char, z: f64| (k, [0.0, 0.0, z], c);
    same(
        &path(&m[1..]),
        &[
            z('R', 2.0),
            z('L', -5.0),
            z('R', 2.0),
            z('R', -4.5),
            z('L', -10.0),
            z('R', 2.0),
            z('R', -9.5),
            z('L', -12.0),
            z('L', -8.0),
            ('A', [5.0, 0.0, -8.0], [2.5, 0.0]),
            ('A', [5.0, 0.0, -6.0], c),
            ('A', [0.0, 0.0, -6.0], [2.5, 0.0]),
            z('R', 2.0),
            z('R', 20.0),
        ],
    );
    assert_eq!(m[2].feed, Feed::PerMinute(150.0));
    assert_eq!(m[9].feed, Feed::PerMinute(750.0));
    // Chip breaking is refused by name.
    let body = thread(
        264,
        "X+0 Y+0",
        "Q335=+20 ~\n Q239=+2 ~\n Q201=-8 ~\n Q356=-12 ~\n Q351=+1 ~\n Q202=+5 ~\n \
         Q258=+0.5 ~\n Q257=+2 ~\n Q256=+0.2 ~\n Q358=+0 ~\n Q359=+0 ~\n Q206=+150",
    );
    let (_, msg) = run(&body).unwrap_err();
    assert!(msg.contains("Q257") && msg.contains("Cycle 264"), "{msg}");
}
