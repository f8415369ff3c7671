//! Bounds of a cutter position's least depth at its own θ (the envelope's `e_min`) without
//! the depth of every row: from the two end rows, the formula's rates along the rows, and
//! rigorous rounding margins.
//!
//! The rows lie on one line of the (ρ, z) half plane (the frustum's generatrix), within
//! `δ` of it. Along that chord, `P(λ) = P₀ + λ v` with λ the height above the
//! first row (0 ≤ λ ≤ L) and `v = ((ρ_N − ρ₀)/L cos θ, (ρ_N − ρ₀)/L sin θ, 1)` ([`Chord`]), the formula
//! of `geometry` in exact arithmetic on the frame's doubles (n, t, n·t, A, 1/A, R², tip) is
//!
//! ```text
//! w(λ) = w₀ + λ v                 B(λ) = B₀ + B₁ λ,   B₁ = v·n − (v·t)(n·t)
//! C(λ) = |w|² − (w·t)² − R²       C'(λ) / 2 = w·v − (w·t)(v·t)
//! D(λ) = B² − A C  (a quadratic)  q = D' / 2 = B B₁ − A (w·v − (w·t)(v·t))
//! f(λ) = (−B − √D) / A            f'(λ) = −(B₁ + q / √D) / A
//! ```
//!
//! Where D > 0 over the chord, f is convex or concave on all of it: √D of a quadratic is
//! convex when D = D₂ (λ − λ₀)² + k with D₂ ≥ 0, k ≥ 0, and concave otherwise (a circle's
//! arc, a hyperbola's branch off its roots, the root of an affine D), and B is affine. So
//! its least over [0, L] is at least the lesser of its ends or, when its slopes are negative
//! at 0 and positive at L, of the crossing of its two end tangents (below a convex function;
//! a concave one never has those slopes) — [`tangent_floor`]. The same holds for the
//! quadratic D itself, which shows D > 0 over the chord first.
//!
//! Every row's depth as computed, d̂ᵢ, is within `ε_d` of f at its height (for a row that
//! cuts; the others are [`NOT_CUT`], above any bound): with `S` the largest of `|w|₁` at the
//! ends plus `|p|₁ + R + δ` (every `|w|`, `|B|/2`, `√D / 3`, `A |d| / 5` and coordinate is
//! below it), a first-order count of the roundings (u = 2⁻⁵³: about 30 u S for B and 1/A,
//! about 130 u S² / √D through the discriminant and its root, the coordinates' own roundings
//! as a move of the row) and the row's move off the chord (`|∂d/∂w| ≤ 2 (|d| + |w|) / √D`)
//! gives
//!
//! ```text
//! ε_d ≤ (K u (S + S² / √D_low) + 12 S δ / √D_low) / A²,   K = 1024
//! ```
//!
//! K is some eight times the count, for the second-order terms; the rates B₁, q and the
//! slopes get margins of the same kind, and so does each bound's own arithmetic. The upper
//! bound is a row's own depth, as computed: the lesser of the end rows' and of the two rows
//! about the tangents' crossing. Where the bound cannot say (D not shown positive, no such
//! row cut, fewer than 3 rows), None: the caller computes every row.

use super::geometry::{greater, lesser, CutGeometry, CutterLine, Row, RowFrame, RowTerms, NOT_CUT};

/// The unit roundoff of f64, 2⁻⁵³.
const U: f64 = f64::EPSILON / 2.0;
/// The margins' factor over a first-order count of the roundings.
const K: f64 = 1024.0;

/// The rows' chord: from the first row to the last, its length L (mm of z) and slope
/// `(ρ_N − ρ₀) / L`, and how far (mm of ρ, at the same height) any row lies off it, with a
/// margin for that sum's own roundings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chord {
    pub length_mm: f64,
    pub radius_per_z: f64,
    pub offset_mm: f64,
}

impl Chord {
    /// The chord of `rows`; None for fewer than 3 rows, rows not rising in z, or ones not
    /// finite.
    pub fn of(rows: &[Row]) -> Option<Chord> {
        let (first, last) = (rows.first()?, rows.last()?);
        let length_mm = last.z_mm - first.z_mm;
        if rows.len() < 3 || !(length_mm > 0.0 && length_mm.is_finite()) {
            return None;
        }
        let radius_per_z = (last.radius_mm - first.radius_mm) / length_mm;
        let (mut offset, mut scale) = (0.0_f64, 0.0_f64);
        let mut previous = f64::NEG_INFINITY;
        for r in rows {
            if !(r.z_mm >= previous && r.radius_mm.is_finite()) {
                return None;
            }
            previous = r.z_mm;
            let rise = (r.z_mm - first.z_mm) * radius_per_z;
            offset = offset.max((r.radius_mm - (first.radius_mm + rise)).abs());
            scale = scale.max(first.radius_mm.abs() + rise.abs() + r.radius_mm.abs());
        }
        let offset_mm = 2.0 * offset + K * U * scale;
        (offset_mm.is_finite() && radius_per_z.is_finite()).then_some(Chord {
            length_mm,
            radius_per_z,
            offset_mm,
        })
    }
}

/// `(lower, upper)`, um, with `lower ≤ least(depths_um(θ, rows, line)) ≤ upper` and upper
/// finite (some row cuts), for `rows` of `chord` ([`Chord::of`]); None where the bound
/// cannot say. See the module's doc.
pub fn least_depth_bounds_um(
    geometry: &CutGeometry,
    theta: (f64, f64),
    rows: &[Row],
    chord: &Chord,
    line: &CutterLine,
) -> Option<(f64, f64)> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU has AVX, checked at run time just above.
        return unsafe { bounds_avx(geometry, theta, rows, chord, line) };
    }
    bounds_inline(geometry, theta, rows, chord, line)
}

