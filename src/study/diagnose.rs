//! Ball-bar diagnostics in the Renishaw sense: which machine error a trace shows, and how
//! large, estimated from the trace.
//!
//! # Circle tests (ISO 230-4), plane axes u → v, radius r, both directions
//!
//! With `dL(θ)` the raw radial deviation of each run, its Fourier terms are fitted by least
//! squares (on full-circle bins they are orthogonal): `dL = r0 + a1 cos θ + b1 sin θ +
//! a2 cos 2θ + b2 sin 2θ + ...`. The errors and their closed-form signatures:
//!
//! ```text
//! scale ε_u, ε_v (u_act = (1 + ε_u) u):  dL = r (ε_u cos²θ + ε_v sin²θ)
//!                                        => a2 = r (ε_u - ε_v) / 2, same in both directions
//! squareness α (u_act = u + α v):        dL = r α cos θ sin θ => b2 = r α / 2, both directions
//! servo mismatch (lags T_u = 1/Kv_u, T_v): dL = ± (v/2)(T_u - T_v) sin 2θ
//!                                        => b2 flips with the direction: + for CCW
//! ```
//!
//! so, with `⟨·⟩` the mean over the two directions and `Δ` half their difference (CCW − CW):
//! `scale mismatch ε_u - ε_v = 2 ⟨a2⟩ / r` less the apparent scale mismatch of the lags
//! ([`LagFit::apparent_scale`]) (ppm), `squareness α = 2 ⟨b2⟩ / r` (µrad, positive when the
//! u axis leans toward +v), `servo mismatch T_u - T_v = 2 Δb2 / v` (ms, in full
//! [`LagFit::mismatch_s`]), its peak-to-peak `v |T_u - T_v|`.
//!
//! Each needs both directions: from one, the flipping and the fixed oval are one sin 2θ term
//! (Kv 30/27 alone read as −1,234 µrad of squareness), and the lag also turns the servo oval
//! into a2. From one direction they are NaN (`null` in `summary.json`) with the reason in
//! [`CircleDiagnostics::not_measured`], never numbers.
//!
//! **Cyclic error** of pitch p along axis u (a screw's pitch error) adds
//! `e(u) cos θ` with `e(u) = A cos(2π u / p + φ)`, `u = r cos θ`: after removing the Fourier
//! terms up to order 2, the amplitude A is fitted on the basis
//! `{cos(2π u/p) cos θ, sin(2π u/p) cos θ}` (and `sin θ` for v) for pitches on a grid, and
//! the pitch explaining the most is reported when A is above [`CYCLIC_FLOOR_UM`].
//!
//! # Every test (circle or cone)
//!
//! Backlash and reversal spikes per axis and direction come from the attributed marks:
//! each step or spike whose candidates hold a single axis is that axis's; the ambiguous ones
//! are listed with all their candidates.
//!
//! # The findings of a run folder (for the report)
//!
//! [`diagnose_run`] reads what a run folder holds (the ball-bar result, the reversal angles,
//! the trace rows) and finds, per run of the trace: one spot that makes most of G
//! ([`g_without_peak`]), and a 2θ (elliptical) part large against G ([`ellipse_um`]); per
//! mark: the reversal it sits at; and from the figures: H and the mean radius error when they
//! are large. The 2θ fit here is least squares on the trace's rows, at their θ: unlike the
//! bins of [`harmonics`], the rows need not cover the circle evenly, so the normal equations
//! are solved rather than the Fourier sums taken.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::error::Result;
use crate::input::program::{CircleTest, Direction};
use crate::measure::ballbar::{BallbarResult, EventKind, BIN_DEG};
use crate::measure::BallbarRun;
use crate::report::run::{AxisMarks, Diagnosis, Finding, Mark, RunFolder};
use crate::study::reversals::angular_distance_deg;

/// A cyclic error below this amplitude is not reported, um.
pub const CYCLIC_FLOOR_UM: f64 = 0.2;
/// Pitch grid for the cyclic-error search: from, to (mm) and the relative step (a pitch
/// resolves to about `p / 4r` relative, 0.005 for r = 50 mm at p = 1 mm).
pub const CYCLIC_PITCH_MM: (f64, f64, f64) = (1.0, 40.0, 0.002);

