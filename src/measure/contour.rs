//! The contour error of any program: how far the actual tool tip is from the programmed path.
//!
//! For a sample of a feed move (G01, G02, G03; rapids and dwells are no contour), the
//! contour error is the distance, normal to the programmed path, from the actual tool tip to
//! that path, in the workpiece (table) frame:
//!
//! ```text
//! e(t) = min over s of | w_act(t) − P(s) |
//! ```
//!
//! where `P(s)` is the programmed path of the sample's block and of its two neighbours (so
//! that a tip lagging behind a corner is measured to the path it is still on), and `w` is a
//! point in the coordinates the program is written in: the tool tip at tool length L in the
//! table frame, with L added back along the table's Z (`w = tip_L + L ẑ`, the reader's TCP
//! coordinates; on a machine without rotaries simply `X Y Z − pivot`). The actual tip comes
//! from the actual axis positions through the actual chain (location errors), as the ball
//! bar and the cut take it ([`actual_tool`]); the programmed path from the block's axis
//! positions at fraction `s` (`motion::sampling::position_in_block`: the straight line, the
//! arc, or the TCP line) through the nominal chain.
//!
//! Where the block's rotaries do not move, `P` is a straight segment (an affine image of the
//! block's line) and the distance is closed-form; otherwise (an arc, a five-axis joint move)
//! `|w − P(s)|²` is minimised by Newton's method on `s ∈ [0, 1]` from the commanded sample's
//! own fraction. Beside it, on five-axis moves, the tool-axis error: the angle between the
//! actual tool axis and the programmed one at the nearest point, µrad.
//!
//! The gauge takes the program's moves as the run reads them (a tee of the run's stream,
//! `program::moves::tee`), in step with the samples (`block_index`), and holds three moves:
//! memory does not grow with the program.

use std::collections::VecDeque;

use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::input::Machine;
use crate::kinematics::{Kinematics, LocationErrors, ToolPose};
use crate::measure::cut::actual_tool;
use crate::motion::sampling::position_in_block;
use crate::pipeline::Sample;
use crate::program::{Motion, Move, Moves};
use crate::{Axis, AxisVec};

/// Places kept in the list of worst places.
pub const WORST_PLACES: usize = 10;

/// Bins of the contour error's profile along the program (the plot).
pub const PROFILE_BINS: usize = 2_000;

/// The contour error of one sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContourReading {
    /// Distance from the actual tip to the programmed path, µm.
    pub contour_um: f64,
    /// From the nearest point of the path to the actual tip, workpiece frame, mm: the
    /// contour error as a vector (its length is `contour_um`), for the error budget.
    pub error_mm: Vector3<f64>,
    /// Angle between the actual and the programmed tool axis, µrad.
    pub tool_axis_error_urad: f64,
}

/// One of the worst places: the program line, and the largest contour error there.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorstPlace {
    pub line: usize,
    /// Machine time of the worst sample, s.
    pub time_s: f64,
    pub contour_um: f64,
    pub tool_axis_error_urad: f64,
}

/// The contour error of a run, as `summary.json`'s `measurements.contour` gives it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ContourFigures {
    /// Samples on feed moves, measured.
    pub samples: u64,
    /// Largest and root-mean-square contour error, µm.
    pub max_um: f64,
    pub rms_um: f64,
    /// Largest tool-axis error, µrad (0 on a machine without rotaries).
    pub max_tool_axis_error_urad: f64,
    /// The worst program lines, worst first (at most [`WORST_PLACES`]).
    pub worst: Vec<WorstPlace>,
}

/// The largest contour error over equal spans of machine time, for a plot along the program:
/// at most [`PROFILE_BINS`] bins, each span doubled (neighbours merged) when the run outgrows
/// them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContourProfile {
    pub start_s: f64,
    pub bin_s: f64,
    /// Largest contour error in each bin, µm (NaN where no feed sample fell).
    pub max_um: Vec<f64>,
}

impl ContourProfile {
    fn new(start_s: f64, period_s: f64) -> ContourProfile {
        ContourProfile {
            start_s,
            bin_s: period_s.max(1e-6),
            max_um: Vec::new(),
        }
    }

