//! Many ball-bar points at once: the points of a study that share their program share its
//! reading, planning and interpolation.
//!
//! [`run_ballbar_lanes`] groups the scenarios by [`share_key`]: everything but each axis's
//! servo, drive and friction tables (gains, feedforward, masses, stiffness, backlash,
//! friction). A group's points differ only in how their drives answer the same setpoints, so
//! one interpolation pass per direction feeds the points' drives
//! ([`crate::pipeline::run_lanes`]), and points whose drive (or linear twin) on an axis is
//! the same share that axis's servo ([`crate::drive::DriveLanes`]). Each point keeps what
//! depends on its drives: its position-error state, ball bars, settle gate and reversal
//! sites. Memory holds the state of the points in one pass, never the setpoint stream.
//!
//! A group runs in passes of at most [`POINTS_PER_PASS`] points; passes run in parallel on
//! the rayon pool. A point whose drives diverge (or whose bar reads a deviation that is not
//! finite: it cannot take the θ sums its pass keeps once), or a pass that fails as a whole,
//! is run alone by [`run_ballbar`]: every result is the single run's.

use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::mpsc;

use rayon::prelude::*;

use crate::error::Result;
use crate::input::scenario::Scenario;
use crate::input::Machine;
use crate::measure::attribution::SharedSites;
use crate::measure::settle::SettleGate;
use crate::measure::shared::{SharedBallbar, SharedReadings};
use crate::measure::BallbarSink;
use crate::pipeline::{self, Sample, Sink};
use crate::program;
use crate::study::lost_motion::SharedRegressors;
use crate::study::simulate::{
    analysed_along, analyses, assemble, ballbar_sink, bar_geometry, directions_of, gates_transient,
    merge_reductions, run_ballbar, run_options, transient_warning, BallbarStudy, SharedRuns,
};

/// Most points in one interpolation pass: enough that the pass's own cost is a small share
/// of the point's, few enough that the passes of a large group spread over the cores.
pub const POINTS_PER_PASS: usize = 64;

/// The ball-bar study of every scenario, as [`run_ballbar`] gives it (without a trace): the
/// i-th result is `run_ballbar(&scenarios[i], None, ..)`'s. `progress` is told the machine
/// time simulated so far, s, summed over the points.
pub fn run_ballbar_lanes(
    scenarios: &[Scenario],
    progress: &dyn Fn(f64),
) -> Vec<Result<BallbarStudy>> {
    // One point shares with nothing: its single run, without a pool or a thread of its own.
    if let [scenario] = scenarios {
        return vec![run_ballbar(scenario, None, progress)];
    }
    run_ballbar_lanes_keyed(scenarios, &share_keys(scenarios), progress)
}

/// [`run_ballbar_lanes`] with each scenario's [`share_key`] made by the caller (`keys[i]`
/// is `share_key(&scenarios[i])`'s), for a caller that needs them too.
pub fn run_ballbar_lanes_keyed(
    scenarios: &[Scenario],
    keys: &[String],
    progress: &dyn Fn(f64),
) -> Vec<Result<BallbarStudy>> {
    if let [scenario] = scenarios {
        return vec![run_ballbar(scenario, None, progress)];
    }
    let passes = passes_keyed(scenarios, keys, rayon::current_num_threads());
    let (sender, receiver) = mpsc::channel::<f64>();
    // The passes run on a pool as wide as the caller's, from a thread of their own, so
    // that this thread can hand their progress to `progress` (which need not be `Sync`).
    let threads = rayon::current_num_threads();
    let studies: Vec<Vec<Option<BallbarStudy>>> = std::thread::scope(|scope| {
        let worker = scope.spawn(|| {
            let run = || {
                passes
                    .par_iter()
                    .map_with(sender, |sender, points| {
                        let told = Cell::new(0.0);
                        let tell = |t: f64| {
                            let _ = sender.send((t - told.replace(t)) * points.len() as f64);
                        };
                        run_pass(scenarios, points, &tell)
                            .unwrap_or_else(|_| (0..points.len()).map(|_| None).collect())
                    })
                    .collect()
            };
            match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
                Ok(pool) => pool.install(run),
                Err(_) => run(),
            }
        });
        let mut total = 0.0;
        for dt in receiver {
            total += dt;
            progress(total);
        }
        worker.join().expect("a study pass panicked")
    });
    let mut out: Vec<Option<BallbarStudy>> = (0..scenarios.len()).map(|_| None).collect();
    for (points, studies) in passes.iter().zip(studies) {
        for (&i, study) in points.iter().zip(studies) {
            out[i] = study;
        }
    }
    out.into_par_iter()
        .enumerate()
        .map(|(i, study)| match study {
            Some(study) => Ok(study),
            None => run_ballbar(&scenarios[i], None, &|_| {}),
        })
        .collect()
}

