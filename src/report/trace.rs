//! `trace.csv` (or `trace.parquet`): one row per traced sample, as a pipeline sink.
//!
//! Columns: direction, time, line, θ, then per axis the commanded and actual position and
//! the following error, then the nonlinear signature and the deviation dL. Rows are
//! gathered in blocks ([`Block`], column by column) and each full block is written at once:
//! nothing is held until a run ends, so memory stays flat in the program's length.
//!
//! **The centre is metadata, not a column.** The centred deviation
//! `dL - (a cos θ + b sin θ)` needs the run's least-squares centring `(a, b)`, known only
//! at the run's end ([`TraceSink::end_run`]). The trace keeps dL, and the centring of each
//! run goes beside it: in `trace.parquet`'s key-value metadata under [`CENTRING_KEY`] (a
//! JSON list of `{direction, a_um, b_um, r0_um}` in run order), and for `trace.csv` in the
//! run folder's `summary.json` (`ballbar.runs[k].centring`, the same numbers). Every reader
//! applies it ([`centred_deviation_um`]): [`read_trace`], the Python package, the report.
//! The trace file appears, by a rename, only when complete; a run that fails leaves no
//! temporary file.
//!
//! [`read_trace`] reads a run folder's trace back (`trace.csv` or `trace.parquet`, the
//! columns the report plots, the centred deviation applied) into one [`Trace`] per format:
//! the one reader of trace files.

use std::fs::File;
use std::io::{BufReader, BufWriter, Write};

use std::path::{Path, PathBuf};

use super::contour::ContourFile;
use super::files::temporary_path;
use super::trace_centring::summary_centrings;
pub use super::trace_centring::{
    centred_deviation_um, centring_per_run, parquet_centrings, RunCentring, CENTRED_COLUMN,
    CENTRING_KEY,
};
use super::trace_parquet::ParquetTrace;
use super::trace_rows::{write_error, Block, AXES, FIXED_COLUMNS, LINE, THETA, TIME};
use super::written::{Hashing, Written};
use crate::error::{Error, Result};
use crate::input::program::{Direction, MeasuredLines};
use crate::input::scenario::TraceFormat;
use crate::measure::ballbar::Centring;
use crate::measure::contour::ContourReading;
use crate::measure::{is_measured, BarGeometry, BarReading};
use crate::numeric::push_fixed_bytes_const;
use crate::pipeline::{Sample, Sink};
use crate::Axis;

/// Writes the trace of every run of a simulation.
pub struct TraceSink {
    /// The block being filled with the current run's rows.
    filling: Block,
    /// The trace file being written.
    format: Format,
    trace_path: PathBuf,
    axes: &'static [Axis],
    geometry: Option<BarGeometry>,
    /// [`BarGeometry::needs_full_chain`], asked once.
    full_chain: bool,
    every: u64,
    direction: Direction,
    measured: Option<MeasuredLines>,
    /// Rows recorded, and the most the run may record (`[simulate] max_trace_rows`).
    rows: u64,
    max_rows: u64,
    /// Each ended run's centring, in run order (the Parquet trace's metadata).
    centrings: Vec<RunCentring>,
    /// A program's trace (no ball bar): `contour.csv` beside it ([`super::contour`]).
    contour: Option<ContourFile>,
}

/// The trace file being written, in its format.
enum Format {
    Csv(CsvTrace),
    Parquet(ParquetTrace),
    /// Finished or failed: nothing open.
    Closed,
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
        let (tmp, names) = (temporary_path(trace_path), column_names(axes));
        // Columns of a block: the fixed ones and three per axis.
        let width = FIXED_COLUMNS + 3 * axes.len();
        let format = match format {
            TraceFormat::Csv => Format::Csv(CsvTrace::create(tmp, &names.join(","))?),
            TraceFormat::Parquet => Format::Parquet(ParquetTrace::create(tmp, names)?),
        };
        let contour = match geometry {
            None => Some(ContourFile::create(
                &trace_path.with_file_name(super::contour::CONTOUR_FILE),
            )?),
            Some(_) => None,
        };
        Ok(TraceSink {
            contour,
            filling: Block::new(width),
            format,
            trace_path: trace_path.to_path_buf(),
            axes,
            full_chain: geometry.is_some_and(|g| g.needs_full_chain()),
            geometry,
            every: every.max(1),
            direction: Direction::Ccw,
            measured: None,
            rows: 0,
            max_rows,
            centrings: Vec::new(),
        })
    }

    /// The next run's direction and measured lines.
    pub fn start_run(&mut self, direction: Direction, measured: Option<MeasuredLines>) {
        self.direction = direction;
        self.measured = measured;
    }

    /// Ends the current run: its last rows are written, and its `centring` (the fit of the
    /// run's ball bar; None without one) noted for the trace's metadata.
    pub fn end_run(&mut self, centring: Option<Centring>) -> Result<()> {
        self.write_block()?;
        if let Some(c) = centring {
            self.centrings.push(RunCentring {
                direction: self.direction,
                a_um: c.a_um,
                b_um: c.b_um,
                r0_um: c.r0_um,
            });
        }
        Ok(())
    }

    /// Puts the trace file in place (its rows were written as their blocks filled).
    pub fn finish(mut self) -> Result<()> {
        // Rows of a run not ended (none from `run_ballbar`): written, not lost.
        let closed = self.write_block().and_then(|()| {
            match std::mem::replace(&mut self.format, Format::Closed) {
                Format::Csv(csv) => csv.finish().map(Some),
                Format::Parquet(parquet) => parquet.finish(&self.centrings).map(Some),
                Format::Closed => Ok(None),
            }
        });
        let tmp = temporary_path(&self.trace_path);
        let record = match closed {
            Ok(record) => record,
            Err(e) => {
                let _ = std::fs::remove_file(&tmp);
                return Err(e);
            }
        };
        std::fs::rename(&tmp, &self.trace_path).map_err(write_error(&self.trace_path))?;
        if let Some(record) = record {
            super::written::note(&self.trace_path, record);
        }
        match self.contour.take() {
            Some(contour) => contour.finish(),
            None => Ok(()),
        }
    }

    /// Writes the rows of the block being filled (if any) and empties it.
    fn write_block(&mut self) -> Result<()> {
        if self.filling.rows() == 0 {
            return Ok(());
        }
        let written = match &mut self.format {
            Format::Csv(csv) => csv.write_block(&self.filling, self.direction),
            Format::Parquet(parquet) => parquet.write_block(&self.filling, self.direction),
            Format::Closed => Ok(()),
        };
        self.filling.clear();
        written
    }
}

