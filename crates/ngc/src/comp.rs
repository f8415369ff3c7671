//! Cutter radius compensation (G41/G42, G41.1/G42.1, G40) in the XY plane (G17) and, for
//! lathes, the ZX plane (G18), ported from LinuxCNC 2.9's interpreter (interp_convert.cc
//! `convert_straight_comp1/2`, `convert_arc_comp1/2`; interp_queue.cc). The tool centre
//! runs at distance r from the programmed path, on its left (G41) or right (G42).
//!
//! Everything is computed in plane coordinates (a, b): (X, Y) under G17, (Z, X) under G18,
//! as LinuxCNC's `comp_get_current` does; the third axis (Z, or Y) rides along. With `c` the
//! compensated current point, `o` the programmed start, `p` the programmed end:
//!
//! - **entry line** (first move after G41/G42): needs `|p - c| > r`; ends at
//!   `p + r (cos α, sin α)`, `α = atan2(p - c) ± π/2` (+ for G41);
//! - **entry arc**: the programmed end moves by r along the radius (toward the centre when
//!   the tool is inside), and the arc from c to it gets a new centre on the old centre line,
//!   `b / cos A` from the end (b half the chord, A the angle between chord and centre line);
//! - **later moves**: θ = direction o → c (the tool side of the last move), β the turn of the
//!   path measured from θ: β > π + 0.05 or β < -0.05 (`TOLERANCE_CONCAVE_CORNER`) is a
//!   **concave** corner, β > 0.05 a **convex** one, else a tangent join. A convex corner gets
//!   an arc of radius r about o (clockwise for G41) from c to `o + r n`; a concave corner
//!   moves the end of every queued move to where the two offset paths cross: line-line
//!   `c + r / tan((β + π)/2)` back along the old direction, line-arc, arc-line and arc-arc
//!   by the triangle of the two centres and radii (r ± tool radius);
//! - moves wait in a queue until the next move fixes their end (`move_endpoint_and_flush`):
//!   a moved end that makes a straight move run backwards, or an arc sweep further than
//!   programmed, is gouging and an error;
//! - **G40** ends the queued moves at c; the next move (which must be straight) starts there.
//!
//! A lathe tool (orientation 1-8, G41.1/G42.1 L) is compensated about the centre of its
//! nose radius; its control point sits r off that centre in X and Z by the orientation
//! (`latheorigin_x/z`), applied when a move leaves the queue.

use std::collections::VecDeque;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

use crate::canon::{Motion, Move};
use crate::{Axis, AxisVec, Plane};

/// LinuxCNC's `TOLERANCE_CONCAVE_CORNER`, rad.
pub const TOLERANCE_CONCAVE_CORNER: f64 = 0.05;
/// LinuxCNC's `TOLERANCE_EQUAL`.
const TOLERANCE_EQUAL: f64 = 0.0001;

/// A queued move's geometry, in plane coordinates.
#[derive(Clone, Copy, Debug)]
enum Kind {
    /// A straight move; `dir` is the direction the gouge check compares with.
    Line { dir: [f64; 2] },
    /// An arc about `center`, turn +1 counter-clockwise, -1 clockwise; `sweep` the
    /// programmed sweep in rad (0 for a corner arc, whose end never moves).
    Arc {
        center: [f64; 2],
        turn: i32,
        sweep: f64,
    },
    /// A dwell.
    Other,
}

#[derive(Clone, Debug)]
struct Queued {
    mv: Move,
    kind: Kind,
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
    first: bool,
    /// Compensated current position (machine mm, deg).
    cur: AxisVec,
    /// Programmed current point (a, b).
    prog: [f64; 2],
    queue: Vec<Queued>,
    /// Start (a, b) of the first queued move, when known (LinuxCNC's `endpoint`).
    endpoint: Option<[f64; 2]>,
    /// End of the last move that left the queue.
    last_out: AxisVec,
    /// Program length unit, mm (1 or 25.4), for LinuxCNC's radius check of 0.01 units.
    unit_mm: f64,
}

fn ab(plane: Plane, p: &AxisVec) -> [f64; 2] {
    let (a, b, _) = plane.axes();
    [p[a], p[b]]
}

fn with_ab(plane: Plane, mut p: AxisVec, v: [f64; 2]) -> AxisVec {
    let (a, b, _) = plane.axes();
    p[a] = v[0];
    p[b] = v[1];
    p
}