/// The key of what a scenario's points share: the scenario with each axis's servo, drive
/// and friction tables at their defaults, in its debug form (exact for f64). Two scenarios
/// with the same key run the same setpoints; anything not known to be drive-side (the
/// kinematics and its location errors, the program, the position-error tables) stays in
/// the key, so a scenario that differs there is its own group. The scenario's and machine's
/// paths are left out: they name the files in messages, and a pass that fails is run point by point.
pub fn share_key(scenario: &Scenario) -> String {
    let mut bare = scenario.clone();
    bare.machine = scenario.machine.with_default_drives();
    // The paths name the files in messages only; a pass that fails runs its points alone.
    bare.path = Default::default();
    bare.machine.path = Default::default();
    format!("{bare:?}")
}

/// The scenarios' indices grouped by [`share_key`] (in order of first appearance), each
/// group cut into passes of at most [`POINTS_PER_PASS`] points and of equal sizes (±1), as
/// many as a multiple of `threads` where the group has that many points, so that the
/// threads finish together. A group of more than a full pass a thread takes, of the counts
/// up to twice the fewest, the cut whose passes share the most drives ([`pass_cost`]): a
/// grid of 100 points per kv runs in passes of 50 that each hold one kv, not of 62 or 63
/// of which half straddle two.
pub fn passes(scenarios: &[Scenario], threads: usize) -> Vec<Vec<usize>> {
    passes_keyed(scenarios, &share_keys(scenarios), threads)
}

/// Every scenario's [`share_key`], made in parallel (a scenario's debug form each: made one
/// by one, they were the study's only serial work of note).
pub fn share_keys(scenarios: &[Scenario]) -> Vec<String> {
    scenarios.par_iter().map(share_key).collect()
}

/// [`passes`] with the scenarios' [`share_key`]s given.
fn passes_keyed(scenarios: &[Scenario], keys: &[String], threads: usize) -> Vec<Vec<usize>> {
    let mut group_of: HashMap<&str, usize> = HashMap::new();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (i, key) in keys.iter().enumerate() {
        let g = *group_of.entry(key).or_insert_with(|| {
            groups.push(Vec::new());
            groups.len() - 1
        });
        groups[g].push(i);
    }
    let threads = threads.max(1);
    groups
        .into_iter()
        .flat_map(|group| -> Vec<Vec<usize>> {
            let mut fewest = group.len().div_ceil(POINTS_PER_PASS);
            if group.len() >= threads {
                fewest = fewest.next_multiple_of(threads);
            }
            // At most a full pass a thread (a few points, a chunk of `mtsim study`): the
            // fewest passes, without an estimate.
            if group.len() <= POINTS_PER_PASS * threads {
                return cut(&group, fewest).map(<[usize]>::to_vec).collect();
            }
            let ids: Vec<Vec<DriveIds>> = group
                .par_iter()
                .map(|&i| drive_ids(&scenarios[i].machine))
                .collect();
            let cost = |count: usize| -> f64 {
                let mut at = 0;
                cut(&group, count)
                    .map(|pass| {
                        at += pass.len();
                        pass_cost(&ids[at - pass.len()..at])
                    })
                    .sum()
            };
            let mut best = (fewest, cost(fewest));
            for count in (fewest + threads..=(2 * fewest).min(group.len())).step_by(threads) {
                let c = cost(count);
                if c < best.1 {
                    best = (count, c);
                }
            }
            cut(&group, best.0).map(<[usize]>::to_vec).collect()
        })
        .collect()
}

