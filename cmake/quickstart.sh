#!/usr/bin/env bash
# One command from a fresh Debian 12 machine (as root) to a built perishell running its
# default case: installs the Debian packages, builds the dependency stack into the cache
# (cmake/deps/bootstrap.sh), configures and builds the preset, runs the default case and
# draws its crack.
# Usage: bash cmake/quickstart.sh [openmp|cuda|debug]   (default: openmp)
set -euo pipefail
preset=${1:-openmp}
backend=openmp
[ "$preset" = cuda ] && backend=cuda
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash cmake/deps/bootstrap.sh --backend "$backend" > /dev/null
cmake --preset "$preset"
# The app first, so the default case runs before the tests and benchmarks are compiled.
cmake --build --preset "$preset" --target perishell_app

if [ "$backend" = cuda ] && ! command -v nvidia-smi > /dev/null; then
  cmake --build --preset "$preset"
  echo "quickstart: built build/$preset; no GPU here, so the default case was not run" \
       "(README: 'GPU build')."
  exit 0
fi
# The default case: a crack runs and branches in a glass plate (apps/cases/default_crack_branching.yaml),
# written for ParaView and drawn to PNG (damage, displacement) by perf/charts/render_results.py.
out=output/default-case
echo
echo "quickstart: running the default case: build/$preset/apps/perishell run apps/cases/default_crack_branching.yaml"
OMP_NUM_THREADS=${OMP_NUM_THREADS:-$(nproc)} \
  "build/$preset/apps/perishell" run apps/cases/default_crack_branching.yaml --output "$out"
for field in damage displacement; do
  /usr/bin/python3 perf/charts/render_results.py damage "$out/results.xmf" --field "$field" --out "$out/crack" > /dev/null
done
echo
echo "quickstart: the crack, drawn at three times: $out/crack_damage_panel.png and"
echo "  $out/crack_displacement_panel.png; in ParaView: $out/results.xmf; history: $out/history.csv."
echo "  The stack-verification case: build/$preset/apps/perishell membrane"
echo
echo "quickstart: building the rest (tests, benchmarks) for 'ctest --preset $preset'"
cmake --build --preset "$preset"
echo "quickstart: done; the tests: ctest --preset $preset"