impl Harmonics {
    /// The fit at bin `i`, um.
    pub fn at(&self, i: usize) -> f64 {
        let t = ((i as f64 + 0.5) * BIN_DEG).to_radians();
        self.r0
            + self.a1 * t.cos()
            + self.b1 * t.sin()
            + self.a2 * (2.0 * t).cos()
            + self.b2 * (2.0 * t).sin()
    }
}

/// Fourier coefficients of one run's raw trace up to order 2, um.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Harmonics {
    pub r0: f64,
    pub a1: f64,
    pub b1: f64,
    pub a2: f64,
    pub b2: f64,
}

/// A cyclic error along one axis.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CyclicError {
    pub axis: String,
    pub pitch_mm: f64,
    pub amplitude_um: f64,
}

/// The circle-test diagnostics.
///
/// A figure the data cannot separate from another is NaN here and `null` in `summary.json`
/// (serde_json writes a non-finite number as `null`), never a number, and
/// [`CircleDiagnostics::not_measured`] says why.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CircleDiagnostics {
    /// `ε_u - ε_v`, ppm: the cos 2θ term less the part the measured servo mismatch makes
    /// ([`CircleDiagnostics::servo_scale_ppm`]). NaN from one direction when a servo
    /// mismatch could make more of it than [`SCALE_SEPARATION_PPM`] (or a tenth of it).
    pub scale_mismatch_ppm: f64,
    /// The apparent scale mismatch the measured servo mismatch makes at this feed, taken out
    /// of `scale_mismatch_ppm`, ppm; NaN without both directions.
    pub servo_scale_ppm: f64,
    /// α, µrad: positive when the first plane axis leans toward the second. NaN without
    /// both directions.
    pub squareness_urad: f64,
    /// α in µm per m of travel (the same number as µrad); NaN without both directions.
    pub squareness_um_per_m: f64,
    /// `T_u - T_v = 1/Kv_u - 1/Kv_v`, ms; NaN without both directions.
    pub servo_mismatch_ms: f64,
    /// Peak-to-peak of the servo-mismatch oval, `v |T_u - T_v|`, um; NaN without both
    /// directions.
    pub servo_mismatch_pp_um: f64,
    /// Why a figure above is not measured, by its field name; left out when all are.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub not_measured: BTreeMap<String, String>,
    /// Cyclic errors found, per plane axis.
    pub cyclic: Vec<CyclicError>,
    /// Per run: the fitted harmonics.
    pub harmonics: Vec<(Direction, Harmonics)>,
}

/// From one direction the scale mismatch is reported only when a servo mismatch (which one
/// direction cannot measure) could make at most this much of it, ppm, or a tenth of it.
pub const SCALE_SEPARATION_PPM: f64 = 1.0;

/// Why squareness is not measured from one direction.
pub const SQUARENESS_NEEDS_BOTH: &str = "needs both directions: from one direction a servo \
     mismatch's oval at 45° cannot be told from squareness's";
/// Why the servo mismatch is not measured from one direction.
pub const MISMATCH_NEEDS_BOTH: &str = "needs both directions: a servo mismatch is the part of \
     the oval at 45° that flips with the direction";

/// One attributed reversal mark.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AxisMark {
    /// The axis, or the ambiguous candidates joined by "/".
    pub axis: String,
    pub direction: Direction,
    pub theta_deg: f64,
    /// Step: the level change in the direction of travel; spike: its signed height, um.
    pub height_um: f64,
}

/// What the trace says about the machine.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Diagnostics {
    /// Backlash (and lost motion) steps, per axis and direction.
    pub backlash: Vec<AxisMark>,
    /// Reversal spikes, per axis and direction.
    pub reversal_spikes: Vec<AxisMark>,
    /// For a planar circle test.
    pub circle: Option<CircleDiagnostics>,
}

