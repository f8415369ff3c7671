//! Continuous collision checking over a stream of samples, by conservative advancement.
//!
//! Between two samples the axes are taken to move linearly. A point of a part then moves at
//! most `w_lin |dXYZ| + w_tilt |d tilt| + w_c |dC|` (angles in rad), with lever arms `w`
//! fixed when the scene is built (1 for the tool stack; the largest distance from the pivot
//! and from the C axis for table parts), so two parts approach each other by at most the
//! sum of their bounds. After a query measures the clearance `d` of a pair, no query of
//! that pair is needed until the accumulated bound reaches `d - near_miss`: until then the
//! pair can neither touch nor come nearer than the threshold, at a sample or between
//! samples. When a query is due and the bound over the last interval exceeds the sum of the
//! clearances at its ends, contact may have happened inside it: the interval is advanced
//! conservatively (step `s += d / bound`) to find it. A pair within the threshold (in a
//! collision or near miss) is measured again once the bound could end its event or bring a
//! new worst value: after a measured `d`, at `min(-d, W + d)` for a collision whose deepest
//! penetration is `W`, at `min(T - d, d, d - w)` for a near miss whose smallest clearance is
//! `w` (threshold `T`). Past the worst-value margin, the separating direction of the last
//! query bounds the signed distance from below at a support point's cost
//! ([`super::plane`]): a part held in a collision while the program runs on is measured
//! again only when its event could end. The samples in between are in the event, so its
//! span and worst value are those of measuring every sample (the worst to 1e-9 mm and the
//! query's own accuracy). A collision's "new worst" margin and plane floor are widened by its
//! depth tolerance `τ(W) = mm + relative · W` ([`super::DepthTolerance`]): a sample not
//! measured is at most `W + τ(W)` deep, so a part pushed deeper sample by sample is measured
//! once per `τ` of growth, and the reported depth `W` (a measured sample's) is within `τ(W)`
//! of the deepest sample's. The cutter/workpiece pair is re-measured once the bound reaches
//! `max(d, engagement resolution)`, so its reported depth is within that
//! resolution of the true maximum.
//!
//! A pair of a tool part and a part on the table (or cradle) has a second, tighter bound:
//! the motion of the tool relative to that frame. With `u = tip - pivot` (machine frame),
//! R the table (or cradle) rotation and `p` a tool point (|p| <= P from the tip), the point
//! is at `y = R^T (u + p)` in the table frame. Over an interval whose rotations change by
//! `Ω = |Δ tilt| + |ΔC|` (rad; `|Δ tilt|` for the cradle), with the axes linear in between,
//! `|R^T' v| <= Ω |v|` and `|R^T'' v| <= Ω² |v|`, so `|y''| <= 2 Ω |Δu| + Ω² (U + P)`
//! (`U` the larger `|u|` at the ends), and the path length of `y` is at most its chord plus
//! `sup |y''|`:
//! `|Δy| <= |Δ(R^T u)| + Ω P + 2 Ω |Δu| + Ω² (U + P)`.
//! The tip's chord in the table frame is what the cone test keeps small (the table turns
//! under the tool), so this bound is several times tighter than the lever arms; the
//! monitor uses the smaller of the two when [`SceneMonitor::with_relative_bounds`] is on.
//!
//! Sample by sample only the running sums of the axis motions advance. The collision pairs
//! are visited when `σ = w_max · sums` reaches the smallest value at which one of them may
//! be due; the cutting pairs ("hot": their slack is the engagement resolution) check their
//! own bound at every sample. When the cutting pair is due, two certified bounds from the
//! last certifying direction (turned with the table about the frustum's axis) often show
//! that the full query could change nothing in the report or the schedule, and it is not
//! made (`Scene::warm_bounds`, docs/scene.md).
//!
//! Memory does not grow with the number of samples: one state per pair, plus the events.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::plane::PlaneBound;
use super::snapshot::{CollisionPose, DeepestCollisions};
use super::{BodyPoses, Carrier, PairKind, Scene, Warm};
use crate::input::machine::Machine;
use crate::{Axis, AxisVec};

/// Kind of a reported event.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EventKind {
    /// Contact or penetration (signed distance <= 0).
    Collision,
    /// Clearance in (0, near-miss threshold).
    NearMiss,
}

/// One span of samples over which a pair stayed in one kind of event.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneEvent {
    pub kind: EventKind,
    pub bodies: [String; 2],
    pub time_start_s: f64,
    pub time_end_s: f64,
    pub theta_start_deg: Option<f64>,
    pub theta_end_deg: Option<f64>,
    /// Program line of the first sample.
    pub line: usize,
    /// Collision: largest penetration depth, mm (>= 0). Near miss: smallest clearance, mm.
    pub worst_mm: f64,
}

