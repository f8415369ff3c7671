//! The limits monitor: travel, velocity and acceleration of every axis, checked on every
//! sample (not only at block ends), with violations merged into intervals.
//!
//! Velocity, acceleration and jerk are finite differences of the samples:
//! `v_k = (q_k - q_{k-1}) / Δt`, `a_k = (v_k - v_{k-1}) / Δt`, `j_k = (a_k - a_{k-1}) / Δt`.
//! On the planner's samples (the default) they are measured everywhere, junctions included.
//! At programmed timing a junction between two straight blocks is a step in velocity, which
//! no real controller executes (its planner rounds the corner), so there acceleration and
//! jerk are taken only from samples inside one block ([`LimitsMonitor::within_blocks`]).
//! Jerk is reported, not checked: the planner bounds the velocity step at a junction by the
//! axis's acceleration over one period, not its jerk.

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::input::machine::Machine;
use crate::pipeline::{Sample, Sink};
use crate::{Axis, AxisVec};

/// The kind of a violation, as scripts read it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ViolationKind {
    Travel,
    Velocity,
    Acceleration,
    Collision,
    NearMiss,
}

impl ViolationKind {
    /// The kind's name in JSON ("near_miss").
    pub fn name(self) -> &'static str {
        match self {
            ViolationKind::Travel => "travel",
            ViolationKind::Velocity => "velocity",
            ViolationKind::Acceleration => "acceleration",
            ViolationKind::Collision => "collision",
            ViolationKind::NearMiss => "near_miss",
        }
    }
}

/// One violation: an interval of samples over which a limit is exceeded.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Violation {
    pub kind: ViolationKind,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis: Option<Axis>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bodies: Option<[String; 2]>,
    /// θ of the first and last sample in violation, deg (null without a cone or circle).
    pub theta_start_deg: Option<f64>,
    pub theta_end_deg: Option<f64>,
    /// Time of the first and last sample in violation, s.
    pub time_start_s: f64,
    pub time_end_s: f64,
    /// Source line of the block of the first sample in violation.
    pub line: usize,
    /// The worst value: position (mm, deg), speed (per min), acceleration (per s²),
    /// penetration depth or smallest clearance (mm).
    pub worst: f64,
    /// The limit exceeded, in the unit of `worst`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub limit: Option<f64>,
    /// A travel violation of a program that would fit read in the other unit: which unit,
    /// and the ranges it gives ([`super::units::other_unit_note`]).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub other_unit: Option<String>,
}

/// How much of an axis a program uses.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AxisUsage {
    /// Not written: JSON keys the usage by its axis (read back from the key, see
    /// [`super::run::CheckReport`]).
    #[serde(skip, default = "unread_axis")]
    pub axis: Axis,
    /// Used range, mm or deg.
    pub min: f64,
    pub max: f64,
    /// Travel limits, mm or deg.
    pub limit_min: f64,
    pub limit_max: f64,
    /// Smallest distance to a travel limit (negative when exceeded); null for a continuous axis.
    pub margin: Option<f64>,
    /// Highest speed, mm/min or deg/min, and its limit.
    pub peak_velocity_per_min: f64,
    pub velocity_limit_per_min: f64,
    /// Highest acceleration, mm/s² or deg/s², and its limit.
    pub peak_acceleration_per_s2: f64,
    pub acceleration_limit_per_s2: f64,
    /// Highest jerk, mm/s³ or deg/s³, and the axis's jerk limit (reported, not checked).
    #[serde(default)]
    pub peak_jerk_per_s3: f64,
    #[serde(default)]
    pub jerk_limit_per_s3: f64,
}

/// The axis of a usage before its JSON key is read.
fn unread_axis() -> Axis {
    Axis::X
}

/// A violation being extended sample by sample.
#[derive(Clone, Debug)]
struct Open {
    first: (f64, Option<f64>, usize),
    /// Time and position of the last sample in violation; its θ is computed at close.
    last: (f64, AxisVec),
    worst: f64,
    limit: f64,
    /// How far past the limit `worst` is: |position - limit|, or the speed or acceleration.
    severity: f64,
}