    fn push(&mut self, time_s: f64, value_um: f64) {
        let mut k = ((time_s - self.start_s) / self.bin_s).floor().max(0.0) as usize;
        while k >= PROFILE_BINS {
            // Merge neighbours: each bin now spans twice the time.
            let merged: Vec<f64> = self
                .max_um
                .chunks(2)
                .map(|pair| pair.iter().copied().fold(f64::NAN, f64::max))
                .collect();
            self.max_um = merged;
            self.bin_s *= 2.0;
            k = ((time_s - self.start_s) / self.bin_s).floor().max(0.0) as usize;
        }
        if self.max_um.len() <= k {
            self.max_um.resize(k + 1, f64::NAN);
        }
        self.max_um[k] = self.max_um[k].max(value_um);
    }
}

/// One programmed block as the gauge measures against it.
#[derive(Clone, Debug)]
struct BlockPath {
    index: u64,
    block: Move,
    /// A feed move (a contour); rapids and dwells are not.
    contour: bool,
    /// The block's path is the segment `a → b` in workpiece coordinates (its rotaries do not
    /// move and it is no arc).
    segment: Option<(Point3<f64>, Point3<f64>)>,
}

/// The contour-error gauge: the program read in step with the samples.
pub struct ContourGauge<'a> {
    machine: &'a Machine,
    nominal: Kinematics,
    actual: Kinematics,
    moves: Moves<'a>,
    /// Treat every feed move as TCP ([`crate::pipeline::RunOptions::force_tcp`]).
    force_tcp: bool,
    /// The moves read so far and still needed: the sample's block and its neighbours.
    window: VecDeque<BlockPath>,
    next_index: u64,
    ended: bool,
    figures: ContourFigures,
    sum_sq: f64,
    profile: ContourProfile,
}

impl<'a> ContourGauge<'a> {
    /// A gauge of a run of `moves` (the same moves the pipeline runs) on
    /// `machine`, starting at machine time `start_s`.
    pub fn new(machine: &'a Machine, moves: Moves<'a>, force_tcp: bool, start_s: f64) -> Self {
        let actual = machine.kinematics.clone();
        let nominal = actual
            .clone()
            .with_location_errors(LocationErrors::default());
        ContourGauge {
            machine,
            nominal,
            actual,
            moves,
            force_tcp,
            window: VecDeque::with_capacity(4),
            next_index: 0,
            ended: false,
            figures: ContourFigures::default(),
            sum_sq: 0.0,
            profile: ContourProfile::new(start_s, machine.interpolation_period_s),
        }
    }

    /// The contour error of sample `s`; None on a rapid or a dwell.
    pub fn read(&mut self, s: &Sample) -> Result<Option<ContourReading>> {
        let k = s.block_index;
        self.fill_to(k + 1)?;
        while self.window.front().is_some_and(|b| b.index + 1 < k) {
            self.window.pop_front();
        }
        let actual = actual_tool(&self.actual, &s.actual);
        let Some((error_mm, programmed_axis)) = self.nearest(s, &actual) else {
            return Ok(None);
        };
        let cos = actual.axis.dot(&programmed_axis).clamp(-1.0, 1.0);
        let reading = ContourReading {
            contour_um: error_mm.norm() * 1e3,
            error_mm,
            tool_axis_error_urad: angle_between(&actual.axis, &programmed_axis, cos) * 1e6,
        };
        self.record(s, &reading);
        Ok(Some(reading))
    }

