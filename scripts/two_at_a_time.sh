#!/usr/bin/env bash
# Sourced by the CI scripts (run_sanitized_tests.sh, fuzz.sh): their jobs are single processes on one core
# each, so two at a time halve their wall time on CI's two cores.

# two_at_a_time LABEL RUN SHOW ITEM...: runs `RUN ITEM` for each ITEM, at most two (and at most nproc) at
# once, in the order given (put the longest first); each one's output is kept apart and shown through SHOW
# (a command given the log's path, e.g. `cat` or `tail -n 12`) once all have ended. Returns 1 naming the
# items that failed, if any did.
two_at_a_time() {
  local label=$1 run=$2 show=$3
  shift 3
  local items=("$@") logs parallel running=0 i
  parallel=$(nproc)
  [ "$parallel" -le 2 ] || parallel=2
  logs=$(mktemp -d)
  for i in "${!items[@]}"; do
    if [ "$running" -ge "$parallel" ]; then
      wait -n || true
      running=$((running - 1))
    fi
    echo "$label: ${items[$i]}" >&2
    (
      status=0
      "$run" "${items[$i]}" >"$logs/$i.log" 2>&1 || status=$?
      echo "$status" >"$logs/$i.status"
    ) &
    running=$((running + 1))
  done
  wait
  local failed=()
  for i in "${!items[@]}"; do
    echo "--- $label: ${items[$i]}" >&2
    $show "$logs/$i.log" >&2
    [ "$(cat "$logs/$i.status" 2>/dev/null)" = 0 ] || failed+=("${items[$i]}")
  done
  rm -rf "$logs"
  if [ ${#failed[@]} -gt 0 ]; then
    echo "$label: failed: ${failed[*]}" >&2
    return 1
  fi
}
