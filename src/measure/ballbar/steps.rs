//! Steps in a trace: the far-window statistic and the joint least-squares fit of the smooth
//! shape (a Fourier series) and one jump per step.

use std::borrow::Cow;

use nalgebra::{DMatrix, DVector};

use super::circular::{circular_regions, median, running_circular_median};
use super::tuning::{SMOOTH_ORDER, STEP_GAP_DEG, STEP_WINDOW_DEG};
use crate::measure::theta::{angle_distance_deg, bins, BIN_DEG, N_BINS};
use crate::numeric::sin_cos_deg;

/// A step at the boundary before bin `index` (angle `index * BIN_DEG`), height in
/// increasing theta, um.
#[derive(Clone, Copy, Debug)]
pub(super) struct Step {
    pub(super) index: usize,
    pub(super) height_um: f64,
}

/// Columns of the Fourier part of the fit: the mean, then cos and sin of each harmonic.
const FOURIER: usize = 1 + 2 * SMOOTH_ORDER;

/// The smooth shape plus steps, fitted jointly by least squares to one trace `v`
/// ([`ShapeFit::fit`]): the Fourier series up to [`SMOOTH_ORDER`] and, per step at bin k,
/// the basis `u_k(i) = [i >= k] - i/N` (a unit jump at k, made periodic by a ramp).
///
/// The normal equations `AᵀA x = Aᵀv` are formed in closed form, without A (n × p). With
/// `f_j` the Fourier columns, `u_s(i) = [i ≥ k_s] - i/n`, `S_j(k) = Σ_{i≥k} f_j(i)`,
/// `M_j = Σ_i i f_j(i)`, `T(k) = Σ_{i≥k} i` and `Q = Σ_i i²`:
///
/// ```text
/// Σ f_j f_l = n (j = l = 0), n/2 (j = l > 0), 0 otherwise   (orthogonal on the grid, 2K < n)
/// Σ f_j u_s = S_j(k_s) - M_j / n
/// Σ u_s u_t = (n - max(k_s, k_t)) - (T(k_s) + T(k_t)) / n + Q / n²
/// Σ u_s v   = S_v(k_s) - M_v / n
/// ```
///
/// The sums over all bins (`M_j`, `Σ f_j v`, `M_v`) do not depend on the
/// steps: they are taken once per trace, by one pass from the last bin down. A fit's
/// suffix sums `S_j(k)`, `S_v(k)` are the same backward sums stopped at each step's bin, so
/// each fit repeats them only down to its first step.
struct ShapeFit<'a> {
    v: &'a [f64],
    /// cos and sin of 360° m / n for each m: the trace's [`unit_circle`].
    trig: Cow<'static, [(f64, f64)]>,
    moment: [f64; FOURIER],
    atb_fourier: [f64; FOURIER],
    moment_v: f64,
}

/// cos and sin of 360° m / n for m in 0..n: once per m rather than once per harmonic and
/// bin, and for the traces' [`N_BINS`] once per process.
fn unit_circle(n: usize) -> Cow<'static, [(f64, f64)]> {
    let table = |n: usize| -> Vec<(f64, f64)> {
        (0..n)
            .map(|m| {
                let (sin, cos) = sin_cos_deg(360.0 * m as f64 / n as f64);
                (cos, sin)
            })
            .collect()
    };
    static BINS: std::sync::OnceLock<Vec<(f64, f64)>> = std::sync::OnceLock::new();
    if n == N_BINS {
        Cow::Borrowed(BINS.get_or_init(|| table(N_BINS)))
    } else {
        Cow::Owned(table(n))
    }
}

/// The Fourier part of row i of A after its leading 1: `f(j, cos, sin)` for each harmonic
/// k, whose cos and sin are columns j = 2k - 1 and j + 1 (entry (k i) mod n of `trig`, the
/// [`unit_circle`] of n bins).
#[inline(always)]
fn each_harmonic(trig: &[(f64, f64)], i: usize, mut f: impl FnMut(usize, f64, f64)) {
    let n = trig.len();
    let mut m = 0;
    for k in 1..=SMOOTH_ORDER {
        m += i; // (k i) mod n: both terms below n
        if m >= n {
            m -= n;
        }
        let (cos, sin) = trig[m];
        f(2 * k - 1, cos, sin);
    }
}

