//! Corner blending between a straight block and a circular arc (LinuxCNC 2.9's planner,
//! measured as a black box: `tests/motion/linuxcnc_planner.rs`, docs/interpolation.md).
//!
//! A line along `u` ends at the corner `C` where an arc of centre `O`, radius `r` starts
//! (its tangent there `t`; an arc ending at `C` with a line leaving it is the same corner
//! walked backwards). Where the arc curves *away* from the turn (a left turn into a
//! clockwise arc, a right turn into a counter-clockwise one), LinuxCNC's blend is the circle
//! of the radius `R` the line-line rule ([`blend::corner`]) gives for the turn `θ` between
//! `u` and `t`, tangent to the line and, from outside, to the arc's circle:
//!
//! ```text
//! centre  B = C − d u + R n          (n: the line's normal toward the turn)
//! |B − O| = r + R   ⇒   d = w·u + sqrt((w·u)² − |w|² + (r + R)²),  w = C + R n − O
//! contact K = O + r (B − O)/|B − O|;  the arc gives up the angle β between C − O and K − O
//! ```
//!
//! The blend turns from `u` to the arc's tangent at `K` (`θ − β`). Measured (G64 at F800
//! on xyzac-trt): a 90° turn into arcs of radius 5, 10 and 20 mm at P0.05 passes 49.1,
//! 49.6, 49.9 um from the corner at 5.596 mm/s (this rule: 49.2, 49.6, 49.8 um, 5.600
//! mm/s), at P0.01 10.1 um at 2.495 mm/s, without P 553.9, 617.3, 656.7 um at 13.333.
//! Where the arc curves the same way as the turn, the blend lies inside the arc's circle
//! (touching it from inside, `|B − O| = r − R`) with a radius of its own
//! ([`same_way_radius`]): the turn is padded by a share of the arc's sweep, 1/6 into an arc
//! and 1/3 out of one. Measured: 90° turns into quarter arcs of radius 5 and 10 mm at F800
//! without P 227.5 and 455.0 um off (this rule: 227.3, 454.9), P0.05 32.5 um, line_into_arc's
//! arc into a line (26.6°, P0.05) 7.6 um at 8.373 mm/s. Arcs with a helix, a spiral, rotary
//! motion or under TCP are not blended, and under LinuxCNC's rules the planner stops there.
//!
//! Also measured, and applied by `interpolation` under LinuxCNC's rules: a circle's speed
//! holds `v²/r` within `√3/2` of the acceleration (circles of radius 0.2-2 mm peak at 259.7
//! mm/s² of 300), its path acceleration is what the centripetal term leaves (299.3 mm/s² at
//! 20 mm/s on r 20 mm: `sqrt(300² − 20²)`), a quarter of it on a program's last move (75).

use super::{blend, ArcGeometry, BlockPath, Held, Interpolator, Planned};
use crate::error::Result;
use crate::program::{Move, PathControl};
use crate::AxisVec;

/// A line-arc blend in the arc's plane: how much of the line and of the arc it takes, and
/// the blend arc from its start.
#[derive(Clone, Copy, Debug)]
pub(super) struct LineArc {
    /// Taken from the line (mm, along it from the corner).
    pub trim_line: f64,
    /// The angle the arc gives up at the corner (rad, ≥ 0).
    pub arc_turn: f64,
    /// The blend, from the line's tangent point (plane coordinates are axes `i0`, `i1`).
    pub bend: blend::Bend,
    pub length: f64,
}

type V2 = [f64; 2];