fn dist(p: [f64; 2], q: [f64; 2]) -> f64 {
    (p[0] - q[0]).hypot(p[1] - q[1])
}

fn dir(from: [f64; 2], to: [f64; 2]) -> f64 {
    (to[1] - from[1]).atan2(to[0] - from[0])
}

fn polar(p: [f64; 2], r: f64, angle: f64) -> [f64; 2] {
    [p[0] + r * angle.cos(), p[1] + r * angle.sin()]
}

/// LinuxCNC's `find_turn`: the signed sweep, rad, from `p1` to `p2` about `c` in the
/// direction of `turn` (a full turn when they coincide).
pub fn find_turn(p1: [f64; 2], c: [f64; 2], turn: i32, p2: [f64; 2]) -> f64 {
    let mut alpha = dir(c, p1);
    let mut beta = dir(c, p2);
    if turn > 0 {
        if beta <= alpha {
            beta += TAU;
        }
        beta - alpha + (turn - 1) as f64 * TAU
    } else {
        if alpha <= beta {
            alpha += TAU;
        }
        beta - alpha + (turn + 1) as f64 * TAU
    }
}

impl Comp {
    /// Compensation switched on at `pos` (programmed and actual position alike, LinuxCNC's
    /// current point), the last move having ended at `last_out`.
    pub fn new(
        left: bool,
        radius: f64,
        orientation: u32,
        plane: Plane,
        pos: AxisVec,
        last_out: AxisVec,
        unit_mm: f64,
    ) -> Comp {
        Comp {
            left,
            radius,
            orientation,
            plane,
            first: true,
            cur: pos,
            prog: ab(plane, &pos),
            queue: Vec::new(),
            endpoint: None,
            last_out,
            unit_mm,
        }
    }

    /// The tool is inside an arc of this turn.
    fn inside(&self, turn: i32) -> bool {
        (self.left && turn > 0) || (!self.left && turn < 0)
    }

    /// `target` with (a, b) = `v` and the third axis at the current point's (a corner).
    fn corner_end(&self, target: &AxisVec, v: [f64; 2]) -> AxisVec {
        let (_, _, n) = self.plane.axes();
        let mut p = with_ab(self.plane, *target, v);
        p[n] = self.cur[n];
        p
    }

    fn push(&mut self, mv: Move, kind: Kind) {
        self.queue.push(Queued { mv, kind });
    }

    /// Sets the compensated current point's (a, b) to `p`'s, the third axis kept, as
    /// rs274 does when a G70 profile read moves its current point (`settings->current_x/z`).
    pub fn set_current(&mut self, p: AxisVec) {
        self.cur = with_ab(self.plane, self.cur, ab(self.plane, &p));
    }

    /// The entry move has been made.
    pub fn started(&self) -> bool {
        !self.first
    }

    /// A move left as programmed (a tool of radius zero): goes out behind the queue.
    pub fn pass(&mut self, mv: Move, out: &mut VecDeque<Move>) {
        self.dequeue(out);
        let mut mv = mv;
        mv.start = self.last_out;
        self.last_out = mv.end;
        self.cur = mv.end;
        out.push_back(mv);
    }

    /// A dwell: waits in the queue behind the queued moves, or goes out at once.
    pub fn dwell(&mut self, mut mv: Move, out: &mut VecDeque<Move>) {
        if self.queue.is_empty() {
            mv.start = self.last_out;
            mv.end = self.last_out;
            out.push_back(mv);
        } else {
            self.push(mv, Kind::Other);
        }
    }

    /// The lathe control point of a nose-centre point (a, b) = (Z, X) under G18.
    fn lathe_origin(&self, p: [f64; 2]) -> [f64; 2] {
        if self.plane != Plane::ZX {
            return p;
        }
        let (o, r) = (self.orientation, self.radius);
        let [mut z, mut x] = p;
        if matches!(o, 2 | 6 | 1) {
            x -= r;
        }
        if matches!(o, 3 | 8 | 4) {
            x += r;
        }
        if matches!(o, 2 | 7 | 3) {
            z -= r;
        }
        if matches!(o, 1 | 5 | 4) {
            z += r;
        }
        [z, x]
    }

