//! **measure/cut** — the cut cone: the machined test piece as a CMM will measure it.
//! Inputs: samples (actual or commanded axis positions, the linear twins'), the cone's geometry, the cutter (radius, flute length), each axis's reversal angles.
//! Outputs: the deviation d(θ, z) on a fixed θ × height grid, the least-squares circle per height, the cone angle error and the reversal marks.
//!
//! Each measured sample's axis positions go through the machine's chain, with its location
//! errors (or the nominal chain for `commanded`), to the tool tip and axis in the table
//! frame, then into the cone frame ([`geometry`]); the cutter there removes what it reaches,
//! and the grid keeps the lower envelope ([`envelope`]). The contract is
//! `cutting-test.md`; `docs/cut.md` says where each definition comes from.

pub mod envelope;
pub mod figures;
pub mod geometry;
pub mod least_bound;
pub mod take_up;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::input::program::{ConeTest, Direction, MeasuredLines};
use crate::input::scenario::Scenario;
use crate::kinematics::{Kinematics, LocationErrors, ToolPose};
use crate::measure::is_measured;
use crate::pipeline::{Sample, Sink};
use crate::{Axis, AxisVec};

use envelope::Envelope;
use figures::{HeightFigures, Mark, MarkInputs};
use geometry::{CutGeometry, Row};
use take_up::LostMotion;

/// Default θ step of the grid, deg.
pub const DEFAULT_THETA_STEP_DEG: f64 = 0.1;
/// Default spacing of the grid's heights over the flank contact, mm.
pub const DEFAULT_HEIGHT_STEP_MM: f64 = 2.0;
/// The lowest row sits this far above the tip height, mm: exactly there a point is cut or
/// not by the sign of a sub-micrometre error along the tool axis (the contract).
pub const ABOVE_TIP_MM: f64 = 0.1;

/// How to cut.
#[derive(Clone, Debug, PartialEq)]
pub struct CutOptions {
    /// θ step of the grid, deg (360 / step columns).
    pub theta_step_deg: f64,
    /// Evaluation heights (cone frame z, mm); empty: three spread over the flank contact.
    pub heights_mm: Vec<f64>,
    /// Spacing of the grid's other heights, mm.
    pub height_step_mm: f64,
    /// Cut with the commanded positions through the nominal chain (what the program alone
    /// leaves) instead of the actual ones through the machine's.
    pub commanded: bool,
    /// The run that cuts; None: the scenario's first.
    pub direction: Option<Direction>,
}

impl Default for CutOptions {
    fn default() -> Self {
        CutOptions {
            theta_step_deg: DEFAULT_THETA_STEP_DEG,
            heights_mm: Vec::new(),
            height_step_mm: DEFAULT_HEIGHT_STEP_MM,
            commanded: false,
            direction: None,
        }
    }
}

/// What the cut reports (`cut.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CutFigures {
    pub cutter_radius_mm: f64,
    pub flute_length_mm: f64,
    /// The run that cut, and whether with the commanded positions.
    pub direction: Option<Direction>,
    pub commanded: bool,
    pub theta_step_deg: f64,
    /// `z_tip = (L − R) sin α` and the flutes' end on the frustum, mm.
    pub tip_height_mm: f64,
    pub flute_end_height_mm: f64,
    /// The least-squares circle at each evaluation height.
    pub heights: Vec<HeightFigures>,
    /// The half apex angle's error, urad (null below two heights cut).
    pub cone_angle_error_urad: Option<f64>,
    /// The step across each reversal, at the middle evaluation height.
    pub marks: Vec<Mark>,
    /// Grid points no cutter position reached, of all.
    pub not_cut_points: usize,
    pub grid_points: usize,
    /// Samples that cut.
    pub samples: u64,
}

/// The cut surface of a cone test: a `Measurement` (its trait methods beside the registry,
/// `measure/measurement.rs`).
#[derive(Clone, Debug)]
pub struct CutSurface {
    pub geometry: CutGeometry,
    kinematics: Kinematics,
    /// `kinematics` without its location errors (the commanded cut's chain), made once.
    nominal: Kinematics,
    options: CutOptions,
    /// The grid's rows that are evaluation heights.
    evaluation_rows: Vec<usize>,
    pub envelope: Envelope,
    /// Each axis's reversal angles, deg, for the marks.
    reversals: Vec<(Axis, Vec<f64>)>,
    /// Each axis's lost motion along the cut (actual less linear twin), for the marks.
    lost_motion: LostMotion,
    /// This run cuts; its measured lines; the direction that cut (once a run has).
    cutting: bool,
    measured: Option<MeasuredLines>,
    cut_direction: Option<Direction>,
    samples: u64,
}

