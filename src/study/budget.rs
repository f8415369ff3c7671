//! The error budget of a ball-bar run, by counterfactual runs: what each mechanism of the
//! machine adds to the bar's curve, computed rather than guessed.
//!
//! # The runs
//!
//! Beside the full run, the same setpoints (the run's own: one read, plan and
//! interpolation for all) drive counterfactual machines, each the ideal machine
//! (actual = commanded, nominal kinematics) plus one mechanism:
//!
//! | run | actual positions q | measured against |
//! |---|---|---|
//! | program | q = s (the setpoint) | nothing: its curve is the row |
//! | servos' common lag (axis null) | every axis through one first-order loop of gain 1/τ̄ | program |
//! | servo of axis a | the common lag's, with q_a from a's linear twin (no backlash, no dry friction) | common lag |
//! | backlash of a | the same, q_a from a's drive with its backlash and no dry friction | servo of a |
//! | friction of a | the same, q_a from a's drive with its dry friction (and pre-sliding), no backlash | servo of a |
//! | geometric (rotaries), squareness, component errors of a | s, read through the chain with that part of the geometric errors alone | program |
//! | error table of a | s, with `q_a = s_a + e_a(s_a, direction)` | program |
//!
//! `τ̄` is the mean of the axes' velocity lags `τ_a = (1 − k_vff,a)/Kv_a` over the axes the
//! program moves (a circle's two; every axis otherwise). Identical dynamics on every axis
//! draw almost nothing on the bar (the spec's closed form 6), while one axis lagging alone
//! draws hundreds of µm that the others' lags cancel: measured against the common loop, a
//! servo row is what that axis's loop does differently from the others (its gain mismatch,
//! its inner loops), and what they do alike is the common lag's row (on a cone, the program's
//! own curve seen a lag later). Friction and backlash ride on their axis's servo, as they do
//! on the machine: a row is the run's curve minus its servo's. Rows are built only for mechanisms the machine has
//! (a drive with backlash, dry friction on a cascade drive, location errors, a table) on
//! axes the program moves. The geometric errors are split by cause
//! ([`LocationErrors::parts`]): the rotaries' location errors, the squareness of the
//! linear axes, and each linear axis's component-error table, a run each.
//!
//! A run's servo that the full run steps too (the machine's own drive, with no backlash to
//! take out for a friction run, or its linear twin) is not stepped again: its positions are
//! the full run's samples' own ([`Sample::actual`], [`Sample::linear`]), the same model on
//! the same setpoints from the same start, so the same bits. Not on an axis with a
//! position-error table, whose samples carry the table's errors.
//!
//! The cut (`study::cut_budget`) runs the same plan: it takes each run's positions
//! ([`BudgetRun::measured_positions`]) and cuts them on its grid instead of reading the bar.
//!
//! # The rows
//!
//! Each run's bar reading `dL_k(θ)` is binned as the full run's is (the same samples, the
//! same θ) and centred by its own least-squares circle; centring is linear in dL over the
//! same θ, so the contribution curves
//!
//! ```text
//! c_program = centred dL_program          c_k = centred dL_k − centred dL_base(k)
//! ```
//!
//! add up to the full run's centred curve d, but for the interplay of the mechanisms. Over
//! the revolution of the direction that gives G,
//!
//! ```text
//! pv_k    = max c_k − min c_k
//! share_k = <c_k − c̄_k, d − d̄> / <d − d̄, d − d̄>
//! interaction_share = 1 − Σ_k share_k
//! ```
//!
//! so a part that works against G has a negative share, and all of them sum to 1.
//!
//! # B per axis
//!
//! The lost motion of axis a is the sum of its backlash and friction rows,
//! `c_lm = dL_backlash + dL_friction − 2 dL_servo` (raw, per sample). Away from a reversal
//! the table lags the linear twin by half the lost motion δ in the direction of motion, so
//! `c_lm(θ) ≈ −(δ/2) sgn(v_a) S_a(θ)` with `S_a = ∂dL/∂q_a` (central difference at the
//! servo run's q, at a bin's first sample). Over the θ bins where the axis moves at least a
//! fifth of its top speed (the take-up after a reversal left out), by least squares,
//!
//! ```text
//! δ = −2 Σ c̄_lm g / Σ g²,     g = sgn(v̄_a) S̄_a
//! ```
//!
//! in mm (µm along the axis) or deg (µm of arc at the bar's length). A machine without
//! backlash and dry friction on an axis has no such runs, and its B is 0.

use std::cell::RefCell;
use std::f64::consts::PI;

use nalgebra::Point3;

