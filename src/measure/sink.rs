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
use super::ballbar::{BallbarRun, CircleFrame, ThetaTerms};
use super::bar::deviation_mm;
use super::feed::FeedMeter;
use crate::error::Result;
use crate::input::program::{Direction, MeasuredLines};
use crate::kinematics::{Kinematics, RotarySinCos};
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
    /// θ's bin and centring terms ([`ThetaTerms`]); None for a non-finite θ.
    pub terms: Option<ThetaTerms>,
}

/// What the bar reads of a setpoint alone, whatever the drives: the same for every point
/// that runs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CommandedReading {
    /// θ of the commanded tool tip, deg in [0, 360), and `(sin θ, cos θ)`.
    pub theta_deg: f64,
    pub theta_sin_cos: (f64, f64),
    /// θ's bin and centring terms; None for a non-finite θ.
    pub terms: Option<ThetaTerms>,
    /// Sines and cosines of the commanded rotaries: the actual ones are taken near them.
    pub at_command: RotarySinCos,
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
    #[inline]
    pub fn read(&self, s: &Sample) -> BarReading {
        self.read_on(self.needs_full_chain(), s)
    }

    /// [`BarGeometry::read`] with [`BarGeometry::needs_full_chain`] known (a test of every
    /// location error: about a hundred instructions a sample, when asked each time).
    #[inline(always)]
    pub(crate) fn read_on(&self, full_chain: bool, s: &Sample) -> BarReading {
        let c = self.read_commanded(&s.commanded);
        let deviation = |q| self.deviation_on(full_chain, q, &s.commanded, &c);
        c.with_deviations(deviation(&s.actual), deviation(&s.linear))
    }

    /// What the bar reads of the setpoint `commanded`: θ of its tool tip on the circle.
    #[inline]
    pub fn read_commanded(&self, commanded: &AxisVec) -> CommandedReading {
        let kin = &self.kinematics;
        let at_command = kin.rotary_sin_cos(commanded);
        let (theta_deg, theta_sin_cos) = self
            .frame
            .theta_deg_sin_cos(&kin.tip_with(commanded, &at_command));
        CommandedReading {
            theta_deg,
            theta_sin_cos,
            terms: ThetaTerms::new(theta_deg, theta_sin_cos),
            at_command,
        }
    }

    /// Whether the bar's table ball needs the whole chain at the actual positions (location
    /// errors or a general chain): no [`BarGeometry::table_ball_mm`] then.
    #[inline]
    pub fn needs_full_chain(&self) -> bool {
        let kin = &self.kinematics;
        !kin.location_errors.is_zero() || !kin.has_closed_form()
    }

    /// dL at axis positions `q` (actual or the twin's) of a sample whose setpoint
    /// `commanded` reads `c`, um, with [`BarGeometry::needs_full_chain`] known (inlined:
    /// twice a sample, its call cost a sixth of it).
    #[inline(always)]
    pub(super) fn deviation_on(
        &self,
        full_chain: bool,
        q: &AxisVec,
        commanded: &AxisVec,
        c: &CommandedReading,
    ) -> f64 {
        if full_chain {
            return deviation_mm(&self.kinematics, q, &self.pivot_table_mm, self.length_mm) * 1e3;
        }
        self.deviation_to_ball_um(q, &self.table_ball_mm(q, commanded, &c.at_command))
    }

    /// The table ball in the machine frame at axis positions `q` within a following error of
    /// `commanded` (whose rotaries' sines and cosines are `at_command`), mm: its rotation
    /// from theirs ([`Kinematics::rotary_sin_cos_near`], one `sin_cos` per angle and sample
    /// saved). A function of `q`'s rotaries alone for a given setpoint; for a machine without
    /// [`BarGeometry::needs_full_chain`].
    #[inline]
    pub fn table_ball_mm(
        &self,
        q: &AxisVec,
        commanded: &AxisVec,
        at_command: &RotarySinCos,
    ) -> Point3<f64> {
        let kin = &self.kinematics;
        let r = kin.rotation_of(&kin.rotary_sin_cos_near(q, commanded, at_command));
        Point3::from(kin.pivot_mm + r * self.pivot_table_mm.coords)
    }

    /// dL with the tool ball at `q`'s X Y Z and the table ball at `ball` (machine frame), um.
    #[inline]
    pub fn deviation_to_ball_um(&self, q: &AxisVec, ball: &Point3<f64>) -> f64 {
        let tool = Point3::new(q[Axis::X], q[Axis::Y], q[Axis::Z]);
        ((tool - ball).norm() - self.length_mm) * 1e3
    }
}

