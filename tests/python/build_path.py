"""The build folder the tests run against: ./build, or PARTICLE_LAB_BUILD (make test-sanitize
points it at build-sanitize), relative to the repository root."""
import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("PARTICLE_LAB_BUILD", ROOT / "build"))
if not BUILD.is_absolute():
    BUILD = ROOT / BUILD


def sanitized() -> bool:
    """True for a build compiled with -fsanitize (valgrind cannot run those programs)."""
    cache = BUILD / "CMakeCache.txt"
    return cache.exists() and "-fsanitize" in cache.read_text()
