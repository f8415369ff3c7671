//! The virtual ball bar: deviation, the angle theta, streamed runs, ISO 230-4 figures, and
//! spike and step detection with attribution to the reversing axis.
//!
//! # Deviation
//!
//! One ball sits at `pivot` on the table (table frame T), the other at the tool tip. With
//! actual axis positions q, both are expressed in the machine frame M:
//!
//! ```text
//! p_tool  = (X, Y, Z)                         (actual tool tip)
//! p_pivot = T_tilt(q) T_C(q) (pivot_M + pivot) (Kinematics::actual_table_to_machine: the
//!                                             actual chain, with the location errors)
//! dL      = |p_tool - p_pivot| - L            (mm)
//! ```
//!
//! # Theta
//!
//! A [`CircleFrame`] holds the measured circle's frame in the table frame: an origin o and a
//! rotation R whose columns are the frame's axes. A table point p has frame coordinates
//! `v = R^T (p - o)` and `theta = atan2(v_y, v_x)` in [0, 360) deg: counter-clockwise from the
//! frame's +X seen from its +Z. The cone frame is `o = O`, `R = Ry(-beta)`; a planar circle
//! in G17/G18/G19 uses the plane's two axes in G-code order (X→Y, Z→X, Y→Z).
//!
//! # Runs and centring
//!
//! A [`BallbarRun`] keeps, in O(1) memory in the number of samples, fixed bins of
//! [`BIN_DEG`] and the normal-equation sums of the least-squares fit
//! `dL = r0 + a cos theta + b sin theta`. Each bin holds its sample count and the sums of
//! dL, cos theta and sin theta, so the *centred* bin mean
//! `(sum dL - a sum cos - b sum sin) / n` is exact for the samples it holds. Empty bins are
//! filled by linear interpolation between their filled neighbours (around the circle).
//!
//! # Figures (ISO 230-4), on the binned trace
//!
//! - G, circular deviation: max - min of the centred trace `dL - a cos - b sin`.
//! - F, radial deviation: max and min of the raw trace dL (relative to the nominal length).
//! - H, circular hysteresis: max over theta of `|dL_ccw - dL_cw|`. Both runs share one
//!   pivot, so this is the difference about a common centre.
//!
//! # Events
//!
//! See [`analyse`]: steps are persistent level changes found with far, robust windows; spikes
//! are short excursions above a smooth local baseline; each is attributed to the axis whose
//! reversal angle is nearest to its onset.

use std::borrow::Cow;

use nalgebra::{DMatrix, DVector, Matrix3, Point3, Rotation3, Vector3};
use serde::{Deserialize, Serialize};

use super::attribution::{attribute_arc, attribute_to_sites, AxisSet, ReversalSite};
use super::theta::{bin_index, bins, wrap_360};
use crate::error::{Error, Result};
use crate::input::program::{ConeTest, Direction};
use crate::numeric::sin_cos_deg;
use crate::Axis;
use crate::Plane;

/// Largest angular gap between filled bins a run may have, deg.
pub const MAX_GAP_DEG: f64 = 10.0;
/// Highest harmonic of the smooth shape removed before looking for events.
pub const SMOOTH_ORDER: usize = 6;
/// Half-width of the running-median baseline for spikes, deg.
pub const BASELINE_HALF_WINDOW_DEG: f64 = 5.0;
/// Steps: the level on each side is the median over a window this far from the step, deg...
pub const STEP_GAP_DEG: f64 = 3.0;
/// ...and this wide, deg.
pub const STEP_WINDOW_DEG: f64 = 6.0;
/// Events must exceed this many noise standard deviations...
pub const NOISE_FACTOR: f64 = 6.0;
/// ...and at least this height for a spike, um...
pub const SPIKE_FLOOR_UM: f64 = 0.5;
/// ...or this height for a step, um.
pub const STEP_FLOOR_UM: f64 = 1.0;
pub use super::attribution::{ATTRIBUTION_MAX_DEG, ONSET_SIGMA_DEG};
pub use super::bar::deviation_mm;
pub use super::theta::{angle_distance_deg, theta_sin_cos, BIN_DEG, N_BINS};

