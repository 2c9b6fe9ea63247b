"""Submissions as courses collect them: a folder of sources with a Makefile, built confined.

An entry of the submissions folder that is a folder is built before anything runs: its files
packed into one archive, unpacked inside a sandbox (`psweep confined`, the tier and limits a
submission's runs get: no network, nothing of the grader's, its own folder), built there by the
grade config's `submission.build` (a shell command line; `make` by default, for a folder with a
Makefile), and the program it made brought out with the build's log: the executable
`submission.program` names, else the one executable file the build made at the top of the folder.
The log, its last 64 KiB, goes into the student's report; a build that fails, times out or makes
no program is the entry's row, `failed`, saying so.
"""
from __future__ import annotations

import subprocess
import tarfile
from dataclasses import dataclass
from pathlib import Path

MAKEFILES = ("GNUmakefile", "makefile", "Makefile")
BUILD_TIMEOUT_S = 300
LOG_BYTES = 64 << 10
# The programs a build may bring out when none is named (a folder of several is an error).
MAX_PRODUCTS = 8

# Inside the sandbox, in its own empty folder: $1 the sources' archive, $2 the build command,
# $3 the program's path or empty. Its stdout is an archive of the log and the program(s).
SCRIPT = r"""
tar -xf "$1" 2>.unpack || { echo "psweep build: cannot unpack the sources: $(cat .unpack)" >&2
  exit 2; }
: > .psweep-before
sh -c "$2" > .build.log 2>&1
status=$?
tail -c %d .build.log > .log
if [ -n "$3" ]; then
  [ -f "$3" ] && [ -x "$3" ] && printf '%%s\n' "$3" > .products
else
  find . -maxdepth 1 -type f -perm -u+x -newer .psweep-before ! -name '.*' | head -n %d \
    > .products
fi
tar -cf - .log $(cat .products 2>/dev/null)
exit $status
""" % (LOG_BYTES, MAX_PRODUCTS + 1)


@dataclass
class Built:
    program: Path | None   # the executable, None when the build made none
    log: str               # its last LOG_BYTES
    note: str = ""         # why it is not graded, or empty


def buildable(folder: Path, submission: dict) -> bool:
    """Whether an entry that is a folder is built: it has a Makefile, or the config says how."""
    return "build" in submission or any((folder / name).is_file() for name in MAKEFILES)


def pack(folder: Path, archive: Path, max_bytes: int) -> str:
    """The folder's contents into `archive` (symlinks as links, never followed); an empty string,
    or why it is not packed (more than `max_bytes` of files)."""
    total = sum(p.lstat().st_size for p in folder.rglob("*") if p.is_file() and not p.is_symlink())
    if total > max_bytes:
        return (f"a folder of {total} bytes of files, more than a submission may be "
                f"({max_bytes >> 20} MiB): not graded")
    with tarfile.open(archive, "w") as tar:
        for path in sorted(folder.iterdir()):
            tar.add(path, arcname=path.name)
    return ""


def _unpack(result: Path, into: Path) -> tuple[str, list[Path]]:
    """The log and the programs of the sandbox's archive, each regular file by its base name only:
    nothing it names can land outside `into`."""
    log, programs = "", []
    try:
        with tarfile.open(result) as tar:
            for member in tar.getmembers():
                data = tar.extractfile(member) if member.isfile() else None
                if data is None:
                    continue
                name = Path(member.name).name
                if name in ("", ".", ".."):
                    continue
                if name == ".log":
                    log = data.read().decode(errors="replace")
                    continue
                path = into / name
                path.write_bytes(data.read())
                path.chmod(0o755)
                programs.append(path)
    except (tarfile.TarError, OSError):
        pass
    return log, programs


def _run(command: list[str]) -> subprocess.CompletedProcess:
    try:
        return subprocess.run(command, capture_output=True, text=True)
    except OSError as err:
        return subprocess.CompletedProcess(command, 2, "", f"cannot run {command[0]}: "
                                                           f"{err.strerror}")


def build(folder: Path, submission: dict, psweep: str, into: Path, max_bytes: int,
          unconfined: bool = False) -> Built:
    """`folder` built confined, its program and log in `into` (made afresh)."""
    into.mkdir(parents=True, exist_ok=True)
    for old in into.iterdir():
        old.unlink()
    archive = into / ".sources.tar"
    refused = pack(folder, archive, max_bytes)
    if refused:
        return Built(None, "", refused)
    command = submission.get("build", "make")
    timeout = submission.get("build_timeout_s", BUILD_TIMEOUT_S)
    result = into / ".built.tar"
    done = _run(
        [psweep, "confined", "--stdout", str(result), "--stdout-bytes", str(max_bytes + LOG_BYTES
                                                                          + (1 << 20)),
         "--timeout-s", str(timeout), *(["--unconfined"] if unconfined else []), "--",
         "/bin/sh", "-c", SCRIPT, "build", str(archive), command,
         submission.get("program", "")])
    log, programs = _unpack(result, into)
    archive.unlink()
    result.unlink(missing_ok=True)
    said = done.stderr.strip()
    if done.returncode == 124:
        return Built(None, log, f"the build (`{command}`) did not end within its {timeout:g} s: "
                                "not graded")
    if done.returncode != 0:
        last = (log.strip().splitlines() or said.splitlines() or [""])[-1]
        return Built(None, log, f"the build (`{command}`) failed with exit status "
                                f"{done.returncode}: {last} (its log in the report): not graded")
    if "program" in submission and not programs:
        return Built(None, log, f"the build (`{command}`) made no executable "
                                f"{submission['program']} (submission.program): not graded")
    if not programs:
        return Built(None, log, f"the build (`{command}`) made no executable file in the folder: "
                                "not graded")
    if len(programs) > 1:
        names = ", ".join(sorted(p.name for p in programs)[:MAX_PRODUCTS])
        return Built(None, log, f"the build (`{command}`) made several executables ({names}): "
                                "not graded (the grade config's submission.program names the "
                                "one to run)")
    return Built(programs[0], log)
