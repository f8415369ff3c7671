"""Type stubs of the mtsim package (docstrings: python/mtsim/__init__.py)."""

import os
from typing import Any, NamedTuple, Sequence, Union

import pyarrow as pa

from .errors import InputError as InputError, MtsimError as MtsimError, RunError as RunError

__version__: str

Scenario = Union[str, os.PathLike[str], dict[str, Any]]
PathLike = Union[str, os.PathLike[str]]

class Simulation(NamedTuple):
    summary: dict[str, Any]
    trace: pa.Table

def simulate(scenario: Scenario, *, output: PathLike | None = ..., timing: bool = ...) -> Simulation:
    """Runs the scenario into the virtual ball bar: (summary dict, trace pyarrow.Table)."""

class Cut(NamedTuple):
    figures: dict[str, Any]
    surface: pa.Table

def cut(scenario: Scenario, *, output: PathLike | None = ..., theta_step_deg: float | None = ...,
        heights_mm: Sequence[float] | None = ..., height_step_mm: float | None = ...,
        commanded: bool = ..., budget: bool = ...) -> Cut:
    """The machined cone as a CMM measures it: (cut.json dict, surface pyarrow.Table)."""

def check(scenario: Scenario, *, dynamics: bool = ..., programmed: bool = ...,
          near_miss_mm: float | None = ...) -> dict[str, Any]:
    """Limits and collisions, as `mtsim check --json` (near_miss_mm in mm)."""

def analyze(scenario: Scenario) -> dict[str, Any]:
    """Travel, peak speed and reversal angles (deg) per axis, as `mtsim analyze --json`."""

def blocks(scenario: Scenario) -> pa.Table:
    """The canonical moves (end points in mm and deg), as `mtsim blocks --json`."""

def fit(scenarios: Scenario | Sequence[Scenario], measured: PathLike | Sequence[PathLike], *,
        output: PathLike | None = ..., placement_known: bool = ..., backlash: bool = ...,
        servo_gain: bool = ...) -> dict[str, Any]:
    """Location errors fitted to measured traces, as `mtsim fit --json`."""

class Study(NamedTuple):
    summary: dict[str, Any]
    rows: pa.Table

def study(path: PathLike, *, output: PathLike | None = ..., samples: int | None = ...,
          g_limit_um: float | None = ...) -> Study:
    """A study file run (docs/studies.md): (study.json dict, rows pyarrow.Table)."""

def to_toml(value: dict[str, Any]) -> str:
    """A scenario or machine dict as the TOML text mtsim reads."""

def run_command(args: Sequence[PathLike]) -> int:
    """The `mtsim` command line in this process; returns its exit code."""
