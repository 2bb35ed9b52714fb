#include "firn/transport/incident_light.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/util/color.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

constexpr double kMinTransmittance = 1e-5;  // beams fainter than this are dropped

// Mass column (kg/m^2) beyond which every channel's reduced transmittance is below kMinTransmittance.
double columnLimit(const glm::dvec3 &reduced) {
    return std::log(1.0 / kMinTransmittance) / std::max(1e-12, std::min({reduced.x, reduced.y, reduced.z}));
}

// exp(-extinction column) per channel; exactly 1 without the exponentials where no snow is crossed (most sky rays).
glm::dvec3 transmittance(const glm::dvec3 &extinction, double column) {
    return column > 0.0 ? glm::exp(-extinction * column) : glm::dvec3(1.0);
}

// The delta-scaled extinction per unit density, per channel: k (1 - omega g^2) (m^2/kg; Crossing::Forward).
glm::dvec3 deltaScaledExtinctionPerDensity(const VolumeOptics &optics) {
    return optics.extinctionPerDensity * (glm::dvec3(1.0) - optics.albedo * (optics.g * optics.g));
}

glm::dvec3 extinction(const VolumeOptics &optics, Crossing crossing) {
    if (crossing == Crossing::Beam) return reducedExtinctionPerDensity(optics);
    if (crossing == Crossing::Forward) return deltaScaledExtinctionPerDensity(optics);
    return glm::dvec3(optics.extinctionPerDensity);
}

double largest(const glm::dvec3 &v) { return std::max({v.x, v.y, v.z}); }

// Snow transmittance from `point` along w (unit) up to `reach` (m) for Crossing::Spreading. Each stretch of snow
// the ray crosses (a piece: contiguous half-voxel samples with snow) lets through its uncollided light and, of
// what it scatters forwards (the similarity beam's e^-tau_tr less e^-tau), the share that reaches the point: a
// lone piece's forwardShare or, where larger, the snow beside the ray over the piece's own column (the mass seen
// through the forward cone's window across the ray at the piece's depth, BlockMasses::windowedColumn: in a wide
// cloud all of it arrives, what the point's own ray loses forwards its neighbours' rays bring), at most 1. 0 once
// every channel is below kMinTransmittance. Each piece is taken in as the march leaves it (nothing held per ray:
// a list of pieces was an allocation per patch and sun).
glm::dvec3 spreadingTransmittance(const Medium &medium, const BlockMasses &blocks, const glm::dvec3 &point,
                                  const glm::dvec3 &w, double reach, Medium::ColumnMarcher &marcher) {
    struct Piece {
        double near = 0.0, far = -1.0;  // m along the ray
        double column = 0.0;            // kg/m^2
    };
    const VolumeOptics &optics = medium.optics();
    const glm::dvec3 reduced = reducedExtinctionPerDensity(optics);
    const double thinnest = std::min({reduced.x, reduced.y, reduced.z});
    const double h = medium.voxelSize();
    const glm::dvec3 start = medium.worldToIndex(point);
    glm::dvec3 through(1.0);
    auto crossed = [&](const Piece &piece) {
        const double tau = optics.extinctionPerDensity * piece.column;
        const double uncollided = std::exp(-tau);
        const double alone = forwardShare(0.5 * (piece.far - piece.near), piece.near, tau, optics.g);
        const double beside =
            blocks.windowedColumn(point, w, piece.near, piece.far, piece.near * forwardConeWidth(tau, optics.g));
        const double share = std::min(1.0, std::max(alone, beside / piece.column));
        through *= uncollided + (glm::exp(-reduced * piece.column) - uncollided) * share;
    };
    Piece piece;  // the one the march is in (column 0 until it meets snow)
    double total = 0.0;
    marcher.march(point, w, reach, 0.5, [&](const openvdb::Vec3d &p, double dt) {
        const double rho = marcher.densityAt(p);
        if (rho <= 0.0) return true;
        const double t = h * glm::length(glm::dvec3(p.x(), p.y(), p.z()) - start);
        if (piece.column > 0.0 && t - 0.5 * dt > piece.far + 1e-3 * h) crossed(piece), piece = Piece();
        if (piece.column == 0.0) piece.near = t - 0.5 * dt;
        piece.column += rho * dt, piece.far = t + 0.5 * dt, total += rho * dt;
        return std::exp(-thinnest * total) >= kMinTransmittance;
    });
    if (piece.column > 0.0) crossed(piece);
    return largest(through) >= kMinTransmittance ? through : glm::dvec3(0.0);
}

