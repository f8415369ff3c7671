//! Small Klartext programs as the CAM posts write them (Fusion, hyperMILL, NX, Mastercam
//! TNC posts, and hand-written ones): `BLK FORM`, `TOOL CALL … DL DR`, M91, FMAX, M3/M8,
//! `M140 MB MAX`, `CYCL DEF 32`, `LBL`/`CALL LBL REP`, FN 9-12 jumps, `PLANE SPATIAL …
//! TURN`/`MOVE`/`PLANE RESET STAY`, `FUNCTION TCPM`/M128, cycles 200, 208, 252 with
//! `CYCL CALL`, `M99` and `CYCL CALL PAT`, 251, `STOP`, `;` comments, `*` and `/` lines (the
//! programs in tests/data/klartext_posts/). Each is read with the moves worked out by hand
//! in its test, or refused by name at its line.

use ngc::{Axis, Feed, Motion, Move, Options, RotaryTable};

use super::klartext_setup::{klartext_options, near, read_named, xyz};

fn table() -> Options {
    Options {
        table: Some(RotaryTable {
            tilt: Axis::A,
            pivot_mm: [0.0; 3],
        }),
        ..klartext_options()
    }
}

fn read(text: &str, o: &Options) -> Result<Vec<Move>, (usize, String)> {
    read_named("post.h", text, o)
}

/// The end points of the feed moves (lines and arcs).
fn feed_ends(m: &[Move]) -> Vec<[f64; 3]> {
    m.iter()
        .filter(|m| matches!(m.motion, Motion::Linear | Motion::Arc { .. }))
        .map(xyz)
        .collect()
}

fn same(got: &[[f64; 3]], want: &[[f64; 3]]) -> bool {
    got.len() == want.len() && got.iter().zip(want).all(|(g, w)| near(*g, *w))
}

/// (counter-clockwise, centre X Y, radius at the start, Z at the end) of each arc.
fn arcs(m: &[Move]) -> Vec<(bool, [f64; 2], f64, f64)> {
    m.iter()
        .filter_map(|m| match m.motion {
            Motion::Arc {
                clockwise,
                center_mm,
                ..
            } => Some((
                !clockwise,
                [center_mm[0], center_mm[1]],
                (m.start[Axis::X] - center_mm[0]).hypot(m.start[Axis::Y] - center_mm[1]),
                m.end[Axis::Z],
            )),
            _ => None,
        })
        .collect()
}

macro_rules! post {
    ($name:literal) => {
        include_str!(concat!("../data/klartext_posts/", $name, ".h"))
    };
}

#[test]
fn fusion_contour_with_m91_tolerance_cycle_and_comments() {
    let m = read(post!("01_fusion_contour"), &klartext_options()).unwrap();
    // Plunge at F300 to Z-2, then the square ±30 at F1000.
    let want = [
        [-30.0, -30.0, -2.0],
        [30.0, -30.0, -2.0],
        [30.0, 30.0, -2.0],
        [-30.0, 30.0, -2.0],
        [-30.0, -30.0, -2.0],
    ];
    assert!(same(&feed_ends(&m), &want), "{:?}", feed_ends(&m));
    let feeds: Vec<Feed> = m
        .iter()
        .filter(|m| m.motion == Motion::Linear)
        .map(|m| m.feed)
        .collect();
    assert_eq!(feeds[0], Feed::PerMinute(300.0));
    assert!(feeds[1..].iter().all(|f| *f == Feed::PerMinute(1000.0)));
}

#[test]
fn fusion_helix_ramp_about_cc_with_ipa_and_iz() {
    let m = read(post!("02_fusion_helix_ramp"), &klartext_options()).unwrap();
    // Three turns of radius 10 about (0, 0), 1 mm down each from Z 1, one flat turn.
    let a = arcs(&m);
    assert_eq!(a.len(), 4, "{a:?}");
    for (k, z) in [0.0, -1.0, -2.0, -2.0].into_iter().enumerate() {
        let (ccw, c, r, end) = a[k];
        assert!(ccw && near([c[0], c[1], r], [0.0, 0.0, 10.0]) && (end - z).abs() < 1e-9);
    }
    assert!(near(*feed_ends(&m).last().unwrap(), [0.0, 0.0, -2.0]));
}

#[test]
fn mastercam_section_repeat_runs_the_section_three_times() {
    let m = read(post!("03_mastercam_section_repeat"), &klartext_options()).unwrap();
    // REP 2: the section LBL 1 … CALL LBL 1 once as read and twice more: Z -2, -4, -6,
    // each a 20 × 20 square from (0, 0).
    let f = feed_ends(&m);
    assert_eq!(f.len(), 16, "{f:?}");
    for (pass, z) in [-2.0, -4.0, -6.0].into_iter().enumerate() {
        let sq = &f[1 + 5 * pass..6 + 5 * pass];
        let want = [
            [0.0, 0.0, z],
            [20.0, 0.0, z],
            [20.0, 20.0, z],
            [0.0, 20.0, z],
            [0.0, 0.0, z],
        ];
        assert!(same(sq, &want), "pass {pass}: {sq:?}");
    }
}

