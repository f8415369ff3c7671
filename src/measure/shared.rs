//! Readings that points of a study share: the bar's reading of a setpoint and its table ball.
//!
//! The points of a study pass (`study::lanes`) run the same setpoints, so what the bar reads
//! of the setpoint alone ([`CommandedReading`]: θ, its terms, the commanded rotaries' sines
//! and cosines) is the same for all of them; where they also share the actual rotary
//! positions (drives alike on the rotaries), the table ball
//! ([`BarGeometry::table_ball_mm`]) is the same too. [`SharedReadings`] keeps them per
//! sample, in a slot chosen by the sample's index, and reuses a value only when its inputs
//! are the same: the sample's index for the commanded reading (a [`SharedReadings`] reads
//! the samples of one run, where an index names one setpoint), the bits of the rotaries of
//! `q` (and that setpoint) for the ball. A reused value is the one [`BarGeometry::read`] computes, so a
//! point's readings are its single run's bit for bit, whatever is shared.
//!
//! Where every bar takes every sample (no settle gate), what a bar sums of θ alone (each
//! bin's count and sums of cos θ and sin θ, the centring's normal matrix `Σ φ φᵀ` with
//! `φ = (1, cos θ, sin θ)`) and its feed meter are the same for all of them:
//! [`SharedReadings::with_theta_sums`] keeps them once, from whichever bar pushes a sample
//! first, and each bar sums only its deviations (`Σ dL` per bin, `Σ φ dL`) until
//! [`SharedReadings::complete`] hands it the rest.

use std::cell::RefCell;

use nalgebra::Point3;

use super::ballbar::BallbarRun;
use super::feed::FeedMeter;
use super::sink::{BallbarSink, BarGeometry, BarReading, CommandMaps, CommandedReading};
use crate::error::Result;
use crate::pipeline::{Sample, Sink};
use crate::{Axis, AxisVec};

/// Slots of [`SharedReadings`]: the samples a pass hands each point at a time (the drives'
/// lane block), so that a block's setpoints are read once for all.
pub const SLOTS: usize = crate::drive::lanes::BLOCK;

/// The table balls of one slot: one for the actual positions, one for the twin's.
const BALLS: usize = 2;

#[derive(Clone, Copy)]
struct Slot {
    /// The index of the sample read here: within one run, it names one setpoint.
    index: u64,
    reading: CommandedReading,
    /// Table balls at this setpoint, keyed by the bits of the tilt and table angles.
    balls: [Option<([u64; 2], Point3<f64>)>; BALLS],
}

/// The bar's readings of recent samples, to be reused by every point of a pass
/// (see the module's doc).
pub struct SharedReadings {
    geometry: BarGeometry,
    /// The tilt and table axes (the angles a table ball depends on).
    rotaries: [Option<Axis>; 2],
    /// [`BarGeometry::needs_full_chain`]: no table balls kept then.
    full_chain: bool,
    slots: Vec<Option<Slot>>,
    /// The bars' [`CommandMaps`], kept once for all (see [`SharedReadings::with_maps`]).
    maps: Option<CommandMaps>,
    /// The bars' θ sums (a run with every deviation 0) and feed meter, kept once for all
    /// (see [`SharedReadings::with_theta_sums`]).
    theta: Option<(BallbarRun, FeedMeter)>,
    /// The index of the next sample the maps and θ sums take.
    next: u64,
}

impl SharedReadings {
    /// Readings of the samples of one run (a sample's index names its setpoint).
    pub fn new(geometry: BarGeometry) -> SharedReadings {
        let layout = geometry.kinematics.layout;
        SharedReadings {
            geometry,
            rotaries: [layout.tilt_axis(), layout.table_axis()],
            full_chain: geometry.needs_full_chain(),
            slots: vec![None; SLOTS],
            maps: None,
            theta: None,
            next: 0,
        }
    }

    /// The same, keeping the [`CommandMaps`] of its bars once for all (their bars are made
    /// [`BallbarSink::without_maps`]). The maps depend only on the samples' setpoints, so
    /// they are the same for every bar that takes every sample of a run, in order, from
    /// index 0 (points of a pass without a settle gate): they take each sample index once,
    /// from whichever bar pushes it first. A bar that stops early (its drives failed)
    /// leaves the samples after its last to the next bar.
    pub fn with_maps(mut self) -> SharedReadings {
        self.maps = Some(CommandMaps::default());
        self
    }

    /// The same, keeping the θ sums and feed meter of its bars once for all (a bar then
    /// sums only its deviations: [`BallbarSink::take_deviations_with`]), for bars in
    /// `direction` that each take every sample of a run, in order, from index 0, as
    /// [`SharedReadings::with_maps`]'s do. [`SharedReadings::complete`] hands each bar its
    /// sums at the run's end.
    pub fn with_theta_sums(mut self, direction: crate::input::program::Direction) -> Self {
        self.theta = Some((BallbarRun::new(direction), FeedMeter::default()));
        self
    }

    /// The maps kept by [`SharedReadings::with_maps`].
    pub fn into_maps(self) -> Option<CommandMaps> {
        self.maps
    }