/// One axis's limits, flat: no map look-up per sample.
#[derive(Clone, Copy, Debug)]
struct Limits {
    /// Index into [`AxisVec`].
    index: usize,
    continuous: bool,
    min: f64,
    max: f64,
    /// mm/min or deg/min, and the same with the rounding slack, mm/min or deg/min.
    max_velocity: f64,
    velocity_trip: f64,
    /// mm/s² or deg/s², and the same with the rounding slack.
    max_acceleration: f64,
    acceleration_trip: f64,
}

#[derive(Clone, Debug)]
struct Track {
    axis: Axis,
    limits: Limits,
    open: [Option<Open>; 3],
}

/// Lanes per sample: one per entry of [`AxisVec`] (X Y Z A B C U V W).
const LANES: usize = 9;
const _: () = assert!(
    LANES == 9,
    "LimitsMonitor::push_avx passes lanes 0..8, then 8"
);

/// A sample's finite-difference factors ([`LimitsMonitor::factors`]).
struct Factors {
    has_v: bool,
    has_a: bool,
    kv: f64,
    ka: f64,
    kj: f64,
}

/// The per-sample state and limits of all nine axis slots (`LANES`), flat (one lane per entry of
/// [`AxisVec`]): the common case is then a few vector operations. A slot with no axis, or
/// a limit that does not apply (the travel of a continuous axis), has an infinite limit.
#[derive(Clone, Debug)]
struct Lanes {
    /// Travel limits, mm or deg.
    lo: [f64; LANES],
    hi: [f64; LANES],
    /// Velocity and acceleration trips (limits with the rounding slack).
    v_trip: [f64; LANES],
    a_trip: [f64; LANES],
    /// Used range, peak speed (per min) and peak acceleration (per s²) so far.
    min: [f64; LANES],
    max: [f64; LANES],
    peak_v: [f64; LANES],
    peak_a: [f64; LANES],
    peak_j: [f64; LANES],
}

/// Checks every sample against the machine's limits; O(1) memory plus the violations found.
pub struct LimitsMonitor<'a> {
    machine: &'a Machine,
    theta_of: &'a dyn Fn(&AxisVec) -> Option<f64>,
    tracks: Vec<Track>,
    lanes: Lanes,
    previous: Previous,
    /// Violations open (being extended).
    open: usize,
    violations: Vec<Violation>,
    /// Acceleration and jerk only from samples of one block (programmed timing).
    within_blocks: bool,
    /// Whether an axis sits in the ninth lane (W): the lanes then go 0..8 and 8, else 0..8.
    ninth_lane: bool,
}

/// What the next sample needs of the previous one, written in place.
#[derive(Clone, Copy, Debug)]
struct Previous {
    /// Whether there was a previous sample (the rest is meaningless before).
    valid: bool,
    time_s: f64,
    block_index: u64,
    /// Positions, mm and deg.
    q: [f64; LANES],
    /// Velocity per s, when the sample had one (inside its block with `within_blocks`).
    v: [f64; LANES],
    has_v: bool,
    /// Acceleration per s², likewise.
    a: [f64; LANES],
    has_a: bool,
}

/// Relative slack on velocity and acceleration limits for rounding in finite differences.
const SLACK: f64 = 1e-9;

