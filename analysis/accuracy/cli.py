"""Error against run time (`make accuracy`): how much accuracy each discrete engine and slow
factor K buys for its run time, measured against the exact continuous-time engine (psim's
declaration names it: `event`) on the same scene and seed, and against kinetic theory.
accuracy.csv's columns name that reference `_event` whatever the engine's name.

Usage: /usr/bin/python3 -m analysis accuracy RESULTS_DIR [RESULTS_DIR ...] --out DIR [--psim PATH]
    [--trajectory-ks 1,4,16] [--horizon-k 256] [--horizon-steps 200]

Inputs are psweep results folders over the same scenes (configs/accuracy.json and
accuracy_engines.json); writes DIR/accuracy.csv, DIR/trajectory.csv, DIR/frontier_<scene>.png
and DIR/report.md. Everything above the "psim runs" and "drawing" sections is a pure function of
DataFrames (tested on fixture tables in tests/python/test_analysis_accuracy.py).

Definitions (unit mass, N disks of radius r in [0, L]^2 over S time units):
- collision rate nu: pair collisions per particle per time unit, 2 pairs / (N S).
- Enskog with Henderson's contact value: nu = 2 n s g(s) sqrt(pi <v^2> / 2), n = N / L^2,
  s = 2r, eta = N pi r^2 / L^2, g(s) = (1 - 7 eta / 16) / (1 - eta)^2, <v^2> = 2 E / N.
- pressure P = wall_impulse / (4 L S), Z = P L^2 / (N <v^2> / 2); Henderson's equation of state
  Z = (1 + eta^2 / 8) / (1 - eta)^2.
- relative errors per seed, then their mean over seeds with the standard error of that mean.
- trajectory deviation: RMS distance between the same particle's positions in two runs, over L.
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd


from analysis.common import psim as psim_runner
from analysis.common.csv_out import write_csv
from analysis.common.declaration import Declaration
from analysis.common.load import InputError, load_results
from analysis.common.trajectory import TrajectoryError, parse_output

SCENE = ["N", "L", "r", "S", "speed_min", "speed_max"]
SETTING = ["engine", "slow_factor"]  # slow_factor is empty (NaN) without sub-steps
TOLERANCE = 0.01  # "within 1% of the exact collision rate"
CHAOS_THRESHOLD = 0.01  # trajectories have diverged once the RMS deviation exceeds 1% of L


# ---------------------------------------------------------------- kinetic theory

def packing_fraction(n, box, radius):
    return n * math.pi * radius ** 2 / box ** 2


def enskog_rate(n, box, radius, v2):
    """Enskog's collision rate per particle per time unit with Henderson's g(s)."""
    eta = packing_fraction(n, box, radius)
    g = (1 - 7 * eta / 16) / (1 - eta) ** 2
    return 2 * (n / box ** 2) * (2 * radius) * g * np.sqrt(np.pi * v2 / 2)


def henderson_z(eta):
    return (1 + eta ** 2 / 8) / (1 - eta) ** 2


# ---------------------------------------------------------------- per run and per seed

def in_scene_order(frame: pd.DataFrame, then: list[str] | None = None) -> pd.DataFrame:
    """Scenes by their parameters' values (r = 80 before r = 160, which their labels' text
    would swap): the one order of every table, plot and section of the report."""
    return frame.sort_values(SCENE + (then or []), na_position="last", kind="stable",
                             ignore_index=True)


def scene_label(row) -> str:
    eta = packing_fraction(row["N"], row["L"], row["r"])
    return f"N={row['N']:g} L={row['L']:g} r={row['r']:g} S={row['S']:g} (eta={eta:.3g})"


def per_seed(runs: pd.DataFrame) -> pd.DataFrame:
    """One row per setting, scene and seed: the minimum wall time over repetitions and the
    physics of the run (repetitions of one configuration compute the same state)."""
    ok = runs[runs["status"] == "ok"].copy()
    if ok.empty:
        raise InputError("no successful run in the results")
    keys = SETTING + SCENE + ["seed"]
    # The physics metrics are newer than some results folders (and than load.py's column list).
    for column in ["wall_impulse", "max_overlap"]:
        ok[column] = pd.to_numeric(ok[column], errors="coerce") if column in ok.columns else np.nan
    agg = ok.groupby(keys, dropna=False).agg(
        wall_s_min=("wall_s", "min"), pair_collisions=("pair_collisions", "first"),
        energy_initial=("energy_initial", "first"), energy_final=("energy_final", "first"),
        dropped=("dropped", "first"), wall_impulse=("wall_impulse", "first"),
        max_overlap=("max_overlap", "first")).reset_index()
    v2 = 2 * agg["energy_initial"] / agg["N"]
    agg["rate"] = 2 * agg["pair_collisions"] / (agg["N"] * agg["S"])
    agg["rate_enskog"] = enskog_rate(agg["N"], agg["L"], agg["r"], v2)
    pressure = agg["wall_impulse"] / (4 * agg["L"] * agg["S"])
    agg["z"] = pressure * agg["L"] ** 2 / (agg["N"] * v2 / 2)
    agg["z_henderson"] = henderson_z(packing_fraction(agg["N"], agg["L"], agg["r"]))
    agg["energy_drift"] = agg["energy_final"] / agg["energy_initial"] - 1
    agg["dropped_per_collision"] = agg["dropped"] / agg["pair_collisions"].where(
        agg["pair_collisions"] > 0)
    return agg


def exact_engine(declaration: Declaration) -> str:
    """The engine the error is measured against: the declared exact continuous-time one."""
    name = declaration.continuous_exact
    if name is None:
        raise InputError("meta.json declares no exact continuous-time engine (results of an "
                         "older psweep?): nothing to measure the error against")
    return name


def with_reference(seeds: pd.DataFrame, exact_name: str) -> pd.DataFrame:
    """Adds each seed's relative errors against the run of the exact engine `exact_name` on the
    same scene and seed and against theory."""
    exact = seeds[seeds["engine"] == exact_name][SCENE + ["seed", "rate", "z"]]
    if exact.empty:
        raise InputError(f"no successful {exact_name} run: nothing to measure the error against")
    merged = seeds.merge(exact, on=SCENE + ["seed"], how="left", suffixes=("", "_event"))
    merged["rate_err_event"] = merged["rate"] / merged["rate_event"] - 1
    merged["rate_err_enskog"] = merged["rate"] / merged["rate_enskog"] - 1
    merged["z_err_event"] = merged["z"] / merged["z_event"] - 1
    merged["z_err_henderson"] = merged["z"] / merged["z_henderson"] - 1
    return merged


def mean_and_error(values: pd.Series) -> tuple[float, float]:
    """Mean over seeds and its standard error (NaN from fewer than two seeds)."""
    v = values.dropna()
    if v.empty:
        return math.nan, math.nan
    error = v.std(ddof=1) / math.sqrt(len(v)) if len(v) > 1 else math.nan
    return float(v.mean()), float(error)


ERRORS = ["rate_err_event", "rate_err_enskog", "z_err_event", "z_err_henderson"]


def accuracy_table(seeds: pd.DataFrame) -> pd.DataFrame:
    """One row per setting and scene: the run time (mean over seeds of the per-seed minimum)
    and every error with its uncertainty."""
    rows = []
    for key, group in seeds.groupby(SETTING + SCENE, dropna=False):
        row = dict(zip(SETTING + SCENE, key))
        row["scene"] = scene_label(row)
        row["seeds"] = len(group)
        row["wall_s_min"] = float(group["wall_s_min"].mean())
        row["rate"] = float(group["rate"].mean())
        for column in ERRORS:
            row[column], row[column + "_se"] = mean_and_error(group[column])
        row["energy_drift_max"] = float(group["energy_drift"].abs().max())
        row["max_overlap"] = float(group["max_overlap"].max())
        row["dropped_per_collision"] = float(group["dropped_per_collision"].mean())
        rows.append(row)
    return in_scene_order(pd.DataFrame(rows), ["engine", "slow_factor"])


def cheapest_within(table: pd.DataFrame, exact_name: str,
                    tolerance: float = TOLERANCE) -> pd.DataFrame:
    """Per scene: the fastest discrete setting whose mean collision rate is within `tolerance`
    of the exact engine's, and that engine's own time (exact can be cheaper than fine steps)."""
    rows = []
    for scene, group in table.groupby("scene", sort=False):
        exact = group[group["engine"] == exact_name]
        close = group[(group["engine"] != exact_name) &
                      (group["rate_err_event"].abs() <= tolerance)]
        row = {"scene": scene, "event_wall_s": float(exact["wall_s_min"].min())
               if not exact.empty else math.nan}
        if close.empty:
            row.update(engine="", slow_factor=math.nan, wall_s_min=math.nan,
                       rate_err_event=math.nan)
        else:
            best = close.loc[close["wall_s_min"].idxmin()]
            row.update(engine=best["engine"], slow_factor=best["slow_factor"],
                       wall_s_min=best["wall_s_min"], rate_err_event=best["rate_err_event"])
        rows.append(row)
    return pd.DataFrame(rows)


# ---------------------------------------------------------------- trajectories

def rms_deviation(a: np.ndarray, b: np.ndarray, box: float) -> float:
    """RMS distance between the same particles' positions (arrays (N, 2)), over L."""
    return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))) / box)


