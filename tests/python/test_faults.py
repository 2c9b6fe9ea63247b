"""Faults and what survives them (docs/faults.md), end to end with the real psim and psweep: kill -9
of psweep at seeded random moments then --resume (and the temporaries such a kill leaves), kill -9
of a child, a full disk, two psweeps on
one folder, merge into a folder that holds results, a sweep into a used folder, psim writing to a
character device, a FIFO, a link, /dev/stdout and its own input, SIGINT twice (psim) and a second
signal while psweep stops, and the bounds on
the command line and config. Each case asserts what is on disk afterwards.

`make test` runs it with FAULT_KILLS=3 kills; `make test-faults` with more (FAULT_KILLS=12).
Cases that need root (mknod, mount) are skipped without it; none touches the real /dev/null.
"""
import json
import os
import random
import re
import signal
import stat
import subprocess
import threading
import time
from pathlib import Path

import pytest

from build_path import BUILD
from test_harness_psweep import PSIM, PSWEEP, ROOT, psweep, read_csv, write_config

SCENE = ROOT / "scenes" / "cradle.in"
KILLS = int(os.environ.get("FAULT_KILLS", "3"))
ROOT_USER = os.geteuid() == 0


@pytest.fixture(scope="module", autouse=True)
def binaries():
    for exe in (PSWEEP, PSIM):
        assert exe.is_file(), f"{exe} is missing: build first (make build) or set PARTICLE_LAB_BUILD"