    /// Sends the queued moves out, each starting where the previous ended.
    fn dequeue(&mut self, out: &mut VecDeque<Move>) {
        self.endpoint = None;
        let plane = self.plane;
        for q in std::mem::take(&mut self.queue) {
            let mut mv = q.mv;
            mv.start = self.last_out;
            if let Kind::Other = q.kind {
                mv.end = self.last_out;
            } else {
                let e = self.lathe_origin(ab(plane, &mv.end));
                mv.end = with_ab(plane, mv.end, e);
            }
            if let Kind::Arc {
                center,
                turn,
                sweep,
            } = q.kind
            {
                let c = self.lathe_origin(center);
                let (a, b, _) = plane.axes();
                let mut center_mm = [mv.start[Axis::X], mv.start[Axis::Y], mv.start[Axis::Z]];
                center_mm[a.index()] = c[0];
                center_mm[b.index()] = c[1];
                // A full circle programmed stays one after rounding.
                if sweep.abs() > PI && dist(ab(plane, &mv.start), ab(plane, &mv.end)) < 1e-7 {
                    let s = ab(plane, &mv.start);
                    mv.end = with_ab(plane, mv.end, s);
                }
                mv.motion = Motion::Arc {
                    clockwise: turn < 0,
                    plane,
                    center_mm,
                };
            }
            self.last_out = mv.end;
            out.push_back(mv);
        }
    }

    /// Moves the end (a, b) of every queued move to `p` and sends them out.
    fn move_endpoint_and_flush(
        &mut self,
        p: [f64; 2],
        out: &mut VecDeque<Move>,
    ) -> Result<(), String> {
        if self.queue.is_empty() {
            return Ok(());
        }
        let plane = self.plane;
        for q in &mut self.queue {
            match q.kind {
                Kind::Arc {
                    center,
                    turn,
                    sweep,
                } => {
                    let r1 = dist(ab(plane, &q.mv.end), center);
                    let r2 = dist(p, center);
                    if (r1 - r2).abs() > 0.01 * self.unit_mm {
                        return Err(format!("cutter compensation made an arc whose radii differ ({r1:.4} and {r2:.4} mm): expected a corner the tool can follow"));
                    }
                    if let Some(e) = self.endpoint {
                        let l2 = find_turn(e, center, turn, p);
                        if sweep != 0.0 && l2.abs() > sweep.abs() + 0.001 {
                            return Err("arc move in concave corner cannot be reached by the tool without gouging: expected a smaller tool or a longer arc".into());
                        }
                    }
                }
                Kind::Line { dir } => {
                    if let Some(e) = self.endpoint {
                        if dir[0] * (p[0] - e[0]) + dir[1] * (p[1] - e[1]) < 0.0 {
                            let what = if matches!(q.mv.motion, Motion::Rapid) {
                                "straight traverse"
                            } else {
                                "straight feed"
                            };
                            return Err(format!("{what} in concave corner cannot be reached by the tool without gouging: expected a move longer than the tool radius"));
                        }
                    }
                }
                Kind::Other => {}
            }
            q.mv.end = with_ab(plane, q.mv.end, p);
        }
        self.dequeue(out);
        self.endpoint = Some(p);
        Ok(())
    }

    /// G40 (or a program stop): the queued moves end at the compensated current point.
    /// Returns where the tool is (the next move's start).
    pub fn off(&mut self, out: &mut VecDeque<Move>) -> Result<AxisVec, String> {
        if self.radius > 0.0 && !self.first {
            let c = ab(self.plane, &self.cur);
            self.move_endpoint_and_flush(c, out)?;
        }
        self.dequeue(out);
        Ok(self.last_out)
    }