// Irradiance (W/m^2) onto a surface with normal n at p from the sky, through snow and past occluders;
// occluders in the way send what they reflect once (when `bounce`). `occluderAlbedo`: adds the grey albedos of the
// occluders met by the rays snow does not hide (what they can send the snow's light back with), `occluderRays`
// marks those rays.
glm::vec3 skyIrradianceAt(const Scene &scene, const glm::dvec3 &p, const glm::dvec3 &n, const SkyRays &rays,
                          bool bounce, Crossing crossing, std::uint64_t seed, std::uint64_t stream,
                          Medium::ColumnMarcher &marcher, std::uint64_t *snowRays = nullptr, glm::vec3 *aim = nullptr,
                          double *occluderAlbedo = nullptr, std::uint64_t *occluderRays = nullptr,
                          double *greyError = nullptr) {
    const glm::dvec3 reduced = extinction(scene.medium->optics(), crossing);
    const double limit = columnLimit(reduced);
    const double thinnest = std::min({reduced.x, reduced.y, reduced.z});
    Rng rng(seed ^ 0xB0B0ull, stream);  // for the occluders' reflections
    glm::dvec3 sum(0.0), towards(0.0);
    double greySquares = 0.0;  // W^2/m^4, the rays' grey irradiance squared
    std::uint64_t hidden = 0, met = 0;
    // Without the bounce a ray that meets an occluder brings nothing, and unless asked which rays snow hides, whether
    // it meets one is all that counts: Embree's any-hit query, cheaper than the nearest hit.
    const bool anyHit = !bounce && !snowRays;
    const RayCaster &caster = scene.occluders->caster();
    for (int k = 0; k < rays.count(); ++k) {
        const glm::dvec3 w = rays.direction(n, k, seed, stream);
        std::optional<RayCaster::Hit> hit;
        if (!anyHit)
            hit = caster.intersect(glm::vec3(p), glm::vec3(w), 1e-5f);
        else if (caster.occluded(glm::vec3(p), glm::vec3(w), 1e-5f))
            continue;
        const double column =
            marcher.column(p, w, hit ? double(hit->distance) : std::numeric_limits<double>::infinity(), limit);
        if (thinnest * column > 0.01)
            hidden |= std::uint64_t(1) << k;  // snow glows along this ray
        else if (hit && occluderAlbedo)
            *occluderAlbedo += channelMean(scene.occluders->albedo(hit->triangle)), met |= std::uint64_t(1) << k;
        if (column >= limit) continue;
        glm::dvec3 radiance;
        if (!hit) {
            radiance = scene.sky.radianceFrom(w);
        } else if (bounce) {
            const glm::dvec3 normal(hit->normal);
            radiance = reflectedByOccluder(scene, p + double(hit->distance) * w, glm::faceforward(normal, w, normal),
                                           scene.occluders->albedo(hit->triangle), rng, marcher);
        } else {
            continue;
        }
        const glm::dvec3 arriving = kPi * radiance * transmittance(reduced, column);
        sum += arriving, towards += greyMoment(arriving, w), greySquares += std::pow(channelMean(arriving), 2);
    }
    if (greyError) {
        const double n = rays.count(), mean = channelMean(sum) / n;
        *greyError = n > 1 ? std::sqrt(std::max(0.0, greySquares / n - mean * mean) / (n - 1)) : 0.0;
    }
    if (snowRays) *snowRays = hidden;
    if (occluderRays) *occluderRays = met;
    if (aim) *aim = glm::vec3(towards / double(rays.count()));
    return glm::vec3(sum / double(rays.count()));
}

// Unknowns in the order beam b's light reaches them, in buckets half a voxel deep (nearest the light
// first), and each unknown's bucket: a voxel's neighbours one step towards the light lie in earlier buckets
// (at least h / sqrt(3) nearer, a few voxels away from a lamp), so a sweep can look back at them.
std::vector<std::vector<std::uint32_t>> bucketsAlongBeam(const Scene &scene, std::size_t b, const SnowTopology &topo,
                                                          std::vector<std::uint32_t> &bucketOf) {
    const Medium &medium = *scene.medium;
    std::vector<double> depth(topo.size());
    for (std::size_t i = 0; i < topo.size(); ++i) {
        const glm::dvec3 x = medium.voxelCentre(topo.coord[i]);
        depth[i] = b < scene.suns.size() ? -glm::dot(x, scene.suns[b].direction)
                                         : glm::length(x - scene.lamps[b - scene.suns.size()].position);
    }
    const double nearest = topo.size() ? *std::min_element(depth.begin(), depth.end()) : 0.0;
    std::vector<std::vector<std::uint32_t>> buckets;
    bucketOf.resize(topo.size());
    for (std::size_t i = 0; i < topo.size(); ++i) {
        bucketOf[i] = std::uint32_t((depth[i] - nearest) / (0.5 * medium.voxelSize()));
        if (bucketOf[i] >= buckets.size()) buckets.resize(bucketOf[i] + 1);
        buckets[bucketOf[i]].push_back(std::uint32_t(i));
    }
    return buckets;
}