impl CutSurface {
    /// The cut of `cone` on a machine of `kinematics` by `scenario`'s tool; bad options
    /// (a step, a height off the flank) are usage errors.
    pub fn new(
        scenario: &Scenario,
        cone: &ConeTest,
        options: CutOptions,
        reversals: Vec<(Axis, Vec<f64>)>,
    ) -> Result<CutSurface> {
        let tool = &scenario.machine.tool;
        let geometry = CutGeometry::new(cone, tool.cutter_diameter_mm / 2.0, tool.flute_length_mm);
        let step = options.theta_step_deg;
        if !(step.is_finite() && step > 0.0 && step <= 10.0)
            || ((360.0 / step) - (360.0 / step).round()).abs() > 1e-9
        {
            return Err(Error::usage(format!(
                "--theta-step-deg {step}: expected a step in (0, 10] deg that divides 360"
            )));
        }
        if !(options.height_step_mm.is_finite() && options.height_step_mm > 0.0) {
            return Err(Error::usage(format!(
                "--height-step-mm {}: expected a spacing > 0 mm",
                options.height_step_mm
            )));
        }
        let (rows, evaluation_rows) = grid_rows(&geometry, &options)?;
        let envelope = Envelope::new(&geometry, step, rows);
        let lost_motion = LostMotion::new(scenario.machine.axes(), envelope.column_count());
        Ok(CutSurface {
            geometry,
            kinematics: scenario.machine.kinematics,
            nominal: scenario
                .machine
                .kinematics
                .with_location_errors(LocationErrors::default()),
            options,
            evaluation_rows,
            envelope,
            reversals,
            lost_motion,
            cutting: false,
            measured: None,
            cut_direction: None,
            samples: 0,
        })
    }

    /// The cutter position of sample `s`: actual positions through the actual chain, or
    /// commanded ones through the nominal chain.
    fn pose(&self, commanded: &AxisVec, actual: &AxisVec) -> ToolPose {
        if self.options.commanded {
            return self.nominal.forward(commanded);
        }
        actual_tool(&self.kinematics, actual)
    }

    /// Cuts with the actual positions through the chain with the geometric `errors` alone
    /// (an error budget's run of one part of the machine's errors).
    pub fn read_through(&mut self, errors: LocationErrors) {
        self.kinematics = self.kinematics.with_location_errors(errors);
        self.nominal = self
            .kinematics
            .with_location_errors(LocationErrors::default());
    }

    /// Cuts with the commanded positions through the nominal chain (`commanded`) or the
    /// actual ones through the machine's: [`CutOptions::commanded`], which nothing else that
    /// [`CutSurface::new`] makes depends on.
    pub fn set_commanded(&mut self, commanded: bool) {
        self.options.commanded = commanded;
    }

    /// Each axis's reversal angles, deg, for the marks.
    pub fn set_reversals(&mut self, reversals: Vec<(Axis, Vec<f64>)>) {
        self.reversals = reversals;
    }

    /// Each axis's reversal angles, deg.
    pub fn reversals(&self) -> &[(Axis, Vec<f64>)] {
        &self.reversals
    }

    /// The options it cuts with.
    pub fn options(&self) -> &CutOptions {
        &self.options
    }

    /// The grid rows that are evaluation heights.
    pub fn evaluation_rows(&self) -> &[usize] {
        &self.evaluation_rows
    }

    /// +1 when the cut ran to higher θ (counter-clockwise), −1 otherwise.
    pub fn sense(&self) -> f64 {
        match self.cut_direction {
            Some(Direction::Cw) => -1.0,
            _ => 1.0,
        }
    }

    /// What a CMM reports of the cut.
    pub fn figures(&self) -> CutFigures {
        let heights: Vec<HeightFigures> = self
            .evaluation_rows
            .iter()
            .map(|&i| figures::height_figures(&self.geometry, &self.envelope, i))
            .collect();
        let angle = figures::cone_angle_error_urad(&self.geometry, &heights);
        let middle = self.evaluation_rows[self.evaluation_rows.len() / 2];
        let not_cut = self
            .envelope
            .values
            .iter()
            .filter(|d| !d.is_finite())
            .count();
        CutFigures {
            cutter_radius_mm: self.geometry.cutter_radius_mm,
            flute_length_mm: self.geometry.flute_length_mm,
            direction: self.cut_direction,
            commanded: self.options.commanded,
            theta_step_deg: self.options.theta_step_deg,
            tip_height_mm: self.geometry.tip_height_mm(),
            flute_end_height_mm: self.geometry.flute_end_height_mm(),
            heights,
            cone_angle_error_urad: angle.is_finite().then_some(angle),
            marks: figures::marks(
                &self.envelope,
                middle,
                &self.reversals,
                self.sense(),
                &MarkInputs {
                    lost_motion: &self.lost_motion,
                    clearance_per_column2_um: self.envelope.clearance_per_column2_um(),
                    lever_mm: self.geometry.length_mm,
                },
            ),
            not_cut_points: not_cut,
            grid_points: self.envelope.values.len(),
            samples: self.samples,
        }
    }
}

