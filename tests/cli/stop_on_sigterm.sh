#!/usr/bin/env bash
# A SIGTERM during a run (issue 22): the run stops after its current step with that step
# written, writes a checkpoint, prints its summary, says why on stderr and exits 143;
# history.csv holds its rows so far as the run goes (checked before the signal is sent). The
# stopped run is then continued with --restart for 300 more steps: its history goes on from the
# checkpoint, no step twice.
# Usage: stop_on_sigterm.sh APP DECK WORKDIR
set -u
app=$1 deck=$2 work=$3
rm -rf "$work"; mkdir -p "$work"
# The shipped strip made long (2,000,000 steps): the signal comes long before its end.
sed -e 's/^    steps: 200$/    steps: 2000000/' -e 's/^    every: 100$/    every: 1000000/' "$deck" > "$work/long_strip.yaml"
grep -q "steps: 2000000" "$work/long_strip.yaml" || { echo "FAIL: could not lengthen $deck"; exit 1; }
"$app" run "$work/long_strip.yaml" --output "$work/out" > "$work/stdout" 2> "$work/stderr" &
pid=$!
# Rows appear while the run goes: wait for 3 (the initial state and 2 more).
for _ in $(seq 1 600); do
  [ -f "$work/out/history.csv" ] && [ "$(wc -l < "$work/out/history.csv")" -ge 4 ] && break
  kill -0 "$pid" 2> /dev/null || break
  sleep 0.1
done
rows_before=$(wc -l < "$work/out/history.csv" 2> /dev/null || echo 0)
[ "$rows_before" -ge 4 ] || { echo "FAIL: history.csv had $rows_before lines while the run went"; cat "$work/stdout" "$work/stderr"; kill "$pid"; exit 1; }
kill -TERM "$pid"
wait "$pid"; rc=$?
fail=0
[ "$rc" -eq 143 ] || { echo "FAIL: exit status $rc, expected 143"; fail=1; }
grep -q "explicit run summary" "$work/stdout" || { echo "FAIL: no summary"; fail=1; }
grep -Eq "steps +[0-9]+ of 2000000 \(stopped by SIGTERM\)" "$work/stdout" || { echo "FAIL: the summary does not say it stopped"; fail=1; }
grep -q "perishell: stopped by SIGTERM before the deck's end" "$work/stderr" || { echo "FAIL: no stop message on stderr"; fail=1; }
# The stop step is the last history row and, with the initial state, the only field step.
last=$(tail -n 1 "$work/out/history.csv" | cut -d, -f1)
[ "$(grep -c '<Grid Name="step_' "$work/out/results.xmf")" -eq 2 ] || { echo "FAIL: results.xmf should hold the initial and the stop step"; fail=1; }
ls "$work/out" | grep -q "tmp\." && { echo "FAIL: temporaries left"; fail=1; }
[ -f "$work/out/checkpoint.h5" ] || { echo "FAIL: no checkpoint.h5"; fail=1; }
grep -q "continue with: .* run $work/long_strip.yaml --restart $work/out" "$work/stderr" || { echo "FAIL: stderr does not say how to continue"; fail=1; }
stopped_rows=$(($(wc -l < "$work/out/history.csv") - 1))
if [ "$fail" -eq 0 ]; then
  "$app" run "$work/long_strip.yaml" --restart "$work/out" --max-steps $((last + 300)) > "$work/restart_stdout" 2>&1; rc=$?
  [ "$rc" -eq 0 ] || { echo "FAIL: the restart exited $rc"; cat "$work/restart_stdout"; fail=1; }
  grep -q "restart: continuing from step $last (t = " "$work/restart_stdout" || { echo "FAIL: the restart does not say where it continues"; fail=1; }
  grep -Eq "steps +$((last + 300)) of 2000000" "$work/restart_stdout" || { echo "FAIL: the continued run did not end at step $((last + 300))"; fail=1; }
  steps=$(tail -n +2 "$work/out/history.csv" | cut -d, -f1)
  [ "$(printf '%s\n' "$steps" | sort -n -u | wc -l)" -eq "$(printf '%s\n' "$steps" | wc -l)" ] || { echo "FAIL: a history step appears twice"; fail=1; }
  [ "$(printf '%s\n' "$steps" | tail -n 1)" -eq $((last + 300)) ] || { echo "FAIL: the last history row is not step $((last + 300))"; fail=1; }
fi
[ "$fail" -eq 0 ] && echo "OK: stopped at step $last with exit 143, $stopped_rows history rows; continued to step $((last + 300))"
[ "$fail" -eq 0 ] || { cat "$work/stdout" "$work/stderr"; }
exit "$fail"
