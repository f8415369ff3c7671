//! Certified signed distance between a cylinder (a tool part) and a frustum (the cone
//! workpiece), without GJK: two bounds that must meet.
//!
//! Both shapes are solids of revolution. The frustum `F` has base centre `O`, unit axis `a`,
//! height `H` and radii `r0` (base) and `r1` (top); in the half plane of a point `x`,
//! `ζ = (x - O)·a`, `ρ = |x - O - ζ a|`, its cross-section is the trapezoid
//! `0 <= ζ <= H, 0 <= ρ <= r0 + (r1 - r0) ζ / H`, so the signed distance `sd_F(x)` of a point
//! is the 2-D signed distance of `(ζ, ρ)` to that trapezoid (closed form). The cylinder `C`
//! has centre `c`, unit axis `t`, half height `h` and radius `R`.
//!
//! The signed distance of the pair (clearance, or minus the penetration depth, i.e. the
//! minimum translation distance) is `sd = -min_{|n|=1} h_{C-F}(n)`, with the support
//! functions
//! `h_C(n) = n·c + h |n·t| + R sqrt(1 - (n·t)^2)` and
//! `h_F(w) = max_i (w·O_i + r_i sqrt(1 - (w·a)^2))` (`O_0 = O`, `O_1 = O + H a`).
//! Hence, for **any** unit `n`, `L(n) = -h_C(n) - h_F(-n) <= sd` (a separating-axis bound),
//! and for **any** point `x` of `C`, `U(x) = sd_F(x) >= sd` (a point of C is at least as
//! deep as C must be moved; apart, it is at least as far). The query alternates: `x` = the
//! point of lowest `sd_F` on the cylinder's flank line facing along `n` (closed form on the
//! frustum's lateral face, where `sd_F = m·(ζ, ρ) - m·(0, r0)` and `ρ(s)` is a hyperbola in
//! the line parameter; golden section otherwise), then `n` = minus the frustum's outward
//! normal at the point nearest `x`. It returns `L` once `U - L <=` [`CERTIFY_MM`], and
//! `None` otherwise (the caller then asks parry): what it returns is within `CERTIFY_MM` of
//! the exact signed distance, and never above it.

use parry3d_f64::math::Vector;

/// Largest gap between the bounds for a certified answer, mm.
pub const CERTIFY_MM: f64 = 1e-6;

/// Alternations before giving up (the caller falls back to GJK/EPA).
const MAX_ROUNDS: usize = 8;

/// The unit component of `v` perpendicular to unit `axis`, when it is long enough to have a
/// direction (a near-parallel `v` leaves only rounding noise, which is not perpendicular).
fn unit_across(v: Vector, axis: Vector) -> Option<Vector> {
    let p = v - axis * v.dot(axis);
    if p.length() <= 1e-9 * v.length() {
        return None;
    }
    let u = p.normalize();
    Some((u - axis * u.dot(axis)).normalize())
}

/// A frustum in its own frame: base centre, unit axis, height and radii (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    pub o: Vector,
    pub a: Vector,
    pub h: f64,
    pub r0: f64,
    pub r1: f64,
    /// A unit vector perpendicular to `a` (the radial direction of points on the axis).
    perp: Vector,
    /// Outward unit normal of the lateral side in the (ζ, ρ) plane, and `m·(0, r0)`.
    m: (f64, f64),
    m_offset: f64,
}

/// A cylinder: centre, unit axis, half height and radius (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cylinder {
    pub c: Vector,
    pub t: Vector,
    pub half_height: f64,
    pub radius: f64,
}

