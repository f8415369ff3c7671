//! A trace handed to pyarrow through the Arrow C stream interface (`__arrow_c_stream__`,
//! the PyCapsule protocol): the record batches built in Rust are moved into pyarrow's
//! table without a copy of their buffers.

use std::ffi::CString;
use std::path::Path;

use arrow::array::{RecordBatch, RecordBatchIterator, RecordBatchReader};
use arrow::datatypes::SchemaRef;
use arrow::ffi_stream::FFI_ArrowArrayStream;
use mtsim::error::Error;
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
    /// The table of a Parquet file, read as one batch (one chunk per column).
    pub fn read_parquet(path: &Path) -> mtsim::Result<Batches> {
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
        let reader = builder
            .with_batch_size(rows)
            .build()
            .map_err(|e| read_error(&e))?;
        let schema = reader.schema();
        let batches = reader
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| read_error(&e))?;
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
