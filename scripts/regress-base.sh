#!/usr/bin/env bash
# make regress BASE=REF: the base commit's psim and psweep, built as make regress builds its own
# (x86-64-v3, no AVX-512, no CUDA) in DIR/build from a git worktree of that commit in
# DIR/src, reused and moved to the commit on the next call. This script and scripts/build.sh are
# the head's, so a base older than them builds too.
#   scripts/regress-base.sh REF DIR
set -euo pipefail
ref=$1 dir=$2
root=$(pwd -P)
commit=$(git rev-parse --verify --quiet "$ref^{commit}") ||
  { echo "make regress: BASE=$ref is not a commit here" >&2; exit 2; }
src="$dir/src"
if [ -e "$src/.git" ]; then
  git -C "$src" checkout --quiet --detach "$commit"
else
  mkdir -p "$dir"
  git worktree prune
  git worktree add --quiet --detach "$src" "$commit"
fi
echo "regress: base $ref = $(git rev-parse --short "$commit"), built in $dir/build" >&2
cd "$src"
"$root/scripts/build.sh" ../build psim psweep -- -DPARTICLE_MARCH=x86-64-v3 -DPARTICLE_AVX512=OFF \
  -DPARTICLE_CUDA=OFF -DPARTICLE_MPI=AUTO