impl<'a> ShapeFit<'a> {
    /// The sums over all bins of trace `v`.
    fn new(v: &'a [f64]) -> Self {
        let n = v.len();
        // The traces have N_BINS bins: far more than the harmonics need for orthogonality.
        debug_assert!(n > 2 * SMOOTH_ORDER);
        let trig = unit_circle(n);
        let (mut moment, mut atb, mut moment_v) = ([0.0; FOURIER], [0.0; FOURIER], 0.0);
        for i in (0..n).rev() {
            let (vi, fi) = (v[i], i as f64);
            // Column 0 is 1.
            moment[0] += fi * 1.0;
            atb[0] += 1.0 * vi;
            each_harmonic(&trig, i, |j, cos, sin| {
                moment[j] += fi * cos;
                atb[j] += cos * vi;
                moment[j + 1] += fi * sin;
                atb[j + 1] += sin * vi;
            });
            moment_v += fi * vi;
        }
        ShapeFit {
            v,
            trig,
            moment,
            atb_fourier: atb,
            moment_v,
        }
    }

    /// The fit with steps at `step_indices` (bins) and the step heights (um, in their order).
    fn fit(&self, step_indices: &[usize]) -> (Vec<f64>, Vec<f64>) {
        let (x, order) = self.solve(step_indices);
        let nf = self.v.len() as f64;
        // The steps' part of the fit, Σ_s h_s u_s(i) = Σ_{k_s ≤ i} h_s - (i/n) Σ_s h_s: the
        // first sum grows as i passes each k_s (in `order`, reversed to increasing bins).
        let heights: Vec<f64> = x[FOURIER..].to_vec();
        let total: f64 = heights.iter().sum();
        let xf: [f64; FOURIER] = x[..FOURIER].try_into().expect("the Fourier columns");
        let mut passed = 0.0;
        let mut pending = order.iter().rev().peekable();
        let fit = (0..self.v.len())
            .map(|i| {
                let smooth = self.smooth_at(&xf, i);
                while let Some(&&s) = pending.peek().filter(|&&&s| step_indices[s] <= i) {
                    passed += heights[s];
                    pending.next();
                }
                smooth + (passed - i as f64 / nf * total)
            })
            .collect();
        (fit, heights)
    }

    /// The fit without steps, bin by bin: at each bin the value of `fit(&[])`, the same bits
    /// (its steps' part `0 - (i/n)·Σ∅` kept as written), for a caller that reads a few bins.
    fn without_steps(&self) -> impl Fn(usize) -> f64 + '_ {
        let (x, _) = self.solve(&[]);
        let total: f64 = x[FOURIER..].iter().sum();
        let xf: [f64; FOURIER] = x[..FOURIER].try_into().expect("the Fourier columns");
        let nf = self.v.len() as f64;
        move |i| self.smooth_at(&xf, i) + (0.0 - i as f64 / nf * total)
    }

    /// Σ_j A_ij x_j of the Fourier columns at bin i, in the order of j, from 1 · x_0 (what a
    /// sum from −0 gives).
    #[inline(always)]
    fn smooth_at(&self, xf: &[f64; FOURIER], i: usize) -> f64 {
        let mut smooth = 1.0 * xf[0];
        each_harmonic(&self.trig, i, |j, cos, sin| {
            smooth += cos * xf[j];
            smooth += sin * xf[j + 1];
        });
        smooth
    }

    /// The least-squares coefficients (the Fourier columns, then the steps in their order)
    /// and the steps' order by decreasing bin.
    fn solve(&self, step_indices: &[usize]) -> (Vec<f64>, Vec<usize>) {
        let (v, n) = (self.v, self.v.len());
        let p = FOURIER + step_indices.len();
        // Steps by decreasing bin: S(k) of each as the backward sums pass its bin.
        let mut order: Vec<usize> = (0..step_indices.len()).collect();
        order.sort_by_key(|&s| std::cmp::Reverse(step_indices[s]));
        let mut suffix = vec![[0.0; FOURIER]; step_indices.len()];
        let mut suffix_v = vec![0.0; step_indices.len()];
        let (mut sum, mut sum_v) = ([0.0; FOURIER], 0.0);
        let mut next = 0;
        let trig: &[(f64, f64)] = &self.trig;
        for i in (0..n).rev() {
            if next == order.len() {
                break;
            }
            sum[0] += 1.0;
            each_harmonic(trig, i, |j, cos, sin| {
                sum[j] += cos;
                sum[j + 1] += sin;
            });
            sum_v += v[i];
            while next < order.len() && step_indices[order[next]] >= i {
                // k_s = i (k_s beyond the last bin sums nothing: it is recorded before any row).
                if step_indices[order[next]] == i {
                    suffix[order[next]] = sum;
                    suffix_v[order[next]] = sum_v;
                }
                next += 1;
            }
        }
        let nf = n as f64;
        let tail = |k: usize| (nf * (nf - 1.0) - k as f64 * (k as f64 - 1.0)) / 2.0; // T(k)
        let q = (nf - 1.0) * nf * (2.0 * nf - 1.0) / 6.0;
        let mut ata = DMatrix::<f64>::zeros(p, p);
        let mut atb = DVector::<f64>::zeros(p);
        for j in 0..FOURIER {
            ata[(j, j)] = if j == 0 { nf } else { 0.5 * nf };
            atb[j] = self.atb_fourier[j];
        }
        for (s, &ks) in step_indices.iter().enumerate() {
            let cs = FOURIER + s;
            for j in 0..FOURIER {
                let g = suffix[s][j] - self.moment[j] / nf;
                ata[(j, cs)] = g;
                ata[(cs, j)] = g;
            }
            for (t, &kt) in step_indices.iter().enumerate() {
                let inside = nf - ks.max(kt).min(n) as f64;
                ata[(cs, FOURIER + t)] =
                    inside - (tail(ks.min(n)) + tail(kt.min(n))) / nf + q / (nf * nf);
            }
            atb[cs] = suffix_v[s] - self.moment_v / nf;
        }
        let x = match ata.cholesky() {
            Some(ch) => ch.solve(&atb),
            None => DVector::zeros(p),
        };
        (x.as_slice().to_vec(), order)
    }
}

