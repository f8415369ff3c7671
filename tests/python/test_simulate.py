"""mtsim.simulate: figures against closed forms and against the binary's files."""

import csv
import json
import math

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

import mtsim
from conftest import cli, scenario_dict


def first_order(kv):
    """Machine overrides that make X, Y and Z ideal first-order loops of gain kv (1/s)
    without friction or feedforward."""
    return {"axes": {a: {"servo": {"model": "first-order", "kv_per_s": kv,
                                   "velocity_feedforward": 0.0,
                                   "acceleration_feedforward": 0.0},
                         "friction": {"coulomb_n": 0.0}} for a in "XYZ"}}


def radius_loss_um(r_mm, feed_mm_min, kv):
    """docs/servo.md: equal first-order loops lose `r (1/sqrt(1 + (ω/Kv)²) − 1)` of radius."""
    w = feed_mm_min / 60.0 / r_mm
    return r_mm * (1.0 / math.sqrt(1.0 + (w / kv) ** 2) - 1.0) * 1e3


def test_a_circle_with_equal_first_order_loops_loses_the_closed_form_radius():
    s = scenario_dict("circle-iso230-4.toml")
    s["machine_overrides"] = first_order(30.0)
    for feed in (1000.0, 3000.0):
        s["program"]["circle"]["feed_mm_min"] = feed
        summary, trace = mtsim.simulate(s)
        want = radius_loss_um(50.0, feed, 30.0)  # -3.086 µm at F1000, -27.755 at F3000
        b = summary["ballbar"]
        for got in (b["radial_max_um"], b["radial_min_um"]):
            assert abs(got - want) <= 0.03 * abs(want), (feed, got, want)
        assert b["circular_deviation_um"] < 0.3
        assert trace.num_rows > 0


def test_the_summary_is_the_summary_json_the_binary_writes(mtsim_bin, tmp_path):
    scenario = "scenarios/circle-iso230-4.toml"
    done = cli(mtsim_bin, "simulate", scenario, "--no-timing", "-o", tmp_path / "cli")
    assert done.returncode == 0, done.stderr
    want = json.loads((tmp_path / "cli" / "summary.json").read_text())
    summary, _ = mtsim.simulate(mtsim_bin.parents[2] / scenario)
    assert summary == want
    assert summary["realtime_factor"] is None


def test_the_trace_has_the_csv_trace_columns_and_rows(mtsim_bin, tmp_path, root):
    scenario = root / "scenarios" / "cone-15-10.toml"
    done = cli(mtsim_bin, "simulate", scenario, "--no-timing", "--trace-format", "csv",
               "-o", tmp_path / "cli")
    assert done.returncode == 0, done.stderr
    with open(tmp_path / "cli" / "trace.csv", newline="") as f:
        rows = list(csv.reader(f))
    header, rows = rows[0], rows[1:]
    _, trace = mtsim.simulate(scenario)
    assert isinstance(trace, pa.Table)
    # The CSV's columns, then the centred deviation the package adds from the file's
    # metadata (the CSV keeps its centre in summary.json).
    assert trace.column_names == header + ["deviation_centred_um"]
    assert trace.num_rows == len(rows)
    assert pa.types.is_floating(trace.schema.field("deviation_um").type)
    # The CSV rounds; the table holds full f64: the same figures to the CSV's digits.
    for name in ("time_s", "X_act_mm", "C_act_deg", "deviation_um"):
        k = header.index(name)
        col = trace.column(name).to_pylist()
        for i in (0, len(rows) // 2, len(rows) - 1):
            assert abs(col[i] - float(rows[i][k])) <= 1e-4, (name, i, col[i], rows[i][k])


def test_output_keeps_the_run_files(tmp_path, root):
    summary, trace = mtsim.simulate(root / "scenarios" / "circle-iso230-4.toml",
                                    output=tmp_path / "run")
    assert json.loads((tmp_path / "run" / "summary.json").read_text()) == summary
    assert pq.read_table(tmp_path / "run" / "trace.parquet").num_rows == trace.num_rows


def test_the_centred_deviation_is_dl_less_an_independently_fitted_centre(tmp_path, root):
    summary, trace = mtsim.simulate(root / "scenarios" / "circle-iso230-4.toml",
                                    output=tmp_path / "run")
    meta = pq.read_schema(tmp_path / "run" / "trace.parquet").metadata
    runs = json.loads(meta[b"mtsim.centring"])
    assert [r["direction"] for r in runs] == [r["direction"] for r in summary["ballbar"]["runs"]]
    direction = trace.column("direction").to_pylist()
    theta = trace.column("theta_deg").to_pylist()
    dev = trace.column("deviation_um").to_pylist()
    centred = trace.column("deviation_centred_um").to_pylist()
    for run in ("ccw", "cw"):
        rows = [i for i, d in enumerate(direction) if d == run]
        assert len(rows) > 1000
        # Least squares of dL on (1, cos θ, sin θ): the normal equations by hand.
        t = np.radians([theta[i] for i in rows])
        a = np.column_stack([np.ones_like(t), np.cos(t), np.sin(t)])
        y = np.array([dev[i] for i in rows])
        _, ca, cb = np.linalg.solve(a.T @ a, a.T @ y)
        want = y - (ca * np.cos(t) + cb * np.sin(t))
        got = np.array([centred[i] for i in rows])
        assert np.abs(got - want).max() < 1e-6, (run, np.abs(got - want).max())
