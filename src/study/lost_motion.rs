//! A study point's reversal value B per axis, for `mtsim study`'s `B_<axis>_um` columns,
//! from the counterfactual run every simulation makes beside the full one: the same
//! setpoints through each axis's linear twin (its drive without backlash, dry friction and
//! pre-sliding). The run's nonlinear signature `dL_nl = dL − dL_twin` is therefore the bar's
//! view of the machine's lost motion alone: not the cone's own path, not the lag, not the
//! geometric errors. `simulate` gives B from the error budget's per-axis lost-motion runs
//! (`study::budget`), which a study's shared passes do not run; both fit the same model to
//! a curve of lost motion alone, and agree within half a µm (tests/study/budget.rs).
//!
//! # B per axis (ISO 230-2 reversal value, as the bar sees it)
//!
//! Away from a reversal of axis a, its lost motion δ_a holds the table half of δ_a behind
//! the twin in the direction of motion, so the signature is
//!
//! ```text
//! dL_nl(θ) ≈ Σ_a −(δ_a/2) sgn(v_a(θ)) S_a(θ),     S_a = ∂L/∂q_a at the commanded pose
//! ```
//!
//! over the lost-motion axes a (backlash, or dry friction on a cascade drive). On a circle
//! each term jumps only where its axis reverses; on a cone `S_a` itself swings with θ, so a
//! step read off the curve with straight lines either side is wrong by the curvature of the
//! other axes' terms (20 µm of "B" on a machine without lost motion). The terms are fitted
//! instead, jointly, by least squares over every direction's bins where each lost-motion
//! axis moves at [`B_SPEED_FRACTION`] of its top speed or more (the take-up after a
//! reversal left out). The poses and speeds are the first direction's command maps; the
//! other direction passes the same poses the other way, so its `sgn(v_a)` flips. Then
//!
//! ```text
//! B_a = δ_a      (µm along a linear axis; µm of arc at the bar's length, δ_a π/180 · L, for a rotary one)
//! ```
//!
//! An axis without lost motion has no term and B = 0 exactly; an axis whose reversals the
//! bar does not see (normalised sensitivity below [`B_SENSITIVITY_MIN`] at all of them) has
//! a term, which keeps its lost motion out of the others' B, and no B.

use std::cell::RefCell;
use std::f64::consts::PI;
use std::rc::Rc;

use nalgebra::{DMatrix, DVector};

use crate::error::Result;
use crate::input::drive::AxisDrive;
use crate::measure::attribution::ReversalSite;
use crate::measure::ballbar::N_BINS;
use crate::measure::{BallbarRun, BarGeometry, CommandMaps};
use crate::report::run::AxisReversal;
use crate::study::budget::{B_SENSITIVITY_MIN, B_SPEED_FRACTION};
use crate::Axis;

/// Whether a drive has lost motion the model runs: backlash, or dry friction.
fn has_lost_motion(d: &AxisDrive) -> bool {
    d.backlash_m_or_rad > 0.0 || d.has_dry_friction()
}

/// Per bin of the first direction, the regressors `sgn(v_a) S_a` of the lost-motion axes
/// (in their order) where every one of them moves fast, None elsewhere.
type Regressors = Vec<Option<Vec<f64>>>;

/// The [`Regressors`] of the points of a study's pass, which share their command maps and
/// bar (the same setpoints and kinematics; only the drives differ): computed once per set
/// of lost-motion axes and shared, the same values each point would compute.
#[derive(Default)]
pub struct SharedRegressors(RefCell<Vec<(Vec<Axis>, Rc<Regressors>)>>);

impl SharedRegressors {
    /// The regressors of `lost` on `maps` with `geometry` (the pass's), computed at the
    /// first point that asks.
    fn get(&self, maps: &CommandMaps, geometry: &BarGeometry, lost: &[Axis]) -> Rc<Regressors> {
        if let Some((_, r)) = self.0.borrow().iter().find(|(axes, _)| axes == lost) {
            return Rc::clone(r);
        }
        let r = Rc::new(regressors(maps, geometry, lost));
        self.0.borrow_mut().push((lost.to_vec(), Rc::clone(&r)));
        r
    }
}

