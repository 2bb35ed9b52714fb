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
};

}  // namespace firn::bake
