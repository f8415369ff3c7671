//! Cutter radius compensation: G41 (tool left of the path), G42 (right), G41.1/G42.1 (the
//! diameter given by D) and G40, in the XY plane (G17) and, for lathes, the ZX plane (G18).
//!
//! Behaviour as the LinuxCNC G-code reference describes it ("G40, G41, G42 cutter
//! compensation", the "Cutter Compensation" chapter) and as the reference interpreter `rs274`
//! shows it when run on small programs. All geometry is in plane coordinates `(a, b)`:
//! `(X, Y)` under G17, `(Z, X)` under G18; the axis normal to the plane and the rotary axes
//! ride along with each move. With `s = +1` for G41 and `-1` for G42 and `t` a unit tangent
//! of the programmed path, the tool-centre offset is `n(t) = s · r · (−t_b, t_a)`:
//!
//! - a straight element `o → p` becomes the parallel line `o + n(t) → p + n(t)`; an arc about
//!   `C` becomes the concentric arc whose end is `p` moved `r` along the radius (towards `C`
//!   when the tool is inside the arc, which needs `r` smaller than the arc radius);
//! - the **entry** (the first move with motion in the plane after G41/G42) starts at the
//!   uncompensated point `c`: a line needs `|p − c| > r` and ends at `p + n(t)` with
//!   `t ∥ p − c`; an arc ends one radius off `p` as above, about a new centre on the line
//!   through `p` and `C`, equidistant from `c` and the new end (so it meets the offset
//!   circle tangentially there);
//! - at each **corner** the turn `φ ∈ (−π, π]` from the old tangent to the new one, seen
//!   from the tool side (`ψ = −s φ`, and a reversal within [`TOLERANCE_CONCAVE_CORNER`] of
//!   a half turn counted as `ψ ≈ +π`), decides the join: `ψ > tol` is **convex**, and the
//!   centre goes round the corner point on an arc of radius `r` to the next element's
//!   offset start (a G0 goes there straight); `ψ < −tol` is **concave**, and the two offset elements are cut where they
//!   cross; `|ψ| ≤ tol` is a tangent join, and the next element runs on from where the last
//!   ended;
//! - the moves since the last element with motion in the plane wait in a queue, because a
//!   concave corner moves their end; a cut that would make a straight move run backwards,
//!   or an arc turn past its end, gouges the part and is refused;
//! - **G40** sends the queued moves as they are; the next move (straight) starts there.
//!
//! A lathe tool of orientation 1-8 (G41.1/G42.1 with L, or Q in the tool table) is
//! compensated about the centre of its nose radius; every move sent out is shifted to the
//! tool's control point, `r` off that centre in X and/or Z (see [`control_point_shift`]).

use std::collections::VecDeque;
use std::f64::consts::{PI, TAU};

use crate::canon::{Motion, Move};
use crate::{Axis, AxisVec, Plane};

/// Corner angle, rad, within which a turn of the path counts as a tangent join (no corner
/// arc, no cut), as rs274 decides it.
pub const TOLERANCE_CONCAVE_CORNER: f64 = 0.05;

/// Plane length, mm, under which a move has no motion in the plane (a plunge).
const PLANE_EPS_MM: f64 = 1e-9;

/// A point or vector in plane coordinates `(a, b)`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct V2(f64, f64);

impl V2 {
    fn add(self, o: V2) -> V2 {
        V2(self.0 + o.0, self.1 + o.1)
    }
    fn sub(self, o: V2) -> V2 {
        V2(self.0 - o.0, self.1 - o.1)
    }
    fn scale(self, k: f64) -> V2 {
        V2(self.0 * k, self.1 * k)
    }
    fn dot(self, o: V2) -> f64 {
        self.0 * o.0 + self.1 * o.1
    }
    /// z component of the cross product: > 0 when `o` lies counter-clockwise of `self`.
    fn cross(self, o: V2) -> f64 {
        self.0 * o.1 - self.1 * o.0
    }
    fn norm(self) -> f64 {
        self.0.hypot(self.1)
    }
    fn unit(self) -> V2 {
        self.scale(1.0 / self.norm())
    }
    /// Turned a quarter turn counter-clockwise.
    fn perp(self) -> V2 {
        V2(-self.1, self.0)
    }
    fn angle(self) -> f64 {
        self.1.atan2(self.0)
    }
}