    /// A G00/G01 move as programmed (`mv.end` the programmed end).
    pub fn straight(&mut self, mut mv: Move, out: &mut VecDeque<Move>) -> Result<(), String> {
        let plane = self.plane;
        let r = self.radius;
        let p = ab(plane, &mv.end);
        let c = ab(plane, &self.cur);
        let rapid = matches!(mv.motion, Motion::Rapid);
        if self.first {
            let distance = dist(p, c);
            if distance <= r {
                return Err(format!("length of cutter compensation entry move is not greater than the tool radius ({distance:.4} mm, tool radius {r:.4} mm): expected an entry move longer than the tool radius in the {} plane", plane.g_code()));
            }
            let alpha = dir(c, p) + if self.left { FRAC_PI_2 } else { -FRAC_PI_2 };
            let end = polar(p, r, alpha);
            self.endpoint = Some(c);
            mv.end = with_ab(plane, mv.end, end);
            self.cur = mv.end;
            self.push(
                mv,
                Kind::Line {
                    dir: [alpha.cos(), alpha.sin()],
                },
            );
            self.first = false;
            self.prog = p;
            return Ok(());
        }
        let o = self.prog;
        if p == o {
            // No motion in the plane: stays at the compensated point.
            mv.end = with_ab(plane, mv.end, c);
            self.cur = mv.end;
            self.push(mv, Kind::Line { dir: [0.0, 0.0] });
            return Ok(());
        }
        let mut theta = dir(o, c);
        let mut alpha = dir(o, p);
        let (beta, gamma) = if self.left {
            if theta < alpha {
                theta += TAU;
            }
            (theta - alpha - FRAC_PI_2, FRAC_PI_2)
        } else {
            if alpha < theta {
                alpha += TAU;
            }
            (alpha - theta - FRAC_PI_2, -FRAC_PI_2)
        };
        let end = polar(p, r, alpha + gamma);
        let mid = polar(o, r, alpha + gamma);
        let small = TOLERANCE_CONCAVE_CORNER;
        let front_arc = match self.queue.first().map(|q| q.kind) {
            Some(Kind::Arc { center, turn, .. }) => Some((center, turn)),
            _ => None,
        };
        let concave = beta < -small
            || beta > PI + small
            // An "h" shape: over the round part, then along the straight one.
            || (beta > PI - small
                && front_arc.is_some_and(|(_, turn)| (!self.left && turn > 0) || (self.left && turn < 0)));
        if !concave && beta > small {
            // Convex corner: an arc about the programmed corner (a traverse for G00).
            self.move_endpoint_and_flush(c, out)?;
            let corner = Move {
                motion: Motion::Rapid,
                end: self.corner_end(&mv.end, mid),
                ..mv.clone()
            };
            if rapid {
                self.push(corner, Kind::Line { dir: [0.0, 0.0] });
            } else {
                let corner = Move {
                    motion: mv_arc_placeholder(),
                    ..corner
                };
                self.push(
                    corner,
                    Kind::Arc {
                        center: o,
                        turn: if self.left { -1 } else { 1 },
                        sweep: 0.0,
                    },
                );
            }
            self.dequeue(out);
            self.endpoint = Some(mid);
        } else if concave {
            match front_arc {
                None => {
                    // Line to line: back along the old direction.
                    let halfcorner = (beta + PI) / 2.0;
                    if halfcorner == 0.0 {
                        return Err("zero degree inside corner is invalid for cutter compensation: expected a corner the tool can enter".into());
                    }
                    let retreat = r / halfcorner.tan();
                    let m = polar(c, retreat, theta + gamma);
                    self.move_endpoint_and_flush(m, out)?;
                }
                Some((pc, pturn)) => {
                    // Arc to line; the queued arc is the compensated one.
                    let pend = ab(plane, &self.queue[0].mv.end);
                    let oldrad = dist(pc, pend);
                    let base_dir = dir(o, p);
                    let theta = if pturn > 0 {
                        base_dir + FRAC_PI_2
                    } else {
                        base_dir - FRAC_PI_2
                    };
                    let phi = dir(o, pc);
                    let inside = self.inside(pturn);
                    let oldrad_uncomp = if inside { oldrad + r } else { oldrad - r };
                    let d = oldrad_uncomp * (theta - phi).cos();
                    let l = if inside { d - r } else { d + r } / oldrad;
                    if !(-1.0..=1.0).contains(&l) {
                        return Err("arc to straight motion makes a corner the compensated tool can't fit in without gouging: expected a smaller tool".into());
                    }
                    let angle = if inside == (pturn > 0) {
                        -l.acos() + theta + PI
                    } else {
                        l.acos() + theta + PI
                    };
                    self.move_endpoint_and_flush(polar(pc, oldrad, angle), out)?;
                }
            }
        } else {
            // Tangent (or straight on): no corner.
            self.dequeue(out);
            self.endpoint = Some(c);
        }
        mv.end = with_ab(plane, mv.end, end);
        self.cur = mv.end;
        self.push(
            mv,
            Kind::Line {
                dir: [p[0] - o[0], p[1] - o[1]],
            },
        );
        self.prog = p;
        Ok(())
    }

