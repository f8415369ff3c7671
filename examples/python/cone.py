# %% [markdown]
# # The five-axis cone-frustum test in Python
#
# A notebook in plain Python (`# %%` cells: VS Code, Jupyter with jupytext, Spyder), or a
# script: `python3 examples/python/cone.py` from the repository root, after `pip install .`.
# It simulates the 15/10 cone (NAS 979 / ISO 10791-7) with the servo dynamics, prints the
# ball-bar figures (ISO 230-4: G, F, H in µm) and plots the trace with matplotlib if it is
# installed (lengths in mm, angles in deg, times in s).

# %%
import pathlib

import pyarrow.compute as pc

import mtsim

root = pathlib.Path(__file__).resolve().parents[2] if "__file__" in globals() else pathlib.Path.cwd()
scenario = {
    "machine": str(root / "machines" / "trt-ac.toml"),
    "program": {
        "cone": {
            "half_apex_deg": 15.0,
            "inclination_deg": 10.0,
            "center_mm": [0.0, -49.8, 200.0],  # the paper's set-up: every linear axis reverses apart
            "ballbar_length_mm": 100.0,
            "feed_mm_min": 1000.0,
            "directions": ["ccw", "cw"],
        }
    },
    # 5 µm of backlash on X, to see its marks.
    "machine_overrides": {"axes": {"X": {"drive": {"backlash_mm": 0.005}}}},
}

# %% [markdown]
# ## The reversal angles, from the program alone

# %%
analysis = mtsim.analyze(scenario)
for axis, a in analysis["axes"].items():
    print(f"{axis}: {a['min']:9.3f} .. {a['max']:9.3f}, reversals at", a["reversals_deg"], "deg")

# %% [markdown]
# ## The simulation: summary and trace

# %%
summary, trace = mtsim.simulate(scenario)
b = summary["ballbar"]
print(f"{summary['sim_time_s']:.2f} s of machine time in {summary['setpoints']} periods")
print(f"G = {b['circular_deviation_um']:.2f} µm, F = {b['radial_max_um']:+.2f} / {b['radial_min_um']:+.2f} µm, "
      f"H = {b['hysteresis_um']:.2f} µm")
for e in b["spikes"]:
    print(f"  {e['direction']:>3} {e['kind']:<5} at θ = {e['theta_deg']:7.2f} deg, {e['height_um']:+.2f} µm, axis {e['axis']}")
print(trace.schema)
print(f"{trace.num_rows} rows")

# %% [markdown]
# ## The ball-bar trace against θ

# %%
try:
    import matplotlib
    import numpy as np
    import matplotlib.pyplot as plt
except ImportError:
    plt = None

if plt is None:
    # No matplotlib: the figures the plot would show, per direction, every 30 deg.
    rows = trace.select(["direction", "theta_deg", "deviation_um"]).to_pylist()
    for d in ("ccw", "cw"):
        run = [r for r in rows if r["direction"] == d]
        marks = [min(run, key=lambda r: abs(r["theta_deg"] - t)) for t in range(0, 360, 30)]
        print(d, " ".join(f"{r['theta_deg']:.0f}:{r['deviation_um']:+.2f}" for r in marks))
else:
    if "__file__" in globals():
        matplotlib.use("Agg")
    fig, ax = plt.subplots(subplot_kw={"projection": "polar"}, figsize=(6, 6))
    for d in ("ccw", "cw"):
        run = trace.filter(pc.equal(trace["direction"], d))

        theta = np.radians(run["theta_deg"].to_numpy())
        ax.plot(theta, run["deviation_um"].to_numpy(), label=d.upper(), lw=0.8)
    for axis, angles in summary["reversals_deg"].items():
        for t in angles:
            ax.annotate(axis, (np.radians(t), ax.get_rmax()), fontsize=8)
    ax.set_title(f"15/10 cone: G = {b['circular_deviation_um']:.2f} µm")
    ax.legend(loc="lower right")
    out = pathlib.Path("cone-trace.png")  # in the current folder
    fig.savefig(out, dpi=100)
    print("wrote", out)
