//! G, F and H of ISO 230-4 from the runs' binned traces, and the events of their signatures.

use super::events::{detect_events, noise_sigma};
use super::result::{BallbarResult, RunFigures};
use super::run::BallbarRun;
use crate::error::{Error, Result};
use crate::input::program::Direction;
use crate::measure::attribution::{attribute_to_sites, ReversalSite};
use crate::Axis;

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
            direction: run.direction(),
            samples: run.samples(),
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
        events.extend(detect_events(&centred, noise, run.direction(), sites));
    }
    let first = |d: Direction| runs.iter().position(|r| r.direction() == d);
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
        feed: None,
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