def deviation_series(steps: np.ndarray, a: np.ndarray, b: np.ndarray, box: float) -> pd.DataFrame:
    """RMS deviation at every printed time unit of two print-mode trajectories (frames, N, 2)."""
    return pd.DataFrame({"t": steps, "deviation": [rms_deviation(a[k], b[k], box)
                                                    for k in range(len(steps))]})


def chaos_horizon(series: pd.DataFrame, threshold: float = CHAOS_THRESHOLD) -> float:
    """First time unit at which the deviation exceeds the threshold; NaN if it never does."""
    over = series[series["deviation"] > threshold]
    return float(over["t"].iloc[0]) if not over.empty else math.nan


# ---------------------------------------------------------------- report

def fmt_k(k) -> str:
    return "exact" if pd.isna(k) else f"K={int(k)}"


def pct(value, error=math.nan) -> str:
    if pd.isna(value):
        return "n/a"
    text = f"{100 * value:+.2f}%"
    return text + (f" ± {100 * error:.2f}%" if not pd.isna(error) else "")


def seconds(value) -> str:
    return "n/a" if pd.isna(value) else f"{value:.3g} s"


def report_markdown(table: pd.DataFrame, cheapest: pd.DataFrame, trajectory: pd.DataFrame,
                    horizons: pd.DataFrame, exact_name: str) -> str:
    lines = ["# Accuracy: error against run time", "",
             "Errors are relative, mean over seeds ± standard error; run times are the minimum "
             "over repetitions (one core), averaged over seeds.", "",
             f"## Cheapest setting within {100 * TOLERANCE:g}% of the exact collision rate", "",
             f"| scene | cheapest discrete setting | its run time | its rate error | {exact_name}'s "
             "run time |",
             "|---|---|---|---|---|"]
    for _, row in cheapest.iterrows():
        setting = (f"{row['engine']} {fmt_k(row['slow_factor'])}" if row["engine"]
                   else "none within tolerance")
        lines.append(f"| {row['scene']} | {setting} | {seconds(row['wall_s_min'])} | "
                     f"{pct(row['rate_err_event'])} | {seconds(row['event_wall_s'])} |")
    lines += ["", "## Every setting", "",
              f"| scene | engine | K | run time | rate vs {exact_name} | rate vs Enskog | "
              f"Z vs {exact_name} | "
              "Z vs Henderson | dropped / collision | max |energy drift| |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for _, row in table.iterrows():
        lines.append(
            f"| {row['scene']} | {row['engine']} | {fmt_k(row['slow_factor'])} | "
            f"{seconds(row['wall_s_min'])} | {pct(row['rate_err_event'], row['rate_err_event_se'])} | "
            f"{pct(row['rate_err_enskog'], row['rate_err_enskog_se'])} | "
            f"{pct(row['z_err_event'], row['z_err_event_se'])} | "
            f"{pct(row['z_err_henderson'], row['z_err_henderson_se'])} | "
            f"{row['dropped_per_collision']:.3g} | {row['energy_drift_max']:.2g} |")
    if not trajectory.empty:
        lines += ["", f"## Trajectory deviation from {exact_name}", "",
                  "RMS position difference over L after the given time, first seed.", "",
                  "| scene | K | at t | deviation |", "|---|---|---|---|"]
        for _, row in trajectory.iterrows():
            lines.append(f"| {row['scene']} | {fmt_k(row['slow_factor'])} | {row['t']:g} | "
                         f"{row['deviation']:.3g} |")
    if not horizons.empty:
        lines += ["", "## Chaos horizon", "",
                  f"First time unit at which the finest discrete setting's RMS deviation from "
                  f"{exact_name} exceeds {100 * CHAOS_THRESHOLD:g}% of L: beyond it single trajectories "
                  f"are incomparable and only statistics (rates, pressure) can be compared.", "",
                  "| scene | K | horizon (time units) |", "|---|---|---|"]
        for _, row in horizons.iterrows():
            h = "beyond the run" if pd.isna(row["horizon"]) else f"{row['horizon']:g}"
            lines.append(f"| {row['scene']} | {fmt_k(row['slow_factor'])} | {h} |")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------- psim runs (I/O)

def psim_positions(psim: str, row, seed: str, engine: str | None, k: int | None, steps: int,
                   mode: str):
    """Runs psim on the scene of `row` and returns its parsed trajectory; engine None: psim's
    default (the cheapest exact discrete engine for the scene)."""
    header = f"{int(row['N'])}\n{row['L']:g}\n{row['r']:g}\n{steps}\n{mode}\n"
    arguments = [*(["--engine", engine] if engine else []), "--seed", seed, "--threads", 1]
    if k is not None:
        arguments += ["--slow-factor", k]
    if not pd.isna(row["speed_min"]):
        arguments += ["--speed", f"{row['speed_min']:g},{row['speed_max']:g}"]
    done = psim_runner.run(psim, arguments, header)
    if done.returncode != 0:
        raise InputError(f"{' '.join(done.command)} failed: {done.stderr.strip()}")
    return parse_output(done.stdout, int(row["N"]))


def measure_trajectories(psim: str, seeds: pd.DataFrame, exact_name: str, ks: list[int],
                         horizon_k: int, horizon_steps: int
                         ) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """Per scene (first seed): deviation of psim's default engine at each K from the exact
    engine after one time unit, and its deviation at horizon_k over time with its chaos
    horizon. Every exact discrete engine computes the same state, so the default stands for
    all."""
    points, series_rows, horizons = [], [], []
    first_seeds = in_scene_order(
        seeds[seeds["engine"] == exact_name].groupby(SCENE, dropna=False).head(1))
    for _, row in first_seeds.iterrows():
        scene = scene_label(row)
        exact = psim_positions(psim, row, row["seed"], exact_name, None, 1, "perf")
        for k in ks:
            discrete = psim_positions(psim, row, row["seed"], None, k, 1, "perf")
            points.append({"scene": scene, "slow_factor": k, "t": 1,
                           "deviation": rms_deviation(exact.positions[-1], discrete.positions[-1],
                                                      row["L"])})
        exact = psim_positions(psim, row, row["seed"], exact_name, None, horizon_steps, "print")
        fine = psim_positions(psim, row, row["seed"], None, horizon_k, horizon_steps, "print")
        series = deviation_series(exact.steps, exact.positions, fine.positions, row["L"])
        series["scene"] = scene
        series_rows.append(series)
        horizons.append({"scene": scene, "slow_factor": horizon_k,
                         "horizon": chaos_horizon(series)})
    return (pd.DataFrame(points), pd.concat(series_rows, ignore_index=True),
            pd.DataFrame(horizons))


# ---------------------------------------------------------------- drawing

def plot_frontier(table: pd.DataFrame, scene: str, stem: Path, exact_name: str) -> Path:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from analysis.common.figures import MARKERS, save

    panels = [("rate_err_event", f"collision rate error vs {exact_name}"),
              ("rate_err_enskog", "collision rate error vs Enskog"),
              ("z_err_event", f"pressure (Z) error vs {exact_name}")]
    group = table[table["scene"] == scene]
    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 4.2))
    for ax, (column, title) in zip(axes, panels):
        for k, (engine, rows) in enumerate(group.groupby("engine")):
            if engine == exact_name and column.endswith("_event"):
                # The reference itself has no error: its run time is the line to beat.
                ax.axvline(rows["wall_s_min"].min(), color="black", linestyle=":",
                           label=f"{exact_name} (exact) run time")
                continue
            rows = rows.sort_values("wall_s_min")
            y = rows[column].abs()
            if y.isna().all():
                continue
            ax.plot(rows["wall_s_min"], y.clip(lower=1e-5), marker=MARKERS[k % len(MARKERS)],
                    label=engine)
            for _, r in rows.iterrows():
                if not pd.isna(r[column]):
                    ax.annotate(fmt_k(r["slow_factor"]), (r["wall_s_min"], max(abs(r[column]), 1e-5)),
                                fontsize=7, textcoords="offset points", xytext=(3, 3))
        if not [line for line in ax.lines if line.get_linestyle() != ":"]:
            ax.text(0.5, 0.5, f"no data ({column} needs wall_impulse in the runs)"
                    if column.startswith("z") else "no data", ha="center", va="center",
                    transform=ax.transAxes, fontsize=8)
        ax.axhline(TOLERANCE, color="grey", linestyle="--", linewidth=0.8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("run time (s, one core)")
        ax.set_ylabel(f"|{column}| (relative)")
        ax.set_title(title)
        if ax.get_legend_handles_labels()[0]:
            ax.legend()
    fig.suptitle(scene + ": error against run time (dashed: 1%)")
    return save(fig, stem)


# ---------------------------------------------------------------- command line

def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("results", nargs="+", help="psweep results folders")
    parser.add_argument("--out", required=True, help="output folder")
    parser.add_argument("--psim", default="build/psim", help="psim for the trajectory runs")
    parser.add_argument("--trajectory-ks", default="1,4,16,64,256")
    parser.add_argument("--horizon-k", type=int, default=256)
    parser.add_argument("--horizon-steps", type=int, default=200)
    parser.add_argument("--no-trajectories", action="store_true")
    args = parser.parse_args(argv)
    out = Path(args.out)
    try:
        results = [load_results(d) for d in args.results]
        runs = pd.concat([r.runs for r in results], ignore_index=True)
        exact_name = exact_engine(results[0].declaration)
        seeds = with_reference(per_seed(runs), exact_name)
        table = accuracy_table(seeds)
        cheapest = cheapest_within(table, exact_name)
        out.mkdir(parents=True, exist_ok=True)
        trajectory = horizons = pd.DataFrame()
        if not args.no_trajectories:
            ks = [int(k) for k in args.trajectory_ks.split(",")]
            trajectory, series, horizons = measure_trajectories(
                args.psim, seeds, exact_name, ks, args.horizon_k, args.horizon_steps)
            write_csv(series, out / "trajectory.csv")
    except (InputError, TrajectoryError, psim_runner.PsimError) as err:
        print(f"accuracy: {err}", file=sys.stderr)
        return 2
    write_csv(table, out / "accuracy.csv")
    for k, scene in enumerate(table["scene"].unique()):
        plot_frontier(table, scene, out / f"frontier_{k}", exact_name)
    (out / "report.md").write_text(report_markdown(table, cheapest, trajectory, horizons,
                                                   exact_name))
    print(f"accuracy: {len(table)} settings; {out / 'report.md'}")
    return 0

