"""trace.parquet as readers other than pyarrow see it: DuckDB and Polars (PyPI) read the
file mtsim writes by hand (src/report/trace_parquet.rs: page headers and footer in Thrift
compact), with the same columns and values as pyarrow, and its `mtsim.centring` metadata.

The hand-written writer is kept because the parquet crate's writer cost about 11 % of a
whole `simulate` (docs/performance.md); these readers are the second opinion on its bytes.
A reader that is not installed skips its test with the reason, and fails it when `CI` is
set."""

import json
import os

import numpy as np
import pyarrow.parquet as pq
import pytest

from conftest import cli


def _need(module: str):
    try:
        return __import__(module)
    except ImportError:
        message = f"{module} is not installed (pip install {module}): the second reader is not run"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)


@pytest.fixture(scope="module")
def trace_file(mtsim_bin, tmp_path_factory, root):
    # The ISO circle (two runs, row groups of each) and the cone (its centre a few µm).
    files = {}
    for name in ("circle-iso230-4", "cone-15-10"):
        out = tmp_path_factory.mktemp(name)
        done = cli(mtsim_bin, "simulate", root / "scenarios" / f"{name}.toml", "--no-timing",
                   "--no-budget", "--trace-format", "parquet", "-o", out)
        assert done.returncode in (0, 1), done.stderr
        files[name] = out / "trace.parquet"
    return files


def _pyarrow_columns(path):
    table = pq.read_table(path)
    return table.column_names, {n: table.column(n).to_pylist() for n in table.column_names}


@pytest.mark.parametrize("name", ["circle-iso230-4", "cone-15-10"])
def test_duckdb_reads_the_trace_as_pyarrow_does(trace_file, name):
    duckdb = _need("duckdb")
    path = str(trace_file[name])
    names, columns = _pyarrow_columns(path)
    con = duckdb.connect()
    rows = con.execute(f"SELECT * FROM read_parquet('{path}')").fetchall()
    described = [d[0] for d in con.description]
    assert described == names
    assert len(rows) == len(columns["time_s"]) > 1000
    for k, n in enumerate(names):
        got = [r[k] for r in rows]
        assert got == columns[n], n
    # The row groups' statistics: DuckDB filters by time_s and line with them.
    lo, hi = min(columns["time_s"]), max(columns["time_s"])
    mid = 0.5 * (lo + hi)
    count = con.execute(f"SELECT count(*) FROM read_parquet('{path}') WHERE time_s > {mid}").fetchone()[0]
    assert count == sum(t > mid for t in columns["time_s"])
    kv = dict(con.execute(f"SELECT key, value FROM parquet_kv_metadata('{path}')").fetchall())
    runs = json.loads(kv[b"mtsim.centring"])
    assert [r["direction"] for r in runs] == list(dict.fromkeys(columns["direction"]))


@pytest.mark.parametrize("name", ["circle-iso230-4", "cone-15-10"])
def test_polars_reads_the_trace_as_pyarrow_does(trace_file, name):
    pl = _need("polars")
    path = trace_file[name]
    names, columns = _pyarrow_columns(path)
    frame = pl.read_parquet(path)
    assert frame.columns == names
    for n in names:
        assert frame[n].to_list() == columns[n], n
    assert frame.schema["line"] == pl.UInt64 and frame.schema["direction"] == pl.String
    # The centred deviation from the metadata, as docs/simulation.md gives it for scripts.
    runs = json.loads(pq.read_schema(path).metadata[b"mtsim.centring"])
    first = frame.filter(pl.col("direction") == runs[0]["direction"])
    t = np.radians(first["theta_deg"].to_numpy())
    centred = first["deviation_um"].to_numpy() - (runs[0]["a_um"] * np.cos(t) + runs[0]["b_um"] * np.sin(t))
    assert np.all(np.isfinite(centred))