/// Each of `drives`' axes' B from the `signatures` (one per direction, the first the
/// direction of `maps`), with the bar's `geometry` and the reversal `sites`; the
/// regressors from `shared` where the caller's points share `maps` and `geometry`.
pub fn reversal_b(
    signatures: &[BallbarRun],
    (maps, geometry): (&CommandMaps, &BarGeometry),
    drives: &[AxisDrive],
    sites: &[ReversalSite],
    shared: Option<&SharedRegressors>,
) -> Result<Vec<AxisReversal>> {
    let lost: Vec<Axis> = drives
        .iter()
        .filter(|d| has_lost_motion(d))
        .map(|d| d.axis)
        .collect();
    let regressors = || match shared {
        Some(shared) => shared.get(maps, geometry, &lost),
        None => Rc::new(regressors(maps, geometry, &lost)),
    };
    let delta = fitted_lost_motion(signatures, regressors, lost.len())?;
    let length_mm = geometry.length_mm;
    Ok(drives
        .iter()
        .map(|d| {
            let axis = d.axis;
            let seen: Vec<f64> = sites
                .iter()
                .filter(|s| s.axis == axis)
                .map(|s| s.sensitivity.unwrap_or(1.0))
                .filter(|&s| s >= B_SENSITIVITY_MIN)
                .collect();
            let b_um = match lost.iter().position(|&a| a == axis) {
                _ if seen.is_empty() => None,
                None => Some(0.0),
                Some(k) => delta.as_ref().and_then(|delta| delta[k]).map(|d| {
                    if axis.is_rotary() {
                        d * PI / 180.0 * length_mm * 1e3
                    } else {
                        d * 1e3
                    }
                }),
            };
            let mean_s = seen.iter().sum::<f64>() / seen.len().max(1) as f64;
            AxisReversal {
                axis: axis.to_string(),
                b_um,
                step_um: b_um.map(|b| b * mean_s),
                reversals: seen.len() * signatures.len(),
            }
        })
        .collect())
}

/// δ_a (mm or deg) of each of the `m` lost-motion axes, by the joint least-squares fit of
/// the module's doc on their `regressors`: None for an axis the bar does not see in the
/// fitted bins; None as a whole when there are no signatures or no lost motion.
fn fitted_lost_motion(
    signatures: &[BallbarRun],
    regressors: impl FnOnce() -> Rc<Regressors>,
    m: usize,
) -> Result<Option<Vec<Option<f64>>>> {
    let Some(first) = signatures.first() else {
        return Ok(None);
    };
    if m == 0 {
        return Ok(None);
    }
    let regressors = regressors();
    // Normal equations over every direction's fitted bins, y in µm.
    let (mut xtx, mut xty) = (DMatrix::<f64>::zeros(m, m), DVector::<f64>::zeros(m));
    for run in signatures {
        let sign = if run.direction() == first.direction() {
            1.0
        } else {
            -1.0
        };
        let y = run.trace_um(false)?;
        for (x, y) in regressors.iter().zip(&y) {
            let Some(x) = x.as_ref().filter(|_| y.is_finite()) else {
                continue;
            };
            for j in 0..m {
                xty[j] += sign * x[j] * y;
                for k in 0..m {
                    xtx[(j, k)] += x[j] * x[k];
                }
            }
        }
    }
    solve_deltas(&xtx, &xty)
}

/// Per bin: each lost axis's regressor sgn(v_a) S_a, where every lost axis moves fast.
fn regressors(maps: &CommandMaps, geometry: &BarGeometry, lost: &[Axis]) -> Regressors {
    let poses: Vec<Option<(crate::AxisVec, crate::AxisVec)>> = (0..N_BINS)
        .map(|i| Some((maps.commanded.bin(i)?, maps.speed.bin(i)?)))
        .collect();
    let top: Vec<f64> = lost
        .iter()
        .map(|&a| {
            poses
                .iter()
                .flatten()
                .map(|(_, v)| v[a].abs())
                .fold(0.0, f64::max)
        })
        .collect();
    poses
        .iter()
        .map(|pose| {
            let (q, v) = pose.as_ref()?;
            let fast = lost
                .iter()
                .zip(&top)
                .all(|(&a, &top)| v[a].abs() >= B_SPEED_FRACTION * top);
            fast.then(|| {
                let s = geometry.sensitivity_at(q);
                lost.iter().map(|&a| v[a].signum() * s[a]).collect()
            })
        })
        .collect()
}

/// δ_a (mm or deg) from the normal equations `xtx β = xty` (y in µm) of the fit.
fn solve_deltas(xtx: &DMatrix<f64>, xty: &DVector<f64>) -> Result<Option<Vec<Option<f64>>>> {
    let m = xty.len();
    // An axis the bar does not see in these bins has no column: its δ is not told.
    let largest = (0..m).map(|j| xtx[(j, j)]).fold(0.0, f64::max);
    let seen: Vec<usize> = (0..m)
        .filter(|&j| largest > 0.0 && xtx[(j, j)] > 1e-9 * largest)
        .collect();
    let a = DMatrix::from_fn(seen.len(), seen.len(), |j, k| xtx[(seen[j], seen[k])]);
    let b = DVector::from_fn(seen.len(), |j, _| xty[seen[j]]);
    let Some(beta) = a.cholesky().map(|c| c.solve(&b)) else {
        return Ok(None);
    };
    // y = 1e3 · (−δ/2) · x: δ = −β / 500 (mm or deg).
    let mut delta = vec![None; m];
    for (j, &i) in seen.iter().enumerate() {
        delta[i] = Some(-beta[j] / 500.0);
    }
    Ok(Some(delta))
}