fn dot(a: V2, b: V2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

fn cross(a: V2, b: V2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// The arc's unit tangent at the point of unit radial direction `rho` (counter-clockwise
/// or not).
fn arc_tangent(rho: V2, ccw: bool) -> V2 {
    let s = if ccw { 1.0 } else { -1.0 };
    [-s * rho[1], s * rho[0]]
}

/// The share of an arc's sweep a same-way line-arc blend may pad its turn with, line into
/// arc and arc into line (measured, docs/interpolation.md).
pub(super) const PAD_LINE_INTO_ARC: f64 = 1.0 / 6.0;
pub(super) const PAD_ARC_INTO_LINE: f64 = 1.0 / 3.0;

/// The arc a line meets at a corner (plane coordinates): centre `o`, radius `r`,
/// counter-clockwise or not, its sweep (rad, ≥ 0: what a blend at its other end left of it;
/// measured, docs/interpolation.md) and the share of it a same-way blend pads its turn with
/// ([`PAD_LINE_INTO_ARC`], [`PAD_ARC_INTO_LINE`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct CornerArc {
    pub o: V2,
    pub r: f64,
    pub ccw: bool,
    pub sweep: f64,
    pub pad_share: f64,
}

/// The radius of a same-way line-arc blend (the arc curving the same way as the turn `θ`
/// between the line and its tangent at the corner), LinuxCNC's rule found black box: the
/// turn is padded by part of the arc, `pad = min(k · sweep, (π − θ)/4)`, the blend sized
/// for the turn `θe = θ + pad` (the tolerance, `P/(1/cos(θe/2) − 1)`; the speed,
/// [`blend::SpeedSizing::radius`]) and at most `r sin(pad/2)/tan(θe/2)`.
fn same_way_radius(
    theta: f64,
    arc: &CornerArc,
    tolerance: Option<f64>,
    speed: Option<(&blend::SpeedSizing, AxisVec, AxisVec)>,
) -> f64 {
    let pad = (arc.pad_share * arc.sweep).min(0.25 * (std::f64::consts::PI - theta));
    let turn = theta + pad;
    let mut radius = arc.r * (0.5 * pad).sin() / (0.5 * turn).tan();
    if let Some(tol) = tolerance {
        let half_cos = (0.5 * turn).cos();
        radius = radius.min(tol.max(0.0) * half_cos / (1.0 - half_cos));
    }
    if let Some((speed, u, n)) = speed {
        radius = radius.min(speed.radius(turn, u, n));
    }
    radius
}

/// The blend where a line along `u` (unit, plane coordinates) reaches the corner `c` at
/// which `arc` starts, taking at most `half_line` of the line and `half_arc` (mm) of the
/// arc, within `tolerance` and LinuxCNC's bound for speed (`speed`, its axes those of the
/// plane). Where the arc curves away from the turn, the blend has the line-line rule's
/// radius and touches the arc's circle from outside; where it curves the same way, the
/// radius of [`same_way_radius`] and it touches the circle from inside:
/// `|B − O| = r − R`, `d = w·u − sqrt((w·u)² − |w|² + (r − R)²)`. `None` where the corner
/// does not turn or turns back, or nothing fits.
pub(super) fn line_into_arc(
    u: V2,
    c: V2,
    arc: &CornerArc,
    half_line: f64,
    half_arc: f64,
    tolerance: Option<f64>,
    speed: Option<&blend::SpeedSizing>,
) -> Option<LineArc> {
    let (o, r, ccw) = (arc.o, arc.r, arc.ccw);
    let rho = [(c[0] - o[0]) / r, (c[1] - o[1]) / r];
    let t = arc_tangent(rho, ccw);
    let turn = cross(u, t);
    if turn == 0.0 || speed.is_none() && tolerance.is_none() {
        return None;
    }
    // Away: the arc curves against the turn (left turn into a clockwise arc).
    let away = (turn > 0.0) != ccw;
    let to_axes = |v: V2| {
        let mut a = AxisVec::ZERO;
        a.0[0] = v[0];
        a.0[1] = v[1];
        a
    };
    let (theta, normal) = blend::turn(to_axes(u), to_axes(t))?;
    let side = turn.signum();
    let n = [-side * u[1], side * u[0]];
    let mut radius = if away {
        let straight = blend::corner(
            to_axes(u),
            to_axes(t),
            f64::INFINITY,
            f64::INFINITY,
            tolerance,
            speed,
        )?;
        straight.bend.along.mixed_norm()
    } else {
        let speed = speed.map(|s| (s, to_axes(u), normal));
        same_way_radius(theta, arc, tolerance, speed)
    };
    if !(radius.is_finite() && radius > 1e-9) || !away && radius >= r {
        return None;
    }
    // The blend circle's centre B touches the arc's circle at |B − O| = r ± R.
    let sign = if away { 1.0 } else { -1.0 };
    let fit = |radius: f64| -> Option<(f64, f64, V2, V2)> {
        let w = [c[0] + radius * n[0] - o[0], c[1] + radius * n[1] - o[1]];
        let wu = dot(w, u);
        let centre_distance = r + sign * radius;
        let disc = wu * wu - dot(w, w) + centre_distance.powi(2);
        if !away && disc < 0.0 {
            return None;
        }
        let d = wu + sign * disc.max(0.0).sqrt();
        let b = [
            c[0] - d * u[0] + radius * n[0],
            c[1] - d * u[1] + radius * n[1],
        ];
        let ob = [b[0] - o[0], b[1] - o[1]];
        let rho_k = [ob[0] / centre_distance, ob[1] / centre_distance];
        let beta = cross(rho, rho_k).atan2(dot(rho, rho_k)).abs();
        (d > 0.0).then_some((d, beta, rho_k, b))
    };
    let fits = |radius: f64| {
        fit(radius).is_some_and(|(d, beta, ..)| d <= half_line && r * beta <= half_arc)
    };
    if !fits(radius) {
        // Halve until it fits, then grow back by bisection to within 1e-9 relative.
        let mut hi = radius;
        while !fits(radius) {
            hi = radius;
            radius *= 0.5;
            if radius < 1e-9 {
                return None;
            }
        }
        while hi - radius > 1e-9 * hi {
            let mid = 0.5 * (radius + hi);
            if fits(mid) {
                radius = mid;
            } else {
                hi = mid;
            }
        }
    }
    let (d, beta, rho_k, _) = fit(radius)?;
    let t_k = arc_tangent(rho_k, ccw);
    let sweep = cross(u, t_k).abs().atan2(dot(u, t_k));
    if !(sweep > 1e-9) {
        return None;
    }
    Some(LineArc {
        trim_line: d,
        arc_turn: beta,
        bend: blend::Bend {
            along: to_axes(u) * radius,
            inward: to_axes(n) * radius,
            sweep_rad: sweep,
        },
        length: radius * sweep,
    })
}

/// `speed` with the axes of the plane `i0`, `i1` as its first two (plane coordinates).
fn in_plane(speed: &blend::SpeedSizing, i0: usize, i1: usize) -> blend::SpeedSizing {
    let mut axes = [None; 9];
    axes[0] = speed.axes[i0];
    axes[1] = speed.axes[i1];
    blend::SpeedSizing { axes, ..*speed }
}

/// Moves the plane components of `v` (axes 0, 1 of a `LineArc`) to axes `i0`, `i1`.
fn to_plane(v: AxisVec, i0: usize, i1: usize) -> AxisVec {
    let mut out = AxisVec::ZERO;
    out.0[i0] = v.0[0];
    out.0[i1] = v.0[1];
    out
}

/// The largest change of radius (mm) along an arc still taken as a circle here: a program's
/// end point rounded to its last digit (X17.071068 Y7.071068 on a circle of radius 10 about
/// the origin ends 3e-7 mm off it), which LinuxCNC blends as a circle (measured: a 45° arc so
/// written between two same-way corners, 250.1 and 426.4 µm off).
const CIRCLE_SLACK_MM: f64 = 1e-6;

/// The arc of `p` if it can be blended with a line: a circle in its plane (no spiral beyond
/// [`CIRCLE_SLACK_MM`], no helix or other axis moving), no TCP.
fn plain_arc(p: &Planned) -> Option<ArcGeometry> {
    let arc = p.path.arc?;
    let still = (0..9)
        .filter(|&i| i != arc.i0 && i != arc.i1)
        .all(|i| p.path.delta.0[i] == 0.0);
    (arc.dr.abs() <= CIRCLE_SLACK_MM && still && !p.path.tcp && p.path.bend.is_none())
        .then_some(arc)
}

/// A straight block of `p` in the plane `i0`, `i1` only, its unit direction there.
fn plane_line(p: &Planned, tangent: AxisVec, i0: usize, i1: usize) -> Option<V2> {
    let off_plane = (0..9)
        .filter(|&i| i != i0 && i != i1)
        .all(|i| p.path.delta.0[i] == 0.0);
    let ok = p.path.is_straight() && !p.path.tcp && p.length > 0.0 && off_plane;
    ok.then_some([tangent.0[i0], tangent.0[i1]])
}

impl<I: Iterator<Item = Result<Move>>> Interpolator<I> {
    /// Blends the corner between the held block `prev` and `next` when one is a line and
    /// the other an arc ([`line_into_arc`]): trims both, pushes `prev` and the blend, and
    /// returns `next` trimmed with its new start tangent. `Err` gives both back untouched.
    pub(super) fn blend_line_arc(
        &mut self,
        prev: Held,
        mut next: Planned,
        start: AxisVec,
        half: f64,
    ) -> std::result::Result<(Planned, AxisVec), (Held, Planned)> {
        let tolerance = match prev.planned.path_control {
            PathControl::Blend { tolerance_mm, .. } => {
                tolerance_mm.or(self.control.path_tolerance_mm)
            }
            _ => return Err((prev, next)),
        };
        let feed = |p: &Planned| p.programmed.is_finite();
        if !(feed(&prev.planned) && feed(&next)) {
            return Err((prev, next));
        }
        let speed = self.speed_sizing(&prev.planned);
        // Line into arc.
        if let (Some(arc), None) = (plain_arc(&next), prev.planned.path.arc) {
            let Some(u) = plane_line(&prev.planned, prev.end, arc.i0, arc.i1) else {
                return Err((prev, next));
            };
            let c = prev.planned.path.start + prev.planned.path.delta;
            let corner = [c.0[arc.i0], c.0[arc.i1]];
            let r = arc.r0;
            let corner_arc = CornerArc {
                o: [arc.c0, arc.c1],
                r,
                ccw: arc.sweep > 0.0,
                sweep: arc.sweep.abs(),
                pad_share: PAD_LINE_INTO_ARC,
            };
            let speed = speed.map(|s| in_plane(&s, arc.i0, arc.i1));
            let Some(b) = line_into_arc(
                u,
                corner,
                &corner_arc,
                prev.half,
                half,
                tolerance,
                speed.as_ref(),
            ) else {
                return Err((prev, next));
            };
            let mut p = prev.planned;
            p.path.delta = p.path.delta * ((p.length - b.trim_line) / p.length);
            p.length -= b.trim_line;
            let arc_start = p.path.start + p.path.delta;
            let signed = b.arc_turn * arc.sweep.signum();
            let trimmed = ArcGeometry {
                theta0: arc.theta0 + signed,
                sweep: arc.sweep - signed,
                ..arc
            };
            next.path.arc = Some(trimmed);
            next.length -= r * b.arc_turn;
            let (new_start, _) = next.path.end_tangents(next.length, &self.kinematics);
            let bend = blend::Bend {
                along: to_plane(b.bend.along, arc.i0, arc.i1),
                inward: to_plane(b.bend.inward, arc.i0, arc.i1),
                sweep_rad: b.bend.sweep_rad,
            };
            let blend = self.line_arc_block(&prev.planned, arc_start, bend, b.length);
            if p.length > 1e-9 {
                self.push(p, prev.start, prev.end);
            }
            self.push(blend, prev.end, new_start);
            return Ok((next, new_start));
        }
        // Arc into line: the same corner walked backwards.
        if let (Some(arc), None) = (plain_arc(&prev.planned), next.path.arc) {
            let Some(u2) = plane_line(&next, start, arc.i0, arc.i1) else {
                return Err((prev, next));
            };
            let c = next.path.start;
            let corner = [c.0[arc.i0], c.0[arc.i1]];
            let r = arc.r0;
            let back = [-u2[0], -u2[1]];
            let corner_arc = CornerArc {
                o: [arc.c0, arc.c1],
                r,
                ccw: arc.sweep < 0.0,
                sweep: arc.sweep.abs(),
                pad_share: PAD_ARC_INTO_LINE,
            };
            let speed = speed.map(|s| in_plane(&s, arc.i0, arc.i1));
            let Some(b) = line_into_arc(
                back,
                corner,
                &corner_arc,
                half,
                prev.half,
                tolerance,
                speed.as_ref(),
            ) else {
                return Err((prev, next));
            };
            let mut p = prev.planned;
            let signed = b.arc_turn * arc.sweep.signum();
            p.path.arc = Some(ArcGeometry {
                sweep: arc.sweep - signed,
                ..arc
            });
            p.length -= r * b.arc_turn;
            let (_, arc_end) = p.path.end_tangents(p.length, &self.kinematics);
            let k = p.path.at(1.0, &self.kinematics);
            // Backwards the blend ran from the line's point to K; forwards from K: its start
            // tangent is the arc's, its inward normal toward the same centre.
            let radius = b.bend.along.mixed_norm();
            let centre = to_plane(b.bend.inward, arc.i0, arc.i1)
                + c
                + to_plane(b.bend.along, arc.i0, arc.i1) * (-b.trim_line / radius);
            let bend = blend::Bend {
                along: arc_end * radius,
                inward: centre - k,
                sweep_rad: b.bend.sweep_rad,
            };
            next.path.start = next.path.start + start * b.trim_line;
            next.path.delta = next.path.delta * ((next.length - b.trim_line) / next.length);
            next.length -= b.trim_line;
            let blend = self.line_arc_block(&prev.planned, k, bend, b.length);
            if p.length > 1e-9 {
                self.push(p, prev.start, arc_end);
            }
            self.push(blend, arc_end, start);
            return Ok((next, start));
        }
        Err((prev, next))
    }

    /// The blend block: a curved block of `bend` from `start` at `prev`'s programmed speed.
    fn line_arc_block(
        &self,
        prev: &Planned,
        start: AxisVec,
        bend: blend::Bend,
        length: f64,
    ) -> Planned {
        let c = blend::Corner {
            trim: 0.0,
            bend,
            length,
            deviation: 0.0,
        };
        self.blend_block(prev, start, c)
    }
}

impl BlockPath {
    /// Under LinuxCNC's rules, a circular arc's (or helix's) exact bounds on `|dq/ds|`,
    /// `|d²q/ds²|`, `|d³q/ds³|` per axis: with `k = |sweep|/L` the plane axes have `r k`,
    /// `r k²`, `r k³`, the others `|Δ_i|/L`, 0, 0. Their centripetal and tangential parts are
    /// orthogonal, so an axis sees at most `hypot(q'' v², q' a)`: with the centripetal part
    /// within [`blend::NORMAL_SHARE`] of its acceleration and the path acceleration within
    /// what that leaves at the cruise speed (`interpolation`), at most all of it. `None` for
    /// a spiral (radius changing) or a TCP arc.
    pub(super) fn circle_bounds(&self, length: f64) -> Option<([f64; 9], [f64; 9], [f64; 9])> {
        let path = self;
        let arc = path.arc?;
        if path.tcp || path.bend.is_some() || arc.dr.abs() > CIRCLE_SLACK_MM || !(length > 0.0) {
            return None;
        }
        let k = arc.sweep.abs() / length;
        let (mut d1, mut d2, mut d3) = ([0.0; 9], [0.0; 9], [0.0; 9]);
        for i in 0..9 {
            if i == arc.i0 || i == arc.i1 {
                d1[i] = arc.r0 * k;
                d2[i] = arc.r0 * k * k;
                d3[i] = arc.r0 * k * k * k;
            } else {
                d1[i] = path.delta.0[i].abs() / length;
            }
        }
        Some((d1, d2, d3))
    }
}