impl Frustum {
    /// The frustum between two coaxial circles (centres `o0`, `o1`, radii `r0`, `r1`, unit
    /// normal `n`), or `None` when they are not coaxial and parallel or do not span a height.
    pub fn from_circles(o0: Vector, r0: f64, o1: Vector, r1: f64, n: Vector) -> Option<Frustum> {
        let n = n.try_normalize()?;
        let d = o1 - o0;
        let h = d.dot(n);
        let tol = 1e-12 * (1.0 + o0.length() + o1.length());
        if h.abs() <= tol || (d - n * h).length() > tol || !(r0 >= 0.0 && r1 >= 0.0) {
            return None;
        }
        let (o, a, h, r0, r1) = if h > 0.0 {
            (o0, n, h, r0, r1)
        } else {
            (o1, -n, -h, r1, r0)
        };
        let perp = a.any_orthonormal_vector();
        let len = h.hypot(r1 - r0);
        let m = ((r0 - r1) / len, h / len);
        Some(Frustum {
            o,
            a,
            h,
            r0,
            r1,
            perp,
            m,
            m_offset: m.1 * r0,
        })
    }

    /// Unit `n` turned about the axis by the angle from point `from` to point `to` (their
    /// azimuths about the axis): `n_a a + (n·e) e' + (n·(a × e)) (a × e')`, with `e`, `e'`
    /// the unit radial directions of `from` and `to`. `n` itself when either is on the axis.
    pub fn turned(&self, n: Vector, from: Vector, to: Vector) -> Vector {
        // With the radial parts p, p' unnormalised: one square root for both lengths.
        let a = self.a;
        let (v, v2) = (from - self.o, to - self.o);
        let (p, p2) = (v - a * v.dot(a), v2 - a * v2.dot(a));
        let l2 = p.length_squared() * p2.length_squared();
        if !(l2 > 1e-36 * (1.0 + v.length_squared() * v2.length_squared())) {
            return n;
        }
        let k = 1.0 / l2.sqrt();
        a * n.dot(a) + (p2 * n.dot(p) + a.cross(p2) * n.dot(a.cross(p))) * k
    }

    /// Signed distance of point `x` to the frustum, mm (the value of [`Frustum::point_sd`]
    /// without its normal).
    pub fn point_sd_only(&self, x: Vector) -> f64 {
        let v = x - self.o;
        let z = v.dot(self.a);
        self.sd_2d(z, (v - self.a * z).length()).0
    }

    /// Signed distance of point `x` to the frustum, mm, and the outward unit normal of the
    /// nearest boundary feature.
    pub fn point_sd(&self, x: Vector) -> (f64, Vector) {
        let v = x - self.o;
        let z = v.dot(self.a);
        let radial = v - self.a * z;
        let rho = radial.length();
        let e = unit_across(v, self.a).unwrap_or(self.perp);
        let (sd, (nz, nr)) = self.sd_2d(z, rho);
        (sd, self.a * nz + e * nr)
    }

