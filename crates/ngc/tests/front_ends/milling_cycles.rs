//! The Klartext milling cycles 208 BORE MILLING, 251 RECTANGULAR POCKET and 252 CIRCULAR
//! POCKET against the
//! geometry the TNC 640 cycle programming manual gives, worked out by hand: a tool Ø10
//! (radius ρ = 5) runs on circles of radius (diameter)/2 − ρ about the call position; a
//! 208 helix drops Q334 per turn and ends at Q201; a 252 pocket's last pass is the circle
//! Q223/2 − ρ at the depth Q201, a 251 pocket's the rectangle of half sides Q218/2 − ρ,
//! Q219/2 − ρ with corner radius Q220 − ρ. And the cycles still refused, each by its name and manual
//! section.

use ngc::{Axis, Feed, Motion, Move};

use super::klartext_setup::{in_program, klartext_options, read_named};

fn run(body: &str) -> Result<Vec<Move>, (usize, String)> {
    read_named("t.h", &in_program(body), &klartext_options())
}

/// An arc's (counter-clockwise, centre X Y, radius of its start, Z of its end, feed).
fn arcs(m: &[Move]) -> Vec<(bool, [f64; 2], f64, f64, Feed)> {
    m.iter()
        .filter_map(|m| match m.motion {
            Motion::Arc {
                clockwise,
                center_mm,
                ..
            } => {
                let c = [center_mm[0], center_mm[1]];
                let r = (m.start[Axis::X] - c[0]).hypot(m.start[Axis::Y] - c[1]);
                Some((!clockwise, c, r, m.end[Axis::Z], m.feed))
            }
            _ => None,
        })
        .collect()
}

/// The file line of the body's line holding `needle` (two lines come before the body).
fn line_of(body: &str, needle: &str) -> usize {
    3 + body.lines().position(|l| l.contains(needle)).unwrap()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9
}

/// The pocket's circles: (radius, Z) of each, all counter-clockwise about (50, 40).
fn pocket_circles(m: &[Move]) -> Vec<(f64, f64)> {
    arcs(m)
        .iter()
        .map(|(ccw, c, r, z, _)| {
            assert!(*ccw && close(c[0], 50.0) && close(c[1], 40.0), "{c:?}");
            ((r * 1e9).round() / 1e9, *z)
        })
        .collect()
}

const POCKET: &str = "2 L X+50 Y+40 Z+20 R0 FMAX\n3 CYCL DEF 252 CIRCULAR POCKET ~\n \
    Q215=+0 ;MACHINING OPERATION ~\n Q223=+50 ;CIRCLE DIAMETER ~\n Q368=+{side} ~\n \
    Q207=+500 ;FEED RATE FOR MILLING ~\n Q351=+1 ;CLIMB OR UP-CUT ~\n Q201=-6 ;DEPTH ~\n \
    Q202=+3 ;PLUNGING DEPTH ~\n Q369=+{floor} ~\n Q206=+150 ;FEED RATE FOR PLUNGING ~\n \
    Q338=+{fin} ~\n Q200=+2 ~\n Q203=+0 ~\n Q204=+50 ~\n Q370=+1 ~\n Q366=+0 ~\n Q385=+200\n\
    4 CYCL CALL";

fn pocket(side: &str, floor: &str, fin: &str) -> Vec<Move> {
    run(&POCKET
        .replace("{side}", side)
        .replace("{floor}", floor)
        .replace("{fin}", fin))
    .unwrap()
}

