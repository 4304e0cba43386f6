#!/usr/bin/env bash
# Sets up a fresh Debian bookworm machine (as root), builds tachi, and runs the main job: the whole
# pipeline as separate processes on the DDS bus (loopback only), fed by a bundled recording.
#   tachi-sensor (recording -> palm centre) -> tachi-filter (smoothing, threshold gate)
#   -> tachi-sim (cloth, cutting) -> tachi-viewer (headless, writes the last frame as PNG)
# Usage: scripts/run_demo.sh [SCENARIO]   (straight_cut, curve, top_edge, push, jitter; default straight_cut)
set -euo pipefail
cd "$(dirname "$0")/.."
scenario=${1:-straight_cut}
bash scripts/setup.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"

recording=build/recordings/$scenario
[ -f "$recording/INDEX.txt" ] || { echo "run_demo.sh: no recording $recording (scenarios: $(ls build/recordings | grep -v -E 'CMake|Makefile|cmake' | tr '\n' ' '))" >&2; exit 2; }
out=out/demo-$scenario
rm -rf "$out" && mkdir -p "$out"
domain=${TACHI_DEMO_DOMAIN:-120}
pids=()
trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done' EXIT

echo "== pipeline on $recording (DDS domain $domain, loopback only); logs in $out/"
build/bin/tachi-sim --grid 64 --pin top-edge --domain "$domain" --exit-when-idle 2 --export "$out" 2>"$out/sim.log" & sim=$!; pids+=("$sim")
build/bin/tachi-viewer --headless --domain "$domain" --snapshot "$out/final.png" --frames-dir "$out/frames" --fps 10 \
  --exit-when-idle 3 2>"$out/viewer.log" & viewer=$!; pids+=("$viewer")
build/bin/tachi-filter --domain "$domain" --gate threshold 2>"$out/filter.log" & filter=$!; pids+=("$filter")
build/bin/tachi-sensor --recording "$recording" --rate 1 --domain "$domain" --wait-readers 1 --csv "$out/hands.csv" 2>"$out/sensor.log"
wait "$sim"
wait "$viewer"
kill -INT "$filter"; wait "$filter"
pids=()

echo "== results (computed by the run above)"
tail -n 1 "$out/sensor.log"
tail -n 1 "$out/filter.log"
grep -E "stroke [0-9]+ cut" "$out/sim.log" || echo "tachi-sim: no stroke cut the cloth"
python3 - "$out/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print(f"cloth {s['columns']}x{s['rows']}: {s['particles']} particles, {s['pieces']} piece(s), "
      f"{s['fallen_pieces']} falling; {s['cut_particles']} particles duplicated along {s['cut_length_m']:.3f} m of cut; "
      f"median step {s['step_ms_median']:.3f} ms")
print("cut line (u, v):", " ".join(f"({u},{v})" for u, v in s["cut_line"]))
PY
echo "mesh: $out/cloth.obj   summary: $out/summary.json   last frame: $out/final.png   frames: $out/frames/"
