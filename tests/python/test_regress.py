"""make regress: the comparison on fixture data (every case of the issue), the step detection,
the suite file's errors, and one end-to-end check that repeated instruction counts agree within
the threshold."""
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from build_path import BUILD, countable_build, sanitized
from entry_point import run_tool
from analysis.regress.changepoint import change_points
from analysis.regress.check import (MEASUREMENT_COLUMNS, Thresholds, check_hashes,
                                    compare_part, environment_differences, instruction_spread,
                                    outcome)
from analysis.regress.report import history_steps
from analysis.regress.suite import (SuiteError, check_build, measure, parse_suite,
                                    resolve_threads)

ROOT = Path(__file__).resolve().parents[2]

TH = Thresholds()
CONFIGS = {"default brute T=1": 300e6, "default sweep T=2": 90e6, "crowd cells T=1": 500e6}
WALL = {"default brute T=1": 0.30, "default sweep T=2": 0.07, "crowd cells T=1": 0.90}


V3 = "-O3 -march=x86-64-v3 -mtune=generic"


def meta(cpu="AMD EPYC", cores=2, isa=("avx", "avx2", "sse4_2"), flags=V3, machine="m1"):
    return {"date": "2026-11-23T01:00:00Z",
            "machine": {"cpu_model": cpu, "online_cpus": cores, "physical_cores": cores,
                        "isa_flags": list(isa), "machine_id": machine},
            "build": {"compiler": "GNU 12.2.0", "flags": flags}, "valgrind": "valgrind-3.19.0",
            "glibc_tunables": "pinned"}


def frame(rng, scale=None, noise=0.01, hashes=None, instructions=None, reps=5):
    """Measurements of the fixture suite: one instruction count and `reps` wall repetitions per
    configuration (minimum at the nominal time, noise only adding time, as on a real machine).
    scale / instructions / hashes: label -> factor, count factor, state hash override."""
    scale, hashes, instructions = scale or {}, hashes or {}, instructions or {}
    rows = []
    for i, label in enumerate(CONFIGS):
        state = hashes.get(label, f"hash{i}")
        count = CONFIGS[label] * instructions.get(label, 1.0)
        rows.append(["instructions", "g", f"i{i}", label, "e", "e", 1, 0, "ok", "instructions",
                     count, state, None])
        walls = WALL[label] * scale.get(label, 1.0) * (1 + noise * np.abs(rng.standard_normal(reps)))
        for rep, wall in enumerate(walls):
            rows.append(["wall", "g", f"w{i}", label, "e", "e", 1, rep, "ok", "wall_s", wall,
                         state, None])
    return pd.DataFrame(rows, columns=MEASUREMENT_COLUMNS)


def check(baseline, now, base_meta=None, now_meta=None):
    base_meta, now_meta = base_meta or meta(), now_meta or meta()
    comparisons = []
    for part in ("instructions", "wall"):
        why = environment_differences(base_meta, now_meta, part)
        comparisons += compare_part(baseline, now, part, TH, why)
    hashes = check_hashes(baseline, now)
    status, reasons = outcome(comparisons, hashes)
    return status, reasons, comparisons, hashes


def test_unchanged_baseline_passes():
    rng = np.random.default_rng(1)
    base = frame(rng)
    status, reasons, comparisons, hashes = check(base, base.copy())
    assert status == 0 and reasons == [] and hashes == []
    assert {c.verdict for c in comparisons} == {"ok"}
    assert all(c.gated for c in comparisons) and len(comparisons) == 6


def test_baseline_ten_percent_faster_fails_and_names_the_configurations():
    rng = np.random.default_rng(2)
    base = frame(rng)
    slower = {"default brute T=1": 1.10, "crowd cells T=1": 1.10}
    status, reasons, comparisons, _ = check(base, frame(rng, scale=slower))
    assert status == 1
    named = {r.split(":")[0] for r in reasons}
    assert named == set(slower)
    wall = {c.label: c for c in comparisons if c.part == "wall"}
    assert wall["default brute T=1"].verdict == "regressed"
    assert wall["default brute T=1"].change == pytest.approx(0.10, abs=0.02)
    assert wall["default sweep T=2"].verdict == "ok"