/// The marks of a ball-bar result, split into steps and spikes, by axis.
pub fn marks(result: &BallbarResult) -> (Vec<AxisMark>, Vec<AxisMark>) {
    let (mut steps, mut spikes) = (Vec::new(), Vec::new());
    for e in &result.events {
        if e.candidates.is_empty() {
            continue;
        }
        let m = AxisMark {
            axis: e.candidates.to_string(),
            direction: e.direction,
            theta_deg: e.theta_deg,
            height_um: e.height_um,
        };
        match e.kind {
            EventKind::Step => steps.push(m),
            EventKind::Spike => spikes.push(m),
        }
    }
    (steps, spikes)
}

/// Fourier terms up to order 2 of a full-circle trace in bins of [`BIN_DEG`].
pub fn harmonics(trace: &[f64]) -> Harmonics {
    let n = trace.len() as f64;
    let mut h = Harmonics::default();
    for (i, &y) in trace.iter().enumerate() {
        let t = ((i as f64 + 0.5) * BIN_DEG).to_radians();
        h.r0 += y / n;
        h.a1 += 2.0 * y * t.cos() / n;
        h.b1 += 2.0 * y * t.sin() / n;
        h.a2 += 2.0 * y * (2.0 * t).cos() / n;
        h.b2 += 2.0 * y * (2.0 * t).sin() / n;
    }
    h
}

/// The circle diagnostics of `runs` (raw traces) of `circle`.
pub fn diagnose_circle(runs: &[BallbarRun], circle: &CircleTest) -> Result<CircleDiagnostics> {
    let r_mm = circle.radius_mm;
    let v_mm_s = circle.feed_mm_min / 60.0;
    let traces: Vec<Vec<f64>> = runs
        .iter()
        .map(|run| run.trace_um(false))
        .collect::<Result<_>>()?;
    let n = traces.first().map_or(0, |t| t.len());
    let mean_trace: Vec<f64> = (0..n)
        .map(|i| traces.iter().map(|t| t[i]).sum::<f64>() / traces.len() as f64)
        .collect();
    let (u, v, _) = circle.axes();
    // The cyclic terms are not orthogonal to the harmonics (cos(z cos θ) cos θ holds every
    // even harmonic): alternate between the two fits, three times.
    let mut cyclic_signal = vec![0.0; n];
    let mut found: Vec<(bool, Cyclic)> = Vec::new();
    for pass in 0..3 {
        let h = harmonics(
            &mean_trace
                .iter()
                .zip(&cyclic_signal)
                .map(|(y, c)| y - c)
                .collect::<Vec<f64>>(),
        );
        let mut residual: Vec<f64> = mean_trace
            .iter()
            .enumerate()
            .map(|(i, &y)| y - h.at(i))
            .collect();
        cyclic_signal = vec![0.0; n];
        let previous = std::mem::take(&mut found);
        for use_cos in [true, false] {
            // The full pitch search once; then around the pitch found.
            let grid = match previous.iter().find(|(k, _)| *k == use_cos) {
                Some((_, c)) if pass > 0 => (c.pitch_mm * 0.99, c.pitch_mm * 1.01, 0.0005),
                _ => CYCLIC_PITCH_MM,
            };
            if let Some(c) = cyclic_error(&residual, r_mm, use_cos, grid) {
                for (i, r) in residual.iter_mut().enumerate() {
                    let s = c.at(i, r_mm, use_cos);
                    *r -= s;
                    cyclic_signal[i] += s;
                }
                found.push((use_cos, c));
            }
        }
    }
    let mut cyclic = Vec::new();
    for (use_cos, c) in &found {
        if c.amplitude_um >= CYCLIC_FLOOR_UM {
            cyclic.push(CyclicError {
                axis: if *use_cos { u } else { v }.to_string(),
                pitch_mm: c.pitch_mm,
                amplitude_um: c.amplitude_um,
            });
        }
    }
    let per_run: Vec<(Direction, Harmonics)> = runs
        .iter()
        .zip(&traces)
        .map(|(run, t)| {
            let clean: Vec<f64> = t.iter().zip(&cyclic_signal).map(|(y, c)| y - c).collect();
            (run.direction(), harmonics(&clean))
        })
        .collect();
    let r0_um = per_run.iter().map(|(_, h)| h.r0).sum::<f64>() / per_run.len().max(1) as f64;
    let (ccw, cw) = (
        direction_mean(&per_run, Direction::Ccw),
        direction_mean(&per_run, Direction::Cw),
    );
    let mut d = CircleDiagnostics {
        scale_mismatch_ppm: f64::NAN,
        servo_scale_ppm: f64::NAN,
        squareness_urad: f64::NAN,
        squareness_um_per_m: f64::NAN,
        servo_mismatch_ms: f64::NAN,
        servo_mismatch_pp_um: f64::NAN,
        not_measured: BTreeMap::new(),
        cyclic,
        harmonics: per_run,
    };
    let (Some(ccw), Some(cw)) = (ccw, cw) else {
        for (figure, why) in [
            ("scale_mismatch_ppm", SCALE_NEEDS_BOTH),
            ("servo_scale_ppm", MISMATCH_NEEDS_BOTH),
            ("squareness_urad", SQUARENESS_NEEDS_BOTH),
            ("squareness_um_per_m", SQUARENESS_NEEDS_BOTH),
            ("servo_mismatch_ms", MISMATCH_NEEDS_BOTH),
            ("servo_mismatch_pp_um", MISMATCH_NEEDS_BOTH),
        ] {
            d.not_measured.insert(figure.to_string(), why.to_string());
        }
        return Ok(d);
    };
    // The servo part of 2θ flips with the direction and cancels in the mean of the two.
    let (a2, b2) = (0.5 * (ccw.a2 + cw.a2), 0.5 * (ccw.b2 + cw.b2));
    let lags = LagFit::of(&ccw, &cw, r0_um, r_mm, v_mm_s);
    let servo_mismatch_s = lags.mismatch_s();
    d.servo_scale_ppm = lags.apparent_scale() * 1e6;
    d.scale_mismatch_ppm = 2.0 * a2 / r_mm * 1e3 - d.servo_scale_ppm;
    d.squareness_urad = 2.0 * b2 / r_mm * 1e3;
    d.squareness_um_per_m = d.squareness_urad;
    d.servo_mismatch_ms = servo_mismatch_s * 1e3;
    d.servo_mismatch_pp_um = v_mm_s * servo_mismatch_s.abs() * 1e3;
    Ok(d)
}

