//! Cutter radius compensation in the XY plane (G41/G42, G41.1/G42.1, G40), as LinuxCNC 2.9
//! does it: the tool centre runs at distance r from the programmed path, on its left (G41)
//! or right (G42).
//!
//! Each programmed element (line or arc) is held until the next one arrives, because its
//! compensated end depends on the corner. With `n(t)` the unit normal of tangent t toward
//! the tool side (left `(-t_y, t_x)` for G41, right `(t_y, -t_x)` for G42), at a corner c
//! between an element ending with tangent t₁ and one starting with t₂:
//!
//! - **convex** (the path turns away from the tool side by more than 0.05 rad, LinuxCNC's
//!   `TOLERANCE_CONCAVE_CORNER`): the first ends at `P₁ = c + r n(t₁)`, an arc about c
//!   (clockwise for G41, counter-clockwise for G42) goes to `P₂ = c + r n(t₂)`, where the
//!   second starts;
//! - otherwise (**concave** or nearly straight) both elements meet at the intersection of
//!   their offset paths (offset line `P + s t`, offset circle of radius `|P - centre|` about
//!   the arc's centre), the intersection nearest the midpoint of P₁ and P₂; where P₁ and
//!   P₂ coincide within 1e-4 mm (a tangent join) they meet at P₁.
//!
//! The entry move (the first after G41/G42) starts at the uncompensated position; the last
//! element before G40 ends at `c + r n(t₁)`, and the exit move goes from there to the
//! programmed point. Arcs keep their centre; their radius grows or shrinks by r. Moves that
//! do not change X or Y (a plunge, a dwell) wait with the element before them and take its
//! compensated end as their X Y.

use crate::canon::{Motion, Move};
use crate::Axis;

/// LinuxCNC's `TOLERANCE_CONCAVE_CORNER`, rad.
pub const CONVEX_ANGLE_RAD: f64 = 0.05;
/// Tangent joins involving an arc: P₁ and P₂ may differ by this much, mm.
pub const TANGENT_JOIN_MM: f64 = 1e-4;

/// One held element, in machine coordinates.
#[derive(Clone, Debug)]
pub struct Held {
    /// The move as programmed (its start already compensated).
    pub mv: Move,
    /// Programmed end X Y.
    pub end: [f64; 2],
    /// Unit tangent at the programmed end.
    pub tangent: [f64; 2],
    /// The element is a line (`None`) or an arc about this centre, X Y mm.
    pub center: Option<[f64; 2]>,
    /// Tool on the left (G41) and its radius, mm, when the element was programmed.
    pub left: bool,
    pub radius: f64,
    /// Z-only moves and dwells that follow it.
    pub after: Vec<Move>,
}

/// Unit tangent of a programmed XY element at its start (`at_end = false`) or end.
pub fn tangent(motion: &Motion, start: [f64; 2], end: [f64; 2], at_end: bool) -> [f64; 2] {
    match motion {
        Motion::Arc {
            clockwise,
            center_mm,
            ..
        } => {
            let p = if at_end { end } else { start };
            let (dx, dy) = (p[0] - center_mm[0], p[1] - center_mm[1]);
            let len = dx.hypot(dy);
            if *clockwise {
                [dy / len, -dx / len]
            } else {
                [-dy / len, dx / len]
            }
        }
        _ => {
            let (dx, dy) = (end[0] - start[0], end[1] - start[1]);
            let len = dx.hypot(dy);
            [dx / len, dy / len]
        }
    }
}

/// The unit normal toward the tool side.
pub fn normal(left: bool, t: [f64; 2]) -> [f64; 2] {
    if left {
        [-t[1], t[0]]
    } else {
        [t[1], -t[0]]
    }
}

/// How a held element joins the next one.
pub enum Join {
    /// End the held element at `end`; the next starts there.
    Meet { end: [f64; 2] },
    /// End the held element at `p1`, then an arc about `corner` to `p2`.
    Arc {
        p1: [f64; 2],
        p2: [f64; 2],
        corner: [f64; 2],
    },
}