// Offsets to a voxel's neighbours one step towards a light in direction w: along w's main axis, and
// diagonally along the others where w leans that way. At most four, held in place (the sweep asks for them at
// every voxel: a vector took up to three allocations each time).
struct Steps {
    std::array<openvdb::Coord, 4> offset;
    int count = 0;
    const openvdb::Coord *begin() const { return offset.data(); }
    const openvdb::Coord *end() const { return offset.data() + count; }
};
Steps stepsTowards(const glm::dvec3 &w) {
    const int axis =
        int(std::max_element(&w.x, &w.x + 3, [](double a, double b) { return std::abs(a) < std::abs(b); }) - &w.x);
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    Steps steps;
    for (int bu = 0; bu < 2; ++bu)
        for (int bv = 0; bv < 2; ++bv) {
            if ((bu && std::abs(w[u]) < 1e-3) || (bv && std::abs(w[v]) < 1e-3)) continue;
            openvdb::Coord o(0);
            o[axis] = w[axis] > 0.0 ? 1 : -1;
            if (bu) o[u] = w[u] > 0.0 ? 1 : -1;
            if (bv) o[v] = w[v] > 0.0 ? 1 : -1;
            steps.offset[steps.count++] = o;
        }
    return steps;
}

// What a traced patch's sky rays say, for its neighbours' test of agreement (skyDonorsAgree).
struct SkyEstimate {
    float grey = 0.0f, greyError = 0.0f;  // W/m^2: the grey irradiance and its standard error over the rays
    std::uint8_t rays = 0, hidden = 0, met = 0;  // rays; of them snow hides; snow does not hide that meet an occluder
    float albedoShare = 0.0f;                    // the occluders' albedo met, per ray (IncidentLight::occluderShare)
};

// Whether two patches' rays (each its own count) may see the same sky: the grey irradiance within kAgreement standard
// errors of the difference (1e-3 of it where both are exact: every ray open, or every ray hidden), and so the shares of
// the rays snow hides and occluders meet, with their binomial errors (what the gathering later reads along them).
bool skyAgrees(const SkyEstimate &a, const SkyEstimate &b) {
    constexpr double kAgreement = 2.0;
    const double error = std::hypot(double(a.greyError), double(b.greyError));
    if (std::abs(a.grey - b.grey) > kAgreement * error + 1e-3 * std::max(a.grey, b.grey)) return false;
    const auto shares = [&](int x, int y) {
        const double p = double(x) / a.rays, q = double(y) / b.rays;
        return std::abs(p - q) <= kAgreement * std::sqrt(p * (1.0 - p) / a.rays + q * (1.0 - q) / b.rays);
    };
    return shares(a.hidden, b.hidden) && shares(a.met, b.met);
}

// The mean of value(j) over surface voxel i's sky donors j (forEachSkyDonor), summed as T (double, glm::dvec3): a
// filled voxel's (fromDonors: at least two, skyDonorsAgree).
template <typename T, typename Value>
T skyDonorMean(const SnowTopology &topo, std::size_t i, const Value &value) {
    T sum(0.0);
    int count = 0;
    forEachSkyDonor(topo, i, [&](std::size_t j) { sum += value(j), ++count; });
    return sum / double(count);
}

// Whether surface voxel i's sky donors (forEachSkyDonor), at least two, agree pairwise.
bool skyDonorsAgree(const SnowTopology &topo, const SurfaceValues<SkyEstimate> &estimates, std::size_t i) {
    std::array<const SkyEstimate *, 26> donors;
    std::size_t count = 0;
    forEachSkyDonor(topo, i, [&](std::size_t j) { donors[count++] = &estimates[j]; });
    if (count < 2) return false;
    for (std::size_t a = 0; a < count; ++a)
        for (std::size_t b = a + 1; b < count; ++b)
            if (!skyAgrees(*donors[a], *donors[b])) return false;
    return true;
}

// body over [0, n) in pieces of at most kPiece items, a cancellation check before each: the auto partitioner's
// chunks may hold a large share of the scene (each item's values are its own: the pieces change none).
template <typename Body>
void parallelChunks(std::size_t n, const SubProgress &progress, const Body &body) {
    constexpr std::size_t kPiece = 256;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kPiece), [&](const auto &range) {
        for (std::size_t begin = range.begin(); begin < range.end(); begin += kPiece) {
            progress.throwIfCancelled();
            body(tbb::blocked_range<std::size_t>(begin, std::min(range.end(), begin + kPiece)));
        }
    });
}

}  // namespace