use crate::drive::AxisServo;
use crate::error::Result;
use crate::input::drive::AxisDrive;
use crate::input::machine::Machine;
use crate::input::scenario::Scenario;
use crate::kinematics::error_table::{DirectionState, ErrorTable};
use crate::kinematics::{ErrorPart, LocationErrors};
use crate::measure::attribution::ReversalSite;
use crate::measure::ballbar::{deviation_mm, BallbarResult, N_BINS};
use crate::measure::{BallbarRun, BarGeometry, BarReading, Direction};
use crate::pipeline::{Sample, Sink, Timing};
use crate::report::run::{AxisReversal, BudgetMechanism, BudgetRow, ErrorBudget};
use crate::{Axis, AxisVec};

/// An axis counts as moving in a bin where its speed is at least this part of its top speed
/// (the take-up after a reversal is left out of B's fit).
pub const B_SPEED_FRACTION: f64 = 0.2;
/// The bar must see an axis at least this much (normalised sensitivity) at one of its
/// reversals for a B to be given.
pub const B_SENSITIVITY_MIN: f64 = 0.5;
/// Central-difference step of `S_a`: mm for a linear axis, deg for a rotary one.
const DIFF_STEP: f64 = 1e-3;

/// Where a run's actual positions come from.
#[derive(Clone, Copy, Debug)]
enum Source {
    /// actual = commanded.
    Ideal,
    /// Every axis through the common servo: a first-order loop of gain 1/τ̄.
    Common,
    /// [`Source::Common`] with the given servo's axis at that servo's actual.
    Servo(usize),
    /// The commanded positions with the given table's axis moved by its error.
    Table(usize),
    /// The commanded positions through the chain with the plan's geometric errors part.
    Geometric(usize),
}

/// One counterfactual run.
#[derive(Clone, Copy, Debug)]
struct Case {
    mechanism: BudgetMechanism,
    axis: Option<Axis>,
    source: Source,
    /// The run it is measured against (None: the program row, measured against nothing).
    base: Option<usize>,
}

/// An axis with lost motion: its servo run and its backlash and friction runs.
#[derive(Clone, Debug)]
struct LostMotion {
    axis: Axis,
    servo_case: usize,
    cases: Vec<usize>,
}

/// A servo of the budget that the full run steps too, on the same setpoints from the same
/// start: its actual positions are the samples' own, bit for bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum InRun {
    /// The axis's drive ([`Sample::actual`]).
    Drive,
    /// The axis's linear twin ([`Sample::linear`]).
    Twin,
}

/// The runs of a scenario's budget: which mechanisms, on which axes.
#[derive(Clone, Debug)]
pub struct BudgetPlan {
    cases: Vec<Case>,
    /// The servos the runs drive, with whether each is a linear twin.
    drives: Vec<(AxisDrive, bool)>,
    /// Per servo of `drives`, whether the full run steps it too: the machine's own drive or
    /// its linear twin, on an axis without a position-error table (whose errors the samples'
    /// positions carry).
    in_run: Vec<Option<InRun>>,
    tables: Vec<(Axis, ErrorTable)>,
    lost_motion: Vec<LostMotion>,
    /// The geometric errors split by cause ([`LocationErrors::parts`]), one run each.
    geometric: Vec<LocationErrors>,
    /// The bar on the nominal chain, and on the chain with each of `geometric`; None for a
    /// plan whose runs are read as positions only ([`BudgetPlan::for_positions`]).
    bar: Option<(BarGeometry, Vec<BarGeometry>)>,
    period_s: f64,
    /// The common servo of every axis (see [`common_lag_s`]); none without a common lag.
    common: Vec<AxisDrive>,
}

impl BudgetPlan {
    /// The runs for `scenario`'s bar `geometry`: every mechanism the machine has.
    pub fn new(scenario: &Scenario, geometry: BarGeometry) -> Result<BudgetPlan> {
        BudgetPlan::build(scenario, Some(geometry))
    }

    /// The same runs for a measurement that reads each run's positions through its own
    /// geometry ([`BudgetRun::measured_positions`]: the contour error of a part program),
    /// without a bar.
    pub fn for_positions(scenario: &Scenario) -> Result<BudgetPlan> {
        BudgetPlan::build(scenario, None)
    }