/// The measured circle's frame in the table frame: origin (mm) and orientation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CircleFrame {
    /// Origin, table frame, mm.
    pub origin_mm: Vector3<f64>,
    /// Frame axes as columns, in table coordinates.
    pub rotation: Rotation3<f64>,
}

impl CircleFrame {
    /// The cone frame: origin O = `center_mm` (table frame), rotated by `Ry(-inclination)`.
    pub fn cone(center_mm: [f64; 3], inclination_deg: f64) -> Self {
        CircleFrame {
            origin_mm: Vector3::from(center_mm),
            rotation: Rotation3::from_axis_angle(&Vector3::y_axis(), -inclination_deg.to_radians()),
        }
    }

    /// A circle in `plane` about `center_mm`; theta runs from the plane's first axis toward
    /// its second (XY: X→Y, ZX: Z→X, YZ: Y→Z), counter-clockwise seen from the normal.
    pub fn planar(center_mm: [f64; 3], plane: Plane) -> Self {
        let (x, y, z) = match plane {
            Plane::XY => (Vector3::x(), Vector3::y(), Vector3::z()),
            Plane::ZX => (Vector3::z(), Vector3::x(), Vector3::y()),
            Plane::YZ => (Vector3::y(), Vector3::z(), Vector3::x()),
        };
        CircleFrame {
            origin_mm: Vector3::from(center_mm),
            rotation: Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z])),
        }
    }

    /// The measured circle of a cone-frustum test.
    pub fn of_cone(cone: &ConeTest) -> Self {
        CircleFrame::cone(cone.center_mm.into(), cone.inclination_deg)
    }

    /// Theta of a table-frame point, deg in [0, 360).
    pub fn theta_deg(&self, p_table: &Point3<f64>) -> f64 {
        let v = self.rotation.inverse() * (p_table.coords - self.origin_mm);
        wrap_360(v.y.atan2(v.x).to_degrees())
    }

    /// [`CircleFrame::theta_deg`] with `(sin θ, cos θ)` from the point's own coordinates in
    /// the circle's plane, `(y, x) / √(x² + y²)` (from [`theta_sin_cos`] where the point is on
    /// the circle's axis).
    #[inline]
    pub fn theta_deg_sin_cos(&self, p_table: &Point3<f64>) -> (f64, (f64, f64)) {
        let v = self.rotation.inverse() * (p_table.coords - self.origin_mm);
        let theta = wrap_360(v.y.atan2(v.x).to_degrees());
        let r = (v.x * v.x + v.y * v.y).sqrt();
        if r > 0.0 && r.is_finite() {
            let inv = 1.0 / r;
            (theta, (v.y * inv, v.x * inv))
        } else {
            (theta, theta_sin_cos(theta))
        }
    }
}

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
    fn filled_mask(&self) -> Vec<bool> {
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

/// Spike or step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EventKind {
    /// A short excursion that returns to the baseline.
    Spike,
    /// A persistent level change.
    Step,
}

