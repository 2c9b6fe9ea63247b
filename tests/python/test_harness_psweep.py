"""psweep end to end with the real psim: a tiny sweep and its files, --dry-run, config errors,
failed and timed-out runs as rows, and SIGINT followed by --resume (each repetition exactly once);
external programs beside the engines (docs/programs.md): plain_allpairs judged exact, broken
builds judged violations, programs that crash, hang, print without end or print garbage as rows,
their config errors, and resume after kill -9.

The binaries come from build/ (as `make test` builds them); PARTICLE_LAB_BUILD=DIR points elsewhere.
"""
import csv
import json
import os
import signal
import socket
import subprocess
import time
from pathlib import Path

import pytest

from build_path import BUILD
from entry_point import run_tool

ROOT = Path(__file__).resolve().parents[2]
PSWEEP = BUILD / "psweep"
PSIM = BUILD / "psim"

RUNS_COLUMNS = (
    "config_id,engine,N,L,r,S,slow_factor,T,P,G,seed,speed_min,speed_max,scene_file,pin,neighbour,wall_stop,overlap,rep,status,exit_code,"
    "wall_s,process_s,user_s,sys_s,max_rss_kb,voluntary_switches,involuntary_switches,context_switches,"
    "cpu_migrations,page_faults,task_clock_s,cycles,instructions,branches,branch_misses,cache_misses,counters_source,"
    "simulated_instructions,simulated_cache_misses,simulated_branch_misses,"
    "broad_phase_s,narrow_phase_s,order_s,filter_s,resolve_s,advance_s,pair_tests,candidates,pair_candidates,broad_phase_builds,pair_collisions,"
    "wall_collisions,dropped,overlaps,receding_overlaps,wall_stops,energy_initial,energy_final,max_overlap,energy_drift,wall_impulse,transfer_s,interrupted,time_reached,"
    "ranks,nodes,halo_particles_max,halo_particles_mean,bytes_sent_max,bytes_sent_mean,filter_rounds,comm_s_max,comm_s_mean,"
    "wait_s_max,wait_s_mean,state_hash,engine_ran,node,cpus,"
    "oversubscribed,busy_tasks,check,check_first_step,check_detail,error"
).split(",")
SUMMARY_COLUMNS = (
    "config_id,engine,N,L,r,S,slow_factor,T,P,G,seed,speed_min,speed_max,scene_file,pin,neighbour,wall_stop,overlap,reps,failed,"
    "wall_s_min,wall_s_median,wall_s_max,builds_per_substep,state_gb_per_s"
).split(",")


@pytest.fixture(scope="module", autouse=True)
def binaries():
    for exe in (PSWEEP, PSIM):
        assert exe.is_file(), f"{exe} is missing: build first (make build) or set PARTICLE_LAB_BUILD"


def write_config(tmp_path, name="tiny", **overrides):
    config = {
        "name": name,
        "base": {"engine": "brute", "N": 50, "L": 2000, "r": 1, "S": 20, "seed": 7, "T": 1},
        "sweep": {"N": [40, 80], "T": [1, 2], "G": [2, 4]},
        "repetitions": 2, "warmup": 1, "pin": "close", "timeout_s": 30,
    }
    config.update(overrides)
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(config))
    return path


def psweep(*args, timeout=60):
    return subprocess.run([str(PSWEEP), *map(str, args)], capture_output=True, text=True, timeout=timeout,
                          cwd=ROOT)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], [dict(zip(rows[0], row)) for row in rows[1:]]


