//! Interpolator with look-ahead feed planning: blocks in, setpoints every interpolation
//! period out.
//!
//! # Path and path speed
//!
//! Every motion block is a path `q(u)`, `u ∈ [0, 1]`, in axis space (mm and deg), walked at
//! a path speed `v = ds/dt` where `s = u L` and `L` is the block's path length:
//!
//! - **G01 / G00 in joint space**: `q(u) = q0 + u d`, `L = |d|` with deg counted as mm
//!   (the mixed-unit length of a controller without tool-centre-point control,
//!   [`AxisVec::mixed_norm`]). The programmed feed F (mm/min) is the rate of `s`, so the block
//!   time at F is `L / F`. Under LinuxCNC's rules (`[control] max_feed_override`) a G01 that
//!   moves X Y Z has `L = |d_xyz|`: F is the X Y Z speed, the other axes follow.
//! - **G93** (inverse time): the block time is `1 / F` min, i.e. a path speed `F L`.
//! - **G00**: no F; the path speed is capped by the axis velocity limits only, so the axis
//!   with the largest `|d_i| / vmax_i` runs at its `vmax_i` and all axes arrive together
//!   (`T = max_i |d_i| / vmax_i` at cruise).
//! - **G02/G03**: the plane axes follow the circle (a spiral if the start and end radii
//!   differ by rounding), the third linear axis and any rotary axes move linearly in `u`
//!   (helix). `L = sqrt(arc² + Δ²)` where Δ collects the other axes' travel; F is the rate of
//!   `s` (for a planar arc, the tangential feed).
//! - **TCP** (`block.tcp` from G43.4, or [`InterpolationOptions::force_tcp`]): the block's X Y
//!   Z are the tool tip `p` in the table frame. `p(u)` is the straight line (or the arc) in the
//!   table frame, the rotary axes move linearly in `u`, and every period the machine axes are
//!   `xyz = Kinematics::tcp_to_machine(q_rotary(u), p(u), L_tool)` (the tool length offset
//!   along the tool axis). `L` is the tool-tip path length,
//!   so F is the tool-tip feed relative to the table; for a pure rotary move (`|Δp| = 0`) the
//!   mixed rule over the rotary axes is used instead.
//!
//! # Limits along the path
//!
//! With `q' = dq/ds`, `q'' = d²q/ds²`, `q''' = d³q/ds³`, the axis velocity, acceleration and
//! jerk are
//!
//! ```text
//! q̇ = q' v,   q̈ = q' a + q'' v²,   q⃛ = q' j + 3 q'' v a + q''' v³
//! ```
//!
//! (a, j: path acceleration and jerk). For a straight block (`q'' = 0`) the path limits are
//! exact: `v ≤ min_i vmax_i/|q'_i|`, `a ≤ min_i amax_i/|q'_i|`, `j ≤ min_i jmax_i/|q'_i|`.
//! For a curved block (arc, or TCP with rotary motion) half of each axis's acceleration budget
//! goes to the path acceleration and half to the centripetal term, and the jerk budget is split
//! in three: `a ≤ ½ amax/|q'|`, `v² |q''| ≤ ½ amax`, `j ≤ ⅓ jmax/|q'|`, `v³ |q'''| ≤ ⅓ jmax`,
//! `3 |q''| v a ≤ ⅓ jmax`. `|q'|`, `|q''|`, `|q'''|` of curved blocks are the maxima of
//! central finite differences sampled at 17 points along the block, raised by the next
//! derivative times half the sample spacing (a bound between the samples). The cruise speed `V` of a
//! block is the programmed speed reduced by these caps, and by nothing else.
//!
//! # Junctions
//!
//! Path speed may jump at a block boundary: the path speed entering block k+1 is
//! `ρ` times the speed leaving block k with `ρ = V_{k+1}/V_k`, so a chain of blocks whose
//! F words differ runs each block at its own F. The axis velocity jumps by
//! `μ |ρ q'_{k+1}(0) - q'_k(1)|` (μ: exit speed of block k); this jump is limited to
//! `corner_acceleration_share · amax_i · period` per axis (default share 1: the step is taken
//! at the axis's full acceleration within one period; half of that next to an arc or a curved
//! TCP block, whose centripetal term may use the other half). That bounds `μ` at every
//! corner. Dwells force a stop on both sides.
//!
//! # Speed profile in a block (jerk-limited S-curve)
//!
//! Inside a block the path speed goes from the entry speed `vs` up (or down) to a peak `vp`,
//! cruises, and goes to the exit speed `ve`; each speed change is the jerk-limited S-curve
//! with zero acceleration at both ends (`a(t)` a trapezoid or triangle):
//!
//! ```text
//! Δv ≤ a²/j:  T(Δv) = 2 sqrt(Δv/j)          (jerk phases only, peak acceleration sqrt(j Δv))
//! Δv > a²/j:  T(Δv) = Δv/a + a/j            (jerk, constant a for Δv/a - a/j, jerk)
//! distance D(v0, v1) = (v0 + v1)/2 · T(|v1 - v0|)   (the profile is point-symmetric)
//! ```
//!
//! `vp = V` if `D(vs, V) + D(V, ve) ≤ L`, else `vp` solves `D(vs, vp) + D(vp, ve) = L`
//! (the left side grows with vp: false position, then bisection to the last float). From
//! rest to rest with `V` reached this gives the textbook double-S time `T = L/V + V/a + a/j`.
//!
//! # Look-ahead
//!
//! The planner keeps a window of `lookahead_blocks` blocks that have not started. The last
//! block of the window must end at rest, so the machine can always stop. A backward pass
//! gives each block its largest entry speed from which it can still reach the next block's
//! entry; a forward step at the start of each block picks the largest feasible exit. The
//! feasibility test uses the monotone bound `D̄(v0, v1) = max(v0, v1) T(|v1 - v0|) ≥ D`
//! (the true `D` is not monotone in the end speed: slowing from v to v/3 takes longer than
//! stopping), so any exit between what the backward pass assumed and what the window now
//! allows is reachable. Backward passes run once per `lookahead_blocks / 2` new blocks; each
//! stops at the first older block whose entry limit rises by less than a relative 1e-12, and
//! `reach` is in closed form, so planning is amortised O(1) per block even when the stopping
//! distance spans the whole window (fine segments). Memory is bounded by the window.
//!
//! Corner blending: under G64 the corner between two straight blocks may be replaced by an
//! arc ([`blend`], LinuxCNC's rules, docs/interpolation.md); under LinuxCNC's rules two
//! straight moves where either moves a rotary axis overlap instead ([`overlap`]: the next
//! starts while the first slows down, their velocities add). Not modelled: blending of other
//! corners (they are passed at a limited speed, with a velocity step of bounded size in one
//! period; the jerk at that step is not limited), acceleration
//! carried across block boundaries (each block's speed changes start and end at zero path
//! acceleration), travel limits (checked downstream).

