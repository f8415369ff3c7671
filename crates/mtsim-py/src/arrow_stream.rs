//! A trace handed to pyarrow through the Arrow C stream interface (`__arrow_c_stream__`,
//! the PyCapsule protocol): the record batches built in Rust are moved into pyarrow's
//! table without a copy of their buffers.

use std::ffi::CString;
use std::path::Path;

use std::sync::Arc;

use arrow::array::{
    Array, AsArray, Float64Array, RecordBatch, RecordBatchIterator, RecordBatchReader,
};
use arrow::datatypes::{DataType, Field, Float64Type, Schema, SchemaRef};
use arrow::ffi_stream::FFI_ArrowArrayStream;
use mtsim::error::Error;
use mtsim::input::program::Direction;
use mtsim::report::trace_centring::{
    centred_deviation_um, centring_per_run, parquet_centrings, CENTRED_COLUMN,
};
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyCapsule;

/// The columns of a table and its batches, owned in Rust until pyarrow takes them.
pub struct Batches {
    pub schema: SchemaRef,
    pub batches: Vec<RecordBatch>,
}

impl Batches {
    /// The table of a Parquet file, read as one batch (one chunk per column), and the file's
    /// key-value metadata.
    fn read_with_metadata(
        path: &Path,
    ) -> mtsim::Result<(Batches, Option<Vec<parquet::file::metadata::KeyValue>>)> {
        let read_error = |e: &dyn std::fmt::Display| Error::Read {
            path: path.to_path_buf(),
            source: std::io::Error::other(e.to_string()),
        };
        let file = std::fs::File::open(path).map_err(|source| Error::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let builder = ParquetRecordBatchReaderBuilder::try_new(file).map_err(|e| read_error(&e))?;
        let rows = builder.metadata().file_metadata().num_rows().max(1) as usize;
        let key_value = builder
            .metadata()
            .file_metadata()
            .key_value_metadata()
            .cloned();
        let reader = builder
            .with_batch_size(rows)
            .build()
            .map_err(|e| read_error(&e))?;
        let schema = reader.schema();
        let batches = reader
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| read_error(&e))?;
        Ok((Batches { schema, batches }, key_value))
    }

    /// The table of a Parquet file, read as one batch (one chunk per column).
    pub fn read_parquet(path: &Path) -> mtsim::Result<Batches> {
        Batches::read_with_metadata(path).map(|(batches, _)| batches)
    }

    /// `simulate`'s `trace.parquet`, with the centred deviation added from the file's
    /// centrings, as every reader of the trace does.
    pub fn read_trace_parquet(path: &Path) -> mtsim::Result<Batches> {
        let (read, key_value) = Batches::read_with_metadata(path)?;
        let read_error = |e: String| Error::Read {
            path: path.to_path_buf(),
            source: std::io::Error::other(e),
        };
        let centrings = parquet_centrings(key_value.as_ref()).map_err(read_error)?;
        read.with_centred_column(&centrings).map_err(read_error)
    }

    /// A trace's batches with `deviation_centred_um` appended: each row's dL less its
    /// run's centring (`mtsim::report::trace_centring::centred_deviation_um`; a run is a stretch of
    /// rows of one direction).
    fn with_centred_column(
        self,
        centrings: &[mtsim::report::trace_centring::RunCentring],
    ) -> Result<Batches, String> {
        let mut fields: Vec<Field> = self
            .schema
            .fields()
            .iter()
            .map(|f| f.as_ref().clone())
            .collect();
        fields.push(Field::new(CENTRED_COLUMN, DataType::Float64, false));
        let schema: SchemaRef = Arc::new(Schema::new_with_metadata(
            fields,
            self.schema.metadata().clone(),
        ));
        let mut batches = Vec::with_capacity(self.batches.len());
        let mut previous: Option<Direction> = None;
        let mut runs = Vec::new();
        for batch in &self.batches {
            let column = |name: &str| {
                let c = batch
                    .column_by_name(name)
                    .ok_or(format!("no column `{name}`"))?;
                arrow::compute::cast(c, &DataType::Float64).map_err(|e| e.to_string())
            };
            let (theta, dev) = (column("theta_deg")?, column("deviation_um")?);
            let direction = batch
                .column_by_name("direction")
                .ok_or("no column `direction`")?;
            let direction =
                arrow::compute::cast(direction, &DataType::Utf8).map_err(|e| e.to_string())?;
            let direction = direction.as_string::<i32>();
            let (theta, dev) = (
                theta.as_primitive::<Float64Type>(),
                dev.as_primitive::<Float64Type>(),
            );
            let mut run_of_row = Vec::with_capacity(batch.num_rows());
            for i in 0..batch.num_rows() {
                let d = if direction.value(i) == "cw" {
                    Direction::Cw
                } else {
                    Direction::Ccw
                };
                if previous != Some(d) {
                    runs.push(d);
                    previous = Some(d);
                }
                run_of_row.push(runs.len() - 1);
            }
            let per_run = centring_per_run(runs.iter().copied(), centrings);
            let centred: Float64Array = (0..batch.num_rows())
                .map(|i| centred_deviation_um(dev.value(i), theta.value(i), per_run[run_of_row[i]]))
                .collect::<Vec<f64>>()
                .into();
            let mut columns = batch.columns().to_vec();
            columns.push(Arc::new(centred));
            batches.push(RecordBatch::try_new(schema.clone(), columns).map_err(|e| e.to_string())?);
        }
        Ok(Batches { schema, batches })
    }
}

/// An Arrow stream that pyarrow reads once: `pyarrow.table(stream)` or
/// `pyarrow.RecordBatchReader.from_stream(stream)`.
#[pyclass(module = "mtsim._native")]
pub struct ArrowStream {
    batches: Option<Batches>,
}

impl ArrowStream {
    pub fn new(batches: Batches) -> ArrowStream {
        ArrowStream {
            batches: Some(batches),
        }
    }
}

#[pymethods]
impl ArrowStream {
    /// The Arrow PyCapsule stream protocol. The stream is handed over once; the schema
    /// cannot be requested otherwise (`requested_schema` must be None).
    #[pyo3(signature = (requested_schema=None))]
    fn __arrow_c_stream__<'py>(
        &mut self,
        py: Python<'py>,
        requested_schema: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyCapsule>> {
        if requested_schema.is_some_and(|s| !s.is_none()) {
            return Err(PyRuntimeError::new_err(
                "an mtsim trace is exported in its own schema only",
            ));
        }
        let Batches { schema, batches } = self
            .batches
            .take()
            .ok_or_else(|| PyRuntimeError::new_err("this Arrow stream was already read"))?;
        let reader = RecordBatchIterator::new(batches.into_iter().map(Ok), schema);
        let stream = FFI_ArrowArrayStream::new(Box::new(reader));
        // The consumer moves the stream out and clears its release callback; dropping the
        // capsule releases a stream nobody took.
        PyCapsule::new(
            py,
            stream,
            Some(CString::new("arrow_array_stream").unwrap()),
        )
    }
}
