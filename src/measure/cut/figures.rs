//! What a CMM reports of the cut cone (ISO 12181-1, ISO 10791-7; `docs/cut.md`).
//!
//! At each evaluation height z the profile is the radius in the plane across the cone axis,
//! `r(θ) = ρ(z) + d(θ, z) / cos α` (d is measured along the normal, which leans α out of
//! that plane). Its least-squares circle (ISO 12181-1 LSCI), for an offset far below the
//! radius, is the linear least-squares fit of the limaçon
//!
//! ```text
//! r(θ) ≈ r₀ + a cos θ + b sin θ
//! ```
//!
//! (the circle's centre at (a, b), radius r₀; the neglected terms are of order e²/r, below
//! 10⁻⁶ um here). Roundness is the peak-to-valley of `r − (r₀ + a cos θ + b sin θ)`, the
//! diameter error `2 (r₀ − ρ(z))`. The cone angle error is the change of the half apex angle
//! the least-squares radii give across the heights: `atan(−dr₀/dz) − α` with `dr₀/dz` the
//! slope of the line fitted to (z, r₀). A reversal mark is the step of d across the
//! reversal's θ: lines fitted to d over [`MARK_FIT_DEG`] either side, leaving out
//! [`MARK_GAP_DEG`] about it, each taken at the reversal (as the ball bar's step).

use serde::{Deserialize, Serialize};

use super::envelope::Envelope;
use super::geometry::CutGeometry;
use crate::Axis;

/// Each side's fit of a reversal mark spans this much θ, deg.
pub const MARK_FIT_DEG: f64 = 3.0;
/// θ left out either side of the reversal, deg: the transition itself.
pub const MARK_GAP_DEG: f64 = 0.3;

/// The least-squares circle at one height.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HeightFigures {
    /// Height above the base circle along the cone axis, mm.
    pub z_mm: f64,
    /// Nominal radius ρ(z), mm.
    pub nominal_radius_mm: f64,
    /// Peak-to-valley radial deviation from the least-squares circle, um.
    pub roundness_um: f64,
    /// The circle's centre from the cone axis, cone frame x and y, um.
    pub centre_offset_um: [f64; 2],
    /// Twice the circle's radius less the nominal diameter, um.
    pub diameter_error_um: f64,
    /// Grid points of the profile that were cut.
    pub points: usize,
}

/// The step a reversal leaves on the surface.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mark {
    pub axis: String,
    pub theta_deg: f64,
    /// d after the reversal less d before it (in the cut's direction of travel), um, at
    /// `z_mm`.
    pub step_um: f64,
    pub z_mm: f64,
}

/// A profile's least-squares circle (limaçon form): `(r₀, a, b)` and the peak-to-valley
/// of the residual, from `(θ rad, r)` points; None below 3 points.
pub fn least_squares_circle(points: &[(f64, f64)]) -> Option<((f64, f64, f64), f64)> {
    if points.len() < 3 {
        return None;
    }
    // Normal equations of r = r0 + a cos θ + b sin θ, about the mean radius for precision.
    let mean = points.iter().map(|p| p.1).sum::<f64>() / points.len() as f64;
    let mut m = [[0.0; 3]; 3];
    let mut v = [0.0; 3];
    for &(theta, r) in points {
        let f = [1.0, theta.cos(), theta.sin()];
        for i in 0..3 {
            for k in 0..3 {
                m[i][k] += f[i] * f[k];
            }
            v[i] += f[i] * (r - mean);
        }
    }
    let [r0, a, b] = solve3(m, v)?;
    let fitted = |theta: f64| mean + r0 + a * theta.cos() + b * theta.sin();
    let (lo, hi) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            let e = p.1 - fitted(p.0);
            (lo.min(e), hi.max(e))
        });
    Some(((mean + r0, a, b), hi - lo))
}

/// Solves the 3×3 system `m x = v` (Cramer's rule); None when singular.
fn solve3(m: [[f64; 3]; 3], v: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&m);
    if d.abs() < 1e-12 {
        return None;
    }
    let mut x = [0.0; 3];
    for (c, xc) in x.iter_mut().enumerate() {
        let mut mc = m;
        for r in 0..3 {
            mc[r][c] = v[r];
        }
        *xc = det(&mc) / d;
    }
    Some(x)
}