/// Why the scale mismatch is not measured from one direction.
pub const SCALE_NEEDS_BOTH: &str = "needs both directions: a servo mismatch, which only both \
     directions measure, also makes a cos 2θ term (its oval turned by the lag, and an apparent \
     scale mismatch)";

/// The mean harmonics of the runs in `direction`; None without one.
fn direction_mean(per_run: &[(Direction, Harmonics)], direction: Direction) -> Option<Harmonics> {
    let runs: Vec<&Harmonics> = per_run
        .iter()
        .filter(|(d, _)| *d == direction)
        .map(|(_, h)| h)
        .collect();
    let n = runs.len() as f64;
    let mean = |f: fn(&Harmonics) -> f64| runs.iter().map(|h| f(h)).sum::<f64>() / n;
    (!runs.is_empty()).then(|| Harmonics {
        r0: mean(|h| h.r0),
        a1: mean(|h| h.a1),
        b1: mean(|h| h.b1),
        a2: mean(|h| h.a2),
        b2: mean(|h| h.b2),
    })
}

/// The plane axes' lags read from the 2θ terms of a CCW and a CW run, as first-order loops
/// (`φ = atan(ω T)`, amplitude `cos φ`): `φ_u = φ̄ + δ`, `φ_v = φ̄ − δ`.
///
/// Lags turn the axes' sines by `φ_u`, `φ_v` and shrink them to `cos φ`, so the radius is
/// `ρ ≈ r ḡ + (r ḡ/2) sin 2δ sin 2θ' ± …` about the *actual* angle `θ' = θ ∓ φ̄` (CCW, CW),
/// with `ḡ = 1 + r0/r` (the mean radius loss). Turning each run's (a2, b2) back by `2φ̄`,
/// `φ̄ = acos ḡ`, half the CCW − CW difference of the turned b2 is `Δ = (r ḡ/2) sin 2δ`.
struct LagFit {
    /// φ̄, rad.
    mean_rad: f64,
    /// δ, rad.
    half_difference_rad: f64,
    /// ω = v/r, rad/s.
    omega: f64,
}

