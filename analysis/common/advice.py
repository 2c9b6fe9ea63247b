"""The config keys that the reports' and messages' advice tells a reader to set: one constant each,
so that the advice names a key psweep takes. tests/python/test_advice.py writes a config with
every key below set to its example and has psweep accept it (`psweep CONFIG --dry-run`), and
finds any key path written into the analysis's text by hand instead of taken from here.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ConfigKey:
    path: str      # dotted, as psweep names it in its errors: sweep.engine, base.S, repetitions
    example: object  # a value psweep accepts there

    def __str__(self) -> str:
        return f"`{self.path}`"


SWEEP_ENGINE = ConfigKey("sweep.engine", ["brute", "sweep"])
SWEEP_T = ConfigKey("sweep.T", [1, 2])
BASE_N = ConfigKey("base.N", 200)
BASE_S = ConfigKey("base.S", 20)
REPETITIONS = ConfigKey("repetitions", 5)