glm::dvec3 reflectedByOccluder(const Scene &scene, const glm::dvec3 &q, const glm::dvec3 &n, const Rgb &albedo,
                               Rng &rng, Medium::ColumnMarcher &marcher) {
    const glm::dvec3 reduced = reducedExtinctionPerDensity(scene.medium->optics());
    const double limit = columnLimit(reduced);
    const glm::dvec3 p = q + 1e-5 * n;
    const RayCaster &caster = scene.occluders->caster();
    glm::dvec3 irradiance(0.0);
    for (std::size_t b = 0; b < beamCount(scene); ++b) {
        const double cosine = glm::dot(n, towardsBeam(scene, b, p));
        if (!(cosine > 0.0)) continue;
        // A sun the occluders hide adds nothing: asked before beamAt's march through the snow, which costs more
        // (on the car the occluders hide three in four of the suns the snow lets through). The same query beamAt
        // asks of its one sample.
        if (b < scene.suns.size() && caster.occluded(glm::vec3(p), glm::vec3(scene.suns[b].direction), 1e-5f)) continue;
        irradiance += cosine * glm::dvec3(beamAt(scene, b, p, 1, 0, 0, marcher).irradiance);
    }
    const glm::dvec3 w = sampleCosineHemisphere(n, rng.uniform(), rng.uniform());
    if (!caster.occluded(glm::vec3(p), glm::vec3(w), 1e-5f)) {
        const double column = marcher.column(p, w, std::numeric_limits<double>::infinity(), limit);
        if (column < limit) irradiance += kPi * scene.sky.radianceFrom(w) * transmittance(reduced, column);
    }
    return albedo * irradiance / kPi;
}

double forwardConeWidth(double opticalDepth, double g) {
    const double scatterings = opticalDepth > 1e-6 ? opticalDepth / -std::expm1(-opticalDepth) : 1.0;
    return scatterings * (1.0 - g) / std::sqrt(std::max(g, 1e-6));
}

double forwardShare(double radius, double distance, double opticalDepth, double g) {
    const double spread = distance * forwardConeWidth(opticalDepth, g);
    if (!(spread > 0.0)) return 1.0;
    const double x = radius / spread;
    return 1.0 - 1.0 / std::sqrt(1.0 + x * x);
}

glm::dvec3 reducedExtinctionPerDensity(const VolumeOptics &optics) {
    return optics.extinctionPerDensity * (glm::dvec3(1.0) - optics.albedo * optics.g);
}

std::size_t beamCount(const Scene &scene) { return scene.suns.size() + scene.lamps.size(); }

glm::dvec3 towardsBeam(const Scene &scene, std::size_t b, const glm::dvec3 &point) {
    if (b < scene.suns.size()) return scene.suns[b].direction;
    const glm::dvec3 w = scene.lamps[b - scene.suns.size()].position - point;
    const double length = glm::length(w);
    return length > 0.0 ? w / length : glm::dvec3(0.0, 0.0, 1.0);
}

glm::dvec3 faceWayToBeam(const Scene &scene, std::size_t b, const glm::dvec3 &centre, const glm::dvec3 &face) {
    const glm::dvec3 atFace = towardsBeam(scene, b, face);
    if (b < scene.suns.size() || !scene.lamps[b - scene.suns.size()].isArea()) return atFace;
    const Lamp &lamp = scene.lamps[b - scene.suns.size()];
    const double d2 = glm::dot(lamp.position - centre, lamp.position - centre), a2 = lamp.area() / kPi;
    const glm::dvec3 atCentre = towardsBeam(scene, b, centre);
    return glm::normalize(atCentre + d2 / (d2 + a2) * (atFace - atCentre));
}

double nearFaceCosineToBeam(const Scene &scene, std::size_t b, const glm::dvec3 &centre, int f, double h) {
    const glm::dvec3 n = faceNormal(f);
    return glm::dot(n, faceWayToBeam(scene, b, centre, centre + 0.5 * h * n));
}