impl Drop for TraceSink {
    fn drop(&mut self) {
        // Finished or failed, an unfinished trace is not kept.
        if !matches!(self.format, Format::Closed) {
            self.format = Format::Closed;
            let _ = std::fs::remove_file(temporary_path(&self.trace_path));
        }
    }
}

impl Sink for TraceSink {
    fn push(&mut self, s: &Sample) -> Result<()> {
        let Some(geometry) = &self.geometry else {
            return Ok(());
        };
        if self.skips(s.index) || !is_measured(s, self.measured) {
            return Ok(());
        }
        let r = geometry.read_on(self.full_chain, s);
        self.push_reading(s, &r)
    }
}

impl TraceSink {
    /// Whether sample `index` falls between every `every`-th one (the division only when
    /// samples are skipped at all).
    #[inline]
    fn skips(&self, index: u64) -> bool {
        self.every > 1 && index % self.every != 0
    }

    /// Records `s` with the ball bar's reading `r` of it (already taken by the ball bar, so
    /// the kinematics run once per sample); skips samples between every `every`-th one.
    pub fn push_reading(&mut self, s: &Sample, r: &BarReading) -> Result<()> {
        if self.geometry.is_none() || self.skips(s.index) {
            return Ok(());
        }
        self.count_row(s)?;
        if self.filling.is_full() {
            self.write_block()?;
        }
        self.filling.push(
            [s.time_s, s.line as f64, r.theta_deg],
            self.axes,
            [&s.commanded, &s.actual, &s.following_error],
            [r.nonlinear_um, r.deviation_um],
        );
        Ok(())
    }

    /// Records sample `s` of a program without a ball bar: its axes, with θ and the bar's
    /// columns empty (NaN), and its contour error (`None` on a rapid or a dwell) in
    /// `contour.csv`; skips samples between every `every`-th one.
    pub fn push_program(&mut self, s: &Sample, contour: Option<&ContourReading>) -> Result<()> {
        if self.geometry.is_some() || self.skips(s.index) {
            return Ok(());
        }
        self.count_row(s)?;
        if self.filling.is_full() {
            self.write_block()?;
        }
        let nan = f64::NAN;
        self.filling.push(
            [s.time_s, s.line as f64, nan],
            self.axes,
            [&s.commanded, &s.actual, &s.following_error],
            [nan, nan],
        );
        match (contour, self.contour.as_mut()) {
            (Some(r), Some(file)) => file.push(self.direction, s.time_s, s.line, r),
            _ => Ok(()),
        }
    }

    /// Counts a row against `[simulate] max_trace_rows`.
    fn count_row(&mut self, s: &Sample) -> Result<()> {
        if self.rows >= self.max_rows {
            return Err(Error::usage(format!(
                "the trace passed its budget of {} rows ([simulate] max_trace_rows) at program line {}, \
                 after {:.1} s of machine time: raise [simulate] trace_every or max_trace_rows, \
                 or measure fewer blocks (measure_lines)",
                self.max_rows, s.line, s.time_s
            )));
        }
        self.rows += 1;
        Ok(())
    }
}

/// The trace's columns: direction, time, line, θ, per axis the commanded and actual
/// position and the following error, the nonlinear signature and dL.
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
    names.extend(["nonlinear_um", "deviation_um"].map(String::from));
    names
}

/// `trace.csv` being written: its temporary file and one reused line buffer.
struct CsvTrace {
    tmp: PathBuf,
    /// Hashed as written (the manifest's record without reading the file back).
    out: BufWriter<Hashing<File>>,
    line: Vec<u8>,
}

