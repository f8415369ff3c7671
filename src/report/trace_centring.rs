//! Where a trace's centre is, and how a reader applies it: the centred deviation
//! `dL - (a cos θ + b sin θ)` of a row, with the least-squares centring `(a, b)` of its run
//! ([`RunCentring`]), which the trace keeps beside its rows, not in a column (the fit is
//! known only at the run's end: [`super::trace`]). `trace.parquet` holds each run's centring
//! in its key-value metadata under [`CENTRING_KEY`] ([`parquet_centrings`]); `trace.csv`
//! leaves it to `summary.json` beside it ([`summary_centrings`]). Runs are matched to
//! centrings by [`centring_per_run`].

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::input::program::Direction;
use crate::measure::ballbar::{theta_sin_cos, Centring};

/// The key of `trace.parquet`'s key-value metadata that holds each run's centring.
pub const CENTRING_KEY: &str = "mtsim.centring";

/// The column every reader adds: dL less the run's centring ([`centred_deviation_um`]).
pub const CENTRED_COLUMN: &str = "deviation_centred_um";

/// One run's centring as the trace's metadata gives it: the direction of its rows and the
/// least-squares fit `dL = r0 + a cos θ + b sin θ` of its ball bar, µm.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunCentring {
    pub direction: Direction,
    pub a_um: f64,
    pub b_um: f64,
    pub r0_um: f64,
}

impl RunCentring {
    fn centring(&self) -> Centring {
        Centring {
            r0_um: self.r0_um,
            a_um: self.a_um,
            b_um: self.b_um,
        }
    }
}

/// The centred deviation of a row, µm: `dL - (a cos θ + b sin θ)` with its run's centring
/// (dL itself for a run without one, as a part program's trace), θ in deg.
#[inline]
pub fn centred_deviation_um(
    deviation_um: f64,
    theta_deg: f64,
    centring: Option<&RunCentring>,
) -> f64 {
    match centring {
        Some(c) => deviation_um - c.centring().offset_um_at(theta_sin_cos(theta_deg)),
        None => deviation_um,
    }
}

/// Each run's centring for rows in the order of `directions` (a run is a stretch of rows of
/// one direction): the run's entry is the next one of `centrings`, in run order, of its
/// direction (None when there is none: a run without a ball bar).
pub fn centring_per_run<'a>(
    directions: impl Iterator<Item = Direction>,
    centrings: &'a [RunCentring],
) -> Vec<Option<&'a RunCentring>> {
    let mut next = 0;
    directions
        .map(|d| {
            let found = centrings[next..].iter().position(|c| c.direction == d);
            found.map(|k| {
                next += k + 1;
                &centrings[next - 1]
            })
        })
        .collect()
}

/// The centrings of the runs of `summary.json` in `dir` (`ballbar.runs[k]`: `direction`
/// and `centring`), for `trace.csv`; none without the file or a ball bar.
pub(super) fn summary_centrings(dir: &Path) -> Result<Vec<RunCentring>> {
    let path = dir.join(super::files::SUMMARY_FILE);
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Ok(Vec::new());
    };
    let bad = |what: String| Error::invalid(&path, what);
    let doc: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| bad(format!("not JSON: {e}")))?;
    let runs = doc["ballbar"]["runs"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    runs.iter()
        .map(|run| {
            let mut entry = run["centring"].clone();
            entry["direction"] = run["direction"].clone();
            serde_json::from_value(entry)
                .map_err(|e| bad(format!("a ball-bar run without its centring: {e}")))
        })
        .collect()
}

/// The centrings in `trace.parquet`'s key-value metadata ([`CENTRING_KEY`]); none when the
/// key is absent (a part program's trace).
pub fn parquet_centrings(
    key_value: Option<&Vec<parquet::file::metadata::KeyValue>>,
) -> std::result::Result<Vec<RunCentring>, String> {
    let entry = key_value.and_then(|kv| kv.iter().find(|e| e.key == CENTRING_KEY));
    match entry.and_then(|e| e.value.as_deref()) {
        None => Ok(Vec::new()),
        Some(json) => serde_json::from_str(json).map_err(|e| {
            format!("the key-value metadata `{CENTRING_KEY}` is not a list of centrings: {e}")
        }),
    }
}
