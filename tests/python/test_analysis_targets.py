"""The targets table: minimum wall_s, ns per particle-step, peak RSS, speed-up against the scene's
reference run, target verdicts and the state-hash check against the declared reference engine;
end to end through psweep on a tiny config with an "analysis" section."""
import json
import subprocess
from pathlib import Path

import pandas as pd
import pytest

from analysis.common.declaration import Declaration
from analysis.common.load import InputError, normalise
from analysis.targets.cli import main, parse_spec, render, scene_tables
from build_path import BUILD

DECLARED = Declaration(engines=[
    {"name": "brute", "matches_reference": True, "reference": True},
    {"name": "cells", "matches_reference": True},
    {"name": "event", "matches_reference": False},
])
COLUMNS = ["engine", "N", "L", "r", "S", "slow_factor", "T", "status", "wall_s", "max_rss_kb",
           "state_hash", "engine_ran"]


def runs(rows):
    return normalise(pd.DataFrame(rows, columns=COLUMNS))


def spec(**scene):
    meta = {"config": {"analysis": {"scenes": [scene]}}}
    return parse_spec(meta)


SCENE = [1000, 100, 1, 10, 1]
RUNS = [
    ["brute", *SCENE, 1, "ok", 0.40, 9000, "aa", "brute"],
    ["brute", *SCENE, 1, "ok", 0.50, 9500, "aa", "brute"],
    ["cells", *SCENE, 2, "ok", 0.08, 12000, "aa", "cells"],
    ["cells", *SCENE, 2, "ok", 0.09, 20480, "aa", "cells"],
    ["cells", *SCENE, 2, "failed", 0.01, 1, "", ""],
    ["event", *SCENE, 1, "ok", 2.0, 5000, "ee", "event"],
]


def test_minimum_speedup_rss_and_targets():
    [table] = scene_tables(runs(RUNS), spec(
        name="s", scene={"N": 1000}, reference={"engine": "brute", "T": 1},
        targets=[{"run": {"engine": "cells", "T": 2}, "speedup_min": 4, "rss_mb_max": 19}]),
        DECLARED)
    rows = table.rows.set_index("engine")
    assert rows.loc["cells", "reps"] == 2  # the failed run is no repetition
    assert rows.loc["cells", "wall_s"] == pytest.approx(0.08)
    assert rows.loc["cells", "speedup"] == pytest.approx(5.0)
    assert rows.loc["cells", "rss_mb"] == pytest.approx(20.0)  # the largest of the repetitions
    assert rows.loc["brute", "ns_per_particle_step"] == pytest.approx(0.40 / (1000 * 10) * 1e9)
    assert table.verdicts == ["target: cells T=2 speedup at least 4: 5 met",
                              "target: cells T=2 rss_mb at most 19: 20 NOT met"]
    # event computes another state (declared): not compared; cells must equal brute's
    assert list(rows["hash"]) == ["=brute", "=brute", ""]
    assert table.hashes_ok and "## s: N=1000" in render([table])


def test_a_state_unlike_the_reference_engines_fails_the_check():
    bad = [r[:] for r in RUNS]
    bad[3][10] = "bb"  # one repetition of cells ends elsewhere
    [table] = scene_tables(runs(bad), [], DECLARED)
    assert table.rows.set_index("engine").loc["cells", "hash"] == "DIFFERS"
    assert not table.hashes_ok
    assert table.name.startswith("N=1000")  # no spec: named by its parameters


def test_without_the_reference_engine_the_matching_engines_must_agree():
    [table] = scene_tables(runs(RUNS[2:4]), [], DECLARED)
    assert list(table.rows["hash"]) == [""]  # one configuration: nothing to compare
    [table] = scene_tables(runs(RUNS[2:]), [], DECLARED)
    assert list(table.rows["hash"]) == ["", ""]  # event is declared to compute another state
    t1 = ["cells", *SCENE, 1, "ok", 0.1, 1, "aa", "cells"]
    [table] = scene_tables(runs(RUNS[2:4] + [t1]), [], DECLARED)
    assert list(table.rows["hash"]) == ["same", "same"]
    [table] = scene_tables(runs(RUNS[2:4] + [t1[:10] + ["cc", "cells"]]), [], DECLARED)
    assert list(table.rows["hash"]) == ["DIFFERS", "DIFFERS"]


@pytest.mark.parametrize("scene, message", [
    ({"name": "s", "scene": {"Q": 1}}, r"scenes\[0\].scene.Q: not a parameter"),
    ({"name": "s", "scene": {"N": 1}, "targets": [{"run": {"engine": "cells"}}]},
     r"targets\[0\]: no limit"),
    ({"name": "s", "scene": {"N": 1}, "targets": [{"run": {"T": 1}, "speedup_min": 2}]},
     r"speedup_min: needs the scene's reference run"),
    ({"name": "s", "scene": {"N": 1}, "targets": [{"run": {"T": 1}, "fast": 2}]},
     r"targets\[0\].fast: unknown limit"),
    ({"name": "s", "scene": {"N": 1}, "extra": 1}, r"scenes\[0\].extra: unknown key"),
])
def test_bad_specs_name_the_key(scene, message):
    with pytest.raises(InputError, match=message):
        spec(**scene)


def test_a_spec_must_pick_one_scene_and_one_run():
    with pytest.raises(InputError, match="matches 0 scenes"):
        scene_tables(runs(RUNS), spec(name="s", scene={"N": 7}), DECLARED)
    with pytest.raises(InputError, match="reference .* matches 0 configurations"):
        scene_tables(runs(RUNS), spec(name="s", scene={"N": 1000},
                                      reference={"engine": "grid"}), DECLARED)


def test_end_to_end_through_psweep(tmp_path, capsys):
    config = {
        "name": "t", "base": {"N": 300, "L": 200, "r": 1, "S": 3, "seed": 5},
        "sweep": {"engine": ["brute", "cells", "auto"], "T": [1, 2, 2]}, "combine": "zip",
        "repetitions": 2,
        "analysis": {"scenes": [{"name": "tiny", "scene": {"N": 300},
                                 "reference": {"engine": "brute", "T": 1},
                                 "targets": [{"run": {"engine": "cells", "T": 2},
                                              "speedup_min": 0.001}]}]}}
    path = tmp_path / "t.json"
    path.write_text(json.dumps(config))
    out = tmp_path / "out"
    subprocess.run([str(BUILD / "psweep"), str(path), "--out", str(out)], check=True,
                   capture_output=True)
    assert main([str(out)]) == 0
    text = capsys.readouterr().out
    assert "## tiny: N=300" in text and "cells T=2" in text and "met" in text
    assert text.count("=brute") == 3
    # a run that ends in another state fails the check
    runs_csv = out / "runs.csv"
    frame = pd.read_csv(runs_csv, dtype=str, keep_default_na=False)
    frame.loc[frame["engine"] == "cells", "state_hash"] = "0123456789abcdef"
    frame.to_csv(runs_csv, index=False)
    assert main([str(out)]) == 1
    assert main([str(tmp_path / "absent")]) == 2


@pytest.mark.parametrize("name", ["targets", "million"])
def test_the_shipped_configs_expand_and_their_specs_parse(name):
    path = Path(__file__).resolve().parents[2] / "configs" / f"{name}.json"
    dry = subprocess.run([str(BUILD / "psweep"), str(path), "--dry-run"], capture_output=True,
                         text=True)
    assert dry.returncode == 0, dry.stderr
    specs = parse_spec({"config": json.loads(path.read_text())})
    assert specs and all(s.targets for s in specs)