impl<'a> LimitsMonitor<'a> {
    /// `theta_of` gives the θ of a sample's commanded position (only asked for the first
    /// and last sample of each violation).
    pub fn new(machine: &'a Machine, theta_of: &'a dyn Fn(&AxisVec) -> Option<f64>) -> Self {
        let tracks = machine
            .axes()
            .iter()
            .map(|&axis| {
                let c = machine.axis(axis);
                Track {
                    axis,
                    limits: Limits {
                        index: axis.index(),
                        continuous: c.continuous,
                        min: c.min,
                        max: c.max,
                        max_velocity: c.max_velocity,
                        velocity_trip: c.max_velocity * (1.0 + SLACK),
                        max_acceleration: c.max_acceleration,
                        acceleration_trip: c.max_acceleration * (1.0 + SLACK),
                    },
                    open: [None, None, None],
                }
            })
            .collect::<Vec<Track>>();
        let mut lanes = Lanes {
            lo: [f64::NEG_INFINITY; LANES],
            hi: [f64::INFINITY; LANES],
            v_trip: [f64::INFINITY; LANES],
            a_trip: [f64::INFINITY; LANES],
            min: [f64::INFINITY; LANES],
            max: [f64::NEG_INFINITY; LANES],
            peak_v: [0.0; LANES],
            peak_a: [0.0; LANES],
            peak_j: [0.0; LANES],
        };
        for t in &tracks {
            let (l, i) = (&t.limits, t.limits.index);
            if !l.continuous {
                (lanes.lo[i], lanes.hi[i]) = (l.min, l.max);
            }
            lanes.v_trip[i] = l.velocity_trip;
            lanes.a_trip[i] = l.acceleration_trip;
        }
        let ninth_lane = tracks.iter().any(|t| t.limits.index == LANES - 1);
        LimitsMonitor {
            machine,
            theta_of,
            tracks,
            lanes,
            previous: Previous {
                valid: false,
                time_s: 0.0,
                block_index: 0,
                q: [0.0; LANES],
                v: [0.0; LANES],
                has_v: false,
                a: [0.0; LANES],
                has_a: false,
            },
            open: 0,
            violations: Vec::new(),
            within_blocks: false,
            ninth_lane,
        }
    }

    /// Takes acceleration and jerk only from samples inside one block: at programmed timing
    /// a junction is a velocity step that no controller runs.
    pub fn within_blocks(mut self) -> Self {
        self.within_blocks = true;
        self
    }