impl LagFit {
    fn of(ccw: &Harmonics, cw: &Harmonics, r0_um: f64, r_mm: f64, v_mm_s: f64) -> LagFit {
        let g = (1.0 + r0_um * 1e-3 / r_mm).clamp(f64::MIN_POSITIVE, 1.0);
        let lag = g.acos();
        let (s, c) = (2.0 * lag).sin_cos();
        // b2 about θ' = θ − σ φ̄: B = b2 cos 2φ̄ − σ a2 sin 2φ̄ (σ = +1 CCW, −1 CW).
        let turned_ccw = ccw.b2 * c - ccw.a2 * s;
        let turned_cw = cw.b2 * c + cw.a2 * s;
        let flip_mm = 0.5 * (turned_ccw - turned_cw) * 1e-3;
        LagFit {
            mean_rad: lag,
            half_difference_rad: 0.5 * (2.0 * flip_mm / (r_mm * g)).clamp(-1.0, 1.0).asin(),
            omega: v_mm_s / r_mm,
        }
    }

    /// `T_u − T_v = (tan(φ̄ + δ) − tan(φ̄ − δ)) / ω`, s. For small lags this is the classic
    /// `2 Δb2 / v`; at r 10 mm F3000 (ω/Kv ≈ 0.17) the classic form is 16 % short.
    fn mismatch_s(&self) -> f64 {
        let (lag, delta) = (self.mean_rad, self.half_difference_rad);
        ((lag + delta).tan() - (lag - delta).tan()) / self.omega
    }

    /// The scale mismatch the lags alone make, `ε_u − ε_v`: with `u = r cos φ_u cos(θ − φ_u)`,
    /// `v = r cos φ_v sin(θ − φ_v)`, `|p|²/r²` has the cos 2θ term
    /// `(cos²φ_u cos 2φ_u − cos²φ_v cos 2φ_v)/2`, the same in both directions, so
    /// `2 a2 / r = (cos²φ_u cos 2φ_u − cos²φ_v cos 2φ_v)/2 ≈ (3/2) ω² (T_v² − T_u²)`.
    fn apparent_scale(&self) -> f64 {
        let term = |phi: f64| phi.cos().powi(2) * (2.0 * phi).cos();
        let (lag, delta) = (self.mean_rad, self.half_difference_rad);
        0.5 * (term(lag + delta) - term(lag - delta))
    }
}