/// A spike or step found in a centred trace.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TraceEvent {
    /// Onset angle, deg: where the event leaves the baseline (a step's position).
    pub theta_deg: f64,
    /// Angle of the peak (spike) or the step position, deg.
    pub peak_deg: f64,
    /// Height, um: a spike's signed peak above the baseline; a step's signed level change in
    /// the direction of travel.
    pub height_um: f64,
    /// Full width at half height, deg (0 for a step).
    pub width_deg: f64,
    /// The arc the mark covers from its first onset to its last peak, deg: more than the
    /// width for a train of spikes (stick-slip or ringing after a reversal), 0 for a step.
    pub extent_deg: f64,
    pub kind: EventKind,
    pub direction: Direction,
    /// The leading axis: the one whose reversal (where the bar can see it) is nearest the
    /// onset, within [`ATTRIBUTION_MAX_DEG`]; see [`super::attribution`].
    pub axis: Option<Axis>,
    /// 0..1: the Gaussian likelihood share of that axis among all sensitive axes' nearest
    /// reversals (onset uncertainty [`ONSET_SIGMA_DEG`]) and "no axis" at [`ATTRIBUTION_MAX_DEG`].
    pub confidence: f64,
    /// Every axis the mark may come from: those reversing within the tie tolerance of the
    /// leading one, where the bar can see them (the leading axis included).
    pub candidates: AxisSet,
    /// More than one candidate: the trace cannot tell these axes apart here.
    pub ambiguous: bool,
}

/// Figures of one run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunFigures {
    pub direction: Direction,
    pub samples: u64,
    pub centring: Centring,
    pub circular_deviation_um: f64,
    pub radial_max_um: f64,
    pub radial_min_um: f64,
    /// Noise standard deviation estimated from the binned trace, um.
    pub noise_um: f64,
}

/// The ISO 230-4 figures and the events of one test.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BallbarResult {
    /// G: the largest over the runs, um.
    pub circular_deviation_um: f64,
    /// F max: the largest over the runs, um.
    pub radial_max_um: f64,
    /// F min: the smallest over the runs, um.
    pub radial_min_um: f64,
    /// H between the first CCW and the first CW run, um; None with one direction.
    pub hysteresis_um: Option<f64>,
    /// Spikes and steps of all runs, by run then theta.
    #[serde(rename = "spikes")]
    pub events: Vec<TraceEvent>,
    pub runs: Vec<RunFigures>,
}

/// Computes G, F, H and the events. `reversals`: each axis's analytic reversal angles, deg.
///
/// Event detection on each run's centred trace c (bins of [`BIN_DEG`]):
/// 1. Noise sigma = 1.4826 MAD of the differences of filled neighbouring bins / sqrt 2.
/// 2. Smooth shape and steps, fitted jointly by least squares: the Fourier series up to
///    harmonic [`SMOOTH_ORDER`] plus one jump per step (so a step does not bend the smooth
///    fit). Steps are added greedily: in the residual r,
///    `S(i) = median(r, right window) - median(r, left window)`, with windows
///    [`STEP_WINDOW_DEG`] wide starting [`STEP_GAP_DEG`] from i. A spike has decayed inside
///    the gap and a median barely sees it, while a step gives a trapezoid of height h
///    centred on it. The largest region with |S| above the threshold becomes a step at the
///    middle of its part above half its peak; refit; repeat until none is left. The step's
///    height is its fitted jump.
/// 3. Spikes: the residual of that fit minus its running median (half-window
///    [`BASELINE_HALF_WINDOW_DEG`]); a spike is a region above half the threshold that
///    reaches the threshold. The onset is where, walking back in time from the peak, the
///    residual falls below 10 % of the height. Spikes within 1.5 deg of a step at least as
///    high belong to it and are not reported; a smaller step never hides a larger spike.
///
/// Threshold: `max(NOISE_FACTOR sigma, floor)`.
pub fn analyse(runs: &[BallbarRun], reversals: &[(Axis, Vec<f64>)]) -> Result<BallbarResult> {
    analyse_events_of(runs, runs, reversals)
}

/// As [`analyse`], but the spikes and steps are detected in `event_runs` instead of `runs`:
/// a simulation passes the nonlinear signature of each run (trace minus a linear twin), so
/// that the linear response to the program is not taken for events. The figures still come
/// from `runs`.
pub fn analyse_events_of(
    runs: &[BallbarRun],
    event_runs: &[BallbarRun],
    reversals: &[(Axis, Vec<f64>)],
) -> Result<BallbarResult> {
    analyse_events_at(runs, event_runs, &ReversalSite::unweighted(reversals))
}

