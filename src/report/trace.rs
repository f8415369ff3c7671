//! `trace.csv` (or `trace.parquet`): one row per traced sample, as a pipeline sink.
//!
//! Columns: direction, time, line, θ, then per axis the commanded and actual position and
//! the following error, then the nonlinear signature, the deviation dL and the centred
//! deviation `dL - (a cos θ + b sin θ)`. The centring is the least-squares fit of a whole
//! run, known only at its end, so a run's rows are held in blocks ([`Block`], column by
//! column) until it ends ([`TraceSink::end_run`]), then written to the trace's temporary
//! file; the blocks are reused by the next run (their memory is mapped once). A run longer
//! than [`RAW_IN_MEMORY`] bytes of rows moves its full blocks to a binary temporary file and
//! reads them back at its end: memory stays bounded. `trace.csv` appears, by a rename, only
//! when complete; a run that fails leaves no temporary file.
//!
//! [`read_trace`] reads a run folder's trace back (`trace.csv` or `trace.parquet`, the
//! columns the report plots) into one [`Trace`] per format: the one reader of trace files.

use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, Write};

use arrow::datatypes::ToByteSlice;
use std::path::{Path, PathBuf};

use super::files::temporary_path;
use super::trace_parquet::ParquetTrace;
use super::trace_rows::{
    centred_from_inputs, write_error, Block, AXES, BLOCK_ROWS, FIXED_COLUMNS, LINE, THETA, TIME,
};
use crate::error::{Error, Result};
use crate::input::program::{Direction, MeasuredLines};
use crate::input::scenario::TraceFormat;
use crate::measure::ballbar::Centring;
use crate::measure::{is_measured, BarGeometry, BarReading};
use crate::numeric::push_fixed_bytes_const;
use crate::pipeline::{Sample, Sink};
use crate::Axis;

/// Full blocks of one run's rows held in memory, at most, before they spill to the
/// temporary file, bytes (the CSV trace's full rows: about twelve blocks of 4,096 rows).
pub const RAW_IN_MEMORY: usize = 8 << 20;

/// Writes the trace of every run of a simulation.
pub struct TraceSink {
    /// The current run's rows: full blocks, then the one being filled.
    held: Vec<Block>,
    /// Emptied blocks, for the next rows.
    spare: Vec<Block>,
    /// The temporary file of spilled blocks, and how many of the current run it holds.
    raw: Option<BufWriter<File>>,
    spilled: usize,
    raw_path: PathBuf,
    trace_path: PathBuf,
    /// The trace file being written (its temporary file), once a run has ended.
    out: Option<TraceOut>,
    axes: &'static [Axis],
    geometry: Option<BarGeometry>,
    every: u64,
    format: TraceFormat,
    direction: Direction,
    measured: Option<MeasuredLines>,
    /// Rows recorded, and the most the run may record (`[simulate] max_trace_rows`).
    rows: u64,
    max_rows: u64,
    /// The centred deviations of the block being written.
    centred: Vec<f64>,
    /// Parquet: the current run's `(dL, sin θ, cos θ)` per row whose other columns are
    /// written, how many such values went to the temporary file, and the run's first row group.
    inputs: Vec<f64>,
    inputs_spilled: usize,
    run_first_group: usize,
}

