//! `trace.csv` (or `trace.parquet`): one row per traced sample, as a pipeline sink.
//!
//! Columns: direction, time, line, θ, then per axis the commanded and actual position and
//! the following error, then the nonlinear signature, the deviation dL and the centred
//! deviation `dL - (a cos θ + b sin θ)`. The centring is the least-squares fit of a whole
//! run, known only at its end ([`TraceSink::end_run`]), so rows are gathered in blocks
//! ([`Block`], column by column) and each format keeps what it needs until then:
//! `trace.csv` holds the run's blocks (`CsvRuns`); `trace.parquet` writes each full block
//! as a row group and holds only each row's `(dL, sin θ, cos θ)` (`ParquetRuns`). Past
//! [`RAW_IN_MEMORY`] bytes, what is held moves to a binary temporary file (`SpillFile`)
//! and is read back at the run's end: memory stays bounded. Blocks are reused by the next
//! run (their memory is mapped once). The trace file appears, by a rename, only when
//! complete; a run that fails leaves no temporary file.
//!
//! [`read_trace`] reads a run folder's trace back (`trace.csv` or `trace.parquet`, the
//! columns the report plots) into one [`Trace`] per format: the one reader of trace files.

use std::fs::File;
use std::io::{BufReader, BufWriter, Write};

use arrow::datatypes::ToByteSlice;
use std::path::{Path, PathBuf};

use super::contour::ContourFile;
use super::files::temporary_path;
use super::trace_parquet::ParquetTrace;
use super::trace_rows::{
    centred_from_inputs, read_f64s_into, write_error, Block, SpillFile, AXES, BLOCK_ROWS,
    FIXED_COLUMNS, LINE, THETA, TIME,
};
use crate::error::{Error, Result};
use crate::input::program::{Direction, MeasuredLines};
use crate::input::scenario::TraceFormat;
use crate::measure::ballbar::Centring;
use crate::measure::contour::ContourReading;
use crate::measure::{is_measured, BarGeometry, BarReading};
use crate::numeric::push_fixed_bytes_const;
use crate::pipeline::{Sample, Sink};
use crate::Axis;

/// What one run holds in memory, at most, before it spills to the temporary file, bytes (the
/// CSV trace's full blocks: about twelve of 4,096 rows; the Parquet trace's centring inputs).
pub const RAW_IN_MEMORY: usize = 8 << 20;

/// Writes the trace of every run of a simulation.
pub struct TraceSink {
    /// The block being filled with the current run's rows.
    filling: Option<Block>,
    /// The rows of the run's earlier blocks and the trace file, as the format keeps them.
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
    /// A program's trace (no ball bar): `contour.csv` beside it ([`super::contour`]).
    contour: Option<ContourFile>,
}