impl BarReading {
    /// θ's map bin: θ is in [0, 360), so its map bin is its run bin (bin 0 for a
    /// non-finite θ, as the θ map's own binning puts it).
    #[inline]
    pub fn bin(&self) -> usize {
        self.terms.map_or(0, |t| t.bin)
    }
}

impl CommandedReading {
    /// θ's map bin, as [`BarReading::bin`] gives it.
    #[inline]
    pub fn bin(&self) -> usize {
        self.terms.map_or(0, |t| t.bin)
    }

    /// The whole reading, with dL and the linear twin's dL (um).
    #[inline]
    pub fn with_deviations(&self, deviation_um: f64, linear_um: f64) -> BarReading {
        BarReading {
            theta_deg: self.theta_deg,
            deviation_um,
            nonlinear_um: deviation_um - linear_um,
            theta_sin_cos: self.theta_sin_cos,
            terms: self.terms,
        }
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
    /// [`BarGeometry::needs_full_chain`], asked once.
    full_chain: bool,
    measured: Option<MeasuredLines>,
    /// dL against θ.
    pub run: BallbarRun,
    /// dL_nl against θ.
    pub signature: BallbarRun,
    /// The commanded positions and speeds against θ; None where they are not wanted (the
    /// runs after a study's first) or are kept for many bars at once.
    pub maps: Option<CommandMaps>,
    /// The tool's speed along the measured circle over the measured samples.
    pub feed: FeedMeter,
}

/// Commanded axis positions and speeds against θ over a run's measured samples, the first
/// value of each bin: where the bar's sensitivity is evaluated for a reversal site
/// ([`BarGeometry::sensitivity_at`]) and how fast each axis moves there. They depend on the
/// setpoints alone, so points that run the same setpoints can share one.
#[derive(Clone, Debug, Default)]
pub struct CommandMaps {
    /// Commanded axis positions against θ, mm or deg.
    pub commanded: ThetaMap,
    /// Commanded axis speeds against θ, mm/s or deg/s: from the previous sample.
    pub speed: ThetaMap,
    /// The previous sample's time (s) and commanded positions.
    previous: Option<(f64, AxisVec)>,
}

impl CommandMaps {
    /// Takes sample `s`, which the bar reads in θ bin `bin` when it is measured (None: not
    /// measured; it is only the next one's previous sample).
    #[inline]
    pub fn take(&mut self, s: &Sample, bin: Option<usize>) {
        let previous = self.previous.replace((s.time_s, s.commanded));
        let Some(bin) = bin else {
            return;
        };
        if self.commanded.wants_bin(bin) {
            self.commanded.set_bin(bin, s.commanded);
        }
        if let Some((t0, q0)) = previous.filter(|(t0, _)| s.time_s > *t0) {
            if self.speed.wants_bin(bin) {
                self.speed
                    .set_bin(bin, (s.commanded - q0) * (1.0 / (s.time_s - t0)));
            }
        }
    }
}

impl BallbarSink {
    pub fn new(
        geometry: BarGeometry,
        direction: Direction,
        measured: Option<MeasuredLines>,
    ) -> BallbarSink {
        BallbarSink {
            geometry,
            full_chain: geometry.needs_full_chain(),
            measured,
            run: BallbarRun::new(direction),
            signature: BallbarRun::new(direction),
            maps: Some(CommandMaps::default()),
            feed: FeedMeter::default(),
        }
    }

