//! The cone-frustum program generator (the paper's post-processor): the cone path on one
//! machine by inverse kinematics, and one G01 block per chord, as canonical moves or text.
//!
//! The geometry (P(θ), the apex, the tool axis) is [`ConeTest`]'s, in `crate::input`.

use std::f64::consts::TAU;
use std::fmt::Write as _;

use crate::input::machine::Machine;
use crate::input::program::{ConePoses, ConeTest, MeasuredLines, NcOptions};
use crate::kinematics::{Branch, Kinematics};
use crate::program::cone_pole::PolePassage;
use crate::program::{Feed, Motion, Move};
use crate::{Axis, AxisVec};

/// The cone path on one machine: axis positions as functions of θ on one IK branch, or,
/// through the pole, on the other branch after it ([`PolePassage`]).
#[derive(Clone, Copy, Debug)]
pub struct ConePath {
    pub cone: ConeTest,
    pub kinematics: Kinematics,
    /// The IK branch at θ = 0.
    pub branch: Branch,
    /// Where the path passes within the pole tolerance of the pole, if it does.
    pub passage: Option<PolePassage>,
    /// `cone`'s constants, for its poses.
    poses: ConePoses,
    /// Travel of A, B and C, deg: (min, max), unbounded for a continuous rotary or one the
    /// machine does not have ([`ConePath::start_within_travel`]).
    rotary_travel_deg: [(f64, f64); 3],
}

/// The rotaries, in the order of [`ConePath`]'s `rotary_travel_deg`.
const ROTARIES: [Axis; 3] = [Axis::A, Axis::B, Axis::C];

/// Grid step of the sweep that [`ConePath::start_within_travel`] follows, rad (0.5 deg).
const SWEEP_STEP_RAD: f64 = 0.5 * std::f64::consts::PI / 180.0;

impl ConePath {
    /// Chooses the IK branch: the spec's (tilt >= 0) unless the machine's tilt limits
    /// exclude it and the other branch fits. Through the pole, the path goes on the other
    /// branch after it when the limits allow (the inner rotary holds), else it keeps its
    /// branch (the inner rotary swings: [`ConePath::pole_swing`]).
    pub fn new(cone: ConeTest, machine: &Machine) -> ConePath {
        let kinematics = machine.kinematics;
        let poses = cone.poses();
        let passage = PolePassage::find(&poses, &kinematics);
        let rotary_travel_deg = ROTARIES.map(|a| {
            let axis = machine.has_axis(a).then(|| machine.axis(a));
            match axis {
                Some(axis) if !axis.continuous => (axis.min, axis.max),
                _ => (f64::NEG_INFINITY, f64::INFINITY),
            }
        });
        let path = ConePath {
            cone,
            kinematics,
            branch: Branch::Primary,
            passage,
            poses,
            rotary_travel_deg,
        };
        // The rotaries the branch must keep within travel: a general chain's all, else the tilt.
        // (A named layout's tilt is a function of the tool axis alone: the same whichever
        // table angle it is unwrapped near.)
        let rotaries = kinematics.travel_bound_rotaries();
        let fits = |path: &ConePath| {
            let mut q = path.start();
            (0..360).all(|k| {
                q = path.axes_after((k as f64).to_radians(), &q);
                rotaries
                    .iter()
                    .all(|&a| machine.axis(a).within_travel(q[a]))
            })
        };
        let with = |branch: Branch, flip: bool| ConePath {
            branch,
            passage: passage.map(|p| PolePassage { flip, ..p }),
            ..path
        };
        let mut candidates = vec![with(Branch::Primary, true), with(Branch::Secondary, true)];
        if passage.is_some() {
            candidates.extend([with(Branch::Primary, false), with(Branch::Secondary, false)]);
        }
        candidates.into_iter().find(fits).unwrap_or(path)
    }