    fn build(scenario: &Scenario, geometry: Option<BarGeometry>) -> Result<BudgetPlan> {
        let machine = &scenario.machine;
        let parts = machine.kinematics.location_errors.parts();
        let bar = geometry.map(|actual| {
            let with = |errors: LocationErrors| {
                let mut g = actual;
                g.kinematics.location_errors = errors;
                g
            };
            let each = parts.iter().map(|(_, e)| with(*e)).collect();
            (with(LocationErrors::default()), each)
        });
        let period_s = machine.interpolation_period_s;
        let delay_s = common_lag_s(scenario)?;
        let mut plan = BudgetPlan {
            cases: vec![Case {
                mechanism: BudgetMechanism::ProgramPath,
                axis: None,
                source: Source::Ideal,
                base: None,
            }],
            drives: Vec::new(),
            in_run: Vec::new(),
            tables: Vec::new(),
            lost_motion: Vec::new(),
            geometric: Vec::new(),
            bar,
            period_s,
            common: Vec::new(),
        };
        // The servos' common response: a row of its own when they lag.
        let lagged = if delay_s > 0.0 {
            for &axis in machine.axes() {
                let d = machine.drive(axis).linear_twin();
                plan.common.push(AxisDrive {
                    model: crate::input::drive::Model::FirstOrder,
                    kv_per_s: 1.0 / delay_s,
                    velocity_feedforward: 0.0,
                    acceleration_feedforward: 0.0,
                    ..d
                });
            }
            plan.cases.push(Case {
                mechanism: BudgetMechanism::Servo,
                axis: None,
                source: Source::Common,
                base: Some(0),
            });
            plan.cases.len() - 1
        } else {
            0
        };
        for &axis in machine.axes() {
            let drive = machine.drive(axis);
            let servo_case =
                plan.servo_case(BudgetMechanism::Servo, drive.linear_twin(), true, lagged);
            let mut lost = Vec::new();
            if drive.backlash_m_or_rad > 0.0 {
                let backlash = AxisDrive {
                    coulomb_n_or_nm: 0.0,
                    presliding_m_or_rad: 0.0,
                    presliding_mm_or_deg: 0.0,
                    ..drive
                };
                lost.push(plan.servo_case(BudgetMechanism::Backlash, backlash, false, servo_case));
            }
            if drive.has_dry_friction() {
                let friction = AxisDrive {
                    backlash_m_or_rad: 0.0,
                    backlash_mm_or_deg: 0.0,
                    ..drive
                };
                lost.push(plan.servo_case(BudgetMechanism::Friction, friction, false, servo_case));
            }
            if !lost.is_empty() {
                plan.lost_motion.push(LostMotion {
                    axis,
                    servo_case,
                    cases: lost,
                });
            }
        }
        for (part, errors) in parts {
            let (mechanism, axis) = match part {
                ErrorPart::Rotaries => (BudgetMechanism::Geometric, None),
                ErrorPart::Squareness => (BudgetMechanism::Squareness, None),
                ErrorPart::Components(a) => (BudgetMechanism::ComponentErrors, Some(a)),
            };
            plan.cases.push(Case {
                mechanism,
                axis,
                source: Source::Geometric(plan.geometric.len()),
                base: Some(0),
            });
            plan.geometric.push(errors);
        }
        for (&axis, table) in &machine.geometry.tables {
            plan.cases.push(Case {
                mechanism: BudgetMechanism::ErrorTable,
                axis: Some(axis),
                source: Source::Table(plan.tables.len()),
                base: Some(0),
            });
            plan.tables.push((axis, table.clone()));
        }
        plan.note_in_run(machine);
        Ok(plan)
    }

    /// Adds a run of `drive` (a linear twin or not) measured against run `base`; its index.
    fn servo_case(
        &mut self,
        mechanism: BudgetMechanism,
        drive: AxisDrive,
        linear: bool,
        base: usize,
    ) -> usize {
        self.cases.push(Case {
            mechanism,
            axis: Some(drive.axis),
            source: Source::Servo(self.drives.len()),
            base: Some(base),
        });
        self.drives.push((drive, linear));
        self.cases.len() - 1
    }

    /// Marks the servos the full run steps too ([`InRun`]) on `machine`.
    fn note_in_run(&mut self, machine: &Machine) {
        self.in_run = (self.drives.iter())
            .map(|&(drive, linear)| {
                let own = machine.drive(drive.axis);
                if machine.geometry.tables.contains_key(&drive.axis) {
                    None
                } else if !linear && drive == own {
                    Some(InRun::Drive)
                } else if linear && drive == own.linear_twin() {
                    Some(InRun::Twin)
                } else {
                    None
                }
            })
            .collect();
    }

