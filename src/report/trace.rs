//! `trace.csv`: one row per traced sample, as a pipeline sink.
//!
//! Columns: direction, time, line, θ, then per axis the commanded and actual position and
//! the following error, then the nonlinear signature, the deviation dL and the centred
//! deviation `dL - (a cos θ + b sin θ)`. The centring is the least-squares fit of the whole
//! run, known only at its end, so rows go to a binary temporary file first and `trace.csv`
//! is written from it, line by line, when the runs are done: memory stays flat, and
//! `trace.csv` appears only when complete. A run that fails leaves no temporary file.
//! The first [`RAW_IN_MEMORY`] bytes of raw rows (about 50,000 rows of five axes) stay in
//! memory and reach the disk only when a longer trace spills over: memory stays bounded,
//! and a trace of one cone never makes the round trip through the file.
//!
//! [`read_trace`] reads a run folder's trace back (`trace.csv` or `trace.parquet`, the
//! columns the report plots) into one [`Trace`] per format: the one reader of trace files.

use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

use super::files::temporary_path;
use super::trace_rows::{write_error, RawRows, RAW_FIXED_COLUMNS};
use crate::error::{Error, Result};
use crate::input::program::{Direction, MeasuredLines};
use crate::input::scenario::TraceFormat;
use crate::measure::{is_measured, BallbarRun, BarGeometry, BarReading};
use crate::numeric::push_fixed_bytes_const;
use crate::pipeline::{Sample, Sink};
use crate::Axis;

/// Raw rows held in memory before they spill to the temporary file, bytes.
pub const RAW_IN_MEMORY: usize = 8 << 20;

/// Writes the trace of every run of a simulation.
pub struct TraceSink {
    /// Raw rows not yet spilled (at most [`RAW_IN_MEMORY`] bytes).
    held: Vec<u8>,
    /// The temporary file, once the rows spilled over.
    raw: Option<BufWriter<File>>,
    raw_path: PathBuf,
    trace_path: PathBuf,
    axes: &'static [Axis],
    geometry: Option<BarGeometry>,
    every: u64,
    format: TraceFormat,
    direction: Direction,
    measured: Option<MeasuredLines>,
    row: Vec<f64>,
    /// Rows recorded, and the most the run may record (`[simulate] max_trace_rows`).
    rows: u64,
    max_rows: u64,
}

impl TraceSink {
    /// A trace of `axes` into `trace_path`, every `every`-th sample of the measured
    /// revolution, at most `max_rows` rows; without a ball bar (`geometry` None) the trace
    /// has its header only.
    pub fn create(
        trace_path: &Path,
        axes: &'static [Axis],
        geometry: Option<BarGeometry>,
        every: u64,
        format: TraceFormat,
        max_rows: u64,
    ) -> Result<TraceSink> {
        let raw_path = trace_path.with_extension("csv.raw.tmp");
        Ok(TraceSink {
            held: Vec::new(),
            raw: None,
            raw_path,
            trace_path: trace_path.to_path_buf(),
            axes,
            geometry,
            every: every.max(1),
            format,
            direction: Direction::Ccw,
            measured: None,
            row: Vec::with_capacity(RAW_FIXED_COLUMNS + 3 * axes.len()),
            rows: 0,
            max_rows,
        })
    }

    /// The next run's direction and measured lines.
    pub fn start_run(&mut self, direction: Direction, measured: Option<MeasuredLines>) {
        self.direction = direction;
        self.measured = measured;
    }

    /// Writes `trace.csv` (atomically) from the raw rows, centring each row with the fit of
    /// its direction's run.
    pub fn finish(mut self, runs: &[BallbarRun]) -> Result<()> {
        let spilled = self.raw.is_some();
        if let Some(mut raw) = self.raw.take() {
            raw.write_all(&self.held)
                .and_then(|()| raw.flush())
                .map_err(write_error(&self.raw_path))?;
            self.held = Vec::new();
        }
        if spilled {
            let file = File::open(&self.raw_path).map_err(write_error(&self.raw_path))?;
            self.write_trace(BufReader::new(file), runs)
        } else {
            self.write_trace(&self.held[..], runs)
        }
    }

