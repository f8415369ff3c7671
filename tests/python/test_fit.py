"""mtsim.fit recovers location errors hidden in traces that mtsim.simulate made."""

import tomllib

import mtsim
from conftest import ROOT

# Hidden errors of the trt-ac machine (µm, µrad) that two cones at one centre identify
# (tests/study/fit.rs: the C-axis offsets and tilts are not separable there).
HIDDEN = {"EY0A_um": 6.0, "EZ0A_um": -9.0, "EB0A_urad": 25.0, "EC0A_urad": -30.0}


def cone(machine, alpha, beta):
    return {"machine": machine,
            "program": {"cone": {"half_apex_deg": alpha, "inclination_deg": beta,
                                 "center_mm": [0.0, 0.0, 200.0], "ballbar_length_mm": 100.0,
                                 "feed_mm_min": 2000.0, "directions": ["ccw", "cw"]}},
            "simulate": {"trace_every": 10}}


def test_fit_recovers_the_errors_simulate_hid(tmp_path):
    nominal = tomllib.loads((ROOT / "machines" / "trt-ac.toml").read_text())
    truth = dict(nominal, location_errors=dict(nominal.get("location_errors", {}), **HIDDEN))
    scenarios, measured = [], []
    for i, (alpha, beta) in enumerate([(15.0, 10.0), (45.0, 30.0)]):
        _, trace = mtsim.simulate(cone(truth, alpha, beta))
        path = tmp_path / f"m{i}.csv"
        with open(path, "w") as f:
            f.write("theta_deg,deviation_um,direction\n")
            for t, d, r in zip(*(trace.column(c).to_pylist()
                                 for c in ("theta_deg", "deviation_um", "direction"))):
                f.write(f"{t},{d},{r}\n")
        scenarios.append(cone(nominal, alpha, beta))
        measured.append(path)
    report = mtsim.fit(scenarios, measured, placement_known=True, output=tmp_path / "fit")
    assert (tmp_path / "fit" / "fit.json").is_file()
    params = {p["name"]: p for p in report["parameters"]}
    for key, truth_value in HIDDEN.items():
        p = params[key.split("_")[0]]
        assert p["identifiable"], p
        assert abs(p["value"] - truth_value) <= max(1.0, 0.1 * abs(truth_value)), (key, p)
