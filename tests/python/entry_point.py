"""`python3 -m analysis TOOL ARGS...` as the Makefile runs it: from the repository root."""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def run_tool(tool: str, *args, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "analysis", tool, *map(str, args)],
                          capture_output=True, text=True, timeout=timeout, cwd=ROOT)