/// The far-window statistic at one boundary `k` of a circular trace of `n` bins whose bin
/// `i` is `r(i)`: `median(right) - median(left)`. Only the two windows' bins are read.
fn far_window_jump(n: usize, r: impl Fn(usize) -> f64, k: usize) -> f64 {
    let n = n as isize;
    let (gap, width) = (bins(STEP_GAP_DEG) as isize, bins(STEP_WINDOW_DEG) as isize);
    let window = |from: isize| -> f64 {
        let mut w: Vec<f64> = (from..from + width)
            .map(|i| r((k as isize + i).rem_euclid(n) as usize))
            .collect();
        median(&mut w)
    };
    window(gap) - window(-gap - width)
}

/// The far-window step statistic `S(i) = median(right) - median(left)` at each boundary.
fn step_statistic(r: &[f64]) -> Vec<f64> {
    let (gap, width) = (bins(STEP_GAP_DEG) as isize, bins(STEP_WINDOW_DEG));
    let right = running_circular_median(r, gap, width);
    let left = running_circular_median(r, -gap - width as isize, width);
    right.iter().zip(&left).map(|(a, b)| a - b).collect()
}

/// Every step in `s` above `threshold`: (peak of its region, the middle of the part of the
/// region above half its peak).
fn all_steps(s: &[f64], threshold: f64) -> Vec<(f64, usize)> {
    let mut out = Vec::new();
    for sign in [1.0, -1.0] {
        for region in circular_regions(s.len(), |i| sign * s[i] > threshold) {
            let peak = region
                .iter()
                .map(|&i| sign * s[i])
                .fold(f64::NEG_INFINITY, f64::max);
            let upper: Vec<usize> = (0..region.len())
                .filter(|&k| sign * s[region[k]] >= 0.5 * peak)
                .collect();
            out.push((peak, region[(upper[0] + upper[upper.len() - 1]) / 2]));
        }
    }
    out
}

/// The position of the largest step in `s` above `threshold`: the middle of the part of its
/// region above half its peak.
fn largest_step(s: &[f64], threshold: f64) -> Option<usize> {
    // The first of the highest peaks, in the order `all_steps` finds them.
    all_steps(s, threshold)
        .into_iter()
        .fold(None::<(f64, usize)>, |best, (peak, index)| {
            if best.is_none_or(|(p, _)| peak > p) {
                Some((peak, index))
            } else {
                best
            }
        })
        .map(|(_, index)| index)
}