/// `group` cut into `count` passes of equal sizes, the first `len % count` one point larger.
fn cut(group: &[usize], count: usize) -> impl Iterator<Item = &[usize]> {
    let (size, larger) = (group.len() / count, group.len() % count);
    let mut rest = group;
    (0..count).map(move |k| {
        let (pass, next) = rest.split_at(size + usize::from(k < larger));
        rest = next;
        pass
    })
}

/// Per axis of a machine, hashes of its drive's and its linear twin's validated form: the
/// points of a pass with the same hashes share that axis's servos ([`DriveLanes`],
/// which compares the forms themselves). Only [`pass_cost`] reads them.
///
/// [`DriveLanes`]: crate::drive::DriveLanes
type DriveIds = (u64, u64);

fn drive_ids(machine: &Machine) -> Vec<DriveIds> {
    let hash = |text: String| {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        text.hash(&mut h);
        h.finish()
    };
    let period = machine.interpolation_period_s;
    machine
        .axes()
        .iter()
        .map(|&a| {
            let d = machine.drive(a);
            (
                hash(format!("{period:?} {d:?}")),
                hash(format!("{period:?} {:?}", d.linear_twin())),
            )
        })
        .collect()
}

/// What a pass costs, roughly (`ids`: its points' [`drive_ids`]), in millions of
/// instructions of the 15/10 cone: the pass's reading, planning and interpolation, each
/// point's ball bar and samples, and each distinct nonlinear drive and linear twin of an
/// axis (weights from profiles: docs/performance.md).
fn pass_cost(ids: &[Vec<DriveIds>]) -> f64 {
    const PASS: f64 = 100.0;
    const POINT: f64 = 18.0;
    const DRIVE: f64 = 25.0;
    const TWIN: f64 = 6.0;
    let axes = ids.first().map_or(0, Vec::len);
    let distinct = |of: &dyn Fn(&[DriveIds]) -> u64| {
        let mut seen: Vec<u64> = ids.iter().map(|ids| of(ids)).collect();
        seen.sort_unstable();
        seen.dedup();
        seen.len() as f64
    };
    let (mut drives, mut twins) = (0.0, 0.0);
    for a in 0..axes {
        drives += distinct(&|ids| ids[a].0);
        twins += distinct(&|ids| ids[a].1);
    }
    PASS + POINT * ids.len() as f64 + DRIVE * drives + TWIN * twins
}

