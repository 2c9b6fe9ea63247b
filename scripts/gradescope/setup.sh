#!/usr/bin/env bash
# Gradescope's setup.sh: run once as the autograder's image is built, with this lab unpacked in
# /autograder/source (make gradescope's zip). Installs what is missing and builds psim and psweep.
set -euo pipefail
cd "$(dirname "$0")"
make tools