use std::collections::VecDeque;
use std::path::PathBuf;

use crate::error::{Error, Result};
use crate::input::machine::{ControlSection, Machine};
use crate::kinematics::Kinematics;
use crate::motion::blend::{self, Bend};
pub use crate::motion::feed_held::{FeedLimit, LimitKind};
use crate::motion::feed_held::{FeedReduction, FeedReductions};
use crate::motion::profile::{reach, Profile};
use crate::program::{Feed, Motion, Move, PathControl};
use crate::{Axis, AxisVec};
use libm::cbrt;

#[path = "arc_corner.rs"]
mod arc_corner;
#[path = "arc_path.rs"]
mod arc_path;
#[path = "lookahead.rs"]
mod lookahead;
#[path = "overlap.rs"]
pub mod overlap;

use arc_path::ArcGeometry;

/// One commanded position of all axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setpoint {
    /// Time since the first setpoint, s. Exactly `n · period`.
    pub time_s: f64,
    /// Commanded axis positions, machine coordinates, mm and deg.
    pub q: AxisVec,
    /// Source line of the block being executed.
    pub line: usize,
    /// 0-based position of that block in the input stream.
    pub block_index: u64,
}

/// Settings of the interpolator.
#[derive(Clone, Debug)]
pub struct InterpolationOptions {
    /// Treat every G01/G02/G03 block as tool-centre-point controlled (as if G43.4 were on).
    pub force_tcp: bool,
    /// Blocks planned ahead of the one executing (at least 1). The machine must be able to
    /// stop within this many blocks, so long, fast moves split into tiny blocks need more.
    /// Default 256; [`InterpolationOptions::for_machine`] takes the machine's
    /// `[control] lookahead_blocks`.
    pub lookahead_blocks: usize,
    /// Allowed per-axis velocity step at a block junction, as a fraction of
    /// `max_acceleration × period` (> 0; default 1: the step takes the full acceleration
    /// for one period). Halved next to a curved block, whose centripetal term needs the rest.
    pub corner_acceleration_share: f64,
    /// Name of the program, used in error messages.
    pub program_path: PathBuf,
    /// Keep a [`FeedLimit`] for every feed block that runs slower than its F word
    /// ([`Interpolator::take_feed_limits`]); off by default (memory would grow with them).
    pub record_feed_limits: bool,
}

impl InterpolationOptions {
    /// The defaults, with the look-ahead depth of `machine`'s control where it gives one.
    pub fn for_machine(machine: &Machine) -> InterpolationOptions {
        let default = InterpolationOptions::default();
        InterpolationOptions {
            lookahead_blocks: machine
                .control
                .lookahead_blocks
                .unwrap_or(default.lookahead_blocks),
            ..default
        }
    }
}

impl Default for InterpolationOptions {
    fn default() -> Self {
        InterpolationOptions {
            force_tcp: false,
            lookahead_blocks: 256,
            corner_acceleration_share: 1.0,
            program_path: PathBuf::from("program"),
            record_feed_limits: false,
        }
    }
}

/// Limits of one axis in per-second units: units/s, units/s², units/s³.
#[derive(Clone, Copy, Debug)]
struct AxisLimits {
    velocity: f64,
    acceleration: f64,
    jerk: f64,
}

/// The geometric path of a block, `q(u)` for `u ∈ [0, 1]` (formulas extend beyond).
#[derive(Clone, Copy, Debug)]
struct BlockPath {
    start: AxisVec,
    delta: AxisVec,
    arc: Option<ArcGeometry>,
    /// A corner's blend arc ([`blend`]): `q(u) = start + bend.offset(u)` (`delta` is zero).
    bend: Option<Bend>,
    /// X Y Z of `start + u delta` (or of the arc) are the tool tip in the table frame of the
    /// interpolator's kinematics (passed to the methods that need it: a block is copied
    /// several times on its way and holds no copy of them).
    tcp: bool,
    /// Tool length offset under TCP, mm: included in Z, applied along the tool axis
    /// ([`Kinematics::tcp_to_machine`]).
    tool_length_mm: f64,
}

impl BlockPath {
    fn at(&self, u: f64, kinematics: &Kinematics) -> AxisVec {
        let mut q = AxisVec(std::array::from_fn(|i| {
            self.start.0[i] + self.delta.0[i] * u
        }));
        if let Some(arc) = &self.arc {
            let (sin, cos) = (arc.theta0 + arc.sweep * u).sin_cos();
            let r = arc.r0 + arc.dr * u;
            q.0[arc.i0] = arc.c0 + r * cos;
            q.0[arc.i1] = arc.c1 + r * sin;
        }
        if let Some(bend) = &self.bend {
            q = q + bend.offset(u);
        }
        if self.tcp {
            return kinematics.tcp_axes_per_sample(&q, self.tool_length_mm);
        }
        q
    }

    /// True when `q(u)` is a straight line in axis space.
    fn is_straight(&self) -> bool {
        self.arc.is_none()
            && self.bend.is_none()
            && (!self.tcp || (3..6).all(|i| self.delta.0[i] == 0.0))
    }

    /// `dq/ds` at `u` for a block of length `length` (central difference, exact for lines).
    fn tangent(&self, u: f64, length: f64, kinematics: &Kinematics) -> AxisVec {
        if self.is_straight() {
            if self.arc.is_none() && !self.tcp {
                // `at(1) - at(0)` written out (`start + delta · 1 - (start + delta · 0)`):
                // the same bits without two path evaluations.
                let d = AxisVec(std::array::from_fn(|i| {
                    (self.start.0[i] + self.delta.0[i]) - self.start.0[i]
                }));
                return d * (1.0 / length);
            }
            return (self.at(1.0, kinematics) - self.at(0.0, kinematics)) * (1.0 / length);
        }
        let h = 1e-5;
        (self.at(u + h, kinematics) - self.at(u - h, kinematics)) * (1.0 / (2.0 * h * length))
    }