/// Greedy step search: fit the smooth shape and the steps found so far, look for the
/// largest remaining step in the residual, add it, refit; until none is above `threshold`.
/// Returns the steps (sorted by index) and the final joint fit.
pub(super) fn find_steps(c: &[f64], threshold: f64, anchors: &[usize]) -> (Vec<Step>, Vec<f64>) {
    const MAX_STEPS: usize = 16;
    if !anchors.is_empty() {
        return anchored_steps(c, threshold, anchors);
    }
    // First every region of the statistic at once (steps 10-20 deg apart each have their
    // own plateau, and fitting them together keeps the smooth shape from bending into
    // them), then greedily whatever the joint fit leaves.
    let shape = ShapeFit::new(c);
    let (fit0, _) = shape.fit(&[]);
    let r0: Vec<f64> = c.iter().zip(&fit0).map(|(x, f)| x - f).collect();
    let stat = step_statistic(&r0);
    let mut indices: Vec<usize> = Vec::new();
    let mut found = all_steps(&stat, threshold);
    found.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (_, index) in found {
        let index = refine_step(r0.len(), |i| r0[i], index);
        let taken = indices.iter().any(|&k| {
            angle_distance_deg(k as f64 * BIN_DEG, index as f64 * BIN_DEG) < STEP_GAP_DEG
        });
        if !taken && indices.len() < MAX_STEPS {
            indices.push(index);
        }
    }
    let (mut fit, mut heights) = shape.fit(&indices);
    while indices.len() < MAX_STEPS {
        let r: Vec<f64> = c.iter().zip(&fit).map(|(x, f)| x - f).collect();
        let Some(index) = largest_step(&step_statistic(&r), threshold) else {
            break;
        };
        let index = refine_step(r.len(), |i| r[i], index);
        let taken = indices.iter().any(|&k| {
            angle_distance_deg(k as f64 * BIN_DEG, index as f64 * BIN_DEG) < STEP_GAP_DEG
        });
        if taken {
            break;
        }
        indices.push(index);
        (fit, heights) = shape.fit(&indices);
    }
    eliminate_weak_steps(&shape, threshold, &mut indices, &mut fit, &mut heights);
    let mut steps: Vec<Step> = indices
        .into_iter()
        .zip(heights)
        .map(|(index, height_um)| Step { index, height_um })
        .collect();
    steps.sort_by_key(|s| s.index);
    (steps, fit)
}

/// Steps where the axes reverse: lost motion changes the level only at a reversal, so with
/// the reversal angles known, a step is looked for at each (`anchors`, bins), placed by
/// [`refine_step`] within [`STEP_GAP_DEG`] of it, fitted jointly with the smooth shape, and
/// kept if it stands out ([`eliminate_weak_steps`]). Anchors closer than [`STEP_GAP_DEG`]
/// share one step.
fn anchored_steps(c: &[f64], threshold: f64, anchors: &[usize]) -> (Vec<Step>, Vec<f64>) {
    let shape = ShapeFit::new(c);
    // The residual of the smooth fit, only in the anchors' windows.
    let fit0 = shape.without_steps();
    let r0 = |i: usize| c[i] - fit0(i);
    let mut indices: Vec<usize> = Vec::new();
    for &a in anchors {
        let index = refine_step(c.len(), r0, a);
        let taken = indices.iter().any(|&k| {
            angle_distance_deg(k as f64 * BIN_DEG, index as f64 * BIN_DEG) < STEP_GAP_DEG
        });
        if !taken {
            indices.push(index);
        }
    }
    let (mut fit, mut heights) = shape.fit(&indices);
    eliminate_weak_steps(&shape, threshold, &mut indices, &mut fit, &mut heights);
    let mut steps: Vec<Step> = indices
        .into_iter()
        .zip(heights)
        .map(|(index, height_um)| Step { index, height_um })
        .collect();
    steps.sort_by_key(|s| s.index);
    (steps, fit)
}