def test_ten_percent_more_instructions_fails():
    rng = np.random.default_rng(3)
    base = frame(rng)
    now = base.copy()
    now.loc[(now["part"] == "instructions") & (now["label"] == "default sweep T=2"),
            "value"] *= 1.10
    status, reasons, _, _ = check(base, now)
    assert status == 1 and reasons == ["default sweep T=2: instructions regressed by +10.0%"]


def test_noise_within_the_threshold_passes():
    rng = np.random.default_rng(4)
    base = frame(rng, noise=0.03)
    # Every configuration 2-3% slower and noisy, instruction counts 0.5% up: below both gates.
    now = frame(rng, noise=0.03, scale={k: 1.025 for k in CONFIGS},
                instructions={k: 1.005 for k in CONFIGS})
    status, reasons, comparisons, _ = check(base, now)
    assert status == 0, reasons
    assert {c.verdict for c in comparisons} == {"ok"}


def test_a_significant_but_small_change_is_not_a_regression():
    base = np.array([1.00, 1.01, 1.00, 1.02, 1.01])
    from analysis.regress.check import wall_verdict
    verdict, change, detail = wall_verdict(base, base * 1.03, TH)  # p < 0.05, but 3% < 5%
    assert verdict == "ok" and change == pytest.approx(0.03)
    verdict, _, _ = wall_verdict(base, base * 1.08, TH)
    assert verdict == "regressed"
    # 8% slower in the minimum, but one slow repetition in the baseline makes it noise: the
    # threshold grows with the spread (3 MADs) and the U test no longer separates the samples.
    noisy = np.array([1.0, 1.3, 1.05, 1.25, 1.1])
    verdict, _, detail = wall_verdict(noisy, noisy[[2, 1, 4, 3, 0]] * 1.08, TH)
    assert verdict == "ok", detail
    # A build several times slower, noisy on a loaded machine (the -O1 case seen here): its
    # spread in seconds is larger than the whole baseline, but relative to its level it is not.
    slow = np.array([6.1, 12.0, 8.2, 15.0, 6.8])
    verdict, change, detail = wall_verdict(base, slow, TH)
    assert verdict == "regressed" and change > 4, detail


def test_a_noisy_configuration_keeps_its_spread_in_the_threshold():
    """The wall threshold is max(wall_rel, wall_mads x the relative MAD): 12% slower in the
    minimum is beyond the 5% and the U test separates the samples (p = 0.027), but repetitions
    spread 7% around their median make 12% noise; without the spread term it would regress."""
    from analysis.regress.check import wall_verdict
    base = np.array([1.00, 1.04, 1.08, 1.12, 1.16, 1.20, 1.24, 1.28])
    verdict, change, detail = wall_verdict(base, base[::-1] * 1.12, TH)
    assert change == pytest.approx(0.12) and change > TH.wall_rel
    assert verdict == "ok", detail
    assert "threshold 21.1%, U test p=0.0273" in detail


def test_rounds_against_a_base_cancel_what_the_machine_does_to_both():
    """make regress BASE=REF: each round's two runs share the machine's state, so a drift that
    makes single runs vary 2.5x hides nothing the rounds' ratios show."""
    from analysis.regress.check import paired_wall_verdict
    rng = np.random.default_rng(8)
    machine = rng.choice([1.0, 1.3, 2.5], size=10) * (1 + rng.uniform(0, 0.01, 10))
    base = machine * (1 + rng.uniform(0, 0.01, 10))
    verdict, change, detail = paired_wall_verdict(base, machine * 1.08, TH)
    assert verdict == "regressed" and change == pytest.approx(0.08, abs=0.01), detail
    # The unpaired rule sees the same samples as noise.
    from analysis.regress.check import wall_verdict
    assert wall_verdict(base, machine * 1.08, TH)[0] == "ok"
    verdict, change, _ = paired_wall_verdict(base, machine * 0.9, TH)
    assert verdict == "improved"
    # Unchanged code: ratios about 1, either way.
    assert paired_wall_verdict(base, machine * (1 + rng.uniform(-0.01, 0.01, 10)), TH)[0] == "ok"
    # Shifted but by less than wall_rel, however significant: not a regression.
    assert paired_wall_verdict(base, base * 1.03, TH)[0] == "ok"
    # Beyond wall_rel in the median, but the rounds disagree: not significant.
    mixed = base * np.array([1.3, 0.8, 1.25, 0.85, 1.2, 0.92, 1.3, 0.8, 1.1, 1.08])  # median 1.09
    assert paired_wall_verdict(base, mixed, TH)[0] == "ok"