/// The best pitch (mm) and amplitude (um) of a cyclic error along the axis at `r cos θ`
/// (`use_cos`) or `r sin θ`, projected on the bar by the same factor; least squares on
/// `{cos(2π q/p) w, sin(2π q/p) w}` over the geometric pitch grid `(from, to, relative step)`.
fn cyclic_error(
    residual: &[f64],
    r_mm: f64,
    use_cos: bool,
    (from, to, step): (f64, f64, f64),
) -> Option<Cyclic> {
    let geometry: Vec<(f64, f64)> = (0..residual.len())
        .map(|i| {
            let t = ((i as f64 + 0.5) * BIN_DEG).to_radians();
            if use_cos {
                (r_mm * t.cos(), t.cos())
            } else {
                (r_mm * t.sin(), t.sin())
            }
        })
        .collect();
    let mut best: Option<(f64, Cyclic)> = None; // (explained, fit)
    let steps = ((to / from).ln() / step.ln_1p()).ceil() as i32;
    for k in 0..=steps {
        let p = from * (1.0 + step).powi(k);
        // 2x2 normal equations.
        let (mut cc, mut cs, mut ss, mut cy, mut sy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (&(q, w), &y) in geometry.iter().zip(residual) {
            let (s, c) = (std::f64::consts::TAU * q / p).sin_cos();
            let (c, s) = (c * w, s * w);
            cc += c * c;
            cs += c * s;
            ss += s * s;
            cy += c * y;
            sy += s * y;
        }
        let det = cc * ss - cs * cs;
        if det.abs() < 1e-12 {
            continue;
        }
        let a = (ss * cy - cs * sy) / det;
        let b = (cc * sy - cs * cy) / det;
        let explained = a * cy + b * sy;
        if best.is_none_or(|(e, _)| explained > e) {
            best = Some((
                explained,
                Cyclic {
                    pitch_mm: p,
                    amplitude_um: a.hypot(b),
                    cos_um: a,
                    sin_um: b,
                },
            ));
        }
    }
    best.map(|(_, c)| c)
}

/// A fitted cyclic term: `(c cos(2π q/p) + s sin(2π q/p)) w` with q, w as in [`cyclic_error`].
#[derive(Clone, Copy, Debug)]
struct Cyclic {
    pitch_mm: f64,
    amplitude_um: f64,
    cos_um: f64,
    sin_um: f64,
}

impl Cyclic {
    /// The term at bin `i`, um.
    fn at(&self, i: usize, r_mm: f64, use_cos: bool) -> f64 {
        let t = ((i as f64 + 0.5) * BIN_DEG).to_radians();
        let w = if use_cos { t.cos() } else { t.sin() };
        let (s, c) = (std::f64::consts::TAU * r_mm * w / self.pitch_mm).sin_cos();
        (self.cos_um * c + self.sin_um * s) * w
    }
}

/// The diagnostics of a ball-bar test: marks per axis for every test, and the circle
/// figures when `circle` is given.
pub fn diagnose(
    result: &BallbarResult,
    runs: &[BallbarRun],
    circle: Option<&CircleTest>,
) -> Result<Diagnostics> {
    let (backlash, reversal_spikes) = marks(result);
    Ok(Diagnostics {
        backlash,
        reversal_spikes,
        circle: circle.map(|c| diagnose_circle(runs, c)).transpose()?,
    })
}

/// Peak-to-peak of `dev` with the ±`half_window_deg` around its extreme left out: how much
/// of G one spot makes. Returns (G, G without the spot, θ of the spot); None with fewer
/// than 3 finite points. The spot is the extreme farther from the mean.
pub fn g_without_peak(theta: &[f64], dev: &[f64], half_window_deg: f64) -> Option<(f64, f64, f64)> {
    let finite: Vec<(f64, f64)> = theta
        .iter()
        .zip(dev)
        .filter(|(t, d)| t.is_finite() && d.is_finite())
        .map(|(t, d)| (*t, *d))
        .collect();
    if finite.len() < 3 {
        return None;
    }
    let band = |values: &mut dyn Iterator<Item = f64>| {
        values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        })
    };
    let (lo, hi) = band(&mut finite.iter().map(|p| p.1));
    let mean = finite.iter().map(|p| p.1).sum::<f64>() / finite.len() as f64;
    let spot = finite
        .iter()
        .max_by(|a, b| (a.1 - mean).abs().total_cmp(&(b.1 - mean).abs()))
        .map(|p| p.0)?;
    let mut rest = finite
        .iter()
        .filter(|p| angular_distance_deg(p.0, spot) > half_window_deg)
        .map(|p| p.1)
        .peekable();
    let g_rest = if rest.peek().is_none() {
        0.0
    } else {
        let (rlo, rhi) = band(&mut rest);
        rhi - rlo
    };
    Some((hi - lo, g_rest, spot))
}

