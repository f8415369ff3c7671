"""`mtsim.study`: a grid over X backlash on the ISO 230-4 circle, read against the physics
(B of X rises one for one with the backlash) and against the command line's rows."""

import csv
import math

import mtsim


def test_backlash_grid_raises_b_of_x_one_for_one_and_leaves_y(root, mtsim_bin, tmp_path):
    from conftest import cli

    summary, rows = mtsim.study(root / "scenarios/studies/backlash-x-circle.toml")
    assert summary["points"] == rows.num_rows == 5
    assert summary["failed"] == 0
    backlash_um = [v * 1000 for v in rows.column("machine.axes.X.drive.backlash_mm").to_pylist()]
    b_x = rows.column("B_X_um").to_pylist()
    b_y = rows.column("B_Y_um").to_pylist()
    # Lost motion adds to the reversal value one for one (ISO 230-2 B = backlash + 2 Fc/k).
    slope = (b_x[-1] - b_x[0]) / (backlash_um[-1] - backlash_um[0])
    assert math.isclose(slope, 1.0, rel_tol=0.05), slope
    # Friction's elastic lost motion alone, 2 Fc/k = 1.5 um in the machine file.
    assert math.isclose(b_x[0], 1.5, abs_tol=0.1), b_x[0]
    assert max(b_y) - min(b_y) < 0.1, b_y
    # The same rows as the command line writes.
    out = tmp_path / "cli"
    run = cli(mtsim_bin, "study", "scenarios/studies/backlash-x-circle.toml", "-o", out)
    assert run.returncode == 0, run.stderr
    with open(out / "rows.csv", newline="") as f:
        written = list(csv.DictReader(f))
    assert [float(r["G_um"]) for r in written] == rows.column("G_um").to_pylist()


def test_a_bad_study_file_raises_input_error_with_its_place(root, tmp_path):
    bad = tmp_path / "bad.toml"
    scenario = (root / "scenarios/circle-iso230-4.toml").as_posix()
    bad.write_text(f'scenario = "{scenario}"\n[[vary]]\n'
                   'key = "machine.axes.X.drive.backlash_mm"\nvalues = [0.0, nan]\n')
    try:
        mtsim.study(bad)
    except mtsim.InputError as e:
        assert e.exit_code == 2
        # Line 4 holds `values`, the key the NaN is in.
        assert (e.line, e.column) == (4, 1), (e.line, e.column, str(e))
        assert e.key == "vary.values", e.key
        assert "not a number" in str(e), str(e)
    else:
        raise AssertionError("a NaN value in a study file must raise InputError")


def test_the_python_example_of_docs_studies_runs(root, monkeypatch, capsys):
    # The fenced Python block of docs/studies.md, run as written from the repository root.
    text = (root / "docs" / "studies.md").read_text()
    code = text.split("```python\n", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(root)
    exec(compile(code, "docs/studies.md", "exec"), {})
    printed = capsys.readouterr().out
    assert "0 points failed" in printed
    assert "B_X_um" in printed
