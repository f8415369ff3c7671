//! Fanuc and Haas optional chamfer `,C` and corner rounding `,R` between two G01 lines in
//! the active plane (corner rounding next to an arc: crate `corner_arc`) (Fanuc 0i-MF operator's manual, "Optional chamfering and corner R";
//! Haas mill operator's manual, "Corner rounding and chamfering").
//!
//! ```text
//!            B                     u1 = (P − A)/|P − A|, u2 = (B − P)/|B − P|
//!            │                     θ  = the turn from u1 to u2 (0 ≤ θ < 180°)
//!            T2                    ,C c:  t = c            (c measured from the virtual corner P)
//!           ╱│                     ,R r:  t = r · tan(θ/2) (the arc is tangent to both lines)
//!  A ──── T1 P                     T1 = P − t·u1, T2 = P + t·u2
//! ```
//!
//! The first line is cut short at T1, a chamfer line (`,C`) or an arc of radius r (`,R`,
//! centre T1 + r·n with n the unit normal of u1 towards the turn, G03 for a left turn) goes
//! to T2, and the second line starts at T2. The computation is on the canonical moves
//! (machine coordinates, mm): work offsets, G68 rotation and mirror images keep lengths and
//! angles, so the tangent points are where the control puts them. The inserted move takes
//! the first line's feed and line number. Refused, naming the rule: a next move that is
//! not a G01 line or G02/G03 arc in the same plane (a rapid, a block without a move), a
//! move off the plane (a helix), a chamfer next to an arc, a chamfer or radius longer than
//! either line, a reversal.

use crate::axis::{Axis, Plane};
use crate::canon::{Feed, Motion, Move};

/// Below this, mm, a length or a cross product is zero.
const EPS_MM: f64 = 1e-9;

/// A `,R` / `,C` line held until the next block's move is known.
#[derive(Clone, Debug)]
pub(crate) struct Pending {
    /// True for `,R`, false for `,C`.
    pub round: bool,
    /// The radius or chamfer length, mm.
    pub size_mm: f64,
    pub plane: Plane,
    /// The line with the `,R` / `,C`, as the interpreter emitted it.
    pub held: Move,
    /// The word as written (for messages), e.g. `,R2.`.
    pub word: String,
    /// Where the word is: its line, its span there and the line's text (for an error
    /// raised later, at the end of the program).
    pub at: crate::source::Cursor,
    pub span: std::ops::Range<usize>,
    pub text: String,
}

impl Pending {
    /// corner rounding `,R2.` (line 12)
    pub fn name(&self) -> String {
        let what = if self.round {
            "corner rounding"
        } else {
            "chamfer"
        };
        format!("{what} `{}` (line {})", self.word, self.held.line)
    }
}