    /// Writes the trace file in the sink's format from the raw rows read from `rows`.
    fn write_trace<R: Read>(&self, rows: R, runs: &[BallbarRun]) -> Result<()> {
        let names = column_names(self.axes);
        match self.format {
            TraceFormat::Csv => complete(
                rows,
                &self.raw_path,
                &self.trace_path,
                &names.join(","),
                self.axes.len(),
                runs,
            ),
            TraceFormat::Parquet => super::trace_parquet::complete_parquet(
                rows,
                &self.raw_path,
                &self.trace_path,
                &names,
                runs,
            ),
        }
    }
}

impl Drop for TraceSink {
    fn drop(&mut self) {
        // Finished or failed, the raw rows are not kept.
        self.raw = None;
        let _ = std::fs::remove_file(&self.raw_path);
    }
}

impl Sink for TraceSink {
    fn push(&mut self, s: &Sample) -> Result<()> {
        let Some(geometry) = &self.geometry else {
            return Ok(());
        };
        if s.index % self.every != 0 || !is_measured(s, self.measured) {
            return Ok(());
        }
        let r = geometry.read(s);
        self.push_reading(s, &r)
    }
}

impl TraceSink {
    /// Records `s` with the ball bar's reading `r` of it (already taken by the ball bar, so
    /// the kinematics run once per sample); skips samples between every `every`-th one.
    pub fn push_reading(&mut self, s: &Sample, r: &BarReading) -> Result<()> {
        if self.geometry.is_none() || s.index % self.every != 0 {
            return Ok(());
        }
        if self.rows >= self.max_rows {
            return Err(Error::usage(format!(
                "the trace passed its budget of {} rows ([simulate] max_trace_rows) at program line {}, \
                 after {:.1} s of machine time: raise [simulate] trace_every or max_trace_rows, \
                 or measure fewer blocks (measure_lines)",
                self.max_rows, s.line, s.time_s
            )));
        }
        self.rows += 1;
        let row = &mut self.row;
        row.clear();
        let cw = if self.direction == Direction::Cw {
            1.0
        } else {
            0.0
        };
        let (sin, cos) = r.theta_sin_cos;
        row.extend_from_slice(&[cw, s.time_s, s.line as f64, r.theta_deg, sin, cos]);
        for &a in self.axes {
            row.extend_from_slice(&[s.commanded[a], s.actual[a], s.following_error[a]]);
        }
        row.extend_from_slice(&[r.nonlinear_um, r.deviation_um]);
        let start = self.held.len();
        self.held.resize(start + 8 * row.len(), 0);
        for (bytes, v) in self.held[start..].chunks_exact_mut(8).zip(row.iter()) {
            bytes.copy_from_slice(&v.to_le_bytes());
        }
        if self.held.len() >= RAW_IN_MEMORY {
            self.spill()?;
        }
        Ok(())
    }

    /// Moves the held rows to the temporary file (created on the first spill).
    fn spill(&mut self) -> Result<()> {
        let raw = match self.raw.as_mut() {
            Some(raw) => raw,
            None => {
                let file = File::create(&self.raw_path).map_err(write_error(&self.raw_path))?;
                self.raw.insert(BufWriter::new(file))
            }
        };
        raw.write_all(&self.held)
            .map_err(write_error(&self.raw_path))?;
        self.held.clear();
        Ok(())
    }
}

/// The trace's columns: direction, time, line, θ, per axis the commanded and actual
/// position and the following error, the nonlinear signature, dL and the centred dL.
fn column_names(axes: &[Axis]) -> Vec<String> {
    let mut names: Vec<String> = ["direction", "time_s", "line", "theta_deg"]
        .map(String::from)
        .to_vec();
    for a in axes {
        let u = a.unit();
        names.extend([
            format!("{a}_cmd_{u}"),
            format!("{a}_act_{u}"),
            format!("{a}_ferr_{u}"),
        ]);
    }
    names.extend(["nonlinear_um", "deviation_um", "deviation_centred_um"].map(String::from));
    names
}

