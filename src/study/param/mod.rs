//! **study::param** — `mtsim study`: the servo simulation over any scenario or machine key.
//! Inputs: a study file (base scenario, keys by dotted path, grid or random sampling).
//! Outputs: one row per point (G, F, H, B and spikes per axis, check verdict, status), its summary, plots and page.

pub mod evaluate;
pub mod outputs;
pub mod page;
pub mod plots;
pub mod random;
pub mod spec;
pub mod stats;
pub mod summary;
pub mod table;

use std::path::Path;

use crate::error::Result;
use crate::input::overrides::ScenarioTree;
use evaluate::Row;
use spec::StudySpec;

pub use outputs::write_outputs;
pub use summary::{StudyHeader, StudySummary};

/// A study ready to run: its spec, the base scenario's tree, the machine's axes and points.
#[derive(Clone, Debug)]
pub struct Study {
    pub spec: StudySpec,
    pub tree: ScenarioTree,
    pub header: StudyHeader,
    pub points: Vec<Vec<f64>>,
}

impl Study {
    /// Loads the study file and its base scenario, makes the points, and checks that every
    /// key names a key of the scenario or its machine (with the first point's values).
    /// `samples` replaces a random study's `samples` (a smaller trial run of the same study).
    pub fn load(path: &Path, g_limit_um: Option<f64>, samples: Option<usize>) -> Result<Study> {
        let mut spec = StudySpec::load(path)?;
        if let Some(n) = samples {
            if !spec.random || !(1..=spec::MAX_POINTS).contains(&n) {
                return Err(crate::error::Error::usage(format!(
                    "--samples {n}: expected 1 to {} points of a random study (uniform, normal)",
                    spec::MAX_POINTS
                )));
            }
            spec.file.samples = Some(n);
        }
        let tree = ScenarioTree::read(&spec.scenario)?;
        let points = spec.points();
        if let Some(first) = points.first() {
            // A bad path fails at every point: say so once, up front. A bad value is the
            // point's own failure, so only "names no key" errors stop the study here.
            // A key the trees do not hold whose first point fails is a bad path too.
            if let Err(e) = tree.load_with(&spec.keys(), first) {
                if matches!(e, crate::error::Error::Usage { .. }) {
                    return Err(e);
                }
                // An error that names the key is about its value: the point's own failure.
                let message = e.to_string();
                let names_it = |k: &crate::input::overrides::KeyPath| {
                    let path = k.to_string();
                    message.contains(path.strip_prefix("machine.").unwrap_or(&path))
                };
                if let Some((key, (depth, near))) = spec
                    .keys()
                    .iter()
                    .filter(|k| !names_it(k))
                    .find_map(|k| Some((k, tree.absent(k)?)))
                {
                    return Err(crate::error::Error::usage(format!(
                        "study key `{key}` names no key of the scenario {} or its machine ({e}); nearest: {}",
                        tree.path.display(),
                        crate::input::overrides::nearest_keys(key, depth, &near)
                    )));
                }
            }
        }
        let header = StudyHeader {
            keys: spec.keys().iter().map(ToString::to_string).collect(),
            axes: tree
                .base
                .machine
                .axes()
                .iter()
                .map(ToString::to_string)
                .collect(),
            g_limit_um: g_limit_um.or(spec.file.g_limit_um),
            study: spec.file.clone(),
        };
        Ok(Study {
            spec,
            tree,
            header,
            points,
        })
    }

    /// The rows of the points `range` (0-based), run in parallel; `done` is told of each.
    pub fn run(&self, range: std::ops::Range<usize>, done: &(dyn Fn() + Sync)) -> Vec<Row> {
        evaluate::evaluate(
            &self.tree,
            &self.spec.keys(),
            &self.header.axes,
            &self.points,
            range,
            done,
        )
    }
}
