"""The manual cites only what exists: every relative link of README.md and docs/*.md reaches a
file (and its #anchor a heading), every repository path they name in backticks exists, and every
docs/ page a source file cites is there."""
import json
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
TOP = ("engine", "apps", "harness", "check", "analysis", "scripts", "configs", "scenes", "bench",
       "tests", "docs", ".ci", ".github")


def anchors(page: Path) -> set[str]:
    """GitHub's heading anchors: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"```.*?```", "", page.read_text(), flags=re.S)
    return {re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-")
            for h in re.findall(r"^#+ (.*)$", text, flags=re.M)}


def cited_paths(text: str):
    """Paths in backticks that start at a top-level folder, without placeholders or globs."""
    for span in re.findall(r"`([^`\n]+)`", text):
        for word in span.split():
            word = word.strip("(),;:")
            if "/" in word and word.split("/")[0] in TOP and not re.search(r"[<>*{}$\[\]|]", word):
                yield word


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_links_reach_files_and_headings(page):
    text = re.sub(r"```.*?```", "", page.read_text(), flags=re.S)
    broken = []
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if re.match(r"[a-z]+://", target):
            continue
        path, _, anchor = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if not dest.exists():
            broken.append(target)
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            broken.append(target)
    assert not broken, f"{page.name}: links to nothing: {broken}"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_named_paths_exist(page):
    missing = [p for p in cited_paths(page.read_text())
               if not (ROOT / p).exists() and not p.startswith(("results/", "build"))]
    assert not missing, f"{page.name}: names paths that do not exist: {missing}"


def test_sources_cite_existing_docs():
    listed = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True,
                            check=True).stdout.split()
    missing = {}
    for name in listed:
        path = ROOT / name
        if path.suffix not in {".cpp", ".hpp", ".c", ".py", ".sh", ".txt", ".json"} and \
                path.name not in {"Makefile", "run"}:
            continue
        for page in re.findall(r"docs/[a-z_]+\.md", path.read_text(errors="replace")):
            if not (ROOT / page).exists():
                missing.setdefault(name, []).append(page)
    assert not missing, f"cite docs pages that do not exist: {missing}"
    # The design lived outside the repository until docs/ took it over; a citation of it would
    # point nowhere. (The name is assembled so that this file does not cite it either.)
    outside = "DESIGN" + ".md"
    assert not any(outside in (ROOT / n).read_text(errors="replace")
                   for n in listed if (ROOT / n).suffix in {".cpp", ".hpp", ".py", ".md", ".txt"}), \
        f"{outside} is not in the repository"


# What `make sweep` builds (make tools): any other program of build/ is `make build`'s.
TOOLS = {"build/psim", "build/psweep", "build/ceilings"}


def sh_blocks(page: Path):
    """The lines of each sh block of a page."""
    block = None
    for line in page.read_text().splitlines():
        if line.startswith("```"):
            if block is not None:
                yield block
            block = [] if block is None and line[3:].strip() in ("sh", "bash") else None
        elif block is not None:
            block.append(line.split("#", 1)[0])


def built_programs(line: str) -> set[str]:
    """The programs of build/ a command line runs: named on it, or named by the commands of a
    psweep config it runs."""
    words = line.split()
    named = {w for w in words if w.startswith("build/")}
    for word in words:
        if word.startswith("configs/") and word.endswith(".json") and "build/psweep" in words:
            programs = json.loads((ROOT / word).read_text()).get("programs", {})
            named |= {p["command"][0] for p in programs.values()
                      if p["command"][0].startswith("build/")}
    return named - TOOLS


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_examples_run_as_written_after_the_two_commands(page):
    """make sweep builds psim and psweep alone: an example that runs anything else of build/
    names `make build` first; a folder it grades is made first (or is the repository's)."""
    problems = []
    for block in sh_blocks(page):
        for i, line in enumerate(block):
            before = block[:i]
            if built_programs(line) and not any(b.strip().startswith("make build")
                                                for b in before):
                problems.append(f"{line.strip()!r} runs {sorted(built_programs(line))} "
                                "without `make build` before it")
            folder = re.search(r"PROGRAMS=(\S+)", line)
            if folder and not (ROOT / folder.group(1)).exists() and not any(
                    "mkdir" in b and folder.group(1).rstrip("/") in b for b in before):
                problems.append(f"{line.strip()!r} grades {folder.group(1)}, which nothing "
                                "before it makes")
    assert not problems, f"{page.name}: " + "; ".join(problems)
