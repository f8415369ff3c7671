//! `trace.parquet`: the columns of `trace.csv` as the f64 the run computed, one row group per
//! block of a run's rows ([`Block`]), its column chunks written straight from the block as
//! it fills; each run's centring goes into the footer's key-value metadata
//! ([`super::trace::CENTRING_KEY`]), where readers find it.
//!
//! The format is simple enough for a trace to be written without a Parquet writer in between
//! (which copied every value three times): the file is `PAR1`, then per row group and column
//! one data page (a page header, then the values), then the footer (the file metadata) and
//! its length, and `PAR1` again. Page headers and footer are Thrift compact structs
//! ([`super::thrift_compact`]). Every column is required, uncompressed and plain-encoded
//! (the little-endian values, no levels), but `direction`, which is dictionary-encoded: a
//! row group is one run, so its dictionary is the run's one name and its data page one RLE
//! run of index 0. Uncompressed: the doubles of a servo trace are nearly incompressible, and
//! compressing them costs more CPU than the file's whole encoding (docs/performance.md).
//! Min/max statistics on `time_s` and `line` (unsigned), which a reader filters rows by.
//! The same rows give the same bytes (fixed `created_by`, no timestamps).
//!
//! Why by hand: the parquet crate's `SerializedFileWriter` with its column writers (from the
//! block's slices, the same file for pyarrow) cost about 11 % of a whole `simulate` more
//! (docs/performance.md, issue 43 item 4), above the 10 % the issue allows; DuckDB and Polars
//! read this file as pyarrow does (`tests/python/test_trace_readers.py`).

// Parquet's plain encoding is little-endian, and the columns are written from memory as
// they are.
#[cfg(target_endian = "big")]
compile_error!(
    "trace.parquet writes the f64 columns' memory as they are: a little-endian target is needed"
);

use std::fs::File;
use std::io::IoSlice;
use std::path::PathBuf;

use arrow::datatypes::ToByteSlice;

use super::thrift_compact::Compact;
use super::trace_centring::{RunCentring, CENTRING_KEY};
use super::trace_rows::{write_all_vectored, write_error, Block, AXES, LINE, THETA, TIME};
use super::written::{Hashing, Written};
use crate::error::Result;
use crate::input::program::Direction;

/// Parquet's physical types, encodings and page types (parquet.thrift).
const BYTE_ARRAY: i32 = 6;
const INT64: i32 = 2;
const DOUBLE: i32 = 5;
const PLAIN: i32 = 0;
const RLE: i32 = 3;
const RLE_DICTIONARY: i32 = 8;
const DATA_PAGE: i32 = 0;
const DICTIONARY_PAGE: i32 = 2;
/// Converted types of the `direction` (UTF8) and `line` (UINT_64) columns.
const UTF8: i32 = 0;
const UINT_64: i32 = 14;

/// Rows per row group of `trace.parquet` at most (a block; a row group never holds two runs).
pub const PARQUET_ROW_GROUP: usize = super::trace_rows::BLOCK_ROWS;

/// A column chunk as the footer describes it.
struct Chunk {
    physical: i32,
    /// Offsets of its dictionary page (if any) and data page, and its size, bytes.
    dictionary_offset: Option<u64>,
    data_offset: u64,
    size: u64,
    /// Min and max as the statistics' bytes, for `time_s` and `line`.
    min_max: Option<([u8; 8], [u8; 8])>,
}

/// `trace.parquet` being written: its temporary file, the offset reached, and what the
/// footer will say of every row group written.
pub(super) struct ParquetTrace {
    tmp: PathBuf,
    /// The file, hashed as written (the manifest's record without reading it back).
    file: Hashing<File>,
    /// Bytes not yet written (the file's magic before the first pages; the spare buffer
    /// of [`Gather`] otherwise), and the file's length with them.
    pending: Vec<u8>,
    offset: u64,
    names: Vec<String>,
    groups: Vec<(usize, Vec<Chunk>)>,
    /// The `line` column of a block as integers.
    lines: Vec<u64>,
}

impl ParquetTrace {
    /// Creates the temporary file `tmp` for a trace with the columns `names` (those of
    /// `trace.csv`).
    pub fn create(tmp: PathBuf, names: Vec<String>) -> Result<ParquetTrace> {
        let file = File::create(&tmp).map_err(write_error(&tmp))?;
        Ok(ParquetTrace {
            tmp,
            file: Hashing::new(file),
            pending: b"PAR1".to_vec(),
            offset: 4,
            names,
            groups: Vec::new(),
            lines: Vec::new(),
        })
    }

    /// Starts gathering pages, after the bytes not yet written.
    fn gather<'a>(&mut self) -> Gather<'a> {
        Gather {
            small: std::mem::take(&mut self.pending),
            large: Vec::new(),
            offset: self.offset,
        }
    }