    /// The runs of one direction, from rest at its first setpoint, fed the samples of a
    /// full run timed by `timing`: under planned timing with the twins, the servos it steps
    /// too ([`InRun`]) are read from its samples rather than stepped again.
    pub fn start(&self, direction: Direction, timing: Timing) -> BudgetRun<'_> {
        let samples_carry = |r: &InRun| match (r, timing) {
            (InRun::Drive, Timing::Planned { .. }) => true,
            (InRun::Twin, Timing::Planned { twins, .. }) => twins,
            (_, Timing::Programmed | Timing::Setpoints) => false,
        };
        BudgetRun {
            plan: self,
            servos: Vec::new(),
            in_run: (self.in_run.iter())
                .map(|&r| r.filter(samples_carry))
                .collect(),
            actual: vec![0.0; self.drives.len()],
            table_state: vec![(DirectionState::default(), 0.0); self.tables.len()],
            runs: self
                .cases
                .iter()
                .map(|_| BallbarRun::new(direction))
                .collect(),
            devs: vec![0.0; self.cases.len()],
            common: Vec::new(),
            first: None,
            moved: Vec::new(),
            previous: None,
            velocity: AxisVec::ZERO,
            lost_bins: self
                .lost_motion
                .iter()
                .map(|_| vec![LostBin::default(); N_BINS])
                .collect(),
            failed: None,
        }
    }
}

/// The servos' common lag τ̄, s: the mean of `τ_a = (1 − k_vff,a) / Kv_a` over the axes
/// the program moves (a circle's two, or every axis of the machine).
fn common_lag_s(scenario: &Scenario) -> Result<f64> {
    let machine = &scenario.machine;
    let axes: Vec<Axis> = match crate::program::test_of(scenario).circle() {
        Some(circle) => {
            let (u, v, _) = circle.axes();
            vec![u, v]
        }
        None => machine.axes().to_vec(),
    };
    let mut lags = Vec::new();
    for a in axes.into_iter().filter(|a| machine.axes().contains(a)) {
        let d = machine.drive(a);
        lags.push((1.0 - d.velocity_feedforward) / d.kv_per_s);
    }
    Ok(match lags.len() {
        0 => 0.0,
        n => (lags.iter().sum::<f64>() / n as f64).max(0.0),
    })
}

/// One θ bin of B's fit: sums over its samples of `c_lm` and `v_a`, and `S_a` at its first
/// sample (smooth in θ: a 0.05° bin holds a few samples, and the difference costs two
/// readings).
#[derive(Clone, Copy, Debug, Default)]
struct LostBin {
    n: u64,
    c: f64,
    s: f64,
    v: f64,
}

/// The budget's runs of one direction, fed sample by sample: [`BudgetStepper`] steps its
/// servos on every sample, the bar's sink hands it each reading it takes
/// ([`BudgetRun::record`]).
pub struct BudgetRun<'p> {
    plan: &'p BudgetPlan,
    /// The plan's servos the full run does not step, made at the first sample (at rest
    /// there, as the full run's), each with its index in the plan's.
    servos: Vec<(usize, AxisServo)>,
    /// Per servo of the plan, whether its positions are the samples' ([`InRun`]).
    in_run: Vec<Option<InRun>>,
    /// Per servo of the plan, its actual position at the current sample, mm or deg.
    actual: Vec<f64>,
    /// Each table's direction of motion and its error at the current sample, mm or deg.
    table_state: Vec<(DirectionState, f64)>,
    runs: Vec<BallbarRun>,
    /// Each run's reading of the current sample, µm.
    devs: Vec<f64>,
    /// The common servo of every axis, made with the others.
    common: Vec<AxisServo>,
    /// The first measured setpoint.
    first: Option<AxisVec>,
    /// The axes whose setpoint has left its first value.
    moved: Vec<Axis>,
    /// The previous sample's time and setpoint, and the setpoint's speed now.
    previous: Option<(f64, AxisVec)>,
    velocity: AxisVec,
    lost_bins: Vec<Vec<LostBin>>,
    /// Why the runs stopped (a servo diverged); the budget is then left out.
    failed: Option<String>,
}

