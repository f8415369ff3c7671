//! `trace.parquet`: the columns of `trace.csv` as the f64 the run computed, written with the
//! Parquet column writers (no Arrow arrays in between).
//!
//! Each row group of [`PARQUET_ROW_GROUP`] rows is gathered column by column from the raw
//! rows and each column written as one batch: plain-encoded doubles and unsigned integers
//! (copied, no per-value work besides the chunk's min and max), the direction dictionary
//! encoded (two values, so one bit per row after the dictionary page). Uncompressed: the
//! doubles of a servo trace are nearly incompressible, and compressing them costs more CPU
//! than the file's whole encoding (see docs/performance.md). The same rows give the same
//! bytes (fixed `created_by`, no timestamps).

use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::Path;
use std::sync::Arc;

use parquet::basic::{Compression, LogicalType, Repetition, Type as PhysicalType};
use parquet::data_type::{ByteArray, ByteArrayType, DoubleType, Int64Type};
use parquet::file::properties::{EnabledStatistics, WriterProperties};
use parquet::file::writer::SerializedFileWriter;
use parquet::schema::types::Type;

use super::files::temporary_path;
use super::trace_rows::{write_error, RawRows, RAW_FIXED_COLUMNS};
use crate::error::{Error, Result};
use crate::measure::BallbarRun;

/// Rows per row group of `trace.parquet` (16 s of machine time at 1 ms): what the writer
/// holds in memory at once, about 3 MB for five axes.
pub const PARQUET_ROW_GROUP: usize = 16_384;

/// The Parquet schema of the trace's columns `names`: `direction` text, `line` an unsigned
/// 64-bit integer, every other column a double; all required.
fn schema(names: &[String]) -> parquet::errors::Result<Type> {
    let fields = names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let (physical, logical) = match i {
                0 => (PhysicalType::BYTE_ARRAY, Some(LogicalType::String)),
                2 => (
                    PhysicalType::INT64,
                    Some(LogicalType::Integer {
                        bit_width: 64,
                        is_signed: false,
                    }),
                ),
                _ => (PhysicalType::DOUBLE, None),
            };
            Type::primitive_type_builder(name, physical)
                .with_repetition(Repetition::REQUIRED)
                .with_logical_type(logical)
                .build()
                .map(Arc::new)
        })
        .collect::<parquet::errors::Result<Vec<_>>>()?;
    Type::group_type_builder("schema")
        .with_fields(fields)
        .build()
}

/// Writes `trace_path` as Parquet from the binary rows read from `reader` (held rows, or
/// the file at `raw_path`), with the columns of `trace.csv` (`names`) and the centred
/// deviation of each row's run. Written to a temporary file, then renamed.
pub(super) fn complete_parquet<R: Read>(
    reader: R,
    raw_path: &Path,
    trace_path: &Path,
    names: &[String],
    runs: &[BallbarRun],
) -> Result<()> {
    let tmp = temporary_path(trace_path);
    // A failure of the Parquet writer is a failed write of the temporary file.
    let failed = |e: parquet::errors::ParquetError| Error::Write {
        path: tmp.clone(),
        source: std::io::Error::other(format!("cannot write Parquet: {e}")),
    };
    let props = WriterProperties::builder()
        .set_compression(Compression::UNCOMPRESSED)
        .set_dictionary_enabled(false)
        .set_column_dictionary_enabled("direction".into(), true)
        .set_statistics_enabled(EnabledStatistics::None)
        .set_column_statistics_enabled("time_s".into(), EnabledStatistics::Chunk)
        .set_column_statistics_enabled("line".into(), EnabledStatistics::Chunk)
        .set_created_by(format!("mtsim {}", env!("CARGO_PKG_VERSION")))
        .set_max_row_group_size(PARQUET_ROW_GROUP)
        .build();
    let schema = Arc::new(schema(names).map_err(failed)?);
    let file = File::create(&tmp).map_err(write_error(&tmp))?;
    let written = (|| -> Result<()> {
        // Buffered: besides whole pages the writer makes many small writes (page headers).
        let sink = BufWriter::with_capacity(1 << 20, file);
        let mut writer =
            SerializedFileWriter::new(sink, schema, Arc::new(props)).map_err(failed)?;
        // Raw rows: direction, time, line, θ, sin θ, cos θ, 3 per axis, nonlinear, dL; the
        // names have 7 columns besides the axes' 3 each.
        let width = RAW_FIXED_COLUMNS + (names.len() - 7);
        let mut rows = RawRows::new(reader, width, runs, raw_path, &tmp);
        let mut group = RowGroup::new(names.len() - 2);
        let mut more = true;
        while more {
            more = group.fill(&mut rows)?;
            if !group.line.is_empty() {
                group.write(&mut writer).map_err(failed)?;
            }
        }
        let mut out = writer.into_inner().map_err(failed)?;
        out.flush().map_err(write_error(&tmp))
    })();
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    std::fs::rename(&tmp, trace_path).map_err(write_error(trace_path))
}

