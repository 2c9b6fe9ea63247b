"""GIF of a scene's particles moving (`make animate SCENE=scenes/cradle.in K=1`).

Runs `psim --slow-factor K SCENE` in print mode (a perf-mode scene is fed to psim on stdin with
its mode line switched to print), parses every printed time unit, and draws the disks at their
true radius in the [0, L] box with matplotlib's Pillow writer. Long runs are strided down to
--max-frames frames. Exit status: 0 done, 2 bad input (scene, options, psim rejected it),
1 psim failed otherwise.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from analysis.common import psim as psim_runner
from analysis.common.trajectory import (TrajectoryError, frame_indices, parse_output,
                                        read_scene_header)

ROOT = Path(__file__).resolve().parents[2]


def parse_args(argv):
    parser = argparse.ArgumentParser(
        description="Animate a psim scene as a GIF.",
        epilog="Default output: results/animations/<scene>.gif (<scene>_K<K>.gif for K > 1).")
    parser.add_argument("scene", metavar="SCENE", help="scene file, e.g. scenes/cradle.in")
    parser.add_argument("--slow-factor", type=int, default=1, metavar="K",
                        help="sub-steps per time unit passed to psim (default 1)")
    parser.add_argument("--psim", default=str(ROOT / "build" / "psim"),
                        help="psim executable (default build/psim)")
    parser.add_argument("--engine", help="psim engine (default: psim's own, auto)")
    parser.add_argument("--from-output", metavar="FILE",
                        help="animate this saved print-mode output instead of running psim")
    parser.add_argument("--out", help="GIF path to write")
    parser.add_argument("--fps", type=float, default=None,
                        help="frames per second (default: 20, slower for short runs so the "
                             "GIF lasts about 5 s)")
    parser.add_argument("--max-frames", type=int, default=300,
                        help="stride longer runs down to this many frames (default 300)")
    parser.add_argument("--size", type=float, default=5.0,
                        help="figure side in inches at 100 dpi (default 5)")
    args = parser.parse_args(argv)
    if args.max_frames < 2:
        parser.error("--max-frames must be at least 2")
    if args.fps is not None and args.fps <= 0:
        parser.error("--fps must be positive")
    return args


def auto_fps(frames: int) -> float:
    """20 fps for long runs; a 5-step scene at 20 fps would be over in a quarter second, so
    short runs slow down to last about 5 s (never below 2 fps)."""
    return min(20.0, max(2.0, frames / 5.0))


def default_out(scene: Path, slow_factor: int) -> Path:
    suffix = f"_K{slow_factor}" if slow_factor != 1 else ""
    return ROOT / "results" / "animations" / f"{scene.stem}{suffix}.gif"


def run_psim(args, header) -> str:
    arguments = ["--slow-factor", args.slow_factor]
    if args.engine:
        arguments += ["--engine", args.engine]
    scene = Path(args.scene)
    stdin = None
    if header.mode == "print":
        arguments.append(scene)
    else:
        # Only steps 0 and S would come out of a perf scene: switch line 5 to print.
        lines = [line for line in scene.read_text().splitlines() if line.strip()]
        lines[4] = "print"
        stdin = "\n".join(lines) + "\n"
    done = psim_runner.run(args.psim, arguments, stdin)
    if done.returncode != 0:
        message = done.stderr.strip() or f"exit status {done.returncode}"
        raise PsimFailed(done.returncode, f"psim failed: {message}")
    return done.stdout


class PsimFailed(Exception):
    def __init__(self, status, message):
        super().__init__(message)
        self.status = 2 if status == 2 else 1


def write_gif(trajectory, header, out: Path, title: str, fps: float, max_frames: int,
              size: float = 5.0) -> int:
    """Draw and save; returns the number of frames written."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.collections import EllipseCollection

    frames = frame_indices(len(trajectory.steps), max_frames)
    fig, ax = plt.subplots(figsize=(size, size), dpi=100)
    box = header.box
    ax.set_xlim(0, box)
    ax.set_ylim(0, box)
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.grid(False)
    # One colour per particle so the eye can follow it; viridis is cut before its pale yellow
    # end, which vanishes on white.
    colors = plt.get_cmap("tab10" if trajectory.n <= 10 else "viridis")(
        range(trajectory.n) if trajectory.n <= 10 else
        [0.85 * i / max(1, trajectory.n - 1) for i in range(trajectory.n)])
    # units="xy": widths are in data units, so a disk is drawn at its true radius whatever
    # the figure size.
    disks = EllipseCollection(widths=2 * header.radius, heights=2 * header.radius, angles=0,
                              units="xy", offsets=trajectory.positions[0],
                              offset_transform=ax.transData, facecolors=colors,
                              edgecolors="black", linewidths=0.3)
    ax.add_collection(disks)
    # Disks smaller than about a pixel would vanish (r=1 in L=20000): add a dot per particle
    # so the motion stays visible, and say so in the title.
    fig.tight_layout()
    pixels_per_unit = ax.get_window_extent().width / box
    dots = None
    if 2 * header.radius * pixels_per_unit < 2:
        dots = ax.scatter(*trajectory.positions[0].T, s=6, c=colors, linewidths=0)
        title += "\n(dots mark disks smaller than a pixel)"
    # Lay out with the longest title in place, so no frame's title is clipped.
    label = ax.set_title(f"{title}\nstep {trajectory.steps[-1]} / {trajectory.steps[-1]}")
    fig.tight_layout()

    def draw(k):
        frame = frames[k]
        disks.set_offsets(trajectory.positions[frame])
        if dots is not None:
            dots.set_offsets(trajectory.positions[frame])
        label.set_text(f"{title}\nstep {trajectory.steps[frame]} / {trajectory.steps[-1]}")
        return (disks, label) if dots is None else (disks, dots, label)

    out.parent.mkdir(parents=True, exist_ok=True)
    animation = FuncAnimation(fig, draw, frames=len(frames), blit=False)
    animation.save(str(out), writer=PillowWriter(fps=fps))
    plt.close(fig)
    return len(frames)


def main(argv=None) -> int:
    args = parse_args(argv)
    scene = Path(args.scene)
    try:
        header = read_scene_header(scene, args.psim)
        if args.from_output:
            text = Path(args.from_output).read_text()
        else:
            text = run_psim(args, header)
        trajectory = parse_output(text, header.n)
    except (TrajectoryError, psim_runner.PsimError) as err:
        print(f"animate: error: {err}", file=sys.stderr)
        return 2
    except PsimFailed as err:
        print(f"animate: error: {err}", file=sys.stderr)
        return err.status
    except OSError as err:
        print(f"animate: error: {err.filename}: {err.strerror}", file=sys.stderr)
        return 2
    out = Path(args.out) if args.out else default_out(scene, args.slow_factor)
    title = f"{scene.name}: N={header.n}, K={args.slow_factor}"
    frames = len(frame_indices(len(trajectory.steps), args.max_frames))
    fps = args.fps or auto_fps(frames)
    count = write_gif(trajectory, header, out, title, fps, args.max_frames, args.size)
    print(f"animate: wrote {out} ({count} frames of {len(trajectory.steps)} steps, "
          f"{fps:g} fps)", file=sys.stderr)
    return 0

