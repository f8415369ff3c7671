//! Parquet tables: one flat table of named, typed columns written as one Parquet file
//! (arrow-rs), so that Spark, Dask, pandas and Polars read a study's results directly, and
//! read back column by column (the report reads `trace.parquet` through [`Table::read_parquet`]).
//!
//! The bytes are deterministic: same table → same file. The writer is pinned to one row
//! group, no compression, no timestamps, and a fixed `created_by` naming mtsim rather than
//! the parquet crate version. Nullable columns carry missing values as Parquet nulls;
//! floats are IEEE f64 as computed (not rounded as in the CSV).

use std::path::Path;
use std::sync::Arc;

use arrow::array::{
    Array, ArrayRef, BooleanArray, Float64Array, RecordBatchReader, StringArray, UInt64Array,
};
use arrow::datatypes::{DataType, Field, Schema};
use arrow::record_batch::RecordBatch;
use parquet::arrow::ArrowWriter;
use parquet::basic::Compression;
use parquet::file::metadata::KeyValue;
use parquet::file::properties::{EnabledStatistics, WriterProperties};

use crate::error::{Error, Result};

/// One column's values.
#[derive(Clone, Debug, PartialEq)]
pub enum Column {
    F64(Vec<Option<f64>>),
    U64(Vec<Option<u64>>),
    Bool(Vec<Option<bool>>),
    Str(Vec<Option<String>>),
}

impl Column {
    fn len(&self) -> usize {
        match self {
            Column::F64(v) => v.len(),
            Column::U64(v) => v.len(),
            Column::Bool(v) => v.len(),
            Column::Str(v) => v.len(),
        }
    }

    /// An empty column of the Parquet (Arrow) type `ty`; None for a type tables do not hold.
    fn empty_of(ty: &DataType) -> Option<Column> {
        match ty {
            DataType::Float64 => Some(Column::F64(Vec::new())),
            DataType::UInt64 => Some(Column::U64(Vec::new())),
            DataType::Boolean => Some(Column::Bool(Vec::new())),
            DataType::Utf8 => Some(Column::Str(Vec::new())),
            _ => None,
        }
    }

    /// Appends the values of `array` (of this column's type), nulls as `None`.
    fn extend_from(&mut self, array: &dyn Array) -> Option<()> {
        fn each<A: Array + 'static, T>(
            array: &dyn Array,
            out: &mut Vec<Option<T>>,
            value: impl Fn(&A, usize) -> T,
        ) -> Option<()> {
            let a = array.as_any().downcast_ref::<A>()?;
            out.extend((0..a.len()).map(|i| (!a.is_null(i)).then(|| value(a, i))));
            Some(())
        }
        match self {
            Column::F64(v) => each(array, v, |a: &Float64Array, i| a.value(i)),
            Column::U64(v) => each(array, v, |a: &UInt64Array, i| a.value(i)),
            Column::Bool(v) => each(array, v, |a: &BooleanArray, i| a.value(i)),
            Column::Str(v) => each(array, v, |a: &StringArray, i| a.value(i).to_string()),
        }
    }

    fn to_arrow(&self) -> (DataType, ArrayRef) {
        match self {
            Column::F64(v) => (DataType::Float64, Arc::new(Float64Array::from(v.clone()))),
            Column::U64(v) => (DataType::UInt64, Arc::new(UInt64Array::from(v.clone()))),
            Column::Bool(v) => (DataType::Boolean, Arc::new(BooleanArray::from(v.clone()))),
            Column::Str(v) => (DataType::Utf8, Arc::new(StringArray::from(v.clone()))),
        }
    }
}

/// A table: named columns of equal length.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    pub columns: Vec<(String, Column)>,
}

impl Table {
    pub fn new() -> Table {
        Table::default()
    }

    /// Adds a column (builder style).
    pub fn with(mut self, name: &str, column: Column) -> Table {
        self.columns.push((name.to_string(), column));
        self
    }