/// The rows of one row group, column by column: the direction, the line, and the f64
/// columns in their order (time, θ, the axes', nonlinear, dL, centred dL), each f64 column a
/// slice of [`PARQUET_ROW_GROUP`] values in `floats` (a row's values stored in place).
struct RowGroup {
    direction: Vec<ByteArray>,
    line: Vec<i64>,
    floats: Vec<f64>,
}

impl RowGroup {
    fn new(n_floats: usize) -> RowGroup {
        RowGroup {
            direction: Vec::with_capacity(PARQUET_ROW_GROUP),
            line: Vec::with_capacity(PARQUET_ROW_GROUP),
            floats: vec![0.0; n_floats * PARQUET_ROW_GROUP],
        }
    }

    /// Empties the group and reads up to [`PARQUET_ROW_GROUP`] rows into it; false when the
    /// rows have ended.
    fn fill<R: Read>(&mut self, rows: &mut RawRows<'_, R>) -> Result<bool> {
        self.direction.clear();
        self.line.clear();
        // One buffer per direction, shared by its rows.
        let (ccw, cw) = (ByteArray::from("ccw"), ByteArray::from("cw"));
        const G: usize = PARQUET_ROW_GROUP;
        while self.line.len() < G {
            let Some((v, cw_row, centred)) = rows.next_row()? else {
                return Ok(false);
            };
            let r = self.line.len();
            self.direction
                .push(if cw_row { cw.clone() } else { ccw.clone() });
            // Parquet's unsigned 64-bit integers are stored as INT64 bits.
            self.line.push(v[2] as u64 as i64);
            let f = &mut self.floats;
            f[r] = v[1];
            f[G + r] = v[3];
            for (k, &x) in v[6..].iter().enumerate() {
                f[(2 + k) * G + r] = x;
            }
            let last = f.len() - G;
            f[last + r] = centred;
        }
        Ok(true)
    }

    /// Writes the group as one row group, one batch per column.
    fn write<W: Write + Send>(
        &self,
        writer: &mut SerializedFileWriter<W>,
    ) -> parquet::errors::Result<()> {
        let mut group = writer.next_row_group()?;
        let mut index = 0;
        while let Some(mut column) = group.next_column()? {
            match index {
                0 => {
                    column
                        .typed::<ByteArrayType>()
                        .write_batch(&self.direction, None, None)?;
                }
                2 => {
                    column
                        .typed::<Int64Type>()
                        .write_batch(&self.line, None, None)?;
                }
                _ => {
                    // Float columns: time (index 1), then the rest from index 3 on.
                    let k = if index == 1 { 0 } else { index - 2 };
                    let start = k * PARQUET_ROW_GROUP;
                    column.typed::<DoubleType>().write_batch(
                        &self.floats[start..start + self.line.len()],
                        None,
                        None,
                    )?;
                }
            }
            column.close()?;
            index += 1;
        }
        group.close()?;
        Ok(())
    }
}
