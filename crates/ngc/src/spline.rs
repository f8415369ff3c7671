//! Splines G5 (cubic), G5.1 (quadratic) and NURBS G5.2/G5.3 (LinuxCNC), in the XY plane,
//! turned into arcs and lines as LinuxCNC's motion canon does (`emccanon.cc`
//! `NURBS_FEED`, with `nurbs_additional_functions.cc`).
//!
//! Every spline is a NURBS of order `k` (degree `k - 1`) with control points `P_i`
//! (program X Y) and weights `w_i`, `i = 0..n`:
//!
//! ```text
//! G5.1 X Y I J     k = 3: P0 = start, P1 = start + (I, J), P2 = (X, Y), weights 1
//! G5   X Y I J P Q k = 4: P0 = start, P1 = start + (I, J), P2 = (X, Y) + (P, Q), P3 = (X, Y);
//!                  I J may be left out after a G5: then P1 = start - (P, Q) of that G5
//! G5.2 X Y P L ... G5.3: the control points X Y with weight P, order L (default 3)
//! ```
//!
//! The knot vector is clamped and uniform: `t_j = 0` for `j < k`, `j - k + 1` for
//! `k <= j <= n`, `n - k + 2` after, so `u` runs over `[0, u_max]`, `u_max = n - k + 2`;
//! the point is `C(u) = sum N_ik(u) w_i P_i / sum N_ik(u) w_i` with Cox-de Boor basis
//! functions (LinuxCNC's `Nmix`, whose degree-0 spans are closed on both ends; the division
//! by the weight sum makes that harmless). The tangent is a central difference over
//! `u ± 1e-5`, clamped to `[0, u_max]`, made unit.
//!
//! The curve is cut at `4 (n + 1)` equal steps of `u`; each step from `C(u_a)` to `C(u_b)`
//! with unit tangents `t_s`, `t_e` becomes a **biarc**: two arcs meeting at `p2` with a
//! common tangent, the first tangent to `t_s` at the start, the second to `t_e` at the end
//! (equal arm lengths, LinuxCNC's `r = 1`):
//!
//! ```text
//! v = p0 - p4,  c = v·v,  b = 2 v·(t_s + t_e),  a = 2 (t_s·t_e - 1)
//! beta = the larger root of a beta² + b beta + c = 0,  alpha = beta
//! p1 = p0 + alpha t_s,  p3 = p4 - beta t_e,  p2 = (p1 + p3) / 2
//! ```
//!
//! An arc from `p` to `q` tangent to `d` at `p` has its centre at
//! `p + r (d_y, -d_x)` with `r = -|q - p|² / (2 ((q - p)_y d_x - (q - p)_x d_y))`, counter-
//! clockwise when `r < 0`; when the denominator is below 1e-6 (program units) it is a line.
//! Where LinuxCNC finds no biarc (negative discriminant, or both roots positive) it
//! emits nothing for that step; mtsim feeds a straight line there so that the path stays
//! continuous. The last piece ends exactly on the last control point.

/// A control point: program X Y and weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlPoint {
    pub x: f64,
    pub y: f64,
    pub w: f64,
}

/// One canonical piece of a spline, program coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Piece {
    Line {
        end: [f64; 2],
    },
    Arc {
        end: [f64; 2],
        center: [f64; 2],
        ccw: bool,
    },
}

impl Piece {
    pub fn end(&self) -> [f64; 2] {
        match *self {
            Piece::Line { end } | Piece::Arc { end, .. } => end,
        }
    }
}

fn knot_vector(n: usize, k: usize) -> Vec<f64> {
    (0..=n + k)
        .map(|i| {
            if i < k {
                0.0
            } else if i <= n {
                (i + 1 - k) as f64
            } else {
                (n + 2 - k) as f64
            }
        })
        .collect()
}

/// Cox-de Boor basis function `N_{i,k}(u)` as LinuxCNC's `Nmix`.
fn nmix(i: usize, k: usize, u: f64, t: &[f64]) -> f64 {
    if k == 1 {
        return if u >= t[i] && u <= t[i + 1] { 1.0 } else { 0.0 };
    }
    let left = t[i + k - 1] - t[i];
    let right = t[i + k] - t[i + 1];
    match (left == 0.0, right == 0.0) {
        (true, true) => 0.0,
        (true, false) => (t[i + k] - u) * nmix(i + 1, k - 1, u, t) / right,
        (false, true) => (u - t[i]) * nmix(i, k - 1, u, t) / left,
        (false, false) => {
            (u - t[i]) * nmix(i, k - 1, u, t) / left
                + (t[i + k] - u) * nmix(i + 1, k - 1, u, t) / right
        }
    }
}

