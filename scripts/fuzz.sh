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
fuzz_one() {  # TARGET, for its SECONDS
  mkdir -p "build-fuzz/corpus/$1"
  # -max_len: a depth frame's header and a few rows are what the parsers branch on.
  "build-fuzz/bin/${1}_fuzz" -max_total_time="$seconds" -max_len=4096 -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix="build-fuzz/crashes/${1}-" -print_final_stats=1 "build-fuzz/corpus/$1" "fuzz/corpus/$1"
}
# Two targets at a time, each on a core of its own for the whole SECONDS; each one's last lines (the final
# stats, or the crash) shown when all have ended. Any target's failure fails the run.
source scripts/two_at_a_time.sh
two_at_a_time "fuzz (${seconds} s each)" fuzz_one "tail -n 12" "${targets[@]}" ||
  { echo "fuzz.sh: inputs that failed are in build-fuzz/crashes" >&2; exit 1; }