def psim(*args, timeout=60, **kw):
    return subprocess.run([str(PSIM), *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, **kw)


def leftovers(folder):
    """Temporaries a writer left behind."""
    return sorted(p.name for p in Path(folder).rglob("*") if ".tmp" in p.name)


def slow_config(tmp_path, name="slow", reps=2):
    """8 configurations of about 0.1-0.2 s per run: time enough to hit a run mid-way."""
    return write_config(tmp_path, name=name,
                        base={"engine": "brute", "N": 600, "L": 20000, "r": 1, "S": 1500, "T": 1},
                        sweep={"N": [500, 600, 700, 800], "T": [1, 2]}, repetitions=reps, warmup=0)


def start_psweep(*args):
    return subprocess.Popen([str(PSWEEP), *map(str, args)], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def psim_children(out):
    """PIDs of the psim processes writing their metrics into `out`."""
    pids = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            argv = (entry / "cmdline").read_bytes().split(b"\0")
            state = (entry / "stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if argv and argv[0].endswith(b"psim") and str(out).encode() in b" ".join(argv) and state != "Z":
            pids.append(int(entry.name))
    return pids


def sigint_pending(pid):
    status = Path(f"/proc/{pid}/status").read_text()
    pending = (int(m, 16) for m in re.findall(r"^(?:ShdPnd|SigPnd):\s*([0-9a-f]+)$", status, re.M))
    return any(p & 1 << (signal.SIGINT - 1) for p in pending)


def wait_for(predicate, timeout=30):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.01)
    return False


def run_keys(out):
    """(config_id, rep) -> state_hash of every row, asserting none is there twice. A runs.csv
    caught between its creation and its header (a test polling a running sweep) has no rows."""
    if not (out / "runs.csv").read_text():
        return {}
    _, rows = read_csv(out / "runs.csv")
    keys = [(r["config_id"], r["rep"]) for r in rows]
    assert len(keys) == len(set(keys)), "a repetition recorded twice"
    return {(r["config_id"], r["rep"]): (r["status"], r["state_hash"]) for r in rows}


# --- psim's output files ---------------------------------------------------------------------

@pytest.mark.skipif(not ROOT_USER, reason="mknod needs root")
def test_psim_writes_into_a_character_device_and_leaves_it_one(tmp_path):
    null = tmp_path / "null"
    os.mknod(null, 0o666 | stat.S_IFCHR, os.makedev(1, 3))  # a /dev/null of its own
    done = psim("--metrics", null, "--state-at", 1, null, SCENE)
    assert done.returncode == 0, done.stderr
    assert stat.S_ISCHR(null.lstat().st_mode) and null.lstat().st_rdev == os.makedev(1, 3)
    assert leftovers(tmp_path) == []


def test_psim_writes_into_a_fifo_and_leaves_it_one(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_text()))
    reader.start()
    done = psim("--metrics", fifo, SCENE)
    reader.join(timeout=30)
    assert done.returncode == 0, done.stderr
    assert json.loads(got[0])["engine"]
    assert stat.S_ISFIFO(fifo.lstat().st_mode)
    assert leftovers(tmp_path) == []


def test_psim_metrics_to_dev_stdout_follow_the_states(tmp_path):
    out = tmp_path / "out.txt"
    with open(out, "w") as f:
        done = subprocess.run([str(PSIM), "--metrics", "/dev/stdout", str(SCENE)], stdout=f,
                              stderr=subprocess.PIPE, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    states, metrics = out.read_text().split("{", 1)
    assert states.startswith("0 ") and json.loads("{" + metrics)["engine"]


def test_psim_follows_a_link_and_keeps_it(tmp_path):
    target = tmp_path / "real.json"
    target.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to("real.json")
    dangling = tmp_path / "dangling.json"
    dangling.symlink_to(tmp_path / "new.json")
    done = psim("--metrics", link, "--state-at", 1, dangling, SCENE)
    assert done.returncode == 0, done.stderr
    assert link.is_symlink() and json.loads(target.read_text())["engine"]
    assert dangling.is_symlink() and (tmp_path / "new.json").read_text().startswith("1 ")
    assert leftovers(tmp_path) == []


def test_psim_check_json_follows_the_same_rule(tmp_path):
    """psim check's --json is one more file the lab writes at a named path: a link's target is
    written and the link kept; a directory or the checked output itself is refused up front."""
    out = tmp_path / "out.txt"
    out.write_text(psim(SCENE).stdout)
    target = tmp_path / "real.json"
    link = tmp_path / "link.json"
    link.symlink_to("real.json")
    done = psim("check", SCENE, out, "--json", link)
    assert done.returncode == 0, done.stderr
    assert link.is_symlink() and json.loads(target.read_text())["verdict"] == "exact"
    assert leftovers(tmp_path) == []
    for bad, message in ((tmp_path, "is a directory"), (out, "name another file")):
        done = psim("check", SCENE, out, "--json", bad)
        assert done.returncode == 2 and message in done.stderr, done.stderr
    assert out.read_text() == psim(SCENE).stdout


def test_a_directory_where_an_input_belongs_is_refused_naming_it(tmp_path):
    """A directory as psim's scene, or as psim check's scene or output: exit 2 and a message
    naming it, never an internal error (the read itself fails: EISDIR) or a verdict on its
    format."""
    out = tmp_path / "out.txt"
    out.write_text(psim(SCENE).stdout)
    for args, message in (([tmp_path], f"psim: {tmp_path}: cannot read: Is a directory"),
                          (["check", tmp_path, out], f"psim check: {tmp_path}: cannot read"),
                          (["check", SCENE, tmp_path],
                           f"psim check: {tmp_path}: is a directory, not a program's output")):
        done = psim(*args)
        assert done.returncode == 2, (args, done.stderr)
        assert done.stderr.startswith(message), (args, done.stderr)
        assert done.stdout == ""


@pytest.mark.parametrize("case", ["input", "stdin", "directory", "other output"])
def test_psim_refuses_its_input_a_directory_or_the_other_output(tmp_path, case):
    scene = tmp_path / "scene.in"
    scene.write_text(SCENE.read_text())
    (tmp_path / "dir").mkdir()
    args, option, stdin = {
        "input": (["--metrics", scene, scene], "--metrics", None),
        "stdin": (["--state-at", 0, scene], "--state-at", scene),
        "directory": (["--metrics", tmp_path / "dir", scene], "--metrics", None),
        "other output": (["--metrics", tmp_path / "m", "--state-at", 0, tmp_path / "link", scene],
                         "--state-at", None),
    }[case]
    if case == "other output":
        (tmp_path / "link").symlink_to("m")
    with open(stdin or os.devnull) as f:
        done = subprocess.run([str(PSIM), *map(str, args)], stdin=f, capture_output=True, text=True,
                              timeout=60)
    assert done.returncode == 2 and done.stderr.startswith(f"psim: {option}: "), done.stderr
    assert done.stdout == ""  # refused before the input was read
    assert scene.read_text() == SCENE.read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["scene.in", "dir"] + (["link"] if case == "other output" else []))


def test_psim_second_sigint_stops_at_once_and_leaves_no_file(tmp_path):
    scene = tmp_path / "big.in"
    # A sub-step of brute takes 0.5 s here (0.04 s at N = 20,000: the stop came before the second).
    scene.write_text("60000\n100000\n1\n100\nperf\n")
    metrics = tmp_path / "m.json"
    states = tmp_path / "states"
    with open(states, "w") as f:
        proc = subprocess.Popen([str(PSIM), "--engine", "brute", "--threads", "1", "--metrics",
                                 metrics, scene], stdout=f, stderr=subprocess.PIPE, text=True)
    assert wait_for(lambda: states.stat().st_size > 0)  # step 0 written: the handlers are in place
    proc.send_signal(signal.SIGINT)
    # Two SIGINTs pending at once are one: the second goes once the first is delivered.
    assert wait_for(lambda: not sigint_pending(proc.pid))
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "a second signal: stopped at once" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.in", "states"]


# --- psweep: the folder ----------------------------------------------------------------------

def test_two_psweeps_on_one_folder_the_second_is_refused(tmp_path):
    out = tmp_path / "out"
    config = slow_config(tmp_path, reps=1)
    first = start_psweep(config, "--out", out)
    assert wait_for(lambda: (out / "runs.csv").exists())
    second = psweep(config, "--out", out)
    _, err = first.communicate(timeout=120)
    assert first.returncode == 0, err
    assert second.returncode == 2
    assert f"in use by another psweep (PID {first.pid}" in second.stderr
    assert "choose another folder" in second.stderr
    assert len(run_keys(out)) == 8 and not (out / "previous").exists()
    # The lock went with the first: a third sweep goes ahead.
    assert psweep(config, "--out", out, "--resume").returncode == 0


def test_a_dead_psweeps_temporaries_go_with_the_next_one(tmp_path):
    """kill -9 between a result file's write and its rename leaves NAME.tmp-PID (the random
    kills above hit that now and then); the next psweep to hold the folder removes those, and
    nothing else that looks alike."""
    out = tmp_path / "out"
    config = write_config(tmp_path, sweep={}, repetitions=1, warmup=0)
    assert psweep(config, "--out", out).returncode == 0
    for name in ("runs.csv", "summary.csv", "meta.json"):
        (out / f"{name}.tmp-999999").write_text("half a file")
    (out / "inputs").mkdir(exist_ok=True)
    (out / "inputs" / "run-1-particles.in.tmp-999999").write_text("half a scene")
    (out / "notes.tmp-999999").write_text("not psweep's")
    done = psweep(config, "--out", out, "--resume")
    assert done.returncode == 0, done.stderr
    assert leftovers(out) == ["notes.tmp-999999"]


def test_every_earlier_sweep_is_kept(tmp_path):
    out = tmp_path / "out"
    config = write_config(tmp_path, sweep={}, repetitions=1, warmup=0)
    texts = []
    for _ in range(3):
        assert psweep(config, "--out", out).returncode == 0
        texts.append((out / "runs.csv").read_text())
    assert (out / "previous" / "runs.csv").read_text() == texts[0]
    assert (out / "previous-2" / "runs.csv").read_text() == texts[1]
    assert (out / "previous-2" / "meta.json").exists() and (out / "previous-2" / "summary.csv").exists()


def test_merge_refuses_a_folder_with_results_unless_replace(tmp_path):
    config = write_config(tmp_path, sweep={"N": [40, 80]}, repetitions=1, warmup=0)
    shards = [tmp_path / f"shard-{i}" for i in (1, 2)]
    for i, shard in enumerate(shards, 1):
        assert psweep(config, "--shard", f"{i}/2", "--out", shard).returncode == 0
    out = tmp_path / "whole"
    assert psweep(config, "--out", out).returncode == 0
    whole = (out / "runs.csv").read_text()
    refused = psweep("merge", out, *shards)
    assert refused.returncode == 2 and "--replace" in refused.stderr
    assert (out / "runs.csv").read_text() == whole and not (out / "previous").exists()
    done = psweep("merge", "--replace", out, *shards)
    assert done.returncode == 0, done.stderr
    assert (out / "previous" / "runs.csv").read_text() == whole
    assert "merged" in json.loads((out / "meta.json").read_text())


# --- psweep: kills ---------------------------------------------------------------------------

def test_kill_9_of_psweep_ends_its_psim(tmp_path):
    out = tmp_path / "out"
    proc = start_psweep(slow_config(tmp_path), "--out", out)
    assert wait_for(lambda: psim_children(out)), "no psim started"
    proc.kill()
    proc.wait(timeout=10)
    assert wait_for(lambda: not psim_children(out), timeout=5), "psim outlived psweep"


def test_kill_9_of_psweep_at_random_moments_then_resume_equals_a_clean_sweep(tmp_path):
    config = slow_config(tmp_path)
    clean = tmp_path / "clean"
    assert psweep(config, "--out", clean, timeout=300).returncode == 0
    out = tmp_path / "out"
    draw = random.Random(2110)
    hits = 0
    for kill in range(KILLS):
        proc = start_psweep(config, "--out", out, *(["--resume"] if kill else []))
        time.sleep(draw.uniform(0.02, 1.0))
        hits += proc.poll() is None
        proc.kill()
        proc.wait(timeout=10)
        assert wait_for(lambda: not psim_children(out), timeout=5), "psim outlived psweep"
    assert hits, "every kill came after the sweep had ended"
    done = psweep(config, "--out", out, "--resume", timeout=300)
    assert done.returncode == 0, done.stderr
    assert run_keys(out) == run_keys(clean)
    assert leftovers(out) == [] and not (out / "tmp").exists()


def test_psweep_a_second_signal_while_stopping_says_so_and_the_resume_finishes(tmp_path):
    """The first signal stops the sweep (the running psim is killed, finished rows kept); a
    second one while it stops says that it is stopping, never a second stop or a broken row.
    --resume then runs only what is missing. SIGINT and SIGTERM, sent back to back: two of one
    kind may merge into one pending signal, two kinds are both delivered (in either order)."""
    out = tmp_path / "out"
    config = slow_config(tmp_path, reps=1)
    proc = start_psweep(config, "--out", out)
    assert wait_for(lambda: len(run_keys(out)) >= 1 if (out / "runs.csv").exists() else False)
    proc.send_signal(signal.SIGINT)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    first = {130: 2, 143: 15}.get(proc.returncode)
    assert first, err
    assert "psweep: stopping already" in err
    assert f"interrupted by signal {first}; finished rows are kept" in err and "--resume" in err
    assert wait_for(lambda: not psim_children(out), timeout=5), "psim outlived psweep"
    kept = run_keys(out)
    assert 1 <= len(kept) < 8 and all(status == "ok" for status, _ in kept.values())
    done = psweep(config, "--out", out, "--resume")
    assert done.returncode == 0, done.stderr
    rows = run_keys(out)
    assert len(rows) == 8 and {k: rows[k] for k in kept} == kept
    assert leftovers(out) == []


def test_kill_9_of_a_child_is_a_crashed_row_and_counts_as_done(tmp_path):
    out = tmp_path / "out"
    config = slow_config(tmp_path, reps=1)
    proc = start_psweep(config, "--out", out)

    def kill_one():
        try:
            os.kill(psim_children(out)[0], signal.SIGKILL)
            return True
        except (IndexError, ProcessLookupError):  # between two runs
            return False
    assert wait_for(kill_one)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    rows = run_keys(out)
    assert len(rows) == 8 and [s for s, _ in rows.values()].count("crashed") == 1
    assert psweep(config, "--out", out, "--resume").returncode == 0
    assert run_keys(out) == rows


@pytest.mark.skipif(not ROOT_USER, reason="mounting a small tmpfs needs root")
def test_a_full_disk_keeps_whole_rows_leaves_no_temporary_and_names_the_resume(tmp_path):
    disk = tmp_path / "disk"
    disk.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(disk)], check=True)
    try:
        out = disk / "out"
        config = slow_config(tmp_path, reps=1)
        proc = start_psweep(config, "--out", out)
        assert wait_for(lambda: (out / "runs.csv").exists()
                        and len((out / "runs.csv").read_text().splitlines()) >= 3)
        # The disk full from here on. Unbuffered: a buffered file keeps the part of a write the
        # disk took only in part, and its close() then fails on it (whether a write lands in part
        # depends on what the sweep has written so far).
        with open(disk / "filler", "wb", buffering=0) as f:
            try:
                while True:
                    f.write(b"\0" * 65536)
            except OSError:
                pass
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 1, err
        assert "No space left on device" in err
        command = err.split("continue with:\n")[1].strip()
        assert command.endswith(f"--out {out} --resume")
        assert leftovers(out) == []
        assert (out / "runs.csv").read_text().endswith("\n")
        (disk / "filler").unlink()
        done = psweep(*command.split()[1:])
        assert done.returncode == 0, done.stderr
        assert [status for status, _ in run_keys(out).values()] == ["ok"] * 8
    finally:
        subprocess.run(["umount", str(disk)], check=True)


