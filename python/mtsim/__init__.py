"""mtsim: a machine-tool motion simulator with servo dynamics, from Python.

Each function takes a scenario as a path to a scenario file (TOML) or as a dict of the
file's tables (``{"machine": ..., "program": {"cone": {...}}, "simulate": {...}}``), whose
``machine`` is a path or a dict of the machine file's tables; relative paths in a dict
resolve from the current folder. Units are those of the files: lengths in mm, angles in
deg, times in s (docs/scenario-format.md, docs/machine-format.md).

The functions return what the ``mtsim`` command prints with ``--json``, as dicts and lists;
tables come as ``pyarrow.Table``. They release the GIL while they run, so threads (or a
Dask worker's threads) run several at once. Errors raise ``mtsim.MtsimError``
(``InputError`` for bad input, ``RunError`` for a failed run) with ``file``, ``line``,
``column`` and ``key`` attributes. docs/python.md is the guide.
"""

from __future__ import annotations

import os
import sys
from typing import Any, NamedTuple, Sequence, Union

import pyarrow as pa

from . import _native
from .errors import InputError, MtsimError, RunError

__all__ = [
    "simulate", "check", "analyze", "blocks", "fit", "study", "cut", "run_command", "to_toml",
    "Simulation", "Study", "Cut",
    "MtsimError", "InputError", "RunError", "__version__",
]
__version__: str = _native.__version__

Scenario = Union[str, "os.PathLike[str]", dict]


class Simulation(NamedTuple):
    """What ``simulate`` returns; unpacks as ``summary, trace = mtsim.simulate(...)``."""

    summary: dict
    """The summary.json document: ``sim_time_s`` (s), ``setpoints``, ``ballbar`` (G, F, H
    in µm and the events, θ in deg), ``reversals_deg``, ``reversal_values``, ..."""
    trace: pa.Table
    """The trace, the columns of trace.csv / trace.parquet (docs/simulation.md, "Outputs")."""


def simulate(scenario: Scenario, *, output: str | os.PathLike[str] | None = None,
             timing: bool = False) -> Simulation:
    """Runs the scenario through the servo dynamics into the virtual ball bar.

    Args:
        scenario: a scenario file's path, or a dict of its tables.
        output: a folder to keep the run's files in (trace.parquet, summary.json,
            ballbar.svg, test.json), each file written whole or not at all (unlike
            ``mtsim simulate -o``, the folder is not swapped in as one unit, so Ctrl-C
            does not end the Python session); by default the files go to a temporary
            folder that is removed.
        timing: fill ``realtime_factor`` and ``wall_time_s`` (left None by default, so
            that the summary is the same run to run).

    Returns:
        ``Simulation(summary, trace)``: ``summary`` is the summary.json document (what
        ``mtsim simulate --json`` prints; G, F and H in µm, angles in deg, times in s);
        ``trace`` a ``pyarrow.Table`` with the trace's columns (time in s, positions in
        mm and deg, the bar's deviation in µm), handed over from Rust through the Arrow
        C stream interface without copying its buffers.

    Raises:
        InputError: the scenario or its machine or program is bad (file, line, column, key).
        RunError: the simulation diverged or a file could not be written.
    """
    summary, stream = _native.simulate(scenario, output=output, timing=timing)
    return Simulation(summary, pa.RecordBatchReader.from_stream(stream).read_all())


class Cut(NamedTuple):
    """What `cut` returns."""

    figures: dict
    """The cut.json document: ``cutter_radius_mm``, ``heights`` (each ``z_mm``,
    ``roundness_um``, ``centre_offset_um`` [x, y], ``diameter_error_um``),
    ``cone_angle_error_urad`` and ``marks`` (``axis``, ``theta_deg``, ``step_um``)."""
    surface: pa.Table
    """The surface: ``theta_deg``, ``z_mm`` and ``deviation_um`` (null where not cut)."""


