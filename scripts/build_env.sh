#!/usr/bin/env bash
# Sourced by the build scripts: one way to configure a build tree, so every tree (Release, ASan, fuzz)
# is built by Ninja through ccache. The cache lives in the home folder and is keyed on paths relative
# to the checkout (CCACHE_BASEDIR + CCACHE_NOHASHDIR), so a fresh clone elsewhere (CI) reuses what a
# session compiled. Each tree renders no recordings of its own when TACHI_RECORDINGS_FROM names the
# Release tree's (see recordings/CMakeLists.txt).
export CCACHE_DIR=${CCACHE_DIR:-$HOME/.cache/ccache}
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$PWD}
export CCACHE_NOHASHDIR=1
export CCACHE_MAXSIZE=${CCACHE_MAXSIZE:-8G}
# The sloppiness that makes precompiled headers cacheable (CMake's target_precompile_headers).
export CCACHE_SLOPPINESS=${CCACHE_SLOPPINESS:-pch_defines,time_macros,include_file_mtime,include_file_ctime}

# tachi_configure DIR [cmake args...]: configures DIR with Ninja and ccache (when installed).
tachi_configure() {
  local dir=$1; shift
  local launcher=()
  if command -v ccache >/dev/null 2>&1; then
    launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  fi
  local generator=(-G Ninja)
  # A tree configured earlier with another generator keeps it (CMake refuses to switch).
  if [ -f "$dir/CMakeCache.txt" ]; then
    generator=()
  fi
  cmake -S . -B "$dir" "${generator[@]}" "${launcher[@]}" "$@" >/dev/null
}