/// One interpolation pass per direction for the scenarios `points` (one group): each
/// point's study, or None for a point to run alone (its drives failed). An error is the
/// pass's as a whole.
fn run_pass(
    scenarios: &[Scenario],
    points: &[usize],
    progress: &dyn Fn(f64),
) -> Result<Vec<Option<BallbarStudy>>> {
    let first = &scenarios[points[0]];
    let machines: Vec<&Machine> = points.iter().map(|&i| &scenarios[i].machine).collect();
    let (along, analysis) = analyses(first)?;
    let geometry = bar_geometry(first);
    let directions = directions_of(first);
    let n = points.len();
    let mut ballbars: Vec<Vec<BallbarSink>> = (0..n).map(|_| Vec::new()).collect();
    let mut warnings: Vec<Vec<String>> = vec![Vec::new(); n];
    let mut failed = vec![false; n];
    let (mut sim_time_s, mut setpoints, mut feed_reductions) = (0.0, 0u64, Vec::new());
    // Without a settle gate every bar takes every sample: their first run's command maps
    // are the same, kept once for all (`SharedReadings::with_maps`).
    let gated = gates_transient(first);
    let mut common_maps = None;
    for (k, &direction) in directions.iter().enumerate() {
        let mut run = program::scenario_run(first, direction, first.simulate.lead_deg)?;
        if let Some(along) = &along {
            run.moves = analysed_along(run.moves, along);
        }
        let options = run_options(first, sim_time_s)?;
        let mut bars: Vec<BallbarSink> = match geometry {
            Some(g) => (0..n)
                .map(|_| match ballbar_sink(g, direction, run.measured, k) {
                    bar if gated => bar,
                    bar => bar.without_maps(),
                })
                .collect(),
            None => Vec::new(),
        };
        let (stats, dead) = match geometry {
            None => {
                let mut discard: Vec<Discard> = (0..n).map(|_| Discard).collect();
                let mut sinks: Vec<&mut dyn Sink> =
                    discard.iter_mut().map(|d| d as &mut dyn Sink).collect();
                pipeline::run_lanes(run.moves, &machines, &options, &mut sinks, progress)?
            }
            Some(g) => {
                // The points' bars read each setpoint (and each table ball their rotaries
                // share) once for all.
                // Without a settle gate every bar takes every sample: their θ sums and feed
                // too are kept once for all (`SharedReadings::with_theta_sums`).
                let readings = match gated {
                    true => SharedReadings::new(g),
                    false => SharedReadings::new(g).with_theta_sums(direction),
                };
                let readings = RefCell::new(match k == 0 && !gated {
                    true => readings.with_maps(),
                    false => readings,
                });
                let mut shared: Vec<SharedBallbar<'_>> = bars
                    .iter_mut()
                    .map(|bar| SharedBallbar {
                        bar,
                        readings: &readings,
                    })
                    .collect();
                let ran = if gated {
                    let theta_deg = |s: &Sample| readings.borrow_mut().read_commanded(s).theta_deg;
                    let mut gates: Vec<SettleGate<'_>> = shared
                        .iter_mut()
                        .map(|bar| {
                            SettleGate::new(
                                vec![bar as &mut dyn Sink],
                                run.measured,
                                Box::new(theta_deg),
                            )
                        })
                        .collect();
                    let mut sinks: Vec<&mut dyn Sink> =
                        gates.iter_mut().map(|g| g as &mut dyn Sink).collect();
                    let ran =
                        pipeline::run_lanes(run.moves, &machines, &options, &mut sinks, progress)?;
                    for (w, gate) in warnings.iter_mut().zip(&gates) {
                        w.extend(transient_warning(gate));
                    }
                    ran
                } else {
                    let mut sinks: Vec<&mut dyn Sink> =
                        shared.iter_mut().map(|b| b as &mut dyn Sink).collect();
                    pipeline::run_lanes(run.moves, &machines, &options, &mut sinks, progress)?
                };
                drop(shared);
                let readings = readings.into_inner();
                // A bar with a deviation of its own not finite runs alone.
                for (f, bar) in failed.iter_mut().zip(&mut bars) {
                    *f |= !readings.complete(bar);
                }
                if k == 0 {
                    common_maps = readings.into_maps();
                }
                ran
            }
        };
        for (f, d) in failed.iter_mut().zip(dead) {
            *f |= d;
        }
        sim_time_s = stats.end_time_s;
        setpoints += stats.samples;
        merge_reductions(&mut feed_reductions, stats.feed_reductions);
        for (mine, bar) in ballbars.iter_mut().zip(bars) {
            mine.push(bar);
        }
    }
    let shared = SharedRuns::new(
        &first.machine,
        (along, analysis),
        directions,
        sim_time_s,
        setpoints,
        feed_reductions,
    );
    // The points on the pass's common maps share the reversal-value fit's regressors.
    let regressors = SharedRegressors::default();
    // And their reversal sites, for each set of slow-zone limits.
    let sites = SharedSites::default();
    Ok(points
        .iter()
        .zip(ballbars)
        .zip(warnings)
        .zip(failed)
        .map(|(((&i, mut bars), warnings), failed)| {
            if failed {
                return None;
            }
            let own = bars.first_mut().and_then(|b| b.maps.take());
            let maps = own.as_ref().or(common_maps.as_ref());
            let pass = own.is_none().then_some((&regressors, &sites));
            assemble(
                &scenarios[i],
                bars,
                maps,
                warnings,
                &shared,
                (pass.map(|p| p.0), pass.map(|p| p.1)),
            )
            .ok()
        })
        .collect())
}

/// A sink that keeps nothing: a point without a measured circle (a file program without a
/// cone) has nothing to measure.
struct Discard;

impl Sink for Discard {
    fn push(&mut self, _: &Sample) -> Result<()> {
        Ok(())
    }
}
