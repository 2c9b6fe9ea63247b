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


def countable_build() -> Path:
    """The build valgrind can run here: BUILD, unless it uses AVX-512 on an AVX-512 CPU; then
    make regress's own build-regress (without AVX-512), where one has been made."""
    from analysis.regress.suite import cpu_isa_flags, uses_avx512
    if uses_avx512(BUILD) and "avx512f" in cpu_isa_flags():
        return ROOT / "build-regress"
    return BUILD
