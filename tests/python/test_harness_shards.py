"""psweep --shard, psweep merge, --dry-run --count and the max_runs guard, end to end with the real
psim: two shards merged equal the whole sweep run at once (the same runs and state hashes), a shard
resumes like a sweep, and the refusals exit 2. (make test-slurm does the same through Slurm.)
"""
import json

from test_harness_psweep import ROOT, psweep, read_csv, write_config


def sweep_config(tmp_path, **overrides):
    return write_config(tmp_path, sweep={"engine": ["brute", "sweep"], "N": [20, 40, 80], "T": [1, 2]},
                        warmup=0, **overrides)


def runs_key(directory):
    _, rows = read_csv(directory / "runs.csv")
    return sorted((r["config_id"], r["rep"], r["status"], r["state_hash"]) for r in rows)


def test_two_shards_merged_equal_the_whole_sweep(tmp_path):
    config = sweep_config(tmp_path)
    assert psweep(config, "--out", tmp_path / "whole").returncode == 0
    shards = []
    for i in (1, 2):
        shards.append(tmp_path / f"shard-{i}")
        done = psweep(config, "--shard", f"{i}/2", "--out", shards[-1])
        assert done.returncode == 0, done.stderr
        meta = json.loads((shards[-1] / "meta.json").read_text())
        assert meta["shard"]["index"] == i and meta["shard"]["count"] == 2
        assert meta["machine"]["hostname"] and "slurm" in meta
    _, one = read_csv(shards[0] / "runs.csv")
    _, two = read_csv(shards[1] / "runs.csv")
    assert one and two and not {r["config_id"] for r in one} & {r["config_id"] for r in two}

    done = psweep("merge", tmp_path / "merged", *shards)
    assert done.returncode == 0, done.stderr
    assert runs_key(tmp_path / "merged") == runs_key(tmp_path / "whole")
    _, summary = read_csv(tmp_path / "merged" / "summary.csv")
    _, whole_summary = read_csv(tmp_path / "whole" / "summary.csv")
    assert [s["config_id"] for s in summary] == [s["config_id"] for s in whole_summary]
    meta = json.loads((tmp_path / "merged" / "meta.json").read_text())
    assert [s["shard"] for s in meta["merged"]["shards"]] == ["1/2", "2/2"]
    assert meta["merged"]["missing_runs"] == 0 and "shard" not in meta

    # Shard 2 given twice and shard 1 lost a run: reported, written anyway, exit 1.
    lines = (shards[0] / "runs.csv").read_text().splitlines(keepends=True)
    (shards[0] / "runs.csv").write_text("".join(lines[:-1]))
    done = psweep("merge", "--replace", tmp_path / "merged", *shards, shards[1])
    assert done.returncode == 1
    assert "shard 1/2 owes 1 runs" in done.stderr and f"--shard 1/2 --out {shards[0]} --resume" in done.stderr
    assert "appear more than once" in done.stderr
    # ... and the command it names completes the shard.
    done = psweep(config, "--shard", "1/2", "--out", shards[0], "--resume")
    assert done.returncode == 0, done.stderr
    assert psweep("merge", "--replace", tmp_path / "merged", *shards).returncode == 0
    assert runs_key(tmp_path / "merged") == runs_key(tmp_path / "whole")


def test_merge_and_shard_refusals(tmp_path):
    config = sweep_config(tmp_path)
    assert psweep(config, "--shard", "1/2", "--out", tmp_path / "a").returncode == 0
    other = sweep_config(tmp_path, name="other", repetitions=1)
    assert psweep(other, "--shard", "2/2", "--out", tmp_path / "b").returncode == 0
    done = psweep("merge", tmp_path / "m", tmp_path / "a", tmp_path / "b")
    assert done.returncode == 2 and "ran different configs" in done.stderr
    assert psweep(config, "--out", tmp_path / "whole").returncode == 0
    done = psweep("merge", tmp_path / "m", tmp_path / "a", tmp_path / "whole")
    assert done.returncode == 2 and "names no shard" in done.stderr
    done = psweep(config, "--shard", "2/2", "--out", tmp_path / "a", "--resume")
    assert done.returncode == 2 and "holds shard 1/2, not shard 2/2" in done.stderr
    done = psweep(config, "--shard", "3/2")
    assert done.returncode == 2 and "I must be between 1 and N" in done.stderr