/// The trace file being written, in its format.
enum TraceOut {
    Csv(CsvTrace),
    Parquet(ParquetTrace),
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
            spare: Vec::new(),
            raw: None,
            spilled: 0,
            raw_path,
            trace_path: trace_path.to_path_buf(),
            out: None,
            axes,
            geometry,
            every: every.max(1),
            format,
            direction: Direction::Ccw,
            measured: None,
            rows: 0,
            max_rows,
            centred: Vec::new(),
            inputs: Vec::new(),
            inputs_spilled: 0,
            run_first_group: 0,
        })
    }

    /// The next run's direction and measured lines.
    pub fn start_run(&mut self, direction: Direction, measured: Option<MeasuredLines>) {
        self.direction = direction;
        self.measured = measured;
    }

    /// Ends the current run: its rows are written to the trace, centred with `centring`
    /// (the fit of the run's ball bar; dL as it is without one).
    pub fn end_run(&mut self, centring: Option<Centring>) -> Result<()> {
        if self.format == TraceFormat::Parquet {
            return self.end_parquet_run(centring);
        }
        if self.held.is_empty() && self.spilled == 0 {
            return Ok(());
        }
        let mut out = match self.out.take() {
            Some(TraceOut::Csv(out)) => out,
            _ => match self.open()? {
                TraceOut::Csv(out) => out,
                TraceOut::Parquet(_) => unreachable!("a CSV trace writes CSV"),
            },
        };
        let written = self.write_run(&mut out, centring);
        self.out = Some(TraceOut::Csv(out));
        written
    }

    /// Parquet: writes the columns of the block being filled, then the centred deviations of
    /// every row group of the run.
    fn end_parquet_run(&mut self, centring: Option<Centring>) -> Result<()> {
        if let Some(block) = self.held.pop() {
            self.stream(block)?;
        }
        let Some(TraceOut::Parquet(out)) = self.out.as_mut() else {
            return Ok(());
        };
        let err = write_error(&self.raw_path);
        let mut spilled = match self.raw.as_mut().filter(|_| self.inputs_spilled > 0) {
            Some(raw) => {
                raw.flush().map_err(&err)?;
                raw.get_mut().rewind().map_err(&err)?;
                Some(BufReader::with_capacity(1 << 16, raw.get_ref()))
            }
            None => None,
        };
        let (mut from_file, mut at) = (self.inputs_spilled, 0);
        let mut read = Vec::new();
        for group in self.run_first_group..out.groups() {
            let need = 3 * out.group_rows(group);
            let inputs = match spilled.as_mut().filter(|_| from_file > 0) {
                Some(reader) => {
                    let n = need.min(from_file);
                    read_f64s(reader, n, &mut read).map_err(&err)?;
                    read.extend_from_slice(&self.inputs[at..at + need - n]);
                    (from_file, at) = (from_file - n, at + need - n);
                    &read[..]
                }
                None => {
                    at += need;
                    &self.inputs[at - need..at]
                }
            };
            centred_from_inputs(inputs, centring, &mut self.centred);
            out.write_centred(group, &self.centred)?;
        }
        drop(spilled);
        if let Some(raw) = self.raw.as_mut().filter(|_| self.inputs_spilled > 0) {
            let file = raw.get_mut();
            file.rewind().and_then(|()| file.set_len(0)).map_err(&err)?;
        }
        self.inputs.clear();
        self.inputs_spilled = 0;
        self.run_first_group = out.groups();
        Ok(())
    }

    /// Parquet: writes the columns of `block` as a row group and keeps what its centred
    /// deviations need; the block is then free for the next rows.
    fn stream(&mut self, mut block: Block) -> Result<()> {
        if block.rows() > 0 {
            if self.out.is_none() {
                self.out = Some(self.open()?);
            }
            let Some(TraceOut::Parquet(out)) = self.out.as_mut() else {
                unreachable!("a Parquet trace writes Parquet");
            };
            out.write_block(&block, self.direction)?;
            block.centring_inputs_into(&mut self.inputs);
            if 8 * self.inputs.len() > RAW_IN_MEMORY {
                let values = std::mem::take(&mut self.inputs);
                self.raw_file()?
                    .write_all(values.to_byte_slice())
                    .map_err(write_error(&self.raw_path))?;
                self.inputs_spilled += values.len();
                self.inputs = values;
                self.inputs.clear();
            }
        }
        block.clear();
        self.spare.push(block);
        Ok(())
    }

    /// Writes the held and spilled rows of the current run to `out`, and empties them.
    fn write_run(&mut self, out: &mut CsvTrace, centring: Option<Centring>) -> Result<()> {
        let direction = self.direction;
        if let Some(mut raw) = self.raw.take().filter(|_| self.spilled > 0) {
            let err = write_error(&self.raw_path);
            let mut block = self.spare.pop().unwrap_or_else(|| Block::new(self.width()));
            let read = (|| -> Result<()> {
                raw.flush().map_err(&err)?;
                let file = raw.get_mut();
                file.rewind().map_err(&err)?;
                let mut reader = BufReader::with_capacity(1 << 16, &*file);
                for _ in 0..self.spilled {
                    block.read_raw(&mut reader).map_err(&err)?;
                    block.centred_into(centring, &mut self.centred);
                    out.write_block(&block, direction, &self.centred)?;
                }
                drop(reader);
                file.rewind().and_then(|()| file.set_len(0)).map_err(&err)
            })();
            block.clear();
            self.spare.push(block);
            self.raw = Some(raw);
            self.spilled = 0;
            read?;
        }
        for mut block in std::mem::take(&mut self.held) {
            block.centred_into(centring, &mut self.centred);
            out.write_block(&block, direction, &self.centred)?;
            block.clear();
            self.spare.push(block);
        }
        Ok(())
    }

    /// Creates the trace's temporary file and writes its header.
    fn open(&self) -> Result<TraceOut> {
        let names = column_names(self.axes);
        let tmp = temporary_path(&self.trace_path);
        Ok(match self.format {
            TraceFormat::Csv => TraceOut::Csv(CsvTrace::create(tmp, &names.join(","))?),
            TraceFormat::Parquet => TraceOut::Parquet(ParquetTrace::create(tmp, names)?),
        })
    }

    /// Puts the trace file in place; every run's rows were written by
    /// [`TraceSink::end_run`], the only place that knows their centring.
    pub fn finish(mut self) -> Result<()> {
        debug_assert!(self.held.is_empty(), "a run's rows not ended by end_run");
        let out = match self.out.take() {
            Some(out) => out,
            None => self.open()?,
        };
        let tmp = temporary_path(&self.trace_path);
        let closed = match out {
            TraceOut::Csv(csv) => csv.finish(),
            TraceOut::Parquet(parquet) => parquet.finish(),
        };
        if let Err(e) = closed {
            let _ = std::fs::remove_file(&tmp);
            return Err(e);
        }
        std::fs::rename(&tmp, &self.trace_path).map_err(write_error(&self.trace_path))
    }

    /// Columns of a block: the fixed ones and three per axis.
    fn width(&self) -> usize {
        FIXED_COLUMNS + 3 * self.axes.len()
    }
}

