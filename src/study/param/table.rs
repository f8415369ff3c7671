//! The rows of a study as `rows.csv` and `rows.parquet`: the same columns, in the same
//! order, nulls as empty CSV fields.

use crate::error::{Error, Result};
use crate::report::parquet::{Column, Table};
use crate::study::param::evaluate::Row;

/// Column names: `point`, the varied keys, then the figures and per axis `B_<axis>_um` and
/// `spike_<axis>_um`.
pub fn columns(keys: &[String], axes: &[String]) -> Vec<String> {
    let mut c = vec!["point".to_string()];
    c.extend(keys.iter().cloned());
    c.extend(
        [
            "status",
            "error",
            "G_um",
            "F_max_um",
            "F_min_um",
            "H_um",
            "verdict",
            "violations",
        ]
        .map(String::from),
    );
    c.extend(axes.iter().map(|a| format!("B_{a}_um")));
    c.extend(axes.iter().map(|a| format!("spike_{a}_um")));
    c
}

/// The table's columns, as typed values.
fn typed(rows: &[Row], keys: usize, axes: usize) -> Vec<Column> {
    let f = |g: &dyn Fn(&Row) -> Option<f64>| Column::F64(rows.iter().map(g).collect());
    let s = |g: &dyn Fn(&Row) -> Option<String>| Column::Str(rows.iter().map(g).collect());
    let mut c = vec![Column::U64(rows.iter().map(|r| Some(r.point)).collect())];
    for k in 0..keys {
        c.push(f(&|r| r.values.get(k).copied()));
    }
    c.push(s(&|r| Some(r.status().to_string())));
    c.push(s(&|r| r.error.clone()));
    c.push(f(&|r| r.g_um));
    c.push(f(&|r| r.f_max_um));
    c.push(f(&|r| r.f_min_um));
    c.push(f(&|r| r.h_um));
    c.push(s(&|r| {
        Some(r.verdict().to_string()).filter(|v| !v.is_empty())
    }));
    c.push(Column::U64(rows.iter().map(|r| r.violations).collect()));
    for a in 0..axes {
        c.push(f(&|r| r.b_um.get(a).copied().flatten()));
    }
    for a in 0..axes {
        c.push(f(&|r| r.spike_um.get(a).copied().flatten()));
    }
    c
}

/// `rows.csv`: floats in their shortest exact decimal form.
pub fn to_csv(rows: &[Row], keys: &[String], axes: &[String]) -> Result<Vec<u8>> {
    let err = |e: csv::Error| Error::usage(format!("cannot format the CSV: {e}"));
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(columns(keys, axes)).map_err(err)?;
    let columns = typed(rows, keys.len(), axes.len());
    for i in 0..rows.len() {
        let record: Vec<String> = columns
            .iter()
            .map(|c| match c {
                Column::F64(v) => v[i].map(|x| x.to_string()).unwrap_or_default(),
                Column::U64(v) => v[i].map(|x| x.to_string()).unwrap_or_default(),
                Column::Bool(v) => v[i].map(|x| x.to_string()).unwrap_or_default(),
                Column::Str(v) => v[i].clone().unwrap_or_default(),
            })
            .collect();
        w.write_record(record).map_err(err)?;
    }
    w.into_inner()
        .map_err(|e| Error::usage(format!("cannot format the CSV: {e}")))
}

/// `rows.parquet`.
pub fn to_parquet(rows: &[Row], keys: &[String], axes: &[String]) -> Result<Vec<u8>> {
    let mut table = Table::new();
    for (name, column) in columns(keys, axes)
        .iter()
        .zip(typed(rows, keys.len(), axes.len()))
    {
        table = table.with(name, column);
    }
    table.to_parquet()
}