/// An offset element as a curve to cut at a concave corner.
#[derive(Clone, Copy, Debug)]
enum Curve {
    /// The line through `point` along the unit `dir`.
    Line { point: V2, dir: V2 },
    /// The circle about `center` of `radius`.
    Circle { center: V2, radius: f64 },
}

impl Curve {
    /// The points where `self` and `other` cross (none, one or two).
    fn crossings(self, other: Curve) -> Vec<V2> {
        match (self, other) {
            (Curve::Line { point: p, dir: d }, Curve::Line { point: q, dir: e }) => {
                // p + λ d = q + μ e  ⇒  λ = ((q − p) × e) / (d × e).
                let den = d.cross(e);
                if den.abs() < 1e-12 {
                    return Vec::new();
                }
                vec![p.add(d.scale(q.sub(p).cross(e) / den))]
            }
            (Curve::Line { point, dir }, Curve::Circle { center, radius })
            | (Curve::Circle { center, radius }, Curve::Line { point, dir }) => {
                // |point + λ dir − center|² = radius²: λ² + 2 b λ + c = 0.
                let w = point.sub(center);
                let b = dir.dot(w);
                let disc = b * b - (w.dot(w) - radius * radius);
                if disc < 0.0 {
                    return Vec::new();
                }
                let root = disc.sqrt();
                vec![
                    point.add(dir.scale(-b - root)),
                    point.add(dir.scale(-b + root)),
                ]
            }
            (
                Curve::Circle {
                    center: c1,
                    radius: r1,
                },
                Curve::Circle {
                    center: c2,
                    radius: r2,
                },
            ) => {
                // Along the centre line at x from c1, and ±h across it.
                let d = c2.sub(c1);
                let l = d.norm();
                if l < 1e-12 {
                    return Vec::new();
                }
                let x = (l * l + r1 * r1 - r2 * r2) / (2.0 * l);
                let h2 = r1 * r1 - x * x;
                if h2 < 0.0 {
                    return Vec::new();
                }
                let u = d.scale(1.0 / l);
                let foot = c1.add(u.scale(x));
                let h = h2.sqrt();
                vec![foot.add(u.perp().scale(h)), foot.sub(u.perp().scale(h))]
            }
        }
    }
}

/// The last offset element with motion in the plane, as a concave corner cuts it.
#[derive(Clone, Copy, Debug)]
enum Element {
    /// A straight move from `start` along `dir`, its end on the line through `end`.
    Line { start: V2, end: V2, dir: V2 },
    /// An arc from `start` to `end` about `center`, counter-clockwise when `ccw`.
    Arc {
        start: V2,
        end: V2,
        center: V2,
        ccw: bool,
    },
}

impl Element {
    fn curve(self) -> Curve {
        match self {
            Element::Line { end, dir, .. } => Curve::Line { point: end, dir },
            Element::Arc { end, center, .. } => Curve::Circle {
                center,
                radius: end.sub(center).norm(),
            },
        }
    }

    /// Whether the element, its end moved to `x`, still runs the way it was programmed: a
    /// line not backwards, an arc not past its programmed end.
    fn can_end_at(self, x: V2) -> bool {
        match self {
            Element::Line { start, dir, .. } => x.sub(start).dot(dir) >= 0.0,
            Element::Arc {
                start,
                end,
                center,
                ccw,
            } => {
                let turn = if ccw { 1 } else { -1 };
                let full = sweep(start, end, center, ccw);
                let cut = find_turn([start.0, start.1], [center.0, center.1], turn, [x.0, x.1]);
                let cut = if x.sub(start).norm() < 1e-9 {
                    0.0
                } else {
                    cut.abs()
                };
                cut <= full + 1e-9
            }
        }
    }
}

