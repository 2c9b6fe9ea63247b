"""psim print-mode parsing and GIF writing on a hand-written 3-particle run (fixtures/
analysis_scene.in: two disks meet head-on between steps 2 and 3, a third drifts up)."""
import subprocess
from pathlib import Path

import numpy as np
import pytest

from build_path import BUILD
from entry_point import run_tool
from analysis.common.trajectory import (TrajectoryError, frame_indices, parse_output,
                                        read_scene_header)


FIXTURES = Path(__file__).parent / "fixtures"
SCENE = FIXTURES / "analysis_scene.in"
OUTPUT = FIXTURES / "analysis_print.txt"
PSIM = BUILD / "psim"


def test_scene_header():
    header = read_scene_header(SCENE, PSIM)
    assert (header.n, header.box, header.radius, header.steps, header.mode) == \
        (3, 10.0, 0.5, 4, "print")


@pytest.mark.parametrize("text", ["3\n10\nwide\n4\nprint\n", "3\n10\n0.5\n4\n", "-3\n10\n1\n4\nperf\n",
                                  "3\n10\n0.5\n4\nshow\n"])
def test_a_bad_header_is_psims_own_message(tmp_path, text):
    """One reader: the animation rejects a header with the words psim uses for a run."""
    bad = tmp_path / "bad.in"
    bad.write_text(text)
    run = subprocess.run([str(PSIM), str(bad)], capture_output=True, text=True, timeout=60)
    assert run.returncode == 2
    with pytest.raises(TrajectoryError) as err:
        read_scene_header(bad, PSIM)
    assert "psim: " + str(err.value) == run.stderr.strip()


def test_parse_print_output():
    t = parse_output(OUTPUT.read_text(), n=3)
    assert list(t.steps) == [0, 1, 2, 3, 4]
    assert t.positions.shape == (5, 3, 2)
    assert t.positions[2, 1].tolist() == [6.0, 5.0]
    assert t.velocities[3, 0].tolist() == [-1.0, 0.0]      # bounced
    assert t.positions[4, 2].tolist() == [5.0, 4.0]
    assert t.collisions.tolist() == [[1, 0], [1, 0], [0, 0]]


def test_perf_output_has_two_frames():
    lines = OUTPUT.read_text().splitlines()
    t = parse_output("\n".join(lines[:3] + lines[-3:]) + "\n")
    assert list(t.steps) == [0, 4] and t.n == 3


@pytest.mark.parametrize("mutate,message", [
    (lambda lines: lines[:-1], "lines per step"),
    (lambda lines: [lines[1], lines[0]] + lines[2:], "particle index"),
    (lambda lines: lines[:4] + ["1 1 x 5 -1 0"] + lines[5:], "6 numbers|step i x y"),
    (lambda lines: [], "printed nothing"),
])
def test_malformed_output_is_rejected(mutate, message):
    text = "\n".join(mutate(OUTPUT.read_text().splitlines())) + "\n"
    with pytest.raises(TrajectoryError, match=message):
        parse_output(text, n=3)


def test_frame_stride_keeps_first_and_last():
    picked = frame_indices(1001, 300)
    assert len(picked) <= 300 and picked[0] == 0 and picked[-1] == 1000
    assert len(set(np.diff(picked[:-1]))) == 1            # uniform time between frames
    assert list(frame_indices(5, 300)) == [0, 1, 2, 3, 4]


def animate(*args):
    return run_tool("animate", *args)


def gif_frames(path):
    from PIL import Image
    with Image.open(path) as image:
        return image.format, image.n_frames


def test_gif_from_saved_output(tmp_path):
    out = tmp_path / "cradle.gif"
    done = animate(SCENE, "--psim", PSIM, "--from-output", OUTPUT, "--out", out, "--size", 2)
    assert done.returncode == 0, done.stderr
    assert out.stat().st_size > 0
    assert gif_frames(out) == ("GIF", 5)


def test_bad_scene_exits_2(tmp_path):
    bad = tmp_path / "bad.in"
    bad.write_text("3\n10\nwide\n4\nprint\n")
    done = animate(bad, "--psim", PSIM, "--from-output", OUTPUT, "--out", tmp_path / "x.gif")
    assert done.returncode == 2 and 'bad.in:3: r: expected a number, got "wide"' in done.stderr
    assert "Traceback" not in done.stderr


@pytest.mark.skipif(not PSIM.exists(), reason="build/psim not built")
def test_gif_through_psim_matches_saved_output(tmp_path):
    done = subprocess.run([str(PSIM), str(SCENE)], capture_output=True, text=True, timeout=60)
    assert done.stdout == OUTPUT.read_text()
    out = tmp_path / "psim.gif"
    done = animate(SCENE, "--psim", PSIM, "--out", out, "--size", 2, "--max-frames", 3)
    assert done.returncode == 0, done.stderr
    assert gif_frames(out) == ("GIF", 3)                  # 5 steps strided to 0, 2, 4
