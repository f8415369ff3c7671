//! The rows of a trace gathered column by column until a block fills: what `trace.csv`
//! ([`super::trace`]) and `trace.parquet` ([`super::trace_parquet`]) are written from as the
//! run goes (nothing waits for the run's end), and the write error both formats report.
//!
//! A [`Block`] holds up to [`BLOCK_ROWS`] rows, each column a slice of that many values, so
//! that a block is a row group of `trace.parquet` as it stands (a column chunk is a slice).

use std::io::{IoSlice, Write};
use std::path::Path;

use crate::error::Error;
use crate::{Axis, AxisVec};

/// Rows a block holds: a row group of `trace.parquet` (4 s of machine time at 1 ms; about
/// 700 kB for five axes, so that a block that is reused touches few pages).
pub const BLOCK_ROWS: usize = 4_096;

/// Values from one column's start to the next's: a cache line more than the rows, so that
/// the columns of one row fall in different cache sets (at a stride of a power of two, the
/// 22 values of a row would compete for one set of the L1 cache, and miss at every row).
const STRIDE: usize = BLOCK_ROWS + 8;

/// Columns besides the three per axis: time, line, θ, the nonlinear signature, dL.
pub(super) const FIXED_COLUMNS: usize = 5;

/// Column indices in a block; the axes' columns (commanded, actual, following error per
/// axis) start at [`AXES`], and the nonlinear signature and dL are the last two.
pub(super) const TIME: usize = 0;
pub(super) const LINE: usize = 1;
pub(super) const THETA: usize = 2;
pub(super) const AXES: usize = 3;

pub(super) fn write_error(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Write {
        path: path.to_path_buf(),
        source,
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

    /// Appends a row: time, line, θ (`head`), each of `axes`' commanded and
    /// actual position and following error (`[commanded, actual, error][j][axis]`), the
    /// nonlinear signature and dL (`tail`). Each value goes straight to its column.
    #[inline]
    pub fn push(
        &mut self,
        head: [f64; AXES],
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
}

/// Writes every byte of `slices` to `file`, in as few system calls as it takes.
pub(super) fn write_all_vectored(
    file: &mut impl Write,
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