/// Cutter engagement over the run, for one cutting pair.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EngagementSummary {
    pub bodies: [String; 2],
    /// Largest measured depth of the cutter in the workpiece, mm (0 if it never touched);
    /// the true maximum exceeds it by at most `resolution_mm`.
    pub max_depth_mm: f64,
    pub max_depth_time_s: Option<f64>,
    pub max_depth_theta_deg: Option<f64>,
    /// Smallest measured signed distance, mm (negative = depth).
    pub min_distance_mm: f64,
    pub resolution_mm: f64,
}

/// What a [`SceneMonitor`] found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneReport {
    /// In order of start time.
    pub events: Vec<SceneEvent>,
    pub engagement: Vec<EngagementSummary>,
    pub near_miss_mm: f64,
    /// A collision's `worst_mm` is the depth at one of its samples, and no sample of it is
    /// deeper than `worst_mm + tolerance.at(worst_mm)` (`[scene] depth_tolerance_mm` and
    /// `depth_tolerance_relative`).
    pub depth_tolerance: super::DepthTolerance,
    /// Smallest clearance measured between any collision pair, mm (negative: penetration).
    /// Queries come more often the closer a pair gets, so below `near_miss_mm` it is the
    /// clearance at a sample; above it, the true minimum lies between `near_miss_mm` and it.
    pub min_clearance_mm: f64,
    /// The pair of the smallest clearance.
    pub min_clearance_bodies: Option<[String; 2]>,
    pub samples: u64,
    /// Geometric (signed-distance) queries made.
    pub queries: u64,
    /// The scene at the deepest sample of the deepest collisions, deepest first (none
    /// unless asked for with [`SceneMonitor::with_collision_poses`]).
    pub collision_poses: Vec<CollisionPose>,
}

impl SceneReport {
    pub fn collisions(&self) -> impl Iterator<Item = &SceneEvent> {
        self.events
            .iter()
            .filter(|e| e.kind == EventKind::Collision)
    }

    pub fn near_misses(&self) -> impl Iterator<Item = &SceneEvent> {
        self.events.iter().filter(|e| e.kind == EventKind::NearMiss)
    }
}

/// θ of a sample: given with it, or computed from its axis positions (the sample's `q`)
/// when it is reported. Small, so that a sample is not passed around with its axis
/// vector twice.
#[derive(Clone, Copy, Debug)]
enum Theta {
    Known(Option<f64>),
    OfQ,
}

#[derive(Clone, Copy, Debug)]
struct Sample {
    time_s: f64,
    theta: Theta,
    line: usize,
    q: AxisVec,
}

/// θ (deg) of the nominal path at axis positions (mm, deg), if the program has one.
pub type ThetaFn = Box<dyn Fn(&AxisVec) -> Option<f64> + Send + Sync>;

struct PairState {
    /// Bound on the pair's approach (mm) per |dXYZ| (mm), |d tilt| (rad), |dC| (rad).
    weights: [f64; 3],
    /// For a tool part against a table (0) or cradle (1) part: that frame and the tool
    /// part's reach P from the tip, mm (the relative-motion bound).
    relative: Option<(usize, f64)>,
    /// Motion bound allowed before the next query (or, in an event, the next look at its
    /// plane bound), mm.
    slack: f64,
    /// In an event: the motion bound before which it cannot end, mm.
    exit_slack: f64,
    /// In an event: the separating direction of the last query ([`PlaneBound`]).
    plane: Option<PlaneBound>,
    /// Motion bound accumulated since the last query, mm.
    moved: f64,
    /// The motion sums ([`SceneMonitor`]'s `sum`) up to which `moved` is brought.
    synced: [f64; 3],
    /// Last measured signed distance, mm.
    last_mm: f64,
    warm: Warm,
    open: Option<SceneEvent>,
    /// θ of the last sample of the open event, with its axis positions (resolved when it
    /// closes).
    open_end: (Theta, AxisVec),
    /// In a collision: the time (s) and axis positions of its deepest measured sample.
    deepest_sample: (f64, AxisVec),
    /// Index into the engagement summaries for a cutting pair.
    engagement: Option<usize>,
}

/// Consumes samples and reports collisions, near misses and engagement.
pub struct SceneMonitor {
    scene: Scene,
    states: Vec<PairState>,
    prev: Option<Sample>,
    events: Vec<SceneEvent>,
    engagement: Vec<EngagementSummary>,
    /// Per engagement summary, θ and the axis positions of its deepest sample so far: θ is
    /// computed once, at the end, not at every new deepest sample.
    deepest_at: Vec<Option<(Theta, AxisVec)>>,
    samples: u64,
    queries: u64,
    min_clearance_mm: f64,
    min_clearance_pair: Option<usize>,
    theta_of: Option<ThetaFn>,
    /// The tool tip relative to the pivot in the table and cradle frames, and |tip - pivot|,
    /// at the previous sample (when a pair uses the relative bound).
    prev_relative: Option<([Vector3<f64>; 2], f64)>,
    uses_relative: bool,
    /// Query every pair at every sample (the reference the bounds are tested against).
    exhaustive: bool,
    /// Running sums of |dXYZ| (mm), |d tilt| and |dC| (rad) over the samples so far.
    sum: [f64; 3],
    /// The largest weight of any pair but the hot ones per component: `σ = w_max · sum`
    /// grows at least as fast as their bounds, so none is due before `σ` reaches `next_due`.
    w_max: [f64; 3],
    next_due: f64,
    /// Per pair, the value of σ before which it cannot be due (kept apart from the pair
    /// states so that a visit scans one short array). A hot pair's is +∞: σ does not wait
    /// for it, and every full visit visits it.
    dues: Vec<f64>,
    is_hot: Vec<bool>,
    /// The cutting pairs, whose slack is short (the engagement resolution): each sample
    /// checks their own bound instead of letting `w_max`, which grows several times faster
    /// than theirs, call a visit every few samples.
    hot: Vec<usize>,
    /// Indices into the axis vector of the tilt axis and the table (C) axis.
    tilt_index: Option<usize>,
    table_index: Option<usize>,
    /// The scene at the deepest collisions so far (kept only when asked for).
    deepest: DeepestCollisions,
}

