#!/usr/bin/env bash
# Runs every benchmark and writes a markdown report (default out/bench_report.md).
# Timings vary with the machine's load; each benchmark prints ratios against a baseline of the same run.
set -euo pipefail
FIRN_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
FIRN_BUILD="${FIRN_BUILD:-$FIRN_ROOT/build}"
report="${1:-$FIRN_ROOT/out/bench_report.md}"
mkdir -p "$(dirname "$report")"
{
  echo "# Firn benchmark report"
  echo
  echo "$(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)."
  echo
  echo "## Add Snow Layer against Blender's Real Snow (same scene, same run)"
  echo
  "$FIRN_ROOT/bench/run.sh" "$FIRN_ROOT/bench/snow_layer_bench.py" -- --triangles 1000000
  echo
  echo "## Bake time against active voxels (FINAL quality)"
  echo
  echo '```'
  PYTHONPATH="$FIRN_BUILD/python" /usr/bin/python3 "$FIRN_ROOT/bench/bake_scaling.py"
  echo '```'
  echo
  echo "## Bake accuracy on small, thin and thick shapes against the core's Monte Carlo (bench/bake_suite.py)"
  echo
  PYTHONPATH="$FIRN_BUILD/python" /usr/bin/python3 "$FIRN_ROOT/bench/bake_suite.py" --markdown | grep -E '^(\||firncore|all cases|$)' | cat -s
  echo
  echo "## Baked render against Cycles brute force (same volume, same run)"
  echo
  for bounces in 256 1024; do
    "$FIRN_ROOT/bench/run.sh" "$FIRN_ROOT/bench/baked_vs_brute_force.py" -- --samples 64 --pixels 32 --bounces "$bounces"
    echo
  done
  echo "## The viewport proxy of the car sample's snow (build time, triangles, .blend growth)"
  echo
  "$FIRN_ROOT/bench/run.sh" "$FIRN_ROOT/bench/proxy_bench.py"
  echo
  echo "## The car sample's bake and Cycles' memory (baked grids as fine as the density, and 2x coarser)"
  echo
  echo '```'
  "$FIRN_ROOT/bench/run.sh" "$FIRN_ROOT/bench/car_memory.py"
  echo '```'
  echo
  echo "## The car sample's bake (bench/car_bake.py)"
  echo
  echo '```'
  "$FIRN_ROOT/bench/run.sh" "$FIRN_ROOT/bench/car_scene.py" -- "$FIRN_ROOT/out/car_bake_inputs" > /dev/null
  PYTHONPATH="$FIRN_BUILD/python" /usr/bin/python3 "$FIRN_ROOT/bench/car_bake.py" "$FIRN_ROOT/out/car_bake_inputs"
  echo '```'
  echo
  echo "## Grain snow: accumulation on the car sample, pile albedo against KZ04"
  echo
  "$FIRN_ROOT/bench/run.sh" "$FIRN_ROOT/bench/car_triangles.py" -- "$FIRN_ROOT/out/car_triangles.npz" > /dev/null
  PYTHONPATH="$FIRN_BUILD/python" /usr/bin/python3 "$FIRN_ROOT/bench/grains_bench.py" --scene "$FIRN_ROOT/out/car_triangles.npz"
  echo
  echo "## Grain snow in Cycles against the core's brute force (same grains, same run)"
  echo
  "$FIRN_ROOT/bench/run.sh" "$FIRN_ROOT/bench/grains_vs_cycles.py" -- --grains 40000 --samples 256 --pixels 48
  echo
  echo "## Multi-scale grain snow against all grains at equal noise (grain_scales sample)"
  echo
  for depth in 0.04 0.08; do
    "$FIRN_ROOT/bench/run.sh" "$FIRN_ROOT/bench/grain_scales_bench.py" -- --samples 16 --width 100 --depth "$depth"
    echo
  done
  echo "## Thrown snow: a frame with 100,000 lumps (simulate, rasterize, write)"
  echo
  echo '```'
  PYTHONPATH="$FIRN_BUILD/python" /usr/bin/python3 "$FIRN_ROOT/bench/spray_bench.py"
  echo '```'
  echo
  echo "## Sub-balls and glints: render time on the car sample against the plain snow"
  echo
  echo '```'
  "$FIRN_ROOT/bench/run.sh" "$FIRN_ROOT/bench/structure_bench.py" -- --width 240 --samples 32
  echo '```'
  echo
  echo "## Large scenes: the car, a street, the valley (levels of detail)"
  echo
  "$FIRN_ROOT/bench/run.sh" "$FIRN_ROOT/bench/large_scenes.py" -- car street valley
  echo
  echo '```'
  "$FIRN_ROOT/bench/run.sh" "$FIRN_ROOT/bench/far_surface_seam.py"
  echo '```'
  echo
  echo "## The UI's longest stalls during Add Snow Layer and Bake Scattering (car sample, window under Xvfb)"
  echo
  "$FIRN_ROOT/bench/ui_stall.sh"
  echo
  echo "## The bake's world: main-thread step and the core's Nishita sky"
  echo
  "$FIRN_ROOT/bench/run.sh" "$FIRN_ROOT/bench/world_light_bench.py"
} | tee "$report"
echo "firn: wrote $report"