    /// The pole passage the path cannot take on the other branch (the travel limits forbid
    /// it), with the inner rotary's swing there, deg.
    pub fn pole_swing(&self) -> Option<(PolePassage, f64)> {
        let p = self.passage.filter(|p| !p.flip)?;
        let at = |t: f64, b: Branch, prev: &AxisVec| self.on_branch(t, b, prev);
        Some((p, p.swing_deg(&at, self.branch)))
    }

    /// This path, or a refusal naming the pole when it passes it with the inner rotary
    /// swinging ([`ConePath::pole_swing`]): a joint-space block would move the linear axes
    /// in a straight line while the rotary turns, and the tool tip would leave the path.
    pub fn refusing_a_swing(
        self,
        scenario_path: &std::path::Path,
    ) -> crate::error::Result<ConePath> {
        let Some((p, swing)) = self.pole_swing() else {
            return Ok(self);
        };
        Err(crate::error::Error::invalid(
            scenario_path,
            format!(
                "[program.cone] passes the pole of {} (tool along {}, {:.4} deg from it at θ = {:.3} deg) and no IK branch within the travel limits avoids the swing: {} would turn {:.3} deg with the tool standing on the pole",
                p.pole.outer,
                p.pole.inner,
                p.angle_deg,
                p.theta_pole.to_degrees(),
                p.pole.inner,
                swing
            ),
        )
        .with_help(format!(
            "a cone whose tool direction keeps more than the pole tolerance ({} deg) from the pole, or {} travel on both sides of 0, lets the test run",
            self.kinematics.pole_tolerance_deg, p.pole.outer
        )))
    }

    /// Axis positions at `theta_rad`, with C unwrapped nearest `reference_c_deg`.
    pub fn axes_near(&self, theta_rad: f64, reference_c_deg: f64) -> AxisVec {
        if self.passage.is_none() {
            return self.kinematics.inverse(
                &self.poses.pose(theta_rad),
                self.branch,
                reference_c_deg,
            );
        }
        // As `Kinematics::inverse` unwraps: every rotary near the reference.
        let mut previous = AxisVec::ZERO;
        for axis in [Axis::A, Axis::B, Axis::C] {
            previous[axis] = reference_c_deg;
        }
        self.axes_after(theta_rad, &previous)
    }

    /// Axis positions at `theta_rad`, each rotary unwrapped nearest its value in
    /// `previous` ([`Kinematics::inverse_after`]).
    pub fn axes_after(&self, theta_rad: f64, previous: &AxisVec) -> AxisVec {
        let Some(p) = self.passage else {
            return self.on_branch(theta_rad, self.branch, previous);
        };
        let at = |t: f64, b: Branch, prev: &AxisVec| self.on_branch(t, b, prev);
        match p.zone_of(theta_rad) {
            Some(zone) => p.axes_in_zone(
                &self.kinematics,
                &self.poses,
                zone,
                theta_rad,
                &at,
                self.branch,
                previous,
            ),
            None => self.on_branch(theta_rad, p.branch_at(theta_rad, self.branch), previous),
        }
    }

    /// Axis positions at `theta_rad` on `branch`, each rotary unwrapped nearest `previous`.
    fn on_branch(&self, theta_rad: f64, branch: Branch, previous: &AxisVec) -> AxisVec {
        self.kinematics
            .inverse_after(&self.poses.pose(theta_rad), branch, previous)
    }

    /// Axis positions at θ = 0, with C in the spec's atan2 range.
    pub fn start(&self) -> AxisVec {
        if self.passage.is_some() {
            return self.axes_after(0.0, &AxisVec::ZERO);
        }
        self.kinematics
            .inverse_first(&self.poses.pose(0.0), self.branch)
    }

    /// Axis positions at `n + 1` equally spaced θ from `theta0_rad` over `span_rad`, C kept
    /// continuous from the start value.
    pub fn sampled(
        self,
        theta0_rad: f64,
        span_rad: f64,
        n: usize,
    ) -> impl Iterator<Item = (f64, AxisVec)> {
        // Each pose continuous from the one before (on a named layout: its table axis, C or
        // trt-ab's A, from the spec's atan2 range at the start, turned by whole turns where
        // that keeps the sweep within travel).
        let mut previous = self.start_within_travel(theta0_rad, span_rad);
        (0..=n).map(move |k| {
            let theta = theta0_rad + span_rad * k as f64 / n as f64;
            let q = self.axes_after(theta, &previous);
            previous = q;
            (theta, q)
        })
    }