    /// A G02/G03 move as programmed (`mv.end` the programmed end, the centre computed from
    /// the programmed start).
    pub fn arc(&mut self, mut mv: Move, out: &mut VecDeque<Move>) -> Result<(), String> {
        let plane = self.plane;
        let Motion::Arc {
            clockwise,
            center_mm,
            ..
        } = mv.motion
        else {
            unreachable!("comp::arc takes arcs");
        };
        let (a, b, _) = plane.axes();
        let center = [center_mm[a.index()], center_mm[b.index()]];
        let turn = if clockwise { -1 } else { 1 };
        let inside = self.inside(turn);
        let r = self.radius;
        let end = ab(plane, &mv.end);
        let c = ab(plane, &self.cur);
        let too_small = |arc_radius: f64| {
            format!("tool radius not less than arc radius with cutter compensation (arc radius {arc_radius:.4} mm, tool radius {r:.4} mm, tool inside the arc): expected a tool smaller than the arc")
        };
        if self.first {
            if dist(end, c) <= r {
                return Err(format!("radius of cutter compensation entry arc is not greater than the tool radius ({r:.4} mm): expected the entry arc to end further than the tool radius from its start"));
            }
            let arc_radius = dist(center, c);
            if arc_radius <= r && inside {
                return Err(too_small(arc_radius));
            }
            let gamma = if inside {
                dir(end, center)
            } else {
                dir(center, end)
            };
            self.first = false;
            self.prog = end;
            let e2 = polar(end, r, gamma);
            let b_len = dist(c, e2) / 2.0;
            let ab_ang = dir(e2, center);
            let a_ang = dir(e2, c) - ab_ang;
            if a_ang.cos().abs() < TOLERANCE_EQUAL {
                return Err(too_small(arc_radius));
            }
            let center2 = polar(e2, b_len / a_ang.cos(), ab_ang);
            if self.orientation != 0 && self.orientation != 9 {
                // A lathe tool first moves its control point to the nose centre.
                let first = Move {
                    motion: Motion::Linear,
                    end: self.corner_end(&mv.end, c),
                    ..mv.clone()
                };
                self.push(first, Kind::Line { dir: [0.0, 0.0] });
                self.endpoint = Some(c);
            }
            mv.end = with_ab(plane, mv.end, e2);
            self.cur = mv.end;
            let sweep = find_turn(c, center2, turn, e2);
            self.push(
                mv,
                Kind::Arc {
                    center: center2,
                    turn,
                    sweep,
                },
            );
            return Ok(());
        }
        let o = self.prog;
        let arc_radius = dist(center, end);
        let theta = dir(o, c) + if self.left { -FRAC_PI_2 } else { FRAC_PI_2 };
        let mut delta = dir(o, center);
        let alpha = if clockwise {
            delta + FRAC_PI_2
        } else {
            delta - FRAC_PI_2
        };
        let mut beta = if self.left {
            theta - alpha
        } else {
            alpha - theta
        };
        if beta > 1.5 * PI {
            beta -= TAU;
        } else if beta < -FRAC_PI_2 {
            beta += TAU;
        }
        let gamma = if inside {
            if arc_radius <= r {
                return Err(too_small(arc_radius));
            }
            dir(end, center)
        } else {
            delta += PI;
            dir(center, end)
        };
        let new_end = polar(end, r, gamma);
        let small = TOLERANCE_CONCAVE_CORNER;
        let sweep = find_turn(o, center, turn, end);
        let main_kind = Kind::Arc {
            center,
            turn,
            sweep,
        };
        if beta < -small || beta > PI + small || ((beta - PI).abs() < small && !inside) {
            // Concave.
            let front_arc = match self.queue.first().map(|q| q.kind) {
                Some(Kind::Arc { center, turn, .. }) => Some((center, turn)),
                _ => None,
            };
            let mid = match front_arc {
                None => {
                    // Line to arc.
                    let cy = arc_radius * (beta - FRAC_PI_2).sin();
                    let (dist_from_center, angle) = if inside {
                        let d = arc_radius - r;
                        let l = (cy + r) / d;
                        if !(-1.0..=1.0).contains(&l) {
                            return Err(gouge_arc());
                        }
                        (
                            d,
                            if turn > 0 {
                                theta + l.asin()
                            } else {
                                theta - l.asin()
                            },
                        )
                    } else {
                        let d = arc_radius + r;
                        let l = (cy - r) / d;
                        if !(-1.0..=1.0).contains(&l) {
                            return Err(gouge_arc());
                        }
                        (
                            d,
                            if turn > 0 {
                                theta + PI - l.asin()
                            } else {
                                theta + PI + l.asin()
                            },
                        )
                    };
                    polar(center, dist_from_center, angle)
                }
                Some((pc, pturn)) => {
                    // Arc to arc: where the two compensated circles cross.
                    let oldrad = dist(pc, ab(plane, &self.queue[0].mv.end));
                    let newrad = if inside {
                        arc_radius - r
                    } else {
                        arc_radius + r
                    };
                    let arc_cc = dist(pc, center);
                    if oldrad == 0.0 || arc_cc == 0.0 {
                        return Err("arc to arc motion is invalid because the arcs have the same center: expected arcs about different centres".into());
                    }
                    let k = (oldrad * oldrad + arc_cc * arc_cc - newrad * newrad)
                        / (2.0 * oldrad * arc_cc);
                    if !(-1.0..=1.0).contains(&k) {
                        return Err("arc to arc motion makes a corner the compensated tool can't fit in without gouging: expected a smaller tool".into());
                    }
                    let pullback = k.acos();
                    let cc_dir = dir(pc, center);
                    let angle = if self.inside(pturn) == (turn > 0) {
                        cc_dir + pullback
                    } else {
                        cc_dir - pullback
                    };
                    polar(pc, oldrad, angle)
                }
            };
            self.move_endpoint_and_flush(mid, out)?;
        } else if beta > small {
            // Convex: an arc about the programmed corner first.
            let mid = polar(o, r, delta);
            self.dequeue(out);
            let corner = Move {
                end: self.corner_end(&mv.end, mid),
                ..mv.clone()
            };
            self.push(
                corner,
                Kind::Arc {
                    center: o,
                    turn: if self.left { -1 } else { 1 },
                    sweep: 0.0,
                },
            );
            self.dequeue(out);
            self.endpoint = Some(mid);
        } else {
            self.dequeue(out);
            self.endpoint = Some(c);
        }
        mv.end = with_ab(plane, mv.end, new_end);
        self.cur = mv.end;
        self.push(mv, main_kind);
        self.prog = end;
        Ok(())
    }
}

