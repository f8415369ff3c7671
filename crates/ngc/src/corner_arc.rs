//! Fanuc and Haas corner rounding `,R` where one or both of the two moves is an arc (Fanuc
//! 0i-MF operator's manual, "Optional chamfering and corner R": corner R "between linear
//! and circular interpolation, circular and linear, circular and circular"). Line to line
//! is crate `corner`; this module is the fillet when an arc is involved.
//!
//! The fillet is the circle of radius r tangent to both moves on the inside of the turn at
//! their common point P. With t1 the direction of the first move at its end and t2 that of
//! the second at its start, the turn is left when t1 × t2 > 0, and the fillet lies to the
//! left of both moves (right for a right turn). Its centre F is on both moves' offsets by r
//! toward that side:
//!
//! - a line offset by r: the parallel line at distance r;
//! - an arc of radius R about C offset by r: the circle about C of radius R − r when the
//!   side is the arc's inside (left of a G03, right of a G02), R + r otherwise.
//!
//! F is the intersection of the two offsets nearest P. The tangent points are F's foot on a
//! line, and `C + R (F − C)/|F − C|` on an arc. Each must lie on its move (within the
//! line, within the arc's sweep): otherwise the radius does not fit and is refused, as a
//! Fanuc control alarms. The first move ends at T1, the fillet (G03 for a left turn) goes
//! to T2 about F, the second move starts at T2; an arc keeps its centre.
//!
//! Not modelled, and refused: a chamfer `,C` next to an arc (the manuals do not say whether
//! c is measured along the chord or the arc), a full circle, an arc whose offset inward
//! vanishes (R ≤ r), and moves that meet tangentially (no corner to round).

use crate::axis::{Axis, Plane};
use crate::canon::{Motion, Move};

/// Below this, mm, a length or a cross product is zero.
const EPS_MM: f64 = 1e-9;

type P2 = [f64; 2];

/// One move in the plane's (u, v) coordinates.
#[derive(Clone, Copy, Debug)]
enum Element {
    Line {
        a: P2,
        b: P2,
    },
    /// `sweep` signed: positive counter-clockwise.
    Arc {
        s: P2,
        c: P2,
        r: f64,
        sweep: f64,
    },
}

