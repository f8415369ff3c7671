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
//! reversal's θ, read outside the whole take-up of the axis's lost motion
//! ([`super::take_up`]): lines fitted to d over [`MARK_FIT_DEG`] on the nearest windows
//! either side where the axis's lost motion has settled (at least [`MARK_GAP_DEG`] from the
//! reversal, and the cutter's reach past the take-up), each taken at the reversal (as the
//! ball bar's step), after less before in the direction of travel. A reversal across which
//! the axis's lost motion does not swing leaves no mark.

use serde::{Deserialize, Serialize};

use super::envelope::Envelope;
use super::geometry::CutGeometry;
use super::take_up::{settled_windows, swing, LostMotion, TakeUp, LEVEL_DEG};
use crate::Axis;

/// Each side's fit of a reversal mark spans this much θ, deg, where the lost motion has settled.
pub const MARK_FIT_DEG: f64 = 3.0;
/// θ left out either side of the reversal at least, deg (more where the take-up is longer).
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
    /// The axis that reverses there, or the axes joined by `+` (X, Y, Z, A, B, C order)
    /// where several reverse within [`COINCIDENT_DEG`].
    pub axis: String,
    pub theta_deg: f64,
    /// d after the reversal less d before it (in the cut's direction of travel), um, at
    /// `z_mm`.
    pub step_um: f64,
    pub z_mm: f64,
    /// Each named axis's lost motion taken up across the reversal, in the order of `axis`:
    /// µm for a linear axis, arcsec for a rotary one (`take_up::LostMotion`).
    pub lost_motion_um_or_arcsec: Vec<f64>,
    /// θ where the surface's level before the reversal was last read and where the level
    /// after it was first read, deg, in the direction of travel: the take-up between them.
    pub take_up_deg: [f64; 2],
}

impl Mark {
    /// Each named axis's lost motion, 3 decimals, comma-separated (µm, rotary arcsec).
    pub fn lost_motion_text(&self) -> String {
        self.lost_motion_um_or_arcsec
            .iter()
            .map(|v| format!("{v:.3}"))
            .collect::<Vec<_>>()
            .join(", ")
    }
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

/// The step of row `i` of `envelope` across the reversal at `theta_deg` whose take-up is
/// `take_up` (columns along the direction of travel `sense` from column `r`), um: a line
/// fitted to d over each settled window, both taken at the reversal, after less before.
/// None when a window has fewer than 3 cut points.
fn step_across(
    envelope: &Envelope,
    i: usize,
    theta_deg: f64,
    (r, sense): (i64, i64),
    take_up: &TakeUp,
) -> Option<f64> {
    let count = envelope.column_count() as i64;
    // The reversal's own θ, in columns along the travel from column r.
    let t0 = sense as f64 * (theta_deg / envelope.step_deg - r as f64);
    let level = |(from, to): (i64, i64)| -> Option<f64> {
        let points: Vec<(f64, f64)> = (from..=to)
            .filter_map(|t| {
                let j = (r + sense * t).rem_euclid(count) as usize;
                let d = envelope.depth_um(j, i);
                d.is_finite().then_some((t as f64 - t0, d))
            })
            .collect();
        if points.len() < 3 {
            return None;
        }
        let mx = points.iter().map(|p| p.0).sum::<f64>() / points.len() as f64;
        let (at_mean, slope) = line_fit(&points)?;
        Some(at_mean - slope * mx)
    };
    Some(level(take_up.after)? - level(take_up.before)?)
}

/// What the marks are read with: each axis's lost motion along the cut, the cutter's
/// clearance per column² (um, its reach past a take-up) and a length that turns a rotary
/// axis's lost motion into um on the surface (the bar's length L, mm).
pub struct MarkInputs<'a> {
    pub lost_motion: &'a LostMotion,
    pub clearance_per_column2_um: f64,
    pub lever_mm: f64,
}

/// Reversals of different axes closer than this, deg, make one mark: their take-ups overlap,
/// and the surface shows one step.
pub const COINCIDENT_DEG: f64 = 2.0;

/// One axis's reversal that takes up lost motion: its column, its take-up and its swing.
struct Reversal {
    axis: Axis,
    theta_deg: f64,
    r: i64,
    take_up: TakeUp,
}