def cut(scenario: Scenario, *, output: str | os.PathLike[str] | None = None,
        theta_step_deg: float | None = None, heights_mm: Sequence[float] | None = None,
        height_step_mm: float | None = None, commanded: bool = False,
        budget: bool = True) -> Cut:
    """Predicts the cone the machine cuts, as a CMM measures it (docs/cut.md): what
    ``mtsim cut`` computes.

    Args:
        scenario: a scenario file's path, or a dict of its tables (a cone: generated, or a
            file program with ``[program.cone]``).
        output: a folder to keep the files in (surface.csv, surface.parquet, cut.json, the
            plots and cut.html); by default a temporary folder that is removed.
        theta_step_deg: the grid's θ step, deg (0.1 by default).
        heights_mm: the evaluation heights, mm in the cone's frame (three over the flank
            contact by default).
        height_step_mm: the spacing of the grid's other heights, mm (2 by default).
        commanded: cut with the commanded motion through the nominal chain (the program's
            own part) instead of the actual motion.
        budget: make the error budget (``figures["budget"]``, as ``mtsim cut`` does; False
            is ``--no-budget``: faster). A commanded cut has none.

    Returns:
        ``Cut(figures, surface)``: the cut.json document (µm, µrad, deg, mm) and the surface
        as a ``pyarrow.Table``.

    Raises:
        InputError: the scenario is bad, or is not a cone.
        RunError: the simulation diverged or a file could not be written.
    """
    figures, stream = _native.cut(
        scenario, output=output, theta_step_deg=theta_step_deg,
        heights_mm=None if heights_mm is None else list(heights_mm),
        height_step_mm=height_step_mm, commanded=commanded, budget=budget)
    return Cut(figures, pa.RecordBatchReader.from_stream(stream).read_all())


def check(scenario: Scenario, *, dynamics: bool = False, programmed: bool = False,
          near_miss_mm: float | None = None) -> dict:
    """Checks the program against the machine's travel, velocity and acceleration limits
    and for collisions, as ``mtsim check --json``.

    Args:
        scenario: a scenario file's path, or a dict of its tables.
        dynamics: check the servo's actual positions instead of the commanded ones.
        programmed: sample at the programmed timing instead of the planner's.
        near_miss_mm: clearance below which a pass is reported as a near miss, mm
            (the scenario's or machine's by default).

    Returns:
        The check document: ``samples``, ``sim_time_s`` (s), ``violations`` (a list, each
        with its kind, axis, time in s, value and limit in mm or deg and their rates),
        ``margins``, ``collisions``, ... An empty ``violations`` list is a clean program.
    """
    return _native.check(scenario, dynamics=dynamics, programmed=programmed,
                         near_miss_mm=near_miss_mm)


def analyze(scenario: Scenario) -> dict:
    """Each axis's travel, peak speed and reversal angles, as ``mtsim analyze --json``.

    Returns:
        ``{"axes": {"X": {"min", "max", "reversals_deg", ...}, ...},
        "min_linear_separation_deg", "warnings", "geometric_trace", "feed_limits"}``:
        positions in mm (linear) or deg (rotary), reversal angles θ in deg on the
        measured circle.
    """
    return _native.analyze(scenario)


def blocks(scenario: Scenario) -> pa.Table:
    """The program's canonical moves, one row per move, as ``mtsim blocks --json``.

    A generated cone or circle is one counter-clockwise revolution with no lead.

    Returns:
        A ``pyarrow.Table``: ``line`` (source line), ``kind`` (rapid, feed, arc, dwell),
        the end point ``x y z`` (mm) and ``a b c`` (deg) in machine coordinates, ``feed``
        (mm/min, null for rapids), ``dwell_s`` (s, null but for dwells), ``tool``; ``u v w``
        (mm) on machines with those axes. A column that is null in every row (``dwell_s`` of
        a program without dwells) keeps its number type, float64.
    """
    table = pa.Table.from_pylist(_native.blocks(scenario))
    for i, field in enumerate(table.schema):
        if pa.types.is_null(field.type):
            table = table.set_column(i, pa.field(field.name, pa.float64()),
                                     table.column(i).cast(pa.float64()))
    return table