    /// The same sink without [`CommandMaps`]: for the runs after a study's first, whose
    /// maps it does not read (the sites come from the first run's), or for bars whose maps
    /// are kept once for all.
    pub fn without_maps(mut self) -> BallbarSink {
        self.maps = None;
        self
    }
}

impl BallbarSink {
    /// The bar's reading of `s` when it is in the measured revolution (None otherwise),
    /// after taking it into the run: for a trace that records the same reading.
    pub fn take(&mut self, s: &Sample) -> Option<BarReading> {
        let full_chain = self.full_chain;
        self.take_with(s, |geometry, s| geometry.read_on(full_chain, s))
    }

    /// [`BallbarSink::take`] with the reading made by `read` (which must give
    /// [`BarGeometry::read`]'s: a cache of readings shared by points, say).
    #[inline]
    pub fn take_with(
        &mut self,
        s: &Sample,
        read: impl FnOnce(&BarGeometry, &Sample) -> BarReading,
    ) -> Option<BarReading> {
        let r = self.read_with(s, read);
        if let Some(maps) = &mut self.maps {
            maps.take(s, r.as_ref().map(BarReading::bin));
        }
        r
    }

    /// [`BallbarSink::take_with`] for a bar whose θ sums and feed are kept once for the
    /// points of a pass ([`crate::measure::shared::SharedReadings::with_theta_sums`]): only
    /// the deviations go into its runs ([`BallbarRun::add_deviation`]); the rest comes with
    /// [`BallbarSink::take_shared`] once the run is over.
    #[inline]
    pub fn take_deviations_with(
        &mut self,
        s: &Sample,
        read: impl FnOnce(&BarGeometry, &Sample) -> BarReading,
    ) -> Option<BarReading> {
        let r = is_measured(s, self.measured).then(|| read(&self.geometry, s));
        // A non-finite θ: rejected by every bar alike, counted in the shared θ sums.
        if let Some((r, terms)) = r.as_ref().and_then(|r| Some((r, r.terms.as_ref()?))) {
            self.run.add_deviation(terms, r.deviation_um);
            self.signature.add_deviation(terms, r.nonlinear_um);
        }
        if let Some(maps) = &mut self.maps {
            maps.take(s, r.as_ref().map(BarReading::bin));
        }
        r
    }

    /// Completes a bar fed by [`BallbarSink::take_deviations_with`] with the θ sums
    /// `theta` and the feed `feed` kept for it (each of a run that took every measured
    /// sample this bar did, in order, with every deviation 0): the same bits as the bar's
    /// own [`BallbarSink::take`] of the same samples. False when one of its deviations was
    /// not finite: its runs' θ sums are then its own, and the point must run alone.
    pub fn take_shared(&mut self, theta: &BallbarRun, feed: &FeedMeter) -> bool {
        self.feed = *feed;
        self.run.take_theta_sums(theta) && self.signature.take_theta_sums(theta)
    }

    /// [`BallbarSink::take_with`] without the maps.
    #[inline]
    fn read_with(
        &mut self,
        s: &Sample,
        read: impl FnOnce(&BarGeometry, &Sample) -> BarReading,
    ) -> Option<BarReading> {
        if !is_measured(s, self.measured) {
            return None;
        }
        let r = read(&self.geometry, s);
        self.feed.take(s.time_s, r.theta_deg);
        BallbarRun::push_pair_terms(
            &mut self.run,
            &mut self.signature,
            r.terms.as_ref(),
            r.deviation_um,
            r.nonlinear_um,
        );
        Some(r)
    }
}

impl Sink for BallbarSink {
    fn push(&mut self, s: &Sample) -> Result<()> {
        self.take(s);
        Ok(())
    }
}
