#!/usr/bin/env bash
# The pipeline across two hosts: tachi-sensor on host A; tachi-filter, tachi-sim and tachi-viewer on
# host B. The hosts are network namespaces this test makes (a veth pair, TEST-NET-2 addresses,
# nothing routed anywhere else), each running config/cyclonedds-multihost.xml filled in for it.
# The sensor plays at twice the recorded pace: nothing here measures it.
# Usage: multihost_test.sh BIN_DIR RECORDING CONFIG_TEMPLATE    (exit 77 = skipped: needs root + ip netns)
set -u
bin=$1 recording=$2 template=$3
prefix=v
source "$(dirname "$0")/../support/two_hosts.sh"
dom=100
# exec: a backgrounded call is then the program itself, so its PID takes our signals.
on_b() { exec ip netns exec "$b" "$@" --domain $dom --dds-config "$work/$if_b.xml"; }

on_b "$bin/tachi-sim" --grid 32 --pin top-edge --exit-when-idle 2 --export "$work/out" 2>"$work/sim.log" & sim=$!; pids+=("$sim")
on_b "$bin/tachi-viewer" --headless --snapshot "$work/final.png" --fps 10 --exit-when-idle 3 2>"$work/viewer.log" & viewer=$!; pids+=("$viewer")
on_b "$bin/tachi-filter" --gate threshold 2>"$work/filter.log" & filter=$!; pids+=("$filter")
ip netns exec "$a" timeout 120 "$bin/tachi-sensor" --recording "$recording" --rate 2 --domain $dom \
  --dds-config "$work/$if_a.xml" --wait-readers 1 2>"$work/sensor.log"
sensor_status=$?
wait "$sim"; sim_status=$?
wait "$viewer"; viewer_status=$?
kill -INT "$filter"; wait "$filter"; filter_status=$?
pids=()

fail() { echo "FAIL: $*"; for f in "$work"/*.log; do echo "--- $f"; tail -5 "$f"; done; exit 1; }
[ "$sensor_status" -eq 0 ] || fail "tachi-sensor on host A exited $sensor_status"
[ "$sim_status" -eq 0 ] || fail "tachi-sim on host B exited $sim_status"
[ "$viewer_status" -eq 0 ] || fail "tachi-viewer on host B exited $viewer_status"
[ "$filter_status" -eq 0 ] || fail "tachi-filter on host B exited $filter_status"
[ -f "$work/out/summary.json" ] || fail "no summary.json"
[ -f "$work/final.png" ] || fail "no viewer snapshot"
python3 - "$work/out/summary.json" <<'PY' || fail "summary: $(cat "$work/out/summary.json" | head -c 600)"
import json, sys
s = json.load(open(sys.argv[1]))
assert s["hand_samples"] > 60, "the hand samples crossed from host A"
assert s["cut_particles"] > 5, "the stroke cut the cloth"
rows = {v for _, v in s["cut_line"]}
assert rows and min(rows) >= 12 and max(rows) <= 19, f"the cut follows the hand at mid height: rows {sorted(rows)}"
PY
echo "pipeline across two hosts: $(python3 -c "import json;s=json.load(open('$work/out/summary.json'));print(s['hand_samples'],'hand samples,',s['cut_particles'],'particles cut')")"
