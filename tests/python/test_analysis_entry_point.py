"""`python3 -m analysis`: the one entry point lists every tool, each tool's --help works, and the
package is imported as one (no sys.path edits)."""
import re
import subprocess
import sys

import pytest

from entry_point import ROOT, run_tool
from analysis.__main__ import TOOLS

PACKAGE = ROOT / "analysis"
SUBPACKAGES = sorted(p.parent.name for p in PACKAGE.glob("*/cli.py"))


def test_every_tool_with_a_command_line_is_listed():
    assert sorted(TOOLS) == SUBPACKAGES
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
    assert done.stdout.startswith(f"usage: python3 -m analysis {tool}")


def test_an_unknown_tool_or_none_exits_2_with_the_list():
    done = run_tool("plot")
    assert done.returncode == 2 and "unknown tool 'plot'" in done.stderr
    assert re.search(r"^  plots +\S", done.stderr, re.M)
    done = subprocess.run([sys.executable, "-m", "analysis"], capture_output=True, text=True,
                          cwd=ROOT, timeout=60)
    assert done.returncode == 2 and done.stderr.startswith("usage: python3 -m analysis TOOL")


def test_the_package_edits_no_import_path():
    assert not [p for p in PACKAGE.rglob("*.py") if "sys.path" in p.read_text()]
