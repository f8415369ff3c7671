"""`mtsim.cut`: the machined cone's figures, error budget and surface, against the command
line's cut.json and the grid the options ask for, `budget=False` against `--no-budget`, and the commanded cut's closed form (the program's own
chords leave a sag that falls as 1/n^2: docs/cut.md)."""

import json
import math

import pytest

import mtsim
from conftest import cli, scenario_dict


def test_cut_gives_the_command_line_s_figures_and_the_grid_asked_for(root, mtsim_bin, tmp_path):
    figures, surface = mtsim.cut(root / "scenarios/cone-15-10.toml", heights_mm=[30.0, 50.0],
                                 theta_step_deg=0.5)
    out = tmp_path / "cli"
    run = cli(mtsim_bin, "cut", "scenarios/cone-15-10.toml", "--heights-mm", "30", "--heights-mm",
              "50", "--theta-step-deg", "0.5", "-o", out)
    assert run.returncode == 0, run.stderr
    assert figures == json.loads((out / "cut.json").read_text())
    assert [h["z_mm"] for h in figures["heights"]] == [30.0, 50.0]
    assert surface.column_names[:3] == ["theta_deg", "z_mm", "deviation_um"]
    # 720 columns of 0.5 deg at each height of the grid, the asked-for ones among them.
    zs = sorted(set(surface.column("z_mm").to_pylist()))
    assert surface.num_rows == 720 * len(zs)
    assert 30.0 in zs and 50.0 in zs
    # The error budget, as the command line's: shares and the interplay add to 1.
    budget = figures["budget"]
    assert abs(sum(r["share"] for r in budget["rows"]) + budget["interaction_share"] - 1) < 1e-9
    assert budget["rows"][0]["mechanism"] == "program"


def test_budget_false_is_no_budget(root, mtsim_bin, tmp_path):
    figures, _ = mtsim.cut(root / "scenarios/cone-15-10.toml", theta_step_deg=1.0, budget=False)
    out = tmp_path / "cli"
    run = cli(mtsim_bin, "cut", "scenarios/cone-15-10.toml", "--theta-step-deg", "1", "--no-budget",
              "-o", out)
    assert run.returncode == 0, run.stderr
    assert "budget" not in figures
    assert figures == json.loads((out / "cut.json").read_text())


def test_a_fine_commanded_cone_is_cut_within_its_chord_sag():
    # The program alone (commanded motion) at 3600 segments: the joint-space sag is under
    # a micrometre, so the surface deviates from the nominal cone by less than that.
    s = scenario_dict("cone-15-10.toml")
    s["program"]["cone"]["segments"] = 3600
    figures, surface = mtsim.cut(s, commanded=True, theta_step_deg=1.0)
    d = [v for v in surface.column("deviation_um").to_pylist() if v is not None]
    assert len(d) > 1000
    assert max(abs(v) for v in d) < 1.0, max(abs(v) for v in d)
    for h in figures["heights"]:
        assert h["roundness_um"] < 1.0, h


def test_a_cut_of_a_circle_is_refused_as_input():
    with pytest.raises(mtsim.InputError):
        mtsim.cut(scenario_dict("circle-iso230-4.toml"))
