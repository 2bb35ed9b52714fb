#pragma once

// The bake's sample counts and tolerance for its quality (resolve, bake.cpp).

namespace firn::bake {

struct Preset {
    int skySamples, sunSamples;
    double tolerance;
    int referenceSamples;
    int snowBounces;  // passes gathering light between snow surfaces
    int tracedSamples;  // paths per optically thin voxel (thinVoxels)
    // As many where all of them cost little (kCheapTracedSteps, kShortTracedSteps: planGathering).
    int cheapTracedSamples;
    // The sky and the light gathered from other snow averaged over like-facing neighbours (averageOverNeighbours):
    // 9 rays a voxel pooled over its neighbours where 16 were its own (docs/bake.md, Performance).
    bool skyOverNeighbours;
    // Of light tracing's photons and least photons where gathering per voxel is over its budget and in whole
    // transport-thin pieces (planLightTracing; bake_thin_snow.cpp has ball_forward's figures).
    // Draft's quarter, as its gathered paths (64 of 256): a ski spray's frame (bench/spray_light_bench.py, seed 0;
    // docs/spray.md "Light") 16.9 + 9.9 -> 4.3 + 2.7 processor s, the lumps from the side 8.9 -> 10.6 % per block
    // (seeds 1-3 12.6, 12.1, 11.3 %), the snow with them from above 10.2 -> 13.1 %; half: 8.2 + 5.3 s, 8.3 %, 12.7 %.
    // Without the least photons scaled too the joint bake's lumps fell to the diffusion: from above 29.8 %.
    double lightTracingShare;
    // Tracking steps the traced voxels of a small scene may take in all, their paths per voxel (or photons) raised
    // beyond the counts above (planGathering, bake_traced_voxels.h); 0: never raised.
    double smallSceneTracedSteps;
};

}  // namespace firn::bake
