"""Parse psim's output into arrays for animation, and ask psim for a scene's header.

Output: lines `step i x y vx vy`, steps 0..S in print mode (0 and S in perf mode), N lines per
step; the final step's lines carry two more integers (pair and wall collision counts).
Scene header (N, L, r, S, `print` or `perf`): read by psim itself (`psim --header`).

Parsing goes through pandas' C reader: print mode of N=1000, S=1000 is a million lines, which a
Python split loop would take seconds over.
"""
from __future__ import annotations

import io
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from analysis.common import psim as psim_runner


class TrajectoryError(Exception):
    """Output or scene that does not follow the format: reported on stderr, exit 2."""


@dataclass
class SceneHeader:
    n: int
    box: float        # L: the box is [0, L]^2
    radius: float     # r
    steps: int        # S
    mode: str         # "print" or "perf"


@dataclass
class Trajectory:
    steps: np.ndarray          # (frames,) step numbers, ascending
    positions: np.ndarray      # (frames, N, 2)
    velocities: np.ndarray     # (frames, N, 2), per time unit
    collisions: np.ndarray | None  # (N, 2) pair and wall counts of the final step, if printed

    @property
    def n(self) -> int:
        return self.positions.shape[1]


def read_scene_header(path: str | Path, psim: str | Path) -> SceneHeader:
    """The scene's header as psim reads it (`psim --header`): the same rules and messages as a
    run, so a scene the animation accepts is one psim runs."""
    asked = psim_runner.run(psim, ["--header", path])
    if asked.returncode != 0:
        raise TrajectoryError(asked.message)
    header = json.loads(asked.stdout)
    return SceneHeader(header["N"], header["L"], header["r"], header["S"], header["mode"])


def parse_output(text: str, n: int | None = None) -> Trajectory:
    """Arrays from psim's stdout. Every step must list particles 0..N-1 exactly once, in
    order, so that frame k row i is always particle i."""
    if not text.strip():
        raise TrajectoryError("psim printed nothing")
    try:
        table = pd.read_csv(io.StringIO(text), sep=r"\s+", header=None, names=range(8),
                            dtype=float, engine="c")
    except (ValueError, pd.errors.ParserError) as err:
        raise TrajectoryError(f"output is not lines of `step i x y vx vy`: {err}") from None
    if table.iloc[:, :6].isna().any().any():
        line = int(table.iloc[:, :6].isna().any(axis=1).idxmax()) + 1
        raise TrajectoryError(f"output line {line}: expected at least 6 numbers "
                              f"(step i x y vx vy)")
    steps_column = table[0].to_numpy()
    index_column = table[1].to_numpy()
    steps, first = np.unique(steps_column, return_index=True)
    n = n or int(index_column.max()) + 1
    if len(table) != len(steps) * n:
        raise TrajectoryError(f"output has {len(table)} lines for {len(steps)} step(s), "
                              f"expected {n} lines per step")
    order = np.argsort(first)
    if not np.array_equal(steps_column, np.repeat(steps[order], n)):
        raise TrajectoryError("output steps are not in contiguous blocks of N lines")
    expected = np.tile(np.arange(n), len(steps))
    if not np.array_equal(index_column, expected):
        line = int(np.argmax(index_column != expected)) + 1
        raise TrajectoryError(f"output line {line}: particle index {index_column[line - 1]:g}, "
                              f"expected {expected[line - 1]} (indices 0..N-1 in order)")
    values = table.iloc[:, 2:6].to_numpy().reshape(len(steps), n, 4)
    last = table.iloc[-n:, 6:8]
    collisions = None if last.isna().any().any() else last.to_numpy().astype(int)
    return Trajectory(steps=steps[order].astype(int), positions=values[:, :, :2].copy(),
                      velocities=values[:, :, 2:].copy(), collisions=collisions)


def frame_indices(count: int, max_frames: int) -> np.ndarray:
    """At most max_frames evenly strided frames, always including the first and the last:
    a 10000-step run becomes a GIF of reasonable size and still ends on the final state."""
    if count <= max_frames:
        return np.arange(count)
    stride = int(np.ceil((count - 1) / (max_frames - 1)))
    picked = np.arange(0, count, stride)
    return picked if picked[-1] == count - 1 else np.append(picked, count - 1)