BeamSample beamAt(const Scene &scene, std::size_t b, const glm::dvec3 &point, int samples, std::uint64_t seed,
                  std::uint64_t stream, Medium::ColumnMarcher &marcher, const glm::dvec3 *shadowPoint,
                  Crossing crossing, const BlockMasses *blocks) {
    const glm::dvec3 reduced = extinction(scene.medium->optics(), crossing);
    const double limit = columnLimit(reduced);
    const bool sun = b < scene.suns.size();
    const glm::dvec3 w = towardsBeam(scene, b, point);
    const double reach = sun ? std::numeric_limits<double>::infinity()
                             : glm::length(scene.lamps[b - scene.suns.size()].position - point);
    BeamSample out;
    glm::dvec3 snow;
    if (crossing == Crossing::Spreading) {
        if (!blocks) throw std::logic_error("Crossing::Spreading needs the snow's block masses");
        snow = spreadingTransmittance(*scene.medium, *blocks, point, w, reach, marcher);
        out.snowBlocks = snow == glm::dvec3(0.0);
    } else {
        const double column = marcher.column(point, w, reach, limit);
        out.snowBlocks = column >= limit;
        snow = transmittance(reduced, column);
    }
    if (out.snowBlocks) return out;
    const glm::vec3 from(shadowPoint ? *shadowPoint : point);
    const RayCaster &caster = scene.occluders->caster();
    Rng rng(seed, stream);
    glm::dvec3 sum(0.0);
    if (sun) {
        const SunLight &light = scene.suns[b];
        int visible = samples;
        if (!scene.occluders->empty()) {
            visible = 0;
            for (int s = 0; s < samples; ++s) {
                const glm::dvec3 d =
                    samples == 1 ? light.direction : sampleSunDirection(light, rng.uniform(), rng.uniform());
                visible += !caster.occluded(from, glm::vec3(d), 1e-5f);
            }
        }
        sum = light.irradiance * double(visible);
    } else {
        const Lamp &lamp = scene.lamps[b - scene.suns.size()];
        if (lamp.shape != Lamp::Shape::Rectangle && lamp.shape != Lamp::Shape::Ellipse && lamp.radius == 0.0)
            samples = 1;
        for (int s = 0; s < samples; ++s) {
            const LampSample l = sampleLamp(lamp, glm::dvec3(from), rng.uniform(), rng.uniform());
            if (l.irradiance == Rgb(0.0)) continue;
            if (!caster.occluded(from, glm::vec3(l.direction), 1e-5f, float(l.distance * (1.0 - 1e-6))))
                sum += l.irradiance;
        }
    }
    out.irradiance = glm::vec3(snow * sum / double(samples));
    return out;
}

SkyRays::SkyRays(int samples) {
    const int count = std::clamp(samples, 1, kMaxRays);
    rows_ = int(std::sqrt(double(count)));
    while (count % rows_) --rows_;
    columns_ = count / rows_;
}

glm::dvec3 SkyRays::direction(const glm::dvec3 &normal, int k, std::uint64_t seed, std::uint64_t stream) const {
    Rng rng(seed, stream * 64 + std::uint64_t(k));
    return sampleCosineHemisphere(normal, (k / columns_ + rng.uniform()) / rows_,
                                  (k % columns_ + rng.uniform()) / columns_);
}

SkyRays skyRaysAt(const SnowTopology &topo, std::size_t i, int samples, bool lattice) {
    return SkyRays(lattice && (topo.patches[i].sharp || onSkyLattice(topo, i)) ? kLatticeRays * samples : samples);
}

bool onSkyLattice(const SnowTopology &topo, std::size_t i) {
    const int axis = faceBeneath(topo.patches[i].normal) / 2;
    const openvdb::Coord &c = topo.coord[i];
    return ((c[(axis + 1) % 3] | c[(axis + 2) % 3]) & 1) == 0;
}

void fillFromSkyDonors(const SnowTopology &topo, const SurfaceValues<std::uint8_t> &fromDonors,
                       SurfaceValues<glm::vec3> &values, bool leaning) {
    // v turned by the least rotation taking unit a onto unit b (Rodrigues' formula with u = a x b, c = a . b > -1).
    const auto turned = [](const glm::dvec3 &v, const glm::dvec3 &a, const glm::dvec3 &b) {
        const glm::dvec3 u = glm::cross(a, b);
        const double c = glm::dot(a, b);
        return v * c + glm::cross(u, v) + u * (glm::dot(u, v) / (1.0 + c));
    };
    // Donors lie on the lattice and are never filled: each value is read from traced ones alone.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            if (!topo.patches[i].isSurface() || !fromDonors[i]) continue;
            values.surface(i) = glm::vec3(skyDonorMean<glm::dvec3>(topo, i, [&](std::size_t j) {
                const glm::dvec3 v(values[j]);
                return leaning ? turned(v, topo.patches[j].normal, topo.patches[i].normal) : v;
            }));
        }
    });
}

