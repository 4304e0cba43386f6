#!/usr/bin/env bash
# Builds the unit tests with AddressSanitizer + UndefinedBehaviorSanitizer (-DTACHI_SANITIZE=ON) in
# build-asan and runs them; any sanitizer report fails the run. The unit tests only (docs/reliability.md):
# the multi-process tests run in the normal build. Exit status 0 when all passed clean.
set -euo pipefail
cd "$(dirname "$0")/.."
tests=(common_test bus_test sim_test sim_cut_test filter_test viewer_test tachi_sensor_tests reliability_unit_test
       bad_files_test)
source scripts/build_env.sh
# The recordings the Release tree rendered (run_tests.sh runs first); rendered here only without it.
recordings=()
[ -f build/recordings/straight_cut/ground_truth.csv ] && recordings=(-DTACHI_RECORDINGS_FROM="$PWD/build/recordings")
tachi_configure build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTACHI_SANITIZE=ON "${recordings[@]}"
cmake --build build-asan -j"$(nproc)" --target "${tests[@]}" tachi_recordings
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# The randomized-world tests score whole clips (12-64 s each sanitized, ~5 of the CI's 14 minutes); one
# of them runs sanitized, the rest in the normal suite (docs/reliability.md, "Fuzzing and sanitizers").
declare -A filter=([tachi_sensor_tests]='*-RandomScene.*:Evaluation.ARandomClip*')
# Each binary is one process on one core: they run two at a time (nproc at most), the longest first (sim_test
# ~60 s, sim_cut_test, filter_test and the sensor tests ~45 s each sanitized; run one after another they took
# ~230 s of CI's wall time). Each one's output is kept apart and printed whole when it ends.
jobs=("sim_test" "sim_cut_test" "filter_test" "tachi_sensor_tests"
      "tachi_sensor_tests:RandomScene.ANewTrackIsMeasuredAtTheArmsEndNotOnItsForearm"
      "bus_test" "viewer_test" "common_test" "reliability_unit_test" "bad_files_test")
for t in "${tests[@]}"; do
  [[ " ${jobs[*]} " == *" $t "* ]] || { echo "run_sanitized_tests.sh: $t is built but not run" >&2; exit 2; }
done
parallel=$(nproc); [ "$parallel" -le 2 ] || parallel=2
logs=$(mktemp -d)
trap 'rm -rf "$logs"' EXIT
run_one() {  # JOB INDEX: a binary, or BINARY:FILTER for one of its tests
  local binary=${1%%:*} only=${1#*:}
  [ "$only" != "$1" ] || only=${filter[$binary]:-*}
  local status=0
  "build-asan/bin/$binary" --gtest_brief=1 --gtest_filter="$only" >"$logs/$2.log" 2>&1 || status=$?
  echo "$status" >"$logs/$2.status"
}
running=0
for i in "${!jobs[@]}"; do
  if [ "$running" -ge "$parallel" ]; then wait -n || true; running=$((running - 1)); fi
  echo "sanitized: ${jobs[$i]}" >&2
  run_one "${jobs[$i]}" "$i" &
  running=$((running + 1))
done
wait
failed=()
for i in "${!jobs[@]}"; do
  echo "--- sanitized: ${jobs[$i]}" >&2
  cat "$logs/$i.log" >&2
  [ "$(cat "$logs/$i.status" 2>/dev/null)" = 0 ] || failed+=("${jobs[$i]}")
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "run_sanitized_tests.sh: failed: ${failed[*]}" >&2
  exit 1
fi