#[test]
fn cycle_252_clears_the_pocket_in_circles_and_ends_on_the_wall_at_the_depth() {
    // Ø50 pocket, Ø10 tool, no allowances: the wall circle has radius 25 − 5 = 20; stepover
    // Q370 ρ = 5: circles 5, 10, 15, 20 at each plunging depth, −3 and −6.
    let m = pocket("0", "0", "0");
    let circles = pocket_circles(&m);
    let mut want = Vec::new();
    for z in [-3.0, -6.0] {
        for r in [5.0, 10.0, 15.0, 20.0] {
            want.push((r, z));
        }
    }
    assert_eq!(circles, want);
    // Nothing outside the wall circle, nothing below the depth.
    for mv in &m[1..] {
        let d = (mv.end[Axis::X] - 50.0).hypot(mv.end[Axis::Y] - 40.0);
        assert!(d <= 20.0 + 1e-9 && mv.end[Axis::Z] >= -6.0 - 1e-9, "{mv:?}");
    }
    // Full circles: each ends where it started.
    for mv in m.iter().filter(|m| matches!(m.motion, Motion::Arc { .. })) {
        assert!(
            close(mv.start[Axis::X], mv.end[Axis::X]) && close(mv.start[Axis::Y], mv.end[Axis::Y])
        );
    }
    // The plunge at the centre at Q206, and the end: FMAX to s + Q200 = 2, then Q204 = 50.
    let first_feed = m.iter().find(|m| m.motion == Motion::Linear).unwrap();
    assert_eq!(first_feed.feed, Feed::PerMinute(150.0));
    assert!(close(first_feed.end[Axis::Z], -3.0));
    let n = m.len();
    assert_eq!(m[n - 2].motion, Motion::Rapid);
    assert_eq!((m[n - 2].end[Axis::Z], m[n - 1].end[Axis::Z]), (2.0, 50.0));
    assert_eq!((m[n - 1].end[Axis::X], m[n - 1].end[Axis::Y]), (50.0, 40.0));
}

#[test]
fn cycle_252_roughs_to_the_allowances_then_finishes_walls_and_floor() {
    // Side allowance 0.5, floor 0.2, finishing infeed 3: roughing to radius 19.5 at −3 and
    // −6 + 0.2 = −5.8; the wall at radius 20 at −3 and −6 (F Q385 = 200); the floor at −6,
    // circles 5 … 20. The last pass is the circle 20 at the depth −6.
    let m = pocket("0.5", "0.2", "3");
    let mut want = Vec::new();
    for z in [-3.0, -5.8] {
        for r in [5.0, 10.0, 15.0, 19.5] {
            want.push((r, z));
        }
    }
    want.extend([(20.0, -3.0), (20.0, -6.0)]);
    for r in [5.0, 10.0, 15.0, 20.0] {
        want.push((r, -6.0));
    }
    let got = pocket_circles(&m);
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(&want) {
        assert!(close(g.0, w.0) && close(g.1, w.1), "{got:?}");
    }
    let feeds: Vec<Feed> = arcs(&m).iter().map(|a| a.4).collect();
    assert!(feeds[..8].iter().all(|f| *f == Feed::PerMinute(500.0)));
    assert!(feeds[8..].iter().all(|f| *f == Feed::PerMinute(200.0)));
}

