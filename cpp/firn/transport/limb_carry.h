#pragma once

namespace firn {

// The sun's light a convex surface's skin (its density ramp) carries past the limb (docs/benchmarks.md, limb-ramp).
// A sun ray scattered forwards at height z above a smooth patch of a sphere of radius R = 1 / kappa (voxels) that it
// entered at local cosine mu0 goes on along a line of impact parameter (R + z) sqrt(1 - mu0^2), which misses the
// sphere where z > z* = mu0^2 R / 2: the light the skin scatters forwards above z* leaves past the limb through the
// skin. With the density falling linearly over the ramp's thickness Delta (voxels), a patch's skin scatters the share
// (1 - z* / Delta)^2 of its mass above z*. Followed along its lines (each keeps its impact parameter), that light
// crosses a point of the skin at density fraction f = 1 - z / Delta and local sun cosine mu (the carrying surface's
// normal to the sun) as the flux, per unit of the half-space's return of the sun's irradiance,
//   f^2                              on the lit side (mu >= 0): the mass above the point scattered it;
//   (f + mu^2 / (2 kappa Delta))^2   past the terminator: its lines rose from z - mu^2 R / 2 on the terminator;
// none where f > 1 - mu^2 / (2 kappa Delta) (lines through there enter the body before the limb). On the terminator
// (mu 0) the flux over the skin's height, Delta / 3 per unit length, is the patches' shares summed over the lit face.
// Before the forward fraction (limbForwardFraction); none on flat snow (kappa 0).
inline double limbCarriedFlux(double f, double mu, double curvaturePerVoxel, double rampThicknessVoxels) {
    if (!(curvaturePerVoxel > 0.0) || !(rampThicknessVoxels > 0.0) || !(f > 0.0)) return 0.0;
    const double height = mu * mu / (2.0 * curvaturePerVoxel * rampThicknessVoxels);  // z* / Delta
    if (f > 1.0 - height) return 0.0;
    const double below = mu < 0.0 ? f + height : f;
    return below * below;
}

// The forward fraction: of the light the skin scatters, the share that keeps the sun's way (delta-Eddington's
// f = omega g^2, the ramp's forwardKept).
inline double limbForwardFraction(double omega, double g) { return omega * g * g; }

}  // namespace firn
