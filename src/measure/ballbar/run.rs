//! One direction of a ball-bar test, streamed: fixed θ bins and the sums of the least-squares
//! centring `dL = r0 + a cos θ + b sin θ`, in O(1) memory in the number of samples.

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use super::tuning::MAX_GAP_DEG;
use crate::error::{Error, Result};
use crate::input::program::Direction;
use crate::measure::theta::{bin_index, wrap_360, BIN_DEG, N_BINS};
use crate::numeric::sin_cos_deg;

/// Least-squares centring `dL = r0 + a cos theta + b sin theta`, um.
///
/// (a, b) is the set-up offset of the pivot from the circle's centre, projected on the
/// frame's X and Y; r0 is the mean length error.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Centring {
    pub r0_um: f64,
    pub a_um: f64,
    pub b_um: f64,
}

impl Centring {
    /// The fit at `theta_deg`, without r0, um.
    pub fn offset_um(&self, theta_deg: f64) -> f64 {
        let (sin, cos) = sin_cos_deg(theta_deg);
        self.a_um * cos + self.b_um * sin
    }

    /// [`Centring::offset_um`] from `(sin θ, cos θ)` (the same bits for θ in [0, 360)).
    #[inline]
    pub fn offset_um_at(&self, (sin, cos): (f64, f64)) -> f64 {
        self.a_um * cos + self.b_um * sin
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct Bin {
    n: u64,
    sum_um: f64,
    sum_cos: f64,
    sum_sin: f64,
}

/// What one sample's θ adds to a run whatever its deviation: its bin and the θ terms of
/// the centring's normal equations, computed once per sample for every run it goes to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThetaTerms {
    /// The bin of θ wrapped to [0, 360).
    pub bin: usize,
    pub sin: f64,
    pub cos: f64,
    /// cos² θ, cos θ sin θ, sin² θ.
    pub cos_cos: f64,
    pub cos_sin: f64,
    pub sin_sin: f64,
}

impl ThetaTerms {
    /// The terms of a finite θ (deg, any range) with `(sin θ, cos θ)`; None for a
    /// non-finite θ (its sample is rejected).
    #[inline]
    pub fn new(theta_deg: f64, (sin, cos): (f64, f64)) -> Option<ThetaTerms> {
        theta_deg.is_finite().then(|| ThetaTerms {
            bin: bin_index(wrap_360(theta_deg)),
            sin,
            cos,
            cos_cos: cos * cos,
            cos_sin: cos * sin,
            sin_sin: sin * sin,
        })
    }
}

/// One direction of a ball-bar test, streamed: fixed bins plus the centring sums.
#[derive(Clone, Debug)]
pub struct BallbarRun {
    direction: Direction,
    bins: Vec<Bin>,
    /// Normal-equation sums of phi = (1, cos, sin): `sum phi phi^T` held as its six distinct
    /// entries `[n, sum cos, sum sin, sum cos², sum cos sin, sum sin²]` (n as a float sum,
    /// the matrix's own (0, 0) entry), and `sum phi dL`.
    normal: [f64; 6],
    rhs: [f64; 3],
    samples: u64,
    rejected: u64,
}

/// Stores into one bin of every page `bins` spans, so that each page is first touched by a
/// write. The compiler may turn `vec![Bin::default(); N]` into a zeroed allocation whose
/// fresh pages the kernel maps on first touch; a first touch that reads (a bin's sums
/// loaded before they are stored) maps the shared zero page, and the store after it faults
/// again and flushes the TLB of every core the process runs on: with two threads, a
/// quarter of a study pass's CPU (docs/performance.md). `black_box` hides the stored zero's
/// value, so the store stays.
fn touch_for_writing(bins: &mut [Bin]) {
    let per_page = (4096 / std::mem::size_of::<Bin>()).max(1);
    let last = bins.len().saturating_sub(1);
    for i in (0..bins.len()).step_by(per_page).chain([last]) {
        if let Some(bin) = bins.get_mut(i) {
            bin.n = std::hint::black_box(0);
        }
    }
}

impl BallbarRun {
    pub fn new(direction: Direction) -> Self {
        let mut bins = vec![Bin::default(); N_BINS];
        touch_for_writing(&mut bins);
        BallbarRun {
            direction,
            bins,
            normal: [0.0; 6],
            rhs: [0.0; 3],
            samples: 0,
            rejected: 0,
        }
    }

    pub fn direction(&self) -> Direction {
        self.direction
    }

    /// Adds one sample: theta on the nominal path (deg, any range) and dL (um).
    /// Non-finite samples are counted in [`BallbarRun::rejected`] and otherwise ignored.
    pub fn push(&mut self, theta_deg: f64, deviation_um: f64) {
        if !theta_deg.is_finite() || !deviation_um.is_finite() {
            self.rejected += 1;
            return;
        }
        let t = wrap_360(theta_deg);
        let sin_cos = t.to_radians().sin_cos();
        if let Some(terms) = ThetaTerms::new(t, sin_cos) {
            self.add(&terms, deviation_um);
        }
    }

