#!/usr/bin/env bash
# Installs the Debian packages particle-lab needs, only when one is missing, so that
# `make test` and `make sweep` work on a fresh Debian 12 machine and stay quiet afterwards.
set -euo pipefail

packages=(
  g++ cmake make pkg-config
  libbenchmark-dev nlohmann-json3-dev libfmt-dev libgtest-dev libcli11-dev
  python3-pandas python3-matplotlib python3-scipy python3-pytest python3-pil python3-yaml
  python3-markdown  # report.md -> report.html
  valgrind
  bubblewrap  # the sandbox of every external program a sweep or a grading runs
  openmpi-bin libopenmpi-dev  # the mpi engine (engine/src/mpi): mpirun and the MPI library
  "$@"  # what one target needs besides, e.g. slurm-wlm munge for make test-slurm
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "bootstrap: installing ${missing[*]}" >&2
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
