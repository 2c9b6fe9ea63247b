"""The analysis's one entry point: `/usr/bin/python3 -m analysis TOOL [ARGS...]`, run from the
repository root (the Makefile's targets do). Each tool is the subpackage of its name; its
cli.main() reads the rest of the command line, so `/usr/bin/python3 -m analysis TOOL --help` is
the tool's own help. Another interpreter (a pyenv or venv python3 first on PATH) that lacks the
lab's packages is told so in one line, exit 2, before any tool is imported."""
from __future__ import annotations

import importlib
import sys

TOOLS = {
    "plots": "tables, plots and report.md from a psweep results folder (make plots)",
    "compare": "two results folders configuration by configuration (make compare)",
    "accuracy": "error against run time of the discrete engines (make accuracy)",
    "stability": "stiff and extreme scenes through every engine (make stability)",
    "regress": "the regression suite against its baseline: run, baseline (make regress)",
    "targets": "the speed targets per scene (make targets, make million)",
    "noise": "quiet against one busy neighbour (make noise)",
    "animate": "a GIF of a scene's particles moving (make animate)",
    "scoreboard": "external programs beside the engines, judged and timed (make scoreboard)",
    "grade": "a folder of submissions judged and timed, a report each (make grade)",
    "grade-slurm": "a class graded in shards on a Slurm cluster, merged (make grade-slurm)",
}
# A tool whose module is not its own subpackage's cli.py.
MODULES = {"grade-slurm": "analysis.grade.shards"}


COMMAND = "/usr/bin/python3 -m analysis"
# Debian's python3-numpy, -pandas, -matplotlib and -scipy (scripts/bootstrap.sh installs them).
PACKAGES = ("numpy", "pandas", "matplotlib", "scipy")


def missing_packages() -> list[str]:
    missing = []
    for name in PACKAGES:
        try:
            importlib.import_module(name)
        except ImportError:
            missing.append(name)
    return missing


def usage() -> str:
    width = max(map(len, TOOLS))
    return "\n".join([f"usage: {COMMAND} TOOL [ARGS...]", "",
                      f"tools ({COMMAND} TOOL --help for each):"]
                     + [f"  {name:<{width}}  {about}" for name, about in TOOLS.items()])


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv or argv[0] in ("-h", "--help"):
        print(usage(), file=sys.stdout if argv else sys.stderr)
        return 0 if argv else 2
    tool, rest = argv[0], argv[1:]
    if tool not in TOOLS:
        print(f"analysis: unknown tool {tool!r}\n\n{usage()}", file=sys.stderr)
        return 2
    missing = missing_packages()
    if missing:
        print(f"analysis: {sys.executable} lacks {', '.join(missing)}; the lab's analysis runs "
              f"under /usr/bin/python3 with Debian's packages (make deps installs them): "
              f"{COMMAND} {tool} ...", file=sys.stderr)
        return 2
    # argparse names the program after argv[0]: help and errors then show the command to type.
    sys.argv[0] = f"{COMMAND} {tool}"
    return importlib.import_module(MODULES.get(tool, f"analysis.{tool}.cli")).main(rest)


if __name__ == "__main__":
    sys.exit(main())