    /// `a` and `b` (the trace and its signature) take one sample at θ, whose terms are made
    /// once for both (None: θ is not finite), with deviations `dev_a_um` and `dev_b_um`.
    #[inline]
    pub fn push_pair_terms(
        a: &mut BallbarRun,
        b: &mut BallbarRun,
        terms: Option<&ThetaTerms>,
        dev_a_um: f64,
        dev_b_um: f64,
    ) {
        let Some(terms) = terms else {
            a.rejected += 1;
            b.rejected += 1;
            return;
        };
        for (run, dev) in [(a, dev_a_um), (b, dev_b_um)] {
            if dev.is_finite() {
                run.add(terms, dev);
            } else {
                run.rejected += 1;
            }
        }
    }

    /// One sample at θ, whose terms are made by the caller (None: θ is not finite), with
    /// deviation `dev_um`: for runs that take the same samples as a bar (the error budget's).
    #[inline]
    pub fn push_terms(&mut self, terms: Option<&ThetaTerms>, dev_um: f64) {
        match terms {
            Some(terms) if dev_um.is_finite() => self.add(terms, dev_um),
            _ => self.rejected += 1,
        }
    }

    /// Adds a finite sample with θ's `terms`.
    #[inline]
    fn add(&mut self, terms: &ThetaTerms, deviation_um: f64) {
        let &ThetaTerms {
            bin,
            sin,
            cos,
            cos_cos,
            cos_sin,
            sin_sin,
        } = terms;
        let bin = &mut self.bins[bin];
        bin.n += 1;
        bin.sum_um += deviation_um;
        bin.sum_cos += cos;
        bin.sum_sin += sin;
        let n = &mut self.normal;
        n[0] += 1.0;
        n[1] += cos;
        n[2] += sin;
        n[3] += cos_cos;
        n[4] += cos_sin;
        n[5] += sin_sin;
        self.rhs[0] += deviation_um;
        self.rhs[1] += cos * deviation_um;
        self.rhs[2] += sin * deviation_um;
        self.samples += 1;
    }

    /// Adds only the deviation of a sample at θ with `terms`, for a run whose θ sums a run
    /// of the same samples keeps for many ([`BallbarRun::take_theta_sums`]): the bin's sum
    /// of dL and `sum phi dL`, each as [`BallbarRun::add`] forms it. A non-finite deviation
    /// is counted in [`BallbarRun::rejected`], and the θ sums are then not that run's.
    #[inline]
    pub fn add_deviation(&mut self, terms: &ThetaTerms, deviation_um: f64) {
        if !deviation_um.is_finite() {
            self.rejected += 1;
            return;
        }
        self.bins[terms.bin].sum_um += deviation_um;
        self.rhs[0] += deviation_um;
        self.rhs[1] += terms.cos * deviation_um;
        self.rhs[2] += terms.sin * deviation_um;
    }

    /// Completes a run fed by [`BallbarRun::add_deviation`] with the θ sums of `theta`, a
    /// run that took every sample this one did (its bins' counts and sums of cos θ and
    /// sin θ, the normal matrix, the counts): the same sums in the same order, so the same
    /// bits as had this run added every sample itself. False, and nothing taken, when this
    /// run rejected a deviation of its own (its θ sums are then not `theta`'s).
    pub fn take_theta_sums(&mut self, theta: &BallbarRun) -> bool {
        if self.rejected > 0 || self.bins.len() != theta.bins.len() {
            return false;
        }
        for (mine, t) in self.bins.iter_mut().zip(&theta.bins) {
            mine.n = t.n;
            mine.sum_cos = t.sum_cos;
            mine.sum_sin = t.sum_sin;
        }
        self.normal = theta.normal;
        self.samples = theta.samples;
        self.rejected = theta.rejected;
        true
    }

    /// Samples accepted so far.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// Non-finite samples ignored so far.
    pub fn rejected(&self) -> u64 {
        self.rejected
    }

    /// The least-squares centring. With fewer than three distinct angles the fit is
    /// singular and only r0 (the mean) is returned.
    pub fn centring(&self) -> Centring {
        if self.samples == 0 {
            return Centring::default();
        }
        let [n, c, s, cc, cs, ss] = self.normal;
        let normal = Matrix3::new(n, c, s, c, cc, cs, s, cs, ss);
        match normal.try_inverse() {
            Some(inv) if normal.determinant().abs() > 1e-9 * (self.samples as f64).powi(3) => {
                let x = inv * Vector3::from(self.rhs);
                Centring {
                    r0_um: x[0],
                    a_um: x[1],
                    b_um: x[2],
                }
            }
            _ => Centring {
                r0_um: self.rhs[0] / self.samples as f64,
                ..Centring::default()
            },
        }
    }