def test_paired_comparison_matches_rounds_by_rep():
    rng = np.random.default_rng(9)
    base = frame(rng, reps=10)
    now = base.copy()
    slow = (now["part"] == "wall") & (now["label"] == "default brute T=1")
    now.loc[slow, "value"] *= 1.2
    now = now.sample(frac=1, random_state=1)  # row order must not matter, only rep
    comparisons = compare_part(base, now, "wall", TH, [], paired=True)
    verdicts = {c.label: c.verdict for c in comparisons}
    assert verdicts.pop("default brute T=1") == "regressed"
    assert set(verdicts.values()) == {"ok"}


def test_changed_state_hash_is_a_correctness_change_reported_apart():
    rng = np.random.default_rng(5)
    base = frame(rng)
    now = frame(rng, hashes={"crowd cells T=1": "different"})
    status, reasons, comparisons, hashes = check(base, now)
    assert status == 1
    assert {(h.label, h.verdict) for h in hashes} == {("crowd cells T=1", "changed")}
    assert all(c.verdict == "ok" for c in comparisons)  # the speed is fine, the result is not
    assert any("final state changed" in r for r in reasons)


def test_repetitions_that_disagree_are_nondeterministic():
    rng = np.random.default_rng(6)
    base = frame(rng)
    now = base.copy()
    now.loc[(now["part"] == "wall") & (now["rep"] == 3) & (now["label"] == "default sweep T=2"),
            "state_hash"] = "other"
    _, _, _, hashes = check(base, now)
    assert [(h.label, h.part, h.verdict) for h in hashes] == [
        ("default sweep T=2", "wall", "nondeterministic")]


def test_a_machine_of_the_same_name_at_another_speed_skips_the_wall_time_gate():
    """VMs of one model name differ by 2x: when the whole suite runs at another speed, a stored
    wall time compares with nothing here; one configuration slower on a machine at the baseline's
    speed still regresses."""
    from types import SimpleNamespace
    from analysis.regress.cli import compare
    suite = SimpleNamespace(thresholds=TH)
    rng = np.random.default_rng(10)
    base = frame(rng)
    slower_vm = frame(rng, scale={k: 1.3 for k in CONFIGS})
    gates, comparisons, _ = compare(suite, base, meta(), slower_vm, meta(), ("wall",))
    assert "the suite runs +30% against the baseline here" in gates["wall"][0]
    assert not any(c.fails for c in comparisons)
    one_slower = frame(rng, scale={"default brute T=1": 1.3})
    gates, comparisons, _ = compare(suite, base, meta(), one_slower, meta(), ("wall",))
    assert gates["wall"] == []
    assert [c.label for c in comparisons if c.fails] == ["default brute T=1"]
    # Measured against a base commit in rounds, the speed is the same by construction.
    gates, _, _ = compare(suite, base, meta(), slower_vm, meta(), ("wall",), paired=True)
    assert gates["wall"] == []


def test_another_vm_of_the_same_name_skips_the_wall_time_gate_but_not_the_counts():
    rng = np.random.default_rng(11)
    base = frame(rng)
    now = frame(rng, scale={"default brute T=1": 1.5}, instructions={"default brute T=1": 1.1})
    for other in (meta(machine="m2"), meta(machine=None)):
        status, reasons, comparisons, _ = check(base, now, meta(), other)
        assert reasons == ["default brute T=1: instructions regressed by +10.0%"]
        wall = next(c for c in comparisons if c.part == "wall" and c.label == "default brute T=1")
        assert wall.verdict == "regressed" and not wall.gated
        assert "another machine (its /etc/machine-id differs" in wall.detail


def test_a_different_machine_skips_the_wall_time_gate():
    rng = np.random.default_rng(7)
    base = frame(rng)
    now = frame(rng, scale={"default brute T=1": 1.5})
    status, reasons, comparisons, _ = check(base, now, meta(), meta(cpu="Intel Xeon", cores=4))
    assert status == 0, reasons
    brute = next(c for c in comparisons if c.part == "wall" and c.label == "default brute T=1")
    assert brute.verdict == "regressed" and not brute.gated
    assert "cpu_model differs" in brute.detail and "online_cpus differs" in brute.detail


