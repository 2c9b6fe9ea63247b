"""python3 -m analysis stability: the checks as pure functions on made-up outcomes, and the quick subset
end to end against build/psim (as `make stability` runs the full suite)."""
import csv
import math

import pytest

from build_path import BUILD
from entry_point import run_tool
from analysis.common.declaration import Declaration
from analysis.stability.cli import Outcome, check, compare_with_reference
from analysis.stability.scenes import Particle, Scene, drift_bound, scenes

PSIM = BUILD / "psim"
SCENE = Scene("two", 10.0, 1.0, 3, [Particle(2, 2, 1, 0), Particle(8, 8, -1, 0)])
BRUTE = "brute"


def outcome(final_lines, metrics=None, rc=0, stderr=""):
    out = "0 0 2.00000000 2.00000000 1.00000000 0.00000000\n" \
          "0 1 8.00000000 8.00000000 -1.00000000 0.00000000\n" + final_lines
    base = {"energy_initial": 1.0, "energy_final": 1.0, "energy_drift": 0.0,
            "state_hash": "abc", "counters": {"pair_collisions": 0}}
    return Outcome(rc, out, stderr, base | (metrics or {}), 0.01)


GOOD = "3 0 5.00000000 2.00000000 1.00000000 0.00000000 0 0\n" \
       "3 1 5.00000000 8.00000000 -1.00000000 0.00000000 0 0\n"


def test_a_good_run_passes():
    assert check(SCENE, BRUTE, outcome(GOOD)).status == "ok"


def test_nan_in_output_or_metrics_fails():
    row = check(SCENE, BRUTE, outcome(GOOD.replace("5.00000000 2.", "-nan 2.")))
    assert row.status == "fail" and row.nan_count == 1
    row = check(SCENE, BRUTE, outcome(GOOD, {"energy_final": None}))
    assert row.status == "fail" and "non-finite" in row.reason


def test_position_outside_box_fails_beyond_print_rounding():
    assert check(SCENE, BRUTE, outcome(GOOD.replace("5.00000000 8.", "9.00000000 8."))).status \
        == "ok"
    row = check(SCENE, BRUTE, outcome(GOOD.replace("5.00000000 8.", "9.00000001 8.")))
    assert row.status == "fail" and row.out_of_box == 1


def test_energy_drift_beyond_bound_fails():
    row = check(SCENE, BRUTE, outcome(GOOD, {"energy_drift": 2e-10}))
    assert row.status == "fail" and "energy drift" in row.reason
    # Without energy_drift in the metrics it comes from the energies.
    metrics = {"energy_final": 1.5}
    out = outcome(GOOD, metrics)
    del out.metrics["energy_drift"]
    assert check(SCENE, BRUTE, out).drift == pytest.approx(0.5)


def test_drift_bound_grows_with_pair_collisions():
    assert drift_bound(0) == 1e-10
    assert drift_bound(10**9) == pytest.approx(8 * 2.0 ** -53 * 10**9)


def test_timeout_and_crash_fail_and_refusals_need_the_reason():
    assert check(SCENE, BRUTE, Outcome(None, "", "", None, 60)).reason == "timeout"
    assert check(SCENE, BRUTE, outcome(GOOD, rc=-11)).status == "fail"
    refuse = Scene("x", 10.0, 1.0, 1, None, refuse="speed", N=2)
    assert check(refuse, BRUTE, outcome("", rc=2, stderr="psim: f: speed: too fast")).status \
        == "refused"
    assert check(refuse, BRUTE, outcome("", rc=2, stderr="psim: f: N: bad")).status == "fail"
    assert check(refuse, BRUTE, outcome(GOOD)).status == "fail"
    by_engine = Scene("y", 10.0, 1.0, 1, [Particle(5, 5, 0, 0)], refuse_by={"event": "event"})
    assert check(by_engine, BRUTE, outcome(GOOD[:GOOD.index("\n") + 1])).status == "ok"
    assert check(by_engine, "event",
                 outcome("", rc=2, stderr="psim: speed: the event engine")).status == "refused"


def test_exact_engine_must_match_brute_hash():
    rows = [check(SCENE, BRUTE, outcome(GOOD)),
            check(SCENE, "cells", outcome(GOOD, {"state_hash": "def"})),
            check(SCENE, "grid-unsafe", outcome(GOOD, {"state_hash": "fed"}))]
    declared = Declaration(engines=[{"name": "brute", "matches_reference": True, "reference": True},
                                    {"name": "cells", "matches_reference": True},
                                    {"name": "grid-unsafe", "matches_reference": False}])
    compare_with_reference(rows, declared)
    assert [r.status for r in rows] == ["ok", "fail", "ok"]
    assert "differs from brute" in rows[1].reason


def test_scenes_are_valid_and_scaled_copies_exact():
    by_name = {s.name: s for s in scenes()}
    for s in by_name.values():
        for p in s.particles or []:
            assert s.r <= p.x <= s.L - s.r and s.r <= p.y <= s.L - s.r, s.name
    base, tiny = by_name["base"], by_name["tiny_copy"]
    assert tiny.L == math.ldexp(base.L, -668)
    assert tiny.particles[3].vx == math.ldexp(base.particles[3].vx, -668)


@pytest.mark.skipif(not PSIM.exists(), reason="build/psim not built")
def test_quick_suite_passes_end_to_end(tmp_path):
    done = run_tool("stability", "--quick", "--psim", PSIM, "--out", tmp_path, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    rows = list(csv.DictReader((tmp_path / "stability.csv").open()))
    assert {r["engine"] for r in rows} >= {"brute", "cells", "sweep", "grid", "auto"}
    assert {r["status"] for r in rows} == {"ok", "refused"}
    assert (tmp_path / "report.md").read_text().startswith("# Stability report")


def test_an_engine_that_cannot_run_here_is_named_in_the_report():
    from analysis.stability.cli import report_markdown
    text = report_markdown([check(SCENE, BRUTE, outcome(GOOD))], [SCENE],
                           {"gpu": "this build has no CUDA"})
    assert "Engine `gpu` not run: this build has no CUDA." in text
    assert "not run" not in report_markdown([check(SCENE, BRUTE, outcome(GOOD))], [SCENE])
