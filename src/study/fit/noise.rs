//! The residual against the noise: each trace's noise estimated from the data, the shape of
//! what the model leaves (steps at reversals, a 2θ term, narrow spikes), and standard errors
//! from a circular block bootstrap along θ that hold for correlated residuals.
//! Inputs: the residual by run, the recorded motion. Outputs: [`NoiseCheck`], bootstrap errors.
//!
//! # Noise
//!
//! Each run's noise is an AR(1) process along θ, estimated from the residual's robust
//! variogram ([`correlated`](super::correlated)): σ is its marginal standard deviation, so
//! correlated noise is not mistaken for a model that misses something. (The white-noise
//! estimate from second differences, [`white_noise_um`], kept for comparison in fit.json,
//! reads 3.8 times too little under a correlation of 0.9 from point to point.)
//!
//! # Block bootstrap
//!
//! With the fixed linearisation `dx = J⁺ r`, each replicate resamples every run's residual
//! (in θ order) as circular blocks of length `ℓ` and solves again; the standard error is the
//! spread of the replicates. `ℓ = max(⌈n^{1/3}⌉, ⌈3 τ⌉)` with `τ = 1 + 2 Σ ρ_k` the
//! integrated autocorrelation time of the residual (summed while ρ_k > 0.05), at most n/4.

use nalgebra::DVector;
use serde::Serialize;

use super::correlated::{fit_ar1, ArNoise};
use super::decomposition::Decomposition;
use super::model::{Recorded, Run};
use crate::input::program::Direction;
use crate::Axis;

/// Residual RMS above this multiple of the estimated noise is reported as unmodelled...
pub const EXCESS_RATIO: f64 = 2.0;
/// ...when the excess, `√(rms² − noise²)`, is also above this, um (a noise-free simulated
/// trace has a residual of ~0.01 um from its printed digits and the binning).
pub const EXCESS_FLOOR_UM: f64 = 0.05;
/// Bootstrap replicates, and the seed of their random numbers (deterministic output).
pub const REPLICATES: usize = 200;
const SEED: u64 = 0x6d74_7369_6d5f_6669;
/// Half-width of the windows either side of a reversal for its step, deg.
const STEP_WINDOW_DEG: f64 = 3.0;
/// How far from a commanded reversal its step is looked for, deg.
const STEP_SEARCH_DEG: f64 = 4.0;
/// Half-width of the running median a spike is measured against, deg.
const SPIKE_WINDOW_DEG: f64 = 2.5;
/// A spike narrower than this (full width at half height) is "narrow", deg...
const NARROW_DEG: f64 = 3.0;
/// ...and at least this many points wide: one point between two levels is a step.
const SPIKE_POINTS: usize = 3;

/// One trace's residual against its noise, um.
#[derive(Clone, Debug, Default, Serialize)]
pub struct NoiseCheck {
    /// The noise: marginal standard deviation of the AR(1) model of the residual (RMS over
    /// the directions).
    pub noise_um: f64,
    /// Its correlation from point to point (φ of the AR(1) model; largest over the
    /// directions), and the distance at which the correlation falls to 1/e, deg.
    pub correlation: f64,
    pub correlation_length_deg: f64,
    /// The white-noise estimate from second differences (what the noise would be if it
    /// were independent from point to point; too small under correlated noise).
    pub noise_white_um: f64,
    /// Residual RMS over the noise.
    pub ratio: f64,
    /// Amplitude of the residual's 2θ term (largest over the directions).
    pub two_theta_um: f64,
    /// Largest step of the residual across a reversal, with the axis and θ.
    pub step_um: f64,
    pub step_axis: Option<String>,
    pub step_theta_deg: Option<f64>,
    /// Largest narrow excursion from the running median, with its θ and width.
    pub spike_um: f64,
    pub spike_theta_deg: Option<f64>,
    pub spike_width_deg: Option<f64>,
    /// What the shape suggests, when the residual is well above the noise (empty otherwise:
    /// the trace is explained).
    pub suggests: Vec<String>,
}