/// What every pair visited at one sample shares: the motion over the last interval (|dXYZ|
/// mm, |d tilt| and |dC| rad), the sums before it, the relative-motion terms, σ and its
/// rounding allowance.
struct Visit {
    step: Option<[f64; 3]>,
    prev_sum: [f64; 3],
    relative: Option<([(f64, f64); 2], f64, f64)>,
    sigma: f64,
    allowance: f64,
}

/// How far below an event's worst value (mm) the plane bound may reach at a sample that is
/// not measured: the bound is exact but computed in floating point, and a part held at one
/// depth (moving parallel to a face) sits on it to the last bits.
const PLANE_TOLERANCE_MM: f64 = 1e-9;
/// Sub-steps of conservative advancement inside one sample interval, at most.
const MAX_ADVANCE_STEPS: usize = 64;
/// Clearance below which advancement inside an interval declares contact, mm.
const CONTACT_TOLERANCE_MM: f64 = 1e-6;

impl SceneMonitor {
    /// `machine` is the one the scene was built for (its axes define the sample vector).
    pub fn new(scene: Scene, _machine: &Machine) -> SceneMonitor {
        let mut engagement = Vec::new();
        let states = scene
            .pairs
            .iter()
            .map(|pair| PairState {
                weights: {
                    let (wa, wb) = (scene.parts[pair.a].motion, scene.parts[pair.b].motion);
                    [wa[0] + wb[0], wa[1] + wb[1], wa[2] + wb[2]]
                },
                relative: {
                    let (a, b) = (&scene.parts[pair.a], &scene.parts[pair.b]);
                    let (tool, other) = if a.carrier == Carrier::Tool {
                        (a, b)
                    } else {
                        (b, a)
                    };
                    let frame = match other.carrier {
                        Carrier::Table => Some(0),
                        Carrier::Cradle => Some(1),
                        _ => None,
                    };
                    // A general chain's bodies have no table rotation written out here.
                    let named = scene.kinematics.has_closed_form();
                    frame
                        .filter(|_| named && tool.carrier == Carrier::Tool)
                        .map(|f| {
                            let aabb = tool.shape.compute_aabb(&tool.local);
                            let reach = (0..8)
                                .map(|i| {
                                    let x = if i & 1 == 0 { aabb.mins.x } else { aabb.maxs.x };
                                    let y = if i & 2 == 0 { aabb.mins.y } else { aabb.maxs.y };
                                    let z = if i & 4 == 0 { aabb.mins.z } else { aabb.maxs.z };
                                    (x * x + y * y + z * z).sqrt()
                                })
                                .fold(0.0, f64::max);
                            (f, reach)
                        })
                },
                slack: 0.0,
                exit_slack: 0.0,
                plane: None,
                moved: 0.0,
                synced: [0.0; 3],
                last_mm: f64::INFINITY,
                warm: Warm::default(),
                open: None,
                open_end: (Theta::Known(None), AxisVec::ZERO),
                deepest_sample: (0.0, AxisVec::ZERO),
                engagement: (pair.kind == PairKind::Cutting).then(|| {
                    engagement.push(EngagementSummary {
                        bodies: scene.pair_bodies(pair),
                        max_depth_mm: 0.0,
                        max_depth_time_s: None,
                        max_depth_theta_deg: None,
                        min_distance_mm: f64::INFINITY,
                        resolution_mm: scene.engagement_resolution_mm,
                    });
                    engagement.len() - 1
                }),
            })
            .collect::<Vec<PairState>>();
        let hot: Vec<usize> = (0..states.len())
            .filter(|&i| scene.pairs[i].kind == PairKind::Cutting)
            .collect();
        // σ only has to outgrow the pairs that are not hot.
        let states_w: Vec<[f64; 3]> = (0..states.len())
            .filter(|i| !hot.contains(i))
            .map(|i| states[i].weights)
            .collect();
        let n_pairs = states.len();
        let tilt_index = scene.tilt_axis.map(Axis::index);
        let table_index = scene.kinematics.layout.table_axis().map(Axis::index);
        SceneMonitor {
            scene,
            states,
            prev: None,
            events: Vec::new(),
            deepest_at: vec![None; engagement.len()],
            engagement,
            samples: 0,
            queries: 0,
            min_clearance_mm: f64::INFINITY,
            min_clearance_pair: None,
            theta_of: None,
            prev_relative: None,
            uses_relative: false,
            exhaustive: false,
            sum: [0.0; 3],
            w_max: [0, 1, 2].map(|k| states_max(&states_w, k)),
            next_due: f64::NEG_INFINITY,
            dues: vec![f64::NEG_INFINITY; n_pairs],
            is_hot: (0..n_pairs).map(|i| hot.contains(&i)).collect(),
            hot,
            tilt_index,
            table_index,
            deepest: DeepestCollisions::new(0),
        }
    }