/// The least-squares circle of row `i` of `envelope`.
pub fn height_figures(geometry: &CutGeometry, envelope: &Envelope, i: usize) -> HeightFigures {
    let row = envelope.rows[i];
    let points: Vec<(f64, f64)> = (0..envelope.column_count())
        .filter_map(|j| {
            let d = envelope.depth_um(j, i);
            d.is_finite().then(|| {
                let theta = (j as f64 * envelope.step_deg).to_radians();
                (theta, row.radius_mm + 1e-3 * d / geometry.cos_alpha())
            })
        })
        .collect();
    let (circle, roundness_mm) = match least_squares_circle(&points) {
        Some(fit) => fit,
        None => ((f64::NAN, f64::NAN, f64::NAN), f64::NAN),
    };
    let (r0, a, b) = circle;
    HeightFigures {
        z_mm: row.z_mm,
        nominal_radius_mm: row.radius_mm,
        roundness_um: roundness_mm * 1e3,
        centre_offset_um: [a * 1e3, b * 1e3],
        diameter_error_um: 2e3 * (r0 - row.radius_mm),
        points: points.len(),
    }
}

/// The half apex angle's error from the least-squares radii at the heights, urad: NaN
/// below two heights.
pub fn cone_angle_error_urad(geometry: &CutGeometry, heights: &[HeightFigures]) -> f64 {
    let points: Vec<(f64, f64)> = heights
        .iter()
        .filter(|h| h.diameter_error_um.is_finite())
        .map(|h| (h.z_mm, h.nominal_radius_mm + h.diameter_error_um * 0.5e-3))
        .collect();
    if points.len() < 2 {
        return f64::NAN;
    }
    let slope = line_fit(&points).map_or(f64::NAN, |(_, slope)| slope);
    ((-slope).atan() - geometry.alpha_rad) * 1e6
}

/// Least-squares line through `(x, y)` points: `(y at the mean x, slope)`, with the mean x.
fn line_fit(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| (my, sxy / sxx))
}

/// The step of row `i` across `theta_deg`, um, `sense` +1 when the cut ran to higher θ;
/// None when a side has fewer than 3 cut points.
pub fn step_at(envelope: &Envelope, i: usize, theta_deg: f64, sense: f64) -> Option<f64> {
    let count = envelope.column_count() as i64;
    let step = envelope.step_deg;
    let side = |from: f64, to: f64| -> Option<f64> {
        let lo = ((theta_deg + from) / step).ceil() as i64;
        let hi = ((theta_deg + to) / step).floor() as i64;
        let points: Vec<(f64, f64)> = (lo..=hi)
            .filter_map(|j| {
                let d = envelope.depth_um(j.rem_euclid(count) as usize, i);
                d.is_finite().then(|| (j as f64 * step - theta_deg, d))
            })
            .collect();
        if points.len() < 3 {
            return None;
        }
        let mx = points.iter().map(|p| p.0).sum::<f64>() / points.len() as f64;
        let (at_mean, slope) = line_fit(&points)?;
        Some(at_mean - slope * mx)
    };
    let below = side(-MARK_FIT_DEG, -MARK_GAP_DEG)?;
    let above = side(MARK_GAP_DEG, MARK_FIT_DEG)?;
    Some(sense * (above - below))
}

/// Every reversal's mark at row `i`.
pub fn marks(
    envelope: &Envelope,
    i: usize,
    reversals: &[(Axis, Vec<f64>)],
    sense: f64,
) -> Vec<Mark> {
    let mut marks: Vec<Mark> = reversals
        .iter()
        .flat_map(|(axis, angles)| angles.iter().map(move |&theta| (*axis, theta)))
        .filter_map(|(axis, theta_deg)| {
            step_at(envelope, i, theta_deg, sense).map(|step_um| Mark {
                axis: axis.to_string(),
                theta_deg,
                step_um,
                z_mm: envelope.rows[i].z_mm,
            })
        })
        .collect();
    marks.sort_by(|a, b| {
        a.theta_deg
            .total_cmp(&b.theta_deg)
            .then(a.axis.cmp(&b.axis))
    });
    marks
}
