//! Splines G5 (cubic), G5.1 (quadratic) and NURBS G5.2/G5.3 (LinuxCNC), in the XY plane:
//! the exact curve the program describes, and its approximation by arcs and lines within
//! [`TOLERANCE`].
//!
//! Every spline is a NURBS of order `k` (degree `k − 1`) with control points `P_i`
//! (program X Y) and weights `w_i`, `i = 0..n`, as the LinuxCNC G-code reference defines
//! the three codes:
//!
//! ```text
//! G5.1 X Y I J     k = 3: P0 = start, P1 = start + (I, J), P2 = (X, Y), weights 1
//! G5   X Y I J P Q k = 4: P0 = start, P1 = start + (I, J), P2 = (X, Y) + (P, Q), P3 = (X, Y)
//! G5.2 X Y P L ... G5.3: the control points X Y with weight P, order L (default 3)
//! ```
//!
//! on the clamped uniform knot vector `t_j = 0` for `j < k`, `j − k + 1` for `k ≤ j ≤ n`,
//! `n − k + 2` after, so the curve starts on `P0`, ends on `P_n` and is one polynomial
//! (rational) piece per unit of `u ∈ [0, n − k + 2]`. With one span (G5, G5.1) it is the
//! Bézier curve of the control points. A point is evaluated in homogeneous coordinates
//! `(w x, w y, w)` by de Boor's recurrence on the span holding `u`, then divided by `w`.
//!
//! **Approximation.** Each knot span is cut into arcs, recursively: a parameter interval
//! `[u_a, u_b]` becomes the circular arc through `C(u_a)`, `C(u_m)` and `C(u_b)` (`u_m` the
//! middle), or the line `C(u_a) → C(u_b)` when the middle point lies within a quarter of the
//! tolerance of the chord, if the curve at seven interior samples lies within [`TOLERANCE`]
//! of that arc or line; otherwise the interval is halved. Consecutive pieces share their
//! end points (points of the curve), so the path is continuous; its tangent turns by at
//! most the small angle the tolerance allows at each join. The last piece ends exactly on
//! the last control point.

/// Largest distance, program units, of the exact curve from the arcs and lines that
/// approximate it (1 µm in G21).
pub const TOLERANCE: f64 = 1e-3;

/// Deepest halving of one knot span (2^20 pieces): beyond it a piece is taken as it is.
const MAX_DEPTH: u32 = 20;

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

/// The quadratic (G5.1) as a NURBS of order 3.
pub fn quadratic(start: [f64; 2], ij: [f64; 2], end: [f64; 2]) -> [ControlPoint; 3] {
    let p = |x: f64, y: f64| ControlPoint { x, y, w: 1.0 };
    [
        p(start[0], start[1]),
        p(start[0] + ij[0], start[1] + ij[1]),
        p(end[0], end[1]),
    ]
}

/// The cubic (G5) as a NURBS of order 4.
pub fn cubic(start: [f64; 2], ij: [f64; 2], end: [f64; 2], pq: [f64; 2]) -> [ControlPoint; 4] {
    let p = |x: f64, y: f64| ControlPoint { x, y, w: 1.0 };
    [
        p(start[0], start[1]),
        p(start[0] + ij[0], start[1] + ij[1]),
        p(end[0] + pq[0], end[1] + pq[1]),
        p(end[0], end[1]),
    ]
}

/// A NURBS curve of order `k` over its clamped uniform knot vector.
struct Curve<'a> {
    cps: &'a [ControlPoint],
    k: usize,
    knots: Vec<f64>,
}