    /// Keeps the scene (every body's shape and pose) at the deepest sample of the `n`
    /// deepest collisions, for a picture of them ([`super::snapshot`]).
    pub fn with_collision_poses(mut self, n: usize) -> SceneMonitor {
        self.deepest = DeepestCollisions::new(n);
        self
    }

    /// The tool tip in the machine frame at `q`, mm ([`Scene::tip_mm`]).
    pub fn tip_mm(&self, q: &AxisVec) -> [f64; 3] {
        self.scene.tip_mm(q)
    }

    /// Offers the collision `event` with its deepest sample to the kept pictures.
    fn offer_collision(&mut self, event: &SceneEvent, time_s: f64, q: &AxisVec) {
        if event.kind != EventKind::Collision || !self.deepest.admits(event.worst_mm, time_s) {
            return;
        }
        let axes = self
            .scene
            .kinematics
            .layout
            .axes()
            .iter()
            .map(|a| (a.to_string(), q[*a]))
            .collect();
        self.deepest.offer(CollisionPose {
            bodies: event.bodies.clone(),
            depth_mm: event.worst_mm,
            time_s,
            line: event.line,
            axes,
            tip_mm: self.scene.tip_mm(q),
            bodies_placed: self.scene.placed_bodies(q),
        });
    }

    /// Whether tool/table pairs use the relative-motion bound as well: fewer queries for two
    /// `sin_cos` and a bound per pair on every sample (off by default; docs/performance.md).
    pub fn with_relative_bounds(mut self, on: bool) -> SceneMonitor {
        self.uses_relative = on && self.states.iter().any(|s| s.relative.is_some());
        self
    }

    /// Queries every pair at every sample, with no bound skipping any: slow, the reference
    /// that the bounded monitor is tested against.
    pub fn exhaustive(mut self) -> SceneMonitor {
        self.exhaustive = true;
        self
    }

    /// Gives the monitor θ as a function of the axis positions, for [`SceneMonitor::push_at`]:
    /// θ is then computed only for the samples it reports.
    pub fn with_theta(mut self, theta_of: ThetaFn) -> SceneMonitor {
        self.theta_of = Some(theta_of);
        self
    }

    fn theta(&self, t: Theta, q: &AxisVec) -> Option<f64> {
        resolve_theta(&self.theta_of, t, q)
    }

    /// Changes the tool in the spindle between two samples ([`Scene::set_tool`]). The parts
    /// changed shape, so no clearance measured before holds: every pair is measured at the
    /// next sample, and no contact is searched for back across the change. The tool parts'
    /// reach from the tip (for the relative bound) is taken again.
    pub fn set_tool(&mut self, tool: &super::ToolConfig, tip_below_mm: f64) {
        self.scene.set_tool(tool, tip_below_mm);
        // Every pair is due at the next sample (no lazy skip past the change).
        self.next_due = f64::NEG_INFINITY;
        self.dues.fill(f64::NEG_INFINITY);
        if !self.scene.kinematics.has_closed_form() {
            // On a chain the tool parts' lever arms changed with the tool.
            for (i, state) in self.states.iter_mut().enumerate() {
                let pair = self.scene.pairs[i];
                let (wa, wb) = (
                    self.scene.parts[pair.a].motion,
                    self.scene.parts[pair.b].motion,
                );
                state.weights = [wa[0] + wb[0], wa[1] + wb[1], wa[2] + wb[2]];
            }
            let states_w: Vec<[f64; 3]> = (0..self.states.len())
                .filter(|i| !self.is_hot[*i])
                .map(|i| self.states[i].weights)
                .collect();
            self.w_max = [0, 1, 2].map(|k| states_max(&states_w, k));
        }
        for (i, state) in self.states.iter_mut().enumerate() {
            state.slack = 0.0;
            state.exit_slack = 0.0;
            state.plane = None;
            state.moved = 0.0;
            state.synced = self.sum;
            state.last_mm = 0.0;
            state.warm = Warm::default();
            if let Some((frame, _)) = state.relative {
                let pair = self.scene.pairs[i];
                let (a, b) = (&self.scene.parts[pair.a], &self.scene.parts[pair.b]);
                let tool = if a.carrier == Carrier::Tool { a } else { b };
                let aabb = tool.shape.compute_aabb(&tool.local);
                let reach = [aabb.mins, aabb.maxs]
                    .iter()
                    .flat_map(|x| [aabb.mins, aabb.maxs].map(|y| (x.x, y.y)))
                    .flat_map(|(x, y)| {
                        [aabb.mins.z, aabb.maxs.z].map(|z| (x * x + y * y + z * z).sqrt())
                    })
                    .fold(0.0, f64::max);
                state.relative = Some((frame, reach));
            }
        }
    }

