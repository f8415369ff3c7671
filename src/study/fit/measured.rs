//! A measured ball-bar trace, read from CSV: θ, deviation and direction, plus the commanded
//! axis positions and time when the trace carries them (mtsim's `trace.csv` does).
//! Inputs: the CSV file. Output: [`MeasuredTrace`], checked against its scenario later.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::input::program::Direction;
use crate::{Axis, AxisVec};

/// One point of a measured trace.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeasuredPoint {
    pub theta_deg: f64,
    pub deviation_um: f64,
    pub direction: Direction,
    /// Time, s (column `time_s`), when the trace carries it.
    pub time_s: Option<f64>,
    /// Commanded axis positions, mm and deg (columns `X_cmd_mm` ... `C_cmd_deg`); NaN for
    /// an axis the trace does not carry.
    pub commanded: AxisVec,
}

/// A measured trace: CSV with `theta_deg`, `deviation_um` and optionally `direction`,
/// `time_s` and the commanded columns `<axis>_cmd_<unit>`.
#[derive(Clone, Debug)]
pub struct MeasuredTrace {
    pub path: PathBuf,
    pub points: Vec<MeasuredPoint>,
    /// The axes whose commanded column the trace carries.
    pub commanded_axes: Vec<Axis>,
}

const HELP: &str = "give a CSV with columns theta_deg, deviation_um and optionally direction \
                    (mtsim's trace.csv is one)";

/// The columns a trace's header names.
struct Columns {
    theta: usize,
    deviation: usize,
    direction: Option<usize>,
    time: Option<usize>,
    commanded: Vec<(Axis, usize)>,
}

impl Columns {
    fn of(path: &Path, header: &str) -> Result<Columns> {
        let cols: Vec<&str> = header.split(',').map(str::trim).collect();
        let find = |name: &str| cols.iter().position(|c| *c == name);
        let (Some(theta), Some(deviation)) = (find("theta_deg"), find("deviation_um")) else {
            // The columns it lacks, not the header: a file given as a trace may be anything.
            let lacks: Vec<&str> = ["theta_deg", "deviation_um"]
                .into_iter()
                .filter(|c| find(c).is_none())
                .collect();
            return Err(Error::invalid(
                path,
                format!(
                    "line 1 (the header, {} columns) has no {} column",
                    cols.len(),
                    lacks.join(" or ")
                ),
            )
            .with_help(HELP));
        };
        Ok(Columns {
            theta,
            deviation,
            direction: find("direction"),
            time: find("time_s"),
            commanded: Axis::ALL
                .into_iter()
                .filter_map(|a| find(&format!("{a}_cmd_{}", a.unit())).map(|c| (a, c)))
                .collect(),
        })
    }
}

impl MeasuredTrace {
    /// Reads a measured trace. Other columns (such as the rest of `trace.csv`) are ignored.
    pub fn read(path: &Path) -> Result<MeasuredTrace> {
        let text = crate::input::toml_text::read_text(path)?;
        let mut lines = text.lines().filter(|l| !l.trim().is_empty());
        let Some(header) = lines.next() else {
            return Err(Error::invalid(path, "the measured trace is empty").with_help(HELP));
        };
        let columns = Columns::of(path, header)?;
        let mut points = Vec::new();
        let mut offset = header.len() + 1;
        for line in lines {
            let start = text[offset.min(text.len())..]
                .find(line)
                .map_or(offset, |i| offset + i);
            offset = start + line.len();
            points.push(parse_row(path, &text, start, line, &columns)?);
        }
        if points.len() < 12 {
            return Err(Error::invalid(
                path,
                format!(
                    "the measured trace holds {} points; give at least 12 over a revolution",
                    points.len()
                ),
            ));
        }
        Ok(MeasuredTrace {
            path: path.to_path_buf(),
            points,
            commanded_axes: columns.commanded.iter().map(|(a, _)| *a).collect(),
        })
    }
}

/// One row of the CSV at byte `start` of `text`.
fn parse_row(
    path: &Path,
    text: &str,
    start: usize,
    line: &str,
    columns: &Columns,
) -> Result<MeasuredPoint> {
    let fields: Vec<&str> = line.split(',').map(str::trim).collect();
    let at = |i: usize, what: &str| {
        let col_start = start
            + fields[..i.min(fields.len())]
                .iter()
                .map(|f| f.len() + 1)
                .sum::<usize>();
        Error::at(
            path,
            text,
            col_start..col_start + fields.get(i).map_or(1, |f| f.len().max(1)),
            what.to_string(),
            "here",
        )
    };
    let number = |i: usize, name: &str| -> Result<f64> {
        match fields.get(i).map(|f| f.parse::<f64>()) {
            Some(Ok(v)) if v.is_finite() => Ok(v),
            _ => Err(at(i, &format!("`{name}` must be a finite number"))),
        }
    };
    let direction = match columns
        .direction
        .map(|i| (i, fields.get(i).copied().unwrap_or("")))
    {
        None | Some((_, "ccw")) => Direction::Ccw,
        Some((_, "cw")) => Direction::Cw,
        Some((i, _)) => return Err(at(i, "`direction` must be ccw or cw")),
    };
    let mut commanded = AxisVec([f64::NAN; 9]);
    for &(axis, c) in &columns.commanded {
        commanded[axis] = number(c, &format!("{axis}_cmd_{}", axis.unit()))?;
    }
    Ok(MeasuredPoint {
        theta_deg: number(columns.theta, "theta_deg")?,
        deviation_um: number(columns.deviation, "deviation_um")?,
        direction,
        time_s: columns.time.map(|c| number(c, "time_s")).transpose()?,
        commanded,
    })
}