    /// Completes `bar`, fed through these readings, with the θ sums and feed meter kept
    /// by [`SharedReadings::with_theta_sums`] ([`BallbarSink::take_shared`]); true without
    /// them (the bar summed everything itself). False when the bar cannot take them (one
    /// of its deviations was not finite): its point must run alone.
    pub fn complete(&self, bar: &mut BallbarSink) -> bool {
        match &self.theta {
            Some((run, feed)) => bar.take_shared(run, feed),
            None => true,
        }
    }

    /// Hands sample `s` to the kept maps and θ sums if none of the bars has yet (`measured`:
    /// whether the bars read it).
    #[inline(always)]
    fn advance(&mut self, s: &Sample, measured: bool) {
        if s.index == self.next {
            self.take_next(s, measured);
        }
    }

    /// [`SharedReadings::advance`] of the next sample (out of line: one bar a pass takes
    /// each sample), with what the bar read of its setpoint.
    #[inline(never)]
    fn take_next(&mut self, s: &Sample, measured: bool) {
        self.next += 1;
        let r = measured.then(|| self.read_commanded(s));
        if let Some(maps) = &mut self.maps {
            maps.take(s, r.as_ref().map(CommandedReading::bin));
        }
        if let (Some((run, feed)), Some(r)) = (&mut self.theta, r) {
            // As `BallbarSink::take` forms them: the feed, then the run's terms.
            feed.take(s.time_s, r.theta_deg);
            run.push_terms(r.terms.as_ref(), 0.0);
        }
    }

    /// [`BarGeometry::read_commanded`] of `s`'s setpoint.
    #[inline]
    pub fn read_commanded(&mut self, s: &Sample) -> CommandedReading {
        slot_of(&mut self.slots, &self.geometry, s).reading
    }

    /// [`BarGeometry::read`] of `s`.
    #[inline(always)]
    pub fn read(&mut self, s: &Sample) -> BarReading {
        let SharedReadings {
            geometry,
            rotaries,
            full_chain,
            slots,
            ..
        } = self;
        let Slot {
            reading: c, balls, ..
        } = slot_of(slots, geometry, s);
        if *full_chain {
            let deviation_um = geometry.deviation_on(true, &s.actual, &s.commanded, c);
            let linear_um = geometry.deviation_on(true, &s.linear, &s.commanded, c);
            return c.with_deviations(deviation_um, linear_um);
        }
        let deviation_um = deviation(geometry, rotaries, &mut balls[0], &s.actual, s, c);
        let linear_um = deviation(geometry, rotaries, &mut balls[1], &s.linear, s, c);
        c.with_deviations(deviation_um, linear_um)
    }
}

/// dL at positions `q` of sample `s` (whose setpoint reads `c`), um, with the table ball
/// kept in `ball` (keyed by the bits of `q`'s `rotaries`) or made there.
#[inline(always)]
fn deviation(
    geometry: &BarGeometry,
    rotaries: &[Option<Axis>; 2],
    ball: &mut Option<([u64; 2], Point3<f64>)>,
    q: &AxisVec,
    s: &Sample,
    c: &CommandedReading,
) -> f64 {
    let key = rotaries.map(|a| a.map_or(0, |a| q[a].to_bits()));
    let at = match ball {
        Some((held, at)) if *held == key => *at,
        _ => new_ball(geometry, ball, key, q, s, c),
    };
    geometry.deviation_to_ball_um(q, &at)
}

/// The table ball at `q` of sample `s`, kept in `ball` with its key (out of line: a pass's
/// points mostly share their rotaries).
#[cold]
#[inline(never)]
fn new_ball(
    geometry: &BarGeometry,
    ball: &mut Option<([u64; 2], Point3<f64>)>,
    key: [u64; 2],
    q: &AxisVec,
    s: &Sample,
    c: &CommandedReading,
) -> Point3<f64> {
    let at = geometry.table_ball_mm(q, &s.commanded, &c.at_command);
    *ball = Some((key, at));
    at
}

/// The slot of sample `s` in `slots`, holding its setpoint's reading (read now if it holds
/// another sample's).
#[inline(always)]
fn slot_of<'s>(slots: &'s mut [Option<Slot>], geometry: &BarGeometry, s: &Sample) -> &'s mut Slot {
    let slot = &mut slots[s.index as usize % SLOTS];
    let held = slot.as_ref().is_some_and(|held| held.index == s.index);
    if !held {
        *slot = Some(Slot {
            index: s.index,
            reading: geometry.read_commanded(&s.commanded),
            balls: [None; BALLS],
        });
    }
    slot.as_mut().expect("filled just above")
}

/// A point's ball bar reading through the [`SharedReadings`] of its pass.
pub struct SharedBallbar<'a> {
    pub bar: &'a mut BallbarSink,
    pub readings: &'a RefCell<SharedReadings>,
}

impl Sink for SharedBallbar<'_> {
    #[inline]
    fn push(&mut self, s: &Sample) -> Result<()> {
        self.push_many(std::slice::from_ref(s))
    }

    fn push_many(&mut self, samples: &[Sample]) -> Result<()> {
        let mut readings = self.readings.borrow_mut();
        if readings.theta.is_some() {
            for s in samples {
                let r = self.bar.take_deviations_with(s, |_, s| readings.read(s));
                readings.advance(s, r.is_some());
            }
        } else {
            for s in samples {
                let r = self.bar.take_with(s, |_, s| readings.read(s));
                readings.advance(s, r.is_some());
            }
        }
        Ok(())
    }
}