def test_a_native_build_on_other_isa_flags_skips_only_the_instruction_gate():
    rng = np.random.default_rng(8)
    base = frame(rng)
    now = frame(rng, scale={"default brute T=1": 1.5}, instructions={"crowd cells T=1": 1.2})
    native = "-O3 -march=native"
    status, reasons, comparisons, _ = check(
        base, now, meta(flags=native), meta(isa=("avx", "avx2", "avx512f", "sse4_2"), flags=native))
    assert status == 1 and len(reasons) == 1
    assert reasons[0].startswith("default brute T=1: wall_s regressed by +"), reasons
    crowd = next(c for c in comparisons if c.part == "instructions" and c.label == "crowd cells T=1")
    assert not crowd.gated and "here only: avx512f" in crowd.detail


def test_a_fixed_instruction_set_gates_counts_on_any_cpu():
    # The case of a runner that is not the baseline's machine: x86-64-v3 counts compare.
    rng = np.random.default_rng(10)
    base = frame(rng)
    now = frame(rng, instructions={"crowd cells T=1": 1.2})
    other = meta(cpu="Intel Xeon", cores=4, isa=("avx", "avx2", "avx512f", "sse4_2"))
    status, reasons, comparisons, _ = check(base, now, meta(), other)
    assert status == 1 and reasons[0].startswith("crowd cells T=1: instructions regressed"), reasons
    wall = next(c for c in comparisons if c.part == "wall" and c.label == "default brute T=1")
    assert not wall.gated  # wall time still only on the baseline's machine
    # ... but not against a baseline of another instruction set or glibc dispatch
    for base_meta in (meta(flags="-O3 -march=native"), {**meta(), "glibc_tunables": None}):
        _, _, comparisons, _ = check(base, now, base_meta, other)
        crowd = next(c for c in comparisons if c.part == "instructions" and c.label == "crowd cells T=1")
        assert not crowd.gated, base_meta


def test_new_configuration_and_failed_run():
    rng = np.random.default_rng(9)
    base = frame(rng)
    now = base.copy()
    now.loc[now["config_id"] == "i2", ["config_id"]] = "i9"  # not in the baseline
    now.loc[now["config_id"] == "w1", ["status", "value", "error"]] = ["crashed", None, "SIGILL"]
    status, reasons, comparisons, _ = check(base, now)
    by_id = {c.config_id: c for c in comparisons}
    assert by_id["i9"].verdict == "new" and not by_id["i9"].gated
    assert by_id["w1"].verdict == "failed" and status == 1
    # On another machine a run valgrind or the CPU cannot do is reported, not failed.
    status, _, comparisons, _ = check(base, now, meta(), meta(cpu="other"))
    assert status == 0
    assert {c.config_id: c for c in comparisons}["w1"].verdict == "not measured"


def test_change_points_find_a_planted_step_and_nothing_in_flat_noise():
    rng = np.random.default_rng(10)
    flat = 1.0 + 0.01 * rng.standard_normal(60)
    assert change_points(flat) == []
    stepped = np.concatenate([flat[:35], flat[35:] + 0.03])  # 3 sigma, below the 5% gate
    steps = change_points(stepped)
    assert [s.index for s in steps] == [35]
    assert steps[0].change == pytest.approx(0.03, abs=0.01)
    # Deterministic counts: a 0.3% step (below the 1% gate) is found above the 0.1% floor...
    counts = np.array([100e6] * 12 + [100.3e6] * 8)
    assert [s.index for s in change_points(counts, rel_floor=0.001)] == [12]
    # ... and a 0.01% wobble is not.
    assert change_points(np.array([100e6] * 12 + [100.01e6] * 8), rel_floor=0.001) == []


def test_history_steps_since_the_baseline_only():
    values = [1.0] * 10 + [1.04] * 10
    history = pd.DataFrame({
        "run_date": [f"2026-11-{d:02d}T00:00:00Z" for d in range(1, 21)],
        "commit": [f"c{d:02d}" for d in range(1, 21)],
        "commit_date": [f"2026-11-{d:02d}T00:00:00Z" for d in range(1, 21)],
        "cpu_model": "AMD EPYC", "part": "wall", "label": "default brute T=1",
        "config_id": "w0", "metric": "wall_s",
        "value": np.array(values) * (1 + 0.002 * np.random.default_rng(11).standard_normal(20))})
    found = history_steps(history, "AMD EPYC", since="2026-11-05T00:00:00Z")
    assert len(found) == 1 and "c11" in found[0] and "+4" in found[0]
    assert history_steps(history, "AMD EPYC", since="2026-11-15T00:00:00Z") == []
    assert history_steps(history, "another CPU", since=None) == []