def test_tiny_sweep_writes_runs_summary_and_meta(tmp_path):
    out = tmp_path / "out"
    done = psweep(write_config(tmp_path), "--out", out)
    assert done.returncode == 0, done.stderr

    header, runs = read_csv(out / "runs.csv")
    assert header == RUNS_COLUMNS
    # G is left out for brute: 2 N x 2 T configurations, 2 repetitions each, warm-ups not recorded
    assert len(runs) == 8
    assert sorted((r["config_id"], r["rep"]) for r in runs) == sorted(
        {(r["config_id"], rep) for r in runs for rep in ("0", "1")})
    cores = os.cpu_count()
    for r in runs:
        assert r["status"] == "ok", r["error"]
        assert r["exit_code"] == "0" and r["error"] == ""
        assert r["G"] == "" and r["speed_min"] == "" and r["scene_file"] == ""
        assert r["pin"] == "close" and r["engine_ran"] == "brute"
        assert r["node"] == (os.environ.get("SLURMD_NODENAME") or socket.gethostname())
        assert 0 < float(r["wall_s"]) < float(r["process_s"])
        assert int(r["pair_tests"]) == int(r["N"]) * (int(r["N"]) - 1) // 2 * 20
        assert len(r["state_hash"]) == 16
        assert r["cpus"] and all(c.isdigit() for c in r["cpus"].split(";"))
        assert len(r["cpus"].split(";")) <= int(r["T"])
        assert r["oversubscribed"] == ("1" if int(r["T"]) > cores else "0")
        assert int(r["max_rss_kb"]) > 0 and r["context_switches"] != "" and r["page_faults"] != ""
    # same scene whatever the thread count: the engine is deterministic
    for n in ("40", "80"):
        assert len({r["state_hash"] for r in runs if r["N"] == n}) == 1

    header, summary = read_csv(out / "summary.csv")
    assert header == SUMMARY_COLUMNS
    assert len(summary) == 4
    for s in summary:
        walls = sorted(float(r["wall_s"]) for r in runs if r["config_id"] == s["config_id"])
        assert s["reps"] == "2" and s["failed"] == "0"
        assert float(s["wall_s_min"]) == walls[0] and float(s["wall_s_max"]) == walls[-1]
        assert float(s["wall_s_median"]) == pytest.approx((walls[0] + walls[1]) / 2)
        assert s["builds_per_substep"] == "0"  # brute builds nothing
        particle_steps = int(s["N"]) * int(s["S"])
        assert float(s["state_gb_per_s"]) == pytest.approx(48 * particle_steps / walls[0] / 1e9)

    meta = json.loads((out / "meta.json").read_text())
    assert meta["config"]["name"] == "tiny"
    for key in ("git", "build", "machine", "openmp", "counters", "date", "psim"):
        assert key in meta
    assert "commit" in meta["git"] and "dirty" in meta["git"]
    assert meta["machine"]["online_cpus"] == cores
    assert "hardware perf events" in meta["counters"]["note"]
    assert meta["sessions"][-1]["jobs"] == 12  # 8 runs + 4 warm-ups
    # psim's declaration travels with the results: the analysis reads engines and metrics there
    declared = json.loads(subprocess.run([str(PSIM), "--describe"], capture_output=True,
                                         text=True, check=True).stdout)
    assert meta["declaration"] == declared
    # the OpenMP recorded is psim's, from its declaration, not psweep's own build
    assert meta["openmp"] == declared["openmp"] and declared["openmp"]["version"] >= 201511
    metric_columns = [m["key"] for m in declared["metrics"]]
    runs_header, _ = read_csv(out / "runs.csv")
    first = runs_header.index("simulated_branch_misses") + 1
    assert runs_header[first:runs_header.index("state_hash")] == metric_columns
    assert (out / "inputs").is_dir() and not (out / "tmp").exists()


def psim_declaring_event(tmp_path):
    """psim whose --describe also declares an engine using none of T, G, K (as `event` does):
    expansion must follow the declaration, not engine names."""
    declaration = json.loads(subprocess.run([str(PSIM), "--describe"], capture_output=True,
                                            text=True, check=True).stdout)
    if not any(e["name"] == "event" for e in declaration["engines"]):
        declaration["engines"].append({"name": "event", "exact": True, "reference": False,
                                       "uses": [], "about": "test"})
    (tmp_path / "describe.json").write_text(json.dumps(declaration))
    script = tmp_path / "psim"
    script.write_text(f'#!/bin/sh\n[ "$1" = --describe ] && exec cat "{tmp_path}/describe.json"\n'
                      f'exec "{PSIM}" "$@"\n')
    script.chmod(0o755)
    return script


def test_dry_run_lists_runs_and_runs_nothing(tmp_path):
    out = tmp_path / "out"
    config = write_config(tmp_path, sweep={"engine": ["brute", "event"], "T": [1, 2, 3], "slow_factor": [1, 2]})
    done = psweep(config, "--out", out, "--dry-run", "--psim", psim_declaring_event(tmp_path))
    assert done.returncode == 0, done.stderr
    lines = done.stdout.strip().splitlines()
    # brute: 3 T x 2 K; event ignores T and K: 1
    assert lines[-1].startswith("7 configurations x 2 repetitions = 14 runs (+ 7 warm-up runs)")
    assert len(lines) == 8
    assert not out.exists()