/// The sweep, rad in (0, 2π], of the arc from `a` to `b` about `c` (a full turn when they
/// coincide).
fn sweep(a: V2, b: V2, c: V2, ccw: bool) -> f64 {
    find_turn([a.0, a.1], [c.0, c.1], if ccw { 1 } else { -1 }, [b.0, b.1]).abs()
}

/// The signed angle, rad, swept from `p1` to `p2` about `c` turning counter-clockwise
/// (`turn` > 0) or clockwise (`turn` < 0), with `|turn| − 1` extra full turns; a full turn
/// when the two directions coincide.
pub fn find_turn(p1: [f64; 2], c: [f64; 2], turn: i32, p2: [f64; 2]) -> f64 {
    let from = V2(p1[0] - c[0], p1[1] - c[1]);
    let to = V2(p2[0] - c[0], p2[1] - c[1]);
    // Counter-clockwise angle from `from` to `to`, in (0, 2π].
    let mut ccw = to.angle() - from.angle();
    while ccw <= 0.0 {
        ccw += TAU;
    }
    while ccw > TAU {
        ccw -= TAU;
    }
    let extra = (turn.unsigned_abs().max(1) - 1) as f64 * TAU;
    if turn > 0 {
        ccw + extra
    } else {
        let cw = TAU - ccw;
        -(if cw == 0.0 { TAU } else { cw } + extra)
    }
}

/// How the path joins at a corner, seen from the tool.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Corner {
    /// The path turns away from the tool: the centre goes round the corner on an arc.
    Convex,
    /// The path turns towards the tool: the offset elements are cut where they cross.
    Concave,
    /// A turn within the tolerance: the next element runs on from the last one's end.
    Tangent,
}

/// The shift, in tool radii along (X, Z), from a lathe tool's nose centre to its control
/// point for orientations 1-8 (the LinuxCNC lathe tool-orientation diagram); none for 0 and 9.
pub fn control_point_shift(orientation: u32) -> (f64, f64) {
    match orientation {
        1 => (-1.0, 1.0),
        2 => (-1.0, -1.0),
        3 => (1.0, -1.0),
        4 => (1.0, 1.0),
        5 => (0.0, 1.0),
        6 => (-1.0, 0.0),
        7 => (0.0, -1.0),
        8 => (1.0, 0.0),
        _ => (0.0, 0.0),
    }
}

/// Compensation state from G41/G42 to G40.
#[derive(Clone, Debug)]
pub struct Comp {
    /// Tool on the left of the path (G41).
    pub left: bool,
    /// Tool (nose) radius, mm, ≥ 0.
    pub radius: f64,
    /// Lathe tool orientation 0-9 (0 and 9: none).
    pub orientation: u32,
    /// G17 or G18.
    pub plane: Plane,
    /// The entry move has been made.
    entered: bool,
    /// Tool-centre point at the end of the queued path (machine coordinates, mm, deg).
    cur: AxisVec,
    /// Programmed point `(a, b)` at the end of the last element.
    prog: V2,
    /// Unit tangent of the programmed path at `prog`.
    tangent: V2,
    /// The last element with motion in the plane, while its end may still be cut.
    last: Option<Element>,
    /// That element and the moves after it (plunges, dwells), waiting for the next corner.
    queue: Vec<Move>,
    /// End of the last move sent out (control point).
    last_out: AxisVec,
}

impl Comp {
    /// Compensation switched on at `pos` (programmed and tool-centre point alike), the last
    /// move sent out having ended at `last_out`. `_unit_mm` (the program's length unit) is
    /// not needed: every rule here is in mm or rad.
    pub fn new(
        left: bool,
        radius: f64,
        orientation: u32,
        plane: Plane,
        pos: AxisVec,
        last_out: AxisVec,
        _unit_mm: f64,
    ) -> Comp {
        let prog = ab(plane, &pos);
        Comp {
            left,
            radius,
            orientation,
            plane,
            entered: false,
            cur: pos,
            prog,
            tangent: V2(1.0, 0.0),
            last: None,
            queue: Vec::new(),
            last_out,
        }
    }

    /// The entry move has been made.
    pub fn started(&self) -> bool {
        self.entered
    }