fn point(u: f64, k: usize, cps: &[ControlPoint], t: &[f64]) -> [f64; 2] {
    let n: Vec<f64> = (0..cps.len()).map(|i| nmix(i, k, u, t)).collect();
    let den: f64 = cps.iter().zip(&n).map(|(c, n)| n * c.w).sum();
    let (mut x, mut y) = (0.0, 0.0);
    for (c, n) in cps.iter().zip(&n) {
        x += c.x * n * c.w / den;
        y += c.y * n * c.w / den;
    }
    [x, y]
}

fn unit(v: [f64; 2]) -> [f64; 2] {
    let h = v[0].hypot(v[1]);
    if h != 0.0 {
        [v[0] / h, v[1] / h]
    } else {
        v
    }
}

fn tangent(u: f64, k: usize, cps: &[ControlPoint], t: &[f64]) -> [f64; 2] {
    const DU: f64 = 1e-5;
    let umax = (cps.len() + 1 - k) as f64;
    let (lo, hi) = ((u - DU).max(0.0), (u + DU).min(umax));
    let (p1, p3) = (point(lo, k, cps, t), point(hi, k, cps, t));
    unit([(p3[0] - p1[0]) / (hi - lo), (p3[1] - p1[1]) / (hi - lo)])
}

/// The arc from `p0` to `p1` tangent to `d` at `p0`, or a line.
fn arc(p0: [f64; 2], p1: [f64; 2], d: [f64; 2]) -> Piece {
    let (x, y) = (p1[0] - p0[0], p1[1] - p0[1]);
    let den = 2.0 * (y * d[0] - x * d[1]);
    if den.abs() > 1e-6 {
        let r = -(x * x + y * y) / den;
        Piece::Arc {
            end: p1,
            center: [p0[0] + d[1] * r, p0[1] - d[0] * r],
            ccw: r < 0.0,
        }
    } else {
        Piece::Line { end: p1 }
    }
}

fn biarc(p0: [f64; 2], ts: [f64; 2], p4: [f64; 2], te: [f64; 2], out: &mut Vec<Piece>) {
    let (ts, te) = (unit(ts), unit(te));
    let (vx, vy) = (p0[0] - p4[0], p0[1] - p4[1]);
    let c = vx * vx + vy * vy;
    let b = 2.0 * (vx * (ts[0] + te[0]) + vy * (ts[1] + te[1]));
    let a = 2.0 * (ts[0] * te[0] + ts[1] * te[1] - 1.0);
    let discr = b * b - 4.0 * a * c;
    let fallback = |out: &mut Vec<Piece>| out.push(Piece::Line { end: p4 });
    if discr < 0.0 {
        return fallback(out);
    }
    let disq = discr.sqrt();
    let (beta1, beta2) = ((-b - disq) / 2.0 / a, (-b + disq) / 2.0 / a);
    if (beta1 > 0.0 && beta2 > 0.0) || !beta1.is_finite() || !beta2.is_finite() {
        return fallback(out);
    }
    let beta = beta1.max(beta2);
    let alpha = beta;
    let ab = alpha + beta;
    let p1 = [p0[0] + alpha * ts[0], p0[1] + alpha * ts[1]];
    let p3 = [p4[0] - beta * te[0], p4[1] - beta * te[1]];
    let p2 = [
        (p1[0] * beta + p3[0] * alpha) / ab,
        (p1[1] * beta + p3[1] * alpha) / ab,
    ];
    if !(p2[0].is_finite() && p2[1].is_finite()) {
        return fallback(out);
    }
    let tm = unit([p3[0] - p2[0], p3[1] - p2[1]]);
    out.push(arc(p0, p2, ts));
    out.push(arc(p2, p4, tm));
}

