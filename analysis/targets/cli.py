"""The speed targets (`make targets`, `make million`): per scene of a psweep results folder, every
configuration's minimum wall_s, ns per particle-step, peak RSS, speed-up against the scene's
reference run, the targets met or not, and the state hashes checked against the reference engine
(where it did not run: among the engines declared to match it).

Usage: /usr/bin/python3 -m analysis targets RESULTS_DIR [RESULTS_DIR ...]

What a scene's reference run is and which targets it has come from the sweep's config
(configs/targets.json, configs/million.json), which meta.json carries: under "analysis",
{"scenes": [...]}, one object per scene: `name`; `scene`, scene parameters that pick
it (e.g. {"N": 1000}); optional `reference`, the run (engine, T, G) speed-ups are against;
`targets`, each a `run` (engine, T, G) and any of `speedup_min`, `ns_per_particle_step_max`,
`rss_mb_max`.

Which engines must end in the reference engine's state comes from psim's declaration in
meta.json (matches_reference; the reference engine itself). Exit status: 0, 1 when a state hash
differs (a target not met is reported, not a failure: timings depend on the machine), 2 on bad
input. Everything above main() is a pure function of DataFrames and dicts.
"""
from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from analysis.common.declaration import Declaration
from analysis.common.load import SCENE_PARAMS, InputError, Results, load_results

RUN_PARAMS = ["engine", "T", "G"]  # how a scene is simulated, apart from the scene
LIMITS = {  # target key: (table column, met when the value is ...)
    "speedup_min": ("speedup", "at least"),
    "ns_per_particle_step_max": ("ns_per_particle_step", "at most"),
    "rss_mb_max": ("rss_mb", "at most"),
}


@dataclass(frozen=True)
class Target:
    run: dict
    limits: dict  # LIMITS key -> number


@dataclass(frozen=True)
class SceneSpec:
    name: str
    scene: dict
    reference: dict | None
    targets: list[Target]


# ---------------------------------------------------------------- the spec in meta.json

def _expect(cond: bool, where: str, what: str):
    if not cond:
        raise InputError(f"{where}: {what}")


def _match_dict(value, where: str, allowed: list[str]) -> dict:
    _expect(isinstance(value, dict) and value, where, "expected an object of parameters")
    for key in value:
        _expect(key in allowed, f"{where}.{key}", f"not a parameter here (one of "
                f"{', '.join(allowed)})")
    return value


def parse_spec(meta: dict, where: str = "meta.json") -> list[SceneSpec]:
    """The scenes of config.analysis, validated; [] when the sweep declares none."""
    analysis = (meta.get("config") or {}).get("analysis")
    if analysis is None:
        return []
    at = f"{where}: config.analysis"
    _expect(isinstance(analysis, dict), at, "expected an object")
    scenes = analysis.get("scenes", [])
    _expect(isinstance(scenes, list), f"{at}.scenes", "expected a list")
    specs = []
    for i, s in enumerate(scenes):
        here = f"{at}.scenes[{i}]"
        _expect(isinstance(s, dict), here, "expected an object")
        for key in s:
            _expect(key in ("name", "scene", "reference", "targets"), f"{here}.{key}",
                    "unknown key (name, scene, reference, targets)")
        _expect(isinstance(s.get("name"), str) and s["name"], f"{here}.name", "expected a name")
        scene = _match_dict(s.get("scene"), f"{here}.scene", SCENE_PARAMS)
        reference = (_match_dict(s["reference"], f"{here}.reference", RUN_PARAMS)
                     if "reference" in s else None)
        targets = []
        for j, t in enumerate(s.get("targets", [])):
            there = f"{here}.targets[{j}]"
            _expect(isinstance(t, dict), there, "expected an object")
            run = _match_dict(t.get("run"), f"{there}.run", RUN_PARAMS)
            limits = {k: v for k, v in t.items() if k != "run"}
            _expect(limits, there, f"no limit (one of {', '.join(LIMITS)})")
            for key, value in limits.items():
                _expect(key in LIMITS, f"{there}.{key}", f"unknown limit (one of "
                        f"{', '.join(LIMITS)})")
                _expect(isinstance(value, (int, float)) and not isinstance(value, bool)
                        and value > 0, f"{there}.{key}", "expected a positive number")
            _expect("speedup_min" not in limits or reference is not None, f"{there}.speedup_min",
                    "needs the scene's reference run")
            targets.append(Target(run, limits))
        specs.append(SceneSpec(s["name"], scene, reference, targets))
    return specs


# ---------------------------------------------------------------- tables

def _matches(frame: pd.DataFrame, values: dict) -> pd.Series:
    mask = pd.Series(True, index=frame.index)
    for key, value in values.items():
        mask &= frame[key] == value
    return mask


def configurations(runs: pd.DataFrame) -> pd.DataFrame:
    """One row per scene and configuration of the ok runs: reps, wall_s_min, the largest peak
    RSS, what ran (engine_ran) and the state hash (None when repetitions disagree)."""
    ok = runs[runs["status"] == "ok"]
    if ok.empty:
        raise InputError("no successful run in the results")
    keys = SCENE_PARAMS + RUN_PARAMS
    table = ok.groupby(keys, dropna=False, sort=False).agg(
        reps=("wall_s", "size"), wall_s=("wall_s", "min"), max_rss_kb=("max_rss_kb", "max"),
        ran=("engine_ran", "first"),
        state_hash=("state_hash", lambda h: h.iloc[0] if h.nunique(dropna=False) == 1 else None),
    ).reset_index()
    sub_steps = table["N"] * table["S"] * table["slow_factor"].fillna(1)
    table["ns_per_particle_step"] = table["wall_s"] / sub_steps * 1e9
    table["rss_mb"] = table["max_rss_kb"] / 1024
    return table