impl<'a> Curve<'a> {
    fn new(cps: &'a [ControlPoint], k: usize) -> Curve<'a> {
        let n = cps.len() - 1;
        let knots = (0..=n + k)
            .map(|j| {
                if j < k {
                    0.0
                } else if j <= n {
                    (j - k + 1) as f64
                } else {
                    (n - k + 2) as f64
                }
            })
            .collect();
        Curve { cps, k, knots }
    }

    /// The parameter's range end, `n − k + 2`.
    fn u_max(&self) -> f64 {
        (self.cps.len() - self.k + 1) as f64
    }

    /// The point at `u` (de Boor's recurrence in homogeneous coordinates).
    fn at(&self, u: f64) -> [f64; 2] {
        let (k, t) = (self.k, &self.knots);
        let n = self.cps.len() - 1;
        // The span s with t_s ≤ u < t_{s+1}, k − 1 ≤ s ≤ n (the last span closed).
        let s = (k - 1..=n).rev().find(|&s| t[s] <= u).unwrap_or(k - 1);
        let mut d: Vec<[f64; 3]> = (0..k)
            .map(|j| {
                let p = self.cps[s + 1 - k + j];
                [p.x * p.w, p.y * p.w, p.w]
            })
            .collect();
        for r in 1..k {
            for j in (r..k).rev() {
                let i = s + 1 - k + j;
                let den = t[i + k - r] - t[i];
                let a = if den == 0.0 { 0.0 } else { (u - t[i]) / den };
                let prev = d[j - 1];
                for (c, lower) in d[j].iter_mut().zip(prev) {
                    *c = (1.0 - a) * lower + a * *c;
                }
            }
        }
        let h = d[k - 1];
        [h[0] / h[2], h[1] / h[2]]
    }
}

/// The spline of control points `cps` and order `k`, as arcs and lines from its first
/// control point to its last. Fewer than two points make no pieces; `k` is clamped to
/// `2..=cps.len()`.
pub fn pieces(cps: &[ControlPoint], k: usize) -> Vec<Piece> {
    if cps.len() < 2 {
        return Vec::new();
    }
    let k = k.clamp(2, cps.len());
    let curve = Curve::new(cps, k);
    let mut out = Vec::new();
    let spans = curve.u_max() as usize;
    for span in 0..spans {
        let (a, b) = (span as f64, (span + 1) as f64);
        approximate(&curve, a, curve.at(a), b, curve.at(b), 0, &mut out);
    }
    // The last piece ends exactly on the last control point.
    let last = cps[cps.len() - 1];
    if let Some(Piece::Line { end } | Piece::Arc { end, .. }) = out.last_mut() {
        *end = [last.x, last.y];
    }
    out
}

/// Appends the pieces for `[ua, ub]` of `curve` (`pa`, `pb` its end points).
fn approximate(
    curve: &Curve,
    ua: f64,
    pa: [f64; 2],
    ub: f64,
    pb: [f64; 2],
    depth: u32,
    out: &mut Vec<Piece>,
) {
    let um = 0.5 * (ua + ub);
    let pm = curve.at(um);
    let piece = fit(pa, pm, pb);
    let fits = depth >= MAX_DEPTH
        || (1..8)
            .filter(|&j| j != 4)
            .all(|j| deviation(&piece, pa, curve.at(ua + (ub - ua) * j as f64 / 8.0)) <= TOLERANCE);
    if fits {
        out.push(piece);
    } else {
        approximate(curve, ua, pa, um, pm, depth + 1, out);
        approximate(curve, um, pm, ub, pb, depth + 1, out);
    }
}

/// The arc from `a` through `m` to `b`, or the line `a → b` when `m` is within a quarter
/// of the tolerance of it.
fn fit(a: [f64; 2], m: [f64; 2], b: [f64; 2]) -> Piece {
    let (ab, am) = (sub(b, a), sub(m, a));
    let chord = norm(ab);
    let cross = ab[0] * am[1] - ab[1] * am[0];
    if chord == 0.0 || (cross / chord).abs() <= 0.25 * TOLERANCE {
        return Piece::Line { end: b };
    }
    // The centre solves |c − a| = |c − m| = |c − b|: with a at the origin,
    // 2 c·am = |am|², 2 c·ab = |ab|².
    let (l1, l2) = (dot(am, am), dot(ab, ab));
    let cx = (l1 * ab[1] - l2 * am[1]) / (2.0 * (am[0] * ab[1] - am[1] * ab[0]));
    let cy = (l2 * am[0] - l1 * ab[0]) / (2.0 * (am[0] * ab[1] - am[1] * ab[0]));
    Piece::Arc {
        end: b,
        center: [a[0] + cx, a[1] + cy],
        // m left of a → b: the arc bulges left, so it turns clockwise.
        ccw: cross < 0.0,
    }
}

/// Distance of `q` from `piece` (starting at `a`): from the segment, or from the arc (its
/// circle, or its nearer end when `q` lies outside its sweep).
fn deviation(piece: &Piece, a: [f64; 2], q: [f64; 2]) -> f64 {
    match *piece {
        Piece::Line { end } => {
            let d = sub(end, a);
            let l2 = dot(d, d);
            let s = if l2 == 0.0 {
                0.0
            } else {
                (dot(sub(q, a), d) / l2).clamp(0.0, 1.0)
            };
            norm(sub(q, [a[0] + s * d[0], a[1] + s * d[1]]))
        }
        Piece::Arc { end, center, ccw } => {
            let r = norm(sub(a, center));
            let sweep = turn(sub(a, center), sub(end, center), ccw);
            let at = turn(sub(a, center), sub(q, center), ccw);
            if at <= sweep {
                (norm(sub(q, center)) - r).abs()
            } else {
                norm(sub(q, a)).min(norm(sub(q, end)))
            }
        }
    }
}

/// The angle, rad in [0, 2π), from direction `from` to `to` turning counter-clockwise
/// (`ccw`) or clockwise.
fn turn(from: [f64; 2], to: [f64; 2], ccw: bool) -> f64 {
    let a = (from[0] * to[1] - from[1] * to[0]).atan2(dot(from, to));
    let a = if ccw { a } else { -a };
    a.rem_euclid(std::f64::consts::TAU)
}

fn sub(p: [f64; 2], q: [f64; 2]) -> [f64; 2] {
    [p[0] - q[0], p[1] - q[1]]
}

fn dot(p: [f64; 2], q: [f64; 2]) -> f64 {
    p[0] * q[0] + p[1] * q[1]
}

fn norm(p: [f64; 2]) -> f64 {
    p[0].hypot(p[1])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points along the pieces from `start`, `per` per piece (each arc walked by angle).
    fn walk(start: [f64; 2], pieces: &[Piece], per: usize) -> Vec<[f64; 2]> {
        let mut out = vec![start];
        let mut from = start;
        for p in pieces {
            for j in 1..=per {
                let s = j as f64 / per as f64;
                out.push(match *p {
                    Piece::Line { end } => [
                        from[0] + s * (end[0] - from[0]),
                        from[1] + s * (end[1] - from[1]),
                    ],
                    Piece::Arc { end, center, ccw } => {
                        let r = norm(sub(from, center));
                        let a0 = (from[1] - center[1]).atan2(from[0] - center[0]);
                        let sweep = turn(sub(from, center), sub(end, center), ccw);
                        let a = a0 + if ccw { s * sweep } else { -s * sweep };
                        [center[0] + r * a.cos(), center[1] + r * a.sin()]
                    }
                });
            }
            from = p.end();
        }
        out
    }

    /// Distance from `q` to the polyline `path`.
    fn to_path(q: [f64; 2], path: &[[f64; 2]]) -> f64 {
        path.windows(2)
            .map(|w| deviation(&Piece::Line { end: w[1] }, w[0], q))
            .fold(f64::INFINITY, f64::min)
    }

    /// Two-sided: every point of the pieces near the exact curve (sampled densely), and
    /// every sample of the curve near the pieces, within the tolerance (plus the polyline
    /// sampling error, under 1e-6 here).
    fn assert_within(exact: &dyn Fn(f64) -> [f64; 2], pieces: &[Piece]) {
        let curve: Vec<[f64; 2]> = (0..=5_000).map(|j| exact(j as f64 / 5_000.0)).collect();
        let path = walk(curve[0], pieces, 64);
        let slack = TOLERANCE + 1e-6;
        for q in &path {
            assert!(
                to_path(*q, &curve) <= slack,
                "piece point {q:?} off the curve"
            );
        }
        for q in curve.iter().step_by(97) {
            assert!(
                to_path(*q, &path) <= slack,
                "curve point {q:?} off the pieces"
            );
        }
        assert_eq!(pieces.last().unwrap().end(), curve[curve.len() - 1]);
    }

    /// Bernstein form of a Bézier curve, evaluated independently of de Boor's recurrence.
    fn bezier(p: &[[f64; 2]], s: f64) -> [f64; 2] {
        let n = p.len() - 1;
        let binom = |k: usize| (0..k).fold(1.0, |c, j| c * (n - j) as f64 / (j + 1) as f64);
        p.iter().enumerate().fold([0.0, 0.0], |acc, (k, q)| {
            let b = binom(k) * s.powi(k as i32) * (1.0 - s).powi((n - k) as i32);
            [acc[0] + b * q[0], acc[1] + b * q[1]]
        })
    }

    #[test]
    fn a_g5_cubic_follows_its_bezier_curve_within_the_tolerance() {
        let cps = cubic([0.0, 0.0], [5.0, -5.0], [40.0, 10.0], [-5.0, 5.0]);
        let p: Vec<[f64; 2]> = cps.iter().map(|c| [c.x, c.y]).collect();
        assert_within(&|s| bezier(&p, s), &pieces(&cps, 4));
        // An S-bend with an inflexion, and a tight loop-like hook.
        let cps = cubic([0.0, 0.0], [30.0, 30.0], [10.0, 0.0], [20.0, -30.0]);
        let p: Vec<[f64; 2]> = cps.iter().map(|c| [c.x, c.y]).collect();
        assert_within(&|s| bezier(&p, s), &pieces(&cps, 4));
    }

    #[test]
    fn a_g5_1_quadratic_follows_its_parabola_within_the_tolerance() {
        let cps = quadratic([0.0, 0.0], [10.0, 10.0], [20.0, 0.0]);
        // The parabola y = x (20 − x) / 20 from (0, 0) to (20, 0), with x = 20 s.
        assert_within(&|s| [20.0 * s, 20.0 * s * (1.0 - s)], &pieces(&cps, 3));
    }

    #[test]
    fn a_weighted_quadratic_is_a_circular_arc() {
        // Control points (1, 0), (1, 1), (0, 1) with weights 1, √2/2, 1: the quarter of the
        // unit circle, exactly; the pieces stay within the tolerance of radius 1.
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let cps = [
            ControlPoint {
                x: 1.0,
                y: 0.0,
                w: 1.0,
            },
            ControlPoint {
                x: 1.0,
                y: 1.0,
                w: h,
            },
            ControlPoint {
                x: 0.0,
                y: 1.0,
                w: 1.0,
            },
        ];
        let p = pieces(&cps, 3);
        for q in walk([1.0, 0.0], &p, 64) {
            assert!((norm(q) - 1.0).abs() <= TOLERANCE, "{q:?}");
        }
        assert_eq!(p.last().unwrap().end(), [0.0, 1.0]);
    }

    /// Cox-de Boor basis functions on the clamped uniform knots, written out for the test.
    fn basis(i: usize, k: usize, u: f64, t: &[f64], last: bool) -> f64 {
        if k == 1 {
            let inside = t[i] <= u && u < t[i + 1];
            // The curve's end belongs to the last non-empty span.
            return if inside
                || (last && u == t[i + 1] && t[i] < t[i + 1] && t[i + 1] == t[t.len() - 1])
            {
                1.0
            } else {
                0.0
            };
        }
        let left = if t[i + k - 1] > t[i] {
            (u - t[i]) / (t[i + k - 1] - t[i]) * basis(i, k - 1, u, t, last)
        } else {
            0.0
        };
        let right = if t[i + k] > t[i + 1] {
            (t[i + k] - u) / (t[i + k] - t[i + 1]) * basis(i + 1, k - 1, u, t, last)
        } else {
            0.0
        };
        left + right
    }

    #[test]
    fn a_nurbs_of_order_4_follows_its_rational_basis_sum_within_the_tolerance() {
        let cps: Vec<ControlPoint> = [
            (0.0, 0.0, 1.0),
            (6.0, 2.0, 2.0),
            (8.0, -1.0, 1.0),
            (10.0, 1.0, 3.0),
            (12.0, 0.0, 1.0),
        ]
        .map(|(x, y, w)| ControlPoint { x, y, w })
        .to_vec();
        // The knot vector is the curve's definition; the evaluation below is the test's own.
        let k = 4;
        let defined = Curve::new(&cps, k);
        let (t, u_max) = (defined.knots.clone(), defined.u_max());
        let exact = |s: f64| {
            let u = s * u_max;
            let (mut x, mut y, mut w) = (0.0, 0.0, 0.0);
            for (i, c) in cps.iter().enumerate() {
                let b = basis(i, k, u, &t, true) * c.w;
                x += b * c.x;
                y += b * c.y;
                w += b;
            }
            [x / w, y / w]
        };
        assert_within(&exact, &pieces(&cps, k));
    }

    #[test]
    fn a_straight_spline_is_one_line_per_span() {
        let cps = cubic([0.0, 0.0], [1.0, 1.0], [3.0, 3.0], [-1.0, -1.0]);
        assert_eq!(pieces(&cps, 4), [Piece::Line { end: [3.0, 3.0] }]);
        assert!(pieces(&cps[..1], 4).is_empty());
    }
}