/// Writes `trace_path` from the binary rows read from `reader` (held rows, or the file at
/// `raw_path`), appending the centred deviation `dL - (a cos θ + b sin θ)` of each row's run.
fn complete<R: Read>(
    reader: R,
    raw_path: &Path,
    trace_path: &Path,
    header: &str,
    n_axes: usize,
    runs: &[BallbarRun],
) -> Result<()> {
    let tmp = temporary_path(trace_path);
    let write_err = write_error(&tmp);
    // Large writes: a 7 MB trace in a few system calls instead of one per 8 kB.
    let mut out = BufWriter::with_capacity(1 << 20, File::create(&tmp).map_err(&write_err)?);
    writeln!(out, "{header}").map_err(&write_err)?;
    let width = RAW_FIXED_COLUMNS + 3 * n_axes;
    let mut rows = RawRows::new(reader, width, runs, raw_path, &tmp);
    let mut line: Vec<u8> = Vec::with_capacity(32 * width);
    while let Some((v, cw_row, centred)) = rows.next_row()? {
        let (theta, dev) = (v[3], v[width - 1]);
        // The row is formatted once into one reused buffer: no allocation per value.
        line.clear();
        line.extend_from_slice(if cw_row { b"cw" } else { b"ccw" });
        // Each column's decimal count known at compile time (unrolled digit loops).
        macro_rules! field {
            ($value:expr, $decimals:literal) => {
                line.push(b',');
                push_fixed_bytes_const::<$decimals>(&mut line, $value);
            };
        }
        field!(v[1], 4);
        field!(v[2], 0);
        field!(theta, 4);
        for axis in v[6..width - 2].chunks_exact(3) {
            field!(axis[0], 6);
            field!(axis[1], 6);
            field!(axis[2], 7);
        }
        for value in [v[width - 2], dev, centred] {
            field!(value, 4);
        }
        line.push(b'\n');
        out.write_all(&line).map_err(&write_err)?;
    }
    out.flush().map_err(&write_err)?;
    drop(out);
    std::fs::rename(&tmp, trace_path).map_err(write_error(trace_path))
}

/// One direction's columns of a trace file.
#[derive(Clone, Debug, Default)]
pub struct TraceRun {
    /// The `direction` column's text ("ccw", "cw").
    pub direction: String,
    pub time_s: Vec<f64>,
    pub theta_deg: Vec<f64>,
    pub deviation_centred_um: Vec<f64>,
    /// Per axis of [`Trace::axes`]: actual position and following error (mm or deg).
    pub actual: Vec<Vec<f64>>,
    pub following_error: Vec<Vec<f64>>,
}

impl TraceRun {
    /// The velocity of axis `k` (index into [`Trace::axes`]) per minute: the central
    /// difference `v_i = 60 (p_{i+1} - p_{i-1}) / (t_{i+1} - t_{i-1})` of the actual
    /// position over the time column (one-sided at the ends; NaN where time does not advance).
    pub fn velocity_per_min(&self, k: usize) -> Vec<f64> {
        let (t, p) = (&self.time_s, &self.actual[k]);
        let n = p.len();
        (0..n)
            .map(|i| {
                let (a, b) = (i.saturating_sub(1), (i + 1).min(n.saturating_sub(1)));
                let dt = t[b] - t[a];
                if b > a && dt > 0.0 {
                    60.0 * (p[b] - p[a]) / dt
                } else {
                    f64::NAN
                }
            })
            .collect()
    }
}

/// A trace file read back, by direction (the rows of one direction come together).
#[derive(Clone, Debug, Default)]
pub struct Trace {
    /// The axes with actual-position and following-error columns.
    pub axes: Vec<Axis>,
    pub runs: Vec<TraceRun>,
}

impl Trace {
    /// An empty trace of `axes`.
    fn of(axes: Vec<Axis>) -> Trace {
        Trace {
            axes,
            runs: Vec::new(),
        }
    }

    /// Appends one row: its direction, time, θ, centred deviation, and per axis the actual
    /// position and following error. A row of another direction than the last starts a run.
    fn push_row(
        &mut self,
        direction: &str,
        [time, theta, dev]: [f64; 3],
        axis_values: impl Iterator<Item = (f64, f64)>,
    ) {
        if self.runs.last().is_none_or(|r| r.direction != direction) {
            self.runs.push(TraceRun {
                direction: direction.to_string(),
                actual: vec![Vec::new(); self.axes.len()],
                following_error: vec![Vec::new(); self.axes.len()],
                ..TraceRun::default()
            });
        }
        let run = self.runs.last_mut().expect("pushed above");
        run.time_s.push(time);
        run.theta_deg.push(theta);
        run.deviation_centred_um.push(dev);
        for (k, (a, f)) in axis_values.enumerate() {
            run.actual[k].push(a);
            run.following_error[k].push(f);
        }
    }
}