#[test]
fn cycle_208_mills_a_helix_of_pitch_q334_down_to_q201() {
    // Ø20 bore, Ø10 tool: helix radius 10 − 5 = 5 about (10, 10), clockwise (Q351 = −1).
    // From s + Q200 = 2 to Q201 = −5: 7 mm at 2 per turn = 3.5 turns; a semicircle from the
    // centre out to (15, 10) first; three full turns to 0, −2, −4 at (15, 10); half a turn
    // to −5 at (5, 10); a full circle at −5; back to the centre; FMAX to 2, then Q204 10.
    let m = run(
        "2 L X+10 Y+10 Z+20 R0 FMAX\n3 CYCL DEF 208 BORE MILLING ~\n Q200=+2 ~\n \
         Q201=-5 ~\n Q206=+300 ~\n Q334=+2 ;PLUNGING DEPTH ~\n Q203=+0 ~\n Q204=+10 ~\n \
         Q335=+20 ;NOMINAL DIAMETER ~\n Q342=+0 ~\n Q351=-1\n4 CYCL CALL",
    )
    .unwrap();
    assert_eq!((m[1].motion, m[1].end[Axis::Z]), (Motion::Rapid, 2.0));
    let a = arcs(&m);
    assert_eq!(a.len(), 6, "{a:?}");
    assert!(a.iter().all(|a| !a.0 && a.4 == Feed::PerMinute(300.0)));
    // The semicircle: about (12.5, 10), radius 2.5, at Z 2.
    assert!(close(a[0].1[0], 12.5) && close(a[0].2, 2.5) && close(a[0].3, 2.0));
    let arc_moves: Vec<&Move> = m
        .iter()
        .filter(|m| matches!(m.motion, Motion::Arc { .. }))
        .collect();
    let mut z = 2.0;
    for k in 1..4 {
        assert!(close(a[k].1[0], 10.0) && close(a[k].1[1], 10.0) && close(a[k].2, 5.0));
        assert!(close(z - a[k].3, 2.0), "turn {k} drops {}", z - a[k].3);
        assert!(close(arc_moves[k].end[Axis::X], 15.0) && close(arc_moves[k].end[Axis::Y], 10.0));
        z = a[k].3;
    }
    // Half a turn, half a pitch, to the depth, opposite the start.
    let half = arc_moves[4];
    assert!(close(half.end[Axis::Z], -5.0) && close(z - half.end[Axis::Z], 1.0));
    assert!(close(half.end[Axis::X], 5.0) && close(half.end[Axis::Y], 10.0));
    assert!((half.arc_sweep_rad().unwrap() + std::f64::consts::PI).abs() < 1e-9);
    // The full circle at the depth, then the centre, then up.
    assert!((arc_moves[5].arc_sweep_rad().unwrap() + std::f64::consts::TAU).abs() < 1e-9);
    assert!(close(arc_moves[5].end[Axis::Z], -5.0));
    let n = m.len();
    assert_eq!(m[n - 3].motion, Motion::Linear);
    assert_eq!(
        [
            m[n - 3].end[Axis::X],
            m[n - 3].end[Axis::Y],
            m[n - 3].end[Axis::Z]
        ],
        [10.0, 10.0, -5.0]
    );
    assert_eq!((m[n - 2].end[Axis::Z], m[n - 1].end[Axis::Z]), (2.0, 10.0));
}

#[test]
fn cycle_208_with_the_bore_the_tool_size_plunges_and_a_smaller_bore_is_refused() {
    let body = |d: &str| {
        format!(
            "2 L X+0 Y+0 Z+20 R0 FMAX\n3 CYCL DEF 208 BORE MILLING ~\n Q200=+2 ~\n Q201=-5 ~\n \
             Q206=+300 ~\n Q334=+2 ~\n Q203=+0 ~\n Q204=+0 ~\n Q335=+{d} ~\n Q351=+1\n4 CYCL CALL"
        )
    };
    let m = run(&body("10")).unwrap();
    let z: Vec<(bool, f64)> = m[1..]
        .iter()
        .map(|m| (m.motion == Motion::Rapid, m.end[Axis::Z]))
        .collect();
    assert_eq!(z, [(true, 2.0), (false, -5.0), (true, 2.0)]);
    let (line, msg) = run(&body("8")).unwrap_err();
    assert_eq!(line, line_of(&body("8"), "CYCL CALL"));
    assert!(msg.contains("Q335") && msg.contains("smaller"), "{msg}");
}

#[test]
fn cycles_not_read_are_refused_by_name_and_manual_section() {
    for (n, title, section) in [
        (204, "BACK BORING", "drilling"),
        (241, "SINGLE-LIP DEEP-HOLE DRILLING", "drilling"),
    ] {
        let (line, msg) = run(&format!(
            "2 L X+0 Y+0 Z+20 R0 FMAX\n3 CYCL DEF {n} ~\n Q200=+2 ~\n Q201=-5\n4 CYCL CALL"
        ))
        .unwrap_err();
        assert_eq!(line, 4, "{msg}");
        let parts = [
            format!("Heidenhain cycle {n} {title}"),
            format!("\"Cycle {n}\""),
            section.to_string(),
        ];
        for part in parts {
            assert!(msg.contains(&part), "{part} not in: {msg}");
        }
    }
    // Helical plunging needs the tool table's ANGLE.
    let helical = POCKET
        .replace("{side}", "0")
        .replace("{floor}", "0")
        .replace("{fin}", "0")
        .replace("Q366=+0", "Q366=+1");
    let (line, msg) = run(&helical).unwrap_err();
    assert_eq!(line, line_of(&helical, "CYCL CALL"));
    assert!(msg.contains("Q366") && msg.contains("ANGLE"), "{msg}");
}