    /// The first pose of the sweep from `theta0_rad` over `span_rad` (either sign): each
    /// rotary from zero as [`ConePath::axes_after`] unwraps it, then turned by the whole
    /// turns `n` (360 deg) that bring the sweep's range `[lo, hi]` within its travel
    /// `[min, max]` where it is not already: `n` from `⌈(min − lo)/360⌉ ..= ⌊(max − hi)/360⌋`,
    /// the one nearest zero. This is what a post does for a rotary of limited travel: C of
    /// ±360 deg turns a clockwise revolution that starts at θ = 0 from 270 deg down to
    /// −90 deg, not from −90 deg to −450 deg. A sweep wider than the travel keeps its start
    /// (the check reports it). The range is followed on a 0.5 deg grid of θ, its ends
    /// included (a rotary's extreme between two grid points exceeds the grid's by at most
    /// its curvature times (0.25 deg)²/2: the margin that a whole turn leaves is far wider).
    fn start_within_travel(&self, theta0_rad: f64, span_rad: f64) -> AxisVec {
        let start = self.axes_after(theta0_rad, &AxisVec::ZERO);
        let bounded: Vec<usize> = (0..ROTARIES.len())
            .filter(|&i| {
                let (min, max) = self.rotary_travel_deg[i];
                min.is_finite() || max.is_finite()
            })
            .collect();
        if bounded.is_empty() {
            return start;
        }
        let steps = ((span_rad.abs() / SWEEP_STEP_RAD).ceil() as usize).max(1);
        let (mut lo, mut hi) = (ROTARIES.map(|a| start[a]), ROTARIES.map(|a| start[a]));
        let mut q = start;
        for k in 1..=steps {
            q = self.axes_after(theta0_rad + span_rad * k as f64 / steps as f64, &q);
            for &i in &bounded {
                lo[i] = lo[i].min(q[ROTARIES[i]]);
                hi[i] = hi[i].max(q[ROTARIES[i]]);
            }
        }
        let mut shifted = start;
        for &i in &bounded {
            let (min, max) = self.rotary_travel_deg[i];
            let least = ((min - lo[i]) / 360.0).ceil();
            let most = ((max - hi[i]) / 360.0).floor();
            if least <= most && !(least..=most).contains(&0.0) {
                let turns = if least > 0.0 { least } else { most };
                shifted[ROTARIES[i]] += 360.0 * turns;
            }
        }
        shifted
    }

    /// dq/dθ at `theta_rad` (mm/rad and deg/rad), by the fourth-order central difference
    /// `q' = (q(θ-2h) - 8q(θ-h) + 8q(θ+h) - q(θ+2h)) / 12h` with h = 1e-3 rad on the exact
    /// path (truncation ~h⁴q⁽⁵⁾/30 ≈ 1e-11, far below the 0.01 deg the analysis needs).
    pub fn derivative(&self, theta_rad: f64) -> AxisVec {
        const H: f64 = 1e-3;
        let q0 = self.axes_after(theta_rad, &AxisVec::ZERO);
        let q = |dt: f64| self.axes_after(theta_rad + dt, &q0);
        (q(-2.0 * H) - q(-H) * 8.0 + q(H) * 8.0 - q(2.0 * H)) * (1.0 / (12.0 * H))
    }
}

/// One generated block: its canonical move, and the θ it reaches, rad.
#[derive(Clone, Debug, PartialEq)]
pub struct ConeBlock {
    pub theta_rad: f64,
    pub mv: Move,
}