/// [`least_depth_bounds_um`] compiled for AVX (its three-operand forms: fewer copies; Rust
/// fuses no multiplication and addition, so the rows' bits are the plain build's).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn bounds_avx(
    geometry: &CutGeometry,
    theta: (f64, f64),
    rows: &[Row],
    chord: &Chord,
    line: &CutterLine,
) -> Option<(f64, f64)> {
    bounds_inline(geometry, theta, rows, chord, line)
}

#[inline(always)]
fn bounds_inline(
    geometry: &CutGeometry,
    theta: (f64, f64),
    rows: &[Row],
    chord: &Chord,
    line: &CutterLine,
) -> Option<(f64, f64)> {
    let frame = RowFrame::new(geometry, theta, line)?;
    let (first, last) = (*rows.first()?, *rows.last()?);
    let (length, offset) = (chord.length_mm, chord.offset_mm);
    let (e0, e1) = (
        frame.terms(first.radius_mm, first.z_mm),
        frame.terms(last.radius_mm, last.z_mm),
    );
    if !(e0.disc > 0.0 && e1.disc > 0.0) {
        return None;
    }
    let v = (
        chord.radius_per_z * frame.c,
        chord.radius_per_z * frame.s,
        1.0,
    );
    let vt = dot(v, frame.t);
    let b1 = dot(v, frame.n) - vt * frame.nt;
    let q = |e: &RowTerms| e.b * b1 - frame.a * (dot(e.w, v) - e.wt * vt);
    let (q0, q1) = (q(&e0), q(&e1));
    let s = greater(l1(e0.w), l1(e1.w)) + l1(frame.tip) + geometry.cutter_radius_mm + offset;
    let v1 = l1(v);
    let err_disc = K * U * s * s + 16.0 * s * offset;
    let err_q = K * U * s * (b1.abs() + 2.0 * v1);
    // D over the chord, from its values and slopes 2q at the ends.
    let (d_floor, _) = tangent_floor((e0.disc, 2.0 * q0), (e1.disc, 2.0 * q1), length)?;
    let d_low = d_floor - 2.0 * err_disc - 2.0 * err_q * length;
    // Not shown positive (NaN included).
    if d_low.is_nan() || d_low <= 0.0 {
        return None;
    }
    let inv_root_low = 1.0 / d_low.sqrt();
    let inv_a2 = frame.inv_a * frame.inv_a;
    let err_d = (K * U * (s + s * s * inv_root_low) + 12.0 * s * offset * inv_root_low) * inv_a2;
    // f' at the ends: −(B₁ + q / √D) / A, both quotients from one division.
    let inv_roots = 1.0 / (e0.root * e1.root);
    let slope0 = -(b1 + q0 * e1.root * inv_roots) * frame.inv_a;
    let slope1 = -(b1 + q1 * e0.root * inv_roots) * frame.inv_a;
    let q_most = (greater(q0.abs(), q1.abs()) + err_q) * inv_root_low;
    let err_s = (K * U * (v1 + q_most)
        + err_q * inv_root_low
        + q_most * err_disc * inv_root_low * inv_root_low)
        * inv_a2
        + K * U * (slope0.abs() + slope1.abs());
    let (f_floor, crossing) = tangent_floor((e0.d, slope0), (e1.d, slope1), length)?;
    let lower_mm = f_floor - 2.0 * err_d - 2.0 * err_s * length;
    // The upper bound: rows' own depths, the ends' and the two about the crossing.
    let own = |e: &RowTerms| if e.cuts { e.d * 1e3 } else { NOT_CUT };
    let mut upper = lesser(own(&e0), own(&e1));
    if let Some(lambda) = crossing {
        let z = first.z_mm + lambda;
        let i = rows.partition_point(|r| r.z_mm < z).min(rows.len() - 1);
        for r in [rows[i.saturating_sub(1)], rows[i]] {
            upper = lesser(upper, frame.depth_um(r.radius_mm, r.z_mm));
        }
    }
    let lower = lower_mm * 1e3;
    (upper.is_finite() && lower.is_finite()).then_some((lower, upper))
}

/// A lower bound over [0, L] of a function convex or concave there, from its values y and
/// slopes at 0 and at L: the lesser of the ends, and where the slopes are negative at 0
/// and positive at L, the crossing of the two tangents (with λ of the crossing, clamped to
/// [0, L]), less a margin for this arithmetic (the crossing's λ rounded off by a few ulps
/// moves the tangent at 0 by at most `|s₀| Δλ`, and `|s₀| ≤ |s₀ − s₁|`). None when an input
/// is not finite.
#[inline(always)]
fn tangent_floor(
    (y0, s0): (f64, f64),
    (y1, s1): (f64, f64),
    length: f64,
) -> Option<(f64, Option<f64>)> {
    if !(y0.is_finite() && y1.is_finite() && s0.is_finite() && s1.is_finite()) {
        return None;
    }
    let mut floor = lesser(y0, y1);
    let mut crossing = None;
    if s0 < 0.0 && s1 > 0.0 {
        let lambda = ((y1 - y0 - s1 * length) / (s0 - s1)).clamp(0.0, length);
        floor = lesser(floor, y0 + s0 * lambda);
        crossing = Some(lambda);
    }
    let err = K * U * (y0.abs() + y1.abs() + (s0.abs() + s1.abs()) * length);
    Some((floor - err, crossing))
}

#[inline(always)]
fn dot(x: (f64, f64, f64), y: (f64, f64, f64)) -> f64 {
    x.0 * y.0 + x.1 * y.1 + x.2 * y.2
}

#[inline(always)]
fn l1(x: (f64, f64, f64)) -> f64 {
    x.0.abs() + x.1.abs() + x.2.abs()
}