impl BudgetRun<'_> {
    /// Steps every run's servos and tables to sample `s`.
    pub fn step(&mut self, s: &Sample) {
        if self.failed.is_some() {
            return;
        }
        let q = &s.commanded;
        let plan = self.plan;
        // The first sample (none before it): the servos start at rest there.
        if self.previous.is_none() {
            if let Err(e) = self.make_servos(q) {
                self.failed = Some(e.to_string());
                return;
            }
        }
        let own = (self.servos.iter_mut()).map(|(i, servo)| (Some(*i), servo, plan.drives[*i]));
        let common = (self.common.iter_mut()).zip(&plan.common);
        let common = common.map(|(servo, drive)| (None, servo, (*drive, true)));
        for (i, servo, (drive, linear)) in own.chain(common) {
            let setpoint = q[drive.axis];
            let stepped = match linear {
                true => servo.advance_twin(setpoint, s.time_s),
                false => servo.advance(setpoint, s.time_s),
            };
            if let Err(e) = stepped {
                self.failed = Some(e.to_string());
                return;
            }
            if let Some(i) = i {
                self.actual[i] = servo.actual();
            }
        }
        for ((actual, in_run), (drive, _)) in
            self.actual.iter_mut().zip(&self.in_run).zip(&plan.drives)
        {
            match in_run {
                Some(InRun::Drive) => *actual = s.actual[drive.axis],
                Some(InRun::Twin) => *actual = s.linear[drive.axis],
                None => {}
            }
        }
        for ((axis, table), (direction, error)) in plan.tables.iter().zip(&mut self.table_state) {
            let v = q[*axis];
            *error = table.error_at(v, direction.update(v));
        }
        if let Some((t0, q0)) = self.previous.replace((s.time_s, *q)) {
            if s.time_s > t0 {
                self.velocity = (*q - q0) * (1.0 / (s.time_s - t0));
            }
        }
    }

    /// The servos the run steps itself, at rest at the first setpoint `q`.
    fn make_servos(&mut self, q: &AxisVec) -> Result<()> {
        let plan = self.plan;
        let period_s = plan.period_s;
        self.servos = (plan.drives.iter().enumerate())
            .filter(|&(i, _)| self.in_run[i].is_none())
            .map(|(i, (d, _))| Ok((i, AxisServo::new(d, period_s, q[d.axis])?)))
            .collect::<Result<_>>()?;
        self.common = (plan.common.iter())
            .map(|d| AxisServo::new(d, period_s, q[d.axis]))
            .collect::<Result<_>>()?;
        Ok(())
    }

    /// Takes the bar's reading `r` of sample `s` (stepped already) into every run.
    pub fn record(&mut self, s: &Sample, r: &BarReading) {
        if self.failed.is_some() {
            return;
        }
        let plan = self.plan;
        // Readings come from the bar's sink alone, which a plan without a bar never has.
        let Some((ideal, geometric)) = &plan.bar else {
            return;
        };
        let cmd = s.commanded;
        self.note_measured(&cmd);
        let reading = IdealReading::new(ideal, &cmd);
        let delayed = self.common_positions(&cmd);
        let delayed_ball = reading.ball_at(&delayed);
        for (k, case) in plan.cases.iter().enumerate() {
            self.devs[k] = match case.source {
                Source::Ideal => reading.at(&cmd, false),
                Source::Common => reading.to_ball(&delayed, delayed_ball.as_ref()),
                Source::Servo(i) => {
                    let axis = plan.drives[i].0.axis;
                    let q = self.positions_of(case.source, &cmd, &delayed);
                    match axis.is_rotary() {
                        true => reading.to_ball(&q, reading.ball_at(&q).as_ref()),
                        false => reading.to_ball(&q, delayed_ball.as_ref()),
                    }
                }
                Source::Table(i) => {
                    let q = self.positions_of(case.source, &cmd, &delayed);
                    reading.at(&q, plan.tables[i].0.is_rotary())
                }
                Source::Geometric(i) => {
                    let g = &geometric[i];
                    deviation_mm(&g.kinematics, &cmd, &g.pivot_table_mm, g.length_mm) * 1e3
                }
            };
        }
        for (run, &dev) in self.runs.iter_mut().zip(&self.devs) {
            run.push_terms(r.terms.as_ref(), dev);
        }
        let Some(bin) = r.terms.map(|t| t.bin) else {
            return;
        };
        for (lost, bins) in plan.lost_motion.iter().zip(&mut self.lost_bins) {
            let a = lost.axis;
            let servo = self.devs[lost.servo_case];
            let c: f64 = lost.cases.iter().map(|&k| self.devs[k] - servo).sum();
            let Source::Servo(i) = plan.cases[lost.servo_case].source else {
                continue;
            };
            let b = &mut bins[bin];
            if b.n == 0 {
                let mut q = delayed;
                q[a] = self.actual[i];
                let (mut up, mut down) = (q, q);
                up[a] += DIFF_STEP;
                down[a] -= DIFF_STEP;
                let at = |q: &AxisVec| match a.is_rotary() {
                    true => reading.to_ball(q, reading.ball_at(q).as_ref()),
                    false => reading.to_ball(q, delayed_ball.as_ref()),
                };
                b.s = (at(&up) - at(&down)) / (2.0 * DIFF_STEP);
            }
            b.n += 1;
            b.c += c;
            b.v += self.velocity[a];
        }
    }

    /// A measured setpoint `cmd`: the axes that have left the first one are moved.
    fn note_measured(&mut self, cmd: &AxisVec) {
        let first = *self.first.get_or_insert(*cmd);
        for &a in crate::Axis::ALL.iter() {
            if cmd[a] != first[a] && !self.moved.contains(&a) {
                self.moved.push(a);
            }
        }
    }

    /// The actual positions of a run from `source` at the setpoint `cmd` (stepped already),
    /// with `delayed` the common servo's ([`BudgetRun::common_positions`]); mm and deg.
    /// The geometric run's are the setpoint: its errors are in the chain it is read through.
    fn positions_of(&self, source: Source, cmd: &AxisVec, delayed: &AxisVec) -> AxisVec {
        match source {
            Source::Ideal | Source::Geometric(_) => *cmd,
            Source::Common => *delayed,
            Source::Servo(i) => {
                let mut q = *delayed;
                q[self.plan.drives[i].0.axis] = self.actual[i];
                q
            }
            Source::Table(i) => {
                let mut q = *cmd;
                q[self.plan.tables[i].0] += self.table_state[i].1;
                q
            }
        }
    }

    /// Each run's actual positions at the measured setpoint `cmd` (stepped already), in the
    /// plan's order ([`BudgetPlan::cases`]), for a measurement other than the bar (the cut)
    /// that reads them through its own geometry; None once a servo failed.
    pub fn measured_positions(&mut self, cmd: &AxisVec, out: &mut Vec<AxisVec>) -> Option<()> {
        if self.failed.is_some() {
            return None;
        }
        self.note_measured(cmd);
        let delayed = self.common_positions(cmd);
        out.clear();
        for case in &self.plan.cases {
            out.push(self.positions_of(case.source, cmd, &delayed));
        }
        Some(())
    }

    /// Every axis through the common servo (the setpoint `cmd` itself without one).
    fn common_positions(&self, cmd: &AxisVec) -> AxisVec {
        let mut q = *cmd;
        for (servo, drive) in self.common.iter().zip(&self.plan.common) {
            q[drive.axis] = servo.actual();
        }
        q
    }

    /// The direction's runs, or why they failed.
    pub fn finish(self) -> std::result::Result<BudgetDirection, String> {
        if let Some(why) = self.failed {
            return Err(why);
        }
        Ok(BudgetDirection {
            runs: self.runs,
            moved: self.moved,
            lost_bins: self.lost_bins,
        })
    }
}