/// The first line shortened, the chamfer or arc, and the second line from the tangent
/// point; `None` in the middle when the lines are collinear (nothing to cut).
pub(crate) fn join(p: &Pending, next: &Move) -> Result<(Move, Option<Move>, Move), String> {
    let name = p.name();
    let kind = match next.motion {
        Motion::Rapid => Some("a rapid (G00)"),
        Motion::Dwell { .. } => Some("a dwell"),
        _ => None,
    };
    if let Some(kind) = kind {
        return Err(format!(
            "{name}: the next move is {kind}; expected a G01 line or a G02/G03 arc in the same plane (Fanuc: the block after `,C`/`,R` must be a G01 or G02/G03 move)"
        ));
    }
    let (u, v, _) = p.plane.axes();
    let first = &p.held;
    for (m, which) in [(first, "this line"), (next, "the next line")] {
        if let Some(a) = Axis::ALL
            .into_iter()
            .find(|a| *a != u && *a != v && (m.end[*a] - m.start[*a]).abs() > EPS_MM)
        {
            return Err(format!(
                "{name}: {which} moves {a} as well, off the {} plane; expected both lines in the plane (Fanuc: chamfer and corner R only between moves of the selected plane)",
                p.plane.g_code()
            ));
        }
    }
    if let Feed::InverseTime(_) = first.feed {
        return Err(format!(
            "{name} under inverse-time feed (G93): not read; expected G94 or G95"
        ));
    }
    let arcs = [first, next]
        .iter()
        .any(|m| matches!(m.motion, Motion::Arc { .. }));
    if arcs && !p.round {
        return Err(format!(
            "{name} next to an arc: not read (the manuals do not say whether the chamfer length is measured along the arc or its chord); expected the chamfer between two G01 lines, or a rounding (Fanuc: `,C` only between two G01 lines; `,R` next to an arc)"
        ));
    }
    if arcs {
        return crate::corner_arc::round(first, next, p.plane, p.size_mm, &name);
    }
    let d1 = [first.end[u] - first.start[u], first.end[v] - first.start[v]];
    let d2 = [next.end[u] - next.start[u], next.end[v] - next.start[v]];
    let (l1, l2) = (d1[0].hypot(d1[1]), d2[0].hypot(d2[1]));
    if l1 < EPS_MM || l2 < EPS_MM {
        return Err(format!(
            "{name}: a line of zero length in the plane; expected two lines that meet at a corner"
        ));
    }
    let u1 = [d1[0] / l1, d1[1] / l1];
    let u2 = [d2[0] / l2, d2[1] / l2];
    let cross = u1[0] * u2[1] - u1[1] * u2[0];
    let dot = u1[0] * u2[0] + u1[1] * u2[1];
    let theta = cross.abs().atan2(dot);
    if cross.abs() < EPS_MM && dot > 0.0 {
        // Collinear: no corner to cut.
        return Ok((first.clone(), None, next.clone()));
    }
    if theta > std::f64::consts::PI - 1e-9 {
        return Err(format!(
            "{name}: the next line goes straight back; expected a corner of less than 180°"
        ));
    }
    let t = if p.round {
        p.size_mm * (theta / 2.0).tan()
    } else {
        p.size_mm
    };
    if t > l1 + EPS_MM || t > l2 + EPS_MM {
        return Err(format!(
            "{name} does not fit: it needs {t:.4} mm of each line from the corner, and the lines are {l1:.4} and {l2:.4} mm long (Fanuc: alarm, chamfer or corner R too large)"
        ));
    }
    let corner = first.end;
    let mut t1 = corner;
    t1[u] -= t * u1[0];
    t1[v] -= t * u1[1];
    let mut t2 = corner;
    t2[u] += t * u2[0];
    t2[v] += t * u2[1];
    let mut a = first.clone();
    a.end = t1;
    let mut b = first.clone();
    b.start = t1;
    b.end = t2;
    if p.round {
        // The normal of u1 towards the turn: left (+90°) for a counter-clockwise turn.
        let s = cross.signum();
        let n = [-u1[1] * s, u1[0] * s];
        let mut center_mm = [t1[Axis::X], t1[Axis::Y], t1[Axis::Z]];
        center_mm[u.index()] = t1[u] + p.size_mm * n[0];
        center_mm[v.index()] = t1[v] + p.size_mm * n[1];
        b.motion = Motion::Arc {
            clockwise: cross < 0.0,
            plane: p.plane,
            center_mm,
        };
    }
    let mut c = next.clone();
    c.start = t2;
    Ok((a, Some(b), c))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::AxisVec;

    fn line(from: [f64; 2], to: [f64; 2]) -> Move {
        Move {
            line: 1,
            motion: Motion::Linear,
            start: AxisVec::xyzabc([from[0], from[1], -1.0, 0.0, 0.0, 0.0]),
            end: AxisVec::xyzabc([to[0], to[1], -1.0, 0.0, 0.0, 0.0]),
            feed: Feed::PerMinute(400.0),
            ..Move::default()
        }
    }

    fn pending(round: bool, size_mm: f64, held: Move) -> Pending {
        Pending {
            round,
            size_mm,
            plane: Plane::XY,
            held,
            word: ",R".into(),
            at: crate::source::Cursor {
                file: 0,
                offset: 0,
                line: 1,
            },
            span: 0..2,
            text: String::new(),
        }
    }

    fn xy(p: AxisVec) -> [f64; 2] {
        [p[Axis::X], p[Axis::Y]]
    }

    fn close(a: [f64; 2], b: [f64; 2]) {
        assert!(
            (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12,
            "{a:?} != {b:?}"
        );
    }

    #[test]
    fn a_right_angle_rounded_r2_touches_2_mm_from_the_corner_about_the_offset_corner() {
        // (0,0) → (10,0) → (10,10), a left turn: tangent points (8,0) and (10,2), centre
        // (8,2), counter-clockwise.
        let p = pending(true, 2.0, line([0.0, 0.0], [10.0, 0.0]));
        let (a, b, c) = join(&p, &line([10.0, 0.0], [10.0, 10.0])).unwrap();
        let b = b.unwrap();
        close(xy(a.end), [8.0, 0.0]);
        close(xy(b.start), [8.0, 0.0]);
        close(xy(b.end), [10.0, 2.0]);
        close(xy(c.start), [10.0, 2.0]);
        close(xy(c.end), [10.0, 10.0]);
        let Motion::Arc {
            clockwise,
            center_mm,
            ..
        } = b.motion
        else {
            panic!("not an arc: {b:?}");
        };
        assert!(!clockwise);
        close([center_mm[0], center_mm[1]], [8.0, 2.0]);
        assert_eq!(center_mm[2], -1.0);
        // A right turn: (0,0) → (10,0) → (10,-10), centre (8,-2), clockwise.
        let (_, b, _) = join(&p, &line([10.0, 0.0], [10.0, -10.0])).unwrap();
        let Motion::Arc {
            clockwise,
            center_mm,
            ..
        } = b.unwrap().motion
        else {
            panic!("not an arc");
        };
        assert!(clockwise);
        close([center_mm[0], center_mm[1]], [8.0, -2.0]);
    }

    #[test]
    fn a_60_degree_turn_touches_r_tan_30_from_the_corner() {
        // (0,0) → (10,0), then 60° left to (10 + 5, 5·√3): t = r·tan 30° = 3/√3 = √3.
        let p = pending(true, 3.0, line([0.0, 0.0], [10.0, 0.0]));
        let s3 = 3f64.sqrt();
        let (a, b, c) = join(&p, &line([10.0, 0.0], [15.0, 5.0 * s3])).unwrap();
        close(xy(a.end), [10.0 - s3, 0.0]);
        close(xy(c.start), [10.0 + s3 * 0.5, s3 * s3 * 0.5]);
        let Motion::Arc { center_mm, .. } = b.unwrap().motion else {
            panic!("not an arc");
        };
        // The centre is r above T1, and r from T2 too.
        close([center_mm[0], center_mm[1]], [10.0 - s3, 3.0]);
        let r2 = (center_mm[0] - c.start[Axis::X]).hypot(center_mm[1] - c.start[Axis::Y]);
        assert!((r2 - 3.0).abs() < 1e-12);
    }

    #[test]
    fn a_chamfer_is_measured_from_the_virtual_corner_along_each_line() {
        let p = pending(false, 5.0, line([0.0, 0.0], [40.0, 0.0]));
        let (a, b, c) = join(&p, &line([40.0, 0.0], [40.0, 40.0])).unwrap();
        let b = b.unwrap();
        assert_eq!(b.motion, Motion::Linear);
        close(xy(a.end), [35.0, 0.0]);
        close(xy(b.end), [40.0, 5.0]);
        close(xy(c.start), [40.0, 5.0]);
        assert_eq!(b.feed, Feed::PerMinute(400.0));
    }

    #[test]
    fn what_does_not_fit_or_is_not_a_line_in_the_plane_is_refused() {
        let p = pending(true, 5.0, line([0.0, 0.0], [4.0, 0.0]));
        let e = join(&p, &line([4.0, 0.0], [4.0, 10.0])).unwrap_err();
        assert!(e.contains("does not fit"), "{e}");
        let p = pending(true, 1.0, line([0.0, 0.0], [4.0, 0.0]));
        let mut rapid = line([4.0, 0.0], [4.0, 10.0]);
        rapid.motion = Motion::Rapid;
        assert!(join(&p, &rapid).unwrap_err().contains("rapid"));
        let mut down = line([4.0, 0.0], [4.0, 10.0]);
        down.end[Axis::Z] = -3.0;
        assert!(join(&p, &down).unwrap_err().contains("off the"));
        let back = line([4.0, 0.0], [0.0, 0.0]);
        assert!(join(&p, &back).unwrap_err().contains("straight back"));
    }
}