    /// The binned trace over one revolution: `N_BINS` values, um, at bin centres
    /// `(i + 0.5) BIN_DEG`; raw dL, or with `a cos + b sin` removed when `centred`.
    /// Empty bins are interpolated. Errors when the samples leave a gap over
    /// [`MAX_GAP_DEG`].
    pub fn trace_um(&self, centred: bool) -> Result<Vec<f64>> {
        let fit = if centred {
            self.centring()
        } else {
            Centring::default()
        };
        let mean = |b: &Bin| (b.sum_um - fit.a_um * b.sum_cos - fit.b_um * b.sum_sin) / b.n as f64;
        if self.bins.len() == N_BINS && self.bins.iter().all(|b| b.n > 0) {
            return Ok(Self::every_bin_filled(self.bins.iter().map(mean).collect()));
        }
        let means: Vec<Option<f64>> = self
            .bins
            .iter()
            .map(|b| (b.n > 0).then(|| mean(b)))
            .collect();
        self.fill(&means)
    }

    /// [`BallbarRun::fill`] when every bin holds samples: each bin is its own span of one
    /// bin, `y_i + (y_j − y_i)·0/1` (kept as written: it turns a −0 mean into +0, as `fill`
    /// does).
    fn every_bin_filled(mut means: Vec<f64>) -> Vec<f64> {
        let first = means[0];
        for i in 0..means.len() {
            let (yi, yj) = (means[i], means.get(i + 1).copied().unwrap_or(first));
            means[i] = yi + (yj - yi) * 0.0 / 1.0;
        }
        means
    }

    /// Which bins hold at least one sample.
    pub(super) fn filled_mask(&self) -> Vec<bool> {
        self.bins.iter().map(|b| b.n > 0).collect()
    }

    fn fill(&self, means: &[Option<f64>]) -> Result<Vec<f64>> {
        let filled: Vec<usize> = (0..N_BINS).filter(|&i| means[i].is_some()).collect();
        let direction = match self.direction {
            Direction::Ccw => "CCW",
            Direction::Cw => "CW",
        };
        if filled.len() < 3 {
            return Err(Error::usage(format!(
                "the {direction} ball-bar run holds {} usable samples; push samples over one \
                 full revolution of the measured circle",
                self.samples
            )));
        }
        let mut out = vec![0.0; N_BINS];
        for (k, &i) in filled.iter().enumerate() {
            let j = filled[(k + 1) % filled.len()];
            let gap = (j + N_BINS - i - 1) % N_BINS + 1; // bins from i to j, going up
            if gap as f64 * BIN_DEG > MAX_GAP_DEG {
                return Err(Error::usage(format!(
                    "the {direction} ball-bar run has no samples between theta {:.2} and {:.2} \
                     deg; push samples over one full revolution (gaps up to {MAX_GAP_DEG} deg \
                     are interpolated)",
                    (i as f64 + 0.5) * BIN_DEG,
                    (j as f64 + 0.5) * BIN_DEG
                )));
            }
            let (yi, yj) = (means[i].unwrap_or(0.0), means[j].unwrap_or(0.0));
            for s in 0..gap {
                out[(i + s) % N_BINS] = yi + (yj - yi) * s as f64 / gap as f64;
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::theta::theta_sin_cos;

    /// The sine and cosine a reading carries give the centring's bits.
    #[test]
    fn offset_from_carried_sin_cos_is_the_offset() {
        let c = Centring {
            a_um: 1.234567,
            b_um: -7.654321,
            r0_um: 0.0,
        };
        for k in 0..3600 {
            let theta = k as f64 * 0.1 + 0.013;
            assert_eq!(
                c.offset_um_at(theta_sin_cos(theta)).to_bits(),
                c.offset_um(theta).to_bits()
            );
        }
    }

    /// A run with every bin filled reads each bin's mean (two samples a bin, 1 and 3 µm
    /// apart from the bin's own level, so the mean is level + 2), the same bits as the
    /// general filling of gaps gives; a −0 mean comes out +0, as there.
    #[test]
    fn every_bin_filled_reads_the_bin_means() {
        let mut run = BallbarRun::new(Direction::Ccw);
        let level = |i: usize| {
            if i == 17 {
                -2.0
            } else {
                (i % 13) as f64 * 0.25
            }
        };
        for i in 0..N_BINS {
            let theta = (i as f64 + 0.5) * BIN_DEG;
            run.push(theta, level(i) + 1.0);
            run.push(theta, level(i) + 3.0);
        }
        let trace = run.trace_um(false).unwrap();
        let means: Vec<Option<f64>> = run
            .bins
            .iter()
            .map(|b| Some(b.sum_um / b.n as f64))
            .collect();
        let filled = run.fill(&means).unwrap();
        for i in 0..N_BINS {
            assert_eq!(trace[i], level(i) + 2.0, "bin {i}");
            assert_eq!(trace[i].to_bits(), filled[i].to_bits(), "bin {i}");
        }
        assert_eq!(
            BallbarRun::every_bin_filled(vec![-0.0, -0.0])[0].to_bits(),
            0
        );
    }
}
