"""harness/'s folders keep one direction (docs/architecture.md, "The harness"): config, run,
results, sweep from the bottom up; a file includes its own folder's headers and those below,
never one above. engine/src/ likewise (docs/architecture.md, the drawing of its layers): no
folder includes one of a layer above it, nor the engine table."""
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


# engine/src/'s folders, bottom up; folders of one layer are side by side.
ENGINE_LAYERS = [["parallel", "io", "scene"], ["step"], ["broad_phase"], ["event", "gpu", "mpi"]]
ENGINE_TABLE = ["engines.hpp"]  # above every folder


def test_no_engine_folder_includes_a_layer_above_its_own():
    rank = {folder: k for k, layer in enumerate(ENGINE_LAYERS) for folder in layer}
    upward = []
    for folder, own in rank.items():
        for path in sorted((ROOT / "engine" / "src" / folder).glob("*.[ch]*")):
            text = path.read_text()
            for included in re.findall(r'#include "(\w+)/', text):
                if rank.get(included, -1) > own or (included != folder and
                                                    rank.get(included, -1) == own):
                    upward.append(f"{path.relative_to(ROOT)} includes {included}/")
            for table in ENGINE_TABLE:
                if f'#include "{table}"' in text:
                    upward.append(f"{path.relative_to(ROOT)} includes {table}")
    assert upward == []