    /// Geometric queries so far.
    pub fn queries(&self) -> u64 {
        self.queries
    }

    /// Starts another run: its first sample has no earlier one, so every pair is queried
    /// there and no motion is assumed across the seam between the runs.
    pub fn restart(&mut self) {
        self.prev = None;
        self.prev_relative = None;
    }

    /// One sample: time (s), angle on the nominal path (deg) if any, program line, axis
    /// positions (mm, deg). Samples with non-finite positions are ignored.
    #[inline]
    pub fn push(&mut self, time_s: f64, theta_deg: Option<f64>, line: usize, q: &AxisVec) {
        self.push_sample(time_s, Theta::Known(theta_deg), line, q);
    }

    /// One sample whose θ is computed, when needed, by the function of
    /// [`SceneMonitor::with_theta`] (none without it).
    #[inline]
    pub fn push_at(&mut self, time_s: f64, line: usize, q: &AxisVec) {
        self.push_sample(time_s, Theta::OfQ, line, q);
    }

    /// One sample. Most samples only advance the motion sums (this, inlined into the
    /// caller); those at which a pair may be due go on to [`SceneMonitor::visit_due`].
    #[inline]
    fn push_sample(&mut self, time_s: f64, theta: Theta, line: usize, q: &AxisVec) {
        // Written on the flat arrays: the `AxisVec` operators are not inlined across crates,
        // and this runs on every sample. Every lane is tested (no early exit), so that the
        // test is a few vector compares.
        let finite =
            q.0.iter()
                .fold(time_s.is_finite(), |ok, v| ok & v.is_finite());
        if !finite {
            return;
        }
        self.samples += 1;
        let step = self.prev.as_ref().map(|prev| self.motion(&prev.q, q));
        let relative = match self.uses_relative {
            true => self.relative_step(q, step),
            false => None,
        };
        // Sample by sample only the sums advance; the pairs are visited once σ reaches the
        // earliest time one of them may be due.
        let prev_sum = self.sum;
        if let Some(s) = step {
            for k in 0..3 {
                self.sum[k] += s[k];
            }
        }
        let sigma = dot3(&self.w_max, &self.sum);
        let allowance = 1e-12 * (1.0 + sigma);
        let lazy = step.is_some() && !self.exhaustive && !self.uses_relative;
        let now = Sample {
            time_s,
            theta,
            line,
            q: *q,
        };
        if lazy && sigma < self.next_due && !self.hot_due(allowance) {
            self.prev = Some(now);
            return;
        }
        let visit = Visit {
            step,
            prev_sum,
            relative,
            sigma,
            allowance,
        };
        self.visit_due(&visit, now, lazy);
    }

    /// The tool tip's motion relative to the table and cradle frames from the previous
    /// sample to `q`: chord and Ω per frame, |Δu| and U (for the relative-motion bound).
    #[inline(never)]
    fn relative_step(
        &mut self,
        q: &AxisVec,
        step: Option<[f64; 3]>,
    ) -> Option<([(f64, f64); 2], f64, f64)> {
        let u = Vector3::new(q[Axis::X], q[Axis::Y], q[Axis::Z]) - self.scene.kinematics.pivot_mm;
        let now = self.scene.kinematics.into_table_frames(q, u);
        let u_norm = u.norm();
        let mut relative = None;
        if let (Some((before, u_before)), Some(s)) = (self.prev_relative, step) {
            let omega = [s[1] + s[2], s[1]];
            relative = Some((
                [0, 1].map(|f| ((now[f] - before[f]).norm(), omega[f])),
                s[0],
                u_norm.max(u_before),
            ));
        }
        self.prev_relative = Some((now, u_norm));
        relative
    }

