"""Advice names what exists. Every config key the analysis tells a reader to set
(analysis/common/advice.py) is one psweep takes: a config with it set passes
`psweep CONFIG --dry-run`. No key path is written into the analysis's messages by hand (the
report once said "Add it to the config's `engines`", a key psweep refuses). Every `make` command
a message names is a target of the Makefile, with variables the Makefile reads."""
import ast
import json
import re
from pathlib import Path

import pytest

from analysis.common import advice
from test_harness_psweep import PSWEEP, psweep
from test_regress import make_targets

ROOT = Path(__file__).resolve().parents[2]
SOURCES = sorted((ROOT / "analysis").rglob("*.py"))
KEYS = [v for v in vars(advice).values() if isinstance(v, advice.ConfigKey)]
# A key path in a message: the config's own words, or a dotted path into base or sweep.
HAND_WRITTEN_KEY = re.compile(r"config's `|`(?:base|sweep)\.\w+")
MAKE_COMMAND = re.compile(r"\bmake ([a-z][\w-]*)((?: [A-Z][A-Z0-9_]*=\S*)*)")


def messages(path: Path):
    """(line, text) of every string the module can emit: its literals and f-strings' literal
    parts, docstrings left out (they speak to a reader of the code)."""
    tree = ast.parse(path.read_text())
    docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                  if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef,
                                       ast.AsyncFunctionDef))
                  and node.body and isinstance(node.body[0], ast.Expr)
                  and isinstance(node.body[0].value, ast.Constant)}
    for node in ast.walk(tree):
        if (isinstance(node, ast.Constant) and isinstance(node.value, str)
                and id(node) not in docstrings):
            yield node.lineno, node.value


def with_key(config: dict, key: advice.ConfigKey) -> dict:
    *parents, last = key.path.split(".")
    place = config
    for parent in parents:
        place = place.setdefault(parent, {})
    place[last] = key.example
    return config


def dry_run(tmp_path: Path, config: dict):
    path = tmp_path / "advice.json"
    path.write_text(json.dumps(config))
    return psweep(path, "--dry-run")


def base_config() -> dict:
    return {"name": "advice", "base": {"engine": "brute", "N": 100, "L": 2000, "r": 1, "S": 10}}


@pytest.mark.skipif(not PSWEEP.is_file(), reason=f"{PSWEEP} is missing: make build")
@pytest.mark.parametrize("key", KEYS, ids=lambda k: k.path)
def test_every_key_the_advice_names_is_one_psweep_takes(tmp_path, key):
    done = dry_run(tmp_path, with_key(base_config(), key))
    assert done.returncode == 0, done.stderr


@pytest.mark.skipif(not PSWEEP.is_file(), reason=f"{PSWEEP} is missing: make build")
def test_the_check_refuses_the_key_the_report_once_named(tmp_path):
    done = dry_run(tmp_path, with_key(base_config(), advice.ConfigKey("engines", ["brute"])))
    assert done.returncode == 2 and "engines: unknown key" in done.stderr


def test_no_message_writes_a_key_path_by_hand():
    found = [f"{path.relative_to(ROOT)}:{line}: {text.strip()[:70]}"
             for path in SOURCES for line, text in messages(path) if HAND_WRITTEN_KEY.search(text)]
    assert not found, "name the key through analysis/common/advice.py:\n" + "\n".join(found)
    assert HAND_WRITTEN_KEY.search("Add it to the config's `engines` to see")


def test_every_make_command_a_message_names_exists():
    targets, makefile = make_targets(), (ROOT / "Makefile").read_text()
    named = [(path, line, m) for path in SOURCES for line, text in messages(path)
             for m in MAKE_COMMAND.finditer(text)]
    assert len(named) > 10
    wrong = [f"{path.relative_to(ROOT)}:{line}: {m.group(0)}" for path, line, m in named
             if m.group(1) not in targets
             or any(not re.search(rf"\$\({var}\)|^{var}\s*\?=", makefile, re.M)
                    for var in re.findall(r"([A-Z][A-Z0-9_]*)=", m.group(2)))]
    assert not wrong, wrong