impl Drop for TraceSink {
    fn drop(&mut self) {
        // Finished or failed, the raw rows are not kept, nor an unfinished trace.
        self.raw = None;
        let _ = std::fs::remove_file(&self.raw_path);
        if self.out.take().is_some() {
            let _ = std::fs::remove_file(temporary_path(&self.trace_path));
        }
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
        if self.held.last().is_none_or(Block::is_full) {
            self.next_block()?;
        }
        let mut axes = [[0.0; 3]; Axis::ALL.len()];
        for (values, &a) in axes.iter_mut().zip(self.axes) {
            *values = [s.commanded[a], s.actual[a], s.following_error[a]];
        }
        let (sin, cos) = r.theta_sin_cos;
        let block = self.held.last_mut().expect("a block with room");
        block.push(
            [s.time_s, s.line as f64, r.theta_deg, sin, cos],
            &axes[..self.axes.len()],
            [r.nonlinear_um, r.deviation_um],
        );
        Ok(())
    }

    /// Starts a block for the next rows: a spare one, or a new one; when the run's full
    /// blocks pass [`RAW_IN_MEMORY`], they move to the temporary file first.
    fn next_block(&mut self) -> Result<()> {
        if self.format == TraceFormat::Parquet {
            if let Some(full) = self.held.pop() {
                self.stream(full)?;
            }
            let block = self.spare.pop().unwrap_or_else(|| Block::new(self.width()));
            self.held.push(block);
            return Ok(());
        }
        let block_bytes = 8 * BLOCK_ROWS * self.width();
        if self.held.len() * block_bytes > RAW_IN_MEMORY {
            self.spill()?;
        }
        let block = self.spare.pop().unwrap_or_else(|| Block::new(self.width()));
        self.held.push(block);
        Ok(())
    }

    /// Moves the held (full) blocks to the temporary file.
    fn spill(&mut self) -> Result<()> {
        let held = std::mem::take(&mut self.held);
        for mut block in held {
            block
                .write_raw(self.raw_file()?)
                .map_err(write_error(&self.raw_path))?;
            block.clear();
            self.spare.push(block);
            self.spilled += 1;
        }
        Ok(())
    }

    /// The temporary file of spilled rows, created on the first spill.
    fn raw_file(&mut self) -> Result<&mut BufWriter<File>> {
        if self.raw.is_none() {
            let file = File::options()
                .read(true)
                .write(true)
                .create(true)
                .truncate(true)
                .open(&self.raw_path)
                .map_err(write_error(&self.raw_path))?;
            self.raw = Some(BufWriter::with_capacity(1 << 16, file));
        }
        Ok(self.raw.as_mut().expect("created above"))
    }
}

/// Reads `n` little-endian f64 from `reader` into `out` (emptied first).
fn read_f64s(reader: &mut impl Read, n: usize, out: &mut Vec<f64>) -> std::io::Result<()> {
    let mut bytes = vec![0u8; 8 * n];
    reader.read_exact(&mut bytes)?;
    out.clear();
    out.extend(
        bytes
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes"))),
    );
    Ok(())
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

/// `trace.csv` being written: its temporary file and one reused line buffer.
struct CsvTrace {
    tmp: PathBuf,
    out: BufWriter<File>,
    line: Vec<u8>,
}

impl CsvTrace {
    /// Creates the temporary file `tmp` and writes the `header` line.
    fn create(tmp: PathBuf, header: &str) -> Result<CsvTrace> {
        let file = File::create(&tmp).map_err(write_error(&tmp))?;
        // Large writes: a 7 MB trace in a few dozen system calls instead of one per 8 kB.
        let mut out = BufWriter::with_capacity(1 << 18, file);
        writeln!(out, "{header}").map_err(write_error(&tmp))?;
        Ok(CsvTrace {
            tmp,
            out,
            line: Vec::with_capacity(1 << 10),
        })
    }

    /// Appends the rows of `block`, of the run `direction`, with their `centred` deviations.
    fn write_block(&mut self, block: &Block, direction: Direction, centred: &[f64]) -> Result<()> {
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
            for value in [nonlinear[r], dev[r], centred[r]] {
                field!(value, 4);
            }
            line.push(b'\n');
            self.out.write_all(line).map_err(write_error(&self.tmp))?;
        }
        Ok(())
    }

    /// Flushes the file (the caller renames it).
    fn finish(mut self) -> Result<()> {
        self.out.flush().map_err(write_error(&self.tmp))
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
