//! The drives of many points of a study on one setpoint stream: each point's [`Drives`]
//! side by side, and the linear twins shared by every point whose twin is the same.
//!
//! A twin is the drive without dry friction and backlash ([`Drives::new`] with `linear`),
//! so the points of a study that differ only in friction or backlash have one twin between
//! them: a backlash study with three kv values steps three twins, not one per point. Each
//! point's drives and each twin are the very models a single run steps, stepped in the same
//! order on the same setpoints: a point's figures are the single run's, bit for bit.

use super::drives::Drives;
use crate::error::Result;
use crate::input::machine::Machine;
use crate::AxisVec;

/// The drives of several points, and their distinct linear twins.
#[derive(Clone, Debug)]
pub struct DriveLanes {
    /// Each point's nonlinear drives; None once they have failed (diverged).
    points: Vec<Option<Drives>>,
    /// The distinct twins; None once one has failed.
    twins: Vec<Option<Drives>>,
    /// Which twin each point shares.
    twin_of: Vec<usize>,
}

impl DriveLanes {
    /// The drives of `machines` (one per point, all with the same axes) at rest at `q`.
    pub fn new(machines: &[&Machine], q: &AxisVec) -> Result<DriveLanes> {
        let mut keys: Vec<String> = Vec::new();
        let mut twins = Vec::new();
        let mut twin_of = Vec::with_capacity(machines.len());
        let mut points = Vec::with_capacity(machines.len());
        for machine in machines {
            points.push(Some(Drives::new(machine, q, false)?));
            let key = twin_key(machine)?;
            let index = match keys.iter().position(|k| *k == key) {
                Some(i) => i,
                None => {
                    keys.push(key);
                    twins.push(Some(Drives::new(machine, q, true)?));
                    twins.len() - 1
                }
            };
            twin_of.push(index);
        }
        Ok(DriveLanes {
            points,
            twins,
            twin_of,
        })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True without points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Number of distinct linear twins stepped.
    pub fn twins(&self) -> usize {
        self.twins.len()
    }

    /// Whether point `i` is still running (neither its drives nor its twin have failed).
    pub fn alive(&self, i: usize) -> bool {
        self.points[i].is_some() && self.twins[self.twin_of[i]].is_some()
    }

    /// Which twin point `i` shares.
    pub fn twin_of(&self, i: usize) -> usize {
        self.twin_of[i]
    }

    /// Steps twin `t` one period towards `setpoint`, reached at `time_s`, writing its
    /// driven axes into `actual` (mm, deg). False when the twin has failed (now or before):
    /// it stops, and with it every point that shares it.
    pub fn step_twin(
        &mut self,
        t: usize,
        setpoint: &AxisVec,
        time_s: f64,
        actual: &mut AxisVec,
    ) -> bool {
        let Some(d) = self.twins[t].as_mut() else {
            return false;
        };
        if d.step_actual_into(setpoint, time_s, actual).is_err() {
            self.twins[t] = None;
            return false;
        }
        true
    }

    /// Steps point `i`'s drives one period (see [`Drives::step_into`]). Returns whether
    /// every axis settled, or None when the point has failed (now or before).
    pub fn step_point(
        &mut self,
        i: usize,
        setpoint: &AxisVec,
        time_s: f64,
        actual: &mut AxisVec,
        following_error: &mut AxisVec,
    ) -> Option<bool> {
        let drives = self.points[i].as_mut()?;
        match drives.step_into(setpoint, time_s, actual, following_error) {
            Ok(settled) => Some(settled),
            Err(_) => {
                self.points[i] = None;
                None
            }
        }
    }
}

/// What makes two machines' linear twins the same: every axis's twin drive and the
/// period (their debug forms, exact for f64: the shortest text that reads back the same).
fn twin_key(machine: &Machine) -> Result<String> {
    let drives = machine
        .axes()
        .iter()
        .map(|&a| Ok(machine.drive(a)?.linear_twin()))
        .collect::<Result<Vec<_>>>()?;
    Ok(format!("{:?} {:?}", machine.interpolation_period_s, drives))
}