    /// A move made as programmed (a tool of radius zero, or a move outside the compensated
    /// path): sent out behind the queued moves.
    pub fn pass(&mut self, mv: Move, out: &mut VecDeque<Move>) {
        self.flush(out);
        self.cur = mv.end;
        self.send_as_is(mv, out);
    }

    /// A dwell: waits behind the queued moves (it happens where they end), or goes out now.
    pub fn dwell(&mut self, mv: Move, out: &mut VecDeque<Move>) {
        if self.queue.is_empty() {
            self.send(mv, out);
        } else {
            self.queue.push(mv);
        }
    }

    /// G40 (or the end of the program): the queued moves go out as they are. Returns where
    /// the tool stands, where the next move starts.
    pub fn off(&mut self, out: &mut VecDeque<Move>) -> Result<AxisVec, String> {
        self.check_last()?;
        self.flush(out);
        self.last = None;
        Ok(self.last_out)
    }

    /// A straight move (G0, G1) under compensation, programmed from the current point to
    /// `mv.end`.
    pub fn straight(&mut self, mv: Move, out: &mut VecDeque<Move>) -> Result<(), String> {
        let p = ab(self.plane, &mv.end);
        let chord = p.sub(self.prog);
        if !self.entered {
            let c = ab(self.plane, &self.cur);
            let reach = p.sub(c);
            if reach.norm() <= self.radius {
                return Err(format!(
                    "cutter compensation entry move of {:.4} mm in the plane, not longer than the tool radius {:.4} mm: start farther from the path, or use a smaller tool",
                    reach.norm(),
                    self.radius
                ));
            }
            let t = reach.unit();
            let end = p.add(self.offset(t));
            self.enter(
                Element::Line {
                    start: c,
                    end,
                    dir: t,
                },
                t,
                p,
                mv,
                end,
                None,
                out,
            );
            return Ok(());
        }
        if chord.norm() < PLANE_EPS_MM {
            // A plunge: the tool centre stays where it is in the plane.
            let mut mv = mv;
            mv.end = with_ab(self.plane, mv.end, ab(self.plane, &self.cur));
            self.cur = mv.end;
            self.queue.push(mv);
            return Ok(());
        }
        let t = chord.unit();
        let n = self.offset(t);
        let (start, end) = (self.prog.add(n), p.add(n));
        let new = Element::Line { start, end, dir: t };
        self.check_last()?;
        self.join(new, t, t, p, mv, end, out)
    }

    /// An arc (G2, G3) under compensation, programmed from the current point to `mv.end`.
    pub fn arc(&mut self, mv: Move, out: &mut VecDeque<Move>) -> Result<(), String> {
        let Motion::Arc {
            clockwise,
            center_mm,
            ..
        } = mv.motion
        else {
            return self.straight(mv, out);
        };
        let ccw = !clockwise;
        let (a, b, _) = self.plane.axes();
        let center = V2(center_mm[index(a)], center_mm[index(b)]);
        let p = ab(self.plane, &mv.end);
        let radial = p.sub(center);
        let r_end = radial.norm();
        let inside = self.left == ccw;
        if inside && self.radius >= r_end {
            return Err(format!(
                "tool radius {:.4} mm not smaller than the arc radius {:.4} mm it cuts inside: use a smaller tool or a larger arc",
                self.radius, r_end
            ));
        }
        let u_end = radial.scale(1.0 / r_end);
        // The offset end: one tool radius along the radius, inwards when inside.
        let end = p.add(u_end.scale(if inside { -self.radius } else { self.radius }));
        let spin = |u: V2| if ccw { u.perp() } else { u.perp().scale(-1.0) };
        let t_end = spin(u_end);
        if !self.entered {
            let c = ab(self.plane, &self.cur);
            // Centre on the line through `end` along u_end, as far from c as from end:
            // |end + k u − c|² = k²  ⇒  k = −|end − c|² / (2 u·(end − c)).
            let w = end.sub(c);
            let den = 2.0 * u_end.dot(w);
            if den.abs() < 1e-12 {
                return Err("cutter compensation entry arc with no arc from the start point to the compensated end: start elsewhere, or enter with a straight move".to_string());
            }
            let new_center = end.add(u_end.scale(-w.dot(w) / den));
            let element = Element::Arc {
                start: c,
                end,
                center: new_center,
                ccw,
            };
            self.enter(element, t_end, p, mv, end, Some(new_center), out);
            return Ok(());
        }
        let u_start = self.prog.sub(center).unit();
        let t_start = spin(u_start);
        let start = self.prog.add(self.offset(t_start));
        let new = Element::Arc {
            start,
            end,
            center,
            ccw,
        };
        self.join(new, t_start, t_end, p, mv, end, out)
    }