/// What the ideal machine's bar reads near one setpoint: the table ball at the commanded
/// rotaries is computed once and kept for every run that leaves them there.
struct IdealReading<'g> {
    geometry: &'g BarGeometry,
    commanded: AxisVec,
    at_command: crate::kinematics::RotarySinCos,
    /// The table ball at the commanded rotaries; None on a general chain (read whole).
    ball: Option<Point3<f64>>,
}

impl<'g> IdealReading<'g> {
    fn new(geometry: &'g BarGeometry, commanded: &AxisVec) -> IdealReading<'g> {
        let at_command = geometry.kinematics.rotary_sin_cos(commanded);
        let ball = (!geometry.needs_full_chain())
            .then(|| geometry.table_ball_mm(commanded, commanded, &at_command));
        IdealReading {
            geometry,
            commanded: *commanded,
            at_command,
            ball,
        }
    }

    /// The table ball at `q`'s rotaries (near the setpoint's); None on a general chain.
    fn ball_at(&self, q: &AxisVec) -> Option<Point3<f64>> {
        self.ball.map(|_| {
            self.geometry
                .table_ball_mm(q, &self.commanded, &self.at_command)
        })
    }

    /// dL at `q` with the table ball `ball` made for q's rotaries ([`IdealReading::ball_at`]),
    /// µm; the whole chain read at q when there is none.
    fn to_ball(&self, q: &AxisVec, ball: Option<&Point3<f64>>) -> f64 {
        let g = self.geometry;
        match ball {
            Some(ball) => g.deviation_to_ball_um(q, ball),
            None => deviation_mm(&g.kinematics, q, &g.pivot_table_mm, g.length_mm) * 1e3,
        }
    }

    /// dL at `q`, µm; `rotary_moved`: q's rotaries may differ from the setpoint's.
    fn at(&self, q: &AxisVec, rotary_moved: bool) -> f64 {
        let g = self.geometry;
        match self.ball {
            None => deviation_mm(&g.kinematics, q, &g.pivot_table_mm, g.length_mm) * 1e3,
            Some(ball) if !rotary_moved => g.deviation_to_ball_um(q, &ball),
            Some(_) => {
                let ball = g.table_ball_mm(q, &self.commanded, &self.at_command);
                g.deviation_to_ball_um(q, &ball)
            }
        }
    }
}

/// The budget's runs of one direction, done.
pub struct BudgetDirection {
    runs: Vec<BallbarRun>,
    moved: Vec<Axis>,
    lost_bins: Vec<Vec<LostBin>>,
}

impl BudgetDirection {
    /// The axes whose measured setpoint left its first value.
    pub fn moved(&self) -> &[Axis] {
        &self.moved
    }
}

/// One run of a plan as another measurement sees it: the mechanism and axis it adds, the
/// run it is measured against (None: the program's own, against nothing) and the geometric
/// errors its positions are read through (a geometric run's part of them), or None for the
/// nominal chain (every other run).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CaseInfo {
    pub mechanism: BudgetMechanism,
    pub axis: Option<Axis>,
    pub base: Option<usize>,
    pub errors: Option<LocationErrors>,
}