const RECT: &str = "2 L X+{x} Y+{y} Z+20 R0 FMAX\n3 CYCL DEF 251 RECTANGULAR POCKET ~\n \
    Q215=+0 ~\n Q218=+60 ;FIRST SIDE LENGTH ~\n Q219=+40 ;SECOND SIDE LENGTH ~\n \
    Q220=+8 ;CORNER RADIUS ~\n Q368=+0 ~\n Q224=+{rot} ;ANGLE OF ROTATION ~\n \
    Q367=+{pos} ;POCKET POSITION ~\n Q207=+500 ~\n Q351=+1 ~\n Q201=-4 ~\n Q202=+4 ~\n \
    Q369=+0 ~\n Q206=+150 ~\n Q338=+0 ~\n Q200=+2 ~\n Q203=+0 ~\n Q204=+50 ~\n Q370=+1 ~\n \
    Q366=+0 ~\n Q385=+500\n4 CYCL CALL";

fn rect(x: f64, y: f64, rot: f64, pos: u32) -> Vec<Move> {
    run(&RECT
        .replace("{x}", &x.to_string())
        .replace("{y}", &y.to_string())
        .replace("{rot}", &rot.to_string())
        .replace("{pos}", &pos.to_string()))
    .unwrap()
}

#[test]
fn cycle_251_clears_in_rounded_rectangles_and_ends_on_the_wall() {
    // 60 × 40, corner radius 8, tool Ø10: the wall path has half sides 25, 15 and corner
    // radius 8 − 5 = 3; stepover 5: rectangles 10 and 5 inside it (half sides 15 × 5 and
    // 20 × 10, sharp), then the wall path, counter-clockwise from the middle of the +X side.
    let m = rect(0.0, 0.0, 0.0, 0);
    let ends: Vec<[f64; 2]> = m
        .iter()
        .filter(|m| matches!(m.motion, Motion::Linear | Motion::Arc { .. }))
        .map(|m| [m.end[Axis::X], m.end[Axis::Y]])
        .collect();
    let mut want = vec![[0.0, 0.0]];
    for (a, b) in [(15.0, 5.0), (20.0, 10.0)] {
        want.extend([[a, 0.0], [a, b], [-a, b], [-a, -b], [a, -b], [a, 0.0]]);
    }
    want.extend([
        [25.0, 0.0],
        [25.0, 12.0],
        [22.0, 15.0],
        [-22.0, 15.0],
        [-25.0, 12.0],
        [-25.0, -12.0],
        [-22.0, -15.0],
        [22.0, -15.0],
        [25.0, -12.0],
        [25.0, 0.0],
        [0.0, 0.0],
    ]);
    assert_eq!(ends.len(), want.len(), "{ends:?}");
    for (e, w) in ends.iter().zip(&want) {
        assert!(close(e[0], w[0]) && close(e[1], w[1]), "{ends:?}");
    }
    // The four corner arcs: radius 3 about (±22, ±12), counter-clockwise, at the depth.
    let a = arcs(&m);
    assert_eq!(a.len(), 4);
    for (k, c) in [[22.0, 12.0], [-22.0, 12.0], [-22.0, -12.0], [22.0, -12.0]]
        .iter()
        .enumerate()
    {
        let (ccw, centre, r, z, _) = a[k];
        assert!(
            ccw && close(centre[0], c[0]) && close(centre[1], c[1]),
            "{a:?}"
        );
        assert!(close(r, 3.0) && close(z, -4.0));
    }
}

