#pragma once

// One colour channel's diffusion system: the voxel scheme's operator, sources and surface terms.

#include <cmath>
#include <cstddef>
#include <vector>

#include <glm/vec3.hpp>

#include "firn/transport/incident_light.h"
#include "firn/transport/multigrid.h"
#include "firn/transport/scene.h"
#include "firn/transport/snow_topology.h"
#include "firn/util/progress.h"

namespace firn::bake {

// One colour channel of the optics. Lengths below are "resistances": 3 times the reduced optical depth,
// the diffusion distance in units of D (the Marshak boundary sits 2 beyond the last scattering).
struct Channel {
    double k, omega, g;
    double sigmaT(double rho) const { return k * rho; }
    double sigmaTrPerDensity() const { return (1.0 - omega * g) * k; }
    double sigmaTr(double rho) const { return sigmaTrPerDensity() * rho; }  // sigma_a + sigma_s (1 - g)
    double reducedAlbedo() const { return omega * (1.0 - g) / (1.0 - omega * g); }
    double beta() const { return std::sqrt((1.0 - omega) / (3.0 * (1.0 - omega * g))); }  // kappa D
    // What a half-space returns of diffuse light by this diffusion (Marshak's condition, extrapolation 2D):
    // (1 - 2 kappa D) / (1 + 2 kappa D). The voxel scheme returns it so to four digits (its links are exact).
    double diffuseAlbedo() const { return (1.0 - 2.0 * beta()) / (1.0 + 2.0 * beta()); }
};

// A solved channel's operator and right-hand side, handed to the next channel's system: of the same sizes, their
// pages are reused rather than mapped and cleared afresh (the kernel's page clearing was 6 % of the car's bake).
struct ChannelStorage {
    Stencil<float> A;
    UnwrittenVector<float> remainder;
    UnwrittenVector<double> b;
};

// What crosses a channel's air faces, per surface voxel: what the light leaving the surface (surfaceLight) reads of
// the channel's system, held from its solve until the three channels' surfaces are worked out together.
struct SurfaceTerms {
    SurfaceValues<float> escaped;             // W: light leaving through air faces without reaching the node
    SurfaceValues<float> sunEscaped;          // W: of it, the beams' light (scattered above the node)
    SurfaceValues<float> outConductance;      // W per (W/m^2) of fluence: sum of the air faces' conductances
    std::vector<SurfaceValues<float>> sunIn;  // per beam (sun or lamp), W entering through air faces
    SurfaceValues<float> skyIn;               // W entering through air faces
    // W: of the light leaving (escaped plus what the node's fluence sends out), the part the sky and other snow drive;
    // found by the beams' own solve (bake.cpp, solveBeamsApart), empty where none ran.
    SurfaceValues<float> skyLeaving;
};

// The diffusion system of one channel plus what the surface needs afterwards.
struct ChannelSystem {
    Stencil<float> A;              // what the solver keeps of the operator (MultigridSolver)
    UnwrittenVector<float> remainder;  // diag minus the conductances, summed in double (assemble writes every row)
    UnwrittenVector<double> b;  // W: diffuse sources at the voxel nodes
    SurfaceTerms surface;   // surface voxels only (what crosses air faces)
    // Per unit of diffuse irradiance on the surface patch (W/m^2): the node's source and the light
    // returned at once (m^2), so that light from other snow adds to the sources as sky light does.
    SurfaceValues<float> skyToNode, skyReturned;
    SurfaceValues<float> area;  // m^2, surface patch

    ChannelSystem(const SnowTopology &topo, std::size_t beams, ChannelStorage storage)
        : A(std::move(storage.A)), remainder(std::move(storage.remainder)), b(std::move(storage.b)),
          surface{surfaceZeros(topo), surfaceZeros(topo), surfaceZeros(topo),
                  std::vector<SurfaceValues<float>>(beams, surfaceZeros(topo)), surfaceZeros(topo), {}},
          skyToNode(surfaceZeros(topo)), skyReturned(surfaceZeros(topo)), area(surfaceZeros(topo)) {
        b.resize(topo.size());  // assemble writes every row (a reused b holds the last solve's residual)
    }
    static SurfaceValues<float> surfaceZeros(const SnowTopology &topo) {
        return SurfaceValues<float>(topo.surfaceSlot, topo.surfaceVoxels(), 0.0f);
    }

    // Adds diffuse irradiance (W/m^2) on the surface patches.
    void addDiffuse(const SurfaceValues<glm::vec3> &irradiance, int c) {
        for (std::size_t i = 0; i < b.size(); ++i) {
            if (!(area[i] > 0.0f)) continue;  // not a surface voxel
            const double E = irradiance[i][c];
            b[i] += E * skyToNode[i], surface.escaped.surface(i) += E * skyReturned[i];
            surface.skyIn.surface(i) += E * area[i];
        }
    }
    // Frees what only the assembly and addDiffuse read (12 bytes per surface voxel), before the solver is built.
    void releaseDiffuseTerms() { skyToNode = skyReturned = area = SurfaceValues<float>(); }
};

// What the voxel scheme returns of a beam entering a half-space of uniform snow (bake_diffusion_system.cpp).
double schemeBeamAlbedo(const Channel &ch, double d, double L, double mu0, double across, double spreadOut);

// Channel c's diffusion system, in `storage`'s vectors; `skinRings`: skinRingGrowths (skin_ring.h). Where `beamSources` is given (sized as the unknowns), the part
// of b the beams (suns and lamps) drive is written there (W: what they scatter at the nodes and send in off occluders;
// the rest is the sky's): the solve is linear, so its solution apart is the fluence the beams drive.
ChannelSystem assemble(const Scene &scene, const SnowTopology &topo, const IncidentLight &light,
                       const SurfaceValues<float> &skinRings, int c, const SubProgress &progress,
                       ChannelStorage storage, UnwrittenVector<double> *beamSources = nullptr);

}  // namespace firn::bake
