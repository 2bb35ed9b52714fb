#include "firn/bake.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/mat4x4.hpp>
#include <glm/mat4x3.hpp>
#include <glm/mat3x3.hpp>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/error.h"
#include "firn/half_space.h"
#include "firn/incident_light.h"
#include "firn/monte_carlo.h"
#include "firn/multigrid.h"
#include "firn/random.h"
#include "firn/sampling.h"
#include "firn/snow_topology.h"
#include "firn/sun_lobe.h"
#include "firn/version.h"

namespace firn {

namespace {

struct Preset {
    int skySamples, sunSamples;
    double tolerance;
    int referenceSamples;
};

Preset resolve(const BakeSettings &s) {
    Preset p = s.quality == BakeQuality::Draft ? Preset{8, 1, 1e-4, 0}
               : s.quality == BakeQuality::Final ? Preset{32, 4, 1e-6, 0}
                                                 : Preset{64, 8, 1e-7, 64};
    if (s.skySamples < 0 || s.sunSamples < 0 || s.referenceSamples < 0 || !(s.tolerance >= 0.0) || s.tolerance >= 1.0)
        throw InvalidArgument("bake settings: sample counts must be >= 0 and the tolerance in [0, 1)");
    if (s.skySamples) p.skySamples = s.skySamples;
    if (s.sunSamples) p.sunSamples = s.sunSamples;
    if (s.tolerance > 0.0) p.tolerance = s.tolerance;
    if (s.referenceSamples) p.referenceSamples = s.referenceSamples;
    return p;
}

// One colour channel of the optics. Lengths below are "resistances": 3 times the reduced optical depth,
// the diffusion distance in units of D (the Marshak boundary sits 2 beyond the last scattering).
struct Channel {
    double k, omega, g;
    double sigmaT(double rho) const { return k * rho; }
    double sigmaTr(double rho) const { return (1.0 - omega * g) * k * rho; }   // sigma_a + sigma_s (1 - g)
    double reducedAlbedo() const { return omega * (1.0 - g) / (1.0 - omega * g); }
    double beta() const { return std::sqrt((1.0 - omega) / (3.0 * (1.0 - omega * g))); }  // kappa D
};

// The source function in one voxel: S(w) = l0 + l1 . w per channel (W/m^2/sr).
struct Source {
    glm::dvec3 l0{0.0};
    glm::dmat3 l1{0.0};  // column c: the vector for channel c
};

// The smooth surface through a surface voxel: outward normal from the density gradient (Sobel), and the
// area of that surface inside the voxel (its air faces projected onto it).
struct SurfacePatch {
    glm::dvec3 normal{0.0, 0.0, 1.0};
    double area = 0.0;  // m^2
};

std::vector<SurfacePatch> surfacePatches(const Medium &medium, const SnowTopology &topo) {
    std::vector<SurfacePatch> patches(topo.size());
    const double h = medium.voxelSize();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        Medium::Accessor density = medium.accessor();
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            glm::dvec3 faces(0.0);
            bool surface = false;
            for (int f = 0; f < 6; ++f)
                if (SnowTopology::isFace(topo.link[i][f]) && !topo.faces[SnowTopology::faceIndex(topo.link[i][f])].occluder)
                    faces += faceNormal(f), surface = true;
            if (!surface) continue;
            glm::dvec3 gradient(0.0);
            const openvdb::Coord &c = topo.coord[i];
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        const double w = (2 - std::abs(dx)) * (2 - std::abs(dy)) * (2 - std::abs(dz));
                        gradient += w * double(density.getValue(c.offsetBy(dx, dy, dz))) * glm::dvec3(dx, dy, dz);
                    }
            glm::dvec3 n = -gradient;
            if (glm::length(n) < 1e-9 * (1.0 + topo.density[i]) || glm::dot(n, faces) <= 0.0) n = faces;
            n = glm::length(n) > 0.0 ? glm::normalize(n) : glm::dvec3(0.0, 0.0, 1.0);
            double area = 0.0;
            for (int f = 0; f < 6; ++f)
                if (SnowTopology::isFace(topo.link[i][f]) && !topo.faces[SnowTopology::faceIndex(topo.link[i][f])].occluder)
                    area += std::max(0.0, glm::dot(n, faceNormal(f)));
            patches[i] = {n, h * h * std::max(area, 0.3)};
        }
    });
    return patches;
}