    /// The tool-centre offset for the unit tangent `t`: r on the tool's side.
    fn offset(&self, t: V2) -> V2 {
        t.perp()
            .scale(if self.left { self.radius } else { -self.radius })
    }

    /// The entry element: from the uncompensated point to `end` (about `center` for an arc).
    #[allow(clippy::too_many_arguments)]
    fn enter(
        &mut self,
        element: Element,
        t_end: V2,
        p: V2,
        mut mv: Move,
        end: V2,
        center: Option<V2>,
        out: &mut VecDeque<Move>,
    ) {
        self.flush(out);
        if center.is_some() && control_point_shift(self.orientation) != (0.0, 0.0) {
            // A lathe tool's control point stands off the nose centre the arc starts from:
            // a straight feed brings it to the arc's (shifted) start first.
            let to_start = Move {
                motion: Motion::Linear,
                end: self.cur,
                ..mv
            };
            self.send(to_start, out);
        }
        mv.end = with_ab(self.plane, mv.end, end);
        if let (Some(c), Motion::Arc { center_mm, .. }) = (center, &mut mv.motion) {
            let (a, b, _) = self.plane.axes();
            center_mm[index(a)] = c.0;
            center_mm[index(b)] = c.1;
        }
        self.entered = true;
        self.push_element(element, t_end, p, mv);
    }

    /// A later element, `start_t`/`end_t` its programmed tangents at `prog` and `p`, its
    /// offset `new` ending at `end`: joined to the queued one by the corner rule.
    #[allow(clippy::too_many_arguments)]
    fn join(
        &mut self,
        new: Element,
        start_t: V2,
        end_t: V2,
        p: V2,
        mut mv: Move,
        end: V2,
        out: &mut VecDeque<Move>,
    ) -> Result<(), String> {
        mv.end = with_ab(self.plane, mv.end, end);
        let new = match self.corner(self.tangent, start_t) {
            Corner::Tangent => {
                self.flush(out);
                restart(new, ab(self.plane, &self.cur))
            }
            Corner::Convex => {
                self.flush(out);
                let start = match new {
                    Element::Line { start, .. } | Element::Arc { start, .. } => start,
                };
                self.corner_arc(&mv, start, out);
                new
            }
            Corner::Concave => {
                let x = self.cut(new)?;
                let (a, b, _) = self.plane.axes();
                for q in &mut self.queue {
                    q.end[a] = x.0;
                    q.end[b] = x.1;
                }
                self.cur = with_ab(self.plane, self.cur, x);
                self.flush(out);
                restart(new, x)
            }
        };
        self.push_element(new, end_t, p, mv);
        Ok(())
    }

    /// A queued straight move must still run forward from its start to its end when a
    /// straight move or G40 ends it (rs274 lets an arc follow one that does not).
    fn check_last(&self) -> Result<(), String> {
        match self.last {
            Some(last @ Element::Line { end, .. }) if !last.can_end_at(end) => Err(gouge(last)),
            _ => Ok(()),
        }
    }

    /// Where the queued element and the offset of the next one cross, nearest the queued
    /// element's end; refused when they do not cross, or the cut gouges.
    fn cut(&self, new: Element) -> Result<V2, String> {
        let last = self.last.expect("an element precedes every corner");
        let c = ab(self.plane, &self.cur);
        let x = last
            .curve()
            .crossings(new.curve())
            .into_iter()
            .min_by(|p, q| p.sub(c).norm().total_cmp(&q.sub(c).norm()));
        match x {
            Some(x) if last.can_end_at(x) => Ok(x),
            _ => Err(gouge(last)),
        }
    }