#[test]
fn cycle_251_from_a_corner_and_turned_about_the_call_position() {
    // Called at (100, 50) as the lower left corner (Q367 = 1), turned 90°: the centre is
    // (100, 50) + rot90 (30, 20) = (80, 80); the corner arcs' centres rot90 (±22, ±12) from
    // it: X 80 ∓ 12, Y 80 ± 22.
    let m = rect(100.0, 50.0, 90.0, 1);
    let a = arcs(&m);
    assert_eq!(a.len(), 4);
    for (k, c) in [[68.0, 102.0], [68.0, 58.0], [92.0, 58.0], [92.0, 102.0]]
        .iter()
        .enumerate()
    {
        assert!(close(a[k].1[0], c[0]) && close(a[k].1[1], c[1]), "{a:?}");
    }
    let last = m.last().unwrap();
    assert!(close(last.end[Axis::X], 80.0) && close(last.end[Axis::Y], 80.0));
    // From the corner to the centre at rapid at s + Q200 = 2, before any feed move.
    let first = m.iter().position(|m| m.motion != Motion::Rapid).unwrap();
    let over = &m[first - 1];
    assert_eq!(over.motion, Motion::Rapid);
    assert!(close(over.end[Axis::X], 80.0) && close(over.end[Axis::Y], 80.0));
    assert!(close(over.end[Axis::Z], 2.0));
    assert!(close(last.end[Axis::Z], 50.0));
}

#[test]
fn cycle_247_is_refused_naming_the_preset_table_it_needs() {
    let (line, msg) =
        run("2 CYCL DEF 247 DATUM SETTING ~\n Q339=+1 ;DATUM NUMBER\n3 L X+0 Y+0 R0 FMAX")
            .unwrap_err();
    assert_eq!(line, 3);
    assert!(
        msg.contains("PRESET.PR") && msg.contains("Cycle 247"),
        "{msg}"
    );
}

#[test]
fn a_milling_cycle_under_radius_compensation_is_refused() {
    let body = POCKET
        .replace("{side}", "0")
        .replace("{floor}", "0")
        .replace("{fin}", "0")
        .replace(
            "2 L X+50 Y+40 Z+20 R0 FMAX",
            "2 L X+0 Y+40 Z+20 R0 FMAX\n2 L X+50 Y+40 RL F100",
        );
    let (line, msg) = run(&body).unwrap_err();
    assert_eq!(line, line_of(&body, "CYCL CALL"));
    assert!(msg.contains("radius compensation RL/RR"), "{msg}");
}

#[test]
fn feed_reference_q439_per_revolution_scales_by_s_and_per_tooth_is_refused() {
    // Q439 = 3: Q206 0.1 and Q207 0.2 mm/rev at S1000 are 100 and 200 mm/min.
    let body = |k: u32| {
        POCKET
            .replace("{side}", "0")
            .replace("{floor}", "0")
            .replace("{fin}", "0")
            .replace("Q206=+150", "Q206=+0.1")
            .replace("Q207=+500", "Q207=+0.2")
            .replace("Q385=+200", &format!("Q385=+0 ~\n Q439=+{k}"))
    };
    let m = run(&body(3)).unwrap();
    let plunge = m.iter().find(|m| m.motion == Motion::Linear).unwrap();
    assert_eq!(plunge.feed, Feed::PerMinute(100.0));
    assert!(arcs(&m).iter().all(|a| a.4 == Feed::PerMinute(200.0)));
    let (line, msg) = run(&body(2)).unwrap_err();
    assert_eq!(line, line_of(&body(2), "CYCL CALL"));
    assert!(msg.contains("Q439") && msg.contains("CUT"), "{msg}");
}

#[test]
fn a_pocket_far_from_zero_ends_read_or_refused() {
    // At Z 1e17 a step of 3 mm is below the last digit: the levels are counted, so the
    // read ends (here refused or read, never a hang).
    let body = POCKET
        .replace("{side}", "0")
        .replace("{floor}", "0")
        .replace("{fin}", "0")
        .replace("Q203=+0", "Q203=+100000000000000000");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(run(&body).is_ok());
    });
    assert!(rx.recv_timeout(std::time::Duration::from_secs(20)).is_ok());
}