    /// `dq/ds` at the start and at the end of the block (the same for a straight one).
    fn end_tangents(&self, length: f64, kinematics: &Kinematics) -> (AxisVec, AxisVec) {
        if self.is_straight() {
            let t = self.tangent(0.0, length, kinematics);
            return (t, t);
        }
        (
            self.tangent(0.0, length, kinematics),
            self.tangent(1.0, length, kinematics),
        )
    }
}

/// Intervals at which the derivatives of a curved block are sampled.
const SAMPLES: usize = 16;

/// Blocks appended between two backward passes: half the look-ahead (at least 1).
fn pass_batch(options: &InterpolationOptions) -> usize {
    (options.lookahead_blocks / 2).max(1)
}

/// A block ready to run, with its limits and look-ahead state. Speeds in path units/s.
#[derive(Clone, Copy, Debug)]
struct Planned {
    line: usize,
    index: u64,
    path: BlockPath,
    /// Path length, mm (deg counted as mm for mixed moves); 0 for a dwell.
    length: f64,
    dwell_s: f64,
    /// How the block joins the next (G61, G61.1, G64 P Q).
    path_control: PathControl,
    /// Programmed path speed, path units/s (infinite for G00), and the axis limit that holds
    /// the cruise speed below it.
    programmed: f64,
    limited_by: Option<(Axis, LimitKind)>,
    /// Cruise speed, path acceleration, path jerk limits.
    cap: f64,
    accel: f64,
    jerk: f64,
    /// Largest entry speed the junction allows, and entry / previous exit speed ratio.
    entry_cap: f64,
    rho: f64,
    /// Largest entry speed from which the rest of the window is feasible.
    entry_max: f64,
    /// Starts in an overlap with the block before ([`overlap`]): the path length left on that
    /// one when this may start by the tolerance.
    overlap: Option<f64>,
    /// Acceleration and jerk limits halved for an overlap ([`overlap`]), once.
    halved: bool,
    /// Appended and not yet passed: `entry_max` stands for [`Planned::rest_entry`], which
    /// the backward pass computes only where it can matter ([`Planned::entry_limit`]).
    rest_entry_due: bool,
}

/// A block's speed limits from the axis limits (see [`Planned`]), path units/s, /s², /s³.
#[derive(Clone, Copy, Debug)]
struct Limits {
    programmed: f64,
    by: Option<(Axis, LimitKind)>,
    cap: f64,
    accel: f64,
    jerk: f64,
}

impl Limits {
    /// A dwell's: no speed.
    const NONE: Limits = Limits {
        programmed: f64::INFINITY,
        by: None,
        cap: 0.0,
        accel: 0.0,
        jerk: 0.0,
    };
}

/// The end of the last planned block, for the next junction.
#[derive(Clone, Copy, Debug)]
struct JunctionEnd {
    tangent: AxisVec,
    cap: f64,
    dwell: bool,
    curved: bool,
    /// A blend arc held below its programmed speed (by its centripetal term): it joins both
    /// its neighbours tangentially, at one path speed.
    slow_bend: bool,
    /// The block's path-control mode: how it joins the next.
    path: PathControl,
    /// A rapid (or a blend between rapids): unbounded programmed speed.
    rapid: bool,
}

/// The last block planned, held back until the next one arrives so that the corner between
/// them can be blended ([`Interpolator::hold`]): the block, its end tangents, and the half of
/// its planned length that a blend at its end may take.
#[derive(Clone, Copy, Debug)]
struct Held {
    planned: Planned,
    start: AxisVec,
    end: AxisVec,
    half: f64,
}

#[derive(Clone, Copy, Debug)]
struct Active {
    planned: Planned,
    profile: Profile,
    /// Start time of the block, s.
    t0: f64,
    /// When the next block starts, s after `t0`: the profile's end, or earlier when the next
    /// overlaps this one ([`overlap`]).
    handover: f64,
}

impl Active {
    /// The setpoint at time `t` (s) if the block is still running then: the path at
    /// `u = s(t - t₀) / L`, clamped to `[0, 1]` (0 for a block of no length).
    #[inline(always)]
    fn setpoint_at(&self, t: f64, kinematics: &Kinematics) -> Option<Setpoint> {
        if !(t < self.t0 + self.handover) {
            return None;
        }
        let p = &self.planned;
        let u = if p.length > 0.0 {
            (self.profile.position(t - self.t0) / p.length).clamp(0.0, 1.0)
        } else {
            0.0
        };
        Some(Setpoint {
            time_s: t,
            q: p.path.at(u, kinematics),
            line: p.line,
            block_index: p.index,
        })
    }
}

/// Turns blocks into setpoints every interpolation period; see the module documentation.
///
/// Yields `Err` once (then ends) when a block cannot be run; errors in the first
/// `lookahead_blocks` blocks are already returned by [`Interpolator::new`].
pub struct Interpolator<I: Iterator<Item = Result<Move>>> {
    blocks: I,
    /// Blocks read from `blocks`, [`pass_batch`] at a time (see
    /// [`Interpolator::read_more`]), planned up to `read_at` (each read where it is stored);
    /// `blocks_done` once `blocks` has ended or failed.
    read_ahead: Vec<Result<Move>>,
    read_at: usize,
    blocks_done: bool,
    input_done: bool,
    pending_error: Option<Error>,
    limits: [Option<AxisLimits>; 9],
    kinematics: Kinematics,
    period_s: f64,
    /// The machine's `[control]`: rapids' acceleration share, default path tolerance.
    control: ControlSection,
    options: InterpolationOptions,
    window: VecDeque<Planned>,
    /// Blocks appended since the last backward pass.
    unpassed: usize,
    feed_limits: Option<Vec<FeedLimit>>,
    /// Every block held below its F word, summarised (always kept: bounded memory).
    reductions: FeedReductions,
    last_end: Option<JunctionEnd>,
    /// The held block ([`Interpolator::hold`]), and the place the next block is planned in
    /// (`None` only while it is planned): boxed so that the next one takes the held one's
    /// place by swapping the two, not by copying hundreds of bytes.
    held: Box<Option<Held>>,
    incoming: Option<Box<Option<Held>>>,
    next_index: u64,
    active: Option<Active>,
    /// The block before the active one while it still runs beside it ([`overlap`]), and the
    /// next block's profile when it will overlap the active one (with its exit speed).
    trailing: Option<Active>,
    queued: Option<(Profile, f64)>,
    /// Exit speed committed for the active block.
    last_exit: f64,
    step: u64,
    done: bool,
}