    /// Visits, at sample `now`, the pairs that may be due: only the hot ones while σ is
    /// short of the next due value of the others (`lazy`), else every pair σ has reached.
    #[inline(never)]
    fn visit_due(&mut self, visit: &Visit, now: Sample, lazy: bool) {
        let mut poses = BodyPoses::new(&now.q);
        let sigma = visit.sigma;
        if lazy && sigma < self.next_due {
            // Only a hot pair may be due: the others keep their sums and their σ.
            for h in 0..self.hot.len() {
                self.visit(self.hot[h], visit, &mut poses, &now);
            }
        } else {
            // A full visit brings up to date only the pairs that may be due (σ past their
            // own due value, and the hot pairs); the others keep their sums behind until a
            // later visit.
            let mut next_due = f64::INFINITY;
            let n = self.states.len();
            let mut i = 0;
            while i < n {
                // The pairs not due are skipped in a tight loop over the flat arrays (most
                // of them on most visits), keeping the earliest due value.
                {
                    let (dues, is_hot) = (&self.dues[..n], &self.is_hot[..n]);
                    while i < n && lazy && sigma < dues[i] && !is_hot[i] {
                        if dues[i] < next_due {
                            next_due = dues[i];
                        }
                        i += 1;
                    }
                }
                if i == n {
                    break;
                }
                self.visit(i, visit, &mut poses, &now);
                if self.dues[i] < next_due {
                    next_due = self.dues[i];
                }
                i += 1;
            }
            self.next_due = next_due;
        }
        self.prev = Some(now);
    }

    /// Brings pair `i` up to date at sample `now` and queries it when it is due.
    fn visit(&mut self, i: usize, v: &Visit, poses: &mut BodyPoses, now: &Sample) {
        let q = &now.q;
        let state = &mut self.states[i];
        if v.step.is_some() {
            let behind = [0, 1, 2].map(|k| v.prev_sum[k] - state.synced[k]);
            state.moved += dot3(&state.weights, &behind);
        }
        state.synced = self.sum;
        let mut pair_step = match v.step {
            Some(s) => state.weights[0] * s[0] + state.weights[1] * s[1] + state.weights[2] * s[2],
            None => f64::INFINITY,
        };
        if let (Some((frames, du, u_max)), Some((f, reach))) = (v.relative, state.relative) {
            let (chord, omega) = frames[f];
            let bound = chord + omega * reach + 2.0 * omega * du + omega * omega * (u_max + reach);
            pair_step = pair_step.min(bound);
        }
        let moved_before = state.moved;
        state.moved += pair_step;
        if let (Some(e), false, true) = (
            state.engagement,
            self.exhaustive,
            state.moved >= state.slack,
        ) {
            // A cutting pair whose warm-start bounds show that the query could change
            // nothing: no new deepest engagement or smallest distance (`lo` at or above the
            // smallest so far), and a slack of the resolution (`hi` within it). The query's
            // certified answer lies in `[lo, hi]`, so the report and the schedule are those
            // the query would give; it counts as one.
            let resolution = self.scene.engagement_resolution_mm;
            if let Some((lo, hi)) = self.scene.warm_bounds(i, poses, &state.warm) {
                if lo >= self.engagement[e].min_distance_mm && hi <= resolution {
                    self.queries += 1;
                    state.last_mm = lo;
                    state.moved = 0.0;
                    state.synced = self.sum;
                    state.slack = resolution;
                    self.dues[i] = f64::INFINITY;
                    return;
                }
            }
        }
        let state = &mut self.states[i];
        let due = state.moved >= state.slack && !self.certified(i, poses);
        let state = &mut self.states[i];
        if due || self.exhaustive {
            let pair = self.scene.pairs[i];
            let d = measure(&self.scene, i, poses, &mut state.warm);
            self.queries += 1;
            // Contact strictly between the previous sample and this one?
            if let (Some(prev), PairKind::Collision) = (self.prev, pair.kind) {
                let start_bound = self.states[i].last_mm - moved_before;
                if start_bound > 0.0 && d > 0.0 && start_bound + d < pair_step {
                    if let Some(s) = self.advance(i, &prev.q, q, start_bound, pair_step) {
                        self.record_contact_between(i, &prev, now, s);
                    }
                }
            }
            self.classify(i, now, d);
            let state = &self.states[i];
            // A pair the closed form of parallel prisms answers is measured again instead:
            // that costs no more than the plane bound, and is exact.
            let plane = match (&state.open, self.exhaustive, state.warm.prism) {
                (Some(_), false, false) => self.scene.plane_bound(i, state.warm.gjk, poses),
                _ => None,
            };
            self.states[i].plane = plane;
        }
        // σ does not wait for a hot pair (its own bound is checked at every sample). Less a
        // rounding allowance on the sums.
        let state = &self.states[i];
        self.dues[i] = match self.is_hot[i] {
            true => f64::INFINITY,
            false => v.sigma + (state.slack - state.moved) - v.allowance,
        };
    }

    /// Whether pair `i`, due by its lever-arm bound, is shown by its plane bound to stay in
    /// its event with no new worst value at this sample: its bound is short of the event's
    /// end (`exit_slack`) and the plane bound keeps the signed distance at or above the
    /// event's worst (less [`PLANE_TOLERANCE_MM`]). The next look is due once the lever-arm
    /// bound could take up the plane bound's margin.
    fn certified(&mut self, i: usize, poses: &mut BodyPoses) -> bool {
        let state = &self.states[i];
        let (Some(open), Some(plane)) = (&state.open, &state.plane) else {
            return false;
        };
        if state.moved >= state.exit_slack {
            return false;
        }
        // A collision's floor is its worst depth less the depth tolerance: a sample within
        // the tolerance of the worst adds nothing the report must show.
        let floor = match open.kind {
            EventKind::Collision => -open.worst_mm - self.scene.depth_tolerance().at(open.worst_mm),
            EventKind::NearMiss => open.worst_mm,
        };
        let lower = self.scene.plane_lower(i, poses, plane);
        if lower < floor - PLANE_TOLERANCE_MM {
            return false;
        }
        let state = &mut self.states[i];
        state.slack = state.exit_slack.min(state.moved + (lower - floor).max(0.0));
        true
    }