// The diffusion system of one channel plus what the surface needs afterwards.
struct ChannelSystem {
    StencilOperator A;
    std::vector<double> b;                   // W: diffuse sources at the voxel nodes
    std::vector<double> escaped;             // W: light leaving through air faces without reaching the node
    std::vector<double> outConductance;      // W per (W/m^2) of fluence: sum of the air faces' conductances
    std::vector<std::vector<double>> sunIn;  // per sun, W entering through air faces
    std::vector<double> skyIn;               // W entering through air faces
};

// Finite volumes with exponential fitting: every link between two unknowns, and between an unknown and
// a boundary, is treated as the exact one-dimensional diffusion problem -phi'' + beta^2 phi = 0 in the
// resistance coordinate R (dR = 3 sigma_tr dz), so voxels many diffusion lengths thick stay exact.

// A link between two unknowns R apart: conductance, and the absorption it lends each end.
struct Link {
    double conductance, halfMass;  // per unit face area
};
Link interiorLink(double beta, double R) {
    return {beta / std::sinh(beta * R), beta * std::tanh(0.5 * beta * R)};
}

// The stretch from a boundary to the unknown's node, L in resistance, with the boundary condition
// phi = Rb dphi/dR + Phi (Marshak: Rb = 2 for air, 2 (1 + a) / (1 - a) for a Lambertian surface of
// albedo a, Phi = 4 x the diffuse light it sends in / (1 - a)). Exact solution of the stretch.
struct BoundaryLink {
    double beta, Rb, L, delta;
    BoundaryLink(double beta_, double Rb_, double L_)
        : beta(beta_), Rb(Rb_), L(L_), delta(Rb_ * beta_ * std::cosh(beta_ * L_) + std::sinh(beta_ * L_)) {}
    double conductance() const { return beta / delta; }  // flux out through the boundary per node fluence
    double mass() const { return beta * (Rb * beta * std::sinh(beta * L) + std::cosh(beta * L) - 1.0) / delta; }
    // A diffuse source at depth R (in resistance) scattering unit power: share reaching the node, and
    // share leaving through the boundary at once.
    double toNode(double R) const { return (Rb * beta * std::cosh(beta * R) + std::sinh(beta * R)) / delta; }
    double toBoundary(double R) const { return std::sinh(beta * (L - R)) / delta; }
    // Diffuse light (irradiance J) arriving through an air boundary: share leaving again at once.
    double diffuseReturned() const { return (std::sinh(beta * L) - 2.0 * beta * std::cosh(beta * L)) / delta; }
};

