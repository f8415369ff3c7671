//! Parquet tables: one flat table of named, typed columns written as one Parquet file
//! (arrow-rs), so that Spark, Dask, pandas and Polars read a study's results directly.
//!
//! The bytes are deterministic: same table → same file. The writer is pinned to one row
//! group, no compression, no timestamps, and a fixed `created_by` naming mtsim rather than
//! the parquet crate version. Nullable columns carry missing values as Parquet nulls;
//! floats are IEEE f64 as computed (not rounded as in the CSV).

use std::sync::Arc;

use arrow::array::{ArrayRef, BooleanArray, Float64Array, StringArray, UInt64Array};
use arrow::datatypes::{DataType, Field, Schema};
use arrow::record_batch::RecordBatch;
use parquet::arrow::ArrowWriter;
use parquet::basic::Compression;
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