/// The pieces of the NURBS of order `k` over `cps` (at least `k` points, `k >= 2`).
pub fn pieces(cps: &[ControlPoint], k: usize) -> Vec<Piece> {
    let n = cps.len() - 1;
    let umax = (n + 2 - k) as f64;
    let div = cps.len() * 4;
    let t = knot_vector(n, k);
    let mut out = Vec::with_capacity(2 * div);
    let mut p0 = point(0.0, k, cps, &t);
    let mut t0 = tangent(0.0, k, cps, &t);
    for i in 1..=div {
        let u = umax * i as f64 / div as f64;
        let p1 = if i == div {
            [cps[n].x, cps[n].y]
        } else {
            point(u, k, cps, &t)
        };
        let t1 = tangent(u, k, cps, &t);
        biarc(p0, t0, p1, t1, &mut out);
        p0 = p1;
        t0 = t1;
    }
    out
}

/// The control points of `G5.1`: start, start + (I, J), end.
pub fn quadratic(start: [f64; 2], ij: [f64; 2], end: [f64; 2]) -> [ControlPoint; 3] {
    let cp = |x, y| ControlPoint { x, y, w: 1.0 };
    [
        cp(start[0], start[1]),
        cp(start[0] + ij[0], start[1] + ij[1]),
        cp(end[0], end[1]),
    ]
}

/// The control points of `G5`: start, start + (I, J), end + (P, Q), end.
pub fn cubic(start: [f64; 2], ij: [f64; 2], end: [f64; 2], pq: [f64; 2]) -> [ControlPoint; 4] {
    let cp = |x, y| ControlPoint { x, y, w: 1.0 };
    [
        cp(start[0], start[1]),
        cp(start[0] + ij[0], start[1] + ij[1]),
        cp(end[0] + pq[0], end[1] + pq[1]),
        cp(end[0], end[1]),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance from the point at parameter `s` of the quadratic Bezier (which G5.1 is).
    fn bezier2(p: &[ControlPoint; 3], s: f64) -> [f64; 2] {
        let (a, b, c) = ((1.0 - s) * (1.0 - s), 2.0 * s * (1.0 - s), s * s);
        [
            a * p[0].x + b * p[1].x + c * p[2].x,
            a * p[0].y + b * p[1].y + c * p[2].y,
        ]
    }

    #[test]
    fn the_nurbs_of_a_g5_1_is_its_quadratic_bezier() {
        let cps = quadratic([0.0, 0.0], [5.0, 5.0], [10.0, 0.0]);
        let t = knot_vector(2, 3);
        for s in [0.0, 0.1, 0.25, 0.5, 0.9, 1.0] {
            let p = point(s, 3, &cps, &t);
            let q = bezier2(&cps, s);
            assert!(
                (p[0] - q[0]).abs() < 1e-12 && (p[1] - q[1]).abs() < 1e-12,
                "{s}"
            );
        }
    }

    #[test]
    fn biarcs_are_continuous_and_stay_within_a_small_fraction_of_the_curve() {
        let cps = quadratic([0.0, 0.0], [5.0, 5.0], [10.0, 0.0]);
        let pieces = pieces(&cps, 3);
        // 12 steps, two arcs each (the apex step is symmetric but still two arcs).
        assert_eq!(pieces.len(), 24);
        assert_eq!(pieces.last().unwrap().end(), [10.0, 0.0]);
        // Each arc's end lies on the circle through its start: radius at start = at end.
        let mut start = [0.0, 0.0];
        for p in &pieces {
            if let Piece::Arc { end, center, .. } = *p {
                let r0 = (start[0] - center[0]).hypot(start[1] - center[1]);
                let r1 = (end[0] - center[0]).hypot(end[1] - center[1]);
                assert!((r0 - r1).abs() < 1e-9 * r0.max(1.0));
            }
            // Every piece end is within 0.01 of the parabola y = x - x²/10 (the Bezier).
            let e = p.end();
            assert!((e[1] - (e[0] - e[0] * e[0] / 10.0)).abs() < 1e-2, "{e:?}");
            start = p.end();
        }
    }

    #[test]
    fn a_straight_cubic_is_cut_into_lines() {
        let cps = cubic([0.0, 0.0], [1.0, 0.0], [4.0, 0.0], [-1.0, 0.0]);
        let pieces = pieces(&cps, 4);
        assert!(pieces.iter().all(|p| matches!(p, Piece::Line { .. })));
        assert_eq!(pieces.last().unwrap().end(), [4.0, 0.0]);
    }
}