/// The cone-frustum program (the paper's post-processor), as canonical moves.
///
/// Each G01 block moves the tool ball along one chord of the circle. Without TCP the F word
/// is the mixed-unit rate `sqrt(dX² + dY² + dZ² + dA² + dC²) / dt` with `dt = chord / F`;
/// with G93 it is `1 / dt`; with TCP (G43.4) X Y Z are the tool tip in the table frame and F
/// is the tip feed. Line numbers are those of the text [`write_program`] writes, so a
/// generated run and the same program read from its file report the same lines.
#[derive(Clone, Debug)]
pub struct ConeProgram {
    path: ConePath,
    options: NcOptions,
    /// Comment and modal lines before the first move.
    header: Vec<String>,
    /// θ step per block, rad (negative when clockwise).
    step_rad: f64,
    theta0_rad: f64,
    /// G01 blocks, lead-in and lead-out included.
    total: usize,
    measured: MeasuredLines,
}

impl ConeProgram {
    pub fn new(path: &ConePath, machine_name: &str, options: &NcOptions) -> ConeProgram {
        let cone = &path.cone;
        let n = options.segments;
        let step_rad = TAU / n as f64 * if options.clockwise { -1.0 } else { 1.0 };
        let lead_blocks = (options.lead_deg.to_radians() / step_rad.abs()).ceil() as usize;
        let feed_kind = if options.tcp {
            "TOOL-TIP FEED WITH G43.4"
        } else if options.inverse_time {
            "INVERSE TIME G93"
        } else {
            "MIXED-UNIT F PER BLOCK"
        };
        let mut header = vec![
            "%".to_string(),
            "O1001 (MTSIM CONE-FRUSTUM TEST, NAS 979 / ISO 10791-7)".to_string(),
            format!("(MACHINE: {})", sanitize(machine_name)),
            format!(
                "(HALF APEX ANGLE {:.4} DEG, INCLINATION {:.4} DEG)",
                cone.half_apex_deg, cone.inclination_deg
            ),
            format!(
                "(BASE CENTRE XT {:.4} YT {:.4} ZT {:.4} MM, BALL BAR LENGTH {:.4} MM)",
                cone.center_mm.x, cone.center_mm.y, cone.center_mm.z, cone.ballbar_length_mm
            ),
            format!(
                "(CIRCLE RADIUS {:.4} MM, DIAMETER {:.4} MM, HEIGHT {:.4} MM)",
                cone.radius_mm(),
                2.0 * cone.radius_mm(),
                cone.height_mm()
            ),
            format!(
                "(SEGMENTS {n}, FEED {:.1} MM/MIN, {feed_kind}, {}, LEAD {:.1} DEG, {:?} BRANCH)",
                options.feed_mm_min,
                if options.clockwise { "CW" } else { "CCW" },
                options.lead_deg,
                path.branch
            ),
            if options.inverse_time && !options.tcp {
                "G21 G90 G93 G17"
            } else {
                "G21 G90 G94 G17"
            }
            .to_string(),
        ];
        if options.tcp {
            // Switch TCP on, then position tip and rotary axes in one rapid move.
            header.push("G43.4 H1".to_string());
        }
        // The G00 block is the line after the header; G01 block j follows it at +1+j.
        let rapid_line = header.len() + 1;
        ConeProgram {
            path: *path,
            options: *options,
            header,
            step_rad,
            theta0_rad: -(lead_blocks as f64) * step_rad,
            total: n + 2 * lead_blocks,
            measured: MeasuredLines {
                first: rapid_line + 1 + lead_blocks,
                last: rapid_line + lead_blocks + n,
            },
        }
    }

    /// The lines of the measured revolution.
    pub fn measured(&self) -> MeasuredLines {
        self.measured
    }