SUITE = {"groups": [{"name": "g", "base": {"engine": "brute", "N": 10, "L": 100, "r": 1, "S": 1}}]}


@pytest.mark.parametrize("change, message", [
    ({"speed": 1}, "x.json: speed: unknown key"),
    ({"wall": {"repetitions": 3}}, "x.json: wall.repetitions: at least 5"),
    ({"thresholds": {"instructions": -1}}, "x.json: thresholds.instructions: expected a positive"),
    ({"groups": []}, "x.json: groups: expected a non-empty list"),
    ({"groups": [{"name": "g", "base": {}, "time": "cpu"}]}, "x.json: groups[0].time: expected"),
    ({"groups": [{"name": "a b", "base": {}}]}, "x.json: groups[0].name: expected a name"),
    ({"groups": [{"name": "g", "base": {}, "sweeps": {}}]}, "x.json: groups[0].sweeps: unknown"),
])
def test_suite_errors_name_the_key(change, message):
    with pytest.raises(SuiteError, match=message.replace("[", r"\[").replace("]", r"\]")):
        parse_suite(json.dumps({**SUITE, **change}), "x.json")


@pytest.mark.parametrize("group, message", [
    ({"parts": []}, "groups[0].parts: expected a non-empty list"),
    ({"parts": ["speed"]}, "groups[0].parts: expected a non-empty list"),
    ({"sweep": {"T": ["many"]}}, "groups[0].sweep.T[0]: expected a thread count or a multiple"),
    ({"sweep": {"T": [1, "0x"]}}, "groups[0].sweep.T[1]: expected a thread count or a multiple"),
])
def test_group_parts_and_relative_threads_are_checked(group, message):
    suite = {"groups": [{"name": "g", "base": {"engine": "auto", "N": 10}, **group}]}
    with pytest.raises(SuiteError, match=re.escape(message)):
        parse_suite(json.dumps(suite), "x.json")


def test_relative_threads_follow_the_machine_and_parts_select_groups():
    suite = parse_suite(json.dumps({"groups": [
        {"name": "over", "base": {"engine": "auto", "N": 10}, "sweep": {"T": ["1x", "1.5x", "4x"]},
         "parts": ["wall"]}]}), "x.json")
    group = suite.groups[0]
    assert group.parts == ("wall",)
    assert resolve_threads(group.body, 2)["sweep"]["T"] == [2, 3, 8]
    assert resolve_threads(group.body, 16)["sweep"]["T"] == [16, 24, 64]
    assert resolve_threads(group.body, 1)["sweep"]["T"] == [1, 2, 4]


def test_suite_json_error_names_the_line():
    with pytest.raises(SuiteError, match=r"x.json: line 2, column 1: invalid JSON"):
        parse_suite('{"groups": [\n}', "x.json")


def test_the_committed_suite_parses():
    suite = parse_suite((ROOT / "configs" / "regression.json").read_text(), "regression.json")
    assert {g.name for g in suite.groups} >= {"default", "section8", "crowd", "print"}


def test_cli_exits_2_without_a_baseline(tmp_path):
    done = run_tool("regress", "run", "--baseline", tmp_path / "none", "--out", tmp_path)
    assert done.returncode == 2
    assert "no baseline" in done.stderr and "make regress-baseline" in done.stderr


