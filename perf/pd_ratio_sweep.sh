#!/usr/bin/env bash
# Run time against PD ratio (the paper's Figs. 18 and 21): runs one paper deck with its PD
# zone grown to each ratio and writes ratio, counts, run time (process wall time, set-up
# and output included), time per increment or step, and the result (pressed: largest
# displacement [m]; steel: broken bonds) to a CSV.
#
#   perf/pd_ratio_sweep.sh APP CASE OUT.csv [LIMIT]
#
# APP   the perishell executable of the build to measure (OpenMP or CUDA preset)
# CASE  pressed  - 4.2.1 pressed plate (implicit), ratios 0, 0.25, 0.5, 0.75, 1; the zone
#                  grows from the middle of the clamped edge (apps/cases/pressed_plate_4_2_1.yaml)
#       steel    - 4.2.2 steel plate (explicit), ratios 0, 0.25, 0.5, 0.75, 1; the zone grows
#                  from the crack centre; at 0 the model is all CCM and has no pre-crack (a
#                  pre-crack must lie in PD)
#       steel-fine - the same on the grid the issue names, dx = 0.7 mm (84,681 nodes): the
#                  flank node sets are the two columns across the crack, x = 100.8 and
#                  101.5 mm, 43 nodes each, carrying 1800 N / 43
# LIMIT to time a slow backend in less time: steel - stop after this many steps (the load
#       ramp is unchanged; default the deck's 50,000); pressed - the grid spacing [m]
#       (default the deck's 0.5e-3).
# AMG_DROP_TOLERANCE=T (pressed only) sets the deck's solver.amg-drop-tolerance, for an A/B of
#       the aggregation (0: every coupling, as before 2026-12-06; default 0.05).
# AMG_REUSE=G (pressed only) sets the deck's solver.amg-reuse (the hierarchy's reuse growth
#       limit; 0 rebuilds it at every Newton iteration; default 1.5).
# AMG_COARSE_NODES=N (pressed only) sets the deck's solver.amg-coarse-nodes (the most nodes of
#       the densely inverted coarsest level; 80 builds the hierarchies of before 2026-12-07).
# AMG_REGION_SCALING=true|false (pressed only) sets the deck's solver.amg-region-scaling (false:
#       one smoother scaling and prolongator damping per level, as before 2026-12-07).
# Each run's full log is kept next to the CSV (OUT.csv.ratio-R.log).
set -euo pipefail
if [[ $# -lt 3 ]]; then
  sed -n '2,29p' "$0" >&2
  exit 2
fi
app=$1 case=$2 csv=$3 limit=${4:-}
cases="$(cd "$(dirname "${BASH_SOURCE[0]}")/../apps/cases" && pwd)"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

case $case in
  pressed) base=$cases/pressed_plate_4_2_1.yaml ratios="0 0.25 0.5 0.75 1" ;;
  steel) base=$cases/steel_plate_4_2_2.yaml ratios="0 0.25 0.5 0.75 1" ;;
  steel-fine)
    base=$work/steel_plate_4_2_2_fine.yaml ratios="0 0.25 0.5 0.75 1"
    sed -e 's/^    spacing: 1.75e-3$/    spacing: 0.7e-3/' \
      -e 's/left-flank: {box: {min: \[0.0995,/left-flank: {box: {min: [0.1005,/' \
      -e 's/\(left-flank: {box: {min: \[0.1005, 0.0865, -1.0\], max: \[\)0.1000,/\10.1010,/' \
      -e 's/right-flank: {box: {min: \[0.1010,/right-flank: {box: {min: [0.1012,/' \
      -e 's/105.88235294117646/41.86046511627907/g' "$cases/steel_plate_4_2_2.yaml" > "$base"
    [[ $(grep -c -e 'spacing: 0.7e-3' -e 'min: \[0.1005' -e 'max: \[0.1010' -e 'min: \[0.1012' -e '41.86046511627907' "$base") == 5 ]] ||
      { echo "pd_ratio_sweep: apps/cases/steel_plate_4_2_2.yaml no longer has the lines steel-fine edits" >&2; exit 1; } ;;
  *) echo "pd_ratio_sweep: unknown case '$case' (pressed, steel or steel-fine)" >&2; exit 2 ;;
esac