    /// One sample. The common case (no limit crossed, none open) is one pass over flat
    /// per-axis arrays; a crossing, or an open violation, takes `LimitsMonitor::track`.
    #[inline]
    pub fn push(&mut self, s: &Sample) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU has AVX, checked at run time just above.
            return unsafe { self.push_avx(s) };
        }
        self.push_inline(s)
    }

    /// What a sample's finite differences need: whether it has a velocity, an acceleration
    /// and a jerk, and their factors `1/Δt` (0 where one does not apply, so that it is 0 in
    /// every lane, NaN where the positions are not finite: it raises no peak and trips
    /// nothing, and the lanes stay free of branches). Moves the previous sample's time on.
    #[inline(always)]
    fn factors(&mut self, s: &Sample) -> Factors {
        let p = &mut self.previous;
        // A velocity needs an earlier sample, an acceleration also a velocity of the same
        // block.
        let in_block = p.valid && p.block_index == s.block_index;
        let joined = p.valid && (!self.within_blocks || in_block);
        let has_v = p.valid && s.time_s > p.time_s;
        let has_a = has_v && p.has_v && joined;
        let has_j = has_a && p.has_a;
        // As `(actual - previous) * (1 / dt)`, element by element: the same rounding.
        let k = 1.0 / (s.time_s - p.time_s);
        p.valid = true;
        p.time_s = s.time_s;
        p.block_index = s.block_index;
        p.has_v = has_v && (!self.within_blocks || in_block);
        p.has_a = has_a;
        Factors {
            has_v,
            has_a,
            kv: if has_v { k } else { 0.0 },
            ka: if has_a { k } else { 0.0 },
            kj: if has_j { k } else { 0.0 },
        }
    }

    /// Lane `i` of a sample at `x` (its position): velocity and acceleration into `v` and
    /// `a`, the previous sample and the extremes moved on. Whether the lane is outside a
    /// limit, or not a number: every lane is checked, axis or not (a slot with no axis has
    /// infinite limits), and `track` sorts them out.
    #[inline(always)]
    fn lane(
        &mut self,
        i: usize,
        x: f64,
        f: &Factors,
        v: &mut [f64; LANES],
        a: &mut [f64; LANES],
    ) -> bool {
        let (p, n) = (&mut self.previous, &mut self.lanes);
        v[i] = (x - p.q[i]) * f.kv;
        a[i] = (v[i] - p.v[i]) * f.ka;
        let jerk = ((a[i] - p.a[i]) * f.kj).abs();
        p.q[i] = x;
        p.v[i] = v[i];
        p.a[i] = a[i];
        n.peak_j[i] = n.peak_j[i].max(jerk);
        // `f64::min`/`max`: a NaN sample keeps the old extreme.
        n.min[i] = n.min[i].min(x);
        n.max[i] = n.max[i].max(x);
        let speed = v[i].abs() * 60.0;
        n.peak_v[i] = n.peak_v[i].max(speed);
        let accel = a[i].abs();
        n.peak_a[i] = n.peak_a[i].max(accel);
        !((x <= n.hi[i]) & (x >= n.lo[i]) & (speed <= n.v_trip[i]) & (accel <= n.a_trip[i]))
    }

    /// [`LimitsMonitor::push`] with the first eight lanes as two vectors of four (AVX, no
    /// FMA: the figures are those of the plain build, bit for bit). The extremes and peaks
    /// are `max(value, peak)` as `vmaxpd` takes it (`value > peak ? value : peak`), which is
    /// `f64::max` while the peak is a number, as it always is (it starts at 0 or ±∞ and a
    /// NaN value keeps it). The ninth lane (W) only when an axis sits there.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn push_avx(&mut self, s: &Sample) {
        use std::arch::x86_64::*;
        let f = self.factors(s);
        let x = &s.actual.0;
        let (mut v, mut a) = ([0.0; LANES], [0.0; LANES]);
        // SAFETY: every load and store is of four lanes at 0 or 4 of nine-lane arrays.
        let inside = unsafe {
            let (p, n) = (&mut self.previous, &mut self.lanes);
            let abs = _mm256_castsi256_pd(_mm256_set1_epi64x(i64::MAX));
            let (kv, ka, kj) = (
                _mm256_set1_pd(f.kv),
                _mm256_set1_pd(f.ka),
                _mm256_set1_pd(f.kj),
            );
            let per_min = _mm256_set1_pd(60.0);
            let mut inside = -1;
            for i in [0, 4] {
                // A macro, not a closure: a closure would not have AVX enabled.
                macro_rules! ld {
                    ($r:expr) => {
                        _mm256_loadu_pd($r.as_ptr().add(i))
                    };
                }
                let xi = ld!(x);
                let vi = _mm256_mul_pd(_mm256_sub_pd(xi, ld!(&p.q)), kv);
                let ai = _mm256_mul_pd(_mm256_sub_pd(vi, ld!(&p.v)), ka);
                let jerk = _mm256_and_pd(_mm256_mul_pd(_mm256_sub_pd(ai, ld!(&p.a)), kj), abs);
                _mm256_storeu_pd(p.q.as_mut_ptr().add(i), xi);
                _mm256_storeu_pd(p.v.as_mut_ptr().add(i), vi);
                _mm256_storeu_pd(p.a.as_mut_ptr().add(i), ai);
                _mm256_storeu_pd(v.as_mut_ptr().add(i), vi);
                _mm256_storeu_pd(a.as_mut_ptr().add(i), ai);
                let speed = _mm256_mul_pd(_mm256_and_pd(vi, abs), per_min);
                let accel = _mm256_and_pd(ai, abs);
                for (value, peak) in [
                    (jerk, &mut n.peak_j),
                    (xi, &mut n.max),
                    (speed, &mut n.peak_v),
                    (accel, &mut n.peak_a),
                ] {
                    let at = peak.as_mut_ptr().add(i);
                    _mm256_storeu_pd(at, _mm256_max_pd(value, _mm256_loadu_pd(at)));
                }
                let at = n.min.as_mut_ptr().add(i);
                _mm256_storeu_pd(at, _mm256_min_pd(xi, _mm256_loadu_pd(at)));
                let ok = _mm256_and_pd(
                    _mm256_and_pd(
                        _mm256_cmp_pd::<_CMP_LE_OQ>(xi, ld!(&n.hi)),
                        _mm256_cmp_pd::<_CMP_GE_OQ>(xi, ld!(&n.lo)),
                    ),
                    _mm256_and_pd(
                        _mm256_cmp_pd::<_CMP_LE_OQ>(speed, ld!(&n.v_trip)),
                        _mm256_cmp_pd::<_CMP_LE_OQ>(accel, ld!(&n.a_trip)),
                    ),
                );
                inside &= _mm256_movemask_pd(ok);
            }
            inside == 0xF
        };
        let mut outside = !inside;
        if self.ninth_lane {
            outside |= self.lane(LANES - 1, x[LANES - 1], &f, &mut v, &mut a);
        }
        if outside || self.open != 0 {
            self.track(s, f.has_v.then_some(&v), f.has_a.then_some(&a));
        }
    }

    #[inline(always)]
    fn push_inline(&mut self, s: &Sample) {
        let f = self.factors(s);
        let x = &s.actual.0;
        let (mut v, mut a) = ([0.0; LANES], [0.0; LANES]);
        let lanes = if self.ninth_lane { LANES } else { LANES - 1 };
        let mut outside = false;
        for i in 0..lanes {
            outside |= self.lane(i, x[i], &f, &mut v, &mut a);
        }
        if outside || self.open != 0 {
            self.track(s, f.has_v.then_some(&v), f.has_a.then_some(&a));
        }
    }

    /// Opens, extends and closes the violations of sample `s` (velocity per s and
    /// acceleration per s² when it has them).
    fn track(&mut self, s: &Sample, velocity: Option<&[f64; 9]>, acceleration: Option<&[f64; 9]>) {
        let mut theta: Option<Option<f64>> = None;
        for track in self.tracks.iter_mut() {
            let l = track.limits;
            let x = s.actual.0[l.index];
            let travel = if l.continuous {
                None
            } else if x > l.max {
                Some((x, l.max, x - l.max))
            } else if x < l.min {
                Some((x, l.min, l.min - x))
            } else {
                None
            };
            let speed = velocity
                .map(|v| v[l.index].abs() * 60.0)
                .and_then(|v| (v > l.velocity_trip).then_some((v, l.max_velocity, v)));
            let accel = acceleration
                .map(|a| a[l.index].abs())
                .and_then(|a| (a > l.acceleration_trip).then_some((a, l.max_acceleration, a)));
            let checks = [travel, speed, accel];
            if checks.iter().all(Option::is_none) && track.open.iter().all(Option::is_none) {
                continue;
            }
            for (k, check) in checks.into_iter().enumerate() {
                match check {
                    Some((value, limit, severity)) => match &mut track.open[k] {
                        Some(open) => {
                            open.last = (s.time_s, s.actual);
                            if severity > open.severity {
                                open.worst = value;
                                open.limit = limit;
                                open.severity = severity;
                            }
                        }
                        None => {
                            let th = *theta.get_or_insert_with(|| (self.theta_of)(&s.actual));
                            self.open += 1;
                            track.open[k] = Some(Open {
                                first: (s.time_s, th, s.line),
                                last: (s.time_s, s.actual),
                                worst: value,
                                limit,
                                severity,
                            })
                        }
                    },
                    None => {
                        if let Some(open) = track.open[k].take() {
                            self.open -= 1;
                            self.violations
                                .push(close(open, KINDS[k], track.axis, self.theta_of));
                        }
                    }
                }
            }
        }
    }

    /// Starts another run on its own clock: the violations open are closed, and the next
    /// sample has no earlier one (no velocity, acceleration or jerk across the runs' seam).
    /// Extremes and peaks carry on.
    pub fn restart(&mut self) {
        self.close_open();
        self.difference_afresh();
    }

    /// The next sample has no earlier one: no velocity, acceleration or jerk is taken across
    /// the gap before it (the violations open stay open).
    pub fn difference_afresh(&mut self) {
        self.previous.valid = false;
        self.previous.has_v = false;
        self.previous.has_a = false;
    }

    /// Closes every violation still open.
    fn close_open(&mut self) {
        for track in &mut self.tracks {
            for (k, open) in track.open.iter_mut().enumerate() {
                if let Some(open) = open.take() {
                    self.violations
                        .push(close(open, KINDS[k], track.axis, self.theta_of));
                }
            }
        }
        self.open = 0;
    }

    /// The per-axis usage and the violations, in the order they started.
    pub fn finish(mut self) -> (Vec<AxisUsage>, Vec<Violation>) {
        self.close_open();
        self.violations
            .sort_by(|a, b| a.time_start_s.total_cmp(&b.time_start_s));
        let usage = self
            .tracks
            .iter()
            .map(|t| {
                let c = self.machine.axis(t.axis);
                let i = t.limits.index;
                let (min, max) = (self.lanes.min[i], self.lanes.max[i]);
                AxisUsage {
                    axis: t.axis,
                    min,
                    max,
                    limit_min: c.min,
                    limit_max: c.max,
                    margin: (!c.continuous).then(|| (min - c.min).min(c.max - max)),
                    peak_velocity_per_min: self.lanes.peak_v[i],
                    velocity_limit_per_min: c.max_velocity,
                    peak_acceleration_per_s2: self.lanes.peak_a[i],
                    acceleration_limit_per_s2: c.max_acceleration,
                    peak_jerk_per_s3: self.lanes.peak_j[i],
                    jerk_limit_per_s3: c.max_jerk,
                }
            })
            .collect();
        (usage, self.violations)
    }
}

