#!/usr/bin/env bash
# Runs a benchmark inside Blender with the add-on from the build tree: bench/run.sh bench/snow_layer_bench.py [-- args]
set -euo pipefail
FIRN_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
FIRN_BUILD="${FIRN_BUILD:-$FIRN_ROOT/build}"
script="$1"
shift
BLENDER_USER_SCRIPTS="$FIRN_BUILD/blender_scripts" BLENDER_USER_CONFIG="$FIRN_BUILD/bench_config" \
  blender -b --factory-startup -noaudio --python-exit-code 1 --python "$script" "$@" 2>&1 |
  grep -vE "^(Blender|Read|Info:|Saved|Fra:| Time:|Warning:|module changed|.* reloading)" || true
