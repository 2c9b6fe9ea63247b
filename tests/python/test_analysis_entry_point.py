"""`python3 -m analysis`: the one entry point lists every tool, each tool's --help works, and the
package is imported as one (no sys.path edits)."""
import re
import subprocess
import sys

import pytest

from entry_point import ROOT, run_tool
from analysis.__main__ import MODULES, TOOLS

PACKAGE = ROOT / "analysis"
SUBPACKAGES = sorted(p.parent.name for p in PACKAGE.glob("*/cli.py"))


def test_every_tool_with_a_command_line_is_listed():
    # each tool is its subpackage's cli.py, or a module of its own that MODULES names
    assert sorted(set(TOOLS) - set(MODULES)) == SUBPACKAGES
    for module in MODULES.values():
        assert (ROOT / (module.replace(".", "/") + ".py")).is_file(), module
    assert set(SUBPACKAGES) >= {"plots", "compare", "accuracy", "stability", "regress",
                                "targets", "noise", "animate"}


def test_help_lists_the_tools_one_line_each():
    done = run_tool("--help")
    assert done.returncode == 0, done.stderr
    for tool in TOOLS:
        assert re.search(rf"^  {tool} +\S", done.stdout, re.M), tool


@pytest.mark.parametrize("tool", sorted(TOOLS))
def test_each_tool_has_help(tool):
    done = run_tool(tool, "--help")
    assert done.returncode == 0, done.stderr
    # argparse shows its program's base name
    assert done.stdout.startswith(f"usage: python3 -m analysis {tool}")


def test_an_unknown_tool_or_none_exits_2_with_the_list():
    done = run_tool("plot")
    assert done.returncode == 2 and "unknown tool 'plot'" in done.stderr
    assert re.search(r"^  plots +\S", done.stderr, re.M)
    done = subprocess.run([sys.executable, "-m", "analysis"], capture_output=True, text=True,
                          cwd=ROOT, timeout=60)
    assert done.returncode == 2 and done.stderr.startswith("usage: /usr/bin/python3 -m analysis TOOL")


@pytest.mark.parametrize("blocked", [["pandas"], ["matplotlib"]])
def test_an_interpreter_without_the_packages_is_told_in_one_line(blocked):
    # As a pyenv python3 first on PATH would be: the packages cannot be imported.
    code = ("import runpy, sys\n"
            f"for name in {blocked!r}: sys.modules[name] = None\n"
            "sys.argv = ['analysis', 'plots', 'results/none']\n"
            "runpy.run_module('analysis', run_name='__main__')\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, timeout=60)
    assert done.returncode == 2
    assert "Traceback" not in done.stderr and done.stderr.count("\n") == 1, done.stderr
    assert f"lacks {', '.join(blocked)}; the lab's analysis runs under /usr/bin/python3" \
        in done.stderr


def test_the_package_edits_no_import_path():
    assert not [p for p in PACKAGE.rglob("*.py") if "sys.path" in p.read_text()]