/// Every reversal's mark at row `i`, `sense` +1 when the cut ran to higher θ: the reversals
/// whose axis's lost motion swings across them ([`swing`]), each the step of d between the
/// levels either side of the whole take-up ([`settled_windows`]). Reversals of several axes
/// within [`COINCIDENT_DEG`] make one mark, named by all of them, read outside all their
/// take-ups.
pub fn marks(
    envelope: &Envelope,
    i: usize,
    reversals: &[(Axis, Vec<f64>)],
    sense: f64,
    inputs: &MarkInputs<'_>,
) -> Vec<Mark> {
    let step = envelope.step_deg;
    let columns = |deg: f64| (deg / step).round() as i64;
    let sense = if sense < 0.0 { -1 } else { 1 };
    let window = columns(MARK_FIT_DEG);
    let mut found: Vec<Reversal> = Vec::new();
    for (axis, angles) in reversals {
        for &theta_deg in angles {
            // Half the way to the axis's nearest other reversal, at most LEVEL_DEG.
            let nearest = angles
                .iter()
                .filter(|&&o| o != theta_deg)
                .map(|&o| {
                    let d = (o - theta_deg).rem_euclid(360.0);
                    d.min(360.0 - d)
                })
                .fold(2.0 * LEVEL_DEG, f64::min);
            let level_columns = columns(0.5 * nearest);
            let r = columns(theta_deg);
            let Some(swing) = swing(inputs.lost_motion, *axis, r, sense, level_columns) else {
                continue;
            };
            // The cutter's reach past a take-up of this size: κ m² = the step's bound.
            let lever_um = if axis.is_rotary() {
                1e3 * inputs.lever_mm * std::f64::consts::PI / 180.0
            } else {
                1e3
            };
            let margin = match inputs.clearance_per_column2_um {
                k if k > 0.0 => (swing.abs() * lever_um / k).sqrt().ceil() as i64,
                _ => 0,
            };
            let windows = (columns(MARK_GAP_DEG).max(1), window, margin);
            let lost = inputs.lost_motion;
            if let Some(take_up) =
                settled_windows(lost, *axis, (r, sense), (level_columns, swing), windows)
            {
                found.push(Reversal {
                    axis: *axis,
                    theta_deg,
                    r,
                    take_up,
                });
            }
        }
    }
    found.sort_by(|a, b| a.theta_deg.total_cmp(&b.theta_deg));
    let mut marks = Vec::new();
    for group in coincident(&found) {
        let first = &found[group[0]];
        let r = first.r;
        // Each take-up's windows about the group's column: the levels are read outside all.
        let before_end = group
            .iter()
            .map(|&k| found[k].take_up.before.1 + sense * (found[k].r - r))
            .min()
            .unwrap_or(0);
        let after_start = group
            .iter()
            .map(|&k| found[k].take_up.after.0 + sense * (found[k].r - r))
            .max()
            .unwrap_or(0);
        let take_up = TakeUp {
            before: (before_end - window, before_end),
            after: (after_start, after_start + window),
            swing: first.take_up.swing,
        };
        let Some(step_um) = step_across(envelope, i, first.theta_deg, (r, sense), &take_up) else {
            continue;
        };
        let theta_at = |t: i64| ((r + sense * t) as f64 * step).rem_euclid(360.0);
        let mut axes: Vec<&Reversal> = group.iter().map(|&k| &found[k]).collect();
        axes.sort_by_key(|v| v.axis as usize);
        marks.push(Mark {
            axis: axes
                .iter()
                .map(|v| v.axis.to_string())
                .collect::<Vec<_>>()
                .join("+"),
            theta_deg: first.theta_deg,
            step_um,
            z_mm: envelope.rows[i].z_mm,
            lost_motion_um_or_arcsec: axes
                .iter()
                .map(|v| v.take_up.swing.abs() * if v.axis.is_rotary() { 3600.0 } else { 1e3 })
                .collect(),
            take_up_deg: [theta_at(before_end), theta_at(after_start)],
        });
    }
    marks
}

/// The reversals of `found` (sorted by θ) in groups whose neighbours lie within
/// [`COINCIDENT_DEG`] (round the circle too), as indices.
fn coincident(found: &[Reversal]) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (k, v) in found.iter().enumerate() {
        match groups.last_mut() {
            Some(g) if v.theta_deg - found[*g.last().unwrap()].theta_deg <= COINCIDENT_DEG => {
                g.push(k)
            }
            _ => groups.push(vec![k]),
        }
    }
    // The last group joins the first across 360°.
    if groups.len() > 1 {
        let (first, last) = (groups[0][0], *groups.last().unwrap().last().unwrap());
        if found[first].theta_deg + 360.0 - found[last].theta_deg <= COINCIDENT_DEG {
            let tail = groups.pop().unwrap();
            groups[0].splice(0..0, tail);
        }
    }
    groups
}