    /// Writes the gathered pages in one system call (as few as the kernel takes), with no
    /// copy of the columns: a whole row group at once, so that the kernel fills its page
    /// cache in large pieces (cheaper than a write per column chunk: docs/performance.md).
    fn flush(&mut self, g: Gather<'_>) -> Result<()> {
        let mut slices = g.slices();
        write_all_vectored(&mut self.file, &mut slices).map_err(write_error(&self.tmp))?;
        self.offset = g.offset;
        let mut spare = g.small;
        spare.clear();
        self.pending = spare;
        Ok(())
    }

    /// Writes the rows of `block`, of the run `direction`, as one row group.
    pub fn write_block(&mut self, block: &Block, direction: Direction) -> Result<()> {
        let rows = block.rows();
        let mut chunks = Vec::with_capacity(self.names.len());
        // Parquet's unsigned 64-bit integers are stored as INT64 bits.
        let mut lines = std::mem::take(&mut self.lines);
        lines.clear();
        lines.extend(block.column(LINE).iter().map(|&l| l as u64));
        let mut g = self.gather();
        // direction: a dictionary of the run's name (plain: length, bytes), then one RLE run
        // of index 0 (bit width 1; the run's header is its length shifted left once).
        let name: &[u8] = if direction == Direction::Cw {
            b"cw"
        } else {
            b"ccw"
        };
        let dictionary_offset = g.offset;
        let mut dictionary = (name.len() as u32).to_le_bytes().to_vec();
        dictionary.extend_from_slice(name);
        g.page(true, 1, PLAIN, &dictionary);
        let data_offset = g.offset;
        let mut indices = Compact::new();
        indices.bytes.push(1);
        indices.varint((rows as u64) << 1);
        indices.bytes.push(0);
        g.page(false, rows, RLE_DICTIONARY, &indices.bytes);
        chunks.push(Chunk {
            physical: BYTE_ARRAY,
            dictionary_offset: Some(dictionary_offset),
            data_offset,
            size: g.offset - dictionary_offset,
            min_max: None,
        });
        let time = block.column(TIME);
        chunks.push(g.plain(DOUBLE, rows, time.to_byte_slice(), min_max_f64(time)));
        let min_max = lines.iter().min().zip(lines.iter().max());
        let min_max = min_max.map(|(lo, hi)| (lo.to_le_bytes(), hi.to_le_bytes()));
        chunks.push(g.plain(INT64, rows, lines.to_byte_slice(), min_max));
        for k in std::iter::once(THETA).chain(AXES..block.width()) {
            let column = block.column(k);
            chunks.push(g.plain(DOUBLE, rows, column.to_byte_slice(), None));
        }
        let written = self.flush(g);
        self.lines = lines;
        written?;
        self.groups.push((rows, chunks));
        Ok(())
    }

    /// Writes the footer, with each run's `centrings` as key-value metadata, and flushes the
    /// file (the caller renames it); the record of the bytes written.
    pub fn finish(mut self, centrings: &[RunCentring]) -> Result<Written> {
        let centrings = serde_json::to_string(centrings).expect("plain data serializes");
        let footer = self.footer(&centrings);
        let length = (footer.len() as u32).to_le_bytes();
        let mut g = self.gather();
        for bytes in [&footer[..], &length, b"PAR1"] {
            g.push(bytes);
        }
        self.flush(g)?;
        Ok(self.file.record())
    }

    /// The file metadata (parquet.thrift's FileMetaData), `centrings` (JSON) under
    /// [`CENTRING_KEY`].
    fn footer(&self, centrings: &str) -> Vec<u8> {
        let mut f = Compact::new();
        f.i32(1, 1);
        // The schema: the root, then every column, required.
        f.struct_list(2, self.names.len() + 1);
        f.open();
        f.binary(4, b"schema");
        f.i32(5, self.names.len() as i32);
        f.end();
        for (k, name) in self.names.iter().enumerate() {
            f.open();
            f.i32(1, physical_of(k));
            f.i32(3, 0);
            f.binary(4, name.as_bytes());
            match k {
                0 => {
                    f.i32(6, UTF8);
                    f.begin(10);
                    f.begin(1); // STRING
                    f.end();
                    f.end();
                }
                2 => {
                    f.i32(6, UINT_64);
                    f.begin(10);
                    f.begin(10); // INTEGER
                    f.byte(1, 64);
                    f.bool(2, false);
                    f.end();
                    f.end();
                }
                _ => {}
            }
            f.end();
        }
        let rows: usize = self.groups.iter().map(|(rows, _)| rows).sum();
        f.i64(3, rows as i64);
        f.struct_list(4, self.groups.len());
        for (rows, chunks) in &self.groups {
            self.row_group(&mut f, *rows, chunks);
        }
        // key_value_metadata: one KeyValue (key, value).
        f.struct_list(5, 1);
        f.open();
        f.binary(1, CENTRING_KEY.as_bytes());
        f.binary(2, centrings.as_bytes());
        f.end();
        f.binary(6, format!("mtsim {}", env!("CARGO_PKG_VERSION")).as_bytes());
        // Column orders: every column by its type's order (what makes min/max usable).
        f.struct_list(7, self.names.len());
        for _ in &self.names {
            f.open();
            f.begin(1);
            f.end();
            f.end();
        }
        f.end();
        f.bytes
    }