ChannelSystem assemble(const Scene &scene, const SnowTopology &topo, const IncidentLight &light, int c,
                       const SubProgress &progress) {
    const Medium &medium = *scene.medium;
    const VolumeOptics &optics = medium.optics();
    const Channel ch{optics.extinctionPerDensity, optics.albedo[c], optics.g};
    const double h = medium.voxelSize(), h2 = h * h, aPrime = ch.reducedAlbedo();
    const double beta = std::max(ch.beta(), 1e-9);
    const std::size_t n = topo.size();
    ChannelSystem sys;
    sys.A.coord = topo.coord;
    sys.A.neighbour.resize(n), sys.A.conductance.resize(n), sys.A.diag.resize(n);
    sys.b.assign(n, 0.0), sys.escaped.assign(n, 0.0), sys.outConductance.assign(n, 0.0), sys.skyIn.assign(n, 0.0);
    sys.sunIn.assign(scene.suns.size(), std::vector<double>(n, 0.0));

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto &range) {
        progress.throwIfCancelled();
        Medium::Accessor density = medium.accessor();
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const double sigmaTr = ch.sigmaTr(topo.density[i]);
            double diag = 0.0, source = 0.0;  // W scattered at the node
            std::array<double, 6> mass{};     // absorption each side lends the node
            std::array<std::optional<BoundaryLink>, 6> boundary;
            std::array<double, 6> albedo{};   // occluder faces
            for (int f = 0; f < 6; ++f) {
                const std::int32_t link = topo.link[i][f];
                sys.A.neighbour[i][f] = StencilOperator::kNone;
                sys.A.conductance[i][f] = 0.0;
                if (!SnowTopology::isFace(link)) {
                    const Link L = interiorLink(beta, 1.5 * h * (sigmaTr + ch.sigmaTr(topo.density[link])));
                    sys.A.neighbour[i][f] = std::uint32_t(link);
                    sys.A.conductance[i][f] = h2 * L.conductance;
                    diag += h2 * L.conductance;
                    mass[f] = h2 * L.halfMass;
                    continue;
                }
                const std::size_t fi = SnowTopology::faceIndex(link);
                const BoundaryFace &face = topo.faces[fi];
                const double beyond = ch.sigmaTr(density.getValue(topo.coord[i] + faceStep(f)));
                const double sky = light.skyIrradiance[fi][c];
                if (!face.occluder) {
                    // Air: the density ramps to zero at the neighbour's centre; diffuse sky light enters
                    // through the Marshak condition.
                    const BoundaryLink &b = boundary[f].emplace(beta, 2.0, 1.5 * h * (sigmaTr + beyond));
                    sys.outConductance[i] += h2 * b.conductance();
                    source += 4.0 * sky * h2 * b.conductance();
                    sys.escaped[i] += sky * h2 * b.diffuseReturned();
                    sys.skyIn[i] += sky * h2;
                } else {
                    // Occluder: a Lambertian surface at `distance` from the node.
                    albedo[f] = std::min(scene.occluders->albedo(face.triangle)[c], 0.99);
                    const double d = face.distance;
                    boundary[f].emplace(beta, 2.0 * (1.0 + albedo[f]) / (1.0 - albedo[f]),
                                        3.0 * (d * sigmaTr + 0.5 * d * d / h * (beyond - sigmaTr)));
                }
                diag += h2 * boundary[f]->conductance();
                mass[f] = h2 * boundary[f]->mass();
            }
            // Absorption: the voxel's own, taken along the axes that meet a boundary (where the fluence
            // varies; exact for a flat surface), or along all three alike inside.
            std::array<double, 3> axisWeight{};
            for (int f = 0; f < 6; ++f) axisWeight[f / 2] += boundary[f] ? 1.0 : 0.0;
            const double weightSum = axisWeight[0] + axisWeight[1] + axisWeight[2];
            for (int a = 0; a < 3; ++a)
                diag += (weightSum > 0.0 ? axisWeight[a] / weightSum : 1.0 / 3.0) * (mass[2 * a] + mass[2 * a + 1]);

            // Sun beams: the power each face lets in or out; the difference is scattered in this voxel.
            std::array<double, 6> groundLight{};  // W/m^2 occluders under the snow send back in
            for (int f = 0; f < 6; ++f)
                if (boundary[f] && albedo[f] > 0.0) groundLight[f] = albedo[f] * light.skyIrradiance[SnowTopology::faceIndex(topo.link[i][f])][c];
            for (std::size_t s = 0; s < scene.suns.size(); ++s) {
                const SunLight &sun = scene.suns[s];
                const double E = sun.irradiance[c], Bv = light.beams[s].atVoxel[i][c];
                if (E <= 0.0) continue;
                std::array<double, 6> flow{};  // W through each face, positive inwards
                double in = 0.0, out = 0.0;
                for (int f = 0; f < 6; ++f) {
                    const double mu = glm::dot(faceNormal(f), sun.direction);
                    const std::int32_t link = topo.link[i][f];
                    double B = 0.0;  // beam fraction on the face
                    if (!SnowTopology::isFace(link)) {
                        B = std::sqrt(Bv * double(light.beams[s].atVoxel[link][c]));
                    } else if (!topo.faces[SnowTopology::faceIndex(link)].occluder) {
                        B = light.beams[s].atFace[SnowTopology::faceIndex(link)][c];
                    } else if (mu < 0.0) {  // the beam reaches the surface under the snow
                        B = Bv * std::exp(-sigmaTr * topo.faces[SnowTopology::faceIndex(link)].distance / std::max(-mu, 0.05));
                        groundLight[f] += albedo[f] * E * -mu * B;
                    }
                    flow[f] = E * h2 * mu * B;
                    (flow[f] > 0.0 ? in : out) += std::abs(flow[f]);
                }
                if (in <= 0.0) continue;
                const double scattered = aPrime * std::max(0.0, in - out) / in;
                for (int f = 0; f < 6; ++f) {
                    if (flow[f] <= 0.0) continue;
                    if (!boundary[f]) {
                        source += scattered * flow[f];
                        continue;
                    }
                    // Through an air face into a thick voxel: the beam scatters at mean resistance 3 mu
                    // (reduced depth mu), cut at the node; what scatters above the node partly escapes.
                    const double mu = glm::dot(faceNormal(f), sun.direction), L = boundary[f]->L;
                    const double R = 3.0 * mu * (1.0 - std::exp(-L / (3.0 * mu)));
                    source += boundary[f]->toNode(R) * scattered * flow[f];
                    sys.escaped[i] += boundary[f]->toBoundary(R) * scattered * flow[f];
                    sys.sunIn[s][i] += flow[f];
                }
            }
            // Light reflected by occluders under the snow enters diffusely through their faces.
            for (int f = 0; f < 6; ++f)
                if (groundLight[f] > 0.0)
                    source += 4.0 * groundLight[f] / (1.0 - albedo[f]) * h2 * boundary[f]->conductance();
            sys.A.diag[i] = diag;
            sys.b[i] = source;
        }
    });
    return sys;
}