#[test]
fn nx_subprogram_called_twice_and_the_program_ends_at_m30() {
    let m = read(post!("04_nx_subprogram"), &klartext_options()).unwrap();
    // LBL 10: IZ-8 from Z 5 to -3, back up; at (10, 10) and (40, 10). M30 ends the program
    // before the subprogram's text.
    assert!(same(
        &feed_ends(&m),
        &[[10.0, 10.0, -3.0], [40.0, 10.0, -3.0]]
    ));
    assert!(near(xyz(m.last().unwrap()), [40.0, 10.0, 100.0]));
}

#[test]
fn hand_written_fn_9_to_12_jumps() {
    let m = read(post!("05_hand_fn_jumps"), &klartext_options()).unwrap();
    // FN 12 loops while Q1 < 30: X 10, 20, 30; FN 9 (Q1 = 30) jumps over X 999; FN 10
    // (Q1 ≠ 30) does not jump: Y 10; FN 11 (Q1 > 0) jumps over Y 999.
    let want = [
        [10.0, 0.0, 0.0],
        [20.0, 0.0, 0.0],
        [30.0, 0.0, 0.0],
        [30.0, 10.0, 0.0],
    ];
    assert!(same(&feed_ends(&m), &want), "{:?}", feed_ends(&m));
}

#[test]
fn hypermill_plane_spatial_turn_with_dl_then_reset_stay_and_move() {
    let text = post!("06_hypermill_plane_spatial");
    let m = read(text, &table()).unwrap();
    let line = |n: usize| m.iter().filter(|m| m.line == n).collect::<Vec<_>>();
    // PLANE SPATIAL SPA+30 … TURN: the table tilts A ±30° for the tilted moves (lines 13,
    // 14: file lines = block number + 1), and PLANE RESET STAY leaves it there.
    for n in [14, 15, 16] {
        assert!(!line(n).is_empty(), "no move at line {n}");
        for mv in line(n) {
            assert!((mv.end[Axis::A].abs() - 30.0).abs() < 1e-9, "{mv:?}");
        }
    }
    // DL+0.05: the same points 0.05 further along the tilted tool axis than with DL 0;
    // with the table turned to the plane, that axis is the machine's Z.
    let plain = read(&text.replace("DL+0.05", "DL+0"), &table()).unwrap();
    let at = |m: &[Move], n: usize| xyz(m.iter().rfind(|m| m.line == n).unwrap());
    for n in [14, 15] {
        let (a, b) = (at(&m, n), at(&plain, n));
        let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        assert!(near(d, [0.0, 0.0, 0.05]), "line {n}: {d:?}");
    }
    // PLANE SPATIAL 0 0 0 MOVE: the table back to A 0.
    assert!(m.last().unwrap().end[Axis::A].abs() < 1e-9);
}

#[test]
fn nx_function_tcpm_and_m128_move_with_the_tool_centre_point() {
    let m = read(post!("07_nx_tcpm"), &table()).unwrap();
    let by_line = |n: usize| m.iter().rfind(|m| m.line == n).unwrap();
    for (n, a) in [(5, 10.0), (6, 20.0), (9, 0.0)] {
        let mv = by_line(n);
        assert!(mv.tcp, "line {n} without TCP");
        assert!((mv.end[Axis::A] - a).abs() < 1e-9);
    }
    assert!(!by_line(11).tcp);
}

#[test]
fn fusion_drilling_cycle_200_called_by_m99_at_two_holes() {
    let m = read(post!("08_fusion_drill_200"), &klartext_options()).unwrap();
    // Per hole from Z 20: FMAX to 2, pecks of 4 to -12 with FMAX back to 2 and down to 2
    // above the depth reached, FMAX to 2, then to the 2nd set-up clearance 20.
    let want = [
        (true, 2.0),
        (false, -4.0),
        (true, 2.0),
        (true, -2.0),
        (false, -8.0),
        (true, 2.0),
        (true, -6.0),
        (false, -12.0),
        (true, 2.0),
        (true, 20.0),
    ];
    for (x, line) in [(10.0, 15), (30.0, 16)] {
        let z: Vec<(bool, f64)> = m
            .iter()
            .filter(|m| {
                m.line == line && m.end[Axis::X] == x && m.motion != Motion::Dwell { seconds: 0.0 }
            })
            .map(|m| (m.motion == Motion::Rapid, m.end[Axis::Z]))
            .collect();
        assert_eq!(z[z.len() - 10..], want, "hole at X {x}");
    }
}

#[test]
fn tool_call_dl_and_dr_shift_the_depth_and_the_compensated_path() {
    let m = read(post!("09_comp_dl_dr"), &klartext_options()).unwrap();
    // DL-0.2: every Z 0.2 lower (a shorter tool); DR-0.5: radius 5 − 0.5 = 4.5. Along
    // Y 0 towards +X under RL the tool runs at Y +4.5; the inside corner at (40, 0) turning
    // to +Y puts it at (40 − 4.5, 4.5).
    let f = feed_ends(&m);
    assert!(near(f[0], [-20.0, -20.0, -3.2]), "{f:?}");
    assert!(f.iter().any(|p| near(*p, [35.5, 4.5, -3.2])), "{f:?}");
}

