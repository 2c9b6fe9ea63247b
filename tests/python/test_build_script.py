"""scripts/build.sh, which every target that builds runs: one build at a time per folder, and a
folder the user cannot write used as it is built (issue 56: two `make grade` at once both rebuilt
build/; a grader who is not root got `build/build.log: Permission denied`)."""
import fcntl
import os
import subprocess

import pytest

from build_path import BUILD
from entry_point import ROOT


def test_a_second_build_of_a_folder_waits_for_the_first():
    with open(BUILD / ".build.lock", "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # as a build under way holds it
        with pytest.raises(subprocess.TimeoutExpired) as waited:
            subprocess.run(["scripts/build.sh", str(BUILD), "tools"], cwd=ROOT,
                           capture_output=True, text=True, timeout=3)
    stderr = waited.value.stderr or b""
    assert b"another build of" in stderr and b"waiting for it" in stderr, stderr


@pytest.mark.skipif(os.geteuid() != 0, reason="needs root to run as another user")
def test_a_folder_another_user_built_is_used_as_built():
    if subprocess.run(["su", "nobody", "-s", "/bin/sh", "-c", "test -x scripts/build.sh"],
                      cwd=ROOT).returncode != 0:
        pytest.skip("nobody cannot reach this checkout")
    done = subprocess.run(["su", "nobody", "-s", "/bin/sh", "-c",
                           f"scripts/build.sh {BUILD} tools"], cwd=ROOT, capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert "is not writable by nobody: its programs are used as built" in done.stderr
    assert "Permission denied" not in done.stderr
