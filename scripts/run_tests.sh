#!/usr/bin/env bash
# Sets up a fresh Debian bookworm machine (as root), builds tachi and runs the whole test suite.
# Exit status: 0 when every test passed.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
source scripts/build_env.sh
tachi_configure build -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=ON -DTACHI_BENCH=ON
cmake --build build -j"$(nproc)"
# One test more than the cores: the end-to-end tests spend much of their time waiting on a recording's pace
# (a fresh clone's suite on 2 cores: 289 s at 2 jobs, 218 and 249 s at 3, the CPU 170 % busy).
ctest --test-dir build -j"$(( $(nproc) + 1 ))" --output-on-failure --timeout 600