@pytest.mark.parametrize("change, message", [
    ({"sweep": {"engine": ["brute", "nosuch"]}}, "tiny.json: sweep.engine[1]: unknown engine \"nosuch\""),
    ({"sweep": {"T": [1, 2, -3]}}, "tiny.json: sweep.T[2]: expected a positive integer, got -3"),
    ({"repetitions": "5"}, "tiny.json: repetitions: expected a positive integer"),
    ({"colour": "blue"}, "tiny.json: colour: unknown key"),
    ({"quiet_wait_s": -1}, "tiny.json: quiet_wait_s: expected a non-negative number"),
    ({"quiet_wait_s": 7200}, "tiny.json: quiet_wait_s: expected at most 3600 (an hour), got 7200"),
    # psim's own limits, checked for every configuration before anything runs (issue 8)
    ({"sweep": {"N": [10, 100000001]}}, "tiny.json: sweep.N[1]: must be between 1 and 100000000"),
    ({"sweep": {"engine": ["grid"], "G": [100000]}}, "tiny.json: sweep.G[0]: G must be between 1 and 4096"),
    ({"sweep": {"T": [5000]}}, "tiny.json: sweep.T[0]: must be from 1 to"),
    ({"sweep": {"N": [2000000]}}, "tiny.json: sweep.N[0]: scene too dense for random placement"),
    ({"sweep": {"r": [1e-300]}}, "tiny.json: sweep.r[0]: the box is L/(2r)"),
    # what psim's placement cannot place from the seed (below Oler's bound), speeds beyond doubles
    ({"base": {"engine": "brute", "N": 250, "L": 40, "r": 1, "S": 2, "seed": 3210, "T": 1}, "sweep": {}},
     "tiny.json: base.N: scene too dense for random placement: placed 249 of 250"),
    ({"base": {"engine": "brute", "N": 50, "L": 1e300, "r": 1e290, "S": 2, "T": 1, "speed_min": 1e300,
               "speed_max": 1e300}, "sweep": {}},
     "tiny.json: base.speed_max: the kinetic energy 2.5e+601 is beyond the largest double"),
])
def test_config_errors_exit_2_naming_the_key(tmp_path, change, message):
    done = psweep(write_config(tmp_path, **change), "--out", tmp_path / "out")
    assert done.returncode == 2
    assert message in done.stderr
    assert not (tmp_path / "out" / "runs.csv").exists()


def test_an_engine_this_build_cannot_run_is_refused_by_the_dry_run(tmp_path):
    """gpu in a build without CUDA: refused before anything runs, naming the key and psim's
    reason, not estimated at 0 s and failed run by run."""
    declared = json.loads(subprocess.run([str(PSIM), "--describe"], capture_output=True,
                                         text=True, check=True).stdout)
    why = {e["name"]: e.get("unavailable", "") for e in declared["engines"]}
    if not why.get("gpu"):
        pytest.skip("this build of psim runs gpu")
    done = psweep(write_config(tmp_path, sweep={"engine": ["brute", "gpu"]}), "--dry-run",
                  "--count")
    assert done.returncode == 2, done.stdout
    assert (f'tiny.json: sweep.engine[1]: engine "gpu" cannot run in this build of psim: '
            f'{why["gpu"]}') in done.stderr


def test_a_just_placeable_random_scene_is_accepted_and_runs(tmp_path):
    """249 disks of radius 1 in a box of 40 from seed 3210: psweep accepts them (one more is
    refused above), and psim places and runs them."""
    out = tmp_path / "out"
    config = write_config(tmp_path, base={"engine": "brute", "N": 249, "L": 40, "r": 1, "S": 2, "seed": 3210,
                                          "T": 1}, sweep={}, repetitions=1, warmup=0)
    done = psweep(config, "--out", out)
    assert done.returncode == 0, done.stderr
    _, rows = read_csv(out / "runs.csv")
    assert [row["status"] for row in rows] == ["ok"]


def test_invalid_json_names_line_and_column(tmp_path):
    path = tmp_path / "broken.json"
    path.write_text('{\n  "name": "x",\n  "base": {"N": 10,,}\n}\n')
    done = psweep(path, "--dry-run")
    assert done.returncode == 2
    assert "broken.json: line 3, column 20: invalid JSON" in done.stderr


def test_failed_and_timed_out_runs_are_rows_and_the_sweep_goes_on(tmp_path):
    out = tmp_path / "out"
    # N=20000 brute for 10000 steps (2e12 pair tests) cannot finish in 1 s; N=20 takes a few ms
    # per thousand steps, so even a loaded machine finishes it well inside the timeout
    config = write_config(tmp_path, base={"engine": "brute", "N": 20, "L": 100000, "r": 1, "S": 10000, "T": 1},
                          sweep={"N": [20000, 20]}, repetitions=1, warmup=0, timeout_s=1)
    started = time.monotonic()
    done = psweep(config, "--out", out)
    assert done.returncode == 0, done.stderr
    assert time.monotonic() - started < 15
    _, runs = read_csv(out / "runs.csv")
    by_n = {r["N"]: r for r in runs}
    assert by_n["20000"]["status"] == "timeout" and by_n["20000"]["exit_code"] == ""
    assert "exceeded timeout_s = 1" in by_n["20000"]["error"]
    assert float(by_n["20000"]["process_s"]) < 5
    assert by_n["20"]["status"] == "ok"
    _, summary = read_csv(out / "summary.csv")
    timed_out = next(s for s in summary if s["N"] == "20000")
    assert timed_out["reps"] == "0" and timed_out["failed"] == "1" and timed_out["wall_s_min"] == ""

    # a scene file psim would reject (one particle line short) is refused before anything runs,
    # with psim's message
    scene = tmp_path / "short.in"
    scene.write_text("2\n100\n1\n10\nperf\n0 10 10 1 1\n")
    bad = write_config(tmp_path, name="bad", base={"engine": "brute", "T": 1}, sweep={},
                       scene_file=str(scene), repetitions=1, warmup=0)
    done = psweep(bad, "--out", tmp_path / "bad")
    assert done.returncode == 2
    assert "short.in:7: particle: expected 2 particle lines, got 1" in done.stderr
    assert not (tmp_path / "bad" / "runs.csv").exists()

    # a run psim fails anyway (a stand-in psim that fails every run) is a row with its exit code
    # and message, and the sweep goes on
    scene.write_text("2\n100\n1\n10\nperf\n0 10 10 1 1\n1 30 30 1 1\n")
    failing = tmp_path / "failing_psim"
    failing.write_text(f'#!/bin/sh\ncase "$1" in --describe) exec "{PSIM}" "$@";; esac\n'
                       'echo "psim: refused by the stand-in" >&2\nexit 2\n')
    failing.chmod(0o755)
    done = psweep(bad, "--out", tmp_path / "bad", "--psim", failing)
    assert done.returncode == 0, done.stderr
    _, runs = read_csv(tmp_path / "bad" / "runs.csv")
    assert len(runs) == 1
    assert runs[0]["status"] == "failed" and runs[0]["exit_code"] == "2"
    assert "refused by the stand-in" in runs[0]["error"]
    assert runs[0]["scene_file"] == str(scene) and runs[0]["seed"] == "" and runs[0]["N"] == "2"


