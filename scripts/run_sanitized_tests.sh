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
failed=()
for t in "${tests[@]}"; do
  echo "sanitized: $t" >&2
  "build-asan/bin/$t" --gtest_brief=1 --gtest_filter="${filter[$t]:-*}" || failed+=("$t")
done
echo "sanitized: tachi_sensor_tests, one randomized clip" >&2
build-asan/bin/tachi_sensor_tests --gtest_brief=1 --gtest_filter=RandomScene.ANewTrackIsMeasuredAtTheArmsEndNotOnItsForearm ||
  failed+=("tachi_sensor_tests (RandomScene)")
if [ ${#failed[@]} -gt 0 ]; then
  echo "run_sanitized_tests.sh: failed: ${failed[*]}" >&2
  exit 1
fi