impl<I: Iterator<Item = Result<Move>>> Interpolator<I> {
    /// Plans the first `options.lookahead_blocks` blocks of `blocks` for `machine`.
    pub fn new(blocks: I, machine: &Machine, options: InterpolationOptions) -> Result<Self> {
        if options.lookahead_blocks == 0 {
            return Err(Error::usage("lookahead_blocks must be at least 1"));
        }
        let share = options.corner_acceleration_share;
        if !(share.is_finite() && share > 0.0) {
            return Err(Error::usage(format!(
                "corner_acceleration_share must be a positive number, got {share}"
            )));
        }
        let mut limits = [None; 9];
        for &axis in machine.axes() {
            let c = machine.axis(axis);
            limits[axis.index()] = Some(AxisLimits {
                velocity: c.max_velocity / 60.0,
                acceleration: c.max_acceleration,
                jerk: c.max_jerk,
            });
        }
        let mut interpolator = Interpolator {
            blocks,
            read_ahead: Vec::with_capacity(pass_batch(&options)),
            read_at: 0,
            blocks_done: false,
            input_done: false,
            pending_error: None,
            limits,
            kinematics: machine.kinematics,
            period_s: machine.interpolation_period_s,
            control: machine.control,
            window: VecDeque::with_capacity(options.lookahead_blocks + pass_batch(&options) + 1),
            unpassed: 0,
            feed_limits: options.record_feed_limits.then(Vec::new),
            reductions: FeedReductions::default(),
            options,
            last_end: None,
            held: Box::new(None),
            incoming: Some(Box::new(None)),
            next_index: 0,
            active: None,
            trailing: None,
            queued: None,
            last_exit: 0.0,
            step: 0,
            done: false,
        };
        interpolator.fill();
        match interpolator.pending_error.take() {
            Some(e) => Err(e),
            None => Ok(interpolator),
        }
    }

    fn block_error(&self, line: usize, message: impl std::fmt::Display) -> Error {
        Error::invalid(
            &self.options.program_path,
            format!("line {line}: {message}"),
        )
    }

    /// Reads blocks until the window holds `lookahead_blocks + 1` of them.
    /// Backward passes run once per [`pass_batch`] new blocks (and when the input ends), so
    /// the window holds up to `lookahead_blocks + pass_batch` blocks and at least
    /// `lookahead_blocks + 1` planned ones when a block starts.
    fn fill(&mut self) {
        let batch = pass_batch(&self.options);
        while !self.input_done && self.window.len() <= self.options.lookahead_blocks + batch - 1 {
            // The block is planned where it was read, into the box it is held in (each copy
            // of one costs a few dozen instructions, and a fine segment's whole planning a few
            // thousand).
            self.read_more(batch);
            let at = self.read_at;
            self.read_at += 1;
            match self.read_ahead.get(at) {
                None => {
                    self.input_done = true;
                    continue;
                }
                Some(Err(_)) => {
                    let failed = std::mem::replace(&mut self.read_ahead[at], Ok(Move::default()));
                    self.pending_error = failed.err();
                    self.input_done = true;
                    continue;
                }
                Some(Ok(_)) => {}
            }
            let Some(Ok(block)) = self.read_ahead.get(at) else {
                continue;
            };
            let index = self.next_index;
            self.next_index += 1;
            let mut next = self.incoming.take().unwrap_or_default();
            match self.plan(block, index, &mut next) {
                Err(e) => {
                    self.pending_error = Some(e);
                    self.input_done = true;
                }
                Ok(()) => {
                    if let Some(held) = next.as_ref() {
                        self.record(&held.planned);
                        next = self.hold_next(next);
                    }
                }
            }
            self.incoming = Some(next);
        }
        if self.input_done {
            if let Some(last) = self.held.take() {
                self.push_last(last);
            }
        }
        if self.unpassed > 0 && (self.input_done || self.unpassed >= batch) {
            self.backward_pass();
        }
    }

    /// Reads the next `batch` blocks of the program once those read are all planned. With
    /// short blocks one is needed per interpolation period or so, between the drives'
    /// samples; read one at a time, the reader's code (interpreter, validation) found the
    /// instruction cache cold on every block. Reading stops at the first error, where the
    /// interpolator stops. Only when blocks are read changes (at most `batch` blocks early),
    /// not what is planned: the window and its backward passes are the same.
    fn read_more(&mut self, batch: usize) {
        if self.read_at < self.read_ahead.len() || self.blocks_done {
            return;
        }
        self.read_ahead.clear();
        self.read_at = 0;
        for _ in 0..batch {
            let Some(block) = self.blocks.next() else {
                self.blocks_done = true;
                break;
            };
            let failed = block.is_err();
            self.read_ahead.push(block);
            if failed {
                self.blocks_done = true;
                break;
            }
        }
    }

    /// Notes a feed block held below its F word (when recording).
    fn record(&mut self, p: &Planned) {
        if let (Some((axis, limit)), true) = (p.limited_by, p.programmed.is_finite()) {
            let held = FeedLimit {
                line: p.line,
                block_index: p.index,
                axis,
                limit,
                programmed_per_min: p.programmed * 60.0,
                planned_per_min: p.cap * 60.0,
            };
            self.reductions.note(&held);
            if let Some(log) = self.feed_limits.as_mut() {
                log.push(held);
            }
        }
    }

    /// The feed blocks planned so far below their F word, per axis and limit.
    pub fn feed_reductions(&self) -> Vec<FeedReduction> {
        self.reductions.list()
    }

    /// The feed limits noted since the last call, in block order (empty unless
    /// [`InterpolationOptions::record_feed_limits`]). Blocks are planned up to
    /// `lookahead_blocks` ahead of the setpoints.
    pub fn take_feed_limits(&mut self) -> Vec<FeedLimit> {
        self.feed_limits
            .as_mut()
            .map(std::mem::take)
            .unwrap_or_default()
    }

    /// Plans `block`, given by reference beside the blocks of the stream (an interpolator
    /// made on an empty one), for its feed limits (and [`Interpolator::feed_reductions`]):
    /// they come out as when the setpoints are taken, since a block's cruise speed and the
    /// limit that holds it are set when the block is planned on its own
    /// ([`Interpolator::plan`]), before the junctions, the look-ahead or the profile, which
    /// this skips. The interpolator yields nothing after.
    pub fn plan_block(&mut self, block: &Move) -> Result<()> {
        self.done = true;
        let index = self.next_index;
        self.next_index += 1;
        let mut planned = None;
        self.plan(block, index, &mut planned)?;
        if let Some(held) = &planned {
            self.record(&held.planned);
        }
        Ok(())
    }