/// The grid's heights: one just above the tip, every `height_step_mm` up to the flutes'
/// end (or the frustum's apex), and the evaluation heights, sorted; with the indices of
/// the evaluation heights among them.
fn grid_rows(geometry: &CutGeometry, options: &CutOptions) -> Result<(Vec<Row>, Vec<usize>)> {
    let bottom = geometry.tip_height_mm() + ABOVE_TIP_MM;
    let top = geometry
        .flute_end_height_mm()
        .min(geometry.apex_height_mm())
        - ABOVE_TIP_MM;
    let evaluation: Vec<f64> = if options.heights_mm.is_empty() {
        [0.25, 0.5, 0.75]
            .iter()
            .map(|f| bottom + f * (top - bottom))
            .collect()
    } else {
        options.heights_mm.clone()
    };
    for &z in &evaluation {
        if !(z.is_finite() && (bottom..=top).contains(&z)) {
            return Err(Error::usage(format!(
                "--heights-mm {z}: expected heights (mm above the base circle, along the cone axis) \
                 on the flank contact, from {bottom:.3} (the tip height plus {ABOVE_TIP_MM}) to {top:.3} mm"
            )));
        }
    }
    let mut heights: Vec<f64> = evaluation.clone();
    let steps = ((top - bottom) / options.height_step_mm).floor() as usize;
    heights.extend((0..=steps).map(|k| bottom + k as f64 * options.height_step_mm));
    heights.sort_by(f64::total_cmp);
    heights.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let rows = heights
        .iter()
        .map(|&z| Row {
            z_mm: z,
            radius_mm: geometry.radius_at(z),
        })
        .collect();
    let evaluation_rows = evaluation
        .iter()
        .map(|z| {
            heights
                .iter()
                .position(|h| (h - z).abs() < 1e-9)
                .expect("every evaluation height is a row")
        })
        .collect();
    Ok((rows, evaluation_rows))
}

/// The tool tip and axis in the table frame at actual positions `q`, through the actual
/// chain (location errors), as the ball bar moves its balls (`measure::bar`): a general
/// chain's own actual chain; for a named layout the tool at the machine's (X, Y, Z), its
/// axis as the nominal chain turns it, and the table through `actual_table_pose`.
pub fn actual_tool(kin: &Kinematics, q: &AxisVec) -> ToolPose {
    if let Some(chain) = kin.actual_chain() {
        let (tip, axis) = chain.tool_in_workpiece(q, 0.0);
        return ToolPose { tip, axis };
    }
    let nominal = kin.forward(q);
    if kin.location_errors.is_zero() {
        return nominal;
    }
    let machine_axis = kin.table_rotation(q) * nominal.axis;
    let tip_machine = nalgebra::Point3::new(q[Axis::X], q[Axis::Y], q[Axis::Z]);
    let table = kin.actual_table_pose(q);
    ToolPose {
        tip: table.inverse_transform_point(&tip_machine),
        axis: table.rotation.inverse_transform_vector(&machine_axis),
    }
}

impl CutSurface {
    /// A run in `direction` starts (`measured`: its measured lines). One piece is cut, by
    /// one run: the chosen direction's, or the first run's.
    pub fn start_run(&mut self, direction: Direction, measured: Option<MeasuredLines>) {
        self.cutting = match self.options.direction {
            Some(d) => d == direction,
            None => self.cut_direction.is_none(),
        } && self.cut_direction.is_none();
        if self.cutting {
            self.cut_direction = Some(direction);
        }
        self.measured = measured;
    }

    /// The run that started last has ended: the columns it reaches are computed.
    pub fn end_run(&mut self) {
        if self.cutting {
            self.envelope.end_run(&self.geometry);
            self.cutting = false;
        }
    }
}

impl CutSurface {
    /// Cuts with a measured sample whose commanded, actual and linear-twin positions are all
    /// `q` (an error budget's run): what [`Sink::push`] does with such a sample, without one.
    #[inline]
    pub fn push_positions(&mut self, q: &AxisVec) {
        if !self.cutting {
            return;
        }
        self.cut_with(self.pose(q, q), q, q);
    }

    /// Cuts with the cutter at `pose`, of a sample of `actual` and `linear` positions.
    #[inline(always)]
    fn cut_with(&mut self, pose: ToolPose, actual: &AxisVec, linear: &AxisVec) {
        let line = self.geometry.line_of(&pose.tip, &pose.axis);
        let contact = line.contact_rad();
        // The commanded cut has no lost motion (and its samples no twin to read it from).
        if !self.options.commanded {
            self.lost_motion.record_positions(contact, actual, linear);
        }
        self.envelope.push_at(&self.geometry, line, contact);
        self.samples += 1;
    }
}

impl Sink for CutSurface {
    #[inline]
    fn push(&mut self, s: &Sample) -> Result<()> {
        if !self.cutting || !is_measured(s, self.measured) {
            return Ok(());
        }
        let pose = self.pose(&s.commanded, &s.actual);
        self.cut_with(pose, &s.actual, &s.linear);
        Ok(())
    }
}
