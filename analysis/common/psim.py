"""The one way the analysis runs psim (accuracy's trajectories, animate, stability, a scene's
header): its output captured as text, a timeout that ends in a result rather than an exception,
and a psim that cannot be started reported the same way by every tool."""
from __future__ import annotations

import json
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

from analysis.common.declaration import Declaration


class PsimError(Exception):
    """psim could not be run or asked (not built, not executable): one line, exit status 2."""


@dataclass
class PsimRun:
    command: list[str]
    returncode: int | None  # None: killed at the timeout
    stdout: str
    stderr: str
    seconds: float

    @property
    def message(self) -> str:
        """psim's error message without its `psim: ` prefix, else the exit status."""
        return (self.stderr.strip().removeprefix("psim: ")
                or f"{' '.join(self.command)} failed with exit status {self.returncode}")


def run(psim: str | Path, arguments: list, stdin: str | None = None,
        timeout: float | None = None) -> PsimRun:
    command = [str(psim), *(str(a) for a in arguments)]
    start = time.monotonic()
    try:
        done = subprocess.run(command, input=stdin, capture_output=True, text=True,
                              timeout=timeout)
    except subprocess.TimeoutExpired:
        return PsimRun(command, None, "", "", time.monotonic() - start)
    except OSError as err:
        raise PsimError(f"cannot run {psim}: {err.strerror} (build it with `make build`)"
                        ) from None
    return PsimRun(command, done.returncode, done.stdout, done.stderr, time.monotonic() - start)


def describe(psim: str | Path) -> Declaration:
    """psim's declaration of its engines and metrics (`psim --describe`)."""
    asked = run(psim, ["--describe"])
    if asked.returncode != 0:
        raise PsimError(f"{psim} --describe failed: {asked.stderr.strip()}")
    return Declaration.from_meta({"declaration": json.loads(asked.stdout)})
