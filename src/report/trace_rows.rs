//! The rows of one run of a trace, column by column, held until the run's centring is known:
//! what `trace.csv` ([`super::trace`]) and `trace.parquet` ([`super::trace_parquet`]) are
//! written from, the spill file of what a run holds past its memory, and the write error
//! both formats report.
//!
//! A [`Block`] holds up to [`BLOCK_ROWS`] rows, each column a slice of that many values, so
//! that a block is a row group of `trace.parquet` as it stands (a column chunk is a slice),
//! and a spilled block goes to disk as one write of its columns, with no copy, and comes back
//! a column a read ([`SpillFile`]).

use std::fs::File;
use std::io::{IoSlice, Read, Seek, Write};
use std::path::{Path, PathBuf};

use arrow::datatypes::ToByteSlice;

use crate::error::{Error, Result};
use crate::measure::ballbar::Centring;
use crate::{Axis, AxisVec};

/// Rows a block holds: a row group of `trace.parquet` (4 s of machine time at 1 ms; about
/// 700 kB for five axes, so that a block that is reused touches few pages).
pub const BLOCK_ROWS: usize = 4_096;

/// Values from one column's start to the next's: a cache line more than the rows, so that
/// the columns of one row fall in different cache sets (at a stride of a power of two, the
/// 22 values of a row would compete for one set of the L1 cache, and miss at every row).
const STRIDE: usize = BLOCK_ROWS + 8;

/// Columns besides the three per axis: time, line, θ, sin θ, cos θ (so that the centring
/// needs no second `sin_cos`), the nonlinear signature, dL.
pub(super) const FIXED_COLUMNS: usize = 7;

/// Column indices in a block; the axes' columns (commanded, actual, following error per
/// axis) start at [`AXES`], and the nonlinear signature and dL are the last two.
pub(super) const TIME: usize = 0;
pub(super) const LINE: usize = 1;
pub(super) const THETA: usize = 2;
const SIN: usize = 3;
const COS: usize = 4;
pub(super) const AXES: usize = 5;

pub(super) fn write_error(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Write {
        path: path.to_path_buf(),
        source,
    }
}

/// A binary temporary file for what a run holds past the memory it may use (see
/// `super::trace::RAW_IN_MEMORY`): created at the first spill, emptied at each run's end for
/// the next, removed when dropped. Values go in as they are in memory (native byte order:
/// the same process reads them back), in large writes and reads, so it has no buffer of its
/// own.
pub(super) struct SpillFile {
    path: PathBuf,
    file: Option<File>,
}

