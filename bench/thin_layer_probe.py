"""Slabs beside bench/bake_suite.py's slab_thin, baked against fresh Monte Carlo references (docs/benchmarks.md,
thin-slab): where a layer thin in transport mean free paths is better traced whole than diffused (bake_thin_snow.cpp,
kMaxTracedPieceDepth, kTracedLayerOpticalDepth, kTracedLayerAbsorptionDepth). One row per slab: mean / worst / bias
over the blocks, the views' biases, the traced voxels. Run the same line on main's build for the other side.

    PYTHONPATH=build/python python3 bench/thin_layer_probe.py TAU_PER_VOXEL OMEGA G LAYERS [WIDTH [SAMPLES]]
"""

import os
import sys
import tempfile

import bake_suite


def main():
    tau, omega, g, layers = float(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
    width = int(sys.argv[5]) if len(sys.argv) > 5 else 24
    samples = int(sys.argv[6]) if len(sys.argv) > 6 else 4096
    slab_thin = bake_suite.case("slab_thin")
    case = bake_suite.Case(f"layer_{tau}_{omega}_{g}_{layers}x{width}", "", bake_suite.slab(width, layers) * 100.0,
                           0.01, tau * 100.0, 100.0, (omega,) * 3, g, views=slab_thin.views, samples=samples)
    cache = os.path.join(tempfile.gettempdir(), "firn_thin_layer_probe")
    os.makedirs(cache, exist_ok=True)
    with tempfile.TemporaryDirectory() as folder:
        r = bake_suite.run_case(case, folder, cache)
    views = ", ".join(f"{100 * b:+.0f}" for b in r["view_bias"])
    print(f"{case.name}: {100 * r['mean']:.1f} % / {100 * r['worst_signed']:+.0f} % / {100 * r['bias']:+.1f} %, "
          f"views {views} %, {r['traced']} traced, trace {r['trace_cpu_s']:.2f} processor s, "
          f"reference noise {100 * r['noise']:.1f} %")


if __name__ == "__main__":
    main()