impl CsvTrace {
    /// Creates the temporary file `tmp` and writes the `header` line.
    fn create(tmp: PathBuf, header: &str) -> Result<CsvTrace> {
        let file = File::create(&tmp).map_err(write_error(&tmp))?;
        // Large writes: a 7 MB trace in a few dozen system calls instead of one per 8 kB.
        let mut out = BufWriter::with_capacity(1 << 18, Hashing::new(file));
        writeln!(out, "{header}").map_err(write_error(&tmp))?;
        Ok(CsvTrace {
            tmp,
            out,
            line: Vec::with_capacity(1 << 10),
        })
    }

    /// Appends the rows of `block`, of the run `direction`.
    fn write_block(&mut self, block: &Block, direction: Direction) -> Result<()> {
        let width = block.width();
        let [time, line_no, theta] = [TIME, LINE, THETA].map(|k| block.column(k));
        let axes: Vec<&[f64]> = (AXES..width - 2).map(|k| block.column(k)).collect();
        let (nonlinear, dev) = (block.column(width - 2), block.column(width - 1));
        let name: &[u8] = if direction == Direction::Cw {
            b"cw"
        } else {
            b"ccw"
        };
        let line = &mut self.line;
        for r in 0..block.rows() {
            // The row is formatted once into one reused buffer: no allocation per value.
            line.clear();
            line.extend_from_slice(name);
            // Each column's decimal count known at compile time (unrolled digit loops).
            macro_rules! field {
                ($value:expr, $decimals:literal) => {
                    line.push(b',');
                    push_fixed_bytes_const::<$decimals>(line, $value);
                };
            }
            field!(time[r], 4);
            field!(line_no[r], 0);
            field!(theta[r], 4);
            for axis in axes.chunks_exact(3) {
                field!(axis[0][r], 6);
                field!(axis[1][r], 6);
                field!(axis[2][r], 7);
            }
            for value in [nonlinear[r], dev[r]] {
                field!(value, 4);
            }
            line.push(b'\n');
            self.out.write_all(line).map_err(write_error(&self.tmp))?;
        }
        Ok(())
    }

    /// Flushes the file (the caller renames it); the record of the bytes written.
    fn finish(mut self) -> Result<Written> {
        self.out.flush().map_err(write_error(&self.tmp))?;
        Ok(self.out.get_ref().record())
    }
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

    /// Appends one row: its direction, time, θ, deviation dL (centred by
    /// [`Trace::centre`]), and per axis the actual position and following error. A row of
    /// another direction than the last starts a run.
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

impl Trace {
    /// Centres each run's deviations with its entry of `centrings` ([`centring_per_run`]):
    /// `deviation_centred_um` held dL until now.
    fn centre(&mut self, centrings: &[RunCentring]) {
        let directions = self.runs.iter().map(|r| match r.direction.as_str() {
            "cw" => Direction::Cw,
            _ => Direction::Ccw,
        });
        let per_run = centring_per_run(directions, centrings);
        for (run, centring) in self.runs.iter_mut().zip(per_run) {
            for (dev, &theta) in run.deviation_centred_um.iter_mut().zip(&run.theta_deg) {
                *dev = centred_deviation_um(*dev, theta, centring);
            }
        }
    }
}

/// The columns of each axis the reader takes: actual position and following error.
fn axis_column_names(axis: Axis) -> [String; 2] {
    let u = axis.unit();
    [format!("{axis}_act_{u}"), format!("{axis}_ferr_{u}")]
}

/// The columns besides the axes' that the reader takes.
const READ_COLUMNS: [&str; 4] = ["direction", "time_s", "theta_deg", "deviation_um"];

/// Reads the trace of the run folder `dir`: `trace.csv`, or else `trace.parquet`; None when
/// the folder has neither. Values that are missing or not numbers read as NaN. Each run's
/// deviation is centred with its centring (`summary.json` beside `trace.csv`, the Parquet
/// trace's own metadata).
pub fn read_trace(dir: &Path) -> Result<Option<Trace>> {
    let csv = dir.join(TraceFormat::Csv.file_name());
    if csv.exists() {
        let mut trace = read_csv(&csv)?;
        trace.centre(&summary_centrings(dir)?);
        return Ok(Some(trace));
    }
    let parquet = dir.join(TraceFormat::Parquet.file_name());
    if parquet.exists() {
        return read_parquet(&parquet).map(Some);
    }
    Ok(None)
}

/// Reads `trace.csv` (the columns [`read_trace`] takes), uncentred.
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
/// `trace.csv` as f64, through [`Table::read_parquet`](super::parquet::Table::read_parquet),
/// centred with the file's own metadata.
fn read_parquet(path: &Path) -> Result<Trace> {
    use super::parquet::{Column, Table};

    let wanted = |name: &str| {
        READ_COLUMNS.contains(&name) || name.contains("_act_") || name.contains("_ferr_")
    };
    let (table, key_value) = Table::read_parquet_with_metadata(path, &wanted)?;
    let bad = |what: String| Error::invalid(path, what);
    let centrings = parquet_centrings(key_value.as_ref()).map_err(bad)?;
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
        floats("deviation_um")?,
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
    trace.centre(&centrings);
    Ok(trace)
}
