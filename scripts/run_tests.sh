#!/usr/bin/env bash
# Sets up a fresh Debian bookworm machine (as root), builds tachi and runs the whole test suite.
# Exit status: 0 when every test passed.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
source scripts/build_env.sh
tachi_configure build -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=ON -DTACHI_BENCH=ON
cmake --build build -j"$(nproc)"
ctest --test-dir build -j"$(nproc)" --output-on-failure --timeout 600