/// Backward elimination of steps that do not stand out once the others are fitted.
fn eliminate_weak_steps(
    shape: &ShapeFit,
    threshold: f64,
    indices: &mut Vec<usize>,
    fit: &mut Vec<f64>,
    heights: &mut Vec<f64>,
) {
    // Backward elimination: a step must still stand out when the others are fitted. With
    // the residual r of the joint fit, step k is tested in r + h_k u_k (its own jump put
    // back) by the far-window statistic at its index; the weakest below the threshold is
    // dropped and the rest refitted, until all stand.
    loop {
        // Only the bins of the statistic's two windows are formed.
        let (c, n) = (shape.v, shape.v.len());
        let weakest = indices
            .iter()
            .zip(heights.iter())
            .enumerate()
            .map(|(j, (&k, &h))| {
                let with = |i: usize| {
                    (c[i] - fit[i]) + h * (f64::from(u8::from(i >= k)) - i as f64 / n as f64)
                };
                (j, far_window_jump(n, with, k).abs().min(h.abs()))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1));
        match weakest {
            Some((j, strength)) if strength < threshold => {
                indices.remove(j);
                (*fit, *heights) = shape.fit(indices);
            }
            _ => break,
        }
    }
}

/// The best position of a step found near bin `near` in the residual `r`: the split of the
/// window `near ± (STEP_GAP_DEG + STEP_WINDOW_DEG)` into two constant levels that explains the
/// most of its variance, `max_k n_l n_r / n (mean_r - mean_l)²`, with k within
/// `near ± STEP_GAP_DEG` (the far-window statistic locates a step only to a few degrees when a
/// spike sits on it).
fn refine_step(n: usize, r: impl Fn(usize) -> f64, near: usize) -> usize {
    let n = n as isize;
    let w = bins(STEP_GAP_DEG + STEP_WINDOW_DEG) as isize;
    let reach = bins(STEP_GAP_DEG) as isize;
    // The window's bins, each read once.
    let window: Vec<f64> = (-w..w)
        .map(|k| r((near as isize + k).rem_euclid(n) as usize))
        .collect();
    let at = |k: isize| window[(k + w) as usize];
    let total: f64 = (-w..w).map(at).sum();
    let len = (2 * w) as f64;
    let (mut left, mut best) = (0.0, (f64::NEG_INFINITY, 0isize));
    for k in -w + 1..w {
        left += at(k - 1);
        let n_l = (k + w) as f64;
        let n_r = len - n_l;
        let d = (total - left) / n_r - left / n_l;
        let score = n_l * n_r / len * d * d;
        if (-reach..=reach).contains(&k) && score > best.0 {
            best = (score, k);
        }
    }
    (near as isize + best.1).rem_euclid(n) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trace that is exactly a smooth shape plus two steps is fitted exactly: the step
    /// heights and every bin, with the steps given in either order, from one `ShapeFit` of
    /// the trace after a fit without steps (the sums it shares), on the traces' bins and on
    /// another bin count.
    #[test]
    fn a_shape_with_steps_is_fitted_exactly() {
        for n in [N_BINS, 360] {
            let (k1, k2) = (n / 7, 5 * n / 8);
            let u = |k: usize, i: usize| f64::from(u8::from(i >= k)) - i as f64 / n as f64;
            let v: Vec<f64> = (0..n)
                .map(|i| {
                    let t = std::f64::consts::TAU * i as f64 / n as f64;
                    2.0 + 0.5 * (3.0 * t).cos() - 0.3 * t.sin()
                        + 0.2 * (6.0 * t).sin()
                        + 1.5 * u(k1, i)
                        - 0.7 * u(k2, i)
                })
                .collect();
            let shape = ShapeFit::new(&v);
            let (smooth, none) = shape.fit(&[]);
            assert!(none.is_empty());
            let at = shape.without_steps();
            for (i, f) in smooth.iter().enumerate() {
                assert_eq!(at(i).to_bits(), f.to_bits(), "{n}: bin {i}");
            }
            assert!(smooth.iter().zip(&v).any(|(f, x)| (f - x).abs() > 0.1));
            for steps in [[k1, k2], [k2, k1]] {
                let (fit, heights) = shape.fit(&steps);
                let want = if steps[0] == k1 {
                    [1.5, -0.7]
                } else {
                    [-0.7, 1.5]
                };
                for (h, w) in heights.iter().zip(want) {
                    assert!((h - w).abs() < 1e-9, "{n}: {h} against {w}");
                }
                for (f, x) in fit.iter().zip(&v) {
                    assert!((f - x).abs() < 1e-9, "{n}: {f} against {x}");
                }
            }
        }
    }
}