    /// Whether a hot pair may be due at this sample: its own bound since its last visit,
    /// `moved + w·(S - S_synced)`, against its slack (less `allowance` for rounding).
    #[inline]
    fn hot_due(&self, allowance: f64) -> bool {
        self.hot.iter().any(|&i| {
            let s = &self.states[i];
            let behind = [0, 1, 2].map(|k| self.sum[k] - s.synced[k]);
            s.moved + dot3(&s.weights, &behind) >= s.slack - allowance
        })
    }

    /// Ends the run.
    pub fn finish(mut self) -> SceneReport {
        for i in 0..self.states.len() {
            self.close_open(i);
        }
        self.events
            .sort_by(|a, b| a.time_start_s.total_cmp(&b.time_start_s));
        for (summary, deepest) in self.engagement.iter_mut().zip(&self.deepest_at) {
            if let Some((theta, q)) = deepest {
                summary.max_depth_theta_deg = resolve_theta(&self.theta_of, *theta, q);
            }
        }
        SceneReport {
            events: self.events,
            engagement: self.engagement,
            near_miss_mm: self.scene.near_miss_mm,
            depth_tolerance: self.scene.depth_tolerance(),
            min_clearance_mm: self.min_clearance_mm,
            min_clearance_bodies: self
                .min_clearance_pair
                .map(|i| self.scene.pair_bodies(&self.scene.pairs[i])),
            samples: self.samples,
            queries: self.queries,
            collision_poses: self.deepest.into_vec(),
        }
    }

    /// |dXYZ| (mm), |d tilt| (rad), |dC| (rad) between two samples; on a general chain
    /// Σ|Δq| over its linear axes (mm) and its rotaries (rad), and 0 ([`super::linked`]).
    #[inline]
    fn motion(&self, a: &AxisVec, b: &AxisVec) -> [f64; 3] {
        if let Some(m) = self.scene.chain_motion(a, b) {
            return m;
        }
        let (a, b) = (&a.0, &b.0);
        let d = |i: usize| b[i] - a[i];
        let lin = (d(0).powi(2) + d(1).powi(2) + d(2).powi(2)).sqrt();
        let tilt = self.tilt_index.map_or(0.0, |t| d(t).abs().to_radians());
        let table = self.table_index.map_or(0.0, |t| d(t).abs().to_radians());
        [lin, tilt, table]
    }

    /// Conservative advancement of pair `i` along the interval `a -> b`, whose motion bound
    /// is `bound` mm, from a clearance lower bound `start` at `a`. Returns the fraction of
    /// the interval at which contact is found.
    fn advance(
        &mut self,
        i: usize,
        a: &AxisVec,
        b: &AxisVec,
        start: f64,
        bound: f64,
    ) -> Option<f64> {
        let mut s = start / bound;
        let mut warm = self.states[i].warm;
        for _ in 0..MAX_ADVANCE_STEPS {
            if s >= 1.0 {
                return None;
            }
            let q = *a + (*b - *a) * s;
            let d = measure(&self.scene, i, &mut BodyPoses::new(&q), &mut warm);
            self.queries += 1;
            if d <= CONTACT_TOLERANCE_MM {
                return Some(s);
            }
            s += d / bound;
        }
        None
    }

    fn record_contact_between(&mut self, i: usize, prev: &Sample, now: &Sample, s: f64) {
        let time = prev.time_s + s * (now.time_s - prev.time_s);
        let theta = match (
            self.theta(prev.theta, &prev.q),
            self.theta(now.theta, &now.q),
        ) {
            (Some(a), Some(b)) => Some(a + s * (b - a)),
            (_, b) => b,
        };
        let bodies = self.scene.pair_bodies(&self.scene.pairs[i]);
        self.close_open(i);
        let event = SceneEvent {
            kind: EventKind::Collision,
            bodies,
            time_start_s: time,
            time_end_s: time,
            theta_start_deg: theta,
            theta_end_deg: theta,
            line: now.line,
            worst_mm: 0.0,
        };
        self.offer_collision(&event, time, &(prev.q + (now.q - prev.q) * s));
        self.events.push(event);
    }

