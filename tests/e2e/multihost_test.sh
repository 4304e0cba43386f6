#!/usr/bin/env bash
# The pipeline across two hosts: tachi-sensor on host A; tachi-filter, tachi-sim and tachi-viewer on
# host B. The hosts are network namespaces this test makes (a veth pair, TEST-NET-2 addresses,
# nothing routed anywhere else), each running config/cyclonedds-multihost.xml filled in for it.
# Usage: multihost_test.sh BIN_DIR RECORDING CONFIG_TEMPLATE    (exit 77 = skipped: needs root + ip netns)
set -u
bin=$1 recording=$2 template=$3
[ "$(id -u)" -eq 0 ] || { echo "skip: needs root for ip netns"; exit 77; }
command -v ip >/dev/null || { echo "skip: needs iproute2"; exit 77; }

a="tachi-host-a-$$" b="tachi-host-b-$$"
work=$(mktemp -d /tmp/tachi-multihost-XXXXXX)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
  ip netns del "$a" 2>/dev/null; ip netns del "$b" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
ip netns add "$a" && ip netns add "$b" || { echo "skip: cannot create network namespaces"; exit 77; }
ip link add "va$$" netns "$a" type veth peer name "vb$$" netns "$b" || { echo "skip: cannot create veth"; exit 77; }
ip -n "$a" addr add 198.51.100.1/24 dev "va$$"; ip -n "$b" addr add 198.51.100.2/24 dev "vb$$"
for ns in "$a" "$b"; do ip -n "$ns" link set lo up; done
ip -n "$a" link set "va$$" up; ip -n "$b" link set "vb$$" up

fill() {  # interface -> config file for that host
  sed -e "s/INTERFACE/$1/" -e "s/HOST_A_ADDRESS/198.51.100.1/" -e "s/HOST_B_ADDRESS/198.51.100.2/" "$template" > "$work/$1.xml"
}
fill "va$$"; fill "vb$$"
dom=100
# exec: a backgrounded call is then the program itself, so its PID takes our signals.
on_b() { exec ip netns exec "$b" "$@" --domain $dom --dds-config "$work/vb$$.xml"; }

on_b "$bin/tachi-sim" --grid 32 --pin top-edge --exit-when-idle 2 --export "$work/out" 2>"$work/sim.log" & sim=$!; pids+=("$sim")
on_b "$bin/tachi-viewer" --headless --snapshot "$work/final.png" --fps 10 --exit-when-idle 3 2>"$work/viewer.log" & viewer=$!; pids+=("$viewer")
on_b "$bin/tachi-filter" --gate threshold 2>"$work/filter.log" & filter=$!; pids+=("$filter")
ip netns exec "$a" timeout 120 "$bin/tachi-sensor" --recording "$recording" --rate 1 --domain $dom \
  --dds-config "$work/va$$.xml" --wait-readers 1 2>"$work/sensor.log"
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
