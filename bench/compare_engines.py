#!/usr/bin/python3
"""Side-by-side end-to-end comparison of the engines on the issue's four target scenes.

Runs build/psim (header-only inputs: random scenes from the seed) round-robin, so drift on a
shared machine hits every configuration alike, keeps the minimum wall_s (the simulation loop) of
REPS runs and the largest peak RSS (/usr/bin/time), checks that every engine ends in brute's
state hash where brute ran, and prints one table per scene with the speed-up against the
scene's reference and the issue's target. `make million` runs the million-particle scene.

    bench/compare_engines.py [--build build] [--reps 3] [--scenes default,sec8,crowd,million]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

# name: (N, L, r, S, slow factor, speed range or None, runs [(engine, T, G)], reference run,
#        target (engine run, factor) or None)
SCENES = {
    "default": dict(header=(1000, 20000, 1, 1000), K=1, speed=None,
                    runs=[("brute", 1, 8), ("brute", 2, 8), ("sweep", 1, 8), ("sweep", 2, 8),
                          ("auto", 2, 8)],
                    reference=("brute", 1, 8), target=(("auto", 2, 8), 4.0)),
    "sec8": dict(header=(2000, 20000, 1, 1000), K=4, speed=None,
                 runs=[("brute", 2, 8), ("auto", 2, 8)] + [("grid", 2, g) for g in (1, 2, 4, 8, 16, 32, 64)],
                 reference=("brute", 2, 8), target=(("auto", 2, 8), 5.0)),
    "crowd": dict(header=(20000, 2000, 1, 10), K=1, speed="0.5,1",
                  runs=[("brute", 2, 8), ("cells", 2, 8), ("cells", 1, 8), ("auto", 2, 8)],
                  reference=("brute", 2, 8), target=(("cells", 2, 8), 50.0)),
    "million": dict(header=(1000000, 4000, 1, 20), K=1, speed="0.05,0.2",
                    runs=[("cells", 2, 8), ("auto", 2, 8), ("cells", 1, 8)],
                    reference=None, target=None),
}


def run_once(build, scene, engine, threads, grid):
    n, L, r, S = scene["header"]
    with tempfile.TemporaryDirectory() as tmp:
        metrics = os.path.join(tmp, "m.json")
        cmd = ["/usr/bin/time", "-f", "%M", os.path.join(build, "psim"), "--engine", engine,
               "--threads", str(threads), "--grid", str(grid), "--slow-factor", str(scene["K"]),
               "--metrics", metrics]
        if scene["speed"]:
            cmd += ["--speed", scene["speed"]]
        text = f"{n}\n{L}\n{r}\n{S}\nperf\n"
        done = subprocess.run(cmd, input=text, capture_output=True, text=True, check=True)
        with open(metrics) as f:
            m = json.load(f)
        m["max_rss_kb"] = int(done.stderr.strip().splitlines()[-1])
        return m


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--scenes", default=",".join(SCENES))
    args = ap.parse_args()
    ok = True
    for name in args.scenes.split(","):
        scene = SCENES[name]
        best, peak_kb = {}, {}
        for _ in range(args.reps):
            for key in scene["runs"]:
                m = run_once(args.build, scene, *key)
                if key not in best or m["wall_s"] < best[key]["wall_s"]:
                    best[key] = m
                peak_kb[key] = max(peak_kb.get(key, 0), m["max_rss_kb"])
        n, L, r, S = scene["header"]
        print(f"\n## {name}: N={n} L={L} r={r} S={S} K={scene['K']}"
              + (f" speed={scene['speed']}" if scene["speed"] else "") + f", min of {args.reps}")
        ref = best.get(scene["reference"]) if scene["reference"] else None
        brute_hash = next((m["state_hash"] for k, m in best.items() if k[0] == "brute"), None)
        print(f"{'engine':<8}{'T':>3}{'G':>4} {'ran':<12}{'wall_s':>9}{'ns/p-step':>10}"
              f"{'speed-up':>9}{'pair_tests':>14}{'rss_MB':>8}  hash")
        for key in scene["runs"]:
            m = best[key]
            engine, threads, grid = key
            per = m["wall_s"] / (n * S * scene["K"]) * 1e9
            up = f"{ref['wall_s'] / m['wall_s']:8.1f}x" if ref else f"{'':>9}"
            same = "" if brute_hash is None else ("=brute" if m["state_hash"] == brute_hash else "DIFFERS")
            ok &= same != "DIFFERS"
            g = str(grid) if engine == "grid" else "-"
            print(f"{engine:<8}{threads:>3}{g:>4} {m['engine']:<12}{m['wall_s']:>9.4f}{per:>10.1f}"
                  f"{up}{m['counters']['pair_tests']:>14}{peak_kb[key] / 1024:>8.0f}  {same}")
        if scene["target"] and ref:
            key, factor = scene["target"]
            got = ref["wall_s"] / best[key]["wall_s"]
            print(f"target: {key[0]} T={key[1]} >= {factor}x faster than {scene['reference'][0]} "
                  f"T={scene['reference'][1]}: {got:.1f}x {'met' if got >= factor else 'NOT met'}")
        if name == "million":
            # The issue measured 79-90 ns on this shared 2-core VM before the work on the loop.
            m = best[("auto", 2, 8)]
            per = m["wall_s"] / (n * S) * 1e9
            peak = peak_kb[("auto", 2, 8)] / 1024
            print(f"target: auto T=2 at half of the issue's 79 ns per particle-step (<= 40): "
                  f"{per:.1f} {'met' if per <= 40 else 'NOT met'}; peak RSS <= 200 MB: "
                  f"{peak:.0f} MB {'met' if peak <= 200 else 'NOT met'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