    /// One row group of the footer (RowGroup, its ColumnChunks and their ColumnMetaData).
    fn row_group(&self, f: &mut Compact, rows: usize, chunks: &[Chunk]) {
        let size: u64 = chunks.iter().map(|c| c.size).sum();
        let start = chunks
            .first()
            .map_or(0, |c| c.dictionary_offset.unwrap_or(c.data_offset));
        f.open();
        f.struct_list(1, chunks.len());
        for (chunk, name) in chunks.iter().zip(&self.names) {
            f.open();
            f.i64(2, 0);
            f.begin(3);
            f.i32(1, chunk.physical);
            if chunk.dictionary_offset.is_some() {
                f.i32_list(2, &[PLAIN, RLE, RLE_DICTIONARY]);
            } else {
                f.i32_list(2, &[PLAIN, RLE]);
            }
            f.binary_list(3, &[name.as_bytes()]);
            f.i32(4, 0); // uncompressed
            f.i64(5, rows as i64);
            f.i64(6, chunk.size as i64);
            f.i64(7, chunk.size as i64);
            f.i64(9, chunk.data_offset as i64);
            if let Some(offset) = chunk.dictionary_offset {
                f.i64(11, offset as i64);
            }
            if let Some((min, max)) = &chunk.min_max {
                f.begin(12);
                f.i64(3, 0); // null count
                f.binary(5, max);
                f.binary(6, min);
                f.end();
            }
            f.end();
            f.end();
        }
        f.i64(2, size as i64);
        f.i64(3, rows as i64);
        f.i64(5, start as i64);
        f.i64(6, size as i64);
        f.end();
    }
}

/// The physical type of column `k` of the trace: `direction` text, `line` INT64, the rest
/// doubles.
fn physical_of(k: usize) -> i32 {
    match k {
        0 => BYTE_ARRAY,
        2 => INT64,
        _ => DOUBLE,
    }
}

/// The least and greatest of `values` that are numbers, as statistics bytes; None when none is.
fn min_max_f64(values: &[f64]) -> Option<([u8; 8], [u8; 8])> {
    let finite = values.iter().filter(|v| !v.is_nan());
    let (lo, hi) = finite.fold(None, |acc: Option<(f64, f64)>, &v| match acc {
        None => Some((v, v)),
        Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
    })?;
    Some((lo.to_le_bytes(), hi.to_le_bytes()))
}

/// Pages gathered for one write: headers and small pages copied into `small`, large pages
/// (a block's column slices) borrowed, each written after `small[..at]` and before the rest.
struct Gather<'a> {
    small: Vec<u8>,
    large: Vec<(usize, &'a [u8])>,
    /// The file's length with the bytes gathered.
    offset: u64,
}

impl<'a> Gather<'a> {
    /// Appends `bytes`: copied if small, by reference otherwise.
    fn push(&mut self, bytes: &'a [u8]) {
        if bytes.len() < 1 << 12 {
            self.copy(bytes);
        } else {
            self.offset += bytes.len() as u64;
            self.large.push((self.small.len(), bytes));
        }
    }

    /// Appends a copy of `bytes`.
    fn copy(&mut self, bytes: &[u8]) {
        self.offset += bytes.len() as u64;
        self.small.extend_from_slice(bytes);
    }

    /// Adds one page: its header (a dictionary page, or a data page of `encoding`), then
    /// `data`, of `values` values.
    fn page(&mut self, dictionary: bool, values: usize, encoding: i32, data: &'a [u8]) {
        let mut h = Compact::new();
        h.i32(
            1,
            if dictionary {
                DICTIONARY_PAGE
            } else {
                DATA_PAGE
            },
        );
        h.i32(2, data.len() as i32);
        h.i32(3, data.len() as i32);
        h.begin(if dictionary { 7 } else { 5 });
        h.i32(1, values as i32);
        h.i32(2, encoding);
        if !dictionary {
            // Definition and repetition levels (none: every column is required).
            h.i32(3, RLE);
            h.i32(4, RLE);
        }
        h.end();
        h.end();
        self.copy(&h.bytes);
        self.push(data);
    }

    /// Adds a plain-encoded column chunk of `values` values from `data`.
    fn plain(
        &mut self,
        physical: i32,
        values: usize,
        data: &'a [u8],
        min_max: Option<([u8; 8], [u8; 8])>,
    ) -> Chunk {
        let data_offset = self.offset;
        self.page(false, values, PLAIN, data);
        Chunk {
            physical,
            dictionary_offset: None,
            data_offset,
            size: self.offset - data_offset,
            min_max,
        }
    }

    /// The bytes in file order.
    fn slices(&self) -> Vec<IoSlice<'_>> {
        let mut slices = Vec::with_capacity(2 * self.large.len() + 1);
        let mut from = 0;
        for &(at, bytes) in &self.large {
            slices.push(IoSlice::new(&self.small[from..at]));
            slices.push(IoSlice::new(bytes));
            from = at;
        }
        slices.push(IoSlice::new(&self.small[from..]));
        slices
    }
}