// The source function from the solved fluence phi (W/m^2) of one channel.
void sourceFunction(const Scene &scene, const SnowTopology &topo, const IncidentLight &light,
                    const std::vector<SurfacePatch> &patches, const ChannelSystem &sys,
                    const std::vector<double> &phi, int c, std::vector<Source> &out) {
    const Medium &medium = *scene.medium;
    const VolumeOptics &optics = medium.optics();
    const Channel ch{optics.extinctionPerDensity, optics.albedo[c], optics.g};
    const double h = medium.voxelSize();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        Medium::Accessor density = medium.accessor();
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            // Inside: S = omega/(4 pi) (phi + 3 g F . w) for the diffuse light, F = -D grad phi, plus the beams.
            glm::dvec3 gradient(0.0);
            for (int axis = 0; axis < 3; ++axis) {
                const std::int32_t lo = topo.link[i][2 * axis], hi = topo.link[i][2 * axis + 1];
                const double pLo = lo >= 0 ? phi[lo] : phi[i], pHi = hi >= 0 ? phi[hi] : phi[i];
                const int span = (lo >= 0) + (hi >= 0);
                gradient[axis] = span ? (pHi - pLo) / (span * h) : 0.0;
            }
            const double D = 1.0 / (3.0 * ch.sigmaTr(topo.density[i]));
            double j0 = phi[i];
            glm::dvec3 j1 = -3.0 * ch.g * D * gradient;
            for (std::size_t s = 0; s < scene.suns.size(); ++s) {
                const double beam = scene.suns[s].irradiance[c] * light.beams[s].atVoxel[i][c];
                j0 += beam;
                j1 -= 3.0 * ch.g * beam * scene.suns[s].direction;
            }
            double l0 = ch.omega * kInvFourPi * j0;
            glm::dvec3 l1 = ch.omega * kInvFourPi * j1;

            if (patches[i].area > 0.0) {
                // A surface voxel: the radiance leaving thick snow, from the fluxes through its air faces.
                // Light that entered returns with its incidence's shape (the sun lobe; sky light,
                // isotropic, as a non-absorbing half-space returns it); the deficit (absorbed, or gone
                // elsewhere) and any surplus from deep inside have the escape function's shape.
                const SurfacePatch &patch = patches[i];
                const double out = sys.escaped[i] + sys.outConductance[i] * phi[i];
                double deficit = sys.skyIn[i] - out, s0 = sys.skyIn[i];
                glm::dvec3 s1(0.0);
                for (std::size_t s = 0; s < scene.suns.size(); ++s) {
                    const double P = sys.sunIn[s][i];
                    if (P <= 0.0) continue;
                    const glm::dvec3 d = -scene.suns[s].direction;  // where the sun's light travels
                    const double mu0 = std::clamp(-glm::dot(d, patch.normal), 0.05, 1.0);
                    const SunLobe lobe = sunLobe(ch.g, mu0);
                    glm::dvec3 t = d - glm::dot(d, patch.normal) * patch.normal;
                    t = glm::length(t) > 1e-9 ? glm::normalize(t) : glm::dvec3(0.0);
                    deficit += P;
                    s0 += P * lobe.a;
                    s1 += P * (lobe.b * patch.normal + lobe.c * t);
                }
                s0 -= deficit * 3.0 / 7.0;
                s1 -= deficit * 6.0 / 7.0 * patch.normal;
                // Thin surface voxels (density ramp optical depth ~1) blend towards the inside formula.
                double ramp = std::numeric_limits<double>::infinity();
                for (int f = 0; f < 6; ++f)
                    if (SnowTopology::isFace(topo.link[i][f]) && !topo.faces[SnowTopology::faceIndex(topo.link[i][f])].occluder)
                        ramp = std::min(ramp, 0.5 * h * ch.sigmaT(topo.density[i] + density.getValue(topo.coord[i] + faceStep(f))));
                const double w = 1.0 - std::exp(-ramp);
                l0 = w * s0 / (kPi * patch.area) + (1.0 - w) * l0;
                l1 = w * s1 / (kPi * patch.area) + (1.0 - w) * l1;
            }
            out[i].l0[c] = l0;
            for (int a = 0; a < 3; ++a) out[i].l1[c][a] = l1[a];
        }
    });
}