def test_a_build_with_avx512_is_refused_for_counting_on_an_avx512_cpu(tmp_path, monkeypatch):
    """valgrind 3.19 would die on every run of it; the error says which build to count."""
    for exe in ("psim", "psweep"):
        (tmp_path / exe).write_text("#!/bin/sh\n")
        (tmp_path / exe).chmod(0o755)
    (tmp_path / "CMakeCache.txt").write_text("PARTICLE_AVX512:BOOL=ON\n")
    monkeypatch.setattr("analysis.regress.suite.cpu_isa_flags", lambda: ["avx2", "avx512f"])
    with pytest.raises(SuiteError, match="AVX-512.*build-regress"):
        check_build(tmp_path, ("instructions",))
    check_build(tmp_path, ("wall",))  # timing it is fine
    monkeypatch.setattr("analysis.regress.suite.cpu_isa_flags", lambda: ["avx2"])
    check_build(tmp_path, ("instructions",))  # -march=native emits none on this CPU
    (tmp_path / "CMakeCache.txt").write_text("PARTICLE_AVX512:BOOL=OFF\n")
    monkeypatch.setattr("analysis.regress.suite.cpu_isa_flags", lambda: ["avx2", "avx512f"])
    check_build(tmp_path, ("instructions",))


@pytest.mark.skipif(not (countable_build() / "psweep").exists(),
                    reason="needs a build valgrind can run: make build, or on an AVX-512 CPU "
                           "make regress (build-regress)")
@pytest.mark.skipif(sanitized(), reason="valgrind cannot run a sanitizer build")
def test_two_identical_runs_count_the_same_instructions(tmp_path):
    """End to end through psweep and valgrind: two runs of each configuration, threads
    included, agree within the instruction threshold (measured: far below it)."""
    assert shutil.which("valgrind"), "valgrind is missing: scripts/bootstrap.sh installs it"
    suite = parse_suite(json.dumps({
        "instructions": {"repetitions": 2},
        "groups": [{"name": "tiny", "base": {"engine": "brute", "N": 300, "L": 5000, "r": 1,
                                              "S": 20, "T": 1},
                    "sweep": {"engine": ["brute", "sweep"], "T": [2]}}]}), "tiny.json")
    measurements, run_meta = measure(suite, countable_build(), tmp_path / "run",
                                     ("instructions",))
    spread = instruction_spread(measurements)
    assert len(spread) == 2 and (spread["count"] == 2).all()
    assert (spread["spread"] < suite.thresholds.instructions).all(), spread.to_string()
    assert spread["min"].min() > 1e6
    assert run_meta["valgrind"].startswith("valgrind-") and run_meta["machine"]["isa_flags"]


def make_targets() -> set[str]:
    """Targets with a rule in the Makefile (a `name ...:` line, not a `:=` assignment)."""
    targets = set()
    for line in (ROOT / "Makefile").read_text().splitlines():
        rule = re.match(r"^([A-Za-z0-9_.-]+(?:[ \t]+[A-Za-z0-9_.-]+)*)[ \t]*:(?!=)", line)
        if rule:
            targets.update(rule.group(1).split())
    return targets


def make_calls(script: str) -> list[str]:
    """The targets of every `make ...` command in a shell script (options, variables and
    comments left out)."""
    called = []
    for line in script.splitlines():
        for command in re.split(r"&&|\|\||[;|]", line.split("#", 1)[0]):
            words = command.split()
            if words[:1] == ["make"]:
                called += [w for w in words[1:] if "=" not in w and not w.startswith("-")]
    return called


def test_nightly_workflow_calls_only_existing_make_targets():
    yaml = pytest.importorskip("yaml", reason="python3-yaml (scripts/bootstrap.sh installs it)")
    workflow = yaml.safe_load((ROOT / ".github" / "workflows" / "nightly.yml").read_text())
    triggers = workflow.get("on", workflow.get(True))  # YAML 1.1 reads a bare `on` as True
    assert "schedule" in triggers and "workflow_dispatch" in triggers
    runs = [step["run"] for job in workflow["jobs"].values() for step in job["steps"]
            if "run" in step]
    called = [t for script in runs for t in make_calls(script)]
    assert {"test", "regress", "sweep"} <= set(called)
    assert set(called) <= make_targets(), set(called) - make_targets()
    ci = make_calls((ROOT / ".ci" / "run").read_text())
    assert "regress" in ci and set(ci) <= make_targets()


def test_make_calls_finds_targets_and_rejects_unknown_ones():
    assert make_calls("make test\nmake sweep CONFIG=threads.json && make -j2 regress") == [
        "test", "sweep", "regress"]
    assert "regresss" not in make_targets() and "regress-baseline" in make_targets()