    /// The blocks, streamed: a G00 to the start, then one G01 per chord.
    pub fn blocks(&self) -> impl Iterator<Item = ConeBlock> {
        let path = self.path;
        let cone = path.cone;
        let options = self.options;
        let axes = path.kinematics.layout.axes();
        let rapid_line = self.header.len() + 1;
        let chord = 2.0 * cone.radius_mm() * (self.step_rad.abs() / 2.0).sin();
        let dt_min = chord / options.feed_mm_min;
        let feed_of: fn(f64) -> Feed = if options.inverse_time && !options.tcp {
            Feed::InverseTime
        } else {
            Feed::PerMinute
        };
        // The program's words: X Y Z are the tool tip under TCP (a W quill keeps its own value),
        // else the machine axes.
        // The cone's poses once, not per block; the tip only when the words are the tip.
        let poses = cone.poses();
        let words = move |q: &AxisVec, theta: f64| {
            let mut end = AxisVec::ZERO;
            for &axis in axes {
                end[axis] = q[axis];
            }
            if options.tcp {
                let tip = poses.point(theta);
                for &axis in axes.iter().filter(|a| a.index() < 3) {
                    end[axis] = tip[axis.index()];
                }
            }
            end
        };
        let (mut previous, mut q_prev) = (AxisVec::ZERO, AxisVec::ZERO);
        path.sampled(
            self.theta0_rad,
            self.step_rad * self.total as f64,
            self.total,
        )
        .enumerate()
        .map(move |(k, (theta, q))| {
            let end = words(&q, theta);
            let (motion, feed) = if k == 0 {
                (Motion::Rapid, Feed::None)
            } else {
                let f = if options.tcp {
                    options.feed_mm_min
                } else if options.inverse_time {
                    1.0 / dt_min
                } else {
                    (q - q_prev).mixed_norm() / dt_min
                };
                (Motion::Linear, feed_of(f))
            };
            let mv = Move {
                line: rapid_line + k,
                motion,
                start: previous,
                end,
                feed,
                tcp: options.tcp,
                ..Move::default()
            };
            previous = end;
            q_prev = q;
            ConeBlock {
                theta_rad: theta,
                mv,
            }
        })
    }

    /// The canonical moves alone.
    pub fn moves(&self) -> impl Iterator<Item = Move> {
        self.blocks().map(|b| b.mv)
    }
}

/// Writes the cone-frustum NC program as text and tells which lines hold the measured
/// revolution: the [`ConeProgram`]'s moves, each word rounded to 4 decimals (0.1 um,
/// 0.0001 deg) and F to 3.
pub fn write_program(
    path: &ConePath,
    machine_name: &str,
    options: &NcOptions,
) -> (String, MeasuredLines) {
    let program = ConeProgram::new(path, machine_name, options);
    let axes = path.kinematics.layout.axes();
    let mut out = String::new();
    for line in &program.header {
        out.push_str(line);
        out.push('\n');
    }
    for block in program.blocks() {
        let mv = &block.mv;
        out.push_str(if mv.motion == Motion::Rapid {
            "G00"
        } else {
            "G01"
        });
        for &axis in axes {
            let _ = write!(out, " {}{}", axis, fmt_num(mv.end[axis]));
        }
        if let Some(f) = mv.feed.rate() {
            let _ = write!(out, " F{f:.3} (THETA {:.3})", block.theta_rad.to_degrees());
        }
        out.push('\n');
    }
    if options.tcp {
        out.push_str("G49\n");
    }
    out.push_str("M30\n%\n");
    (out, program.measured())
}

/// A number as an NC word value: 4 decimals (0.1 um, 0.0001 deg), no "-0".
fn fmt_num(v: f64) -> String {
    let s = format!("{v:.4}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        "0.0000".to_string()
    } else {
        s
    }
}

/// Parentheses end an NC comment, so they cannot appear inside one.
fn sanitize(text: &str) -> String {
    text.replace(['(', ')'], " ").to_uppercase()
}

/// An angle in deg brought into [0, 360); values within 1e-9 deg below 360 become 0.
pub fn normalize_deg(angle_deg: f64) -> f64 {
    let a = angle_deg.rem_euclid(360.0);
    if a > 360.0 - 1e-9 {
        0.0
    } else {
        a
    }
}
