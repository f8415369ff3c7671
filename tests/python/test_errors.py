"""Errors raise mtsim's exception classes with the place of the fault; no panic reaches
Python."""

import pickle

import pytest

import mtsim
from conftest import cli, scenario_dict


def test_a_nan_in_a_dict_names_its_key():
    s = scenario_dict("cone-15-10.toml")
    s["program"]["cone"]["half_apex_deg"] = float("nan")
    with pytest.raises(mtsim.InputError) as e:
        mtsim.analyze(s)
    err = e.value
    assert isinstance(err, mtsim.MtsimError) and isinstance(err, ValueError)
    assert err.key == "program.cone.half_apex_deg"
    assert err.file == "<scenario dict>"
    assert err.exit_code == 2
    # Line and column point into the TOML text the dict is read as.
    line = mtsim.to_toml(s).splitlines()[err.line - 1]
    assert line.startswith("half_apex_deg") and err.column >= 1


def test_an_unknown_key_in_a_dict_names_it():
    s = scenario_dict("cone-15-10.toml")
    s["program"]["cone"]["half_apex"] = 15.0
    with pytest.raises(mtsim.InputError) as e:
        mtsim.check(s)
    assert e.value.key == "program.cone.half_apex"
    assert "half_apex" in str(e.value)


def test_a_bad_machine_dict_names_its_key():
    s = scenario_dict("circle-iso230-4.toml")
    import tomllib
    with open(s["machine"], "rb") as f:
        machine = tomllib.load(f)
    machine["axes"]["X"]["servo"]["kv_per_s"] = -5.0
    s["machine"] = machine
    with pytest.raises(mtsim.InputError) as e:
        mtsim.simulate(s)
    assert e.value.file == "<machine dict>"
    assert e.value.key == "axes.X.servo.kv_per_s"


def test_a_bad_file_gives_the_line_column_and_message_of_the_command_line(tmp_path, root, mtsim_bin):
    machine = root / "machines" / "trt-ac.toml"
    bad = tmp_path / "bad.toml"
    bad.write_text(f'machine = "{machine}"\n\n[program.cone]\nhalf_apex_deg = 15.0\n'
                   'inclination_deg = 10.0\ncenter_mm = [0.0, 0.0, 200.0]\n'
                   'ballbar_length_mm = 100.0\nfeed_mm_min = -1000.0\n')
    with pytest.raises(mtsim.InputError) as e:
        mtsim.simulate(bad)
    err = e.value
    assert (err.file, err.line, err.key) == (str(bad), 8, "program.cone.feed_mm_min")
    assert err.column == 1  # the key, where the command line puts its caret
    done = cli(mtsim_bin, "simulate", bad, "-o", tmp_path / "out")
    assert done.returncode == 2
    # The command line's report wraps its lines at 80 columns behind a gutter ("│"), even
    # inside "mm/min", at places the temporary path's length decides: compare the text
    # without its whitespace and gutter.
    bare = lambda text: "".join(text.replace("│", " ").split())
    assert bare(err.message.split(": ", 1)[1]) in bare(done.stderr)
    assert f"{bad}:8:1: " in err.message


def test_a_missing_file_is_an_input_error(tmp_path):
    with pytest.raises(mtsim.InputError) as e:
        mtsim.analyze(tmp_path / "none.toml")
    assert e.value.file == str(tmp_path / "none.toml") and e.value.line is None


def test_a_value_that_has_no_toml_form_is_a_type_error():
    s = scenario_dict("cone-15-10.toml")
    s["program"]["cone"]["feed_mm_min"] = object()
    with pytest.raises(TypeError, match="program.cone.feed_mm_min"):
        mtsim.analyze(s)


def test_the_exception_survives_pickle():
    s = scenario_dict("cone-15-10.toml")
    s["simulate"] = {"trace_every": 0}
    with pytest.raises(mtsim.InputError) as e:
        mtsim.simulate(s)
    back = pickle.loads(pickle.dumps(e.value))
    assert type(back) is mtsim.InputError
    assert (back.key, back.line, back.message) == (e.value.key, e.value.line, e.value.message)
    assert back.key == "simulate.trace_every"


def test_run_command_returns_the_exit_code(tmp_path):
    assert mtsim.run_command(["analyze", tmp_path / "none.toml"]) == 2
    assert mtsim.run_command(["--version"]) == 0
