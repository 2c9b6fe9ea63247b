#!/usr/bin/env bash
# Packs what the device machine needs to run the GPU and thread-scaling checks
# (scripts/device-check.sh) into KIT: psim, psweep and gpu_tests from BUILD (built here, with
# CUDA for sm_90 and the CUDA runtime linked statically), psim-mpi beside psim where the build has
# MPI (psim hands the mpi engine's runs to it, found beside its own executable), and the shared
# libraries they load that a bare machine may lack (ldd; the C library and the loader stay the
# machine's). The device machine has no network and none of our Debian packages; what is carried
# is at most 64 MiB.
# Usage: device-kit.sh BUILD KIT
set -euo pipefail
build=$1 kit=$2
rm -rf "$kit"
mkdir -p "$kit/lib"
optional=
[ -x "$build/psim-mpi" ] && optional=psim-mpi
for exe in psim psweep tests/gpu_tests $optional; do
  test -x "$build/$exe" || { echo "device-kit: $build/$exe missing (make build CUDA=ON)" >&2; exit 2; }
  cp "$build/$exe" "$kit/"
  ldd "$build/$exe" | awk '$3 ~ /^\// {print $3}' | while read -r lib; do
    case "$(basename "$lib")" in
      libc.so*|libm.so*|ld-linux*|libpthread.so*|libdl.so*|librt.so*) ;;
      *) cp -L "$lib" "$kit/lib/" ;;
    esac
  done
done
size=$(du -sm "$kit" | cut -f1)
echo "device-kit: $kit, ${size} MiB: $(ls "$kit" "$kit/lib" | grep -v ':$' | tr '\n' ' ')"
[ "$size" -le 64 ] || { echo "device-kit: over the 64 MiB a device run can carry" >&2; exit 2; }