    /// Signed distance of `(ζ, ρ)` (ρ >= 0) to the trapezoid, and the outward normal there.
    fn sd_2d(&self, z: f64, rho: f64) -> (f64, (f64, f64)) {
        let (h, r0, r1) = (self.h, self.r0, self.r1);
        let lateral = self.m.0 * z + self.m.1 * rho - self.m_offset;
        if z >= 0.0 && z <= h && lateral <= 0.0 {
            // Inside: the nearest face.
            let mut best = (z, (-1.0, 0.0));
            if h - z < best.0 {
                best = (h - z, (1.0, 0.0));
            }
            if -lateral < best.0 {
                best = (-lateral, self.m);
            }
            return (-best.0, best.1);
        }
        // Outside: the nearest of the three edges of the half-plane boundary.
        let segments = [
            ((0.0, 0.0), (0.0, r0)),
            ((0.0, r0), (h, r1)),
            ((h, 0.0), (h, r1)),
        ];
        let mut best = (f64::INFINITY, (0.0, 0.0));
        for ((ax, ay), (bx, by)) in segments {
            let (dx, dy) = (bx - ax, by - ay);
            let l2 = dx * dx + dy * dy;
            let u = if l2 > 0.0 {
                (((z - ax) * dx + (rho - ay) * dy) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (px, py) = (z - (ax + u * dx), rho - (ay + u * dy));
            let d2 = px * px + py * py;
            if d2 < best.0 {
                best = (d2, (px, py));
            }
        }
        let d = best.0.sqrt();
        let normal = if d > 0.0 {
            (best.1 .0 / d, best.1 .1 / d)
        } else {
            self.m
        };
        (d, normal)
    }

    /// `h_F(w)`, the support function, for unit `w`.
    fn support(&self, w: Vector) -> f64 {
        let wa = w.dot(self.a);
        let s = (1.0 - wa * wa).max(0.0).sqrt();
        let base = w.dot(self.o);
        (base + self.r0 * s).max(base + wa * self.h + self.r1 * s)
    }
}

impl Cylinder {
    /// `h_C(n)` for unit `n`.
    fn support(&self, n: Vector) -> f64 {
        let nt = n.dot(self.t);
        n.dot(self.c) + self.half_height * nt.abs() + self.radius * (1.0 - nt * nt).max(0.0).sqrt()
    }
}

/// The separating-axis lower bound `L(n) = -h_C(n) - h_F(-n)` for unit `n` (C toward F).
fn lower_bound(f: &Frustum, c: &Cylinder, n: Vector) -> f64 {
    let n = n.normalize();
    -c.support(n) - f.support(-n)
}

/// Certified signed distance of cylinder `c` and frustum `f` (mm, within [`CERTIFY_MM`] and
/// never above it), with the unit direction from C toward F that certifies it; `None` when
/// the bounds do not meet (a rim or end face against a rim, say). `warm` is that direction
/// from a previous query of the pair, if any.
pub fn signed_distance(f: &Frustum, c: &Cylinder, warm: Option<Vector>) -> Option<(f64, Vector)> {
    let mut n = match warm.and_then(|w| w.try_normalize()) {
        Some(n) => n,
        None => -f.point_sd(c.c).1,
    };
    let mut best_lower = f64::NEG_INFINITY;
    let mut best_n = n;
    for _ in 0..MAX_ROUNDS {
        let lower = lower_bound(f, c, n);
        if lower > best_lower {
            (best_lower, best_n) = (lower, n);
        }
        // The flank line of C facing along n: x(s) = c + s t + R u, |s| <= half height.
        let u = unit_across(n, c.t)?;
        let base = c.c + u * c.radius;
        // Cheap bounds first (closed form and end points), then the refinements: golden
        // section along C's flank line, and the points of F on its generatrix facing C
        // (overlapping at a rim, a point of C is shallower than C must move; a rim point of
        // F is not).
        let (mut upper, mut normal) = line_minimum(f, base, c.t, c.half_height, false);
        let certified = |upper: f64, lower: f64, n: Vector| {
            let n = unit_across(n, c.t).map_or(lower, |a| lower.max(lower_bound(f, c, a)));
            upper - n.max(lower_bound(f, c, -normal)) <= CERTIFY_MM
        };
        if !certified(upper, best_lower, -normal) {
            upper = upper.min(generatrix_minimum(f, c, -n, false));
            if !certified(upper, best_lower, -normal) {
                let refined = line_minimum(f, base, c.t, c.half_height, true);
                if refined.0 < upper {
                    (upper, normal) = refined;
                }
                upper = upper.min(generatrix_minimum(f, c, -n, true));
            }
        }
        let n_next = -normal;
        // Also the nearest direction across the flank (n·t = 0), which is the exact one for
        // a contact inside the flank: off it, h_C grows by h |n·t|.
        let across = unit_across(n_next, c.t);
        for candidate in [Some(n_next), across].into_iter().flatten() {
            let lower = lower_bound(f, c, candidate);
            if lower > best_lower {
                (best_lower, best_n) = (lower, candidate);
            }
        }
        if upper - best_lower <= CERTIFY_MM {
            return Some((best_lower, best_n));
        }
        n = n_next;
    }
    None
}

/// Certified bounds `(L(n), U)` on the signed distance of cylinder `c` and frustum `f` from
/// one direction `n` (from C toward F), without the alternation: `L(n)` below, and above
/// `U = sd_F(x)` of C's point farthest along `n`, `x = c + h sign(n·t) t + R u` (`u` the
/// unit part of `n` across `t`). Both are certified for any `n`; they are tight when `n` is
/// near the certifying direction (a warm start). `None` for `n` along C's axis.
pub fn bounds(f: &Frustum, c: &Cylinder, n: Vector) -> Option<(f64, f64)> {
    let n = n.try_normalize()?;
    let nt = n.dot(c.t);
    let across = n - c.t * nt;
    let len = across.length();
    if len <= 1e-9 {
        return None;
    }
    let s = if nt >= 0.0 {
        c.half_height
    } else {
        -c.half_height
    };
    let x = c.c + c.t * s + across * (c.radius / len);
    Some((lower_bound(f, c, n), f.point_sd_only(x)))
}

/// Signed distance of point `y` to the cylinder: the 2-D box distance of (axial, radial).
fn cylinder_sd(c: &Cylinder, y: Vector) -> f64 {
    let v = y - c.c;
    let z = v.dot(c.t);
    let rho = (v - c.t * z).length();
    let (dz, dr) = (z.abs() - c.half_height, rho - c.radius);
    dz.max(dr).min(0.0) + dz.max(0.0).hypot(dr.max(0.0))
}

/// The smallest `sd_C` on the frustum's generatrix farthest along `w` (from the base rim to
/// the top rim): an upper bound on the pair's signed distance like any point of F, and the
/// one that certifies an overlap at a rim (`sd_C` is convex along the segment).
fn generatrix_minimum(f: &Frustum, c: &Cylinder, w: Vector, refine: bool) -> f64 {
    let Some(e) = unit_across(w, f.a) else {
        return f64::INFINITY;
    };
    let (p0, p1) = (f.o + e * f.r0, f.o + f.a * f.h + e * f.r1);
    let at = |s: f64| cylinder_sd(c, p0 + (p1 - p0) * s);
    let mut ends = at(0.0).min(at(1.0));
    // On C's flank, sd_C = (distance to C's axis) - R, least where the generatrix passes
    // nearest the axis: s = (b e - d·w) / (|d|² - b²), b = d·t, e = t·w, w = p0 - c.
    let (d, w) = (p1 - p0, p0 - c.c);
    let b = d.dot(c.t);
    let denom = d.dot(d) - b * b;
    if denom > 1e-12 * d.dot(d) {
        let s = ((b * c.t.dot(w) - d.dot(w)) / denom).clamp(0.0, 1.0);
        ends = ends.min(at(s));
    }
    match refine {
        true => golden(at, 0.0, 1.0, 1e-9).min(ends),
        false => ends,
    }
}

/// Minimum of a convex function on `[lo, hi]` by golden section, to `tol` in the argument.
fn golden(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64, tol: f64) -> f64 {
    const G: f64 = 0.618_033_988_749_894_8;
    let mut x1 = hi - G * (hi - lo);
    let mut x2 = lo + G * (hi - lo);
    let (mut f1, mut f2) = (f(x1), f(x2));
    while hi - lo > tol {
        if f1 <= f2 {
            hi = x2;
            (x2, f2) = (x1, f1);
            x1 = hi - G * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            (x1, f1) = (x2, f2);
            x2 = lo + G * (hi - lo);
            f2 = f(x2);
        }
    }
    f1.min(f2)
}

/// The smallest `sd_F` on the segment `base + s t`, `|s| <= h`, and the frustum's outward
/// normal nearest that point. `sd_F` is convex along a line (the signed distance to a
/// convex set); on the lateral face it is `m_ζ ζ(s) + m_ρ ρ(s) - m·(0, r0)` with `ζ` linear
/// and `ρ(s) = sqrt(A s² + 2 B s + C)`, whose stationary point solves
/// `A s + B = κ sqrt(D / (A - κ²))`, `κ = -m_ζ (t·a) / m_ρ`, `D = A C - B²`.
fn line_minimum(f: &Frustum, base: Vector, t: Vector, h: f64, refine: bool) -> (f64, Vector) {
    let at = |s: f64| f.point_sd(base + t * s);
    let mut best = at(-h);
    let mut best_s = -h;
    let end = at(h);
    if end.0 < best.0 {
        (best, best_s) = (end, h);
    }
    let v = base - f.o;
    let tau = t.dot(f.a);
    let r0 = v - f.a * v.dot(f.a);
    let tp = t - f.a * tau;
    let (a2, b, c2) = (tp.dot(tp), r0.dot(tp), r0.dot(r0));
    let kappa = -f.m.0 * tau / f.m.1;
    let mut interior = None;
    if a2 > kappa * kappa && a2 > 1e-15 {
        let d = (a2 * c2 - b * b).max(0.0);
        let s = (-b + kappa * (d / (a2 - kappa * kappa)).sqrt()) / a2;
        if s > -h && s < h {
            interior = Some(s);
        }
    }
    if let Some(s) = interior {
        let mid = at(s);
        if mid.0 < best.0 {
            (best, best_s) = (mid, s);
        }
    }
    // The closed form is exact where the lateral face is nearest; elsewhere (a rim or a
    // flat face nearest) refine by golden section on the convex function.
    let lateral_nearest = {
        let (nz, nr) = f.m;
        let normal = best.1;
        let x = base + t * best_s;
        let e = unit_across(x - f.o, f.a).unwrap_or(f.perp);
        (normal.dot(f.a) - nz).abs() < 1e-12 && (normal.dot(e) - nr).abs() < 1e-12
    };
    if lateral_nearest || !refine {
        return best;
    }
    let (mut lo, mut hi) = (-h, h);
    const G: f64 = 0.618_033_988_749_894_8;
    let mut x1 = hi - G * (hi - lo);
    let mut x2 = lo + G * (hi - lo);
    let (mut f1, mut f2) = (at(x1), at(x2));
    while hi - lo > 1e-7 {
        if f1.0 <= f2.0 {
            hi = x2;
            (x2, f2) = (x1, f1);
            x1 = hi - G * (hi - lo);
            f1 = at(x1);
        } else {
            lo = x1;
            (x1, f1) = (x2, f2);
            x2 = lo + G * (hi - lo);
            f2 = at(x2);
        }
    }
    for candidate in [f1, f2] {
        if candidate.0 < best.0 {
            best = candidate;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn upright() -> Frustum {
        Frustum::from_circles(
            Vector::new(0.0, 0.0, 0.0),
            50.0,
            Vector::new(0.0, 0.0, 40.0),
            30.0,
            Vector::Z,
        )
        .unwrap()
    }

    #[test]
    fn a_point_beside_the_lateral_face_is_at_its_perpendicular_distance() {
        let f = upright();
        // Lateral line from (0, 50) to (40, 30): unit normal (20, 40)/sqrt(2000).
        // (ζ, ρ) = (24, 42): (24, 42 - 50)·(20, 40)/√2000 past the line through (0, 50).
        let (sd, n) = f.point_sd(Vector::new(42.0, 0.0, 24.0));
        let expected = (24.0 * 20.0 - 8.0 * 40.0) / 2000f64.sqrt();
        assert!((sd - expected).abs() < 1e-12, "{sd} {expected}");
        assert!((n - Vector::new(40.0, 0.0, 20.0).normalize()).length() < 1e-12);
        // Inside, nearest the base.
        let (sd, n) = f.point_sd(Vector::new(0.0, 10.0, 1.0));
        assert!((sd + 1.0).abs() < 1e-12 && (n + Vector::Z).length() < 1e-12);
    }

    /// Deterministic pseudo-random numbers in [0, 1) (a 64-bit LCG).
    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn the_warm_bounds_hold_for_any_direction_and_meet_when_turned_with_the_pair() {
        // Cylinders lying near the flank (apart, touching, overlapping, tilted), all around
        // the axis. For any direction the bounds enclose the certified distance; for the
        // certifying direction of a pose, turned about the axis with the pair, they meet
        // on the turned pose (the frustum is symmetric: the distance is the same).
        let f = upright();
        let g = Vector::new(-20.0, 0.0, 40.0).normalize();
        let nrm = Vector::new(40.0, 0.0, 20.0).normalize();
        let mut rng = 7u64;
        let mut met = 0;
        for k in 0..400 {
            let gap = -0.5 + 3.0 * lcg(&mut rng);
            let tilt = 0.05 * (lcg(&mut rng) - 0.5);
            let along = 10.0 * (lcg(&mut rng) - 0.5);
            let t = (g + Vector::new(0.0, tilt, 0.3 * tilt)).normalize();
            let c = Cylinder {
                c: Vector::new(40.0, 0.0, 20.0) + g * along + nrm * (5.0 + gap),
                t,
                half_height: 10.0,
                radius: 5.0,
            };
            let Some((sd, n)) = signed_distance(&f, &c, None) else {
                continue;
            };
            // Any direction: a random one, and one near the certifying direction.
            let random = Vector::new(
                lcg(&mut rng) - 0.5,
                lcg(&mut rng) - 0.5,
                lcg(&mut rng) - 0.5,
            );
            let near = n + random * 0.01;
            for dir in [random, near, n] {
                if let Some((lo, hi)) = bounds(&f, &c, dir) {
                    assert!(lo <= sd + CERTIFY_MM + 1e-12, "{k}: lower {lo} > {sd}");
                    assert!(hi >= sd - 1e-12, "{k}: upper {hi} < {sd}");
                }
            }
            // The pair turned by an angle about the frustum's axis (z).
            let phi = std::f64::consts::TAU * lcg(&mut rng);
            let (sp, cp) = phi.sin_cos();
            let turn = |v: Vector| Vector::new(cp * v.x - sp * v.y, sp * v.x + cp * v.y, v.z);
            let turned_c = Cylinder {
                c: turn(c.c),
                t: turn(c.t),
                ..c
            };
            let (lo, hi) = bounds(&f, &turned_c, f.turned(n, c.c, turned_c.c)).unwrap();
            assert!(
                lo <= sd + CERTIFY_MM + 1e-9 && hi >= sd - 1e-9,
                "{k}: {lo} {hi} {sd}"
            );
            if hi - lo <= 1e-6 {
                met += 1;
            }
        }
        // Flank contacts certify from the carried direction at once (rim contacts need the
        // alternation, and the monitor then queries).
        assert!(met > 200, "met {met} of 400");
    }

    #[test]
    fn a_cylinder_lying_on_the_flank_touches_it() {
        let f = upright();
        // Generatrix at azimuth 0: from (50, 0, 0) to (30, 0, 40); outward normal (2, 0, 1)/√5.
        let g = Vector::new(-20.0, 0.0, 40.0).normalize();
        let nrm = Vector::new(40.0, 0.0, 20.0).normalize();
        for gap in [3.0, 0.0, -0.25] {
            let c = Cylinder {
                c: Vector::new(40.0, 0.0, 20.0) + nrm * (5.0 + gap),
                t: g,
                half_height: 10.0,
                radius: 5.0,
            };
            let (sd, _) = signed_distance(&f, &c, None).expect("certified");
            assert!((sd - gap).abs() < 1e-7, "{sd} vs {gap}");
        }
    }
}
