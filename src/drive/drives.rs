//! The drives of one machine: one [`AxisServo`] per axis, stepped together.

#[cfg(target_arch = "x86_64")]
use super::product::Avx2;
use super::product::{ColumnProduct, Portable, Width};
use super::servo::AxisServo;
use crate::error::Result;
use crate::input::machine::Machine;
use crate::{Axis, AxisVec};

/// Every axis of a machine at the end of one interpolation period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrivesState {
    /// Table-side positions, mm and deg.
    pub actual: AxisVec,
    /// Setpoint minus actual, mm and deg.
    pub following_error: AxisVec,
    /// Every axis within 0.1 um (0.1 mdeg) of its setpoint and below 1 um/s (1 mdeg/s).
    pub settled: bool,
}

/// One servo per machine axis.
#[derive(Clone, Debug)]
pub struct Drives {
    axes: &'static [Axis],
    servos: Vec<AxisServo>,
    /// The vector width of the period maps' products (the same result at every width).
    width: Width,
}

impl Drives {
    /// The machine's drives at rest at `q`. With `linear`, its linear twins: the same drives
    /// without dry friction and backlash, whose response is what the nonlinearities are
    /// measured against.
    pub fn new(machine: &Machine, q: &AxisVec, linear: bool) -> Result<Drives> {
        let period = machine.interpolation_period_s;
        let servos = machine
            .axes()
            .iter()
            .map(|&a| {
                let drive = machine.drive(a);
                let drive = if linear { drive.linear_twin() } else { drive };
                AxisServo::new(&drive, period, q[a])
            })
            .collect::<Result<_>>()?;
        Ok(Drives {
            axes: machine.axes(),
            servos,
            width: Width::detect(),
        })
    }

    /// Steps every axis through one interpolation period towards `setpoint`, which it should
    /// reach at `time_s`.
    pub fn step(&mut self, setpoint: &AxisVec, time_s: f64) -> Result<DrivesState> {
        let mut state = DrivesState {
            actual: *setpoint,
            following_error: AxisVec::ZERO,
            settled: true,
        };
        state.settled = self.step_into(
            setpoint,
            time_s,
            &mut state.actual,
            &mut state.following_error,
        )?;
        Ok(state)
    }

    /// [`Drives::step`] into the caller's vectors: each driven axis's entry of `actual`
    /// (mm, deg) and `following_error` is written, the others are left as they are. Returns
    /// whether every axis has settled ([`DrivesState::settled`]). Written in place, entry by
    /// entry, so that nothing reads a whole vector back right after its entries were stored
    /// (a stalled store forward).
    pub fn step_into(
        &mut self,
        setpoint: &AxisVec,
        time_s: f64,
        actual: &mut AxisVec,
        following_error: &mut AxisVec,
    ) -> Result<bool> {
        match self.width {
            // SAFETY: the CPU has AVX2, as the token says.
            #[cfg(target_arch = "x86_64")]
            Width::Avx2(k) => unsafe {
                self.step_avx2(k, setpoint, time_s, actual, following_error)
            },
            Width::Portable => self.step_portable(setpoint, time_s, actual, following_error),
        }
    }

    /// [`Drives::step_into`] for any CPU (out of line: the vector builds are the rule).
    #[inline(never)]
    fn step_portable(
        &mut self,
        setpoint: &AxisVec,
        time_s: f64,
        actual: &mut AxisVec,
        following_error: &mut AxisVec,
    ) -> Result<bool> {
        self.step_inline(Portable, setpoint, time_s, actual, following_error)
    }

    /// [`Drives::step_into`] compiled for AVX2, every axis's period inlined into one
    /// function, a period map's column in two registers (no FMA, whose single rounding would
    /// change the result: the arithmetic is the same whatever the vector width).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2")]
    unsafe fn step_avx2(
        &mut self,
        k: Avx2,
        setpoint: &AxisVec,
        time_s: f64,
        actual: &mut AxisVec,
        following_error: &mut AxisVec,
    ) -> Result<bool> {
        self.step_inline(k, setpoint, time_s, actual, following_error)
    }

    #[inline(always)]
    fn step_inline<K: ColumnProduct>(
        &mut self,
        k: K,
        setpoint: &AxisVec,
        time_s: f64,
        actual: &mut AxisVec,
        following_error: &mut AxisVec,
    ) -> Result<bool> {
        let mut settled = true;
        for (servo, &a) in self.servos.iter_mut().zip(self.axes) {
            servo.advance_with(k, setpoint[a], time_s)?;
            let fe = servo.following_error();
            actual[a] = servo.actual();
            following_error[a] = fe;
            settled &= fe.abs() < 1e-4 && servo.velocity().abs() < 1e-3;
        }
        Ok(settled)
    }

    /// [`Drives::step`] for the actual positions alone (mm and deg), as the linear twins
    /// need them (with their period map inlined: [`AxisServo::advance_twin`]).
    pub fn step_actual(&mut self, setpoint: &AxisVec, time_s: f64) -> Result<AxisVec> {
        let mut actual = *setpoint;
        self.step_actual_into(setpoint, time_s, &mut actual)?;
        Ok(actual)
    }

    /// [`Drives::step_actual`] into `actual`, entry by entry (see [`Drives::step_into`]).
    pub fn step_actual_into(
        &mut self,
        setpoint: &AxisVec,
        time_s: f64,
        actual: &mut AxisVec,
    ) -> Result<()> {
        match self.width {
            // SAFETY: the CPU has AVX2, as the token says.
            #[cfg(target_arch = "x86_64")]
            Width::Avx2(k) => unsafe { self.step_actual_avx2(k, setpoint, time_s, actual) },
            Width::Portable => self.step_actual_portable(setpoint, time_s, actual),
        }
    }

    /// [`Drives::step_actual_into`] for any CPU (out of line, see [`Drives::step_portable`]).
    #[inline(never)]
    fn step_actual_portable(
        &mut self,
        setpoint: &AxisVec,
        time_s: f64,
        actual: &mut AxisVec,
    ) -> Result<()> {
        self.step_actual_inline(Portable, setpoint, time_s, actual)
    }

    /// [`Drives::step_actual_into`] compiled for AVX2 (see [`Drives::step_avx2`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2")]
    unsafe fn step_actual_avx2(
        &mut self,
        k: Avx2,
        setpoint: &AxisVec,
        time_s: f64,
        actual: &mut AxisVec,
    ) -> Result<()> {
        self.step_actual_inline(k, setpoint, time_s, actual)
    }

    #[inline(always)]
    fn step_actual_inline<K: ColumnProduct>(
        &mut self,
        k: K,
        setpoint: &AxisVec,
        time_s: f64,
        actual: &mut AxisVec,
    ) -> Result<()> {
        for (servo, &a) in self.servos.iter_mut().zip(self.axes) {
            servo.advance_twin_with(k, setpoint[a], time_s)?;
            actual[a] = servo.actual();
        }
        Ok(())
    }
}