impl NoiseCheck {
    /// Figures rounded to 1e-6 (stable output).
    pub fn rounded(mut self) -> NoiseCheck {
        let r = |v: f64| (v * 1e6).round() / 1e6;
        self.noise_um = r(self.noise_um);
        self.correlation = r(self.correlation);
        self.correlation_length_deg = r(self.correlation_length_deg);
        self.noise_white_um = r(self.noise_white_um);
        self.ratio = r(self.ratio);
        self.two_theta_um = r(self.two_theta_um);
        self.step_um = r(self.step_um);
        self.spike_um = r(self.spike_um);
        self.step_theta_deg = self.step_theta_deg.map(r);
        self.spike_theta_deg = self.spike_theta_deg.map(r);
        self.spike_width_deg = self.spike_width_deg.map(r);
        self
    }
}

/// A run's residual in θ order: (θ deg, residual um).
fn ordered(run: &Run, measured_theta: &[f64], residual: &DVector<f64>) -> Vec<(f64, f64)> {
    let mut pts: Vec<(f64, f64)> = run
        .rows
        .iter()
        .map(|&i| (measured_theta[i].rem_euclid(360.0), residual[i]))
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    pts
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

/// White noise σ from second differences, robust (MAD), um.
pub fn white_noise_um(r: &[f64]) -> f64 {
    if r.len() < 5 {
        return 0.0;
    }
    let mut d: Vec<f64> = r.windows(3).map(|w| w[2] - 2.0 * w[1] + w[0]).collect();
    let m = median(&mut d.clone());
    let mut dev: Vec<f64> = d.iter_mut().map(|v| (*v - m).abs()).collect();
    1.4826 * median(&mut dev) / 6f64.sqrt()
}

/// Amplitude of the 2θ term of `pts` by least squares on (1, cos 2θ, sin 2θ), um.
fn two_theta_um(pts: &[(f64, f64)]) -> f64 {
    let a = nalgebra::DMatrix::from_fn(pts.len(), 3, |i, c| {
        let t = 2.0 * pts[i].0.to_radians();
        [1.0, t.cos(), t.sin()][c]
    });
    let b = DVector::from_iterator(pts.len(), pts.iter().map(|p| p.1));
    match (a.transpose() * &a).try_inverse() {
        Some(inv) => {
            let c = inv * a.transpose() * b;
            c[1].hypot(c[2])
        }
        None => 0.0,
    }
}

/// θ where an axis's commanded motion reverses in the recorded revolution.
fn reversals(samples: &[Recorded]) -> Vec<(Axis, f64)> {
    let mut out = Vec::new();
    for axis in [Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::B] {
        let mut last = 0.0;
        for w in samples.windows(2) {
            let d = w[1].commanded[axis] - w[0].commanded[axis];
            if d.abs() < 1e-9 {
                continue;
            }
            let s = d.signum();
            if last != 0.0 && s != last {
                out.push((axis, w[0].theta_deg.rem_euclid(360.0)));
            }
            last = s;
        }
    }
    out
}

/// Residuals with θ within [from, to) (circular), deg.
fn window(pts: &[(f64, f64)], from: f64, to: f64) -> Vec<f64> {
    pts.iter()
        .filter(|p| (p.0 - from).rem_euclid(360.0) < (to - from).rem_euclid(360.0))
        .map(|p| p.1)
        .collect()
}

/// The step at `t`: median of the window after minus median of the window before.
fn step_at(pts: &[(f64, f64)], t: f64) -> Option<f64> {
    let mut before = window(pts, t - STEP_WINDOW_DEG, t);
    let mut after = window(pts, t, t + STEP_WINDOW_DEG);
    (before.len() >= 3 && after.len() >= 3).then(|| median(&mut after) - median(&mut before))
}

/// The largest step near a reversal: the split is searched within [`STEP_SEARCH_DEG`] of the
/// commanded reversal, since the actual one lags it (servo lag, the dead zone taken up).
/// Returns (step um, axis, θ of the step deg).
fn largest_step(pts: &[(f64, f64)], samples: &[Recorded]) -> Option<(f64, Axis, f64)> {
    reversals(samples)
        .into_iter()
        .flat_map(|(axis, t)| {
            pts.iter()
                .filter(move |p| {
                    let d = (p.0 - t + 180.0).rem_euclid(360.0) - 180.0;
                    d.abs() <= STEP_SEARCH_DEG
                })
                .filter_map(move |p| step_at(pts, p.0).map(|h| (h, axis, p.0)))
        })
        .max_by(|a, b| a.0.abs().total_cmp(&b.0.abs()))
}

/// The largest excursion from the running median at least [`SPIKE_POINTS`] wide at half
/// height: (height um, θ deg, width deg).
fn largest_spike(pts: &[(f64, f64)]) -> Option<(f64, f64, f64)> {
    let dev: Vec<f64> = pts
        .iter()
        .map(|p| {
            let mut w = window(pts, p.0 - SPIKE_WINDOW_DEG, p.0 + SPIKE_WINDOW_DEG);
            p.1 - median(&mut w)
        })
        .collect();
    let extent = |i: usize| {
        let peak = dev[i];
        let inside =
            |j: usize| dev[j].abs() >= 0.5 * peak.abs() && dev[j].signum() == peak.signum();
        let (mut lo, mut hi) = (i, i);
        while lo > 0 && inside(lo - 1) {
            lo -= 1;
        }
        while hi + 1 < dev.len() && inside(hi + 1) {
            hi += 1;
        }
        (lo, hi)
    };
    let mut order: Vec<usize> = (0..dev.len()).collect();
    order.sort_by(|a, b| dev[*b].abs().total_cmp(&dev[*a].abs()));
    order.into_iter().find_map(|i| {
        let (lo, hi) = extent(i);
        (hi - lo + 1 >= SPIKE_POINTS).then(|| (dev[i], pts[i].0, pts[hi].0 - pts[lo].0))
    })
}

/// The AR(1) model of a run's residual, in θ order.
pub(super) fn run_noise(run: &Run, measured_theta: &[f64], residual: &DVector<f64>) -> ArNoise {
    let r: Vec<f64> = ordered(run, measured_theta, residual)
        .iter()
        .map(|p| p.1)
        .collect();
    fit_ar1(&r)
}

/// A run's rows in θ order.
pub(super) fn theta_order(run: &Run, measured_theta: &[f64]) -> Vec<usize> {
    let mut rows = run.rows.clone();
    rows.sort_by(|a, b| {
        measured_theta[*a]
            .rem_euclid(360.0)
            .total_cmp(&measured_theta[*b].rem_euclid(360.0))
    });
    rows
}

/// Checks one trace's residual (its runs) against the noise estimated from it.
pub(super) fn check_trace(
    runs: &[&Run],
    measured_theta: &[f64],
    residual: &DVector<f64>,
) -> NoiseCheck {
    let mut c = NoiseCheck::default();
    let (mut noise2, mut white2, mut rss, mut n) = (0.0, 0.0, 0.0, 0usize);
    for run in runs {
        let pts = ordered(run, measured_theta, residual);
        let r: Vec<f64> = pts.iter().map(|p| p.1).collect();
        let ar = fit_ar1(&r);
        noise2 += ar.sigma_um.powi(2) * r.len() as f64;
        white2 += white_noise_um(&r).powi(2) * r.len() as f64;
        if ar.phi >= c.correlation {
            c.correlation = ar.phi;
            let spacing = 360.0 / r.len().max(1) as f64;
            c.correlation_length_deg = if ar.phi > 0.0 {
                spacing / -ar.phi.ln()
            } else {
                0.0
            };
        }
        rss += r.iter().map(|v| v * v).sum::<f64>();
        n += r.len();
        c.two_theta_um = c.two_theta_um.max(two_theta_um(&pts));
        if let Some((s, axis, t)) = largest_step(&pts, &run.samples) {
            if s.abs() > c.step_um.abs() {
                (c.step_um, c.step_axis, c.step_theta_deg) = (s, Some(axis.to_string()), Some(t));
            }
        }
        if let Some((h, t, w)) = largest_spike(&pts) {
            if w < NARROW_DEG && h.abs() > c.spike_um.abs() {
                (c.spike_um, c.spike_theta_deg, c.spike_width_deg) = (h, Some(t), Some(w));
            }
        }
    }
    let n = n.max(1) as f64;
    c.noise_um = (noise2 / n).sqrt();
    c.noise_white_um = (white2 / n).sqrt();
    let rms = (rss / n).sqrt();
    c.ratio = if c.noise_um > 0.0 {
        rms / c.noise_um
    } else {
        0.0
    };
    let excess = (rms * rms - c.noise_um * c.noise_um).max(0.0).sqrt();
    if c.ratio > EXCESS_RATIO && excess > EXCESS_FLOOR_UM {
        c.suggests = suggestions(&c, excess);
    }
    c
}

/// What the residual's shape suggests, with its figures.
fn suggestions(c: &NoiseCheck, excess: f64) -> Vec<String> {
    let mut out = Vec::new();
    if c.step_um.abs() >= (3.0 * c.noise_um).max(0.5 * excess) {
        out.push(format!(
            "steps of {:+.2} um at the reversals of {} (theta {:.1} deg): backlash or lost \
             motion (friction's elastic pre-sliding); the ball bar cannot tell the two apart",
            c.step_um,
            c.step_axis.as_deref().unwrap_or("?"),
            c.step_theta_deg.unwrap_or(0.0)
        ));
    }
    if c.two_theta_um / 2f64.sqrt() >= 0.5 * excess && c.two_theta_um >= 2.0 * c.noise_um {
        out.push(format!(
            "a 2-theta term of {:.2} um: squareness or scale error, or a servo gain mismatch \
             between the axes (try --servo-gain)",
            c.two_theta_um
        ));
    }
    if c.spike_um.abs() >= (4.0 * c.noise_um).max(0.5 * excess) {
        out.push(format!(
            "narrow spikes of {:+.2} um at theta {:.1} deg ({:.1} deg wide): friction at a \
             reversal",
            c.spike_um,
            c.spike_theta_deg.unwrap_or(0.0),
            c.spike_width_deg.unwrap_or(0.0)
        ));
    }
    if out.is_empty() {
        out.push(format!(
            "no step, 2-theta term or spike stands out ({excess:.2} um RMS unexplained): \
             correlated noise, drift, or an effect the model lacks"
        ));
    }
    out
}

/// Small deterministic generator (SplitMix64) for the bootstrap.
struct SplitMix(u64);
impl SplitMix {
    fn below(&mut self, n: usize) -> usize {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) % n as u64) as usize
    }
}