def test_base_and_head_are_measured_interleaved(tmp_path):
    """make regress BASE=REF: group by group, base.rounds rounds of one run per build, the order
    alternating, base.repetitions runs a round, so that whatever the machine does meanwhile falls
    on both; `rep` is the round."""
    from analysis.regress.cli import measure_against_base
    suite = parse_suite((ROOT / "configs" / "regression.json").read_text(), "s.json")
    calls = []

    def fake_measure(single, build, out, parts):
        [group] = single.groups
        calls.append((build.name, parts[0], group.name, single.wall["repetitions"],
                      single.wall["warmup"]))
        rows = [[parts[0], group.name, "c1", "label", "e", "e", 1, 0, "ok", "wall_s", 1.0, "h",
                 None]]
        return pd.DataFrame(rows, columns=MEASUREMENT_COLUMNS), {"build": {"flags": build.name}}

    base, base_meta, head, head_meta = measure_against_base(
        suite, tmp_path / "head", tmp_path / "base", tmp_path / "out", ("instructions", "wall"),
        measure_one=fake_measure)
    rounds = suite.base_rounds
    counted = [g.name for g in suite.groups if "instructions" in g.parts]
    timed = [g.name for g in suite.groups if "wall" in g.parts]
    order = [("base", "head"), ("head", "base")]
    assert calls == ([(b, "instructions", g, suite.base_repetitions, 0) for g in counted
                      for b in order[0]]
                     + [(b, "wall", g, suite.base_repetitions, 0) for g in timed
                        for r in range(rounds) for b in order[r % 2]])
    wall = head[head["part"] == "wall"]
    assert sorted(wall[wall["group"] == timed[0]]["rep"]) == list(range(rounds))
    assert base_meta["build"]["flags"] == "base" and head_meta["build"]["flags"] == "head"
    wall_rounds = suite.wall["repetitions"]
    assert suite.wall["repetitions"] == wall_rounds  # the suite itself is left as it was


def test_a_group_recorded_alone_replaces_its_rows_and_keeps_the_rest(tmp_path, monkeypatch, capsys):
    from analysis.common.csv_out import write_csv
    from analysis.regress import cli
    old = frame(np.random.default_rng(1))
    start = old[old["part"] == "instructions"].head(1).assign(group="one", label="one brute",
                                                               config_id="o1", value=5e6)
    write_csv(pd.concat([old, start], ignore_index=True), tmp_path / "measurements.csv")
    (tmp_path / "meta.json").write_text(json.dumps(meta()))
    suite = tmp_path / "suite.json"
    suite.write_text(json.dumps({"groups": [
        {"name": "g", "base": {"engine": "brute", "N": 10}},
        {"name": "one", "base": {"engine": "brute", "N": 1}, "parts": ["instructions"]}]}))
    args = ["baseline", "--group", "one", "--config", str(suite), "--baseline", str(tmp_path),
            "--out", str(tmp_path / "out")]
    measured = []

    def measure_here(suite, build, out, parts, *rest):
        measured.append(([g.name for g in suite.groups], parts))
        return start.assign(value=4e6), {**meta(), "date": "2026-12-03T00:00:00Z",
                                          "git": {"commit": "abc"}}

    monkeypatch.setattr(cli, "measure", measure_here)
    assert cli.main(args) == 0
    assert measured == [(["one"], ("instructions",))]
    rows = pd.read_csv(tmp_path / "measurements.csv")
    assert rows[rows["group"] == "one"]["value"].tolist() == [4e6]
    assert len(rows[rows["group"] == "g"]) == len(old)
    recorded = json.loads((tmp_path / "meta.json").read_text())
    assert recorded["date"] == meta()["date"]  # the baseline's own, the group's apart
    assert recorded["groups_recorded_alone"] == [
        {"group": "one", "parts": ["instructions"], "date": "2026-12-03T00:00:00Z",
         "git": {"commit": "abc"}}]
    # Counted in another environment, its rows would not compare with the others': refused.
    monkeypatch.setattr(cli, "measure", lambda *a: (start, meta(flags="-O3 -march=native")))
    assert cli.main(args) == 2
    assert "group one: its instructions would not compare" in capsys.readouterr().err
    assert pd.read_csv(tmp_path / "measurements.csv")["value"].tolist() == rows["value"].tolist()
    assert cli.main(args[:2] + ["nothing"] + args[3:]) == 2
    assert "no group 'nothing'" in capsys.readouterr().err
