#include "firn/transport/bake_diffusion_system.h"

#include <algorithm>
#include <array>
#include <memory>
#include <optional>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/diffusion_links.h"
#include "firn/transport/skin_ring.h"
#include "firn/util/work_check.h"

namespace firn::bake {

namespace {

// Finite volumes with exponential fitting (diffusion_links.h): the links between unknowns, and below those to
// a boundary.

// The stretch from a boundary to the unknown's node, L in resistance, with the boundary condition
// phi = Rb dphi/dR + Phi (Marshak: Rb = 2 for air, 2 (1 + a) / (1 - a) for a Lambertian surface of
// albedo a, Phi = 4 x the diffuse light it sends in / (1 - a)). Exact solution of the stretch.
struct BoundaryLink {
    double beta, Rb, L, sh, ch, delta;  // sh, ch: sinh, cosh of beta L
    BoundaryLink(double beta_, double Rb_, double L_)
        : beta(beta_), Rb(Rb_), L(L_), sh(beta_ * L_ * sinhOverX(beta_ * L_)), ch(std::sqrt(1.0 + sh * sh)),
          delta(Rb_ * beta_ * ch + sh) {}
    double conductance() const { return beta / delta; }  // flux out through the boundary per node fluence
    // cosh - 1 = sinh^2 / (cosh + 1)
    double mass() const { return beta * (Rb * beta * sh + sh * sh / (ch + 1.0)) / delta; }
    // A diffuse source at depth R (in resistance) scattering unit power: share reaching the node, and
    // share leaving through the boundary at once.
    double toNode(double R) const { return (Rb * beta * std::cosh(beta * R) + std::sinh(beta * R)) / delta; }
    double toBoundary(double R) const { return std::sinh(beta * (L - R)) / delta; }
    // Diffuse light (irradiance J) arriving through an air boundary: share leaving again at once.
    double diffuseReturned() const { return (sh - 2.0 * beta * ch) / delta; }
};

// Past the terminator a beam grazes through the density ramp above a patch facing away from it (irradiance B, W/m^2,
// in the ramp a voxel out): no beam enters through such a patch, but the ramp cells in front of its air faces
// scatter it, each over a voxel's length of its own density, and half of that (isotropic after the similarity's
// reduction) comes in. W into the node. The truth's outer node past the terminator is fed so (its net flux there points
// inwards on ball_issue and ball_grey; docs/benchmarks.md, limb-skin). `rampScatter` (m^2): over the air faces,
// each face's share of the patch times what its ramp cell scatters, 1 - e^-tau' (rampScattering). The half goes to
// the node itself, not split in the boundary stretch the cell lies in as a lit
// patch's beam is (toNode at the cell's depth of all it scatters): split so, the sun leaving along the normal at
// 100-110 degrees fell from 0.82 and 0.87 of the truth to 0.77 and 0.78, the suite's absorbing balls 0.1 point worse
// (docs/benchmarks.md, review-mends48). Only patches facing away take it: a lit patch at cosine 0.02 takes mu0 B A,
// one at -0.02 about a' B A (1 - e^-tau') / 2, some ten times more on ball_issue (tau' 0.8 estimated); the lit
// patches' ramp is not counted, a jump at mu0 0 (max of the two below a grazing cosine would close it; not tried).
double rampInflow(double aPrime, double B, double rampScatter) { return 0.5 * aPrime * B * rampScatter; }

// One air face's term of rampScatter (m^2): its share of the patch, its ramp cell's reduced optical depth over a voxel.
double rampScattering(double share, double tau) { return share * -std::expm1(-tau); }

// Where a beam entering at cosine mu scatters within a stretch L (resistance) above the node: at mean resistance
// 3 mu (reduced depth mu below the surface), cut at the node.
double beamScatteringDepth(double mu, double L) { return 3.0 * mu * (1.0 - std::exp(-L / (3.0 * mu))); }

}  // namespace

// What the voxel scheme (assemble) returns of a beam entering a half-space of uniform snow through a flat grid face,
// per W entering: its closed form, exact as its links are (a source at a node R below the boundary, in resistance,
// escapes exp(-beta R) / (1 + 2 beta)). The beam arrives at cosine mu0 and `across` (its cosines to the face's
// other axes) through the top voxel's side faces; voxels are d thick, the top node L below the boundary (both
// resistance). The top voxel scatters what its bottom face does not pass, the share entering through the surface
// at its mean depth (toNode, toBoundary), that through the sides at its node; voxel j below it, at L + j d,
// scatters B0 q^(j - 1/2) (1 - q) of it, a geometric series. On flat slabs of omega 0.98, g 0.85 and omega 0.9,
// g 0.6 overhead it gives 0.387 and 0.266 where the solve returned 0.387 and 0.267 (1D diffusion 0.393, 0.281).
// A near lamp's beam spreads: `spreadOut` (in `across`'s units) is the cosines its faces' own ways (faceCosineToBeam)
// let out of the top voxel's faces shared with snow (the side faces and the one below) over the centre's way; the
// top voxel scatters that much less, and the neighbours take it in at their nodes, where it scatters as from a top
// node (no share escaping at once): in grey snow 3 cm under a point lamp, left out, the render read 8 % dark
// (docs/benchmarks.md, grey-lamps). 0 for a sun. On the flat slab of omega 0.9, g 0.6 under a point lamp 3 and 10 cm
// up the solve returned 0.240 and 0.255 per W entering within 1.5 cm of the point under it, this 0.244 and 0.258
// (spreadOut 0: 0.262, 0.264, the sun's); of omega 0.98, g 0.85 10 cm up, within 3.5 cm, 0.363 against 0.376 (0.385;
// docs/benchmarks.md, mends-lamps52).
double schemeBeamAlbedo(const Channel &ch, double d, double L, double mu0, double across, double spreadOut) {
    const double beta = std::max(ch.beta(), 1e-9);
    const BoundaryLink top(beta, 2.0, L);
    const auto escaping = [&](double R) { return std::exp(-beta * R) / (1.0 + 2.0 * beta); };
    const double B0 = std::exp(-L / (3.0 * mu0)),
                 halfPass = std::exp(-d / (6.0 * mu0));  // beam at the top node; sqrt(q)
    const double R = beamScatteringDepth(mu0, L), side = across * B0;
    const double topReturn =
        (mu0 * (top.toBoundary(R) + top.toNode(R) * escaping(L)) + side * escaping(L)) / (mu0 + side);
    // (1 - q) / (1 - q exp(-beta d)), q = exp(-d / (3 mu0)), exact where the snow is thin
    const double series = std::expm1(-d / (3.0 * mu0)) / std::expm1(-d / (3.0 * mu0) - beta * d);
    const double passedDown = B0 * halfPass * series * escaping(L + d);  // the voxels below's return, per W entering
    const double sideways = std::clamp(spreadOut * B0 / mu0, 0.0, 1.0 - B0 * halfPass);  // W per W entering
    return ch.reducedAlbedo() * ((1.0 - B0 * halfPass - sideways) * topReturn + passedDown +
                                 sideways * ((1.0 - B0 * halfPass) * escaping(L) + passedDown));
}

ChannelSystem assemble(const Scene &scene, const SnowTopology &topo, const IncidentLight &light,
                       const SurfaceValues<float> &skinRings, int c, const SubProgress &progress,
                       ChannelStorage storage, UnwrittenVector<double> *beamSources) {
    const Medium &medium = *scene.medium;
    const VolumeOptics &optics = medium.optics();
    const Channel ch{optics.extinctionPerDensity, optics.albedo[c], optics.g};
    const double h = medium.voxelSize(), h2 = h * h, aPrime = ch.reducedAlbedo();
    const double beta = std::max(ch.beta(), 1e-9);
    const std::size_t n = topo.size();
    ChannelSystem sys(topo, light.beams.size(), std::move(storage));
    // The topology's voxels and links, not copies: the topology outlives the solver (aliasing pointers owning
    // nothing).
    sys.A.coord = std::shared_ptr<const Stencil<float>::Voxels>(std::shared_ptr<void>(), &topo.coord);
    sys.A.neighbour = std::shared_ptr<const VoxelLinks>(std::shared_ptr<void>(), &topo.link);
    sys.A.conductance.resize(n), sys.A.diag.resize(n), sys.remainder.resize(n);

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto &range) {
        Medium::Accessor density = medium.accessor();
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
        const SharedLinks links(topo.link, topo.density, ch.sigmaTrPerDensity(), beta, h, range.begin(), range.end());
        WorkCheck work(progress);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            work.add(WorkCheck::kVoxel);
            const double sigmaTr = ch.sigmaTr(topo.density[i]);
            const SurfacePatch &patch = topo.patches[i];
            double diag = 0.0, source = 0.0;  // W scattered at the node
            std::array<double, 6> mass{};     // absorption each side lends the node
            std::array<std::optional<BoundaryLink>, 6> boundary;
            std::array<double, 6> albedo{};   // occluder faces
            std::array<double, 6> conductance{};  // to the neighbours
            double rampScatter = 0.0;  // m^2 (rampInflow)
            for (int f = 0; f < 6; ++f) {
                const std::int32_t link = topo.link[i][f];
                if (!SnowTopology::isFace(link)) {
                    const Link L = links.at(i, f);
                    conductance[f] = h2 * L.conductance;
                    diag += h2 * L.conductance;
                    mass[f] = h2 * L.halfMass;
                    continue;
                }
                const std::size_t fi = SnowTopology::faceIndex(link);
                const BoundaryFace &face = topo.faces[fi];
                double area = h2;  // m^2 of boundary the face stands for
                if (!face.occluder) {
                    // Air: the density ramps down to zero through any fringe; diffuse sky light (its share
                    // of what falls on the voxel's surface patch) enters through the Marshak condition.
                    // A face on the patch's side counts with its projection on the smooth surface: a
                    // staircase has more face than the surface has area.
                    const double facing = glm::dot(patch.normal, faceNormal(f));
                    if (facing > 0.0 && !patch.sharp) area = h2 * facing;
                    const BoundaryLink &b = boundary[f].emplace(beta, 2.0, 3.0 * ch.sigmaTr(face.rampMass));
                    const double shareOfPatch = patch.area * patch.share[f];  // m^2
                    // One read per air face, beams or none: cheap beside the face's ramp mass.
                    rampScatter += rampScattering(
                        shareOfPatch, ch.sigmaTr(density.getValue(topo.coord[i] + faceStep(f))) * h);
                    sys.surface.outConductance.surface(i) += area * b.conductance();
                    sys.skyToNode.surface(i) += 4.0 * shareOfPatch * b.conductance();
                    sys.skyReturned.surface(i) += shareOfPatch * b.diffuseReturned();
                } else {
                    // Occluder: a Lambertian surface at `distance` from the node.
                    albedo[f] = std::min(scene.occluders->albedo(face.triangle)[c], 0.99);
                    const double beyond = ch.sigmaTr(density.getValue(topo.coord[i] + faceStep(f)));
                    const double d = face.distance;
                    boundary[f].emplace(beta, 2.0 * (1.0 + albedo[f]) / (1.0 - albedo[f]),
                                        3.0 * (d * sigmaTr + 0.5 * d * d / h * (beyond - sigmaTr)));
                }
                diag += area * boundary[f]->conductance();
                mass[f] = area * boundary[f]->mass();
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
            std::array<double, 6> groundBeams{};  // of it, the beams'
            for (int f = 0; f < 6; ++f)
                if (boundary[f] && albedo[f] > 0.0)
                    groundLight[f] = albedo[f] * light.skyUnderSnow[SnowTopology::faceIndex(topo.link[i][f])][c];
            const glm::dvec3 centre = medium.voxelCentre(topo.coord[i]), surface = patchSurface(medium, topo, i);
            // The suns' light the soft skin beyond the patches' sphere intercepts, scattered at the nodes it passes
            // over (skin_ring.h); the carried light's divergence (spreadCarriedSun) needs it.
            const double ringGrowth = skinRings[i];
            for (std::size_t s = 0; s < light.beams.size(); ++s) {
                const IncidentLight::Beam &beam = light.beams[s];
                // W/m^2. Bs: facing the light, the beam outside the patch; facing away, the beam in the ramp
                // (rampInflow; incident_light.h, atSurface).
                const double Bv = beam.atVoxel[i][c], Bs = beam.atSurface[i][c];
                if (Bv <= 0.0 && Bs <= 0.0) continue;
                // Through the surface patch (facing the light: in, else out; at a sharp edge face by face) and
                // through the voxel's other faces. Per air face: W entering, and the cosine it enters at, to the
                // light seen from the patch's surface (as the incident light's facing test: a lamp's way varies).
                std::array<double, 6> entering{}, muIn{};
                double in = 0.0, out = 0.0;
                const glm::dvec3 wPatch = towardsBeam(scene, s, surface);
                for (int f = 0; f < 6 && patch.isSurface(); ++f) {
                    if (patch.share[f] <= 0.0f) continue;
                    const double mu = glm::dot(patch.sharp ? faceNormal(f) : patch.normal, wPatch);
                    const double flow = mu * patch.area * patch.share[f] * (mu > 0.0 ? Bs : Bv);
                    (flow > 0.0 ? in : out) += std::abs(flow);
                    if (flow > 0.0) entering[f] = flow, muIn[f] = mu;
                }
                const double patchIn = in;
                if (patchIn <= 0.0 && Bs > 0.0) source += rampInflow(aPrime, Bs, rampScatter);
                if (ringGrowth > 1.0 && s < scene.suns.size())
                    source += aPrime * skinRingIrradiance(ringGrowth, glm::dot(patch.normal, wPatch), Bs) * patch.area;
                std::array<double, 6> flow{};  // W through each link and occluder face, positive inwards
                for (int f = 0; f < 6; ++f) {
                    const double mu = faceCosineToBeam(scene, s, centre, f, h);
                    const std::int32_t link = topo.link[i][f];
                    if (!SnowTopology::isFace(link)) {
                        flow[f] = h2 * mu * std::sqrt(Bv * double(beam.atVoxel[link][c]));
                    } else if (topo.faces[SnowTopology::faceIndex(link)].occluder && mu < 0.0) {
                        // The beam reaches the surface under the snow.
                        const double B = Bv * std::exp(-sigmaTr * topo.faces[SnowTopology::faceIndex(link)].distance /
                                                       std::max(-mu, 0.05));
                        flow[f] = h2 * mu * B;
                        groundLight[f] += albedo[f] * -mu * B, groundBeams[f] += albedo[f] * -mu * B;
                    }
                    (flow[f] > 0.0 ? in : out) += std::abs(flow[f]);
                }
                if (in <= 0.0) continue;
                const double scattered = aPrime * std::max(0.0, in - out) / in;
                for (int f = 0; f < 6; ++f)
                    if (flow[f] > 0.0) source += scattered * flow[f];
                if (patchIn <= 0.0) continue;
                // Into a surface voxel through its air faces: the beam scatters at its mean depth
                // (beamScatteringDepth); what scatters above the node partly escapes at once.
                sys.surface.sunIn[s].surface(i) += patchIn;
                for (int f = 0; f < 6; ++f) {
                    if (entering[f] <= 0.0) continue;
                    const double P = scattered * entering[f], L = boundary[f]->L;
                    const double R = beamScatteringDepth(muIn[f], L);
                    source += boundary[f]->toNode(R) * P;
                    sys.surface.escaped.surface(i) += boundary[f]->toBoundary(R) * P;
                    sys.surface.sunEscaped.surface(i) += boundary[f]->toBoundary(R) * P;
                }
            }
            double beams = source;  // W: so far the node's sources are the beams' alone
            // Light reflected by occluders under the snow enters diffusely through their faces.
            for (int f = 0; f < 6; ++f)
                if (groundLight[f] > 0.0) {
                    source += 4.0 * groundLight[f] / (1.0 - albedo[f]) * h2 * boundary[f]->conductance();
                    beams += 4.0 * groundBeams[f] / (1.0 - albedo[f]) * h2 * boundary[f]->conductance();
                }
            if (beamSources) (*beamSources)[i] = beams;
            const double sky = light.skyOnSurface[i][c];
            for (int f = 0; f < 6; ++f) sys.A.conductance[i][f] = float(conductance[f]);
            sys.A.diag[i] = float(diag);
            sys.remainder[i] = float(rowRemainder(diag, conductance, topo.link[i]));
            sys.b[i] = source + sky * sys.skyToNode[i];
            if (!patch.isSurface()) continue;
            sys.surface.escaped.surface(i) += sky * sys.skyReturned[i];
            sys.area.surface(i) = patch.area;
            sys.surface.skyIn.surface(i) = sky * sys.area[i];
        }
    }, tbb::simple_partitioner());  // runs of at most 1024 unknowns: SharedLinks' buffer stays small
    return sys;
}

}  // namespace firn::bake