    /// Ends pair `i`'s open event, if any, resolving its last θ. The samples the pair was
    /// not measured at since its last query were in the event (its slack says so, see
    /// [`SceneMonitor::classify`]), so the event lasts up to the sample before the one that
    /// closes it (at the end of the run: the last sample).
    fn close_open(&mut self, i: usize) {
        if let Some(mut event) = self.states[i].open.take() {
            let (mut theta, mut q) = self.states[i].open_end;
            if let Some(prev) = self.prev.filter(|p| p.time_s > event.time_end_s) {
                event.time_end_s = prev.time_s;
                (theta, q) = (prev.theta, prev.q);
            }
            event.theta_end_deg = self.theta(theta, &q);
            let (time, q) = self.states[i].deepest_sample;
            self.offer_collision(&event, time, &q);
            self.events.push(event);
        }
    }

    /// Updates pair `i`'s event and query schedule with the clearance `d` measured at `now`.
    fn classify(&mut self, i: usize, now: &Sample, d: f64) {
        let threshold = self.scene.near_miss_mm;
        let resolution = self.scene.engagement_resolution_mm;
        let state = &mut self.states[i];
        state.last_mm = d;
        state.moved = 0.0;
        state.synced = self.sum;
        if let Some(e) = state.engagement {
            state.slack = d.max(resolution);
            let summary = &mut self.engagement[e];
            summary.min_distance_mm = summary.min_distance_mm.min(d);
            if -d > summary.max_depth_mm {
                summary.max_depth_mm = -d;
                summary.max_depth_time_s = Some(now.time_s);
                self.deepest_at[e] = Some((now.theta, now.q));
            }
            return;
        }
        state.slack = d - threshold;
        if d < self.min_clearance_mm {
            self.min_clearance_mm = d;
            self.min_clearance_pair = Some(i);
        }
        let kind = if d <= 0.0 {
            Some(EventKind::Collision)
        } else if d < threshold {
            Some(EventKind::NearMiss)
        } else {
            None
        };
        let worst = |kind: EventKind| match kind {
            EventKind::Collision => -d,
            EventKind::NearMiss => d,
        };
        match (&mut state.open, kind) {
            (Some(open), Some(k)) if open.kind == k => {
                open.time_end_s = now.time_s;
                state.open_end = (now.theta, now.q);
                if k == EventKind::Collision && -d > open.worst_mm {
                    state.deepest_sample = (now.time_s, now.q);
                }
                open.worst_mm = match k {
                    EventKind::Collision => open.worst_mm.max(-d),
                    EventKind::NearMiss => open.worst_mm.min(d),
                };
            }
            (_, kind) => {
                self.close_open(i);
                let theta = self.theta(now.theta, &now.q);
                let state = &mut self.states[i];
                state.open_end = (Theta::Known(theta), now.q);
                state.deepest_sample = (now.time_s, now.q);
                state.open = kind.map(|k| SceneEvent {
                    kind: k,
                    bodies: self.scene.pair_bodies(&self.scene.pairs[i]),
                    time_start_s: now.time_s,
                    time_end_s: now.time_s,
                    theta_start_deg: theta,
                    theta_end_deg: theta,
                    line: now.line,
                    worst_mm: worst(k),
                });
            }
        }
        // Inside an event the pair need not be measured again until its bound `m` could
        // change the event: a collision (`d <= 0`, deepest `W`) stays one while `m < -d`, with
        // no new deepest sample while `m < W + d`; a near miss (`0 < d < T`, smallest `w`)
        // stays one while `m < min(T - d, d)`, with no new smallest clearance while
        // `m < d - w`. Past the second, the plane bound may still show it ([`Self::certified`]).
        let state = &mut self.states[i];
        if let Some(open) = &state.open {
            let (exit, worst) = match open.kind {
                EventKind::Collision => {
                    let tolerance = self.scene.depth_tolerance().at(open.worst_mm);
                    (-d, open.worst_mm + d + tolerance)
                }
                EventKind::NearMiss => ((threshold - d).min(d), d - open.worst_mm),
            };
            state.exit_slack = exit;
            state.slack = exit.min(worst);
        }
    }
}

/// θ of a sample with axis positions `q`: `t` when known, else `theta_of(q)` (none without).
fn resolve_theta(theta_of: &Option<ThetaFn>, t: Theta, q: &AxisVec) -> Option<f64> {
    match t {
        Theta::Known(v) => v,
        Theta::OfQ => theta_of.as_ref().and_then(|f| f(q)),
    }
}

fn dot3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn states_max(weights: &[[f64; 3]], k: usize) -> f64 {
    weights.iter().map(|w| w[k]).fold(0.0, f64::max)
}

/// Signed distance of pair `i` with the bodies at `poses`.
fn measure(scene: &Scene, i: usize, poses: &mut BodyPoses, warm: &mut Warm) -> f64 {
    let pair = scene.pairs[i];
    let (a, b) = (&scene.parts[pair.a], &scene.parts[pair.b]);
    let pose_a = scene.body_pose(a.carrier as usize, poses) * a.local;
    let pose_b = scene.body_pose(b.carrier as usize, poses) * b.local;
    super::pair_distance(&pair, a, b, &pose_a, &pose_b, warm)
}