/// As [`analyse_events_of`], with each reversal's bar sensitivity known: marks are
/// attributed only to axes the bar can see there ([`super::attribution`]).
pub fn analyse_events_at(
    runs: &[BallbarRun],
    event_runs: &[BallbarRun],
    sites: &[ReversalSite],
) -> Result<BallbarResult> {
    if runs.is_empty() {
        return Err(Error::usage(
            "no ball-bar run to analyse; record at least one direction",
        ));
    }
    let mut figures = Vec::with_capacity(runs.len());
    let mut events = Vec::new();
    let mut raw_traces = Vec::with_capacity(runs.len());
    for run in runs {
        let raw = run.trace_um(false)?;
        let centred = run.trace_um(true)?;
        let noise = noise_sigma(&centred, &run.filled_mask());
        let (cmin, cmax) = min_max(&centred);
        let (rmin, rmax) = min_max(&raw);
        figures.push(RunFigures {
            direction: run.direction,
            samples: run.samples,
            centring: run.centring(),
            circular_deviation_um: cmax - cmin,
            radial_max_um: rmax,
            radial_min_um: rmin,
            noise_um: noise,
        });
        raw_traces.push(raw);
    }
    for run in event_runs {
        let centred = run.trace_um(true)?;
        let noise = noise_sigma(&centred, &run.filled_mask());
        events.extend(detect_events(&centred, noise, run.direction, sites));
    }
    let first = |d: Direction| runs.iter().position(|r| r.direction == d);
    let hysteresis_um = match (first(Direction::Ccw), first(Direction::Cw)) {
        (Some(i), Some(j)) => Some(
            raw_traces[i]
                .iter()
                .zip(&raw_traces[j])
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f64::max),
        ),
        _ => None,
    };
    Ok(BallbarResult {
        circular_deviation_um: figures
            .iter()
            .map(|f| f.circular_deviation_um)
            .fold(f64::NEG_INFINITY, f64::max),
        radial_max_um: figures
            .iter()
            .map(|f| f.radial_max_um)
            .fold(f64::NEG_INFINITY, f64::max),
        radial_min_um: figures
            .iter()
            .map(|f| f.radial_min_um)
            .fold(f64::INFINITY, f64::min),
        hysteresis_um,
        events,
        runs: figures,
    })
}

/// The leading axis for a mark at `theta_deg` and its confidence, all reversals taken as
/// visible to the bar (see [`super::attribution::attribute_to_sites`]).
pub fn attribute(theta_deg: f64, reversals: &[(Axis, Vec<f64>)]) -> (Option<Axis>, f64) {
    let a = attribute_to_sites(theta_deg, &ReversalSite::unweighted(reversals));
    (a.axis, a.confidence)
}

fn min_max(v: &[f64]) -> (f64, f64) {
    v.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
            (lo.min(x), hi.max(x))
        })
}