/// The columns of each axis the reader takes: actual position and following error.
fn axis_column_names(axis: Axis) -> [String; 2] {
    let u = axis.unit();
    [format!("{axis}_act_{u}"), format!("{axis}_ferr_{u}")]
}

/// The columns besides the axes' that the reader takes.
const READ_COLUMNS: [&str; 4] = ["direction", "time_s", "theta_deg", "deviation_centred_um"];

/// Reads the trace of the run folder `dir`: `trace.csv`, or else `trace.parquet`; None when
/// the folder has neither. Values that are missing or not numbers read as NaN.
pub fn read_trace(dir: &Path) -> Result<Option<Trace>> {
    let csv = dir.join(TraceFormat::Csv.file_name());
    if csv.exists() {
        return read_csv(&csv).map(Some);
    }
    let parquet = dir.join(TraceFormat::Parquet.file_name());
    if parquet.exists() {
        return read_parquet(&parquet).map(Some);
    }
    Ok(None)
}

/// Reads `trace.csv` (the columns [`read_trace`] takes).
fn read_csv(path: &Path) -> Result<Trace> {
    let bad = |what: String| Error::invalid(path, what);
    let file = File::open(path).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let mut reader = csv::Reader::from_reader(BufReader::new(file));
    let header = reader
        .headers()
        .map_err(|e| bad(format!("cannot read the header: {e}")))?
        .clone();
    let col = |name: &str| header.iter().position(|h| h == name);
    let mut fixed = [0; 4];
    for (c, name) in fixed.iter_mut().zip(READ_COLUMNS) {
        *c = col(name).ok_or_else(|| bad(format!("no column `{name}`")))?;
    }
    let [c_dir, c_time, c_theta, c_dev] = fixed;
    let (mut axes, mut axis_cols) = (Vec::new(), Vec::new());
    for axis in Axis::ALL {
        let [act, ferr] = axis_column_names(axis);
        if let (Some(a), Some(f)) = (col(&act), col(&ferr)) {
            axes.push(axis);
            axis_cols.push((a, f));
        }
    }
    let mut trace = Trace::of(axes);
    for (i, record) in reader.records().enumerate() {
        let record = record.map_err(|e| bad(format!("row {}: {e}", i + 2)))?;
        let num = |c: usize| -> f64 {
            record
                .get(c)
                .and_then(|s| s.trim().parse().ok())
                .unwrap_or(f64::NAN)
        };
        trace.push_row(
            record.get(c_dir).unwrap_or(""),
            [num(c_time), num(c_theta), num(c_dev)],
            axis_cols.iter().map(|&(a, f)| (num(a), num(f))),
        );
    }
    Ok(trace)
}

/// Reads `trace.parquet` (`[simulate] trace_format = "parquet"`): the columns of
/// `trace.csv` as f64, through [`Table::read_parquet`](super::parquet::Table::read_parquet).
fn read_parquet(path: &Path) -> Result<Trace> {
    use super::parquet::{Column, Table};

    let wanted = |name: &str| {
        READ_COLUMNS.contains(&name) || name.contains("_act_") || name.contains("_ferr_")
    };
    let table = Table::read_parquet(path, &wanted)?;
    let bad = |what: String| Error::invalid(path, what);
    let floats = |name: &str| match table.column(name) {
        Some(Column::F64(v)) => Ok(v),
        _ => Err(bad(format!("no f64 column `{name}`"))),
    };
    let Some(Column::Str(direction)) = table.column("direction") else {
        return Err(bad("no text column `direction`".into()));
    };
    let [time, theta, dev] = [
        floats("time_s")?,
        floats("theta_deg")?,
        floats("deviation_centred_um")?,
    ];
    let (mut axes, mut axis_cols) = (Vec::new(), Vec::new());
    for axis in Axis::ALL {
        let [act, ferr] = axis_column_names(axis);
        if table.column(&act).is_some() && table.column(&ferr).is_some() {
            axes.push(axis);
            axis_cols.push((floats(&act)?, floats(&ferr)?));
        }
    }
    let value = |v: &[Option<f64>], i: usize| v[i].unwrap_or(f64::NAN);
    let mut trace = Trace::of(axes);
    for (i, dir) in direction.iter().enumerate() {
        trace.push_row(
            dir.as_deref().unwrap_or(""),
            [value(time, i), value(theta, i), value(dev, i)],
            axis_cols.iter().map(|(a, f)| (value(a, i), value(f, i))),
        );
    }
    Ok(trace)
}
