#!/usr/bin/env bash
# The project's shape, checked: a stage (sim, filter, sensor, viewer, launcher) includes only its own
# headers, idl/'s (tachi/bus/) and common/'s (tachi/common/) -- never another stage's -- and every
# executable's main file stays a thin main (<= 40 lines: flags, a node, run_until_signal). pipeline/
# (tachi-pipeline, `tachi run --in-process`) is the composition root: it alone includes every stage's
# flags ("sim/cli.hpp", ...), and its main is thin too.
# Usage: layering_test.sh SOURCE_DIR {includes|mains}. Exit 1 naming each file that breaks the rule.
set -euo pipefail
src=${1:?source dir}
what=${2:?includes or mains}
stages=(sim filter sensor viewer launcher)

# Known exceptions, each with its reason; the check fails when one is no longer needed, so the list only shrinks.
#   sim/src/object.cpp reads a fakenect recording to build the object under the cloth (tachi_sim_object, kept out
#   of tachi_sim); the way out is the recording reader in common/.
allowed_includes=(
  "sim/src/object.cpp:tachi/sensor/depth_model.hpp"
  "sim/src/object.cpp:tachi/sensor/fakenect_recording.hpp"
)
allowed_mains=()  # none left: every main, the tools' too, is flags and a call into its library

failures=0
fail() { echo "layering: $*" >&2; failures=$((failures + 1)); }
contains() { local needle=$1; shift; for x in "$@"; do [[ $x == "$needle" ]] && return 0; done; return 1; }

case $what in
includes)
  used=()
  for stage in "${stages[@]}"; do
    while IFS= read -r file; do
      rel=${file#"$src"/}
      while IFS= read -r header; do
        other=${header#tachi/}; other=${other%%/*}
        [[ $other == "$stage" ]] && continue
        contains "$other" "${stages[@]}" || continue  # tachi/bus, tachi/common, third-party: shared
        if contains "$rel:$header" "${allowed_includes[@]}"; then used+=("$rel:$header"); continue; fi
        fail "$rel includes $header: stage $stage may include only its own, idl/ (tachi/bus) and common/ headers"
      done < <(sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\(tachi\/[a-z_]*\/[^"]*\)".*/\1/p' "$file")
      # A relative include that climbs out of the stage reaches into another folder.
      if grep -qE '^[[:space:]]*#[[:space:]]*include[[:space:]]*"(\.\./)+(sim|filter|sensor|viewer|launcher)/' "$file"; then
        fail "$rel includes another stage's file by a relative path"
      fi
      # Another stage's executable headers (its flags, "filter/cli.hpp") are tachi-pipeline's to include.
      while IFS= read -r header; do
        [[ ${header%%/*} == "$stage" ]] || fail "$rel includes $header: another stage's executable header"
      done < <(sed -nE 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"((sim|filter|sensor|viewer|launcher)\/[^"]*)".*/\1/p' "$file")
    done < <(find "$src/$stage" -name '*.cpp' -o -name '*.hpp' -o -name '*.h' | sort)
  done
  for pair in "${allowed_includes[@]}"; do
    contains "$pair" "${used[@]+"${used[@]}"}" || fail "exception $pair is no longer needed: remove it from this script"
  done
  ;;
mains)
  for stage in "${stages[@]}" pipeline; do
    while IFS= read -r file; do
      rel=${file#"$src"/}
      lines=$(wc -l < "$file")
      if contains "$rel" "${allowed_mains[@]+"${allowed_mains[@]}"}"; then
        (( lines > 40 )) || fail "exception $rel is thin now ($lines lines): remove it from this script"
        continue
      fi
      (( lines <= 40 )) || fail "$rel has $lines lines: a main parses flags and runs a node (<= 40 lines)"
    done < <(find "$src/$stage" -maxdepth 1 \( -name 'main.cpp' -o -name '*_main.cpp' \) | sort)
  done
  ;;
*) echo "usage: $0 SOURCE_DIR {includes|mains}" >&2; exit 2 ;;
esac
if (( failures > 0 )); then exit 1; fi
echo "layering $what: ok"