    /// Geometry and limits of one block, with the tangents `dq/ds` at its start and end,
    /// written to `out` ready to be held; `None` for a block without motion. Inlined: its
    /// result is large, and each caller keeps a part of it.
    #[inline(always)]
    fn plan(&self, b: &Move, index: u64, out: &mut Option<Held>) -> Result<()> {
        let tcp = (b.tcp || self.options.force_tcp).then_some(&self.kinematics);
        self.check_block(b, tcp.is_some())?;
        // The block's `Planned` is assembled last, from its parts: built early and filled in,
        // it was copied whole into the result and read back in pieces (a stall).
        let mut path = BlockPath {
            start: b.start,
            delta: b.end - b.start,
            arc: None,
            bend: None,
            tcp: tcp.is_some(),
            tool_length_mm: b.tool_length_mm,
        };
        let planned = |path: BlockPath, length: f64, limits: Limits| Planned {
            line: b.line,
            index,
            path,
            length,
            dwell_s: 0.0,
            path_control: b.path,
            programmed: limits.programmed,
            limited_by: limits.by,
            cap: limits.cap,
            accel: limits.accel,
            jerk: limits.jerk,
            entry_cap: 0.0,
            rho: 1.0,
            entry_max: 0.0,
            overlap: None,
            halved: false,
            rest_entry_due: false,
        };
        // A B C (deg counted as mm) and U V W (mm): the axes besides the tool tip's X Y Z.
        let rotary_norm = (3..9).map(|i| path.delta.0[i].powi(2)).sum::<f64>().sqrt();
        let mixed = |path_xyz: f64| (path_xyz * path_xyz + rotary_norm * rotary_norm).sqrt();
        let tip_or_mixed = |path_xyz: f64| {
            if path_xyz > 1e-12 {
                path_xyz
            } else {
                rotary_norm
            }
        };
        let length;
        // The delta's parts read where they are (a copy of it, stored in pieces and loaded
        // whole, stalled).
        let [dx, dy, dz, ..] = path.delta.0;
        let linear_norm = (dx * dx + dy * dy + dz * dz).sqrt();
        match b.motion {
            Motion::Dwell { seconds } => {
                if !(seconds.is_finite() && seconds >= 0.0) {
                    return Err(self.block_error(
                        b.line,
                        format!("G04 dwell must be a finite time >= 0 s, got {seconds}"),
                    ));
                }
                path.delta = AxisVec::ZERO;
                path.tcp = false;
                let dwell = Planned {
                    dwell_s: seconds,
                    ..planned(path, 0.0, Limits::NONE)
                };
                *out = Some(Held {
                    planned: dwell,
                    start: AxisVec::ZERO,
                    end: AxisVec::ZERO,
                    half: 0.0,
                });
                return Ok(());
            }
            Motion::Rapid => {
                // G00 runs in joint space even under TCP: convert tip to machine coordinates.
                if let Some(k) = tcp {
                    let to_machine = |q: &AxisVec| k.tcp_axes(q, b.tool_length_mm);
                    path.start = to_machine(&b.start);
                    path.delta = to_machine(&b.end) - path.start;
                    path.tcp = false;
                }
                length = path.delta.mixed_norm();
            }
            Motion::Linear => {
                // LinuxCNC's F is the X Y Z speed when X Y Z move (measured: overlap).
                let xyz_feed = self.control.max_feed_override.is_some();
                length = if tcp.is_some() || xyz_feed {
                    tip_or_mixed(linear_norm)
                } else {
                    mixed(linear_norm)
                };
            }
            Motion::Arc {
                clockwise,
                plane,
                center_mm,
            } => {
                let arc = arc_path::arc_geometry(b, clockwise, plane, center_mm)
                    .map_err(|why| self.block_error(b.line, why))?;
                let i2 = 3 - arc.i0 - arc.i1;
                let arc_len = arc.sweep.abs() * (arc.r0 + 0.5 * arc.dr).abs();
                let helix = arc_len.hypot(path.delta.0[i2]);
                path.arc = Some(arc);
                length = if tcp.is_some() {
                    tip_or_mixed(helix)
                } else {
                    mixed(helix)
                };
            }
        }
        if length <= 1e-12 {
            *out = None;
            return Ok(());
        }
        if !length.is_finite() {
            return Err(self.block_error(
                b.line,
                "the move is too long to plan: check the axis positions",
            ));
        }
        let programmed = self.programmed_speed(b, length)?;
        let (start, end) = path.end_tangents(length, &self.kinematics);
        let mut limits = self.limits(&path, length, programmed, start);
        if matches!(b.motion, Motion::Rapid) {
            // The control's rule for rapids ([control] rapid_acceleration_share).
            limits.accel *= self.control.rapid_acceleration_share;
        }
        if !(limits.cap.is_finite() && limits.cap > 0.0 && limits.accel > 0.0 && limits.jerk > 0.0)
            || !(limits.accel.is_finite() && limits.jerk.is_finite())
        {
            return Err(self.block_error(
                b.line,
                "the move has no finite speed: check the axis positions and the feed",
            ));
        }
        *out = Some(Held {
            planned: planned(path, length, limits),
            start,
            end,
            half: 0.5 * length,
        });
        Ok(())
    }

    /// The block's positions are finite, it moves only axes the machine has, and it asks
    /// for TCP (`tcp`) only where the machine's tool pose is modelled.
    #[inline(always)]
    fn check_block(&self, b: &Move, tcp: bool) -> Result<()> {
        if !b.start.is_finite() || !b.end.is_finite() {
            return Err(self.block_error(b.line, "an axis position is not a finite number"));
        }
        for axis in Axis::ALL {
            if self.limits[axis.index()].is_none() && b.end[axis] != b.start[axis] {
                return Err(self.block_error(
                    b.line,
                    format!(
                        "the block moves axis {axis}, which this machine ({}) does not have",
                        self.kinematics.layout.name()
                    ),
                ));
            }
        }
        if let (true, Some(why)) = (tcp, self.kinematics.layout.tool_pose_unmodelled()) {
            return Err(self.block_error(
                b.line,
                format!(
                    "the block asks for tool-centre-point control (TCP), which this machine ({}) cannot give: {why}; expected no TCP (G43.4 or a `tcp-on` user M code) on this machine",
                    self.kinematics.layout.name()
                ),
            ));
        }
        Ok(())
    }

