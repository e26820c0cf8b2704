#!/usr/bin/env bash
# A SIGTERM during a run (issue 22): the run stops after its current step with that step
# written, prints its summary, says why on stderr and exits 143; history.csv holds its rows so
# far as the run goes (checked before the signal is sent).
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
[ "$fail" -eq 0 ] && echo "OK: stopped at step $last with exit 143, $(($(wc -l < "$work/out/history.csv") - 1)) history rows"
[ "$fail" -eq 0 ] || { cat "$work/stdout" "$work/stderr"; }
exit "$fail"