def test_count_and_the_max_runs_guard(tmp_path):
    config = sweep_config(tmp_path, max_runs=10)
    done = psweep(config, "--dry-run", "--count")
    assert done.returncode == 0, done.stderr
    table = {line.split()[0]: line.split()[1:3] for line in done.stdout.splitlines()[1:4]}
    assert table == {"brute": ["6", "12"], "sweep": ["6", "12"], "total": ["12", "24"]}
    assert done.stdout.splitlines()[-1] == "largest T: 2"

    out = tmp_path / "out"
    done = psweep(config, "--out", out)
    assert done.returncode == 2 and not out.exists()
    assert "has 24 runs (12 configurations x 2 repetitions), more than max_runs = 10" in done.stderr
    assert "--yes" in done.stderr
    # A shard counts its own runs: 12 of them is still above 10; --yes goes ahead.
    assert psweep(config, "--shard", "1/2", "--out", out).returncode == 2
    done = psweep(config, "--shard", "1/2", "--out", out, "--yes")
    assert done.returncode == 0, done.stderr
    assert len(read_csv(out / "runs.csv")[1]) == 12


def estimates(stdout):
    """The --count table's estimate per engine, in seconds ("0.4 s", "51 s", "3 min")."""
    unit = {"s": 1, "min": 60, "h": 3600, "days": 86400}
    rows = [line.split() for line in stdout.splitlines()[1:] if line.split()[0] != "total"]
    return {row[0]: float(row[-2]) * unit[row[-1]] for row in rows if row[-1] in unit}


def test_count_ranks_the_engines_as_the_quick_sweep_ran():
    # Issue 31: the estimate once put auto above brute on make sweep's config, where auto took a
    # third of brute's time (measured figures in docs/sweeps.md, "The cost model").
    done = psweep(ROOT / "configs" / "quick.json", "--dry-run", "--count")
    assert done.returncode == 0, done.stderr
    seconds = estimates(done.stdout)
    assert set(seconds) == {"auto", "bands", "brute", "sweep"}, done.stdout
    assert 2 * seconds["auto"] < seconds["brute"] < 8 * seconds["auto"], done.stdout
    assert 2 * seconds["sweep"] < seconds["brute"], done.stdout


def test_a_product_of_a_trillion_is_refused_before_it_is_walked(tmp_path):
    # Six axes of 100 values: 10^12 configurations, counted without the walk (which would take
    # hours) and refused by max_runs at once; the timeout turns a walk into a failure.
    axis = list(range(1, 101))
    config = write_config(tmp_path, name="huge",
                          sweep={"N": axis, "S": axis, "seed": axis, "T": axis, "L": [2000 + k for k in axis],
                                 "r": [1 + k / 1000 for k in axis]})
    done = psweep(config, "--out", tmp_path / "out", timeout=30)
    assert done.returncode == 2 and not (tmp_path / "out").exists()
    assert "has 2000000000000 runs (1000000000000 configurations x 2 repetitions), more than " \
           "max_runs = 100000" in done.stderr, done.stderr


def test_repeated_values_are_stepped_over(tmp_path):
    # Six axes of 100 values, two of them distinct: 10^12 combinations, 64 configurations. The
    # walk steps only over first occurrences; the timeout turns a walk of every combination
    # (hours) into a failure.
    def axis(a, b):
        return [a] * 99 + [b]
    config = write_config(tmp_path, name="repeated",
                          sweep={"N": axis(40, 80), "S": axis(10, 20), "seed": axis(1, 2), "T": axis(1, 2),
                                 "L": axis(2000, 3000), "r": axis(1, 2)})
    done = psweep(config, "--dry-run", "--count", timeout=30)
    assert done.returncode == 0, done.stderr
    assert "64 configurations x 2 repetitions = 128 runs" in done.stdout, done.stdout