    /// The arc of radius r about the corner point `prog` from the tool centre to `to` (a
    /// straight traverse for a rapid), at the height and rotary positions where the tool
    /// stands.
    fn corner_arc(&mut self, mv: &Move, to: V2, out: &mut VecDeque<Move>) {
        let corner = with_ab(self.plane, self.cur, self.prog);
        // A rapid goes round the corner straight, as rs274 does: the path of a traverse is
        // not cut.
        let motion = match mv.motion {
            Motion::Rapid => Motion::Rapid,
            _ => Motion::Arc {
                clockwise: self.left,
                plane: self.plane,
                center_mm: [corner[Axis::X], corner[Axis::Y], corner[Axis::Z]],
            },
        };
        let arc = Move {
            motion,
            end: with_ab(self.plane, self.cur, to),
            ..*mv
        };
        self.cur = arc.end;
        self.send(arc, out);
    }

    /// Queues `mv` as the new last element, the programmed path now at `p` with tangent `t`.
    fn push_element(&mut self, element: Element, t: V2, p: V2, mv: Move) {
        self.last = Some(element);
        self.tangent = t;
        self.prog = p;
        self.cur = mv.end;
        self.queue.push(mv);
    }

    /// The join at a corner from tangent `from` to tangent `to`.
    fn corner(&self, from: V2, to: V2) -> Corner {
        let phi = from.cross(to).atan2(from.dot(to));
        let mut psi = if self.left { -phi } else { phi };
        // A reversal within the tolerance of a half turn is taken round the outside.
        if psi <= -PI + TOLERANCE_CONCAVE_CORNER {
            psi += TAU;
        }
        if psi > TOLERANCE_CONCAVE_CORNER {
            Corner::Convex
        } else if psi < -TOLERANCE_CONCAVE_CORNER {
            Corner::Concave
        } else {
            Corner::Tangent
        }
    }

    /// Sends every queued move out.
    fn flush(&mut self, out: &mut VecDeque<Move>) {
        for mv in std::mem::take(&mut self.queue) {
            self.send(mv, out);
        }
    }

    /// Sends `mv` out, from where the last move ended, shifted to a lathe tool's control
    /// point.
    fn send(&mut self, mut mv: Move, out: &mut VecDeque<Move>) {
        let (dx, dz) = control_point_shift(self.orientation);
        let (dx, dz) = (dx * self.radius, dz * self.radius);
        mv.end[Axis::X] += dx;
        mv.end[Axis::Z] += dz;
        if let Motion::Arc { center_mm, .. } = &mut mv.motion {
            center_mm[0] += dx;
            center_mm[2] += dz;
        }
        self.send_as_is(mv, out);
    }

    /// Sends `mv` out from where the last move ended, unshifted.
    fn send_as_is(&mut self, mut mv: Move, out: &mut VecDeque<Move>) {
        mv.start = self.last_out;
        if matches!(mv.motion, Motion::Dwell { .. }) {
            mv.end = self.last_out;
        }
        self.last_out = mv.end;
        out.push_back(mv);
    }
}

/// The refusal of a concave corner that `last` cannot reach.
fn gouge(last: Element) -> String {
    let what = match last {
        Element::Line { .. } => "straight move",
        Element::Arc { .. } => "arc",
    };
    format!(
        "concave corner the tool cannot reach without gouging: the compensated {what} before it would have to run backwards; use a smaller tool or a longer {what}"
    )
}

/// `element` starting at `start` instead (a tangent join or a concave cut).
fn restart(element: Element, at: V2) -> Element {
    match element {
        Element::Line { end, dir, .. } => Element::Line {
            start: at,
            end,
            dir,
        },
        Element::Arc {
            end, center, ccw, ..
        } => Element::Arc {
            start: at,
            end,
            center,
            ccw,
        },
    }
}