/// The join at corner `c` between an element ending with tangent `t1` (`center1`: `None`
/// for a line, the centre of an arc) and one starting with `t2`.
pub fn join(
    left: bool,
    r: f64,
    c: [f64; 2],
    t1: [f64; 2],
    center1: Option<[f64; 2]>,
    t2: [f64; 2],
    center2: Option<[f64; 2]>,
) -> Result<Join, &'static str> {
    let n1 = normal(left, t1);
    let n2 = normal(left, t2);
    let p1 = [c[0] + r * n1[0], c[1] + r * n1[1]];
    let p2 = [c[0] + r * n2[0], c[1] + r * n2[1]];
    let cross = t1[0] * t2[1] - t1[1] * t2[0];
    let turn = cross.atan2(t1[0] * t2[0] + t1[1] * t2[1]);
    let convex = if left {
        turn < -CONVEX_ANGLE_RAD
    } else {
        turn > CONVEX_ANGLE_RAD
    };
    if turn.abs() > std::f64::consts::PI - 1e-9 {
        return Err("the path reverses under cutter radius compensation: expected a corner of less than 180 deg");
    }
    if convex {
        return Ok(Join::Arc { p1, p2, corner: c });
    }
    if (p1[0] - p2[0]).hypot(p1[1] - p2[1]) <= TANGENT_JOIN_MM {
        return Ok(Join::Meet { end: p1 });
    }
    if center1.is_some() || center2.is_some() {
        let near = [(p1[0] + p2[0]) / 2.0, (p1[1] + p2[1]) / 2.0];
        let points = match (center1, center2) {
            (Some(a), Some(b)) => circle_circle(a, dist(p1, a), b, dist(p2, b)),
            (Some(a), None) => line_circle(p2, t2, a, dist(p1, a)),
            (None, Some(b)) => line_circle(p1, t1, b, dist(p2, b)),
            (None, None) => unreachable!("one is an arc"),
        };
        let best = points
            .into_iter()
            .flatten()
            .min_by(|x, y| dist(*x, near).total_cmp(&dist(*y, near)));
        return match best {
            Some(end) => Ok(Join::Meet { end }),
            None => Err("concave corner with an arc that the offset paths cannot reach: expected a tool small enough for the corner"),
        };
    }
    // p1 + s t1 = p2 + u t2: s = cross(p2 - p1, t2) / cross(t1, t2).
    if cross.abs() < 1e-12 {
        return Ok(Join::Meet { end: p1 });
    }
    let d = [p2[0] - p1[0], p2[1] - p1[1]];
    let s = (d[0] * t2[1] - d[1] * t2[0]) / cross;
    Ok(Join::Meet {
        end: [p1[0] + s * t1[0], p1[1] + s * t1[1]],
    })
}

/// Sets the X Y of a move's end.
pub fn set_end(m: &mut Move, p: [f64; 2]) {
    m.end[Axis::X] = p[0];
    m.end[Axis::Y] = p[1];
}

/// Sets the X Y of a move's start.
pub fn set_start(m: &mut Move, p: [f64; 2]) {
    m.start[Axis::X] = p[0];
    m.start[Axis::Y] = p[1];
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Intersections of the line `p + s t` (t unit) with the circle of radius `rc` about `c`:
/// `s = -(d·t) ± sqrt((d·t)² - |d|² + rc²)`, d = p - c.
fn line_circle(p: [f64; 2], t: [f64; 2], c: [f64; 2], rc: f64) -> [Option<[f64; 2]>; 2] {
    let d = [p[0] - c[0], p[1] - c[1]];
    let b = d[0] * t[0] + d[1] * t[1];
    let disc = b * b - (d[0] * d[0] + d[1] * d[1]) + rc * rc;
    if disc < 0.0 {
        return [None, None];
    }
    let q = disc.sqrt();
    [-b - q, -b + q].map(|s| Some([p[0] + s * t[0], p[1] + s * t[1]]))
}

/// Intersections of two circles: along the centre line at `a = (d² + r1² - r2²) / 2d` from
/// c1, then `±sqrt(r1² - a²)` across it.
fn circle_circle(c1: [f64; 2], r1: f64, c2: [f64; 2], r2: f64) -> [Option<[f64; 2]>; 2] {
    let d = dist(c1, c2);
    if d < 1e-12 {
        return [None, None];
    }
    let a = (d * d + r1 * r1 - r2 * r2) / (2.0 * d);
    let h2 = r1 * r1 - a * a;
    if h2 < 0.0 {
        return [None, None];
    }
    let h = h2.sqrt();
    let u = [(c2[0] - c1[0]) / d, (c2[1] - c1[1]) / d];
    let m = [c1[0] + a * u[0], c1[1] + a * u[1]];
    [h, -h].map(|k| Some([m[0] - k * u[1], m[1] + k * u[0]]))
}