/// Each format's state between a run's blocks, its trace file opened at its first rows.
enum Format {
    Csv(CsvRuns),
    Parquet(ParquetRuns),
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
        let spill = SpillFile::new(trace_path.with_extension("csv.raw.tmp"));
        let format = match format {
            TraceFormat::Csv => Format::Csv(CsvRuns {
                direct: geometry.is_none(),
                width,
                held: Vec::new(),
                spare: Vec::new(),
                spill,
                spilled: 0,
                centred: Vec::new(),
                tmp,
                header: names.join(","),
                out: None,
            }),
            TraceFormat::Parquet => Format::Parquet(ParquetRuns {
                direct: geometry.is_none(),
                width,
                spare: None,
                inputs: Vec::new(),
                spill,
                inputs_spilled: 0,
                run_first_group: 0,
                centred: Vec::new(),
                tmp,
                names,
                out: None,
            }),
        };
        let contour = match geometry {
            None => Some(ContourFile::create(
                &trace_path.with_file_name(super::contour::CONTOUR_FILE),
            )?),
            Some(_) => None,
        };
        Ok(TraceSink {
            contour,
            filling: None,
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
        let last = self.filling.take();
        match &mut self.format {
            Format::Csv(csv) => csv.end_run(last, self.direction, centring),
            Format::Parquet(parquet) => parquet.end_run(last, self.direction, centring),
        }
    }

    /// Puts the trace file in place; every run's rows were written by
    /// [`TraceSink::end_run`], the only place that knows their centring.
    pub fn finish(mut self) -> Result<()> {
        // Rows of a run not ended (none from `run_ballbar`): written as they are, not lost.
        if self.filling.is_some() {
            self.end_run(None)?;
        }
        let closed = match &mut self.format {
            Format::Csv(csv) => csv.finish(),
            Format::Parquet(parquet) => parquet.finish(),
        };
        if let Err(e) = closed {
            let _ = std::fs::remove_file(temporary_path(&self.trace_path));
            return Err(e);
        }
        let tmp = temporary_path(&self.trace_path);
        std::fs::rename(&tmp, &self.trace_path).map_err(write_error(&self.trace_path))?;
        match self.contour.take() {
            Some(contour) => contour.finish(),
            None => Ok(()),
        }
    }
}

impl Drop for TraceSink {
    fn drop(&mut self) {
        // Finished or failed, an unfinished trace is not kept (nor the spill file, which
        // removes itself).
        let open = match &mut self.format {
            Format::Csv(csv) => csv.out.take().is_some(),
            Format::Parquet(parquet) => parquet.out.take().is_some(),
        };
        if open {
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
        if self.filling.as_ref().is_none_or(Block::is_full) {
            self.next_block()?;
        }
        let (sin, cos) = r.theta_sin_cos;
        let block = self.filling.as_mut().expect("a block with room");
        block.push(
            [s.time_s, s.line as f64, r.theta_deg, sin, cos],
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
        if self.filling.as_ref().is_none_or(Block::is_full) {
            self.next_block()?;
        }
        let nan = f64::NAN;
        let block = self.filling.as_mut().expect("a block with room");
        block.push(
            [s.time_s, s.line as f64, nan, nan, nan],
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

    /// Hands the full block (if any) to the format and takes an empty one for the next rows.
    fn next_block(&mut self) -> Result<()> {
        let full = self.filling.take();
        self.filling = Some(match &mut self.format {
            Format::Csv(csv) => csv.next_block(full, self.direction)?,
            Format::Parquet(parquet) => parquet.next_block(full, self.direction)?,
        });
        Ok(())
    }
}

/// `trace.csv`'s state: the run's full blocks, held until its centring is known (past
/// [`RAW_IN_MEMORY`], moved to the spill file), then written row by row.
struct CsvRuns {
    /// A program's trace (no ball bar): nothing to centre, so each full block is written at
    /// once and nothing is held.
    direct: bool,
    /// Columns of a block.
    width: usize,
    held: Vec<Block>,
    /// Emptied blocks, for the next rows.
    spare: Vec<Block>,
    /// The spill file, and how many blocks of the current run it holds.
    spill: SpillFile,
    spilled: usize,
    /// The centred deviations of the block being written.
    centred: Vec<f64>,
    /// The trace's temporary file and header, and the file once opened.
    tmp: PathBuf,
    header: String,
    out: Option<CsvTrace>,
}

impl CsvRuns {
    /// Holds the `full` block (when the held blocks pass [`RAW_IN_MEMORY`], they move to
    /// the spill file), and gives an empty one.
    fn next_block(&mut self, full: Option<Block>, direction: Direction) -> Result<Block> {
        if self.direct {
            if let Some(mut full) = full {
                self.write_now(&mut full, direction)?;
                self.spare.push(full);
            }
            return Ok(self.spare.pop().unwrap_or_else(|| Block::new(self.width)));
        }
        if let Some(full) = full {
            self.held.push(full);
            if self.held.len() * 8 * BLOCK_ROWS * self.width > RAW_IN_MEMORY {
                self.spill()?;
            }
        }
        Ok(self.spare.pop().unwrap_or_else(|| Block::new(self.width)))
    }

    /// Writes `block` (of a program's trace: nothing to centre) and empties it.
    fn write_now(&mut self, block: &mut Block, direction: Direction) -> Result<()> {
        if self.out.is_none() {
            self.out = Some(CsvTrace::create(self.tmp.clone(), &self.header)?);
        }
        let out = self.out.as_mut().expect("opened above");
        block.centred_into(None, &mut self.centred);
        out.write_block(block, direction, &self.centred)?;
        block.clear();
        Ok(())
    }

    /// Moves the held (full) blocks to the spill file.
    fn spill(&mut self) -> Result<()> {
        for mut block in std::mem::take(&mut self.held) {
            block
                .write_raw(self.spill.writer()?)
                .map_err(write_error(self.spill.path()))?;
            block.clear();
            self.spare.push(block);
            self.spilled += 1;
        }
        Ok(())
    }

    /// Writes the run's rows (the spilled blocks, the held ones, then `last`), centred with
    /// `centring`, and empties them.
    fn end_run(
        &mut self,
        last: Option<Block>,
        direction: Direction,
        centring: Option<Centring>,
    ) -> Result<()> {
        if self.direct {
            if let Some(mut last) = last {
                self.write_now(&mut last, direction)?;
                self.spare.push(last);
            }
            return Ok(());
        }
        self.held.extend(last);
        if self.held.is_empty() && self.spilled == 0 {
            return Ok(());
        }
        if self.out.is_none() {
            self.out = Some(CsvTrace::create(self.tmp.clone(), &self.header)?);
        }
        let out = self.out.as_mut().expect("opened above");
        if self.spilled > 0 {
            let path = self.spill.path().to_path_buf();
            let mut block = self.spare.pop().unwrap_or_else(|| Block::new(self.width));
            let mut reader = self.spill.reader()?;
            for _ in 0..self.spilled {
                block.read_raw(&mut reader).map_err(write_error(&path))?;
                block.centred_into(centring, &mut self.centred);
                out.write_block(&block, direction, &self.centred)?;
            }
            self.spill.clear()?;
            block.clear();
            self.spare.push(block);
            self.spilled = 0;
        }
        for mut block in std::mem::take(&mut self.held) {
            block.centred_into(centring, &mut self.centred);
            out.write_block(&block, direction, &self.centred)?;
            block.clear();
            self.spare.push(block);
        }
        Ok(())
    }

    /// Flushes the trace file (with its header only when no run had rows); the caller
    /// renames it.
    fn finish(&mut self) -> Result<()> {
        match self.out.take() {
            Some(out) => out.finish(),
            None => CsvTrace::create(self.tmp.clone(), &self.header)?.finish(),
        }
    }
}

/// `trace.parquet`'s state: each full block is written at once as a row group, and each
/// row's `(dL, sin θ, cos θ)` kept (past [`RAW_IN_MEMORY`], in the spill file) for the
/// run's centred deviations, written at its end.
struct ParquetRuns {
    /// A program's trace (no ball bar): no centring inputs are kept, the centred column is
    /// dL (NaN) as it is.
    direct: bool,
    /// Columns of a block.
    width: usize,
    /// The block written last, emptied for the next rows.
    spare: Option<Block>,
    /// The current run's centring inputs in memory, and how many went to the spill file.
    inputs: Vec<f64>,
    spill: SpillFile,
    inputs_spilled: usize,
    /// The current run's first row group.
    run_first_group: usize,
    /// The centred deviations of the row group being written.
    centred: Vec<f64>,
    /// The trace's temporary file and columns, and the file once opened.
    tmp: PathBuf,
    names: Vec<String>,
    out: Option<ParquetTrace>,
}

impl ParquetRuns {
    /// Writes the `full` block (if any) of the run `direction`, and gives an empty one.
    fn next_block(&mut self, full: Option<Block>, direction: Direction) -> Result<Block> {
        match full {
            Some(block) => self.write(block, direction),
            None => Ok(self.spare.take().unwrap_or_else(|| Block::new(self.width))),
        }
    }

    /// Writes the columns of `block` as a row group and keeps what its centred deviations
    /// need; gives the block back emptied.
    fn write(&mut self, mut block: Block, direction: Direction) -> Result<Block> {
        if block.rows() > 0 {
            if self.out.is_none() {
                self.out = Some(ParquetTrace::create(self.tmp.clone(), self.names.clone())?);
            }
            let out = self.out.as_mut().expect("opened above");
            out.write_block(&block, direction)?;
            if self.direct {
                // Nothing to centre: the centred column is dL (NaN) as it is.
                block.centred_into(None, &mut self.centred);
                out.write_centred(out.groups() - 1, &self.centred)?;
                block.clear();
                return Ok(block);
            }
            block.centring_inputs_into(&mut self.inputs);
            if 8 * self.inputs.len() > RAW_IN_MEMORY {
                self.spill
                    .writer()?
                    .write_all(self.inputs.to_byte_slice())
                    .map_err(write_error(self.spill.path()))?;
                self.inputs_spilled += self.inputs.len();
                self.inputs.clear();
            }
        }
        block.clear();
        Ok(block)
    }

    /// Writes the columns of `last` (the block being filled), then the centred deviations
    /// of every row group of the run.
    fn end_run(
        &mut self,
        last: Option<Block>,
        direction: Direction,
        centring: Option<Centring>,
    ) -> Result<()> {
        if let Some(block) = last {
            self.spare = Some(self.write(block, direction)?);
        }
        let direct = self.direct;
        let Some(out) = self.out.as_mut().filter(|_| !direct) else {
            return Ok(());
        };
        let path = self.spill.path().to_path_buf();
        let mut spilled = match self.inputs_spilled {
            0 => None,
            _ => Some(self.spill.reader()?),
        };
        let (mut from_file, mut at) = (self.inputs_spilled, 0);
        let mut read = Vec::new();
        for group in self.run_first_group..out.groups() {
            let need = 3 * out.group_rows(group);
            let inputs = match spilled.as_mut().filter(|_| from_file > 0) {
                Some(reader) => {
                    let n = need.min(from_file);
                    read.clear();
                    read.resize(n, 0.0);
                    read_f64s_into(reader, &mut read).map_err(write_error(&path))?;
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
        if spilled.is_some() {
            self.spill.clear()?;
        }
        self.inputs.clear();
        self.inputs_spilled = 0;
        self.run_first_group = out.groups();
        Ok(())
    }

    /// Writes the footer (a trace without rows: the schema only); the caller renames the
    /// file.
    fn finish(&mut self) -> Result<()> {
        match self.out.take() {
            Some(out) => out.finish(),
            None => ParquetTrace::create(self.tmp.clone(), self.names.clone())?.finish(),
        }
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