# --- bounds ----------------------------------------------------------------------------------

@pytest.mark.parametrize("args, message", [
    (["CONFIG", "--count"], "psweep: --count: only together with --dry-run"),
    (["CONFIG", "--out", ""], 'psweep: --out: expected a folder, got ""'),
    (["CONFIG", "--out", "a", "--out", "b"], "psweep: --out: given 2 times; give it once"),
    (["CONFIG", "--force"], "psweep: --force: only together with --resume"),
    (["CONFIG", "--bogus"], "psweep: not an option or argument here: --bogus"),
    (["merge"], "psweep merge: OUT is missing"),
    (["TMP"], "is a directory, not a config file"),
])
def test_command_line_errors_exit_2_in_the_labs_words(tmp_path, args, message):
    config = write_config(tmp_path, sweep={}, repetitions=1, warmup=0)
    args = [str(config) if a == "CONFIG" else str(tmp_path) if a == "TMP" else a for a in args]
    done = psweep(*args)
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert "required but received" not in done.stderr


def test_psim_command_line_errors_exit_2_in_the_labs_words():
    done = psim("--metrics", "a", "--metrics", "b", SCENE)
    assert done.returncode == 2
    assert done.stderr.startswith("psim: --metrics: given 2 times; give it once"), done.stderr


