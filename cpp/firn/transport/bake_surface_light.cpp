#include "firn/transport/bake_surface_light.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/transport/bake_sun_downstream.h"
#include "firn/transport/edge_lobe.h"
#include "firn/transport/sun_lobe.h"
#include "firn/util/sampling.h"
#include "firn/util/work_check.h"

namespace firn::bake {

namespace {

// A neighbour's normal this near a face's (cosine) is the face going on: a flat wall's voxels take the face's normal
// itself (onFlatWall); a ball of 5 voxels' radius turns 11 degrees (0.98) a voxel.
constexpr double kFlatCosine = 0.999;

// The three channels' fluence gradients along surface voxel i's patch (per m): least squares over the surface voxels
// of its 3^3 block (weighted by the cosine between their normals and its own), in its tangent plane.
std::array<glm::dvec3, 3> surfaceGradients(const SnowTopology &topo, const std::array<UnwrittenVector<double>, 3> &phi,
                                           std::size_t i, double h) {
    const glm::dvec3 n = topo.patches[i].normal;
    const glm::dvec3 u = glm::normalize(glm::cross(n, std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
    const glm::dvec3 v = glm::cross(n, u);
    double a = 0.0, b = 0.0, c = 0.0;
    std::array<double, 3> ru{}, rv{};
    for (std::size_t k = topo.neighbourhoodStart[i]; k < topo.neighbourhoodStart[i + 1]; ++k) {
        const std::uint32_t j = topo.neighbourhood[k];
        const double w = std::max(0.0, glm::dot(n, topo.patches[j].normal));
        if (j == i || w <= 0.0) continue;
        const openvdb::Coord d = topo.coord[j] - topo.coord[i];
        const glm::dvec3 step = h * glm::dvec3(d.x(), d.y(), d.z());
        const double x = glm::dot(step, u), y = glm::dot(step, v);
        a += w * x * x, b += w * x * y, c += w * y * y;
        for (int ch = 0; ch < 3; ++ch) {
            const double f = phi[ch][j] - phi[ch][i];
            ru[ch] += w * x * f, rv[ch] += w * y * f;
        }
    }
    const double det = a * c - b * b;
    std::array<glm::dvec3, 3> gradient{};
    if (det <= 1e-12 * h * h * h * h) return gradient;
    for (int ch = 0; ch < 3; ++ch) gradient[ch] = ((c * ru[ch] - b * rv[ch]) * u + (a * rv[ch] - b * ru[ch]) * v) / det;
    return gradient;
}

// Whether sharp voxel i's air face f goes on as a flat wall away from each of its other air faces: the voxel a step
// away from that face is a surface voxel with f's normal (a box's or a layer's side, onFlatWall), not a step of a
// staircase (a ball's flat caps, whose faces meet the curved surface past them).
bool goesOnFlat(const SnowTopology &topo, std::size_t i, int f) {
    for (int g = 0; g < 6; ++g) {
        if (g / 2 == f / 2 || topo.patches[i].share[g] <= 0.0f) continue;
        const std::int32_t next = topo.link[i][g ^ 1];
        if (SnowTopology::isFace(next) || !topo.patches[std::size_t(next)].isSurface() ||
            glm::dot(topo.patches[std::size_t(next)].normal, faceNormal(f)) < kFlatCosine)
            return false;
    }
    return true;
}

// kg/m^2 of snow from surface voxel i's centre out through its patch: its air faces' ramps by their shares.
double patchRampMass(const SnowTopology &topo, std::size_t i) {
    double mass = 0.0;
    for (int f = 0; f < 6; ++f)
        if (topo.patches[i].share[f] > 0.0f)
            mass += topo.patches[i].share[f] * topo.faces[SnowTopology::faceIndex(topo.link[i][f])].rampMass;
    return mass;
}

}  // namespace

// The density of the snow beneath surface voxel i's patch: its neighbour against the normal's largest component
// (its own where that is no snow).
double densityBeneath(const SnowTopology &topo, std::size_t i, const glm::dvec3 &n) {
    const std::int32_t link = topo.link[i][faceBeneath(n)];
    return SnowTopology::isFace(link) ? topo.density[i] : topo.density[std::size_t(link)];
}

namespace {

// Beam b, towards w at surface voxel i's centre, through the voxel's faces shared with snow (the side faces and the
// one below alike), per W/m^2 at its node and m^2 of its patch: schemeBeamAlbedo's `across`, what the faces let in
// at w (on a flat grid face the cosines to the other axes; a staircase's steps let less in so, the voxel's other air
// faces none), and its `spreadOut`, what each face's own way (faceCosineToBeam, the assembly's) lets out over w's. A
// near lamp's beam spreads; a sun's way is one everywhere (spreadOut 0 to the bit).
struct ThroughSnowFaces {
    double across, spreadOut;
};
ThroughSnowFaces throughSnowFaces(const Scene &scene, const SnowTopology &topo, std::size_t i, std::size_t b,
                                  const glm::dvec3 &w, double h) {
    const glm::dvec3 centre = scene.medium->voxelCentre(topo.coord[i]);
    double across = 0.0, spreadOut = 0.0;
    for (int f = 0; f < 6; ++f) {
        if (SnowTopology::isFace(topo.link[i][f])) continue;
        const double mu = glm::dot(faceNormal(f), w);
        across += std::max(0.0, mu);
        spreadOut += mu - faceCosineToBeam(scene, b, centre, f, h);
    }
    return {across * h * h / topo.patches[i].area, spreadOut * h * h / topo.patches[i].area};
}

// What returnedThrough reads of surface voxel i whatever the channel and the face, found when first asked and kept
// for i's three channels and (a sharp edge's) air faces: its curvature (surfaceCurvature, -1 until a low sun asks for
// it) and each beam's way through its snow faces (throughSnowFaces, from the beam's direction at i's centre).
class VoxelShared {
  public:
    explicit VoxelShared(std::size_t beams) : faces_(beams), facesFound_(beams, false) {}
    void startVoxel(std::size_t i) {
        i_ = i, curvature = -1.0;
        std::fill(facesFound_.begin(), facesFound_.end(), false);
    }
    // w: beam b's direction towards its light at i's centre.
    const ThroughSnowFaces &faces(const Scene &scene, const SnowTopology &topo, std::size_t b, const glm::dvec3 &w,
                                  double h) {
        if (!facesFound_[b]) faces_[b] = throughSnowFaces(scene, topo, i_, b, w, h), facesFound_[b] = true;
        return faces_[b];
    }
    double curvature = -1.0;  // per voxel

  private:
    std::size_t i_ = 0;
    std::vector<ThroughSnowFaces> faces_;
    std::vector<bool> facesFound_;
};

// Light returned through a patch (W and the first moments of its linear radiance), over and above the escape
// function's share: of the sky (and light from other snow) and of the beams.
struct ReturnedLight {
    double sky0;
    glm::dvec3 sky1;
    double sun0;
    glm::dvec3 sun1;
    double sunShape0;  // of sun0, sun1: the sun lobe's shape beyond the escape function's
    glm::dvec3 sunShape1;
    double sunMissed, sunReturned;  // W: what the diffusion misses of it; all the half-space returns
};

// The sky on a patch of normal n read as an even part and a beam, from the first moment of its arrival
// directions per unit irradiance m (IncidentLight::skyAim): m = (1 - share) 2/3 n + share w, w the beam's unit
// direction towards the light (an even sky's moment is 2/3 n; the share solves |w| = 1). A wall's sky from above
// only is share 0.57 from 48 degrees above its normal: its light, carried on downwards at g 0.7, leaves less
// upwards than an even sky's (docs/bake.md Method 5; bench/wall_on_ground_bench.py).
struct SkyBeam {
    double share = 0.0;
    glm::dvec3 towards{0.0};
};
SkyBeam skyBeamPart(const glm::dvec3 &m, const glm::dvec3 &n) {
    const double delta = glm::dot(m, n) - 2.0 / 3.0, across = glm::length(m - glm::dot(m, n) * n);
    const double share = std::min(1.0, (6.0 * delta + std::sqrt(81.0 * delta * delta + 45.0 * across * across)) / 5.0);
    const glm::dvec3 towards = m - (1.0 - share) * 2.0 / 3.0 * n;  // times share
    if (!(share > 1e-3) || glm::dot(towards, n) <= 0.0) return {};  // none, or light skimming the surface only
    return {share, glm::normalize(towards)};
}

}  // namespace

bool beamLightsRamp(const Scene &scene, std::size_t b, double mu0) {
    if (mu0 >= kGrazingSunCosine) return false;
    return b < scene.suns.size() || scene.lamps[b - scene.suns.size()].isArea() || mu0 >= 0.0;
}

// The unit direction along a surface of normal n in which light travelling along d moves (0 along the normal).
glm::dvec3 travelAlong(const glm::dvec3 &d, const glm::dvec3 &n) {
    const glm::dvec3 t = d - glm::dot(d, n) * n;
    return glm::length(t) > 1e-9 ? glm::normalize(t) : glm::dvec3(0.0);
}

// The three channels' light leaving each surface voxel, from their solves: per voxel the channels in turn, the
// geometry and the neighbours read once for the three.
void surfaceLight(const Scene &scene, const SnowTopology &topo, const IncidentLight &light, const SnowLight &snow,
                  const std::array<SurfaceTerms, 3> &terms, const std::array<UnwrittenVector<double>, 3> &phi,
                  bool flatFaces, SurfaceValues<SurfaceLight> &out, EdgeFaceLobes &edgeFaces,
                  const SubProgress &progress) {
    const Medium &medium = *scene.medium;
    const VolumeOptics &optics = medium.optics();
    const Channel kernelChannel{optics.extinctionPerDensity, optics.albedo[1], optics.g};  // one kernel for the three
    std::array<SurfaceValues<SunReturned>, 3> sun;
    for (auto &channel : sun) channel = SurfaceValues<SunReturned>(topo.surfaceSlot, topo.surfaceVoxels());
    // Where the snow absorbs, the diffusion returns other amounts than a half-space of this snow does (the sun
    // lobe's Monte Carlo table): of diffuse light less (the spherical albedo 0.447 against Marshak's 0.429 at
    // omega 0.98, g 0.85; 0.330 against 0.300 at omega 0.9, g 0.6), of a beam more at steep incidence and less at
    // grazing (the voxel scheme's 0.387 against 0.353 at mu0 1, 0.505 against 0.571 at mu0 0.3, omega 0.98,
    // g 0.85: schemeBeamAlbedo, on the snow beneath the patch). What it misses (negative where it returns too
    // much) leaves too: an absorbing ball's shadowed side, lit by the sky alone, was 5-9 % too dark, its sunward
    // face 5-8 % too bright (docs/bake.md, Accuracy).
    struct ChannelOptics {
        Channel ch;
        double y, diffuseMissed;
    };
    std::array<ChannelOptics, 3> channels;
    for (int c = 0; c < 3; ++c) {
        const Channel ch{optics.extinctionPerDensity, optics.albedo[c], optics.g};
        const double y = absorptionParameter(ch.omega, ch.g);
        channels[c] = {ch, y, sphericalAlbedo(ch.g, y) - ch.diffuseAlbedo()};
    }
    const double h = medium.voxelSize();
    // The part of a smooth patch's diffuse light that arrives as a beam (skyBeamPart; none at a sharp edge).
    auto skyBeamOn = [&](std::size_t i) {
        const glm::dvec3 snowE = snow.light ? glm::dvec3((*snow.light)[i]) : glm::dvec3(0.0);
        const glm::dvec3 E = glm::dvec3(light.skyOnSurface[i]) + snowE;
        const double grey = (E.x + E.y + E.z) / 3.0;
        if (topo.patches[i].sharp || !(grey > 0.0)) return SkyBeam{};
        const glm::dvec3 snowAim = snow.aim ? glm::dvec3((*snow.aim)[i]) : glm::dvec3(0.0);
        return skyBeamPart((glm::dvec3(light.skyAim[i]) + snowAim) / grey, topo.patches[i].normal);
    };
    // Sun light that entered returns as a half-space of this snow returns it, with the sun lobe's albedo and
    // shape; sky light isotropically (a non-absorbing half-space returns uniform sky light so; absorption takes
    // the escape function's shape from it, by reciprocity with ART's plane albedo). What the diffusion says
    // beyond that (absorbed sky light, light gone elsewhere, light from deep inside, from the ground or from
    // neighbouring snow) and what it misses take the escape function's u(mu) = 3/7 + 6/7 mu. So:
    // leaving = sum returned (shape - u) + (out + missed) u. Channel c's returned part (W, moments of a linear form)
    // through a surface of normal n taking `skyShare` of voxel i's sky light and beamShare(s) of each beam's; with
    // `peak` (a smooth patch, or each air face of a sharp edge), the suns' light returned sharply forwards leaves as
    // the peaked lobe instead (SunPeak: at grazing sun the lit rim seen against the sun, bench/bake_halfspace.py),
    // added to `peak` (radiance), the rest linear:
    // `index` finds the patch's neighbours for its curvature (restKept); `shared`: what voxel i's channels and faces
    // share (VoxelShared, started at i).
    auto returnedThrough = [&](int c, std::size_t i, const glm::dvec3 &n, double skyShare, const SkyBeam &beam,
                               const auto &beamShare, SurfaceLight *peak,
                               openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index, VoxelShared &shared) {
        const Channel &ch = channels[c].ch;
        const double y = channels[c].y;
        const glm::dvec3 centre = medium.voxelCentre(topo.coord[i]), escape1 = 6.0 / 7.0 * n;
        const double sky = skyShare * terms[c].skyIn[i];
        double r0 = sky * (1.0 - 3.0 / 7.0), missed = sky * channels[c].diffuseMissed;  // W
        glm::dvec3 r1 = -sky * escape1;
        // A smooth patch's lopsided diffuse light (sky, occluders' reflections and other snow's light, each from
        // where it arrives) returns as its beam part would, in the sun lobe's shape (a + b n.w + c t.w against the
        // even 1: the same exitance, a + 2b/3 = 1). Not a sharp edge's faces: the moment is over the patch
        // normal's hemisphere, and an even sky would lean 45 degrees off each face.
        if (beam.share > 0.0) {
            const SunLobe lobe = sunLobe(ch.g, std::clamp(glm::dot(beam.towards, n), 0.05, 1.0), y);
            const double returned = beam.share * lobe.albedo * sky;
            r0 += returned * (lobe.a - 1.0);
            r1 += returned * (lobe.b * n + lobe.c * travelAlong(-beam.towards, n));
        }
        double sun0 = 0.0, sunMissed = 0.0, sunReturned = 0.0;  // the beams' part
        glm::dvec3 sun1(0.0);
        // The half-space of the snow beneath the patch: a voxel's resistance and the node's below the surface
        // (schemeBeamAlbedo's d, L). A smooth surface's fringe voxel holds less snow where the surface crosses it
        // (antialiasing), its ramp: the snow's own density for d, not the fringe's (with the fringe's ball_grey
        // was 12.6 % where it is 11.5 %, docs/bake.md).
        const double voxelR = 3.0 * h * ch.sigmaTr(densityBeneath(topo, i, n)),
                     nodeR = 3.0 * ch.sigmaTr(patchRampMass(topo, i));
        for (std::size_t s = 0; s < light.beams.size(); ++s) {
            const double P = terms[c].sunIn[s][i] * beamShare(s);
            if (P <= 0.0) continue;
            // Where the light travels: a lamp's way at the voxel centre, not the patch's surface (sunIn's cosine):
            // from the surface the lobe and kernel read ball_grey's limb 1.22 -> 1.35 (docs/benchmarks.md, lamp-near).
            const glm::dvec3 d = -towardsBeam(scene, s, centre);
            const double mu0 = std::clamp(-glm::dot(d, n), 0.05, 1.0);
            const SunLobe lobe = sunLobe(ch.g, mu0, y);
            const glm::dvec3 t = travelAlong(d, n);
            const double returned = P * lobe.albedo;
            sunReturned += returned;
            const ThroughSnowFaces &faces = shared.faces(scene, topo, s, -d, h);
            sunMissed += P * (lobe.albedo - schemeBeamAlbedo(ch, voxelR, nodeR, mu0, faces.across, faces.spreadOut));
            if (!peak) {
                sun0 += returned * (lobe.a - 3.0 / 7.0);
                sun1 += returned * (lobe.b * n + lobe.c * t - escape1);
                continue;
            }
            const SunPeak split = sunPeak(ch.g, mu0, y, lobe);
            // Under a low sun less than what returns, but where the surface curves (its limb shows grazing exits).
            if (split.rest < 1.0 && shared.curvature < 0.0)
                shared.curvature = std::max(0.0, surfaceCurvature(topo, topo.coord[i], index));
            const double rest = (1.0 - split.share) * restKept(split, shared.curvature);
            sun0 += returned * (rest * split.a() - 3.0 / 7.0);
            sun1 += returned * (rest * (split.b * n + split.c * t) - escape1);
            const double p0 = split.mean * returned / (kPi * topo.patches[i].area);
            const glm::dvec3 m = std::cos(split.elevation) * t + std::sin(split.elevation) * n;
            const glm::vec3 peak1 = glm::vec3(split.k * p0 * glm::normalize(m));  // 3 k m mean(p0), channel c's part
            peak->peak0[c] += float(p0);
            peak->peak1 += peak1;
            // Read with lamps alone (rampPeaks), so a scene of suns skips the test.
            if (!scene.lamps.empty() && beamLightsRamp(scene, s, glm::dot(n, towardsBeam(scene, s, centre + h * n))))
                peak->rampPeak0[c] += float(p0), peak->rampPeak1 += peak1;
        }
        return ReturnedLight{r0 + missed * 3.0 / 7.0, r1 + missed * escape1, sun0 + sunMissed * 3.0 / 7.0,
                             sun1 + sunMissed * escape1, sun0, sun1, sunMissed, sunReturned};
    };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
        VoxelShared shared(light.beams.size());  // returnedThrough's, started per voxel
        WorkCheck work(progress);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            if (!topo.patches[i].isSurface()) continue;
            work.add(WorkCheck::kVoxel);
            const glm::dvec3 centre = medium.voxelCentre(topo.coord[i]);
            const SurfacePatch &patch = topo.patches[i];
            SurfaceLight &surface = out.surface(i);
            const SkyBeam skyBeam = skyBeamOn(i);
            // Light flowing along the surface leaves leaning the way it flows: the diffusion's radiance
            // (phi + 3 F . w) / 4 pi holds the tangential flux F_t = -D grad_t phi, which the escape function (the
            // flux across the surface) does not; added to the exit form relative to phi, 3 F_t / phi, it moves no
            // exitance (t . w integrates to zero over the hemisphere). Past a ball's terminator the fluence falls
            // away from the lit side, and on its sunward face away from the point under the sun (docs/bake.md,
            // Accuracy: the terminator). At most 3/7, so the form stays positive at grazing exit.
            const std::array<glm::dvec3, 3> gradient =
                patch.sharp ? std::array<glm::dvec3, 3>{} : surfaceGradients(topo, phi, i, h);
            shared.startVoxel(i);
            for (int c = 0; c < 3; ++c) {
                const Channel &ch = channels[c].ch;
                const double leaving = terms[c].escaped[i] + terms[c].outConductance[i] * phi[c][i];
                const auto whole = [](std::size_t) { return 1.0; };
                const ReturnedLight r =
                    returnedThrough(c, i, patch.normal, 1.0, skyBeam, whole, patch.sharp ? nullptr : &surface, index,
                                    shared);
                // The similarity-reduced beam is forward-scattered light: where it reaches a patch from inside
                // it leaves around its direction, as a lobe of k = g (its exitance taken as pi l0 (1 + 3 k cos)),
                // through the smooth surface or, at a sharp edge, through each air face.
                const double k = crossingAnisotropy(ch.g);
                double crossing = 0.0;
                glm::dvec3 axis(0.0);
                for (std::size_t s = 0; s < light.beams.size(); ++s) {
                    const double beam = light.beams[s].atVoxel[i][c];
                    const glm::dvec3 d = -towardsBeam(scene, s, centre);
                    for (int f = 0; f < 6 && beam > 0.0; ++f) {
                        const double cos = glm::dot(d, patch.sharp ? faceNormal(f) : patch.normal);
                        if (patch.share[f] <= 0.0f || cos <= 0.0) continue;
                        const double l0 = beam * cos * patch.area * patch.share[f] / (kPi * (1.0 + 3.0 * k * cos));
                        crossing += l0, axis += l0 * d;
                    }
                }
                glm::dvec3 drift(0.0);
                if (!patch.sharp && phi[c][i] > 0.0) {
                    const glm::dvec3 g = gradient[c];
                    const double sigmaTr = ch.sigmaTr(densityBeneath(topo, i, patch.normal));
                    drift = -(g - glm::dot(g, patch.normal) * patch.normal) / (sigmaTr * phi[c][i]);
                    const double length = glm::length(drift);
                    if (length > 3.0 / 7.0) drift *= 3.0 / 7.0 / length;
                }
                surface.crossing[c] = float(crossing);
                if (crossing > 0.0) surface.crossingAxis = glm::vec3(axis / crossing);
                if (!terms[c].skyLeaving.values().empty()) surface.skyLeaving = terms[c].skyLeaving[i];
                if (patch.sharp) {
                    surface.returned.l0[c] = float(r.sky0 + r.sun0);
                    surface.returned.l1[c] = glm::vec3(r.sky1 + r.sun1 + leaving * drift);
                    surface.leaving[c] = float(leaving);
                    continue;
                }
                // The suns' light the half-space returns at the patch it entered leaves downstream
                // (sunLeavingDownstream): what escaped at once and what the diffusion misses, with their share of the
                // sun lobe's shape (the rest of the shape goes with the light the diffusion carries from the node).
                // The peaked lobe stays: single scattering at grazing sun leaves within a mean free path, a small
                // part of 1/sigma_tr.
                const double atOnce = terms[c].sunEscaped[i];
                const double moved =
                    r.sunReturned > 0.0 ? std::clamp((atOnce + r.sunMissed) / r.sunReturned, 0.0, 1.0) : 0.0;
                surface.returned.l0[c] = float(r.sky0 + (1.0 - moved) * r.sunShape0);
                surface.returned.l1[c] = glm::vec3(r.sky1 + (1.0 - moved) * r.sunShape1 + leaving * drift);
                surface.leaving[c] = float(leaving);
                SunReturned &sunHere = sun[c].surface(i);
                sunHere.l0 = float(moved * r.sunShape0 + r.sunMissed * 3.0 / 7.0);
                sunHere.l1 = glm::vec3(moved * r.sunShape1 + r.sunMissed * 6.0 / 7.0 * patch.normal);
                sunHere.atOnce = float(atOnce);
                // The same kernel for each channel, found per channel from its beams' power (a loop over the beams).
                downstreamKernel(scene, light, terms[c], kernelChannel, topo, i, sunHere);
            }
        }
    });
    // Sharp edges: each air face's own exit radiance (the light returned through it, the exitance of the
    // surface voxels facing its way, other edge voxels left out as in surfaceRadiance), the one lobe
    // fitted to what cameras see of them (edgeLobe), and each flat face's own lobe for the air across it
    // (EdgeFaceLobes). A face the sun enters at grazing incidence returns it sharply forwards as a smooth surface
    // does: its SunPeak joins the voxel's peaked lobe (a small lump's edges are its rim against the sun, docs/bake.md
    // Method 5: lump_angles_bench's view 27 degrees off the sun's travel -39.5 -> -16.0 %).
    edgeFaces.voxels.clear();
    for (std::size_t i = 0; i < topo.size(); ++i)
        if (topo.patches[i].sharp) edgeFaces.voxels.push_back({std::uint32_t(i)});
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, edgeFaces.voxels.size(), 64), [&](const auto &range) {
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
        std::vector<FaceExit> faces, skimmedIn;  // skimmedIn: per air face, the sun skimming its ramp (W/m^2/sr)
        std::vector<glm::dvec3> normals;  // the air faces'
        std::vector<double> radiance;     // each face's peak radiance over the voxel's
        VoxelShared shared(light.beams.size());  // returnedThrough's, started per voxel
        WorkCheck work(progress);
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
            work.add(WorkCheck::kVoxel);
            EdgeFaceLobes::Voxel &own = edgeFaces.voxels[k];
            const std::size_t i = own.key;
            const SurfacePatch &patch = topo.patches[i];
            for (int f = 0; f < 6; ++f)
                if (flatFaces && patch.share[f] > 0.0f && goesOnFlat(topo, i, f)) own.flat |= std::uint8_t(1u << f);
            normals.clear();
            for (int f = 0; f < 6; ++f)
                if (patch.share[f] > 0.0f) normals.push_back(faceNormal(f));
            const glm::dvec3 surface = patchSurface(medium, topo, i);
            std::array<std::pair<glm::dvec3, double>, 6> outflow;  // per air face, the three channels' at once
            shared.startVoxel(i);
            std::array<double, 6> facePeak{};  // W/m^2/sr: each face's SunPeak, the channels' sum
            const bool walls = own.facesAreWalls(patch);
            for (int f = 0; f < 6; ++f)
                if (patch.share[f] > 0.0f)
                    outflow[f] = neighbourhoodOutflow<glm::dvec3>(
                        topo, i, faceNormal(f), [&](std::size_t j) { return glm::dvec3(out[j].leaving); });
            for (int c = 0; c < 3; ++c) {
                faces.clear(), skimmedIn.clear();
                for (int f = 0; f < 6; ++f) {
                    if (patch.share[f] <= 0.0f) continue;
                    const glm::dvec3 n = faceNormal(f);
                    const double voxelOpticalDepth = channels[c].ch.sigmaT(densityBeneath(topo, i, n)) * h;
                    const float peakBefore = out.surface(i).peak0[c];
                    const ReturnedLight r = returnedThrough(c, i, n, patch.share[f], SkyBeam{}, [&](std::size_t s) {
                        // The beam entered each face by its cosine to the light seen from the patch's surface, as
                        // the diffusion let it in (bake_diffusion_system.cpp).
                        const glm::dvec3 w = towardsBeam(scene, s, surface);
                        const double seen = projectedArea(normals, w);
                        return seen > 0.0 ? std::max(0.0, glm::dot(n, w)) / seen : 0.0;
                    }, &out.surface(i), index, shared);
                    // The sun skimming the face's ramp beyond a lit edge (skimmedThroughRamp), returned as the
                    // half-space returns a grazing beam; on a corner of flat walls only (a staircase's next step takes
                    // that strip in itself: ball_issue 8.45 -> 8.82 % ungated; docs/benchmarks.md, edge-skim).
                    const auto skimmed = [&](std::size_t s) {
                        if (!walls) return 0.0;
                        const glm::dvec3 w = towardsBeam(scene, s, surface);
                        const double seen = projectedArea(normals, w);
                        return seen > 0.0 ? skimmedThroughRamp(normals, n, w, voxelOpticalDepth, channels[c].ch.g) / seen
                                          : 0.0;
                    };
                    const ReturnedLight skim =
                        returnedThrough(c, i, n, 0.0, SkyBeam{}, skimmed, &out.surface(i), index, shared);
                    facePeak[f] += out.surface(i).peak0[c] - peakBefore;
                    const double leaving = outflow[f].first[c], area = outflow[f].second;
                    const double exitance = area > 0.0 ? leaving / area : 0.0, own = kPi * h * h;
                    skimmedIn.push_back({n, (skim.sunShape0 + skim.sunReturned * 3.0 / 7.0) / own,
                                         (skim.sunShape1 + skim.sunReturned * 6.0 / 7.0 * n) / own});
                    faces.push_back({n, (r.sky0 + r.sun0) / own + exitance * (3.0 / 7.0 / kPi),
                                     (r.sky1 + r.sun1) / own + exitance * 6.0 / 7.0 / kPi * n});
                }
                // sigma_eff h = 3 kappa D sigma_tr h: the voxel in diffusion lengths of the snow beneath the patch.
                const double sigmaTr = channels[c].ch.sigmaTr(densityBeneath(topo, i, patch.normal));
                relaxTowardsNeighbours(faces, 3.0 * channels[c].ch.beta() * sigmaTr * h);
                // The skimmed light after relaxing: it stays on the face whose ramp caught it (before, it lifted the
                // lit face's corner air: slab_thick +8 -> +16 %).
                for (std::size_t q = 0; q < faces.size(); ++q)
                    faces[q].e0 += skimmedIn[q].e0, faces[q].e1 += skimmedIn[q].e1;
                const SourceLobe lobe = edgeLobe(faces);
                out.surface(i).returned.l0[c] = float(lobe.l0);
                out.surface(i).returned.l1[c] = glm::vec3(lobe.l1);
                for (const FaceExit &face : faces) {
                    const int f = faceBeneath(-face.normal);  // the air face of that normal
                    if (!(own.flat >> f & 1u)) continue;
                    const SourceLobe shown =
                        withCrossing(exitLobe(face.e0, face.e1, face.normal), out[i], patch.area, c, channels[c].ch.g);
                    own.lobe[f].l0[c] = float(shown.l0);
                    own.lobe[f].l1[c] = glm::vec3(shown.l1);
                }
            }
            const double peak = std::accumulate(facePeak.begin(), facePeak.end(), 0.0);
            for (int f = 0; f < 6 && peak > 0.0; ++f) own.peakShare[f] = float(facePeak[f] / peak);
            // Where its faces are walls, the voxel's one value shows their peaks through every air face (edgeLobe's
            // mix), the air across each face that face's own (ownFacesToward); kept whole where no face shows it
            // along its axis.
            SurfaceLight &lit = out.surface(i);
            if (!own.facesAreWalls(patch) || !(peak > 0.0) || lit.peak1 == glm::vec3(0.0f)) continue;
            radiance.clear();
            for (int f = 0; f < 6; ++f)
                if (patch.share[f] > 0.0f) radiance.push_back(own.peakShare[f] / patch.share[f]);
            const float shown = float(peakSeenThroughFaces(normals, radiance, glm::normalize(glm::dvec3(lit.peak1))));
            if (!(shown > 0.0f)) continue;
            lit.peak0 *= shown, lit.peak1 *= shown, lit.rampPeak0 *= shown, lit.rampPeak1 *= shown;
            for (float &share : own.peakShare) share /= shown;
        }
    });
    edgeFaces.voxels.erase(std::remove_if(edgeFaces.voxels.begin(), edgeFaces.voxels.end(),
                                          [](const EdgeFaceLobes::Voxel &v) { return v.flat == 0; }),
                           edgeFaces.voxels.end());
    sunLeavingDownstream(topo, sun, h, out, progress);
}

}  // namespace firn::bake
