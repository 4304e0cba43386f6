#!/bin/sh
# Renders docs/cutting.md's side-by-side images with tachi-sim itself: the same two strokes cut in the three
# --cut-mode's on a 64 x 64 cloth pinned along its top edge; each run's pattern.svg is copied here and its
# summary figures are written to README.md. Usage: docs/images/cut_modes/make.sh [build dir, default build]
set -eu
here=$(cd "$(dirname "$0")" && pwd)
sim=${1:-build}/bin/tachi-sim
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 - "$work" <<'PY'
import math, sys
work = sys.argv[1]
with open(f"{work}/diagonal.csv", "w") as f:
    f.write("t,x,y,z\n")
    for i in range(61):
        s = i / 60
        f.write(f"{0.05 + s:.4f},{-0.6 + 1.2 * s:.4f},{0.35 - 0.8 * s:.4f},0.0\n")
with open(f"{work}/wavy.csv", "w") as f:
    f.write("t,x,y,z\n")
    for i in range(65):
        s = i / 64
        f.write(f"{0.05 + s:.4f},{-0.56 + 1.12 * s:.4f},{-0.05 + 0.15 * math.sin(2 * math.pi * 1.5 * s):.4f},0.0\n")
PY
{
  echo "# Three cut modes on the same strokes (written by make.sh)"
  echo
  echo "| mode | stroke | pieces | particles | cut_deviation_cells_max | cut_length_m | max_strain (end of run) |"
  echo "|---|---|---|---|---|---|---|"
} > "$here/README.md"
for stroke in diagonal wavy; do
  for mode in exact grid delete; do
    "$sim" --offline --cut-mode "$mode" --grid 64 --pin top-edge --stroke "$work/$stroke.csv" --steps 600 \
      --export "$work/$mode-$stroke" --log-level warn
    cp "$work/$mode-$stroke/pattern.svg" "$here/${mode}_$stroke.svg"
    python3 - "$work/$mode-$stroke/summary.json" "$mode" "$stroke" >> "$here/README.md" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
print(f"| {sys.argv[2]} | {sys.argv[3]} | {d['pieces']} | {d['particles']} | {d['cut_deviation_cells_max']:.3f} | "
      f"{d['cut_length_m']:.3f} | {d['max_strain']:.3f} |")
PY
  done
done