// REFERENCE quality: the radiance leaving each surface voxel, path traced from 12 directions around
// its normal, fitted by least squares with the stored linear form.
void referenceSurface(const Scene &scene, const SnowTopology &topo, const std::vector<SurfacePatch> &patches,
                      int samples, std::uint64_t seed, std::vector<Source> &out, const SubProgress &progress) {
    const MonteCarloReference reference(scene);
    const double h = scene.medium->voxelSize();
    std::vector<std::size_t> surface;
    for (std::size_t i = 0; i < topo.size(); ++i)
        if (patches[i].area > 0.0) surface.push_back(i);
    std::atomic<std::size_t> done{0};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, surface.size(), 1), [&](const auto &range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
            progress.throwIfCancelled();
            const std::size_t i = surface[k];
            const glm::dvec3 centre = scene.medium->voxelCentre(topo.coord[i]);
            glm::dmat4 normal(0.0);
            glm::dmat4x3 rhs(0.0);  // column m: basis function m against the three channels
            int d = 0;
            for (double mu : {0.95, 0.7, 0.35})
                for (int a = 0; a < 4; ++a, ++d) {
                    const glm::dvec3 w = directionAround(patches[i].normal, mu, kPi * (0.5 * a + 0.25 * (mu < 0.5)));
                    const Ray ray{centre + 3.0 * h * w, -w};
                    const Rgb L = reference.estimate(ray, samples, seed, i * 12 + d).mean;
                    const glm::dvec4 basis(1.0, w.x, w.y, w.z);
                    normal += glm::outerProduct(basis, basis);
                    for (int m = 0; m < 4; ++m) rhs[m] += basis[m] * L;
                }
            const glm::dmat4 inverse = glm::inverse(normal);
            for (int c = 0; c < 3; ++c) {
                glm::dvec4 v;
                for (int m = 0; m < 4; ++m) v[m] = rhs[m][c];
                const glm::dvec4 coefficients = inverse * v;
                out[i].l0[c] = coefficients[0];
                for (int a = 0; a < 3; ++a) out[i].l1[c][a] = coefficients[1 + a];
            }
            progress.report(double(++done) / surface.size());
        }
    });
}