# The deck at one ratio, from the base deck's zones block.
deck_for() {
  local ratio=$1 deck=$work/deck-$1.yaml
  case $case in
    pressed)
      sed -e "s/^      target: 0.5$/      target: $ratio/" "$base" > "$deck"
      grep -q "target: $ratio\$" "$deck" || { echo "pd_ratio_sweep: $base has no 'target: 0.5' line" >&2; exit 1; }
      if [[ -n $limit ]]; then sed -i -e "s/^    spacing: 0.5e-3$/    spacing: $limit/" "$deck"; fi
      if [[ -n ${AMG_DROP_TOLERANCE:-} ]]; then
        sed -i -e "s/^    preconditioner: amg$/    preconditioner: amg\n    amg-drop-tolerance: $AMG_DROP_TOLERANCE/" "$deck"
        grep -q "amg-drop-tolerance: $AMG_DROP_TOLERANCE\$" "$deck" ||
          { echo "pd_ratio_sweep: $base has no 'preconditioner: amg' line" >&2; exit 1; }
      fi
      if [[ -n ${AMG_COARSE_NODES:-} ]]; then
        sed -i -e "s/^    preconditioner: amg$/    preconditioner: amg\n    amg-coarse-nodes: $AMG_COARSE_NODES/" "$deck"
        grep -q "amg-coarse-nodes: $AMG_COARSE_NODES\$" "$deck" ||
          { echo "pd_ratio_sweep: $base has no 'preconditioner: amg' line" >&2; exit 1; }
      fi
      if [[ -n ${AMG_REGION_SCALING:-} ]]; then
        sed -i -e "s/^    preconditioner: amg$/    preconditioner: amg\n    amg-region-scaling: $AMG_REGION_SCALING/" "$deck"
        grep -q "amg-region-scaling: $AMG_REGION_SCALING\$" "$deck" ||
          { echo "pd_ratio_sweep: $base has no 'preconditioner: amg' line" >&2; exit 1; }
      fi
      if [[ -n ${AMG_REUSE:-} ]]; then
        sed -i -e "s/^    preconditioner: amg$/    preconditioner: amg\n    amg-reuse: $AMG_REUSE/" "$deck"
        grep -q "amg-reuse: $AMG_REUSE\$" "$deck" ||
          { echo "pd_ratio_sweep: $base has no 'preconditioner: amg' line" >&2; exit 1; }
      fi ;;
    steel | steel-fine)
      if [[ $ratio == 0 ]]; then
        sed -e "s/^    default: pd$/    default: ccm/" "$base" | awk '/^    pre-cracks:/ {skip = 1; next} skip && /^      / {next} {skip = 0; print}' > "$deck"
        grep -q "default: ccm" "$deck" || { echo "pd_ratio_sweep: $base has no 'default: pd' line" >&2; exit 1; }
      else
        sed -e "s/^    default: pd$/    default: ccm\n    pd-ratio: {target: $ratio, around: {crack-centre: [0.1015, 0.1015, 0.0]}}/" \
          "$base" > "$deck"
        grep -q "pd-ratio: {target: $ratio" "$deck" || { echo "pd_ratio_sweep: $base has no 'default: pd' line" >&2; exit 1; }
      fi
      if [[ -n $limit ]]; then sed -i -e "s/^    steps: 50000$/    steps: $limit/" "$deck"; fi ;;
  esac
  echo "$deck"
}

echo "case,ratio,pd_ratio_percent,shell_elements,bonds,run_seconds,per_step_seconds,result" > "$csv.tmp"
for ratio in $ratios; do
  deck=$(deck_for "$ratio")
  log=$csv.ratio-$ratio.log
  start=$(date +%s.%N)
  "$app" run "$deck" --output "$work/out-$ratio" > "$log" 2>&1 || { echo "pd_ratio_sweep: ratio $ratio failed, see $log" >&2; exit 1; }
  seconds=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN {printf "%.3f", b - a}')
  percent=$(grep -o 'PD ratio [0-9.]* %' "$log" | head -1 | grep -o '[0-9.]*')
  if [[ $case == pressed ]]; then
    shells=$(grep -o 'implicit: [0-9]* shell elements' "$log" | grep -o '[0-9]*')
    bonds=$(grep -o 'shell elements, [0-9]* bonds' "$log" | grep -o '[0-9]*')
    per_step=$(awk '/^  increments/ {print $2}' "$log" | head -1)
    per_step=$(awk -v s="$seconds" -v n="$per_step" 'BEGIN {printf "%.4g", s / n}')
    result=$(awk '/max displacement/ {print $3}' "$log")
  else
    shells=$(grep -oE 'bonds, [0-9]+' "$log" | head -1 | grep -oE '[0-9]+')
    bonds=$(grep -o 'PD nodes, [0-9]* bonds' "$log" | grep -o '[0-9]*' | tail -1)
    per_step=$(grep -o '[0-9.e+-]* s per step' "$log" | head -1 | awk '{print $1}')
    result=$(awk '/broken bonds/ {print $3}' "$log")
  fi
  echo "$case,$ratio,$percent,$shells,$bonds,$seconds,$per_step,$result" >> "$csv.tmp"
  echo "ratio $ratio: $seconds s, result $result" >&2
done
mv "$csv.tmp" "$csv"
cat "$csv"
