//! Readings that points of a study share: the bar's reading of a setpoint and its table ball.
//!
//! The points of a study pass (`study::lanes`) run the same setpoints, so what the bar reads
//! of the setpoint alone ([`CommandedReading`]: θ, its terms, the commanded rotaries' sines
//! and cosines) is the same for all of them; where they also share the actual rotary
//! positions (drives alike on the rotaries), the table ball
//! ([`BarGeometry::table_ball_mm`]) is the same too. [`SharedReadings`] keeps them per
//! sample, in a slot chosen by the sample's index, and reuses a value only when its inputs
//! are the same bits: the setpoint for the commanded reading, the rotaries of `q` (and that
//! setpoint) for the ball. A reused value is the one [`BarGeometry::read`] computes, so a
//! point's readings are its single run's bit for bit, whatever is shared.

use std::cell::RefCell;

use nalgebra::Point3;

use super::sink::{BallbarSink, BarGeometry, BarReading, CommandMaps, CommandedReading};
use crate::error::Result;
use crate::pipeline::{Sample, Sink};
use crate::{Axis, AxisVec};

/// Slots of [`SharedReadings`]: the samples a pass hands each point at a time (the drives'
/// lane block), so that a block's setpoints are read once for all.
pub const SLOTS: usize = crate::drive::lanes::BLOCK;

/// Bits of every value of an axis vector: the key of exact equality (NaN included).
type Bits = [u64; 9];

/// The table balls of one slot: one for the actual positions, one for the twin's.
const BALLS: usize = 2;

#[derive(Clone, Copy)]
struct Slot {
    /// The setpoint read here.
    commanded: Bits,
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
    /// The bars' [`CommandMaps`], kept once for all, and the index of the next sample they
    /// take (see [`SharedReadings::with_maps`]).
    maps: Option<(CommandMaps, u64)>,
}

impl SharedReadings {
    pub fn new(geometry: BarGeometry) -> SharedReadings {
        let layout = geometry.kinematics.layout;
        SharedReadings {
            geometry,
            rotaries: [layout.tilt_axis(), layout.table_axis()],
            full_chain: geometry.needs_full_chain(),
            slots: vec![None; SLOTS],
            maps: None,
        }
    }

    /// The same, keeping the [`CommandMaps`] of its bars once for all (their bars are made
    /// [`BallbarSink::without_maps`]). The maps depend only on the samples' setpoints, so
    /// they are the same for every bar that takes every sample of a run, in order, from
    /// index 0 (points of a pass without a settle gate): they take each sample index once,
    /// from whichever bar pushes it first. A bar that stops early (its drives failed)
    /// leaves the samples after its last to the next bar.
    pub fn with_maps(mut self) -> SharedReadings {
        self.maps = Some((CommandMaps::default(), 0));
        self
    }

    /// The maps kept by [`SharedReadings::with_maps`].
    pub fn into_maps(self) -> Option<CommandMaps> {
        self.maps.map(|(maps, _)| maps)
    }

    /// Hands sample `s` to the kept maps if none of the bars has yet (`bin`: its θ bin
    /// when it is measured).
    #[inline]
    fn map(&mut self, s: &Sample, bin: Option<usize>) {
        if let Some((maps, next)) = &mut self.maps {
            if s.index == *next {
                maps.take(s, bin);
                *next += 1;
            }
        }
    }

    /// [`BarGeometry::read_commanded`] of `s`'s setpoint.
    #[inline]
    pub fn read_commanded(&mut self, s: &Sample) -> CommandedReading {
        slot_of(&mut self.slots, &self.geometry, s).reading
    }

    /// [`BarGeometry::read`] of `s`.
    #[inline]
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
        let mut deviation = |k: usize, q: &AxisVec| {
            let key = rotaries.map(|a| a.map_or(0, |a| q[a].to_bits()));
            let ball = match &balls[k] {
                Some((held, ball)) if *held == key => *ball,
                _ => {
                    let ball = geometry.table_ball_mm(q, &s.commanded, &c.at_command);
                    balls[k] = Some((key, ball));
                    ball
                }
            };
            geometry.deviation_to_ball_um(q, &ball)
        };
        let deviation_um = deviation(0, &s.actual);
        let linear_um = deviation(1, &s.linear);
        c.with_deviations(deviation_um, linear_um)
    }
}

/// The slot of sample `s` in `slots`, holding its setpoint's reading (read now if it holds
/// another setpoint).
#[inline(always)]
fn slot_of<'s>(slots: &'s mut [Option<Slot>], geometry: &BarGeometry, s: &Sample) -> &'s mut Slot {
    let slot = &mut slots[s.index as usize % SLOTS];
    let held = slot
        .as_ref()
        .is_some_and(|held| same_bits(&held.commanded, &s.commanded));
    if !held {
        *slot = Some(Slot {
            commanded: s.commanded.0.map(f64::to_bits),
            reading: geometry.read_commanded(&s.commanded),
            balls: [None; BALLS],
        });
    }
    slot.as_mut().expect("filled just above")
}

/// Whether `q`'s values have the bits `key` (without a branch per value).
#[inline]
fn same_bits(key: &Bits, q: &AxisVec) -> bool {
    key.iter()
        .zip(&q.0)
        .fold(0, |differ, (k, v)| differ | (k ^ v.to_bits()))
        == 0
}

/// A point's ball bar reading through the [`SharedReadings`] of its pass.
pub struct SharedBallbar<'a> {
    pub bar: &'a mut BallbarSink,
    pub readings: &'a RefCell<SharedReadings>,
}

impl Sink for SharedBallbar<'_> {
    #[inline]
    fn push(&mut self, s: &Sample) -> Result<()> {
        let mut readings = self.readings.borrow_mut();
        let r = self.bar.take_with(s, |_, s| readings.read(s));
        readings.map(s, r.as_ref().map(BarReading::bin));
        Ok(())
    }
}