fn median(buf: &mut [f64]) -> f64 {
    let mid = buf.len() / 2;
    let (_, m, _) = buf.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

/// For every i, the median of `v[i + offset .. i + offset + len]` (indices around the
/// circle; the upper median for even `len`), as [`median`] gives it. The window is kept
/// sorted and slid one bin at a time: the values between the leaving value's place and the
/// entering value's move by one. The window holds each value's [`total_order_key`], so that
/// its searches compare integers in the order of [`f64::total_cmp`]: the median is the
/// same value, bit for bit.
fn running_circular_median(v: &[f64], offset: isize, len: usize) -> Vec<f64> {
    let n = v.len() as isize;
    let keys: Vec<i64> = v.iter().map(|&x| total_order_key(x)).collect();
    // `k.rem_euclid(n)` without a division for k within a turn of [0, n).
    let at = |k: isize| {
        let i = if k < 0 {
            k + n
        } else if k >= n {
            k - n
        } else {
            k
        };
        keys[if (0..n).contains(&i) {
            i
        } else {
            k.rem_euclid(n)
        } as usize]
    };
    let mut window: Vec<i64> = (0..len as isize).map(|k| at(offset + k)).collect();
    window.sort_unstable();
    let mut out = Vec::with_capacity(v.len());
    for i in 0..n {
        if i > 0 {
            let leaving = at(i - 1 + offset);
            let entering = at(i + offset + len as isize - 1);
            let from = window.partition_point(|&x| x < leaving);
            let to = window.partition_point(|&x| x < entering);
            // Removing `from` and inserting at the entering value's place in what is left.
            if to <= from {
                window.copy_within(to..from, to + 1);
                window[to] = entering;
            } else {
                window.copy_within(from + 1..to, from);
                window[to - 1] = entering;
            }
        }
        out.push(from_total_order_key(window[len / 2]));
    }
    out
}

/// An integer that orders as [`f64::total_cmp`] orders `x`: the bits, with those below the
/// sign flipped for negative values (an involution: [`from_total_order_key`] undoes it).
fn total_order_key(x: f64) -> i64 {
    let bits = x.to_bits() as i64;
    bits ^ (((bits >> 63) as u64) >> 1) as i64
}

/// The value whose [`total_order_key`] is `key`.
fn from_total_order_key(key: i64) -> f64 {
    f64::from_bits((key ^ (((key >> 63) as u64) >> 1) as i64) as u64)
}

/// Noise standard deviation from the differences of neighbouring filled bins, um.
fn noise_sigma(trace: &[f64], filled: &[bool]) -> f64 {
    let Some(first) = (0..trace.len()).find(|&i| filled[i]) else {
        return 0.0;
    };
    // Each filled bin to the next one around the circle, the last back to the first.
    let mut diffs = Vec::with_capacity(trace.len());
    let mut previous = first;
    for j in first + 1..trace.len() {
        if filled[j] {
            diffs.push((trace[j] - trace[previous]).abs());
            previous = j;
        }
    }
    diffs.push((trace[first] - trace[previous]).abs());
    1.4826 * median(&mut diffs) / 2f64.sqrt()
}

/// A step at the boundary before bin `index` (angle `index * BIN_DEG`), height in
/// increasing theta, um.
#[derive(Clone, Copy, Debug)]
struct Step {
    index: usize,
    height_um: f64,
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
fn find_steps(c: &[f64], threshold: f64, anchors: &[usize]) -> (Vec<Step>, Vec<f64>) {
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

/// Spikes whose peaks follow each other within this are one mark: a train (stick-slip of
/// an axis creeping through its reversal, or ringing after it), deg.
pub const TRAIN_GAP_DEG: f64 = 3.0;

/// Merges trains of spikes into one mark each (see [`TRAIN_GAP_DEG`]): the largest spike's
/// peak, height and width, the onset of the first in the direction of travel, the extent
/// from the earliest to the latest angle of the train; attributed over that arc.
fn merge_trains(mut spikes: Vec<TraceEvent>, sites: &[ReversalSite]) -> Vec<TraceEvent> {
    if spikes.is_empty() {
        return spikes;
    }
    spikes.sort_by(|a, b| a.peak_deg.total_cmp(&b.peak_deg));
    let m = spikes.len();
    let gap_after =
        |i: usize| (spikes[(i + 1) % m].peak_deg - spikes[i].peak_deg).rem_euclid(360.0);
    // Start at a spike preceded by a gap (if every gap is small, the train is the circle).
    let start = (0..m)
        .find(|&i| m == 1 || gap_after((i + m - 1) % m) > TRAIN_GAP_DEG)
        .unwrap_or(0);
    let mut trains: Vec<Vec<usize>> = Vec::new();
    for k in 0..m {
        let i = (start + k) % m;
        if k == 0 || gap_after((i + m - 1) % m) > TRAIN_GAP_DEG {
            trains.push(vec![i]);
        } else {
            trains.last_mut().expect("started").push(i);
        }
    }
    trains
        .into_iter()
        .map(|train| {
            let main = *train
                .iter()
                .max_by(|&&a, &&b| {
                    spikes[a]
                        .height_um
                        .abs()
                        .total_cmp(&spikes[b].height_um.abs())
                })
                .expect("non-empty");
            let mut e = spikes[main];
            // Angles of the train measured from a point before it.
            let base = spikes[train[0]].peak_deg - 10.0;
            let off = |a: f64| (a - base).rem_euclid(360.0);
            let (lo, hi) = train
                .iter()
                .flat_map(|&i| [off(spikes[i].theta_deg), off(spikes[i].peak_deg)])
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
                    (l.min(x), h.max(x))
                });
            e.theta_deg = match e.direction {
                Direction::Ccw => wrap_360(base + off(spikes[train[0]].theta_deg)),
                Direction::Cw => {
                    wrap_360(base + off(spikes[*train.last().expect("non-empty")].theta_deg))
                }
            };
            e.extent_deg = hi - lo;
            let who = attribute_arc(wrap_360(base + lo), hi - lo, sites);
            e.axis = who.axis;
            e.confidence = who.confidence;
            e.candidates = who.candidates;
            e.ambiguous = who.candidates.len() > 1;
            e
        })
        .collect()
}

/// Contiguous runs (around the circle) of indices where `inside(i)`; each as a list of
/// indices in increasing order from its start.
fn circular_regions(n: usize, inside: impl Fn(usize) -> bool) -> Vec<Vec<usize>> {
    let Some(start) = (0..n).find(|&i| !inside(i)) else {
        return Vec::new();
    };
    let mut regions = Vec::new();
    let mut current: Vec<usize> = Vec::new();
    for k in 1..=n {
        let i = (start + k) % n;
        if inside(i) {
            current.push(i);
        } else if !current.is_empty() {
            regions.push(std::mem::take(&mut current));
        }
    }
    regions
}

fn detect_events(
    c: &[f64],
    noise: f64,
    direction: Direction,
    sites: &[ReversalSite],
) -> Vec<TraceEvent> {
    let n = c.len();
    let step_threshold = (NOISE_FACTOR * noise).max(STEP_FLOOR_UM);
    // With the reversal angles known (and visible to the bar), steps are looked for there.
    let mut anchors: Vec<usize> = sites
        .iter()
        .filter(|s| s.visible() && s.theta_deg.is_finite())
        .map(|s| bin_index(wrap_360(s.theta_deg)))
        .collect();
    anchors.sort_unstable();
    anchors.dedup();
    let (steps, fit) = find_steps(c, step_threshold, &anchors);
    let flat: Vec<f64> = c.iter().zip(&fit).map(|(x, f)| x - f).collect();

    // Spikes above a running median.
    let half = bins(BASELINE_HALF_WINDOW_DEG) as isize;
    let baseline = running_circular_median(&flat, -half, 2 * half as usize + 1);
    let res: Vec<f64> = flat.iter().zip(&baseline).map(|(f, b)| f - b).collect();
    let threshold = (NOISE_FACTOR * noise).max(SPIKE_FLOOR_UM);
    let angle = |i: usize| i as f64 * BIN_DEG;
    let centre = |i: usize| (i as f64 + 0.5) * BIN_DEG;
    // Walking back in time: CCW runs came from lower theta.
    let back: isize = match direction {
        Direction::Ccw => -1,
        Direction::Cw => 1,
    };
    let at = |i: isize| res[i.rem_euclid(n as isize) as usize];
    let mut events = Vec::new();
    let mut spikes = Vec::new();
    for sign in [1.0, -1.0] {
        for region in circular_regions(n, |i| sign * res[i] > 0.5 * threshold) {
            let Some(&peak) = region
                .iter()
                .max_by(|&&i, &&j| (sign * res[i]).total_cmp(&(sign * res[j])))
            else {
                continue;
            };
            let height = res[peak];
            if sign * height < threshold {
                continue;
            }
            // A spike next to a step is the step's own transient only if the step is larger:
            // a step never hides a larger spike.
            let near_step = steps.iter().any(|s| {
                s.height_um.abs() >= sign * height
                    && region
                        .iter()
                        .any(|&i| angle_distance_deg(centre(i), angle(s.index)) < 1.5)
            });
            if near_step {
                continue;
            }
            // Onset: walk back in time while above 10 % of the height (at most 5 deg).
            let floor = 0.1 * sign * height;
            let mut first = peak as isize;
            for _ in 0..bins(5.0) {
                if sign * at(first + back) <= floor {
                    break;
                }
                first += back;
            }
            let first = first.rem_euclid(n as isize) as usize;
            let onset = match direction {
                Direction::Ccw => angle(first),
                Direction::Cw => angle((first + 1) % n),
            };
            // Full width at half height, contiguous around the peak.
            let above = |i: isize| sign * at(i) >= 0.5 * sign * height;
            let mut width = 1;
            let mut k = 1;
            while k < n as isize && above(peak as isize + k) {
                width += 1;
                k += 1;
            }
            k = 1;
            while k < n as isize && above(peak as isize - k) {
                width += 1;
                k += 1;
            }
            spikes.push(TraceEvent {
                theta_deg: onset,
                peak_deg: centre(peak),
                height_um: height,
                width_deg: width as f64 * BIN_DEG,
                extent_deg: 0.0,
                kind: EventKind::Spike,
                direction,
                axis: None,
                confidence: 0.0,
                candidates: AxisSet::EMPTY,
                ambiguous: false,
            });
        }
    }
    events.extend(merge_trains(spikes, sites));
    for s in &steps {
        let theta = angle(s.index);
        let who = attribute_to_sites(theta, sites);
        events.push(TraceEvent {
            theta_deg: theta,
            peak_deg: theta,
            height_um: match direction {
                Direction::Ccw => s.height_um,
                Direction::Cw => -s.height_um,
            },
            width_deg: 0.0,
            extent_deg: 0.0,
            kind: EventKind::Step,
            direction,
            axis: who.axis,
            confidence: who.confidence,
            candidates: who.candidates,
            ambiguous: who.candidates.len() > 1,
        });
    }
    events.sort_by(|a, b| a.theta_deg.total_cmp(&b.theta_deg));
    events
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// The running median equals the median of each window sorted afresh, bit for bit: on a
    /// trace with repeated values, ±0, infinities and a NaN, windows of odd and even length,
    /// ahead of and behind the bin, and one longer than the trace.
    #[test]
    fn running_median_is_each_windows_median() {
        let mut v: Vec<f64> = (0..500)
            .map(|i| ((i * 7919) % 37) as f64 * 0.5 - 9.0 + ((i * 31) % 5) as f64 * 1e-3)
            .collect();
        (v[3], v[4], v[40], v[41], v[200], v[300]) =
            (0.0, -0.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, -0.0);
        let n = v.len() as isize;
        for (offset, len) in [
            (-100, 201),
            (30, 120),
            (-150, 120),
            (0, 1),
            (-7, 4),
            (-20, 600),
        ] {
            let running = running_circular_median(&v, offset, len);
            for i in 0..n {
                let mut w: Vec<f64> = (0..len as isize)
                    .map(|k| v[(i + offset + k).rem_euclid(n) as usize])
                    .collect();
                let m = median(&mut w);
                assert_eq!(
                    running[i as usize].to_bits(),
                    m.to_bits(),
                    "{offset} {len} {i}"
                );
            }
        }
        for x in [0.0, -0.0, 1.5, -1.5, f64::MIN_POSITIVE, -f64::MAX, f64::NAN] {
            assert_eq!(
                from_total_order_key(total_order_key(x)).to_bits(),
                x.to_bits()
            );
        }
    }

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