// The four source grids over the snow's voxels and a margin of two: unknowns hold their source function;
// the voxels around surface voxels (where the density ramps to zero) hold their neighbours' average, so
// the renderer's trilinear ramp sees a constant ratio of emission to extinction; voxels too thin for the
// solve hold their single scattering; the outermost ring holds zeros (Cycles reads Vec3 edges wrongly).
BakedGrids makeGrids(const Scene &scene, const SnowTopology &topo, const std::vector<SurfacePatch> &patches,
                     const std::vector<Source> &source, const Preset &preset, const BakeSettings &settings) {
    const Medium &medium = *scene.medium;
    openvdb::BoolTree topology(medium.density().tree(), false, openvdb::TopologyCopy());
    openvdb::tools::dilateActiveValues(topology, 2, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    std::array<openvdb::Vec3fTree::Ptr, 4> trees;
    for (auto &tree : trees)
        tree = std::make_shared<openvdb::Vec3fTree>(topology, openvdb::Vec3f(0.0f), openvdb::TopologyCopy());
    openvdb::tree::LeafManager<openvdb::Vec3fTree> leaves(*trees[0]);
    const VolumeOptics &optics = medium.optics();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.leafCount(), 4), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
        Medium::Accessor density = medium.accessor();
        Medium::ColumnMarcher marcher(medium);
        for (std::size_t l = range.begin(); l != range.end(); ++l) {
            std::array<openvdb::Vec3fTree::LeafNodeType *, 4> leaf{&leaves.leaf(l), nullptr, nullptr, nullptr};
            for (int k = 1; k < 4; ++k) leaf[k] = trees[k]->probeLeaf(leaf[0]->origin());
            for (auto it = leaf[0]->beginValueOn(); it; ++it) {
                const openvdb::Coord c = it.getCoord();
                Source S;
                const std::int32_t i = index.getValue(c);
                if (i >= 0) {
                    S = source[i];
                } else {
                    int count = 0;
                    for (int dx = -1; dx <= 1; ++dx)
                        for (int dy = -1; dy <= 1; ++dy)
                            for (int dz = -1; dz <= 1; ++dz) {
                                const std::int32_t j = index.getValue(c.offsetBy(dx, dy, dz));
                                if (j < 0 || patches[j].area <= 0.0) continue;
                                S.l0 += source[j].l0, S.l1 += source[j].l1, ++count;
                            }
                    if (count) {
                        S.l0 /= double(count), S.l1 /= double(count);
                    } else if (density.getValue(c) > 0.0f) {
                        const glm::dvec3 centre = medium.voxelCentre(c);
                        for (const SunLight &sun : scene.suns) {
                            const glm::dvec3 beam = glm::dvec3(sunBeamAt(scene, sun, centre, preset.sunSamples,
                                                                         settings.seed, std::uint64_t(l), marcher)) *
                                                    sun.irradiance * optics.albedo * kInvFourPi;
                            S.l0 += beam;
                            for (int ch = 0; ch < 3; ++ch) S.l1[ch] -= 3.0 * optics.g * beam[ch] * sun.direction;
                        }
                    }
                }
                const auto pos = it.pos();
                leaf[0]->setValueOnly(pos, openvdb::Vec3f(float(S.l0.x), float(S.l0.y), float(S.l0.z)));
                for (int a = 0; a < 3; ++a)
                    leaf[1 + a]->setValueOnly(pos, openvdb::Vec3f(float(S.l1[0][a]), float(S.l1[1][a]), float(S.l1[2][a])));
            }
        }
    });
    BakedGrids out;
    for (std::size_t k = 0; k < 4; ++k) {
        auto grid = openvdb::Vec3fGrid::create(trees[k]);
        grid->setTransform(medium.density().transform().copy());
        grid->setName(BakedGrids::kNames[k]);
        grid->setVectorType(openvdb::VEC_INVARIANT);
        grid->insertMeta("firn_units", openvdb::StringMetadata("W/m^2/sr (source function: emission / extinction)"));
        grid->insertMeta("firn_extinction_per_density", openvdb::DoubleMetadata(optics.extinctionPerDensity));
        grid->insertMeta("firn_bake_quality",
                         openvdb::StringMetadata(settings.quality == BakeQuality::Draft   ? "DRAFT"
                                                 : settings.quality == BakeQuality::Final ? "FINAL"
                                                                                          : "REFERENCE"));
        grid->insertMeta("firn_bake_seed", openvdb::Int64Metadata(openvdb::Int64(settings.seed)));
        grid->insertMeta("firn_version", openvdb::StringMetadata(kVersion));
        out.source[k] = grid;
    }
    return out;
}

}  // namespace