impl BudgetPlan {
    /// The plan's runs, in the order [`BudgetRun::measured_positions`] gives them.
    pub fn cases(&self) -> Vec<CaseInfo> {
        self.cases
            .iter()
            .map(|c| CaseInfo {
                mechanism: c.mechanism,
                axis: c.axis,
                base: c.base,
                errors: match c.source {
                    Source::Geometric(i) => Some(self.geometric[i]),
                    _ => None,
                },
            })
            .collect()
    }
}

/// Steps a direction's [`BudgetRun`] on every sample of the pipeline (placed before any
/// settle gate: the servos must see every setpoint).
pub struct BudgetStepper<'a, 'p>(pub &'a RefCell<BudgetRun<'p>>);

impl Sink for BudgetStepper<'_, '_> {
    #[inline]
    fn push(&mut self, s: &Sample) -> Result<()> {
        self.0.borrow_mut().step(s);
        Ok(())
    }
}

/// The error budget and each axis's B from the budget's runs of every direction
/// (`directions[k]` beside the full run `full[k]`), with the full run's `result` and the
/// reversal `sites` (for which axes' reversals the bar sees).
pub fn assemble(
    plan: &BudgetPlan,
    directions: &[BudgetDirection],
    full: &[BallbarRun],
    result: &BallbarResult,
    sites: &[ReversalSite],
) -> Result<(ErrorBudget, Vec<AxisReversal>)> {
    // The revolution that gives G (the first of equals).
    let k = result
        .runs
        .iter()
        .enumerate()
        .fold(0, |best, (i, f)| {
            if f.circular_deviation_um > result.runs[best].circular_deviation_um {
                i
            } else {
                best
            }
        })
        .min(directions.len().saturating_sub(1));
    let dir = &directions[k];
    let d = full[k].trace_um(true)?;
    let curves: Vec<Vec<f64>> = dir
        .runs
        .iter()
        .map(|r| r.trace_um(true))
        .collect::<Result<_>>()?;
    let moved = |a: Axis| directions.iter().any(|d| d.moved.contains(&a));
    let contribution = |i: usize| -> Vec<f64> {
        match plan.cases[i].base {
            None => curves[i].clone(),
            Some(b) => curves[i]
                .iter()
                .zip(&curves[b])
                .map(|(c, b)| c - b)
                .collect(),
        }
    };
    let mut rows = Vec::new();
    for (i, case) in plan.cases.iter().enumerate() {
        if case.axis.is_some_and(|a| !moved(a)) {
            continue;
        }
        let c = contribution(i);
        rows.push(BudgetRow {
            mechanism: case.mechanism,
            axis: case.axis.map(|a| a.to_string()),
            pv_um: peak_to_valley(&c),
            share: share_of(&c, &d),
        });
    }
    let interaction_share = 1.0 - rows.iter().map(|r| r.share).sum::<f64>();
    let budget = ErrorBudget {
        g_um: result.runs[k].circular_deviation_um,
        rows,
        interaction_share,
    };
    let b = reversal_b(plan, directions, sites, &contribution, &moved);
    Ok((budget, b))
}

/// `max − min` of a curve, µm.
pub fn peak_to_valley(c: &[f64]) -> f64 {
    let (lo, hi) = c
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if c.is_empty() {
        0.0
    } else {
        hi - lo
    }
}

/// `<c − c̄, d − d̄> / <d − d̄, d − d̄>`; 0 when d is flat.
pub fn share_of(c: &[f64], d: &[f64]) -> f64 {
    projection_share(c, d, true)
}

/// The part of `d` that `c` explains, `<c − c̄, d − d̄> / <d − d̄, d − d̄>` with the means
/// taken out (`about_mean`: a centred curve, the bar's) or `<c, d> / <d, d>` about zero
/// (a deviation whose mean is a figure, the cut's size); 0 when d is flat (zero).
pub fn projection_share(c: &[f64], d: &[f64], about_mean: bool) -> f64 {
    let n = d.len().min(c.len()) as f64;
    if n == 0.0 {
        return 0.0;
    }
    let (cm, dm) = match about_mean {
        true => (c.iter().sum::<f64>() / n, d.iter().sum::<f64>() / n),
        false => (0.0, 0.0),
    };
    let (cd, dd) = c.iter().zip(d).fold((0.0, 0.0), |(cd, dd), (c, d)| {
        (cd + (c - cm) * (d - dm), dd + (d - dm) * (d - dm))
    });
    if dd > 0.0 {
        cd / dd
    } else {
        0.0
    }
}

