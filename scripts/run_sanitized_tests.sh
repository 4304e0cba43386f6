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
# Two binaries at a time, the longest first (sim_test ~60 s sanitized, sim_cut_test, filter_test and the
# sensor tests ~45 s each; one after another they took ~230 s of CI's wall time).
jobs=("sim_test" "sim_cut_test" "filter_test" "tachi_sensor_tests"
      "tachi_sensor_tests:RandomScene.ANewTrackIsMeasuredAtTheArmsEndNotOnItsForearm"
      "bus_test" "viewer_test" "common_test" "reliability_unit_test" "bad_files_test")
for t in "${tests[@]}"; do
  [[ " ${jobs[*]} " == *" $t "* ]] || { echo "run_sanitized_tests.sh: $t is built but not run" >&2; exit 2; }
done
run_one() {  # BINARY, or BINARY:FILTER for some of its tests
  local binary=${1%%:*} only=${1#*:}
  [ "$only" != "$1" ] || only=${filter[$binary]:-*}
  "build-asan/bin/$binary" --gtest_brief=1 --gtest_filter="$only"
}
source scripts/two_at_a_time.sh
two_at_a_time sanitized run_one cat "${jobs[@]}" || exit 1
