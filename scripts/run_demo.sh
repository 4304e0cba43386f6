#!/usr/bin/env bash
# README command (1): sets up a fresh Debian bookworm machine (as root) with only what a run needs, builds
# only the executables `tachi run` starts and the one recording it plays, and plays it through the whole
# pipeline (sensor, filter, simulator, headless viewer as supervised processes on DDS domain 120, loopback
# only). Prints the run's summary and the output folder (summary.json, cloth.obj, final.png, latency.png,
# trajectory.png, each process's log). Tests, benchmarks and their toolchain: scripts/run_tests.sh.
# Usage: scripts/run_demo.sh [SCENARIO] [more `tachi run` flags]
#        SCENARIO: straight_cut (default), curve, top_edge, push, jitter, ... (recordings/scenarios/*.json)
set -euo pipefail
cd "$(dirname "$0")/.."
scenario=${1:-straight_cut}
[ $# -gt 0 ] && shift
[ -f "recordings/scenarios/$scenario.json" ] || {
  echo "run_demo.sh: no scenario '$scenario' (scenarios: $(cd recordings/scenarios && ls *.json | sed 's/\.json$//' | tr '\n' ' '))" >&2
  exit 2
}
started=$SECONDS
echo "run_demo.sh: [1/3] packages (scripts/setup.sh --demo)" >&2
bash scripts/setup.sh --demo
echo "run_demo.sh: [2/3] building tachi, its nodes and the $scenario recording ($((SECONDS - started)) s so far)" >&2
source scripts/build_env.sh
# A tree that is configured already keeps its BUILD_TESTING (run_tests.sh turns it on); a new one
# builds no tests, so the test toolchain is not needed.
testing=()
[ -f build/CMakeCache.txt ] || testing=(-DBUILD_TESTING=OFF)
tachi_configure build -DCMAKE_BUILD_TYPE=Release "${testing[@]}"
cmake --build build -j"$(nproc)" --target tachi "tachi_recording_$scenario"
echo "run_demo.sh: [3/3] tachi run on build/recordings/$scenario ($((SECONDS - started)) s so far)" >&2
exec build/bin/tachi run --recording "build/recordings/$scenario" --headless --domain "${TACHI_DEMO_DOMAIN:-120}" --out "out/demo-$scenario" "$@"
