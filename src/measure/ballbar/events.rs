//! Spikes and steps in a centred trace: the noise, the detector, trains of spikes merged into
//! one mark, each attributed to the axis reversing where the bar can see it.

use super::circular::{circular_regions, median, running_circular_median};
use super::result::{EventKind, TraceEvent};
use super::steps::find_steps;
use super::tuning::*;
use crate::input::program::Direction;
use crate::measure::attribution::{attribute_arc, attribute_to_sites, AxisSet, ReversalSite};
use crate::measure::theta::{angle_distance_deg, bin_index, bins, wrap_360, BIN_DEG};

/// Noise standard deviation from the differences of neighbouring filled bins, um.
pub(super) fn noise_sigma(trace: &[f64], filled: &[bool]) -> f64 {
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

pub(super) fn detect_events(
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
