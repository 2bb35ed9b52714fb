#pragma once

#include <cstddef>

#include <glm/vec3.hpp>
#include <openvdb/openvdb.h>

#include "firn/transport/medium.h"
#include "firn/transport/scene.h"
#include "firn/transport/snow_topology.h"
#include "firn/util/progress.h"

namespace firn::bake {

// A ball of kSkyRampRadius voxels or smaller (curvature above 1 / kSkyRampRadius) is a small ball: its ramp takes the
// suns and the sky in itself (beamsInRamp's RampOfThickConvexSnow, skyInRamp's marches below the limb; a ball of 10
// voxels misses 1 % of its sky, of 5 voxels 7 %: docs/benchmarks.md, backlit-balls 2; the 5-voxel balls read kappa
// 0.20-0.25).
constexpr double kSkyRampRadius = 5.5;  // voxels
inline bool smallBall(double kappaPerVoxel) { return kappaPerVoxel * kSkyRampRadius > 1.0; }

// Whether the light the surface at surface voxel `carrier` (curvature kappa per voxel there, surfaceCurvature) lets
// out spreads as from a sphere of radius 1 / kappa: a smooth convex surface, not at or beside a sharp voxel (a box's
// or slab's edge reads a curvature that is no sphere's, and flat faces' light does not spread).
bool spreadsAsSphere(const SnowTopology &topo, const openvdb::Coord &carrier,
                     openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index, double kappaPerVoxel);

// What the suns' radiance a smooth convex surface (spreadsAsSphere) carries out into its ramp keeps d voxels beyond
// the patches' sphere (radius 1 / kappa): the patches' exitance per m^2 of their sphere shown over one of R + d,
// 1 / (1 + kappa d)^2, where the sun the skin intercepts beyond the patches is given to them (skinRingIrradiance). A
// small ball takes no ring: its ramp's own single scattering (beamsInRamp) holds the sun its skin intercepts, and
// the rest of that skin is its carried light shown over the density's larger ball, which divides as 1 / (1 + kappa
// d)^kSmallBallSpread, an exponent chosen by the energy balance where the snow absorbs nothing (omega 1 - 1e-7; the
// 5 cm ball on 1 cm voxels at g 0 to 0.85, 6 to 60 optical depths per voxel): undivided it let out 1.05-1.11 W per W
// of sun entering, divided as the larger balls' without their ring 0.83-0.90; with the exponent 1/2 0.98-1.07
// (lead-91). Since the ramp's grazing sun is delta-scaled (beamsInRamp, lead-92) the exponent 1/2 reads 1.01-1.05 on
// the three snows of the energy test and 3/4 0.98-1.02 (0.91-1.07 over lead-90's table)
// (bench/ball_energy_balance.py; docs/benchmarks.md).
constexpr double kSmallBallSpread = 0.75;
double carriedSunSpread(double kappaPerVoxel, double d);

// Voxels along a surface voxel's patch normal n from its node (voxel `node`) out to the snow's surface, where the density (trilinear)
// falls to half the snow's beneath it (the larger of the node's and a voxel further in): the patches' sphere, on
// which their exitance is per m^2, lies there (on the suite's balls the half level's sphere holds the patches' area,
// 0.06-0.21 voxel above the nodes: docs/benchmarks.md, cap-ring), not at the staircase's half voxel (patchSurface).
// Between -1 and 1.5 voxels; 0.5 where the density does not fall there.
// Reads no more of the topology than the grids keep (the patch's normal).
double surfaceOffset(const Medium &medium, const openvdb::Coord &node, const glm::dvec3 &n,
                     Medium::Accessor &density);

// The sun the soft skin outside surface patch i intercepts, as the growth (1 + kappa delta)^2 of the patches' sphere
// (radius R = 1 / kappa voxels) it adds to: the density's own cross-section, not a chosen ring. A ray passing x
// voxels above the patch's surface (`offset` voxels out of its node along its normal) at its nearest
// is stopped with probability 1 - exp(-tau(x)), tau the optical depth of its chord through the density outside the
// sphere, read along the patch's normal as a radial profile; the ring intercepts pi ((R + delta)^2 - R^2) = integral
// over x of 2 pi (R + x) (1 - exp(-tau(x))).
double skinRingGrowth(const Medium &medium, const SnowTopology &topo, std::size_t i, double kappaPerVoxel,
                      double offset, Medium::Accessor &density);

// Per surface voxel, its skinRingGrowth where its light spreads as a sphere's (spreadsAsSphere), not a small ball's
// (carriedSunSpread), and a sun meets its patch within the band the widest ring (3 voxels) could reach, 1 elsewhere:
// read once per patch for every channel and pass's assembly (read per assembly, the car's solve phase took +37 %:
// docs/benchmarks.md, cap-ring). The ring is the skin beyond patchSurface, where the patches' beams are read (the sun
// they miss), not beyond the half level the carried light's divergence starts from (surfaceOffset): from there the
// balls' bias rose 6 points, the ring's light the sun the patches already take (docs/benchmarks.md, cap-sphere).
SurfaceValues<float> skinRingGrowths(const Scene &scene, const SnowTopology &topo, const SubProgress &progress);

// W/m^2 of patch area a smooth convex patch lit at cosine mu0 scatters at its node, of the sun (irradiance E normal
// to it) its skin's ring intercepts, before the albedo: the ring's rays pass over the band 0 < mu0 < sin alpha (cos
// alpha = R / (R + delta)), 2 pi R^2 sin alpha of sphere, and half their scattered light heads into the snow (the
// forward lobe of a ray skimming the surface is split by its tangent plane), half out of it; so each m^2 of the band
// takes ((1 + kappa delta)^2 - 1) pi R^2 E / 2 over 2 pi R^2 sin alpha.
double skinRingIrradiance(double growth, double mu0, double sunIrradiance);

}  // namespace firn::bake
