"""Shared fixtures of the Python tests: the repository's paths and the `mtsim` binary the
figures are compared with (the release build; `MTSIM_BIN` to point elsewhere)."""

import os
import pathlib
import subprocess
import tomllib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root() -> pathlib.Path:
    return ROOT


@pytest.fixture(scope="session")
def mtsim_bin() -> pathlib.Path:
    path = pathlib.Path(os.environ.get("MTSIM_BIN", ROOT / "target" / "release" / "mtsim"))
    if not path.exists():
        pytest.fail(f"{path} does not exist: run `cargo build --release` first (or set MTSIM_BIN)")
    return path


def cli(mtsim_bin, *args, cwd=ROOT):
    """Runs the binary; returns the CompletedProcess (text)."""
    return subprocess.run([str(mtsim_bin), *map(str, args)], cwd=cwd, capture_output=True, text=True)


def scenario_dict(name: str) -> dict:
    """A bundled scenario file as a dict, its machine path made absolute (a dict's
    relative paths resolve from the current folder)."""
    path = ROOT / "scenarios" / name
    d = tomllib.loads(path.read_text())
    d["machine"] = str((path.parent / d["machine"]).resolve())
    return d