#[test]
fn hypermill_circular_pocket_252_ends_on_the_wall_at_the_depth() {
    let m = read(post!("10_hypermill_pocket_252"), &klartext_options()).unwrap();
    // Ø40, tool Ø10: wall circle radius 15; stepover 5: circles 5, 10, 15 at Z -4 and -8,
    // counter-clockwise (climb) about (50, 40).
    let a = arcs(&m);
    let got: Vec<(f64, f64)> = a.iter().map(|a| (a.2, a.3)).collect();
    let want = [
        (5.0, -4.0),
        (10.0, -4.0),
        (15.0, -4.0),
        (5.0, -8.0),
        (10.0, -8.0),
        (15.0, -8.0),
    ];
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(want) {
        assert!(
            (g.0 - w.0).abs() < 1e-9 && (g.1 - w.1).abs() < 1e-9,
            "{got:?}"
        );
    }
    assert!(a.iter().all(|a| a.0 && a.1 == [50.0, 40.0]));
}

#[test]
fn bore_milling_208_at_each_point_of_a_pattern() {
    let m = read(post!("11_bore_208_pattern"), &klartext_options()).unwrap();
    // Ø16 bore, tool Ø10: helix radius 3; from 2 to -10 at 3 per turn: four turns, the
    // fourth ending at -10, then a full circle there; at (20, 20) and (60, 20).
    let a = arcs(&m);
    assert_eq!(a.len(), 12, "{a:?}");
    for (hole, cx) in [(0, 20.0), (1, 60.0)] {
        let h = &a[6 * hole..6 * hole + 6];
        let mut z = 2.0;
        for turn in &h[1..5] {
            assert!(turn.0 && turn.1 == [cx, 20.0] && (turn.2 - 3.0).abs() < 1e-9);
            assert!((z - turn.3 - 3.0).abs() < 1e-9, "{h:?}");
            z = turn.3;
        }
        assert!((z + 10.0).abs() < 1e-9 && (h[5].3 + 10.0).abs() < 1e-9);
    }
}

#[test]
fn m92_is_refused_naming_the_machine_builders_datum() {
    let (line, msg) = read(post!("12_hypermill_m92"), &klartext_options()).unwrap_err();
    assert_eq!(line, 3);
    assert!(
        msg.contains("M92") && msg.contains("machine tool builder"),
        "{msg}"
    );
}

#[test]
fn mastercam_skip_stop_rnd_and_chf() {
    let m = read(post!("13_mastercam_skip_stop"), &klartext_options()).unwrap();
    // The `/` block is skipped (no move to 500, 500). RND R5 at (25, 0): the line stops
    // 5 tan 45° = 5 short, the arc about (20, 5) to (25, 5); CHF 3 at (25, 25): (25, 22)
    // to (22, 25), then to (0, 25).
    assert!(m.iter().all(|m| m.end[Axis::X] < 500.0));
    let want = [
        [0.0, 0.0, -1.0],
        [20.0, 0.0, -1.0],
        [25.0, 5.0, -1.0],
        [25.0, 22.0, -1.0],
        [22.0, 25.0, -1.0],
        [0.0, 25.0, -1.0],
    ];
    assert!(same(&feed_ends(&m), &want), "{:?}", feed_ends(&m));
    let a = arcs(&m);
    assert!(a.len() == 1 && a[0].0 && near([a[0].1[0], a[0].1[1], a[0].2], [20.0, 5.0, 5.0]));
}

#[test]
fn a_coordinate_written_nan_is_refused_as_a_fault_of_the_post() {
    let text =
        "0 BEGIN PGM P MM\n1 TOOL CALL 1 Z S1000\n2 L Xnan Ynan Znan FMAX M9\n3 END PGM P MM\n";
    let (line, msg) = read(text, &klartext_options()).unwrap_err();
    assert_eq!(line, 3);
    assert!(
        msg.contains("`Xnan`") && msg.contains("fault of the post"),
        "{msg}"
    );
}

#[test]
fn mastercam_rectangular_pocket_251_up_cut_is_clockwise() {
    let m = read(post!("14_mastercam_pocket_251"), &klartext_options()).unwrap();
    // 40 × 30 about (50, 50), corner radius 5 = the tool's radius: a sharp wall path of
    // half sides 15 × 10; stepover 5: the rectangle 10 × 5 first; Q351 = -1: clockwise,
    // so from the middle of the +X side down first. One level at -3 (roughing only).
    let mut want = vec![[50.0, 50.0, -3.0]];
    for (a, b) in [(10.0, 5.0), (15.0, 10.0)] {
        for (u, v) in [(a, 0.0), (a, -b), (-a, -b), (-a, b), (a, b), (a, 0.0)] {
            want.push([50.0 + u, 50.0 + v, -3.0]);
        }
    }
    want.push([50.0, 50.0, -3.0]);
    assert!(same(&feed_ends(&m), &want), "{:?}", feed_ends(&m));
    assert!(arcs(&m).is_empty());
}