/// Block length for a run's residual `r` (θ order), samples.
pub fn block_length(r: &[f64]) -> usize {
    let n = r.len();
    let mean = r.iter().sum::<f64>() / n.max(1) as f64;
    let var = r.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
    let mut tau = 1.0;
    if var > 0.0 {
        for k in 1..n / 2 {
            let rho = (0..n - k)
                .map(|i| (r[i] - mean) * (r[i + k] - mean))
                .sum::<f64>()
                / var;
            if rho <= 0.05 {
                break;
            }
            tau += 2.0 * rho;
        }
    }
    let l = ((n as f64).cbrt().ceil()).max((3.0 * tau).ceil()) as usize;
    l.clamp(1, (n / 4).max(1))
}

/// Standard errors by circular block bootstrap of each run's residual along θ, in parameter
/// units, and the block lengths used (samples, per run).
pub(super) fn bootstrap_errors(
    d: &Decomposition,
    runs: &[Run],
    measured_theta: &[f64],
    residual: &DVector<f64>,
) -> (DVector<f64>, Vec<usize>) {
    let order: Vec<Vec<usize>> = runs
        .iter()
        .map(|run| {
            let mut rows = run.rows.clone();
            rows.sort_by(|a, b| {
                measured_theta[*a]
                    .rem_euclid(360.0)
                    .total_cmp(&measured_theta[*b].rem_euclid(360.0))
            });
            rows
        })
        .collect();
    let blocks: Vec<usize> = order
        .iter()
        .map(|rows| block_length(&rows.iter().map(|&i| residual[i]).collect::<Vec<_>>()))
        .collect();
    let mut rng = SplitMix(SEED);
    let np = d.v.nrows();
    let (mut sum, mut sum2) = (DVector::zeros(np), DVector::zeros(np));
    let mut star = DVector::zeros(residual.len());
    for _ in 0..REPLICATES {
        for (rows, &l) in order.iter().zip(&blocks) {
            let n = rows.len();
            let mut filled = 0;
            while filled < n {
                let start = rng.below(n);
                for k in 0..l.min(n - filled) {
                    star[rows[filled + k]] = residual[rows[(start + k) % n]];
                }
                filled += l;
            }
        }
        let dx = d.solve(&star);
        sum += &dx;
        sum2 += dx.component_mul(&dx);
    }
    let b = REPLICATES as f64;
    let se = DVector::from_iterator(
        np,
        (0..np).map(|j| (sum2[j] / b - (sum[j] / b).powi(2)).max(0.0).sqrt()),
    );
    (se, blocks)
}