    /// The column named `name`.
    pub fn column(&self, name: &str) -> Option<&Column> {
        self.columns.iter().find(|(n, _)| n == name).map(|(_, c)| c)
    }

    /// Reads the columns of the Parquet file at `path` whose names `keep` accepts (the
    /// others are not decoded), in the file's order, every row group after the other.
    pub fn read_parquet(path: &Path, keep: &dyn Fn(&str) -> bool) -> Result<Table> {
        Table::read_parquet_with_metadata(path, keep).map(|(table, _)| table)
    }

    /// [`Table::read_parquet`], with the file's key-value metadata.
    pub fn read_parquet_with_metadata(
        path: &Path,
        keep: &dyn Fn(&str) -> bool,
    ) -> Result<(Table, Option<Vec<KeyValue>>)> {
        use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
        use parquet::arrow::ProjectionMask;

        let bad = |what: String| Error::invalid(path, what);
        let file = std::fs::File::open(path).map_err(|source| Error::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let builder = ParquetRecordBatchReaderBuilder::try_new(file)
            .map_err(|e| bad(format!("not a readable Parquet file: {e}")))?;
        let wanted: Vec<usize> = (builder.schema().fields().iter().enumerate())
            .filter(|(_, f)| keep(f.name()))
            .map(|(i, _)| i)
            .collect();
        let key_value = builder
            .metadata()
            .file_metadata()
            .key_value_metadata()
            .cloned();
        let mask = ProjectionMask::roots(builder.parquet_schema(), wanted);
        let reader = builder
            .with_projection(mask)
            .build()
            .map_err(|e| bad(format!("not a readable Parquet file: {e}")))?;
        let mut table = Table::new();
        for field in reader.schema().fields() {
            let column = Column::empty_of(field.data_type()).ok_or_else(|| {
                bad(format!(
                    "column `{}` is of type {}, not f64, u64, bool or text",
                    field.name(),
                    field.data_type()
                ))
            })?;
            table.columns.push((field.name().clone(), column));
        }
        for batch in reader {
            let batch = batch.map_err(|e| bad(format!("cannot read a row group: {e}")))?;
            for ((name, column), array) in table.columns.iter_mut().zip(batch.columns()) {
                column
                    .extend_from(array.as_ref())
                    .ok_or_else(|| bad(format!("column `{name}` changes its type")))?;
            }
        }
        Ok((table, key_value))
    }

    /// Rows in the table (0 without columns).
    pub fn rows(&self) -> usize {
        self.columns.first().map_or(0, |(_, c)| c.len())
    }

    /// The table as the bytes of one Parquet file.
    pub fn to_parquet(&self) -> Result<Vec<u8>> {
        let err = |e: &dyn std::fmt::Display| Error::usage(format!("cannot write Parquet: {e}"));
        let rows = self.rows();
        if let Some((name, _)) = self.columns.iter().find(|(_, c)| c.len() != rows) {
            return Err(err(&format!("column {name} has not {rows} rows")));
        }
        let (fields, arrays): (Vec<Field>, Vec<ArrayRef>) = self
            .columns
            .iter()
            .map(|(name, c)| {
                let (ty, array) = c.to_arrow();
                (Field::new(name, ty, true), array)
            })
            .unzip();
        let schema = Arc::new(Schema::new(fields));
        let batch = RecordBatch::try_new(schema.clone(), arrays).map_err(|e| err(&e))?;
        let props = WriterProperties::builder()
            .set_compression(Compression::UNCOMPRESSED)
            .set_statistics_enabled(EnabledStatistics::Chunk)
            .set_created_by(format!("mtsim {}", env!("CARGO_PKG_VERSION")))
            .set_max_row_group_size(rows.max(1))
            .build();
        let mut writer =
            ArrowWriter::try_new(Vec::new(), schema, Some(props)).map_err(|e| err(&e))?;
        writer.write(&batch).map_err(|e| err(&e))?;
        writer.into_inner().map_err(|e| err(&e))
    }
}