fn sub(a: P2, b: P2) -> P2 {
    [a[0] - b[0], a[1] - b[1]]
}
fn add(a: P2, b: P2, k: f64) -> P2 {
    [a[0] + k * b[0], a[1] + k * b[1]]
}
fn norm(a: P2) -> f64 {
    a[0].hypot(a[1])
}
fn cross(a: P2, b: P2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}
fn dot(a: P2, b: P2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
/// `a` turned +90°.
fn left(a: P2) -> P2 {
    [-a[1], a[0]]
}

impl Element {
    fn of(m: &Move, plane: Plane, name: &str) -> Result<Element, String> {
        let (u, v, _) = plane.axes();
        let pt = |p: &crate::AxisVec| [p[u], p[v]];
        match m.motion {
            Motion::Linear => Ok(Element::Line {
                a: pt(&m.start),
                b: pt(&m.end),
            }),
            Motion::Arc {
                plane: arc_plane,
                center_mm,
                ..
            } => {
                if arc_plane != plane {
                    return Err(format!("{name}: an arc in {} while the corner is in {}; expected both moves in one plane", arc_plane.g_code(), plane.g_code()));
                }
                let sweep = m.arc_sweep_rad().unwrap_or(0.0);
                let c = [center_mm[u.index()], center_mm[v.index()]];
                let (s, e) = (pt(&m.start), pt(&m.end));
                if norm(sub(e, s)) < EPS_MM {
                    return Err(format!("{name}: a full circle beside the corner; expected an arc that ends elsewhere than it starts"));
                }
                Ok(Element::Arc {
                    s,
                    c,
                    r: norm(sub(s, c)),
                    sweep,
                })
            }
            _ => Err(format!("{name}: expected a G01 line or a G02/G03 arc")),
        }
    }

    /// The unit direction of travel at point `q` of the move.
    fn direction(&self, q: P2) -> P2 {
        match *self {
            Element::Line { a, b } => {
                let d = sub(b, a);
                let l = norm(d);
                [d[0] / l, d[1] / l]
            }
            Element::Arc { c, r, sweep, .. } => {
                let k = if sweep > 0.0 { 1.0 } else { -1.0 } / r;
                let l = left(sub(q, c));
                [k * l[0], k * l[1]]
            }
        }
    }

    /// Whether point `q` (on the move's line or circle) lies within the move.
    fn holds(&self, q: P2) -> bool {
        match *self {
            Element::Line { a, b } => {
                let d = sub(b, a);
                let l = norm(d);
                let t = dot(sub(q, a), d) / l;
                t >= -EPS_MM && t <= l + EPS_MM
            }
            Element::Arc { s, c, sweep, r, .. } => {
                let tau = std::f64::consts::TAU;
                let a0 = (s[1] - c[1]).atan2(s[0] - c[0]);
                let aq = (q[1] - c[1]).atan2(q[0] - c[0]);
                let along = if sweep > 0.0 { aq - a0 } else { a0 - aq }.rem_euclid(tau);
                let along = if along > tau - EPS_MM / r { 0.0 } else { along };
                along <= sweep.abs() + EPS_MM / r
            }
        }
    }

    /// The tangent point of a circle about `f` tangent to this move.
    fn touch(&self, f: P2) -> P2 {
        match *self {
            Element::Line { a, b } => {
                let d = sub(b, a);
                let t = dot(sub(f, a), d) / dot(d, d);
                add(a, d, t)
            }
            Element::Arc { c, r, .. } => {
                let d = sub(f, c);
                add(c, d, r / norm(d))
            }
        }
    }
}

/// The points at distance `r` to `side` (+1 left, −1 right) of a move: a line (point and
/// direction) or a circle (centre and radius).
enum Offset {
    Line(P2, P2),
    Circle(P2, f64),
}

fn offset(e: &Element, side: f64, r: f64) -> Option<Offset> {
    match *e {
        Element::Line { a, b } => {
            let d = sub(b, a);
            let l = norm(d);
            let u = [d[0] / l, d[1] / l];
            Some(Offset::Line(add(a, left(u), side * r), u))
        }
        Element::Arc {
            c, r: big, sweep, ..
        } => {
            // Left of a counter-clockwise arc is its inside.
            let inside = (sweep > 0.0) == (side > 0.0);
            let rho = if inside { big - r } else { big + r };
            (rho > EPS_MM).then_some(Offset::Circle(c, rho))
        }
    }
}

/// The intersections of two offsets (a line and a line have been crate `corner`'s).
fn meet(a: &Offset, b: &Offset) -> Vec<P2> {
    match (a, b) {
        (Offset::Line(p, u), Offset::Circle(c, rho))
        | (Offset::Circle(c, rho), Offset::Line(p, u)) => {
            // |p + t u − c|² = ρ²: t² + 2 t u·(p − c) + |p − c|² − ρ² = 0.
            let w = sub(*p, *c);
            let half_b = dot(*u, w);
            let disc = half_b * half_b - (dot(w, w) - rho * rho);
            if disc < 0.0 {
                return Vec::new();
            }
            let root = disc.sqrt();
            vec![add(*p, *u, -half_b - root), add(*p, *u, -half_b + root)]
        }
        (Offset::Circle(c1, r1), Offset::Circle(c2, r2)) => {
            let d = sub(*c2, *c1);
            let dist = norm(d);
            if dist < EPS_MM {
                return Vec::new();
            }
            // Along the centre line x = (d² + r1² − r2²) / 2d from c1, across ±h.
            let x = (dist * dist + r1 * r1 - r2 * r2) / (2.0 * dist);
            let h2 = r1 * r1 - x * x;
            if h2 < 0.0 {
                return Vec::new();
            }
            let ux = [d[0] / dist, d[1] / dist];
            let foot = add(*c1, ux, x);
            let h = h2.sqrt();
            vec![add(foot, left(ux), h), add(foot, left(ux), -h)]
        }
        (Offset::Line(..), Offset::Line(..)) => Vec::new(),
    }
}

/// The first move shortened, the fillet arc and the second move from its tangent point,
/// for corner rounding of radius `r` mm in `plane` where one move or both is an arc;
/// `name` names the word for messages.
pub(crate) fn round(
    first: &Move,
    next: &Move,
    plane: Plane,
    r: f64,
    name: &str,
) -> Result<(Move, Option<Move>, Move), String> {
    let (u, v, _) = plane.axes();
    let e1 = Element::of(first, plane, name)?;
    let e2 = Element::of(next, plane, name)?;
    let corner = [first.end[u], first.end[v]];
    let (t1, t2) = (e1.direction(corner), e2.direction(corner));
    let turn = cross(t1, t2);
    if turn.abs() < 1e-12 {
        if dot(t1, t2) > 0.0 {
            // The moves meet tangentially: no corner to round.
            return Ok((first.clone(), None, next.clone()));
        }
        return Err(format!(
            "{name}: the next move goes straight back; expected a corner of less than 180°"
        ));
    }
    let side = turn.signum();
    let too_big = || {
        format!("{name} does not fit: no circle of radius {r:.4} mm touches both moves inside the corner (Fanuc: alarm, chamfer or corner R too large)")
    };
    let (Some(o1), Some(o2)) = (offset(&e1, side, r), offset(&e2, side, r)) else {
        return Err(too_big());
    };
    let f = meet(&o1, &o2)
        .into_iter()
        .min_by(|a, b| norm(sub(*a, corner)).total_cmp(&norm(sub(*b, corner))))
        .ok_or_else(too_big)?;
    let (p1, p2) = (e1.touch(f), e2.touch(f));
    if !e1.holds(p1) || !e2.holds(p2) {
        return Err(too_big());
    }
    let at = |p: P2| {
        let mut q = first.end;
        q[u] = p[0];
        q[v] = p[1];
        q
    };
    let mut a = first.clone();
    a.end = at(p1);
    let mut fillet = first.clone();
    fillet.start = at(p1);
    fillet.end = at(p2);
    let mut center_mm = [first.end[Axis::X], first.end[Axis::Y], first.end[Axis::Z]];
    center_mm[u.index()] = f[0];
    center_mm[v.index()] = f[1];
    fillet.motion = Motion::Arc {
        clockwise: side < 0.0,
        plane,
        center_mm,
    };
    let mut c = next.clone();
    c.start = at(p2);
    Ok((a, Some(fillet), c))
}