    /// The block's programmed path speed (path units/s) over `length`: its feed per
    /// minute, or `length` per inverse-time feed; unbounded for a rapid.
    #[inline(always)]
    fn programmed_speed(&self, b: &Move, length: f64) -> Result<f64> {
        Ok(match (b.motion, b.feed) {
            (Motion::Rapid, _) => f64::INFINITY,
            (_, Feed::PerMinute(f)) if f.is_finite() && f > 0.0 => f / 60.0,
            (_, Feed::InverseTime(f)) if f.is_finite() && f > 0.0 => f * length / 60.0,
            // The reader refuses a feed move without a positive F; a generated or hand-made
            // move may still carry none, or F0 from a G95 or G33 at S0.
            (_, feed) => {
                let what = match feed {
                    Feed::InverseTime(_) => {
                        "an inverse-time feed: under G93 program an F word > 0 (1/min) on every move"
                    }
                    _ => "a feed rate: program an F word > 0 (mm/min)",
                };
                return Err(self.block_error(b.line, format!("the move needs {what}")));
            }
        })
    }

    /// Cruise cap and path acceleration and jerk limits of a block of `length` along `path`
    /// from the axis limits, with the axis and limit that hold the cap below `programmed`.
    /// `tangent_start`: `dq/ds` at the block's start (all of it for a straight block).
    fn limits(
        &self,
        path: &BlockPath,
        length: f64,
        programmed: f64,
        tangent_start: AxisVec,
    ) -> Limits {
        let (mut cap, mut accel, mut jerk) = (programmed, f64::INFINITY, f64::INFINITY);
        let mut by = None;
        let mut lower = |cap: &mut f64, value: f64, i: usize, kind: LimitKind| {
            if value < *cap {
                *cap = value;
                by = Some((Axis::ALL[i], kind));
            }
        };
        let present = |i: usize| self.limits[i].map(|l| (i, l));
        if path.is_straight() {
            let t = tangent_start;
            for (i, l) in (0..9).filter_map(present) {
                let d = t.0[i].abs();
                if d > 0.0 {
                    lower(&mut cap, l.velocity / d, i, LimitKind::Velocity);
                    accel = accel.min(l.acceleration / d);
                    jerk = jerk.min(l.jerk / d);
                }
            }
        } else {
            // The cruise speed is bounded by what each axis sees at constant speed (a = j = 0:
            // velocity q' v, acceleration q'' v², jerk q''' v³); the path acceleration and
            // jerk of a speed change then get what that leaves of each axis's budget.
            // A blend arc's derivatives are known exactly, and its budget is LinuxCNC's.
            // So are a circle's, whose budget is LinuxCNC's under its rules (arc_corner).
            let linuxcnc = self.control.max_feed_override.is_some();
            let circle = linuxcnc.then(|| path.circle_bounds(length)).flatten();
            let ((d1, d2, d3), normal, tangential) = match (&path.bend, circle) {
                (Some(b), _) => (
                    b.derivative_bounds(),
                    blend::NORMAL_SHARE,
                    blend::TANGENTIAL_SHARE,
                ),
                (None, Some(bounds)) => (bounds, blend::NORMAL_SHARE, blend::TANGENTIAL_SHARE),
                (None, None) => (self.derivative_bounds(path, length), 0.5, 0.5),
            };
            for (i, l) in (0..9).filter_map(present) {
                if d1[i] > 0.0 {
                    lower(&mut cap, l.velocity / d1[i], i, LimitKind::Velocity);
                }
                if d2[i] > 0.0 {
                    let centripetal = (normal * l.acceleration / d2[i]).sqrt();
                    lower(&mut cap, centripetal, i, LimitKind::Acceleration);
                }
                if d3[i] > 0.0 {
                    lower(&mut cap, cbrt(l.jerk / (3.0 * d3[i])), i, LimitKind::Jerk);
                }
            }
            // Every speed in the block is at most `cap`, so `3 |q''| v a ≤ ⅓ jmax` holds
            // with `a ≤ ⅓ jmax / (3 |q''| cap)`.
            for (i, l) in (0..9).filter_map(present) {
                if d1[i] > 0.0 {
                    // A circle under LinuxCNC's rules: what the centripetal term leaves at
                    // the cruise speed, `sqrt(a² − (q'' cap²)²)` (arc_corner).
                    let share = match circle {
                        Some(_) if path.bend.is_none() && cap.is_finite() => (1.0
                            - (d2[i] * cap * cap / l.acceleration).powi(2))
                        .max(0.0)
                        .sqrt(),
                        _ => tangential,
                    };
                    accel = accel.min(share * l.acceleration / d1[i]);
                    jerk = jerk.min(l.jerk / (3.0 * d1[i]));
                }
                if d2[i] > 0.0 && cap.is_finite() {
                    accel = accel.min(l.jerk / (9.0 * d2[i] * cap));
                }
            }
        }
        Limits {
            programmed,
            by,
            cap,
            accel,
            jerk,
        }
    }

    /// Maxima of |dq/ds|, |d²q/ds²|, |d³q/ds³| per axis, sampled at `SAMPLES + 1` points.
    fn derivative_bounds(&self, path: &BlockPath, length: f64) -> ([f64; 9], [f64; 9], [f64; 9]) {
        let (mut d1, mut d2, mut d3) = ([0.0; 9], [0.0; 9], [0.0; 9]);
        // One five-point stencil per sample: h small enough for O(h²) truncation to be
        // negligible, large enough for rounding in the third difference to stay small.
        let h = 2e-3;
        for k in 0..=SAMPLES {
            let u = k as f64 / SAMPLES as f64;
            let k = &self.kinematics;
            let q = path.at(u, k);
            let (p1, m1) = (path.at(u + h, k), path.at(u - h, k));
            let (p2, m2) = (path.at(u + 2.0 * h, k), path.at(u - 2.0 * h, k));
            for i in 0..9 {
                let first = (p1.0[i] - m1.0[i]) / (2.0 * h * length);
                let second = (p1.0[i] - 2.0 * q.0[i] + m1.0[i]) / (h * h * length * length);
                let third = (p2.0[i] - 2.0 * p1.0[i] + 2.0 * m1.0[i] - m2.0[i])
                    / (2.0 * h.powi(3) * length.powi(3));
                d1[i] = f64::max(d1[i], first.abs());
                d2[i] = f64::max(d2[i], second.abs());
                d3[i] = f64::max(d3[i], third.abs());
            }
        }
        // Between samples (half a spacing Δs/2 = L/(2 SAMPLES) away) a derivative can exceed
        // its sampled maximum by at most the next derivative times Δs/2.
        let half_spacing = 0.5 * length / SAMPLES as f64;
        for i in 0..9 {
            d3[i] *= 1.1;
            d2[i] += d3[i] * half_spacing;
            d1[i] += d2[i] * half_spacing;
        }
        (d1, d2, d3)
    }

