//! The fit's parameters: location errors, bar offsets, the table ball's placement, servo
//! parameters; with the fit's options, tolerances and finite-difference steps.
//! Inputs: none (plain types). Outputs: [`Param`], [`FitOptions`], the constants.

use crate::kinematics::LocationParam;
use crate::Axis;

/// Singular values below this fraction of the largest (of the column-scaled sensitivity
/// matrix) span the null space. Exact degeneracies of the ideal test sit at ~1e-10; some are
/// broken only by second-order effects such as the servo lag of the recorded motion
/// (~1e-5, e.g. the table-ball placement against the A-axis errors when the placement is fitted), which
/// no real noise level resolves; genuine information starts near 1e-3.
pub const NULL_TOLERANCE: f64 = 1e-4;
/// Smallest RMS change of the traces, um per unit of a parameter (um, urad, mdeg, 1/s),
/// for the parameter to count as seen. A servo parameter below it is left out of the fit
/// (its sensitivity, from re-simulation, is mostly rounding); a location error or
/// placement below it is kept in the fit as a nuisance, given no value, and its spread is
/// carried into the others' standard errors.
pub const MIN_VISIBILITY: f64 = 0.01;
/// A column below this RMS, um per unit, moves the traces only by rounding: the parameter
/// does not act at all (a tilt of C with the ball on C's line, for example).
pub const NUMERICAL_ZERO: f64 = 1e-7;
/// Gauss–Newton iterations at most, and the RMS model change (um) of a step below which
/// they stop.
pub(crate) const MAX_ITERATIONS: usize = 12;
pub(crate) const CONVERGED_UM: f64 = 1e-6;
/// Entries of a null direction below this fraction of its largest (column-scaled) are
/// rounding noise and dropped.
pub(crate) const NULL_ENTRY: f64 = 1e-4;
/// Finite-difference step of the location errors, um or urad.
pub(crate) const GEOMETRY_STEP: f64 = 1.0;
/// Finite-difference steps of backlash (um, or mdeg) and servo gain (1/s).
pub(crate) const BACKLASH_STEP: f64 = 2.0;
pub(crate) const GAIN_STEP: f64 = 0.5;

/// What to estimate besides the location errors and the bar-length offsets.
#[derive(Clone, Copy, Debug, Default)]
pub struct FitOptions {
    /// The table ball's placement is known: do not fit its error (three translations per
    /// trace, fitted by default).
    pub placement_known: bool,
    /// Per-axis backlash.
    pub backlash: bool,
    /// Per-axis servo position-loop gain.
    pub servo_gain: bool,
}

/// One parameter of the fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Param {
    Location(LocationParam),
    BarOffset(usize),
    Setup(usize, usize),
    Backlash(Axis),
    Gain(Axis),
}

impl Param {
    pub fn name(&self) -> String {
        match self {
            Param::Location(p) => p.name().to_string(),
            Param::BarOffset(k) => format!("bar_offset[{k}]"),
            Param::Setup(k, i) => format!("setup_{}[{k}]", ["x", "y", "z"][*i]),
            Param::Backlash(a) => format!("backlash_{a}"),
            Param::Gain(a) => format!("kv_{a}"),
        }
    }
    pub fn unit(&self) -> &'static str {
        match self {
            Param::Location(p) => p.unit(),
            Param::BarOffset(_) | Param::Setup(..) => "um",
            Param::Backlash(a) if a.is_rotary() => "mdeg",
            Param::Backlash(_) => "um",
            Param::Gain(_) => "1/s",
        }
    }
    pub fn is_servo(&self) -> bool {
        matches!(self, Param::Backlash(_) | Param::Gain(_))
    }
    /// Pivot preference when naming a null direction: lower first. The bar offset comes
    /// last, so it carries what the placement and it cannot separate (the constant a
    /// foreign trace needs, checked against the trace's own radius change).
    pub fn pivot_class(&self) -> u8 {
        match self {
            Param::Location(p) if !p.is_position() => 0,
            Param::Location(_) => 1,
            Param::BarOffset(_) => 3,
            _ => 2,
        }
    }
}

pub(crate) fn round6(v: f64) -> f64 {
    (v * 1e6).round() / 1e6
}

pub(crate) fn round_sig(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let e = v.abs().log10().floor() as i32;
    let s = 10f64.powi(5 - e);
    (v * s).round() / s
}