@pytest.mark.parametrize("text, message", [
    ('{"name": "d", "base": {"engine": "brute", "N": 5, "N": 6, "L": 100, "r": 1, "S": 2}}',
     "base.N: given twice in one object"),
    ('{"name": "d", "timeout_s": 1e10, "base": {"engine": "brute", "N": 5, "L": 100, "r": 1, "S": 2}}',
     "timeout_s: expected at most 604800 (a week)"),
])
def test_config_bounds_exit_2_at_their_key(tmp_path, text, message):
    config = tmp_path / "d.json"
    config.write_text(text)
    done = psweep(config, "--out", tmp_path / "out")
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert not (tmp_path / "out").exists()


def test_resume_refuses_a_config_of_other_configurations_unless_forced(tmp_path):
    out = tmp_path / "out"
    config = write_config(tmp_path, sweep={"N": [40, 80]}, repetitions=1, warmup=0)
    assert psweep(config, "--out", out).returncode == 0
    before = (out / "runs.csv").read_text()
    renamed = write_config(tmp_path, name="tiny", sweep={"N": [40, 80]}, repetitions=1, warmup=0,
                           timeout_s=20)
    assert psweep(renamed, "--out", out, "--resume").returncode == 0  # same configurations
    other = write_config(tmp_path, sweep={"N": [40, 120]}, repetitions=1, warmup=0)
    refused = psweep(other, "--out", out, "--resume")
    assert refused.returncode == 2 and "sweep.N[1]" in refused.stderr and "--force" in refused.stderr
    assert (out / "runs.csv").read_text() == before
    forced = psweep(other, "--out", out, "--resume", "--force")
    assert forced.returncode == 0, forced.stderr
    assert len(run_keys(out)) == 3
