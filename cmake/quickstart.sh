#!/usr/bin/env bash
# One command from a fresh Debian 12 machine (as root) to a built perishell running its
# default case: installs the Debian packages, builds the dependency stack into the cache
# (cmake/deps/bootstrap.sh), configures and builds the preset, runs the default case.
# Usage: bash cmake/quickstart.sh [openmp|cuda|debug]   (default: openmp)
set -euo pipefail
preset=${1:-openmp}
backend=openmp
[ "$preset" = cuda ] && backend=cuda
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash cmake/deps/bootstrap.sh --backend "$backend" > /dev/null
cmake --preset "$preset"
cmake --build --preset "$preset"

if [ "$backend" = cuda ] && ! command -v nvidia-smi > /dev/null; then
  echo "quickstart: built build/$preset; no GPU here, so the default case was not run" \
       "(README: 'GPU build')."
  exit 0
fi
echo
echo "quickstart: running the default case: build/$preset/apps/perishell membrane"
OMP_NUM_THREADS=${OMP_NUM_THREADS:-$(nproc)} OMP_PROC_BIND=${OMP_PROC_BIND:-false} \
  "build/$preset/apps/perishell" membrane
