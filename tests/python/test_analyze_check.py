"""mtsim.analyze, mtsim.check and mtsim.blocks against the spec's reference values and
the binary's --json output."""

import json

import pyarrow as pa
import pytest

import mtsim
from conftest import cli, scenario_dict


# docs/spec cone-frustum.md, "Reversal angles": 15/10 cone, YT = -25 mm, ZT = 200 mm, L 100.
REFERENCE_YT25 = {"X": [148.71, 252.74], "Y": [146.91, 338.05], "Z": [144.25, 324.25]}


def test_analyze_gives_the_spec_reversal_angles():
    s = scenario_dict("cone-15-10.toml")
    s["program"]["cone"]["center_mm"] = [0.0, -25.0, 200.0]
    axes = mtsim.analyze(s)["axes"]
    for axis, want in REFERENCE_YT25.items():
        got = axes[axis]["reversals_deg"]
        assert len(got) == len(want), (axis, got)
        for g, w in zip(got, want):
            assert abs(g - w) <= 0.05, (axis, got, want)


def test_analyze_is_the_binary_s_json(mtsim_bin, root):
    done = cli(mtsim_bin, "analyze", "scenarios/cone-15-10-offset.toml", "--json")
    assert done.returncode == 0, done.stderr
    assert mtsim.analyze(root / "scenarios" / "cone-15-10-offset.toml") == json.loads(done.stdout)


def test_check_counts_the_travel_violations_of_a_shrunk_axis():
    # The 15/10 cone at (0, 0, 200) moves X over ±67.093 mm (the spec's travel table);
    # X limited to ±60 mm is exceeded once at each end of its travel per revolution.
    s = scenario_dict("cone-15-10.toml")
    s["program"]["cone"]["directions"] = ["ccw"]
    s["machine_overrides"] = {"axes": {"X": {"min": -60.0, "max": 60.0}}}
    report = mtsim.check(s)
    travel = [v for v in report["violations"] if v["kind"] == "travel"]
    assert len(travel) == 2, travel
    assert all(v["axis"] == "X" for v in travel)
    assert sorted(round(v["worst"], 2) for v in travel) == [-67.09, 67.09]
    assert sorted(v["limit"] for v in travel) == [-60.0, 60.0]
    assert abs(report["axes"]["X"]["max"] - 67.093) <= 0.01
    # The untouched scenario is clean.
    del s["machine_overrides"]
    assert mtsim.check(s)["violations"] == []


def test_blocks_is_the_binary_s_rows_as_a_table(mtsim_bin, root):
    done = cli(mtsim_bin, "blocks", "scenarios/cone-15-10.toml", "--json")
    assert done.returncode == 0, done.stderr
    rows = json.loads(done.stdout)
    table = mtsim.blocks(root / "scenarios" / "cone-15-10.toml")
    assert isinstance(table, pa.Table)
    assert table.num_rows == len(rows)
    assert table.to_pylist() == rows


def test_check_refuses_a_negative_near_miss():
    with pytest.raises(mtsim.InputError, match="near_miss_mm -1"):
        mtsim.check(scenario_dict("cone-15-10.toml"), near_miss_mm=-1.0)


def test_blocks_of_a_program_without_dwells_types_dwell_s_as_float64(root):
    table = mtsim.blocks(root / "scenarios" / "cone-15-10.toml")
    assert table.column("dwell_s").null_count == table.num_rows
    assert table.schema.field("dwell_s").type == pa.float64()
    assert table.schema.field("x").type == pa.float64()
