#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, Debian's clang, ASan + UBSan) in build-fuzz and runs each for
# SECONDS (default 20: the short run CI does; docs/reliability.md gives the long run's command).
# New inputs that found coverage go to build-fuzz/corpus/<target>; crashes to build-fuzz/crashes.
# Usage: scripts/fuzz.sh [SECONDS] [TARGET...]   (targets: recording stroke_csv config cut_engine)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-20}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(recording stroke_csv config cut_engine)
source scripts/build_env.sh
tachi_configure build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DTACHI_FUZZ=ON -DBUILD_TESTING=OFF
cmake --build build-fuzz -j"$(nproc)" --target "${targets[@]/%/_fuzz}"
mkdir -p build-fuzz/crashes
# Each target is one process on one core: two run at once (nproc at most), each for the whole SECONDS,
# its last lines (the final stats, or the crash) printed when it ends. Any target's failure fails the run.
parallel=$(nproc); [ "$parallel" -le 2 ] || parallel=2
logs=$(mktemp -d)
trap 'rm -rf "$logs"' EXIT
fuzz_one() {  # TARGET
  local t=$1 status=0
  mkdir -p "build-fuzz/corpus/$t"
  # -max_len: a depth frame's header and a few rows are what the parsers branch on.
  "build-fuzz/bin/${t}_fuzz" -max_total_time="$seconds" -max_len=4096 -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix="build-fuzz/crashes/${t}-" -print_final_stats=1 \
    "build-fuzz/corpus/$t" "fuzz/corpus/$t" >"$logs/$t.log" 2>&1 || status=$?
  echo "$status" >"$logs/$t.status"
}
running=0
for t in "${targets[@]}"; do
  if [ "$running" -ge "$parallel" ]; then wait -n || true; running=$((running - 1)); fi
  echo "fuzz: $t for ${seconds} s" >&2
  fuzz_one "$t" &
  running=$((running + 1))
done
wait
failed=()
for t in "${targets[@]}"; do
  echo "--- fuzz: $t" >&2
  tail -n 12 "$logs/$t.log" >&2
  [ "$(cat "$logs/$t.status" 2>/dev/null)" = 0 ] || failed+=("$t")
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz.sh: failed: ${failed[*]} (inputs in build-fuzz/crashes)" >&2
  exit 1
fi
