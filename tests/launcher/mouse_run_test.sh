#!/usr/bin/env bash
# `tachi run --mouse` as a user runs it, under a virtual display: the launcher starts only tachi-sim and
# tachi-viewer --mouse; a mouse drag across the window (xdotool) cuts the cloth; `q` closes the window,
# which ends the run with its outputs written. The same with `--in-process` (the viewer's window on a
# thread of tachi-pipeline), side by side: each on its own display and domain, as each mostly waits.
# Usage: mouse_run_test.sh BIN_DIR   (exit 77 = skipped: Xvfb or xdotool missing)
set -u
bin=$1
command -v Xvfb >/dev/null && command -v xdotool >/dev/null || { echo "skip: needs Xvfb and xdotool"; exit 77; }

# One run of `tachi run --mouse` in MODE (processes | in-process) on its own virtual display.
mouse_run() {
  local mode=$1 domain=131 extra=() viewer_log=viewer.log
  if [ "$mode" = in-process ]; then domain=139 extra=(--in-process) viewer_log=pipeline.log; fi
  # Not local: the EXIT trap runs when the subshell ends, after this function has returned, when its
  # locals are gone (it killed nothing and removed nothing: every run left its Xvfb and folder behind).
  # Each mode runs in a subshell of its own, so these are its own.
  work="" pids=() xvfb=""
  local n
  work=$(mktemp -d "/tmp/tachi-mouse-run-$mode-XXXXXX")
  trap 'for p in "${pids[@]}" $xvfb; do kill "$p" 2>/dev/null; done; wait 2>/dev/null; rm -rf "$work"' EXIT
  # A display number no other X server (or the other mode's) holds: Xvfb takes the lock or fails.
  for n in $(seq $((600 + ($$ + domain) % 300)) 999); do
    [ -e "/tmp/.X$n-lock" ] && continue
    # -noreset: an X server resets when its last client leaves (an xdotool search before the viewer is up) and
    # refuses connections meanwhile (viewer_window_test.cpp).
    Xvfb ":$n" -screen 0 1024x900x24 -nolisten tcp -noreset >/dev/null 2>&1 & xvfb=$!
    for _ in $(seq 100); do [ -S "/tmp/.X11-unix/X$n" ] && break; kill -0 $xvfb 2>/dev/null || break; sleep 0.05; done
    kill -0 $xvfb 2>/dev/null && break
  done
  export DISPLAY=":$n"

  timeout 120 "$bin/tachi" run --mouse --grid 16 --domain $domain --out "$work/run" --set viewer.size=600 \
    --set sim.cut-mode=grid "${extra[@]}" >"$work/out" 2>"$work/err" & local run=$!; pids+=("$run")
  fail() { echo "FAIL ($mode): $*"; cat "$work/err"; for f in "$work"/run/*.log; do echo "--- $f"; tail -5 "$f"; done; exit 1; }
  local window=""
  for _ in $(seq 200); do window=$(xdotool search --onlyvisible --name '^tachi$' 2>/dev/null | head -1); [ -n "$window" ] && break; sleep 0.1; done
  [ -n "$window" ] || fail "no viewer window"
  # The viewer has the cloth to cast the cursor onto once its heartbeat counts samples in (cloth states).
  for _ in $(seq 60); do
    "$bin/tachi" status --domain $domain --listen 0.3 2>/dev/null | grep -Eq "^tachi-viewer .* in [1-9]" && break
  done
  eval "$(xdotool getwindowgeometry --shell "$window")"  # WIDTH, HEIGHT
  local y=$((HEIGHT * 58 / 100)) i
  xdotool mousemove --window "$window" $((WIDTH / 20)) $y mousedown 1
  for i in $(seq 1 30); do xdotool mousemove --window "$window" $((WIDTH / 20 + WIDTH * 9 * i / 300)) $y; sleep 0.03; done
  xdotool mouseup 1
  sleep 1.5
  # `p` saves a snapshot into the run's --out (not the folder tachi was started in): wait for it.
  xdotool key --window "$window" p
  for i in $(seq 1 100); do [ -e "$work/run/tachi_snapshot_1.png" ] && break; sleep 0.05; done
  [ -e "$work/run/tachi_snapshot_1.png" ] || fail "p saved no snapshot into --out: $(ls "$work/run")"
  xdotool key --window "$window" q
  wait "$run"; local status=$?
  pids=()
  [ "$status" -eq 0 ] || fail "tachi run --mouse exited $status"
  [ ! -e "$work/run/sensor.log" ] || fail "the mouse run started a sensor"
  grep -q -- "--mouse" "$work/run/$viewer_log" || fail "the viewer did not get --mouse"
  [ -s "$work/run/video.mp4" ] || fail "no video.mp4"
  python3 - "$work/run/summary.json" <<'PY' || fail "summary: $(head -c 600 "$work/run/summary.json")"
import json, sys
s = json.load(open(sys.argv[1]))
assert s["ended"] == "viewer window closed", s["ended"]
assert s["cuts"] >= 1, "the mouse drag cut the cloth"
assert s["strokes"] >= s["cuts"], ("the mouse blade's strokes count as strokes", s["strokes"], s["cuts"])
assert s["cut_particles"] > 3, s["cut_particles"]
PY
  echo "tachi run --mouse${extra[*]:+ ${extra[*]}}: $(python3 -c "import json;s=json.load(open('$work/run/summary.json'));print(s['cuts'],'cut(s),',s['cut_particles'],'particles,',s['pieces'],'pieces')")"
}

( mouse_run processes ) & processes=$!
( mouse_run in-process ) & in_process=$!
wait $processes; a=$?
wait $in_process; b=$?
[ $a -eq 0 ] && [ $b -eq 0 ]