void averageOverNeighbours(const SnowTopology &topo, SurfaceValues<glm::vec3> &values) {
    const auto own = values.values();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const SurfacePatch &patch = topo.patches[i];
            if (!patch.isSurface() || patch.sharp) continue;
            glm::dvec3 sum(0.0);
            int count = 0;
            for (std::size_t k = topo.neighbourhoodStart[i]; k < topo.neighbourhoodStart[i + 1]; ++k) {
                const std::uint32_t j = topo.neighbourhood[k];
                const SurfacePatch &other = topo.patches[j];
                if (other.sharp || glm::dot(patch.normal, other.normal) < kLikeFacingCosine) continue;
                sum += glm::dvec3(own[std::size_t((*topo.surfaceSlot)[j])]), ++count;
            }
            values.surface(i) = glm::vec3(sum / double(count));  // count >= 1: i itself
        }
    });
}

namespace {

// patchOutside out along `normal` (unit): the patch's own or one of a sharp voxel's air faces'.
glm::dvec3 outsideAlongNormal(const Medium &medium, const SnowTopology &topo, std::size_t i, const glm::dvec3 &normal,
                              Medium::Accessor &density) {
    const double h = medium.voxelSize();
    const double thin = kMinVoxelOpticalDepth / (medium.optics().extinctionPerDensity * h);
    const glm::dvec3 step = 0.5 * h * normal;
    glm::dvec3 p = medium.voxelCentre(topo.coord[i]) + h * normal;
    double rho = medium.densityAt(p, density);
    // Out of the patch's own ramp: where the density rises again the walk has entered other snow's (a narrow
    // groove's opposite wall), so it stops at the least dense point, never inside other snow.
    for (int k = 0; k < 6 && rho >= thin; ++k) {
        const double next = medium.densityAt(p + step, density);
        if (next > rho) break;
        p += step, rho = next;
    }
    return p;
}

}  // namespace

glm::dvec3 patchOutside(const Medium &medium, const SnowTopology &topo, std::size_t i, Medium::Accessor &density) {
    return outsideAlongNormal(medium, topo, i, topo.patches[i].normal, density);
}

glm::dvec3 patchSurface(const Medium &medium, const SnowTopology &topo, std::size_t i) {
    return medium.voxelCentre(topo.coord[i]) + 0.5 * medium.voxelSize() * topo.patches[i].normal;
}

glm::dvec3 patchOutsideAlong(const Medium &medium, const SnowTopology &topo, std::size_t i, const glm::dvec3 &w,
                             Medium::Accessor &density) {
    const SurfacePatch &patch = topo.patches[i];
    glm::dvec3 n = patch.normal;
    glm::dvec3 surface = patchSurface(medium, topo, i);
    if (patch.sharp) {
        // A sharp voxel's light enters by its air face most open to w, out of that face's own ramp: along the smooth
        // normal, which points out of the edge, a face lit past the normal's horizon started its ray 20 heights away,
        // beyond the snow in front (a cut side's corner on a slope facing away from the sun skipped the crest that
        // shades it: docs/benchmarks.md, bumpy-sides).
        if (const int f = patch.airFaceMostOpenTo(w); f >= 0) n = faceNormal(f);
        surface = medium.voxelCentre(topo.coord[i]) + 0.5 * medium.voxelSize() * n;
    }
    const double height = glm::length(outsideAlongNormal(medium, topo, i, n, density) - surface);
    // Out of the own ramp down to the sun lobe's least cosine (0.05, 3 degrees): capped at mu 1/3, a flat top's ray
    // under a sun below 20 degrees started inside its trilinear ramp and crossed it on a long chord (a sun 10 degrees
    // up -27.8 %, 3 degrees -87.5 % against the core's Monte Carlo; docs/benchmarks.md, grazing-sun).
    return surface + height / std::max(glm::dot(n, w), 0.05) * w;
}

// A patch facing away from a beam takes the beam in the ramp above it where the light meets the patch's normal at
// cosine above this: grazing rays skim a ball's one-voxel ramp to acos(R / (R + h/2)) past the terminator (20-25
// degrees on the suite's balls of 5-8 voxels), and behind that the ramp lies in the body's shadow. The bound,
// cos >= -sqrt(1 - R^2 / r^2) at r = R + h/2, does not depend on the light's distance: it holds for lamps as for
// the sun. On large bodies (a car panel, R 100 h: 6 degrees) the patches to 60 degrees past take a ray that finds
// the body's shadow.
constexpr double kRampBeamCosine = -0.5;

