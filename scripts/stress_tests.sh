#!/usr/bin/env bash
# Runs test groups again and again while every core is kept busy, to catch tests that depend on the machine's
# load (issue: a UI test that failed one time in three on a busy machine).
#   scripts/stress_tests.sh [RUNS] [ctest arguments]     default: 20 runs of -L blender (the Blender and UI tests)
#   scripts/stress_tests.sh 5 -R blender_ui              five runs of the UI tests alone
# The load is one busy loop per core (nice 0, like a build or a render on the same machine). Prints one line per
# run and a summary; exits non-zero if any run failed. Logs of failed runs are kept in build/stress/.
set -euo pipefail
FIRN_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
FIRN_BUILD="${FIRN_BUILD:-$FIRN_ROOT/build}"
runs="${1:-20}"
shift || true
[ $# -gt 0 ] || set -- -L blender
[ -f "$FIRN_BUILD/CTestTestfile.cmake" ] || { echo "firn: build first (scripts/test.sh)" >&2; exit 1; }

hogs=()
stop_load() { [ ${#hogs[@]} -eq 0 ] || kill "${hogs[@]}" 2>/dev/null || true; }
trap stop_load EXIT
for _ in $(seq "$(nproc)"); do
  (while :; do :; done) &
  hogs+=($!)
done

logs="$FIRN_BUILD/stress"
mkdir -p "$logs"
passed=0 failed=0
for run in $(seq "$runs"); do
  started=$SECONDS
  if (cd "$FIRN_BUILD" && ctest --output-on-failure --parallel 1 "$@") >"$logs/run.log" 2>&1; then
    passed=$((passed + 1)); verdict=passed
  else
    failed=$((failed + 1)); verdict=FAILED
    cp "$logs/run.log" "$logs/failed-run-$run.log"
  fi
  echo "run $run/$runs: $verdict ($(grep -Eo '[0-9]+ tests failed out of [0-9]+|100% tests passed, 0 tests failed out of [0-9]+' "$logs/run.log" | tail -1), $((SECONDS - started)) s, load $(cut -d' ' -f1 /proc/loadavg))"
done
echo "stress: $* under load on $(nproc) cores"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