/// "ccw" or "cw".
pub fn direction_name(d: Direction) -> &'static str {
    match d {
        Direction::Ccw => "ccw",
        Direction::Cw => "cw",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::AxisVec;

    /// A revolution whose commanded X, sin θ, reverses at 90 and 270 deg.
    fn samples() -> Vec<Recorded> {
        (0..3600)
            .map(|i| {
                let t = i as f64 * 0.1;
                let mut q = AxisVec::ZERO;
                q[Axis::X] = (t - 90.0).to_radians().cos();
                Recorded {
                    theta_deg: t,
                    time_s: i as f64 * 1e-3,
                    commanded: q,
                    actual: q,
                }
            })
            .collect()
    }

    #[test]
    fn a_step_at_a_reversal_and_a_narrow_spike_are_measured() {
        let s = samples();
        let revs = reversals(&s);
        assert_eq!(revs.len(), 2, "{revs:?}");
        assert!(revs.iter().all(|r| r.0 == Axis::X));
        assert!(
            (revs[0].1 - 90.0).abs() < 0.2 && (revs[1].1 - 270.0).abs() < 0.2,
            "{revs:?}"
        );
        // +2 um at 90 deg, -2 um at 270, a 1.5 um spike 1 deg wide at 45 deg, every 0.2 deg.
        let pts: Vec<(f64, f64)> = (0..1800)
            .map(|i| {
                let t = i as f64 * 0.2 + 0.1;
                let step = if t > 90.0 && t < 270.0 { 1.0 } else { -1.0 };
                let spike = if (t - 45.0).abs() < 0.5 { 1.5 } else { 0.0 };
                (t, step + spike)
            })
            .collect();
        let (h, axis, t) = largest_step(&pts, &s).unwrap();
        assert!(
            (h.abs() - 2.0).abs() < 1e-9 && axis == Axis::X,
            "{h} {axis} {t}"
        );
        // Noise-free levels tie over the splits whose windows each hold one level's majority.
        assert!((t - 90.0).abs() < 2.0 || (t - 270.0).abs() < 2.0, "{t}");
        let (h, t, w) = largest_spike(&pts).unwrap();
        assert!(
            (h - 1.5).abs() < 1e-9 && (t - 45.0).abs() < 0.6 && (w - 0.8).abs() < 0.3,
            "{h} {t} {w}"
        );
    }

    #[test]
    fn white_noise_is_estimated_through_a_smooth_shape() {
        // Deterministic pseudo-noise: uniform in [-√3, √3] σ (variance σ²).
        let mut g = SplitMix(7);
        let sigma = 0.2;
        let r: Vec<f64> = (0..5000)
            .map(|i| {
                let u = g.below(1_000_000) as f64 / 1e6;
                5.0 * (i as f64 * 0.002).sin() + sigma * 3f64.sqrt() * (2.0 * u - 1.0)
            })
            .collect();
        let est = white_noise_um(&r);
        // MAD-based: uniform noise is not Gaussian, so allow 15 %.
        assert!((est / sigma - 1.0).abs() < 0.15, "{est}");
    }
}