IncidentLight computeIncidentLight(const Scene &scene, const SnowTopology &topo,
                                   const IncidentLightSettings &settings, const SubProgress &progress) {
    const Medium &medium = *scene.medium;
    IncidentLight light;
    const double jobs = double(beamCount(scene) + 1);
    // Only the patches' beams read it (Crossing::Spreading): built here when there are beams, freed before the solves.
    const BlockMasses blocks =
        beamCount(scene) > 0 ? BlockMasses(medium.density(), medium.voxelSize(), medium.indexToWorld(glm::dvec3(0.0)))
                             : BlockMasses();

    for (std::size_t b = 0; b < beamCount(scene); ++b) {
        IncidentLight::Beam beam;
        parallelAssign(beam.atVoxel, topo.size(), glm::vec3(0.0f));
        beam.atSurface = SurfaceValues<glm::vec3>(topo.surfaceSlot, topo.surfaceVoxels(), glm::vec3(0.0f));
        const std::uint64_t seed = settings.seed ^ (0x5A17ull + b);
        // Voxel centres nearest the light first: a voxel inside the snow whose neighbours towards the light
        // all lie behind too much snow lies behind too much snow too, and needs no ray.
        std::vector<std::uint32_t> bucketOf;
        std::vector<std::uint8_t> blocked(topo.size(), 0);
        for (const std::vector<std::uint32_t> &bucket : bucketsAlongBeam(scene, b, topo, bucketOf))
            parallelChunks(bucket.size(), progress, [&](const auto &range) {
                Medium::ColumnMarcher marcher(medium);
                openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
                for (std::size_t n = range.begin(); n != range.end(); ++n) {
                    const std::uint32_t i = bucket[n];
                    const glm::dvec3 centre = medium.voxelCentre(topo.coord[i]);
                    bool dark = !topo.patches[i].isSurface();
                    for (const openvdb::Coord &step : stepsTowards(towardsBeam(scene, b, centre))) {
                        if (!dark) break;
                        const std::int32_t j = index.getValue(topo.coord[i] + step);
                        dark = j >= 0 && bucketOf[j] < bucketOf[i] && blocked[j];
                    }
                    if (dark) {
                        blocked[i] = 1;
                        continue;
                    }
                    const BeamSample sample = beamAt(scene, b, centre, settings.sunSamples, seed, 2 * i, marcher);
                    beam.atVoxel[i] = sample.irradiance;
                    blocked[i] = sample.snowBlocks;
                }
            });
        parallelChunks(topo.size(), progress, [&](const auto &range) {
            Medium::ColumnMarcher marcher(medium);
            Medium::Accessor density = medium.accessor();
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                const SurfacePatch &patch = topo.patches[i];
                if (!patch.isSurface()) continue;
                const glm::dvec3 surface = patchSurface(medium, topo, i), w = towardsBeam(scene, b, surface);
                if (patch.facesTowards(w)) {
                    // Snow in the way from the line through the patch along the light, past the density ramp
                    // (patchOutsideAlong); occluders' shadow on the surface itself (half a voxel out), so shadow
                    // edges fall where they do on the snow.
                    const glm::dvec3 from = patchOutsideAlong(medium, topo, i, w, density);
                    beam.atSurface.surface(i) = beamAt(scene, b, from, settings.sunSamples, seed, 2 * i + 1, marcher,
                                                       &surface, Crossing::Spreading, &blocks).irradiance;
                } else if (glm::dot(patch.normal, w) > kRampBeamCosine) {
                    // Past the terminator: the beam in the density ramp a voxel out along the normal (rampInflow),
                    // attenuated by sigma_tr as at the voxels: the grazing path runs through this body's own ramp.
                    // Other snow in front (a lump before the ball) passes its forward-scattered light on as beam
                    // here, which the patches' Crossing::Spreading would not: over-credited, untested.
                    const glm::dvec3 ramp = medium.voxelCentre(topo.coord[i]) + medium.voxelSize() * patch.normal;
                    beam.atSurface.surface(i) =
                        beamAt(scene, b, ramp, settings.sunSamples, seed, 2 * i + 1, marcher).irradiance;
                }
            }
        });
        light.beams.push_back(std::move(beam));
        progress.report((b + 1) / jobs);
    }

    light.skyOnSurface = SurfaceValues<glm::vec3>(topo.surfaceSlot, topo.surfaceVoxels(), glm::vec3(0.0f));
    light.snowRays = SurfaceValues<std::uint64_t>(topo.surfaceSlot, topo.surfaceVoxels(), 0);
    light.occluderRays = SurfaceValues<std::uint64_t>(topo.surfaceSlot, topo.surfaceVoxels(), 0);
    light.skyAim = SurfaceValues<glm::vec3>(topo.surfaceSlot, topo.surfaceVoxels(), glm::vec3(0.0f));
    const SkyRays rays(settings.skySamples);
    parallelAssign(light.skyUnderSnow, topo.faces.size(), glm::vec3(0.0f));
    const bool bounce = !scene.occluders->empty();
    const double limit = columnLimit(reducedExtinctionPerDensity(medium.optics()));
    const std::uint64_t seed = settings.seed ^ 0x5C1Eull;
    // The albedos met per ray, summed over the surface patches in fixed point (2^-32): integer sums do not depend on
    // how the threads split the patches, so the gate on the share (bake.cpp) is the same every run.
    std::atomic<std::uint64_t> albedoSum{0};
    std::atomic<std::size_t> skyTraced{0};
    const auto fixedPoint = [](double share) { return std::uint64_t(std::llround(share * 4294967296.0)); };
    // The lattice (and sharp voxels) first, then the voxels between, from their donors where those agree; without the
    // lattice all in the first pass.
    light.skyLattice = settings.skyOverNeighbours;
    SurfaceValues<SkyEstimate> estimates(topo.surfaceSlot, topo.surfaceVoxels());
    light.fromDonors = SurfaceValues<std::uint8_t>(topo.surfaceSlot, topo.surfaceVoxels(), 0);
    for (const bool first : {true, false}) {
        parallelChunks(topo.size(), progress, [&](const auto &range) {
            Medium::ColumnMarcher marcher(medium);
            Medium::Accessor density = medium.accessor();
            std::uint64_t albedos = 0;
            std::size_t traced = 0;
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                const SurfacePatch &patch = topo.patches[i];
                if (!patch.isSurface()) continue;
                if ((!light.skyLattice || patch.sharp || onSkyLattice(topo, i)) != first) continue;
                if (!first && skyDonorsAgree(topo, estimates, i)) {
                    light.fromDonors.surface(i) = 1;
                    continue;
                }
                double met = 0.0, greyError = 0.0;
                const SkyRays own = skyRaysAt(topo, i, settings.skySamples, light.skyLattice);
                const glm::vec3 sky = light.skyOnSurface.surface(i) = skyIrradianceAt(
                    scene, patchOutside(medium, topo, i, density), patch.normal, own, bounce, Crossing::Uncollided,
                    seed, i, marcher, &light.snowRays.surface(i), &light.skyAim.surface(i), &met,
                    &light.occluderRays.surface(i), &greyError);
                estimates.surface(i) = {float(channelMean(sky)), float(greyError), std::uint8_t(own.count()),
                                        std::uint8_t(__builtin_popcountll(light.snowRays[i])),
                                        std::uint8_t(__builtin_popcountll(light.occluderRays[i])),
                                        float(met / own.count())};
                albedos += fixedPoint(met / own.count()), ++traced;
            }
            albedoSum += albedos, skyTraced += traced;
        });
    }
    // A voxel filled from its donors counts their mean share: the traced voxels alone lie where the sky changes, by
    // the occluders (their share alone turned the send-back's gate on under a roof in black sky: test_geometry_inputs).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo.size(), 1024), [&](const auto &range) {
        std::uint64_t albedos = 0;
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            if (!topo.patches[i].isSurface() || !light.fromDonors[i]) continue;
            albedos += fixedPoint(
                skyDonorMean<double>(topo, i, [&](std::size_t j) { return double(estimates[j].albedoShare); }));
        }
        albedoSum += albedos;
    });
    fillFromSkyDonors(topo, light.fromDonors, light.skyOnSurface, false);
    fillFromSkyDonors(topo, light.fromDonors, light.skyAim, true);
    light.skyTraced = skyTraced;
    if (topo.surfaceVoxels() > 0) light.occluderShare = double(albedoSum) / 4294967296.0 / double(topo.surfaceVoxels());
    if (settings.skyOverNeighbours)
        averageOverNeighbours(topo, light.skyOnSurface), averageOverNeighbours(topo, light.skyAim);
    if (scene.sky.isBlack()) return light;
    parallelChunks(topo.faces.size(), progress, [&](const auto &range) {
        Medium::ColumnMarcher marcher(medium);
        for (std::size_t f = range.begin(); f != range.end(); ++f) {
            const BoundaryFace &face = topo.faces[f];
            if (!face.occluder) continue;
            // Sky light reaching the surface under the snow without scattering: only under thin snow.
            const glm::dvec3 n = faceNormal(face.face);
            const glm::dvec3 normal = glm::normalize(glm::dvec3(scene.occluders->mesh().crossNormal(face.triangle)));
            const glm::dvec3 up = glm::dot(normal, n) > 0.0 ? -normal : normal;  // towards the snow
            const glm::dvec3 ground = medium.voxelCentre(topo.coord[face.voxel]) + double(face.distance) * n;
            if (marcher.column(ground, up, std::numeric_limits<double>::infinity(), limit) >= limit) continue;
            light.skyUnderSnow[f] = skyIrradianceAt(scene, ground, up, rays, false, Crossing::Beam, seed,
                                                    topo.size() + f, marcher);
        }
    });
    return light;
}

}  // namespace firn