def start_sweep_until_rows(config, out, rows):
    """psweep started in the background, once runs.csv holds `rows` rows (or 30 s passed)."""
    proc = subprocess.Popen([str(PSWEEP), str(config), "--out", str(out)], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    runs_csv = out / "runs.csv"
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        if runs_csv.exists() and len(runs_csv.read_text().splitlines()) >= 1 + rows:
            break
        time.sleep(0.02)
    return proc


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_interrupt_then_resume_runs_each_repetition_exactly_once(tmp_path, sig):
    out = tmp_path / "out"
    # 6 configurations x 3 repetitions of roughly 0.1-0.3 s each
    config = write_config(tmp_path, base={"engine": "brute", "N": 600, "L": 20000, "r": 1, "S": 300, "T": 1},
                          sweep={"N": [500, 600, 700], "T": [1, 2]}, repetitions=3, warmup=0)
    proc = start_sweep_until_rows(config, out, 4)
    runs_csv = out / "runs.csv"
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 128 + sig, err
    assert "--resume" in err
    _, partial = read_csv(runs_csv)
    assert 4 <= len(partial) < 18, "interrupt came too late to test resume"
    assert list(out.glob("tmp/*")) == []

    done = psweep(config, "--out", out, "--resume")
    assert done.returncode == 0, done.stderr
    _, runs = read_csv(runs_csv)
    assert runs[:len(partial)] == partial  # finished rows kept as they were
    keys = [(r["config_id"], r["rep"]) for r in runs]
    assert len(keys) == 18 and len(set(keys)) == 18
    assert {rep for _, rep in keys} == {"0", "1", "2"}
    assert all(r["status"] == "ok" for r in runs)
    _, summary = read_csv(out / "summary.csv")
    assert [s["reps"] for s in summary] == ["3"] * 6
    meta = json.loads((out / "meta.json").read_text())
    assert len(meta["resumed"]) == 1 and len(meta["sessions"]) == 2

    # resuming a finished sweep runs nothing
    again = psweep(config, "--out", out, "--resume")
    assert again.returncode == 0
    assert len(read_csv(runs_csv)[1]) == 18


def test_a_fresh_run_sets_earlier_results_aside(tmp_path):
    out = tmp_path / "out"
    config = write_config(tmp_path, sweep={}, repetitions=1, warmup=0)
    assert psweep(config, "--out", out).returncode == 0
    first = (out / "runs.csv").read_text()
    done = psweep(config, "--out", out)
    assert done.returncode == 0
    assert (out / "previous" / "runs.csv").read_text() == first
    assert len(read_csv(out / "runs.csv")[1]) == 1


# ---------------------------------------------------------------- external programs

PLAIN = BUILD / "plain_allpairs"
CHECK_PROGRAMS = BUILD / "check_programs"
# psim's metrics: a program has none, so its cells stay empty
ENGINE_METRICS = ["broad_phase_s", "pair_tests", "pair_collisions", "energy_initial", "energy_drift",
                  "state_hash", "engine_ran", "cpus"]


def programs_config(tmp_path, programs, engines, name="progs", **overrides):
    settings = {"base": {"engine": "brute", "N": 40, "L": 2000, "r": 1, "S": 20, "seed": 7, "T": 1},
                "sweep": {"engine": engines}, "programs": programs, "repetitions": 2, "warmup": 1,
                "pin": "none", "timeout_s": 30}
    settings.update(overrides)
    return write_config(tmp_path, name=name, **settings)


def script(tmp_path, name, body):
    path = tmp_path / name
    path.write_text("#!/bin/sh\n" + body + "\n")
    path.chmod(0o755)
    return str(path)


def by_engine(runs):
    out = {}
    for r in runs:
        out.setdefault(r["engine"], []).append(r)
    return out


def test_plain_allpairs_as_a_program_is_exact_with_empty_engine_metrics(tmp_path):
    out = tmp_path / "out"
    config = programs_config(tmp_path, {"plain": {"command": [str(PLAIN)], "input": "stdin"}},
                             ["brute", "plain"], sweep={"engine": ["brute", "plain"], "T": [1, 2]})
    done = psweep(config, "--out", out)
    assert done.returncode == 0, done.stderr
    header, runs = read_csv(out / "runs.csv")
    assert header == RUNS_COLUMNS
    rows = by_engine(runs)
    assert len(rows["brute"]) == 4 and len(rows["plain"]) == 2  # plain ignores T: one configuration
    for r in rows["plain"]:
        assert r["status"] == "ok", r["error"]
        assert r["T"] == "" and r["slow_factor"] == "1"
        assert r["wall_s"] == r["process_s"]  # its whole process: a program has no timer of its own
        assert float(r["max_rss_kb"]) > 0
        assert all(r[m] == "" for m in ENGINE_METRICS), {m: r[m] for m in ENGINE_METRICS}
    # judged once per configuration, on its first recorded run
    judged = [r for r in rows["plain"] if r["check"]]
    assert len(judged) == 1 and judged[0]["rep"] == "0"
    assert judged[0]["check"] == "exact" and judged[0]["check_first_step"] == ""
    assert "identical to the reference" in judged[0]["check_detail"]
    assert all(r["check"] == "" for r in rows["brute"])
    cid = judged[0]["config_id"]
    assert (out / "outputs" / f"{cid}.out").stat().st_size > 0
    assert json.loads((out / "outputs" / f"{cid}.check.json").read_text())["verdict"] == "exact"
    scene = (out / "inputs" / f"{cid}-particles.in").read_text().splitlines()
    assert scene[:5] == ["40", "2000", "1", "20", "perf"] and len(scene) == 45
    meta = json.loads((out / "meta.json").read_text())
    plain = meta["programs"]["plain"]
    assert plain["command"] == [str(PLAIN)] and plain["input"] == "stdin" and plain["uses"] == []
    assert plain["executable_hash"].startswith("fnv1a64:")
    assert meta["sessions"][0]["checks_s"] > 0
    _, summary = read_csv(out / "summary.csv")
    assert [s["reps"] for s in summary if s["engine"] == "plain"] == ["2"]


def test_broken_builds_are_judged_violations_at_their_step(tmp_path):
    out = tmp_path / "out"
    # a shell that runs a program on its scene file: both staged into the sandbox
    nan = ["/bin/sh", "-c", 'exec "$0" < "$1"', str(CHECK_PROGRAMS / "nan")]
    programs = {"plain": {"command": [str(PLAIN), "{K}"], "uses": ["slow_factor"]},
                "wall": {"command": [str(CHECK_PROGRAMS / "wall_tolerance")]},
                "nan": {"command": nan + ["{scene}"], "input": "file"}}
    config = write_config(tmp_path, name="broken", base={"engine": "brute", "T": 1},
                          sweep={"engine": ["brute", "plain", "wall", "nan"]},
                          scene_file=str(ROOT / "scenes" / "wall_before_end.in"),
                          programs=programs,
                          repetitions=1, warmup=0, timeout_s=30)
    done = psweep(config, "--out", out)
    assert done.returncode == 0, done.stderr
    rows = {r["engine"]: r for r in read_csv(out / "runs.csv")[1]}
    assert rows["plain"]["check"] == "exact"
    assert rows["wall"]["check"] == "violations" and rows["wall"]["check_first_step"] == "1"
    assert "wall hit missed" in rows["wall"]["check_detail"]
    assert rows["nan"]["check"] == "violations" and "not finite" in rows["nan"]["check_detail"]
    assert "wall: check: violations" in done.stderr
    # the scoreboard ranks the broken builds below the correct program and the engine
    board = run_tool("scoreboard", out)
    assert board.returncode == 0, board.stderr
    _, ranked = read_csv(out / "scoreboard.csv")
    assert [r["name"] for r in ranked][:2] in (["brute", "plain"], ["plain", "brute"])
    assert {r["name"] for r in ranked[2:]} == {"wall", "nan"}
    assert all(r["verdict"] == "violations" for r in ranked[2:])
    assert "the first at time unit 1, particle 0: wall hit missed" in next(
        r for r in ranked if r["name"] == "wall")["first_violation"]


def test_misbehaving_programs_are_rows_and_the_sweep_completes(tmp_path):
    out = tmp_path / "out"
    not_executable = tmp_path / "not_executable"
    not_executable.write_text("#!/bin/sh\n")
    programs = {
        "crash": {"command": [script(tmp_path, "crash.sh", "kill -SEGV $$")]},
        "hang": {"command": [script(tmp_path, "hang.sh", "exec sleep 60")]},
        "endless": {"command": [script(tmp_path, "endless.sh", "exec yes 0 1.00000000 2.00000000")]},
        "garbage": {"command": [script(tmp_path, "garbage.sh", "echo hello; echo world")]},
        "fails": {"command": [script(tmp_path, "fails.sh", "echo 'no input for me' >&2; exit 3")]},
        "missing": {"command": [str(tmp_path / "no_such_program")]},
        "noexec": {"command": [str(not_executable)]},
        "plain": {"command": [str(PLAIN)]},
    }
    config = programs_config(tmp_path, programs, list(programs), timeout_s=2, warmup=0,
                             repetitions=1)
    started = time.monotonic()
    done = psweep(config, "--out", out, timeout=120)
    assert done.returncode == 0, done.stderr
    assert time.monotonic() - started < 60
    rows = {r["engine"]: r for r in read_csv(out / "runs.csv")[1]}
    assert rows.keys() == programs.keys()  # nothing of the sweep lost
    assert rows["crash"]["status"] == "crashed" and "signal 11" in rows["crash"]["error"]
    assert rows["hang"]["status"] == "timeout" and "exceeded timeout_s = 2" in rows["hang"]["error"]
    assert rows["endless"]["status"] == "too_much_output"
    assert "where a 2019 output of this scene takes at most" in rows["endless"]["error"]
    limit = int(rows["endless"]["error"].split()[1])
    assert limit < 1_000_000  # 2 states of 40 lines: the bound is tight, not 4 GB of `yes`
    assert rows["garbage"]["status"] == "ok" and rows["garbage"]["check"] == "malformed"
    assert "line 1: " in rows["garbage"]["check_detail"]
    assert rows["fails"]["status"] == "failed" and rows["fails"]["exit_code"] == "3"
    assert "no input for me" in rows["fails"]["error"]
    for name in ("missing", "noexec"):
        assert rows[name]["status"] == "failed", rows[name]
        assert "cannot execute" in rows[name]["error"]
    assert rows["plain"]["check"] == "exact"
    for name in ("crash", "hang", "endless", "fails", "missing", "noexec"):
        assert rows[name]["check"] == "" and rows[name]["wall_s"] == ""
    assert list(out.glob("tmp/*")) == []


@pytest.mark.parametrize("programs, message", [
    ({"mine": {"command": ["./x", "{threads}"]}},
     "programs.mine.command[1]: unknown placeholder {threads}"),
    ({"brute": {"command": ["./x"]}}, 'programs.brute: shadows psim\'s engine "brute"'),
    ({"mine": {"command": "./x {T}"}}, "programs.mine.command: expected a non-empty list of strings"),
    ({"mine": {"command": ["./x", 1]}}, "programs.mine.command[1]: expected a string, got 1"),
    ({"mine": {"command": ["./x"], "stdin": True}}, "programs.mine.stdin: unknown key"),
])
def test_program_config_errors_exit_2_at_their_key_path(tmp_path, programs, message):
    config = programs_config(tmp_path, programs, ["brute"])
    done = psweep(config, "--out", tmp_path / "out")
    assert done.returncode == 2, done.stderr
    assert message in done.stderr
    assert not (tmp_path / "out" / "runs.csv").exists()


def test_resume_after_kill_with_programs(tmp_path):
    out = tmp_path / "out"
    # the sandbox shows the program only the files its command names: plain_allpairs is one
    slow = ["/bin/sh", "-c", 'sleep 0.1; exec "$0"', str(PLAIN)]
    config = programs_config(tmp_path, {"slow": {"command": slow}}, ["slow"],
                             sweep={"engine": ["slow"], "N": [20, 30, 40]}, repetitions=3, warmup=0)
    proc = start_sweep_until_rows(config, out, 4)
    runs_csv = out / "runs.csv"
    proc.kill()
    proc.communicate(timeout=30)
    _, partial = read_csv(runs_csv)
    assert 4 <= len(partial) < 9, "kill came too late to test resume"

    # a changed program is another program: refused, naming the key
    changed = programs_config(tmp_path, {"slow": {"command": slow + ["2"]}}, ["slow"], name="changed",
                              sweep={"engine": ["slow"], "N": [20, 30, 40]}, repetitions=3,
                              warmup=0)
    refused = psweep(changed, "--out", out, "--resume")
    assert refused.returncode == 2 and "programs.slow.command[4]" in refused.stderr

    done = psweep(config, "--out", out, "--resume")
    assert done.returncode == 0, done.stderr
    _, runs = read_csv(runs_csv)
    assert runs[:len(partial)] == partial
    keys = [(r["config_id"], r["rep"]) for r in runs]
    assert len(keys) == 9 and len(set(keys)) == 9
    assert all(r["status"] == "ok" for r in runs)
    verdicts = {}
    for r in runs:
        if r["check"]:
            verdicts.setdefault(r["config_id"], []).append(r["check"])
    assert verdicts == {cid: ["exact"] for cid in {r["config_id"] for r in runs}}


def test_a_perf_mode_sweep_judges_each_program_step_by_step(tmp_path):
    # A random scene in perf mode: the timed runs' final states alone keep the invariants for a
    # program that takes two collisions for one particle in a step; its judging run, the same
    # particles in print mode for judge_steps time units, shows the broken rule.
    out = tmp_path / "out"
    programs = {"two": {"command": [str(CHECK_PROGRAMS / "two_collisions")]},
                "plain": {"command": [str(PLAIN)]}}
    config = programs_config(tmp_path, programs, list(programs), repetitions=1, warmup=0,
                             judge_steps=30, base={"engine": "brute", "N": 200, "L": 2000,
                                                   "r": 1, "S": 200, "seed": 7, "T": 1})
    done = psweep(config, "--out", out)
    assert done.returncode == 0, done.stderr
    rows = {r["engine"]: r for r in read_csv(out / "runs.csv")[1]}
    two, plain = rows["two"], rows["plain"]
    assert two["check"] == "violations", two
    assert two["check_detail"].startswith("judging run (print mode, S = 30): ")
    assert "two collisions for one particle in a step" in two["check_detail"]
    assert two["check_first_step"] == "1"
    assert plain["check"] == "exact", plain
    cid = two["config_id"]
    judge_scene = (out / "inputs" / f"{cid}-judge.in").read_text().splitlines()
    assert judge_scene[3:5] == ["30", "print"]
    assert (out / "outputs" / f"{cid}.judge.check.json").is_file()
    assert (out / "outputs" / f"{cid}.check.json").is_file()  # the timed run's, as before


def test_wall_stop_is_a_parameter_of_the_model(tmp_path):
    # Two readings of "stops just next to the wall" (docs/model.md, "Readings"): another state per
    # reading, the same in every discrete engine; the event engine has none, so one row.
    out = tmp_path / "out"
    config = write_config(tmp_path, base={"engine": "brute", "N": 200, "L": 2000, "r": 1,
                                          "S": 50, "T": 1},
                          sweep={"engine": ["brute", "cells", "event"],
                                 "wall_stop": ["per-coordinate", "whole-motion"]},
                          repetitions=1, warmup=0)
    done = psweep(config, "--out", out)
    assert done.returncode == 0, done.stderr
    rows = read_csv(out / "runs.csv")[1]
    hashes = {(r["engine"], r["wall_stop"]): r["state_hash"] for r in rows}
    assert set(hashes) == {("brute", "per-coordinate"), ("brute", "whole-motion"),
                           ("cells", "per-coordinate"), ("cells", "whole-motion"),
                           ("event", "per-coordinate")}
    for reading in ("per-coordinate", "whole-motion"):
        assert hashes[("brute", reading)] == hashes[("cells", reading)]
    assert hashes[("brute", "per-coordinate")] != hashes[("brute", "whole-motion")]
    # The default reading keeps the ids sweeps had before the parameter.
    plain = [r for r in rows if r["engine"] == "brute" and r["wall_stop"] == "per-coordinate"]
    again = write_config(tmp_path, name="plain", base={"engine": "brute", "N": 200, "L": 2000,
                                                       "r": 1, "S": 50, "T": 1},
                         sweep={}, repetitions=1, warmup=0)
    listed = psweep(again, "--out", tmp_path / "out2", "--dry-run")
    assert plain[0]["config_id"] in listed.stdout, listed.stdout


def test_overlap_is_a_parameter_of_the_model(tmp_path):
    # The two readings of the handout's overlap sentence: pairs left overlapping by the
    # one-collision rule recede on this dense scene (receding_overlaps), so the readings part.
    out = tmp_path / "out"
    config = write_config(tmp_path, base={"engine": "brute", "N": 200, "L": 300, "r": 2,
                                          "S": 30, "T": 1, "seed": 1},
                          sweep={"engine": ["brute", "sweep", "event"],
                                 "overlap": ["approaching", "always"]},
                          repetitions=1, warmup=0)
    done = psweep(config, "--out", out)
    assert done.returncode == 0, done.stderr
    rows = read_csv(out / "runs.csv")[1]
    hashes = {(r["engine"], r["overlap"]): r["state_hash"] for r in rows}
    assert set(hashes) == {("brute", "approaching"), ("brute", "always"),
                           ("sweep", "approaching"), ("sweep", "always"),
                           ("event", "approaching")}
    for reading in ("approaching", "always"):
        assert hashes[("brute", reading)] == hashes[("sweep", reading)]
    assert hashes[("brute", "approaching")] != hashes[("brute", "always")]
    brute = next(r for r in rows if r["engine"] == "brute" and r["overlap"] == "approaching")
    assert int(brute["receding_overlaps"]) > 0 and int(brute["wall_stops"]) > 0, brute


def test_a_program_of_the_other_reading_is_judged_by_it_unless_the_config_requires_one(tmp_path):
    programs = {"whole": {"command": [str(CHECK_PROGRAMS / "whole_motion")]}}
    scene = str(ROOT / "tests" / "check" / "scenes" / "random200.in")
    for required in (None, "per-coordinate"):
        out = tmp_path / f"out-{required}"
        extra = {"reading": required} if required else {}
        config = programs_config(tmp_path, programs, ["whole"], repetitions=1, warmup=0,
                                 scene_file=scene, base={"engine": "brute", "T": 1}, **extra)
        done = psweep(config, "--out", out)
        assert done.returncode == 0, done.stderr
        (row,) = read_csv(out / "runs.csv")[1]
        if required:
            assert row["check"] == "violations", row
            assert row["check_detail"].startswith(
                "per-coordinate reading (required), overlap either: 107 "), row["check_detail"]
        else:
            assert row["check"] == "exact", row
            assert row["check_detail"].startswith("whole-motion reading, overlap either: identical "), \
                row["check_detail"]


def test_a_required_overlap_reading_judges_by_it(tmp_path):
    programs = {"rec": {"command": [str(CHECK_PROGRAMS / "overlap_receding")]}}
    scene = str(ROOT / "scenes" / "overlap_receding.in")
    for required, verdict, named in ((None, "exact", "overlap always:"),
                                     ("approaching", "violations",
                                      "overlap approaching (required):")):
        extra = {"overlap_reading": required} if required else {}
        config = programs_config(tmp_path, programs, ["rec"], name=f"rec-{required}",
                                 repetitions=1, warmup=0, scene_file=scene,
                                 base={"engine": "brute", "T": 1}, **extra)
        done = psweep(config, "--out", tmp_path / f"out-{required}")
        assert done.returncode == 0, done.stderr
        (row,) = read_csv(tmp_path / f"out-{required}" / "runs.csv")[1]
        assert row["check"] == verdict and named in row["check_detail"], row


def test_an_unknown_reading_is_refused_naming_the_key(tmp_path):
    config = write_config(tmp_path, reading="sideways")
    done = psweep(config, "--out", tmp_path / "out")
    assert done.returncode == 2
    assert "reading: expected one of" in done.stderr and "sideways" in done.stderr
    config = write_config(tmp_path, sweep={"wall_stop": ["per-coordinate", "diagonal"]})
    done = psweep(config, "--out", tmp_path / "out")
    assert done.returncode == 2 and "sweep.wall_stop[1]" in done.stderr, done.stderr
    config = write_config(tmp_path, sweep={"overlap": ["never"]})
    done = psweep(config, "--out", tmp_path / "out")
    assert done.returncode == 2 and "sweep.overlap[0]" in done.stderr, done.stderr
    config = write_config(tmp_path, overlap_reading="sometimes")
    done = psweep(config, "--out", tmp_path / "out")
    assert done.returncode == 2 and "overlap_reading: expected one of" in done.stderr


def test_a_run_started_on_a_busier_machine_says_by_how_much(tmp_path):
    # The program's first run leaves 8 spinning processes behind for 2 s, so the second starts
    # with them running: psweep waits quiet_wait_s (0.2 s here), times it anyway, and its row's
    # busy_tasks says so (make grade excludes such a run from its points). 8, not 1: other work
    # on a shared machine moves the count of running tasks by a few.
    marker = tmp_path / "spun"
    busy = script(tmp_path, "busy", f"""
if [ ! -e {marker} ]; then
  touch {marker}
  for i in 1 2 3 4 5 6 7 8; do setsid timeout 2 sh -c 'while :; do :; done' >/dev/null 2>&1 & done
fi
exec {PLAIN}
""")
    out = tmp_path / "out"
    config = programs_config(tmp_path, {"busy": {"command": [str(busy)], "input": "stdin"}},
                             ["brute", "busy"], warmup=0, quiet_wait_s=0.2)
    done = psweep(config, "--out", out, "--unconfined")
    assert done.returncode == 0, done.stderr
    _, runs = read_csv(out / "runs.csv")
    rows = by_engine(runs)
    assert [r["busy_tasks"] for r in rows["brute"]] == ["", ""]  # psweep waits for programs only
    first, second = rows["busy"]
    assert int(second["busy_tasks"]) > 0 and int(second["busy_tasks"]) > int(first["busy_tasks"])
    assert "other tasks running" in done.stderr and "timed anyway" in done.stderr