/// Each machine axis's B from its lost-motion runs (see the module's doc).
fn reversal_b(
    plan: &BudgetPlan,
    directions: &[BudgetDirection],
    sites: &[ReversalSite],
    contribution: &dyn Fn(usize) -> Vec<f64>,
    moved: &dyn Fn(Axis) -> bool,
) -> Vec<AxisReversal> {
    let Some((ideal, _)) = &plan.bar else {
        return Vec::new();
    };
    let length_mm = ideal.length_mm;
    plan.drives
        .iter()
        .filter(|(_, linear)| *linear)
        .map(|(drive, _)| {
            let axis = drive.axis;
            let seen = sites
                .iter()
                .filter(|s| s.axis == axis && s.sensitivity.unwrap_or(1.0) >= B_SENSITIVITY_MIN)
                .count();
            let lost = plan
                .lost_motion
                .iter()
                .enumerate()
                .find(|(_, l)| l.axis == axis);
            let (b_um, step_um) = match lost {
                _ if seen == 0 || !moved(axis) => (None, None),
                None => (Some(0.0), Some(0.0)),
                Some((i, l)) => {
                    let delta = fitted_lost_motion(directions.iter().map(|d| &d.lost_bins[i][..]));
                    let scale = if axis.is_rotary() {
                        PI / 180.0 * length_mm * 1e3
                    } else {
                        1e3
                    };
                    let lm: Vec<f64> = l
                        .cases
                        .iter()
                        .map(|&c| contribution(c))
                        .fold(vec![0.0; N_BINS], |sum, c| {
                            sum.iter().zip(&c).map(|(s, c)| s + c).collect()
                        });
                    (delta.map(|d| d * scale), Some(peak_to_valley(&lm)))
                }
            };
            AxisReversal {
                axis: axis.to_string(),
                b_um,
                step_um,
                reversals: seen * directions.len(),
            }
        })
        .collect()
}

/// δ = −2 Σ c̄ g / Σ g², g = sgn(v̄) S̄, over the bins of every direction where the axis
/// moves at [`B_SPEED_FRACTION`] of its top speed or more; None when the bar does not see
/// the axis there.
fn fitted_lost_motion<'b>(directions: impl Iterator<Item = &'b [LostBin]>) -> Option<f64> {
    let (mut cg, mut gg) = (0.0, 0.0);
    for bins in directions {
        let mean = |b: &LostBin, x: f64| x / b.n as f64;
        let top = bins
            .iter()
            .filter(|b| b.n > 0)
            .map(|b| mean(b, b.v).abs())
            .fold(0.0, f64::max);
        for b in bins.iter().filter(|b| b.n > 0) {
            let v = mean(b, b.v);
            if top == 0.0 || v.abs() < B_SPEED_FRACTION * top {
                continue;
            }
            let g = v.signum() * b.s;
            cg += mean(b, b.c) * g;
            gg += g * g;
        }
    }
    (gg > 0.0).then(|| -2.0 * cg / gg)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A curve that is a multiple of d takes that multiple as its share; one orthogonal to
    /// it takes none; an offset changes nothing.
    #[test]
    fn shares_are_projections_on_the_full_curve() {
        let d: Vec<f64> = (0..360)
            .map(|i| (i as f64).to_radians().cos() * 3.0)
            .collect();
        let half: Vec<f64> = d.iter().map(|v| 0.5 * v + 7.0).collect();
        let orthogonal: Vec<f64> = (0..360).map(|i| (i as f64).to_radians().sin()).collect();
        assert!((share_of(&half, &d) - 0.5).abs() < 1e-12);
        assert!(share_of(&orthogonal, &d).abs() < 1e-12);
        assert_eq!(share_of(&d, &vec![1.0; 360]), 0.0);
    }

    /// A lag of δ/2 against the motion through a sensitivity S gives back δ.
    #[test]
    fn lost_motion_fit_gives_back_the_lag() {
        let delta = 0.01;
        let bins: Vec<LostBin> = (0..N_BINS)
            .map(|i| {
                let t = (i as f64 + 0.5) * crate::measure::ballbar::BIN_DEG;
                let (s, v) = (t.to_radians().cos() * 1e3, -t.to_radians().sin());
                LostBin {
                    n: 2,
                    c: 2.0 * (-0.5 * delta * v.signum() * s),
                    s,
                    v: 2.0 * v,
                }
            })
            .collect();
        let fitted = fitted_lost_motion([&bins[..]].into_iter()).unwrap();
        assert!((fitted - delta).abs() < 1e-12, "{fitted}");
    }
}