    /// Appends a planned block: junction limit, then the backward pass.
    fn push(&mut self, p: Planned, tangent_start: AxisVec, tangent_end: AxisVec) {
        self.window.push_back(p);
        self.finish_push(tangent_start, tangent_end);
    }

    /// Appends the held block ([`Interpolator::hold`]) as [`Interpolator::push`] does, copied
    /// once, from where it is held into the window (taken out first, it was copied twice more).
    fn push_held(&mut self) {
        let Some(held) = &*self.held else {
            return;
        };
        self.window.push_back(held.planned);
        let (start, end) = (held.start, held.end);
        self.finish_push(start, end);
    }

    /// Takes the next planned block, `next` (`Some`), as [`Interpolator::hold`] does, and
    /// returns a box to plan the following one in. At a plain junction (no overlap, no blend)
    /// the held block goes to the window from where it is held and `next` is held by swapping
    /// the boxes: one copy of the block where `hold` took three.
    fn hold_next(&mut self, mut next: Box<Option<Held>>) -> Box<Option<Held>> {
        let Some(n) = next.as_ref() else {
            return next;
        };
        let plain = match self.held.as_ref() {
            None => true,
            Some(prev) => self.plain_junction(prev, &n.planned, n.start, n.half),
        };
        if plain {
            self.push_held();
            std::mem::swap(&mut self.held, &mut next);
        } else if let Some(n) = next.take() {
            self.hold(n.planned, n.start, n.end);
        }
        next
    }

    /// The held block `prev` joins `next` (starting along `start`, half of it `half` mm) with
    /// neither an overlap nor a blend ([`Interpolator::hold`]'s other cases).
    fn plain_junction(&self, prev: &Held, next: &Planned, start: AxisVec, half: f64) -> bool {
        prev.planned.path.arc.is_none()
            && next.path.arc.is_none()
            && self.overlap_travel(&prev.planned, next).is_none()
            && self.corner(prev, next, start, half).is_none()
    }

    /// Takes the next planned block: the one held before it is pushed, its corner with this
    /// one blended when both allow it ([`blend::corner`]: the end of the held block and the
    /// start of this one trimmed, the arc pushed between them), and this one is held.
    fn hold(&mut self, mut next: Planned, start: AxisVec, end: AxisVec) {
        let half = 0.5 * next.length;
        if let Some(mut prev) = self.held.take() {
            if let Some(travel) = self.overlap_travel(&prev.planned, &next) {
                self.halve_for_overlap(&mut prev.planned);
                self.halve_for_overlap(&mut next);
                next.overlap = Some(travel);
            }
            let corner = self.corner(&prev, &next, start, half);
            if corner.is_none() && (prev.planned.path.arc.is_some() || next.path.arc.is_some()) {
                match self.blend_line_arc(prev, next, start, half) {
                    Ok((trimmed, new_start)) => {
                        *self.held = Some(Held {
                            planned: trimmed,
                            start: new_start,
                            end,
                            half,
                        });
                        return;
                    }
                    Err((p, n)) => (prev, next) = (p, n),
                }
            }
            if let Some(c) = corner {
                let a = &mut prev.planned;
                a.path.delta = a.path.delta * ((a.length - c.trim) / a.length);
                a.length -= c.trim;
                let arc_start = a.path.start + a.path.delta;
                next.path.start = next.path.start + start * c.trim;
                next.path.delta = next.path.delta * ((next.length - c.trim) / next.length);
                next.length -= c.trim;
                let arc = self.blend_block(&prev.planned, arc_start, c);
                if prev.planned.length > 1e-9 {
                    self.push(prev.planned, prev.start, prev.end);
                }
                self.push(arc, prev.end, start);
            } else {
                // (A start trimmed by a blend leaves at least half the block.)
                self.push(prev.planned, prev.start, prev.end);
            }
        }
        *self.held = Some(Held {
            planned: next,
            start,
            end,
            half,
        });
    }

    /// Pushes `held`, the program's last block. Under LinuxCNC's rules (`[control]
    /// max_feed_override`) a straight G64 block runs at half its acceleration there
    /// (measured: 150 of 300 mm/s² where the last move of a program starts from rest and
    /// where it stops, 300 everywhere else; docs/interpolation.md).
    fn push_last(&mut self, held: Held) {
        let mut p = held.planned;
        let halves = self.control.max_feed_override.is_some()
            && matches!(p.path_control, PathControl::Blend { .. })
            && p.path.arc.is_none()
            && p.path.bend.is_none()
            && !p.path.tcp
            && !p.halved;
        if halves {
            p.accel *= 0.5;
        }
        // A last arc: a quarter of the acceleration (arc_corner).
        let circle = p.path.circle_bounds(p.length);
        if let (Some((d1, ..)), Some(_), PathControl::Blend { .. }) =
            (circle, self.control.max_feed_override, p.path_control)
        {
            for (i, l) in self.limits.iter().enumerate() {
                if let (Some(l), true) = (l, d1[i] > 0.0) {
                    p.accel = p.accel.min(0.25 * l.acceleration / d1[i]);
                }
            }
        }
        self.push(p, held.start, held.end);
    }

    /// The blend of the corner between the held block `prev` and `next` (starting along
    /// `start`, half of it `half` mm), if both are blendable (straight moves of X Y Z only,
    /// no TCP, both rapids or both feed moves: LinuxCNC stops between a G1 and a G0 and blends
    /// the others otherwise) and something bounds it: the
    /// tolerance (G64 P, or the machine's default), or, with `[control] max_feed_override`,
    /// the radius LinuxCNC gives the feed ([`blend::SpeedSizing`]).
    fn corner(
        &self,
        prev: &Held,
        next: &Planned,
        start: AxisVec,
        half: f64,
    ) -> Option<blend::Corner> {
        let blendable = |p: &Planned| {
            p.length > 0.0
                && p.path.is_straight()
                && !p.path.tcp
                && (3..9).all(|i| p.path.delta.0[i] == 0.0)
        };
        let PathControl::Blend { tolerance_mm, .. } = prev.planned.path_control else {
            return None;
        };
        let rapid = |p: &Planned| p.programmed == f64::INFINITY;
        if !(blendable(&prev.planned) && blendable(next)) || rapid(&prev.planned) != rapid(next) {
            return None;
        }
        let tolerance = tolerance_mm.or(self.control.path_tolerance_mm);
        let speed = self.speed_sizing(&prev.planned);
        if speed.is_none() && tolerance.is_none() {
            return None;
        }
        blend::corner(prev.end, start, prev.half, half, tolerance, speed.as_ref())
    }

