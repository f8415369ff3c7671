"""The exceptions mtsim raises.

Every error of a run is an ``MtsimError``; its message is the one the ``mtsim`` command
prints. Where the error is at a place in an input, ``file``, ``line`` and ``column``
(1-based) say where, and ``key`` names the dotted key of the TOML table there (e.g.
``"program.cone.half_apex_deg"``). For a scenario or machine given as a dict, ``file`` is
``"<scenario dict>"`` or ``"<machine dict>"`` and line and column refer to the TOML text
the dict is read as (``mtsim.to_toml(d)``).
"""

from __future__ import annotations


class MtsimError(Exception):
    """An mtsim run that could not be done.

    Attributes:
        message: the command line's message.
        file: the input file at fault (str), or None.
        line, column: 1-based place in ``file``, or None.
        key: the dotted TOML key at that place, or None.
        help: what to do about it, when mtsim knows.
        exit_code: the exit code the command line would give (2 bad input, 3 failed run).
    """

    def __init__(self, message: str, *, file: str | None = None, line: int | None = None,
                 column: int | None = None, key: str | None = None, help: str | None = None,
                 exit_code: int = 3) -> None:
        super().__init__(message)
        self.message = message
        self.file = file
        self.line = line
        self.column = column
        self.key = key
        self.help = help
        self.exit_code = exit_code

    def __reduce__(self):
        # Keeps the attributes through pickle (Dask and multiprocessing send exceptions).
        return (self.__class__, (self.message,), self.__dict__)

    def __str__(self) -> str:
        return self.message if self.help is None else f"{self.message}\nhelp: {self.help}"


class InputError(MtsimError, ValueError):
    """Bad input: a missing file, a syntax error, an unknown key, a value out of range
    (the command line's exit code 2)."""


class RunError(MtsimError, RuntimeError):
    """A run that failed: the simulation diverged, or an output could not be written
    (exit code 3)."""