impl SpillFile {
    pub fn new(path: PathBuf) -> SpillFile {
        SpillFile { path, file: None }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The file to append to, created at the first call.
    pub fn writer(&mut self) -> Result<&mut File> {
        if self.file.is_none() {
            let file = File::options()
                .read(true)
                .write(true)
                .create(true)
                .truncate(true)
                .open(&self.path)
                .map_err(write_error(&self.path))?;
            self.file = Some(file);
        }
        Ok(self.file.as_mut().expect("created above"))
    }

    /// What was written since the last [`SpillFile::clear`], from its start.
    pub fn reader(&mut self) -> Result<&File> {
        self.writer()?;
        let (path, file) = (&self.path, self.file.as_mut().expect("created above"));
        file.rewind().map_err(write_error(path))?;
        Ok(file)
    }

    /// Empties the file for the next run.
    pub fn clear(&mut self) -> Result<()> {
        let Some(file) = self.file.as_mut() else {
            return Ok(());
        };
        file.rewind()
            .and_then(|()| file.set_len(0))
            .map_err(write_error(&self.path))
    }
}

impl Drop for SpillFile {
    fn drop(&mut self) {
        // Finished or failed, a run's spilled rows are not kept.
        self.file = None;
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Up to [`BLOCK_ROWS`] rows of one run, column `k` in `values[k·STRIDE ..]`.
#[derive(Debug)]
pub(super) struct Block {
    values: Vec<f64>,
    rows: usize,
    width: usize,
}

impl Block {
    /// An empty block of `width` columns. Zeroed by the allocator: pages that no row
    /// reaches are never touched.
    pub fn new(width: usize) -> Block {
        Block {
            values: vec![0.0; width * STRIDE],
            rows: 0,
            width,
        }
    }

    pub fn rows(&self) -> usize {
        self.rows
    }

    pub fn is_full(&self) -> bool {
        self.rows == BLOCK_ROWS
    }

    /// Appends a row: time, line, θ, sin θ, cos θ (`head`), each of `axes`' commanded and
    /// actual position and following error (`[commanded, actual, error][j][axis]`), the
    /// nonlinear signature and dL (`tail`). Each value goes straight to its column.
    #[inline]
    pub fn push(
        &mut self,
        head: [f64; 5],
        axes: &[Axis],
        [commanded, actual, error]: [&AxisVec; 3],
        tail: [f64; 2],
    ) {
        debug_assert!(AXES + 3 * axes.len() + 2 == self.width);
        const G: usize = STRIDE;
        let r = self.rows;
        assert!(r < BLOCK_ROWS, "a block with room");
        // Split so that each index below is known in bounds from `r < BLOCK_ROWS` alone.
        let (head_columns, rest) = self.values.split_at_mut(AXES * G);
        for (k, x) in head.into_iter().enumerate() {
            head_columns[k * G + r] = x;
        }
        let (axis_columns, tail_columns) = rest.split_at_mut(3 * G * axes.len());
        for (columns, &a) in axis_columns.chunks_exact_mut(3 * G).zip(axes) {
            columns[r] = commanded[a];
            columns[G + r] = actual[a];
            columns[2 * G + r] = error[a];
        }
        tail_columns[r] = tail[0];
        tail_columns[G + r] = tail[1];
        self.rows += 1;
    }

    /// Column `k` of the rows held.
    #[inline]
    pub fn column(&self, k: usize) -> &[f64] {
        &self.values[k * STRIDE..k * STRIDE + self.rows]
    }

    /// The number of columns.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Empties the block (its memory stays, for the next rows).
    pub fn clear(&mut self) {
        self.rows = 0;
    }

    /// Each row's centred deviation ([`centred`]) with its run's `centring` (dL itself without
    /// one), into `out`.
    pub fn centred_into(&self, centring: Option<Centring>, out: &mut Vec<f64>) {
        let (dev, sin, cos) = (
            self.column(self.width - 1),
            self.column(SIN),
            self.column(COS),
        );
        out.clear();
        match centring {
            None => out.extend_from_slice(dev),
            Some(c) => out.extend(
                dev.iter()
                    .zip(sin.iter().zip(cos))
                    .map(|(&d, (&s, &k))| centred(d, (s, k), c)),
            ),
        }
    }

    /// Appends each row's `(dL, sin θ, cos θ)` to `out`: what its centred deviation needs.
    pub fn centring_inputs_into(&self, out: &mut Vec<f64>) {
        let (dev, sin, cos) = (
            self.column(self.width - 1),
            self.column(SIN),
            self.column(COS),
        );
        for ((&d, &s), &c) in dev.iter().zip(sin).zip(cos) {
            out.extend_from_slice(&[d, s, c]);
        }
    }

    /// Writes a full block's values, column after column as they are in memory, to `out` (a
    /// spill): one vectored write of the columns, no copy.
    pub fn write_raw(&self, out: &mut File) -> std::io::Result<()> {
        let mut columns: Vec<IoSlice<'_>> = (self.values.chunks_exact(STRIDE))
            .map(|column| IoSlice::new(column[..BLOCK_ROWS].to_byte_slice()))
            .collect();
        write_all_vectored(out, &mut columns)
    }

    /// Reads a full block written by [`Block::write_raw`] from `input`.
    pub fn read_raw(&mut self, input: &mut impl Read) -> std::io::Result<()> {
        for column in self.values.chunks_exact_mut(STRIDE) {
            read_f64s_into(input, &mut column[..BLOCK_ROWS])?;
        }
        self.rows = BLOCK_ROWS;
        Ok(())
    }
}

/// Fills `out` with f64 read from `input`, in the machine's byte order (as [`SpillFile`]
/// holds them): one read of the whole slice.
pub(super) fn read_f64s_into(input: &mut impl Read, out: &mut [f64]) -> std::io::Result<()> {
    let mut bytes = vec![0u8; 8 * out.len()];
    input.read_exact(&mut bytes)?;
    for (v, b) in out.iter_mut().zip(bytes.chunks_exact(8)) {
        *v = f64::from_ne_bytes(b.try_into().expect("8 bytes"));
    }
    Ok(())
}

/// The centred deviations of rows given as `(dL, sin θ, cos θ)` in a row
/// ([`Block::centring_inputs_into`]), with their run's `centring` (dL without one), into `out`.
pub(super) fn centred_from_inputs(inputs: &[f64], centring: Option<Centring>, out: &mut Vec<f64>) {
    out.clear();
    out.extend(inputs.chunks_exact(3).map(|t| match centring {
        None => t[0],
        Some(c) => centred(t[0], (t[1], t[2]), c),
    }));
}

/// The centred deviation `dL - (a cos θ + b sin θ)` of a row with deviation `dev` (dL) at
/// `sin_cos` (the sine and cosine of θ the ball bar took: the same bits) in a run whose
/// ball bar was centred by `centring`.
#[inline(always)]
fn centred(dev: f64, sin_cos: (f64, f64), centring: Centring) -> f64 {
    dev - centring.offset_um_at(sin_cos)
}

/// Writes every byte of `slices` to `file`, in as few system calls as it takes.
pub(super) fn write_all_vectored(
    file: &mut File,
    mut slices: &mut [IoSlice<'_>],
) -> std::io::Result<()> {
    IoSlice::advance_slices(&mut slices, 0);
    while !slices.is_empty() {
        match file.write_vectored(slices) {
            Ok(0) => return Err(std::io::ErrorKind::WriteZero.into()),
            Ok(n) => IoSlice::advance_slices(&mut slices, n),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}
