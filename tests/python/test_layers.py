"""harness/'s folders keep one direction (docs/architecture.md, "The harness"): config, run,
results, sweep from the bottom up; a file includes its own folder's headers and those below,
never one above."""
import re

from entry_point import ROOT

LAYERS = ["config", "run", "results", "sweep"]


def test_no_harness_file_includes_a_folder_above_its_own():
    upward = []
    for layer in LAYERS:
        for path in sorted((ROOT / "harness" / layer).glob("*.[ch]pp")):
            for included in re.findall(r'#include "(\w+)/', path.read_text()):
                if included in LAYERS and LAYERS.index(included) > LAYERS.index(layer):
                    upward.append(f"{path.relative_to(ROOT)} includes {included}/")
    assert upward == []