def fit(scenarios: Scenario | Sequence[Scenario],
        measured: str | os.PathLike[str] | Sequence[str | os.PathLike[str]], *,
        output: str | os.PathLike[str] | None = None, placement_known: bool = False,
        backlash: bool = False, servo_gain: bool = False) -> dict:
    """Fits the machine's location errors (and optionally backlash and servo gain) to
    measured ball-bar traces, as ``mtsim fit --json``.

    Args:
        scenarios: one scenario, or a list, each the test one trace was measured with.
        measured: the measured trace CSV of each scenario, in the same order.
        output: a folder to keep fit.json, location-errors.toml, fit.svg and fit.html in;
            by default a temporary folder that is removed.
        placement_known: the table ball's placement is known (not fitted).
        backlash: also fit each axis's backlash (mm or deg).
        servo_gain: also fit each axis's position-loop gain (1/s).

    Returns:
        The fit document: ``parameters`` (name, value, standard error, unit, whether it
        is identifiable; location errors in µm and µrad), ``traces`` (residual RMS in µm
        per trace), ``unidentifiable``, ``suggestion``, ``warnings``.
    """
    if isinstance(scenarios, (str, os.PathLike, dict)):
        scenarios = [scenarios]
    if isinstance(measured, (str, os.PathLike)):
        measured = [measured]
    return _native.fit(list(scenarios), [os.fspath(m) for m in measured], output=output,
                       placement_known=placement_known, backlash=backlash,
                       servo_gain=servo_gain)


class Study(NamedTuple):
    """What ``study`` returns; unpacks as ``summary, rows = mtsim.study(...)``."""

    summary: dict
    """The study.json document: the study as read, the counts, G's range (µm), the share of
    points with G below the limit with its 95 % Wilson interval, and (random studies) each
    key's Spearman rank correlation with G."""
    rows: pa.Table
    """One row per point, the columns of rows.csv / rows.parquet (docs/studies.md): the
    varied values, ``status``, ``error``, ``G_um``, ``F_max_um``, ``F_min_um``, ``H_um``,
    ``verdict``, ``violations``, ``B_<axis>_um`` and ``spike_<axis>_um``."""


def study(path: str | os.PathLike[str], *, output: str | os.PathLike[str] | None = None,
          samples: int | None = None, g_limit_um: float | None = None) -> Study:
    """Runs a study file (docs/studies.md): the servo simulation over any scenario or
    machine key, on a grid or at seeded random points, as ``mtsim study``.

    Args:
        path: the study file (TOML).
        output: a folder to keep rows.csv, rows.parquet, study.json, the plots and
            study.html in; by default a temporary folder that is removed.
        samples: points of a random study, in place of the file's ``samples``.
        g_limit_um: the G limit, µm, in place of the file's ``g_limit_um``.

    Returns:
        ``Study(summary, rows)``: the study.json dict and the rows as a ``pyarrow.Table``.

    Raises:
        InputError: a bad study file, key path or value (file, line, column and key set).
    """
    summary, stream = _native.study(os.fspath(path), output=output, samples=samples,
                                    g_limit_um=g_limit_um)
    return Study(summary, pa.RecordBatchReader.from_stream(stream).read_all())


def to_toml(value: dict[str, Any]) -> str:
    """A scenario or machine dict as the TOML text mtsim reads it as: save it as a file,
    or read the line and column of a dict's error in it."""
    return _native.to_toml(value)


def run_command(args: Sequence[str | os.PathLike[str]]) -> int:
    """Runs the ``mtsim`` command line in this process: ``run_command(["sweep",
    "scenarios/cone-15-10.toml", "--vary", "center_y", ..., "--shard", "1/8", "-o", "out"])``
    does what ``mtsim sweep ...`` does, so a worker with the package needs no binary.

    Its text goes to the process's standard output and error (file descriptors 1 and 2,
    not ``sys.stdout``); its files are written as the command writes them. A command that
    writes an ``-o`` folder as one unit (``simulate``, ``sweep`` without ``--shard``,
    ``merge``, ...) ends the process on SIGINT or SIGTERM as the command would.

    Returns:
        The exit code: 0 success, 1 violations found, 2 bad input, 3 a run that failed.
    """
    sys.stdout.flush()
    sys.stderr.flush()
    return _native.run_command([os.fspath(a) for a in args])