    /// The contour error vector (mm) of the tool at `pose` at sample `s` (read already by
    /// [`ContourGauge::read`], which holds its blocks), and the programmed tool axis at the
    /// nearest point; None off the contour.
    fn nearest(&self, s: &Sample, pose: &ToolPose) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let k = s.block_index;
        let here = self.window.iter().position(|b| b.index == k)?;
        // The first move only places the machine (its start is unknown), and is no contour.
        if !self.window[here].contour || k == 0 {
            return None;
        }
        let w = workpiece_point(pose, self.window[here].block.tool_length_mm);
        let mut best: Option<(f64, Vector3<f64>, Vector3<f64>)> = None;
        for (j, path) in self.window.iter().enumerate() {
            if !path.contour || path.index == 0 || path.index + 1 < k || path.index > k + 1 {
                continue;
            }
            // The sample's own block from its commanded fraction; a neighbour from its end
            // nearest the sample.
            let start_f = match j.cmp(&here) {
                std::cmp::Ordering::Less => 1.0,
                std::cmp::Ordering::Greater => 0.0,
                std::cmp::Ordering::Equal => fraction_of(&path.block, &s.commanded),
            };
            let (point, axis) = self.nearest_on(path, &w, start_f);
            let d = (w - point).norm();
            if best.is_none_or(|(b, _, _)| d < b) {
                best = Some((d, w - point, axis));
            }
        }
        best.map(|(_, e, axis)| (e, axis))
    }

    /// The contour error vector (mm) at sample `s` (read already) of axis positions `q`
    /// other than the actual ones (an error budget's run), through the chain with the
    /// geometric `errors` (a part of the machine's), or through the nominal one for None.
    pub fn error_at(
        &self,
        s: &Sample,
        q: &AxisVec,
        errors: Option<&LocationErrors>,
    ) -> Option<Vector3<f64>> {
        let pose = match errors {
            Some(e) => actual_tool(&self.actual.with_location_errors(*e), q),
            None => self.nominal.forward(q),
        };
        self.nearest(s, &pose).map(|(e, _)| e)
    }

    /// What the gauge measured over the run.
    pub fn figures(&self) -> ContourFigures {
        let mut f = self.figures.clone();
        if f.samples > 0 {
            f.rms_um = (self.sum_sq / f.samples as f64).sqrt();
        }
        f
    }

    /// The largest contour error along the run, binned in time.
    pub fn profile(&self) -> &ContourProfile {
        &self.profile
    }

    fn record(&mut self, s: &Sample, r: &ContourReading) {
        let f = &mut self.figures;
        f.samples += 1;
        f.max_um = f.max_um.max(r.contour_um);
        f.max_tool_axis_error_urad = f.max_tool_axis_error_urad.max(r.tool_axis_error_urad);
        self.sum_sq += r.contour_um * r.contour_um;
        self.profile.push(s.time_s, r.contour_um);
        let place = WorstPlace {
            line: s.line,
            time_s: s.time_s,
            contour_um: r.contour_um,
            tool_axis_error_urad: r.tool_axis_error_urad,
        };
        // One place per line, the worst of it; the list sorted worst first, bounded.
        match f.worst.iter().position(|p| p.line == s.line) {
            Some(i) if f.worst[i].contour_um >= r.contour_um => return,
            Some(i) => {
                f.worst.remove(i);
            }
            None => {
                if f.worst.len() == WORST_PLACES
                    && f.worst.last().is_some_and(|p| p.contour_um >= r.contour_um)
                {
                    return;
                }
            }
        }
        let at = f.worst.partition_point(|p| p.contour_um >= r.contour_um);
        f.worst.insert(at, place);
        f.worst.truncate(WORST_PLACES);
    }

    /// Reads moves until the window holds block `index` (or the program ended).
    fn fill_to(&mut self, index: u64) -> Result<()> {
        while !self.ended && self.next_index <= index {
            match self.moves.next() {
                Some(m) => {
                    let mut block = m?;
                    if self.force_tcp && block.motion != Motion::Rapid {
                        block.tcp = true;
                    }
                    let path = self.block_path(self.next_index, block);
                    self.window.push_back(path);
                    self.next_index += 1;
                }
                None => self.ended = true,
            }
        }
        Ok(())
    }

    fn block_path(&self, index: u64, block: Move) -> BlockPath {
        let contour = matches!(block.motion, Motion::Linear | Motion::Arc { .. });
        let rotaries_still = Axis::ALL
            .iter()
            .filter(|a| a.is_rotary())
            .all(|&a| block.start[a] == block.end[a]);
        let segment = (contour && rotaries_still && block.motion == Motion::Linear).then(|| {
            let l = block.tool_length_mm;
            (
                self.programmed(&block, 0.0, l).0,
                self.programmed(&block, 1.0, l).0,
            )
        });
        BlockPath {
            index,
            block,
            contour,
            segment,
        }
    }

    /// The programmed point and tool axis at fraction `f` of `block`.
    fn programmed(&self, block: &Move, f: f64, tool_length_mm: f64) -> (Point3<f64>, Vector3<f64>) {
        let q = position_in_block(block, self.machine, f.clamp(0.0, 1.0));
        let pose = self.nominal.forward(&q);
        (workpiece_point(&pose, tool_length_mm), pose.axis)
    }

    /// The point of `path` nearest `w`, and the programmed tool axis there; `start_f` is
    /// where the search starts.
    fn nearest_on(
        &self,
        path: &BlockPath,
        w: &Point3<f64>,
        start_f: f64,
    ) -> (Point3<f64>, Vector3<f64>) {
        let l = path.block.tool_length_mm;
        if let Some((a, b)) = path.segment {
            let ab = b - a;
            let len2 = ab.norm_squared();
            let f = if len2 > 0.0 {
                ((w - a).dot(&ab) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let axis = self.programmed(&path.block, f, l).1;
            return (a + ab * f, axis);
        }
        newton_nearest(|f| self.programmed(&path.block, f, l), w, start_f)
    }
}

/// Minimises `|P(f) − w|²` over `f ∈ [0, 1]` by Newton's method on its derivative
/// `(P − w)·P'`, with `P'` and `P''` by central differences (a stencil kept inside the
/// block); returns the nearest point and the tool axis there.
fn newton_nearest(
    p: impl Fn(f64) -> (Point3<f64>, Vector3<f64>),
    w: &Point3<f64>,
    start_f: f64,
) -> (Point3<f64>, Vector3<f64>) {
    const H: f64 = 1e-4;
    let mut f = start_f.clamp(0.0, 1.0);
    for _ in 0..8 {
        // The stencil stays inside the block: centred at c, within H of f.
        let c = f.clamp(H, 1.0 - H);
        let (p_c, p_lo, p_hi) = (p(c).0, p(c - H).0, p(c + H).0);
        let d1 = (p_hi - p_lo) / (2.0 * H);
        let d2 = (p_hi.coords - p_c.coords * 2.0 + p_lo.coords) / (H * H);
        let r = p(f).0 - w;
        let g = r.dot(&d1);
        // Newton's step where the model is convex; a gradient step (Gauss-Newton) elsewhere.
        let h = match d1.norm_squared() + r.dot(&d2) {
            h if h > 0.0 && h.is_finite() => h,
            _ => d1.norm_squared(),
        };
        if h <= 0.0 {
            break;
        }
        let next = (f - g / h).clamp(0.0, 1.0);
        let moved = (next - f).abs();
        f = next;
        if moved < 1e-12 {
            break;
        }
    }
    p(f)
}

/// `tip_L + L ẑ` with `tip_L = tip_0 − L·axis`: the reader's coordinates of a tool tip
/// (tool length `L`) in the table frame.
fn workpiece_point(pose: &ToolPose, tool_length_mm: f64) -> Point3<f64> {
    let l = tool_length_mm;
    pose.tip - pose.axis * l + Vector3::z() * l
}

/// Where commanded positions `q` lie along `block`, as a fraction: the projection on its
/// chord in axis space (an arc: its angle over the sweep).
fn fraction_of(block: &Move, q: &AxisVec) -> f64 {
    if let (
        Motion::Arc {
            plane, center_mm, ..
        },
        Some(sweep),
    ) = (block.motion, block.arc_sweep_rad())
    {
        let (u, v, _) = plane.axes();
        let (cu, cv) = (center_mm[u.index()], center_mm[v.index()]);
        let a0 = (block.start[v] - cv).atan2(block.start[u] - cu);
        let a = (q[v] - cv).atan2(q[u] - cu);
        let mut turned = a - a0;
        let tau = std::f64::consts::TAU;
        if sweep > 0.0 {
            turned = turned.rem_euclid(tau);
        } else {
            turned = -(-turned).rem_euclid(tau);
        }
        return (turned / sweep).clamp(0.0, 1.0);
    }
    let d = block.end - block.start;
    let len2: f64 = d.0.iter().map(|x| x * x).sum();
    if len2 == 0.0 {
        return 0.0;
    }
    let along: f64 = (*q - block.start)
        .0
        .iter()
        .zip(d.0.iter())
        .map(|(a, b)| a * b)
        .sum();
    (along / len2).clamp(0.0, 1.0)
}

/// The angle between unit vectors `a` and `b` whose dot product is `cos`: from the cross
/// product where it is small (acos loses digits near 0).
fn angle_between(a: &Vector3<f64>, b: &Vector3<f64>, cos: f64) -> f64 {
    a.cross(b).norm().atan2(cos)
}