BakedGrids bakeScattering(const Scene &scene, const BakeSettings &settings, Progress *progress, BakeStats *stats) {
    validate(scene);
    const Preset preset = resolve(settings);
    Progress quiet;
    Progress &p = progress ? *progress : quiet;
    const bool reference = settings.quality == BakeQuality::Reference;
    const double solved = reference ? 0.5 : 0.9;  // progress when the diffusion solve is done

    p.report(0.0, "Finding the snow's voxels");
    const SnowTopology topo = buildSnowTopology(*scene.medium, *scene.occluders, SubProgress(&p, 0.0, 0.05));
    p.report(0.05, "Tracing sun and sky light");
    const IncidentLight light = computeIncidentLight(
        scene, topo, {preset.skySamples, preset.sunSamples, settings.seed}, SubProgress(&p, 0.05, 0.4));
    const std::vector<SurfacePatch> patches = surfacePatches(*scene.medium, topo);

    BakeStats local;
    local.unknowns = topo.size();
    for (const BoundaryFace &face : topo.faces) ++(face.occluder ? local.occluderFaces : local.airFaces);
    for (const SurfacePatch &patch : patches) local.surfaceVoxels += patch.area > 0.0;

    std::vector<Source> source(topo.size());
    std::vector<double> phi(topo.size(), 0.0);  // each channel starts from the previous one's solution
    for (int c = 0; c < 3; ++c) {
        const SubProgress sub(&p, 0.4 + (solved - 0.4) * c / 3.0, 0.4 + (solved - 0.4) * (c + 1) / 3.0);
        p.report(0.4 + (solved - 0.4) * c / 3.0, "Solving multiple scattering");
        ChannelSystem sys = assemble(scene, topo, light, c, sub);
        if (topo.size() > 0) {
            const MultigridSolver solver(std::move(sys.A));
            const MultigridSolver::Result result = solver.solve(sys.b, phi, preset.tolerance, 500, sub);
            local.iterations[c] = result.iterations;
            local.relativeResidual[c] = result.relativeResidual;
        }
        sourceFunction(scene, topo, light, patches, sys, phi, c, source);
    }
    if (reference) {
        p.report(solved, "Path tracing the surface (reference)");
        referenceSurface(scene, topo, patches, preset.referenceSamples, settings.seed, source, SubProgress(&p, solved, 0.95));
    }
    p.report(reference ? 0.95 : solved, "Writing the grids");
    BakedGrids grids = makeGrids(scene, topo, patches, source, preset, settings);
    p.report(1.0, "Done");
    if (stats) *stats = local;
    return grids;
}

}  // namespace firn
