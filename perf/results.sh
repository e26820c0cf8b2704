#!/usr/bin/env bash
# Regenerates the measurements behind docs/results.md (issue 7), from one perishell build
# (a CUDA build measures both backends: --backend host on 2 OpenMP threads is the CPU).
#
#   perf/results.sh BUILD OUT [PART...]
#
# BUILD  a build directory with apps/perishell and perf/perishell_perf_accuracy_cost
#        (build/cuda; or a bundle of cmake/gpu_bundle.sh, whose bin/ holds both)
# OUT    where the parts write (created); each part can run on its own, e.g. on two
#        machines or in two sessions, and `report` puts together what is there
# PART   speedup   perf/speedup.py: CPU vs GPU on the paper's grids -> OUT/speedup/
#        accuracy  perishell_perf_accuracy_cost on both backends + charts -> OUT/accuracy/
#        examples  the paper's explicit examples 4.1.2, 4.2.2, 4.2.3, 4.2.4 run to the end
#                  on the device, with damage images -> OUT/examples/
#        report    docs/results.md and docs/images/results/ from OUT
#        (default: all four, in that order)
# Environment: PYTHON (default /usr/bin/python3 if it has matplotlib, else python3),
# SPEEDUP_ARGS (extra perf/speedup.py options, e.g. "--repeats 1 --quick"),
# ACCURACY_BACKEND (device, host or both, default both: each run writes
# OUT/accuracy/accuracy_<backend>.csv, and the charts draw every such file there, so the
# CPU curves can come from a CPU machine and the GPU ones from a GPU machine).
set -euo pipefail
if [[ $# -lt 2 ]]; then
  sed -n '2,20p' "$0" >&2
  exit 2
fi
build=$(cd "$1" && pwd) out=$2
shift 2
parts=("$@")
[[ ${#parts[@]} -gt 0 ]] || parts=(speedup accuracy examples report)
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
find_binary() {
  for candidate in "$build/$1" "$build/bin/$(basename "$1")"; do
    [[ -x $candidate ]] && { echo "$candidate"; return; }
  done
  echo "results: no $1 under $build" >&2
  exit 1
}
python=${PYTHON:-}
if [[ -z $python ]]; then
  python=python3
  /usr/bin/python3 -c "import matplotlib, h5py" 2> /dev/null && python=/usr/bin/python3
fi
export OMP_PROC_BIND=false
mkdir -p "$out"
# The machine and date of a part, for the report.
stamp() {
  mkdir -p "$1"
  {
    echo "date: $(date -u +%Y-%m-%d)"
    echo "cpu: $(grep -m1 '^model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //') ($(nproc --all) logical CPUs)"
    echo "gpu: $(nvidia-smi --query-gpu=name --format=csv,noheader 2> /dev/null | head -1 || true)"
    echo "build: $build"
  } > "$1/machine.txt"
}

for part in "${parts[@]}"; do
  echo "=== results: $part ($(date -u +%H:%M:%S))"
  case $part in
    speedup)
      stamp "$out/speedup"
      # shellcheck disable=SC2086
      "$python" "$root/perf/speedup.py" --app "$(find_binary apps/perishell)" --out "$out/speedup" ${SPEEDUP_ARGS:-} ;;
    accuracy)
      backend=${ACCURACY_BACKEND:-both}
      stamp "$out/accuracy"
      cp "$out/accuracy/machine.txt" "$out/accuracy/machine_$backend.txt"
      OMP_NUM_THREADS=2 "$(find_binary perf/perishell_perf_accuracy_cost)" --backend "$backend" \
        --out "$out/accuracy/accuracy_$backend.csv"
      "$python" "$root/perf/charts/speed_accuracy.py" "$out"/accuracy/accuracy_*.csv --out "$out/accuracy/accuracy" ;;
    examples)
      app=$(find_binary apps/perishell)
      stamp "$out/examples"
      for deck in glass_plate_4_1_2 steel_plate_4_2_2 steel_plate_4_2_2_running hexagonal_prism_4_2_3 cracked_cylinder_4_2_4; do
        OMP_NUM_THREADS=2 "$app" run "$root/apps/cases/$deck.yaml" --output "$out/examples/$deck" \
          > "$out/examples/$deck.log" 2>&1 || { tail -20 "$out/examples/$deck.log"; exit 1; }
        grep -A20 "run summary" "$out/examples/$deck.log"
        "$python" "$root/perf/charts/render_results.py" damage "$out/examples/$deck/results.xmf" \
          --out "$out/examples/$deck/$deck"
        "$python" "$root/perf/charts/render_results.py" damage "$out/examples/$deck/results.xmf" \
          --field displacement --out "$out/examples/$deck/$deck"
      done
      "$python" "$root/perf/charts/render_results.py" history "$out/examples/glass_plate_4_1_2/history.csv" \
        --x time --y crack-tip-speed --x-scale 1e6 --xlabel "time [µs]" --ylabel "crack tip speed [m/s]" \
        --hline 3058 --hline-label "Rayleigh speed 3058 m/s" --out "$out/examples/glass_plate_4_1_2/tip_speed.png"
      "$python" "$root/perf/charts/render_results.py" history "$out/examples/steel_plate_4_2_2/history.csv" \
        --x load-factor-ramp --x-scale 1800 --y-expr "lift-left-flank-uz - push-right-flank-uz" --y-scale 1e3 \
        --xlabel "load F [N]" --ylabel "crack opening [mm]" --labels "opening (left flank uz - right flank uz)" \
        --out "$out/examples/steel_plate_4_2_2/load_opening.png"
      "$python" "$root/perf/charts/render_results.py" history "$out/examples/steel_plate_4_2_2_running/history.csv" \
        --x load-factor-ramp --x-scale 2200 --y-expr "lift-left-flank-uz - push-right-flank-uz" --y-scale 1e3 \
        --xlabel "load F [N]" --ylabel "crack opening [mm]" --labels "opening (left flank uz - right flank uz)" \
        --out "$out/examples/steel_plate_4_2_2_running/load_opening.png" ;;
    report)
      "$python" "$root/perf/results_report.py" "$out" --docs "$root/docs" ;;
    *)
      echo "results: unknown part '$part' (speedup, accuracy, examples or report)" >&2
      exit 2 ;;
  esac
done