const KINDS: [ViolationKind; 3] = [
    ViolationKind::Travel,
    ViolationKind::Velocity,
    ViolationKind::Acceleration,
];

fn close(
    open: Open,
    kind: ViolationKind,
    axis: Axis,
    theta_of: &dyn Fn(&AxisVec) -> Option<f64>,
) -> Violation {
    Violation {
        kind,
        axis: Some(axis),
        bodies: None,
        theta_start_deg: open.first.1,
        theta_end_deg: theta_of(&open.last.1),
        time_start_s: open.first.0,
        time_end_s: open.last.0,
        line: open.first.2,
        worst: open.worst,
        limit: Some(open.limit),
        other_unit: None,
    }
}

impl Sink for LimitsMonitor<'_> {
    fn push(&mut self, sample: &Sample) -> Result<()> {
        LimitsMonitor::push(self, sample);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A walk of five axes over blocks of 40 samples at 1 ms: steady motion, a travel
    /// crossing, velocity and acceleration spikes, a repeated time and a NaN position.
    fn samples() -> Vec<Sample> {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut noise = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut q = AxisVec::ZERO;
        let mut out = Vec::new();
        for k in 0..2000u64 {
            // X swings through its travel limit at 60 mm; the others walk.
            q.0[0] = 55.0 + 10.0 * (k as f64 / 200.0).sin();
            for (i, step) in [(1, -0.03), (2, 0.01), (3, 0.02), (5, 0.1)] {
                q.0[i] += step * (1.0 + 0.002 * noise());
            }
            if k % 300 == 150 {
                q.0[1] += 3.0; // a jump: velocity and acceleration far past their limits
            }
            let mut actual = q;
            if k == 1234 {
                actual.0[1] = f64::NAN;
            }
            out.push(Sample {
                index: k,
                time_s: if k == 700 { 0.699 } else { k as f64 * 1e-3 },
                line: 10 + k as usize / 40,
                block_index: k / 40,
                commanded: q,
                actual,
                following_error: AxisVec::ZERO,
                linear: actual,
            });
        }
        out
    }

    #[test]
    fn the_vector_lanes_give_the_plain_lanes_figures_bit_for_bit() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/trt-ac.toml");
        let mut machine = Machine::load(&path).unwrap();
        machine.axis_mut(Axis::X).max = 60.0;
        let theta = |q: &AxisVec| Some(q.0[0]);
        for within_blocks in [false, true] {
            let monitor = || {
                let m = LimitsMonitor::new(&machine, &theta);
                if within_blocks {
                    m.within_blocks()
                } else {
                    m
                }
            };
            let (mut plain, mut vector) = (monitor(), monitor());
            for s in &samples() {
                plain.push_inline(s);
                vector.push(s);
            }
            let (plain, vector) = (plain.finish(), vector.finish());
            assert!(!plain.1.is_empty(), "the walk crosses limits");
            let x = samples()
                .iter()
                .map(|s| s.actual.0[0])
                .fold(f64::MIN, f64::max);
            let usage_x = vector.0.iter().find(|u| u.axis == Axis::X).unwrap();
            assert_eq!(usage_x.max.to_bits(), x.to_bits());
            // Debug prints the shortest text that reads back to the same bits.
            assert_eq!(format!("{plain:?}"), format!("{vector:?}"));
        }
    }
}
