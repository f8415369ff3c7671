//! The virtual ball bar as a pipeline sink.
//!
//! The bar joins the table ball (fixed in the table frame) to the tool ball (the tool tip).
//! For each sample in the measured revolution it reads
//!
//! ```text
//! θ       = angle of the commanded tool tip on the measured circle (nominal path)
//! dL      = |p_tool(q_actual) − p_pivot(q_actual)| − L                       (um)
//! dL_nl   = dL − dL(q_linear)     what the nonlinearities alone (friction, backlash) add
//! ```
//!
//! The figures come from `dL`; spikes and steps from `dL_nl`, so that the linear response to
//! the program (the lag ellipse, the ripple of short blocks) is not taken for them.

use nalgebra::Point3;

use super::attribution::{bar_sensitivity_at, ThetaMap};
use super::ballbar::{BallbarRun, CircleFrame};
use super::bar::deviation_mm;
use crate::error::Result;
use crate::input::program::{Direction, MeasuredLines};
use crate::kinematics::Kinematics;
use crate::pipeline::{Sample, Sink};
use crate::{Axis, AxisVec};

/// The virtual ball bar of a test on one machine.
#[derive(Clone, Copy, Debug)]
pub struct BarGeometry {
    pub kinematics: Kinematics,
    /// The measured circle, for θ.
    pub frame: CircleFrame,
    /// Table-side ball, table frame, mm.
    pub pivot_table_mm: Point3<f64>,
    /// Nominal bar length L, mm.
    pub length_mm: f64,
}

/// What the bar reads at one sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BarReading {
    /// θ of the commanded tool tip, deg in [0, 360).
    pub theta_deg: f64,
    /// dL, um.
    pub deviation_um: f64,
    /// dL minus the linear twin's dL, um.
    pub nonlinear_um: f64,
    /// `(sin θ, cos θ)` ([`CircleFrame::theta_deg_sin_cos`]): the run's terms and the
    /// trace's centring.
    pub theta_sin_cos: (f64, f64),
}

impl BarGeometry {
    /// The bar's sensitivity ∂L/∂q to every axis at the commanded position `q`, mm per mm
    /// or deg ([`bar_sensitivity_at`]).
    pub fn sensitivity_at(&self, q: &AxisVec) -> AxisVec {
        let kin = &self.kinematics;
        bar_sensitivity_at(
            kin,
            kin.layout.axes(),
            q,
            &kin.rotary_sin_cos(q),
            &self.pivot_table_mm,
            self.length_mm,
        )
    }

    /// What the bar reads at sample `s`.
    pub fn read(&self, s: &Sample) -> BarReading {
        let kin = &self.kinematics;
        if !kin.location_errors.is_zero() || kin.general.is_some() {
            let dev = |q| deviation_mm(kin, q, &self.pivot_table_mm, self.length_mm) * 1e3;
            let deviation_um = dev(&s.actual);
            let (theta_deg, theta_sin_cos) =
                self.frame.theta_deg_sin_cos(&kin.forward(&s.commanded).tip);
            let reading = BarReading {
                theta_deg,
                deviation_um,
                nonlinear_um: deviation_um - dev(&s.linear),
                theta_sin_cos,
            };
            return reading;
        }
        // The actual and the twin's poses are within a following error of the commanded one:
        // their rotations from its sines and cosines (one `sin_cos` per angle and sample).
        let at_command = kin.rotary_sin_cos(&s.commanded);
        let dev = |q: &AxisVec| {
            let r = kin.rotation_of(&kin.rotary_sin_cos_near(q, &s.commanded, &at_command));
            let pivot = Point3::from(kin.pivot_mm + r * self.pivot_table_mm.coords);
            let tool = Point3::new(q[Axis::X], q[Axis::Y], q[Axis::Z]);
            ((tool - pivot).norm() - self.length_mm) * 1e3
        };
        let deviation_um = dev(&s.actual);
        let (theta_deg, theta_sin_cos) = self
            .frame
            .theta_deg_sin_cos(&kin.forward_with(&s.commanded, &at_command).tip);
        let reading = BarReading {
            theta_deg,
            deviation_um,
            nonlinear_um: deviation_um - dev(&s.linear),
            theta_sin_cos,
        };
        reading
    }
}

/// Whether a sample is in the measured revolution: on the measured lines, or, when none
/// are given, anywhere after the first move (which only brings the machine to the start).
pub fn is_measured(s: &Sample, measured: Option<MeasuredLines>) -> bool {
    match measured {
        Some(m) => (m.first..=m.last).contains(&s.line),
        None => s.block_index >= 1,
    }
}

/// One direction of a ball-bar test: the trace and its nonlinear signature, in θ bins.
#[derive(Clone, Debug)]
pub struct BallbarSink {
    geometry: BarGeometry,
    measured: Option<MeasuredLines>,
    /// dL against θ.
    pub run: BallbarRun,
    /// dL_nl against θ.
    pub signature: BallbarRun,
    /// Commanded axis positions against θ, mm or deg: where the bar's sensitivity is
    /// evaluated for a reversal site ([`BarGeometry::sensitivity_at`]).
    pub commanded: ThetaMap,
    /// Commanded axis speeds against θ, mm/s or deg/s.
    pub speed: ThetaMap,
    /// The previous sample's time (s) and commanded positions.
    previous: Option<(f64, crate::AxisVec)>,
}

impl BallbarSink {
    pub fn new(
        geometry: BarGeometry,
        direction: Direction,
        measured: Option<MeasuredLines>,
    ) -> BallbarSink {
        BallbarSink {
            geometry,
            measured,
            run: BallbarRun::new(direction),
            signature: BallbarRun::new(direction),
            commanded: ThetaMap::default(),
            speed: ThetaMap::default(),
            previous: None,
        }
    }
}

impl BallbarSink {
    /// The bar's reading of `s` when it is in the measured revolution (None otherwise),
    /// after taking it into the run: for a trace that records the same reading.
    pub fn take(&mut self, s: &Sample) -> Option<BarReading> {
        let previous = self.previous.replace((s.time_s, s.commanded));
        if !is_measured(s, self.measured) {
            return None;
        }
        let r = self.geometry.read(s);
        BallbarRun::push_pair_at(
            &mut self.run,
            &mut self.signature,
            r.theta_deg,
            r.theta_sin_cos,
            r.deviation_um,
            r.nonlinear_um,
        );
        if self.commanded.wants(r.theta_deg) {
            self.commanded.set(r.theta_deg, s.commanded);
        }
        if let Some((t0, q0)) = previous.filter(|(t0, _)| s.time_s > *t0) {
            if self.speed.wants(r.theta_deg) {
                self.speed
                    .set(r.theta_deg, (s.commanded - q0) * (1.0 / (s.time_s - t0)));
            }
        }
        Some(r)
    }
}

impl Sink for BallbarSink {
    fn push(&mut self, s: &Sample) -> Result<()> {
        self.take(s);
        Ok(())
    }
}
