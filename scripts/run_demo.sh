#!/usr/bin/env bash
# README command (1): sets up a fresh Debian bookworm machine (as root), builds tachi, and plays a
# bundled recording through the whole pipeline with `tachi run` (sensor, filter, simulator, headless
# viewer as supervised processes on DDS domain 120, loopback only). Prints the run's summary and the
# output folder (summary.json, cloth.obj, final.png, latency.png, trajectory.png, each process's log).
# Usage: scripts/run_demo.sh [SCENARIO] [more `tachi run` flags]
#        SCENARIO: straight_cut (default), curve, top_edge, push, jitter
set -euo pipefail
cd "$(dirname "$0")/.."
scenario=${1:-straight_cut}
[ $# -gt 0 ] && shift
bash scripts/setup.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"

recording=build/recordings/$scenario
[ -f "$recording/INDEX.txt" ] || { echo "run_demo.sh: no recording $recording (scenarios: $(ls build/recordings | grep -v -E 'CMake|Makefile|cmake' | tr '\n' ' '))" >&2; exit 2; }
exec build/bin/tachi run --recording "$recording" --headless --domain "${TACHI_DEMO_DOMAIN:-120}" --out "out/demo-$scenario" "$@"