def hash_verdicts(scene: pd.DataFrame, declaration: Declaration) -> pd.Series:
    """Per row: "=<reference>" when the state equals the reference engine's; where the reference
    engine did not run, "same" when it equals that of every other engine declared to match it;
    "DIFFERS" when it must and does not (or repetitions disagree); "" for an engine declared to
    compute another state, or with nothing to compare against."""
    reference = declaration.reference
    held = declaration.exact_engines
    if held is None:  # no declaration: every engine is held to the same state
        held = set(scene["engine"])
    ran = scene["engine"] == reference
    base = scene[ran] if ran.any() else scene[scene["engine"].isin(held)]
    if len(base) < (1 if ran.any() else 2):
        return pd.Series("", index=scene.index)
    hashes = set(base["state_hash"])
    want = hashes.pop() if len(hashes) == 1 else None
    same = f"={reference}" if ran.any() else "same"

    def verdict(row) -> str:
        if row["engine"] not in held and row["engine"] != reference:
            return ""
        return same if want is not None and row["state_hash"] == want else "DIFFERS"
    return scene.apply(verdict, axis=1).astype(str)


@dataclass
class SceneTable:
    name: str
    params: dict
    rows: pd.DataFrame
    verdicts: list[str]  # one line per target

    @property
    def hashes_ok(self) -> bool:
        return not (self.rows["hash"] == "DIFFERS").any()


def _one(rows: pd.DataFrame, values: dict, where: str) -> pd.Series:
    hit = rows[_matches(rows, values)]
    if len(hit) != 1:
        raise InputError(f"{where} {values} matches {len(hit)} configurations of the scene "
                         f"(expected one)")
    return hit.iloc[0]


def scene_tables(runs: pd.DataFrame, specs: list[SceneSpec],
                 declaration: Declaration) -> list[SceneTable]:
    """Every scene of the runs, those the specs pick first (in their order), named and judged
    by their spec; rows sorted by engine, T and G."""
    table = configurations(runs)
    scene_keys = table[SCENE_PARAMS].astype(str).agg("|".join, axis=1)
    picked = {}
    for spec in specs:
        keys = set(scene_keys[_matches(table, spec.scene)])
        if len(keys) != 1:
            raise InputError(f"scene {spec.name!r}: {spec.scene} matches {len(keys)} scenes of "
                             f"the results (expected one)")
        picked[keys.pop()] = spec
    out = []
    for key in dict.fromkeys(list(picked) + list(scene_keys)):
        rows = table[scene_keys == key].sort_values(RUN_PARAMS).copy()
        rows["hash"] = hash_verdicts(rows, declaration)
        spec = picked.get(key)
        ref = _one(rows, spec.reference, f"scene {spec.name!r}: reference") \
            if spec and spec.reference else None
        rows["speedup"] = ref["wall_s"] / rows["wall_s"] if ref is not None else math.nan
        verdicts = []
        for target in spec.targets if spec else []:
            row = _one(rows, target.run, f"scene {spec.name!r}: target run")
            for limit, bound in target.limits.items():
                column, sense = LIMITS[limit]
                value = row[column]
                met = value >= bound if sense == "at least" else value <= bound
                verdicts.append(f"target: {_label(row)} {column} {sense} {bound:g}: {value:.3g} "
                                + ("met" if met else "NOT met"))
        first = rows.iloc[0]
        params = {k: first[k] for k in SCENE_PARAMS if not pd.isna(first[k])}
        out.append(SceneTable(spec.name if spec else _scene_text(params), params, rows, verdicts))
    return out


def _label(row) -> str:
    text = f"{row['engine']} T={row['T']:g}"
    return text + (f" G={row['G']:g}" if not pd.isna(row["G"]) else "")


def _scene_text(params: dict) -> str:
    def text(v):
        return f"{v:.0f}" if isinstance(v, float) and v.is_integer() else f"{v:g}" \
            if isinstance(v, float) else str(v)
    return " ".join(f"{k}={text(v)}" for k, v in params.items())


def render(tables: list[SceneTable]) -> str:
    lines = []
    for t in tables:
        lines += ["", f"## {t.name}: {_scene_text(t.params)}"]
        shown = pd.DataFrame({
            "run": t.rows.apply(_label, axis=1), "ran": t.rows["ran"].fillna(""),
            "reps": t.rows["reps"], "wall_s": t.rows["wall_s"].map("{:.4f}".format),
            "ns/p-step": t.rows["ns_per_particle_step"].map("{:.1f}".format),
            "speed-up": t.rows["speedup"].map(lambda v: "" if pd.isna(v) else f"{v:.1f}x"),
            "rss_MB": t.rows["rss_mb"].map(lambda v: "" if pd.isna(v) else f"{v:.0f}"),
            "state_hash": t.rows["state_hash"].fillna("(varies)"), "check": t.rows["hash"]})
        lines += [shown.to_string(index=False)] + t.verdicts
    return "\n".join(lines)


# ---------------------------------------------------------------- command line

def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", metavar="DIR", nargs="+", help="psweep results folder")
    args = parser.parse_args(argv)
    ok = True
    try:
        for directory in args.results:
            results: Results = load_results(directory)
            specs = parse_spec(results.meta, str(Path(directory) / "meta.json"))
            tables = scene_tables(results.runs, specs, results.declaration)
            print(f"# {directory}: minimum wall_s of the repetitions; ns per particle and "
                  f"sub-step; largest peak RSS")
            print(render(tables))
            ok &= all(t.hashes_ok for t in tables)
    except InputError as err:
        print(f"targets: error: {err}", file=sys.stderr)
        return 2
    if not ok:
        print("targets: a state hash differs from the reference engine's", file=sys.stderr)
    return 0 if ok else 1