/// Least-squares amplitude (µm) and orientation (deg, 0..180) of the 2θ (elliptical) part of
/// `dev` at the angles `theta` (deg): `d ≈ c cos 2θ + s sin 2θ`, amplitude `√(c² + s²)`,
/// long axis at `atan2(s, c) / 2`. None with fewer than 8 finite points or a singular system.
pub fn ellipse_um(theta: &[f64], dev: &[f64]) -> Option<(f64, f64)> {
    let (mut cc, mut ss, mut cs, mut dc, mut ds, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0);
    for (t, d) in theta.iter().zip(dev) {
        if !(t.is_finite() && d.is_finite()) {
            continue;
        }
        let (s2, c2) = (2.0 * t.to_radians()).sin_cos();
        cc += c2 * c2;
        ss += s2 * s2;
        cs += c2 * s2;
        dc += d * c2;
        ds += d * s2;
        n += 1;
    }
    let det = cc * ss - cs * cs;
    if n < 8 || det.abs() < 1e-12 {
        return None;
    }
    let c = (dc * ss - ds * cs) / det;
    let s = (ds * cc - dc * cs) / det;
    Some((
        (c * c + s * s).sqrt(),
        (s.atan2(c).to_degrees() / 2.0).rem_euclid(180.0),
    ))
}

/// A spot makes "most of G" when G without it is less than this share of G.
const DOMINANT_SPOT_SHARE: f64 = 0.5;
/// The window left out around the spot, ± deg.
pub const SPOT_HALF_WINDOW_DEG: f64 = 5.0;

/// [`g_without_peak`] over ±[`SPOT_HALF_WINDOW_DEG`] when the spot makes most of G (G
/// without it below half of G): (G, G without the spot, θ of the spot); None otherwise.
pub fn dominant_spot(theta: &[f64], dev: &[f64]) -> Option<(f64, f64, f64)> {
    g_without_peak(theta, dev, SPOT_HALF_WINDOW_DEG)
        .filter(|&(g, g_rest, _)| g > 0.0 && g_rest < DOMINANT_SPOT_SHARE * g)
}
/// The 2θ part is worth a word above this share of G and above [`ELLIPSE_FLOOR_UM`].
const ELLIPSE_SHARE: f64 = 0.15;
const ELLIPSE_FLOOR_UM: f64 = 0.5;
/// H is worth a word above this share of G.
const HYSTERESIS_SHARE: f64 = 0.3;
/// A mean radius error worth a word, µm.
const RADIUS_FLOOR_UM: f64 = 1.0;

/// The nearest of `angles` to `theta_deg`: (angle, distance), deg; the first of equals.
fn nearest_angle(angles: &[f64], theta_deg: f64) -> Option<(f64, f64)> {
    angles
        .iter()
        .map(|t| (*t, angular_distance_deg(*t, theta_deg)))
        .min_by(|x, y| x.1.total_cmp(&y.1))
}

/// The marks of a run folder's ball-bar result, numbered, each with the reversal it sits
/// at and the trace's deviation there.
fn run_marks(folder: &RunFolder) -> Vec<Mark> {
    let Some(ballbar) = &folder.summary.ballbar else {
        return Vec::new();
    };
    let reversals = &folder.summary.reversals_deg;
    ballbar
        .events
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let theta = e.theta_deg;
            let direction = format!("{:?}", e.direction).to_lowercase();
            // The trace's value where the mark is drawn: at its peak, as the plots and
            // tables give its angle.
            let peak = e.peak_deg;
            let trace_um = folder.trace.as_ref().and_then(|trace| {
                let run = trace.runs.iter().find(|r| r.direction == direction)?;
                let (_, dev) = run
                    .theta_deg
                    .iter()
                    .zip(&run.deviation_centred_um)
                    .filter(|(t, v)| t.is_finite() && v.is_finite())
                    .min_by(|a, b| {
                        angular_distance_deg(*a.0, peak)
                            .total_cmp(&angular_distance_deg(*b.0, peak))
                    })?;
                Some(*dev)
            });
            let (reversal, nearest) = match e.axis {
                Some(axis) => (
                    reversals
                        .get(&axis.to_string())
                        .and_then(|angles| nearest_angle(angles, theta)),
                    None,
                ),
                None => (
                    None,
                    reversals
                        .iter()
                        .flat_map(|(a, angles)| {
                            angles
                                .iter()
                                .map(move |t| (angular_distance_deg(*t, theta), a))
                        })
                        .min_by(|a, b| a.0.total_cmp(&b.0))
                        .map(|(d, a)| (a.clone(), d)),
                ),
            };
            Mark {
                number: i + 1,
                event: *e,
                reversal,
                nearest,
                trace_um,
            }
        })
        .collect()
}