    /// How LinuxCNC sizes a blend after `prev` for speed ([`blend::SpeedSizing`]: its feed,
    /// the control's highest override, the axes' limits), `[control] max_feed_override` given.
    fn speed_sizing(&self, prev: &Planned) -> Option<blend::SpeedSizing> {
        let ovr = self.control.max_feed_override?;
        let mut axes = [None; 9];
        for (i, l) in self.limits.iter().enumerate() {
            axes[i] = l.map(|l| (l.velocity, l.acceleration));
        }
        Some(blend::SpeedSizing {
            feed: prev.programmed,
            max_feed_override: ovr,
            axes,
        })
    }

    /// The blend arc of corner `c` after `prev` (trimmed), from `arc_start`: a
    /// curved block at `prev`'s programmed speed (the corner's speed ratio, when the feed
    /// changes, stays at its far end), limited as any curved block.
    fn blend_block(&self, prev: &Planned, arc_start: AxisVec, c: blend::Corner) -> Planned {
        let path = BlockPath {
            start: arc_start,
            delta: AxisVec::ZERO,
            arc: None,
            bend: Some(c.bend),
            tcp: false,
            tool_length_mm: prev.path.tool_length_mm,
        };
        let programmed = prev.programmed;
        let limits = self.limits(&path, c.length, programmed, c.bend.along);
        Planned {
            path,
            length: c.length,
            programmed,
            limited_by: limits.by,
            cap: limits.cap,
            accel: limits.accel,
            jerk: limits.jerk,
            entry_cap: 0.0,
            rho: 1.0,
            entry_max: 0.0,
            overlap: None,
            rest_entry_due: false,
            ..*prev
        }
    }

    /// Starts the next block at time `t0`; false when the program is finished.
    fn activate(&mut self, t0: f64) -> bool {
        self.fill();
        // The block is read in place and copied once, into `active` (popped after).
        let Some(p) = self.window.front() else {
            return false;
        };
        let profile = if p.length == 0.0 {
            self.last_exit = 0.0;
            Profile {
                duration: p.dwell_s,
                ..Profile::default()
            }
        } else if let Some((profile, exit)) = self.queued.take() {
            // Planned from rest when the block before handed over to it (`plan_handover`).
            self.last_exit = exit;
            profile
        } else {
            let entry = (p.rho * self.last_exit).min(p.entry_limit());
            let exit_max = self
                .window
                .get(1)
                .map_or(0.0, |n| n.entry_limit() / n.rho)
                .min(p.cap);
            let exit = reach(entry, p.length, exit_max, p.accel, p.jerk);
            self.last_exit = exit;
            Profile::new(entry, exit, p.cap, p.length, p.accel, p.jerk)
        };
        // Written over the last active block in place (a new `Active` was copied twice).
        match &mut self.active {
            Some(a) => {
                a.planned = *p;
                a.profile = profile;
                a.t0 = t0;
                a.handover = profile.duration;
            }
            None => {
                self.active = Some(Active {
                    planned: *p,
                    profile,
                    t0,
                    handover: profile.duration,
                })
            }
        }
        if self.window.get(1).is_some_and(|n| n.overlap.is_some()) {
            self.plan_handover();
        }
        self.window.pop_front();
        true
    }
}

impl<I: Iterator<Item = Result<Move>>> Iterator for Interpolator<I> {
    type Item = Result<Setpoint>;

    /// The setpoint within the active block inline (so that it is built in place, not
    /// copied out of a call); the block change out of line.
    #[inline]
    fn next(&mut self) -> Option<Result<Setpoint>> {
        if self.done {
            return None;
        }
        let t = self.step as f64 * self.period_s;
        if self.trailing.is_none() {
            if let Some(setpoint) = self.active_setpoint(t) {
                self.step += 1;
                return Some(Ok(setpoint));
            }
        }
        self.next_after_block(t)
    }
}

impl<I: Iterator<Item = Result<Move>>> Interpolator<I> {
    /// The setpoint of the active block at `t` ([`Active::setpoint_at`]), if it runs then.
    #[inline(always)]
    fn active_setpoint(&self, t: f64) -> Option<Setpoint> {
        self.active
            .as_ref()
            .and_then(|a| a.setpoint_at(t, &self.kinematics))
    }

    /// [`Iterator::next`] where the active block has ended at time `t`, or where the block
    /// before it still runs beside it ([`overlap`]: what is left of that one added, until it
    /// ends): activates the next one (its first setpoint), or ends at rest at the last end
    /// point.
    #[inline(never)]
    fn next_after_block(&mut self, t: f64) -> Option<Result<Setpoint>> {
        loop {
            if let Some(mut setpoint) = self.active_setpoint(t) {
                if let Some(trailing) = &self.trailing {
                    setpoint.q = setpoint.q + trailing.left_at(t, &self.kinematics);
                    if !(t < trailing.t0 + trailing.profile.duration) {
                        self.trailing = None;
                    }
                }
                self.step += 1;
                return Some(Ok(setpoint));
            }
            let t0 = self.active.as_ref().map_or(0.0, |a| a.t0 + a.handover);
            // The block that hands over early runs on beside the next ([`overlap`]).
            // (Copied only then: an `Option` chain copied the block four times.)
            if self
                .active
                .as_ref()
                .is_some_and(|a| a.handover < a.profile.duration)
            {
                self.trailing = self.active;
            } else if !self
                .trailing
                .as_ref()
                .is_some_and(|a| t0 < a.t0 + a.profile.duration)
            {
                self.trailing = None;
            }
            let started = self.activate(t0);
            if let Some(e) = self.pending_error.take() {
                self.done = true;
                return Some(Err(e));
            }
            if !started {
                self.done = true;
                // At rest at the last end point.
                let a = self.active.as_ref()?;
                let p = &a.planned;
                let u = if p.length > 0.0 { 1.0 } else { 0.0 };
                return Some(Ok(Setpoint {
                    time_s: t,
                    q: p.path.at(u, &self.kinematics),
                    line: p.line,
                    block_index: p.index,
                }));
            }
        }
    }
}
