"""psim's declaration of its engines and metrics, as psweep keeps it in meta.json
(`psim --describe` prints the same JSON).

The analysis names no engine and no metric: which columns are stage times, which engines must
agree bit for bit, which engine is the sequential reference all come from here. A results
folder without a declaration (an old sweep, a hand-made CSV) gets the empty one: no stage
plot, no speed-up over the reference, every engine held to the hash check.
"""
from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Declaration:
    engines: list[dict] = field(default_factory=list)
    metrics: list[dict] = field(default_factory=list)

    @classmethod
    def from_meta(cls, meta: dict) -> "Declaration":
        declared = meta.get("declaration") if isinstance(meta, dict) else None
        if not isinstance(declared, dict):
            return cls()
        return cls(engines=[e for e in declared.get("engines", []) if isinstance(e, dict)],
                   metrics=[m for m in declared.get("metrics", []) if isinstance(m, dict)])

    def metric_columns(self, kind: str | None = None) -> list[str]:
        """runs.csv's metric columns in psim's order, optionally only those of one kind
        (stage_time, counter, physics, status)."""
        return [m["key"] for m in self.metrics if kind is None or m.get("kind") == kind]

    @property
    def stage_columns(self) -> list[str]:
        return self.metric_columns("stage_time")

    @property
    def exact_engines(self) -> set[str] | None:
        """Engines whose final state must equal the reference's bit for bit (declared
        matches_reference); None when undeclared."""
        if not self.engines:
            return None
        return {e["name"] for e in self.engines if e.get("matches_reference")}

    @property
    def reference(self) -> str | None:
        """The engine every other one is timed against (speedup_vs_brute)."""
        return next((e["name"] for e in self.engines if e.get("reference")), None)

    @property
    def continuous_exact(self) -> str | None:
        """The engine computing the model's true trajectory (exact, continuous time): the
        discrete engines' error is measured against it (make accuracy)."""
        return next((e["name"] for e in self.engines
                     if e.get("exact") and e.get("continuous_time")), None)

    def uses(self, engine: str, param: str) -> bool:
        """Whether `engine` reads parameter `param` (T, G, slow_factor); True when unknown."""
        for e in self.engines:
            if e.get("name") == engine:
                return param in e.get("uses", [])
        return True