fn gouge_arc() -> String {
    "arc move in concave corner cannot be reached by the tool without gouging: expected a smaller tool or a gentler corner".into()
}

/// The motion of a queued arc before it leaves the queue (`dequeue` sets its centre).
fn mv_arc_placeholder() -> Motion {
    Motion::Arc {
        clockwise: false,
        plane: Plane::XY,
        center_mm: [0.0; 3],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn find_turn_sweeps_in_the_direction_of_the_turn() {
        let c = [0.0, 0.0];
        // A quarter turn from +x to +y: +π/2 counter-clockwise, -3π/2 clockwise.
        assert!((find_turn([1.0, 0.0], c, 1, [0.0, 1.0]) - FRAC_PI_2).abs() < 1e-12);
        assert!((find_turn([1.0, 0.0], c, -1, [0.0, 1.0]) + 1.5 * PI).abs() < 1e-12);
        // Start = end: a full turn either way.
        assert!((find_turn([1.0, 0.0], c, 1, [1.0, 0.0]) - TAU).abs() < 1e-12);
        assert!((find_turn([1.0, 0.0], c, -1, [1.0, 0.0]) + TAU).abs() < 1e-12);
    }

    #[test]
    fn lathe_origin_moves_by_the_nose_radius_by_orientation() {
        let mut c = Comp::new(true, 0.5, 2, Plane::ZX, AxisVec::ZERO, AxisVec::ZERO, 1.0);
        // (a, b) = (Z, X): orientation 2 takes r off both X and Z.
        assert_eq!(c.lathe_origin([10.0, 4.0]), [9.5, 3.5]);
        c.orientation = 4;
        assert_eq!(c.lathe_origin([10.0, 4.0]), [10.5, 4.5]);
        c.orientation = 9;
        assert_eq!(c.lathe_origin([10.0, 4.0]), [10.0, 4.0]);
        c.plane = Plane::XY;
        c.orientation = 2;
        assert_eq!(c.lathe_origin([10.0, 4.0]), [10.0, 4.0]);
    }
}