/// The marks as findings, one per axis (or set of candidates) and kind, in the order of
/// their first mark; the unattributed ones last, as one.
fn grouped_marks(folder: &RunFolder, marks: &[Mark]) -> Vec<Finding> {
    let summary = &folder.summary;
    let mut groups: Vec<AxisMarks> = Vec::new();
    let (mut loose, mut loose_um) = (Vec::new(), 0.0f64);
    for m in marks {
        let e = &m.event;
        let Some(axis) = e.axis else {
            loose.push(m.number);
            loose_um = loose_um.max(e.height_um.abs());
            continue;
        };
        let label = if e.ambiguous {
            e.candidates.to_string()
        } else {
            axis.to_string()
        };
        match groups
            .iter_mut()
            .find(|g| g.axis == label && g.kind == e.kind)
        {
            Some(g) => {
                g.numbers.push(m.number);
                g.largest_um = g.largest_um.max(e.height_um.abs());
            }
            None => groups.push(AxisMarks {
                machine: label
                    .split('/')
                    .filter_map(|a| Some((a.to_string(), *summary.reversal_values.get(a)?)))
                    .collect(),
                b_um: summary
                    .reversal_b
                    .iter()
                    .find(|r| r.axis == label)
                    .and_then(|r| r.b_um),
                axis: label,
                kind: e.kind,
                numbers: vec![m.number],
                largest_um: e.height_um.abs(),
            }),
        }
    }
    let mut out: Vec<Finding> = groups.into_iter().map(Finding::AxisMarks).collect();
    if !loose.is_empty() {
        out.push(Finding::Unattributed {
            numbers: loose,
            largest_um: loose_um,
        });
    }
    out
}

/// What a run folder says about the machine, for the report: its marks, and the findings
/// in the order the page lists them (per trace run the dominant spot and the 2θ part, the
/// marks, H, the mean radius per run, a cone's block sawtooth).
pub fn diagnose_run(folder: &RunFolder) -> Diagnosis {
    let marks = run_marks(folder);
    let Some(ballbar) = &folder.summary.ballbar else {
        return Diagnosis {
            marks,
            findings: vec![Finding::NoCircle],
        };
    };
    let g = ballbar.circular_deviation_um;
    let mut findings = Vec::new();
    for run in folder.trace.iter().flat_map(|t| &t.runs) {
        let (theta, dev) = (&run.theta_deg, &run.deviation_centred_um);
        if let Some((g_um, g_without_um, theta_deg)) = dominant_spot(theta, dev) {
            findings.push(Finding::DominantSpot {
                direction: run.direction.clone(),
                theta_deg,
                g_um,
                g_without_um,
            });
        }
        if let Some((amplitude_um, long_axis_deg)) = ellipse_um(theta, dev) {
            if g.is_finite() && amplitude_um > ELLIPSE_SHARE * g && amplitude_um > ELLIPSE_FLOOR_UM
            {
                findings.push(Finding::Elliptical {
                    direction: run.direction.clone(),
                    amplitude_um,
                    long_axis_deg,
                });
            }
        }
    }
    findings.extend(grouped_marks(folder, &marks));
    if let Some(h_um) = ballbar.hysteresis_um {
        if g.is_finite() && h_um > HYSTERESIS_SHARE * g {
            findings.push(Finding::Hysteresis { h_um });
        }
    }
    for run in &ballbar.runs {
        let r0_um = run.centring.r0_um;
        if r0_um.abs() > RADIUS_FLOOR_UM {
            findings.push(Finding::RadiusOffset {
                direction: format!("{:?}", run.direction).to_lowercase(),
                r0_um,
            });
        }
    }
    if folder
        .test
        .as_ref()
        .is_some_and(|t| t.test.starts_with("cone") && !t.tcp)
    {
        findings.push(Finding::BlockSawtooth);
    }
    if findings.is_empty() {
        findings.push(Finding::Nothing);
    }
    Diagnosis { marks, findings }
}