/// Index of `a` in an `[X, Y, Z]` arc centre.
fn index(a: Axis) -> usize {
    match a {
        Axis::X => 0,
        Axis::Y => 1,
        _ => 2,
    }
}

fn ab(plane: Plane, p: &AxisVec) -> V2 {
    let (a, b, _) = plane.axes();
    V2(p[a], p[b])
}

fn with_ab(plane: Plane, mut p: AxisVec, v: V2) -> AxisVec {
    let (a, b, _) = plane.axes();
    p[a] = v.0;
    p[b] = v.1;
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn find_turn_sweeps_in_the_asked_direction() {
        let c = [0.0, 0.0];
        let q = find_turn([1.0, 0.0], c, 1, [0.0, 1.0]);
        assert!((q - PI / 2.0).abs() < 1e-12);
        let q = find_turn([1.0, 0.0], c, -1, [0.0, 1.0]);
        assert!((q + 1.5 * PI).abs() < 1e-12);
        assert!((find_turn([1.0, 0.0], c, 1, [1.0, 0.0]) - TAU).abs() < 1e-12);
        assert!((find_turn([1.0, 0.0], c, -1, [1.0, 0.0]) + TAU).abs() < 1e-12);
        assert!((find_turn([1.0, 0.0], c, 2, [-1.0, 0.0]) - 3.0 * PI).abs() < 1e-12);
    }

    #[test]
    fn crossings_of_lines_and_circles() {
        let l = Curve::Line {
            point: V2(0.0, 1.0),
            dir: V2(1.0, 0.0),
        };
        let m = Curve::Line {
            point: V2(3.0, 0.0),
            dir: V2(0.0, 1.0),
        };
        assert_eq!(l.crossings(m), vec![V2(3.0, 1.0)]);
        let c = Curve::Circle {
            center: V2(0.0, 0.0),
            radius: 2.0,
        };
        let x = l.crossings(c);
        assert_eq!(x.len(), 2);
        for p in &x {
            assert!((p.norm() - 2.0).abs() < 1e-12 && (p.1 - 1.0).abs() < 1e-12);
        }
        let d = Curve::Circle {
            center: V2(2.0, 0.0),
            radius: 2.0,
        };
        for p in c.crossings(d) {
            assert!(
                (p.norm() - 2.0).abs() < 1e-12 && (p.sub(V2(2.0, 0.0)).norm() - 2.0).abs() < 1e-12
            );
        }
        let far = Curve::Circle {
            center: V2(10.0, 0.0),
            radius: 1.0,
        };
        assert!(c.crossings(far).is_empty());
    }

    #[test]
    fn corners_are_classified_from_the_tool_side() {
        let g41 = Comp::new(true, 1.0, 0, Plane::XY, AxisVec::ZERO, AxisVec::ZERO, 1.0);
        let east = V2(1.0, 0.0);
        let at = |deg: f64| V2(deg.to_radians().cos(), deg.to_radians().sin());
        // G41: a left turn goes towards the tool.
        assert_eq!(g41.corner(east, at(90.0)), Corner::Concave);
        assert_eq!(g41.corner(east, at(-90.0)), Corner::Convex);
        assert_eq!(g41.corner(east, at(2.0)), Corner::Tangent);
        assert_eq!(g41.corner(east, at(180.0)), Corner::Convex);
        assert_eq!(g41.corner(east, at(178.0)), Corner::Convex);
        assert_eq!(g41.corner(east, at(170.0)), Corner::Concave);
        let g42 = Comp { left: false, ..g41 };
        assert_eq!(g42.corner(east, at(90.0)), Corner::Convex);
        assert_eq!(g42.corner(east, at(-170.0)), Corner::Concave);
    }

    #[test]
    fn lathe_shifts_are_one_radius_along_x_and_z() {
        for o in 1..=8 {
            let (x, z) = control_point_shift(o);
            assert!(x.abs() <= 1.0 && z.abs() <= 1.0 && (x != 0.0 || z != 0.0));
        }
        assert_eq!(control_point_shift(0), (0.0, 0.0));
        assert_eq!(control_point_shift(9), (0.0, 0.0));
    }
}
