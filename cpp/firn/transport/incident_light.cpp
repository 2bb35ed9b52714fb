#include "firn/transport/incident_light.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/util/random.h"
#include "firn/util/sampling.h"

namespace firn {

namespace {

constexpr double kMinTransmittance = 1e-5;  // beams fainter than this are dropped

// Mass column (kg/m^2) beyond which every channel's reduced transmittance is below kMinTransmittance.
double columnLimit(const glm::dvec3 &reduced) {
    return std::log(1.0 / kMinTransmittance) / std::max(1e-12, std::min({reduced.x, reduced.y, reduced.z}));
}


glm::dvec3 extinction(const VolumeOptics &optics, Crossing crossing) {
    return crossing == Crossing::Beam ? reducedExtinctionPerDensity(optics) : glm::dvec3(optics.extinctionPerDensity);
}

// Radiance (W/m^2/sr) an occluder sends from point q (unit normal n facing the viewer) after one
// reflection of sun and sky light, each estimated with one ray.
glm::dvec3 reflectedByOccluder(const Scene &scene, const glm::dvec3 &q, const glm::dvec3 &n, const Rgb &albedo,
                               Rng &rng, Medium::ColumnMarcher &marcher) {
    const glm::dvec3 reduced = reducedExtinctionPerDensity(scene.medium->optics());
    const double limit = columnLimit(reduced);
    const glm::dvec3 p = q + 1e-5 * n;
    glm::dvec3 irradiance(0.0);
    for (const SunLight &sun : scene.suns) {
        const double cosine = glm::dot(n, sun.direction);
        if (cosine > 0.0) irradiance += sun.irradiance * cosine * glm::dvec3(sunBeamAt(scene, sun, p, 1, 0, 0, marcher));
    }
    const glm::dvec3 w = sampleCosineHemisphere(n, rng.uniform(), rng.uniform());
    if (!scene.occluders->caster().occluded(glm::vec3(p), glm::vec3(w), 1e-5f)) {
        const double column = marcher.column(p, w, std::numeric_limits<double>::infinity(), limit);
        if (column < limit) irradiance += kPi * scene.sky.radianceFrom(w) * glm::exp(-reduced * column);
    }
    return albedo * irradiance / kPi;
}

// Irradiance (W/m^2) onto a surface with normal n at p from the sky, through snow and past occluders;
// occluders in the way send what they reflect once (when `bounce`).
glm::vec3 skyIrradianceAt(const Scene &scene, const glm::dvec3 &p, const glm::dvec3 &n, const SkyRays &rays, bool bounce,
                          Crossing crossing, std::uint64_t seed, std::uint64_t stream, Medium::ColumnMarcher &marcher,
                          std::uint64_t *snowRays = nullptr) {
    const glm::dvec3 reduced = extinction(scene.medium->optics(), crossing);
    const double limit = columnLimit(reduced);
    const double thinnest = std::min({reduced.x, reduced.y, reduced.z});
    Rng rng(seed ^ 0xB0B0ull, stream);  // for the occluders' reflections
    glm::dvec3 sum(0.0);
    std::uint64_t hidden = 0;
    for (int k = 0; k < rays.count(); ++k) {
        const glm::dvec3 w = rays.direction(n, k, seed, stream);
        const auto hit = scene.occluders->caster().intersect(glm::vec3(p), glm::vec3(w), 1e-5f);
        const double column = marcher.column(p, w, hit ? double(hit->distance) : std::numeric_limits<double>::infinity(), limit);
        if (thinnest * column > 0.01) hidden |= std::uint64_t(1) << k;  // snow glows along this ray
        if (column >= limit) continue;
        glm::dvec3 radiance;
        if (!hit) {
            radiance = scene.sky.radianceFrom(w);
        } else if (bounce) {
            const glm::dvec3 normal(hit->normal);
            radiance = reflectedByOccluder(scene, p + double(hit->distance) * w, glm::dot(normal, w) < 0.0 ? normal : -normal,
                                           scene.occluders->albedo(hit->triangle), rng, marcher);
        } else {
            continue;
        }
        sum += kPi * radiance * glm::exp(-reduced * column);
    }
    if (snowRays) *snowRays = hidden;
    return glm::vec3(sum / double(rays.count()));
}

constexpr float kDark = 1e-6f;  // beam fractions below this are darkness

// Unknowns grouped by their coordinate along `axis`, ordered so that `step` leads from one group to the next.
std::vector<std::vector<std::uint32_t>> slicesAlong(const SnowTopology &topo, int axis, int step) {
    if (topo.size() == 0) return {};
    int lo = topo.coord[0][axis], hi = lo;
    for (const openvdb::Coord &c : topo.coord) lo = std::min(lo, c[axis]), hi = std::max(hi, c[axis]);
    std::vector<std::vector<std::uint32_t>> slices(std::size_t(hi - lo + 1));
    for (std::size_t i = 0; i < topo.size(); ++i) slices[std::size_t(topo.coord[i][axis] - lo)].push_back(std::uint32_t(i));
    if (step < 0) std::reverse(slices.begin(), slices.end());
    return slices;
}

template <typename Body>
void parallelChunks(std::size_t n, const SubProgress &progress, const Body &body) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const auto &range) {
        progress.throwIfCancelled();
        body(range);
    });
}

}  // namespace

glm::dvec3 reducedExtinctionPerDensity(const VolumeOptics &optics) {
    return optics.extinctionPerDensity * (glm::dvec3(1.0) - optics.albedo * optics.g);
}

glm::vec3 sunBeamAt(const Scene &scene, const SunLight &sun, const glm::dvec3 &point, int sunSamples,
                    std::uint64_t seed, std::uint64_t stream, Medium::ColumnMarcher &marcher,
                    const glm::dvec3 *shadowPoint, Crossing crossing) {
    const glm::dvec3 reduced = extinction(scene.medium->optics(), crossing);
    const double limit = columnLimit(reduced);
    const double column = marcher.column(point, sun.direction, std::numeric_limits<double>::infinity(), limit);
    if (column >= limit) return glm::vec3(0.0f);
    const glm::vec3 from(shadowPoint ? *shadowPoint : point);
    int visible = sunSamples;
    if (!scene.occluders->empty()) {
        Rng rng(seed, stream);
        visible = 0;
        for (int s = 0; s < sunSamples; ++s) {
            const glm::dvec3 w = sunSamples == 1 ? sun.direction : sampleSunDirection(sun, rng.uniform(), rng.uniform());
            visible += !scene.occluders->caster().occluded(from, glm::vec3(w), 1e-5f);
        }
    }
    return glm::vec3(glm::exp(-reduced * column)) * (float(visible) / float(sunSamples));
}

SkyRays::SkyRays(int samples) : strata_(std::clamp(int(std::lround(std::sqrt(double(samples)))), 1, 8)) {}

glm::dvec3 SkyRays::direction(const glm::dvec3 &normal, int k, std::uint64_t seed, std::uint64_t stream) const {
    Rng rng(seed, stream * 64 + std::uint64_t(k));
    return sampleCosineHemisphere(normal, (k / strata_ + rng.uniform()) / strata_, (k % strata_ + rng.uniform()) / strata_);
}

glm::dvec3 patchOutside(const Medium &medium, const SnowTopology &topo, std::size_t i) {
    const double h = medium.voxelSize();
    const double thin = kMinVoxelOpticalDepth / (medium.optics().extinctionPerDensity * h);
    Medium::Accessor density = medium.accessor();
    glm::dvec3 p = medium.voxelCentre(topo.coord[i]) + h * topo.patches[i].normal;
    for (int k = 0; k < 6 && medium.densityAt(p, density) >= thin; ++k) p += 0.5 * h * topo.patches[i].normal;
    return p;
}

IncidentLight computeIncidentLight(const Scene &scene, const SnowTopology &topo,
                                   const IncidentLightSettings &settings, const SubProgress &progress) {
    const Medium &medium = *scene.medium;
    auto outside = [&](std::size_t i) { return patchOutside(medium, topo, i); };
    IncidentLight light;
    const double jobs = double(scene.suns.size() + 1);

    for (std::size_t s = 0; s < scene.suns.size(); ++s) {
        const SunLight &sun = scene.suns[s];
        IncidentLight::Beam beam;
        beam.atVoxel.assign(topo.size(), glm::vec3(0.0f));
        beam.atSurface.assign(topo.size(), glm::vec3(0.0f));
        const std::uint64_t seed = settings.seed ^ (0x5A17ull + s);
        // Voxel centres slice by slice across the sun's main axis, sunward slice first: a voxel inside the
        // snow whose sunward neighbours all lie in darkness is dark too, and needs no ray.
        const int axis = int(std::max_element(&sun.direction.x, &sun.direction.x + 3,
                                              [](double a, double b) { return std::abs(a) < std::abs(b); }) -
                             &sun.direction.x);
        const int toward = sun.direction[axis] > 0.0 ? 1 : -1;
        std::vector<openvdb::Coord> upstream;  // offsets to the sunward neighbours in the previous slice
        for (int b = 0; b < 2; ++b)
            for (int c = 0; c < 2; ++c) {
                openvdb::Coord o(0);
                o[axis] = toward;
                const int u = (axis + 1) % 3, v = (axis + 2) % 3;
                if (b) o[u] = sun.direction[u] > 0.0 ? 1 : -1;
                if (c) o[v] = sun.direction[v] > 0.0 ? 1 : -1;
                if ((b && std::abs(sun.direction[u]) < 1e-3) || (c && std::abs(sun.direction[v]) < 1e-3)) continue;
                upstream.push_back(o);
            }
        const std::vector<std::vector<std::uint32_t>> slices = slicesAlong(topo, axis, -toward);
        for (const std::vector<std::uint32_t> &slice : slices)
            parallelChunks(slice.size(), progress, [&](const auto &range) {
                Medium::ColumnMarcher marcher(medium);
                openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
                for (std::size_t n = range.begin(); n != range.end(); ++n) {
                    const std::uint32_t i = slice[n];
                    bool dark = !topo.patches[i].isSurface();
                    for (std::size_t k = 0; k < upstream.size() && dark; ++k) {
                        const std::int32_t j = index.getValue(topo.coord[i] + upstream[k]);
                        dark = j >= 0 && std::max({beam.atVoxel[j].x, beam.atVoxel[j].y, beam.atVoxel[j].z}) < kDark;
                    }
                    if (!dark)
                        beam.atVoxel[i] = sunBeamAt(scene, sun, medium.voxelCentre(topo.coord[i]), settings.sunSamples,
                                                    seed, 2 * i, marcher);
                }
            });
        parallelChunks(topo.size(), progress, [&](const auto &range) {
            Medium::ColumnMarcher marcher(medium);
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                if (topo.patches[i].isSurface() && glm::dot(topo.patches[i].normal, sun.direction) > 0.0) {
                    // Snow in the way from outside the density ramp; occluders' shadow on the surface itself
                    // (half a voxel out), so shadow edges fall where they do on the snow.
                    const glm::dvec3 surface = medium.voxelCentre(topo.coord[i]) + 0.5 * medium.voxelSize() * topo.patches[i].normal;
                    beam.atSurface[i] = sunBeamAt(scene, sun, outside(i), settings.sunSamples, seed, 2 * i + 1, marcher,
                                                  &surface, Crossing::Uncollided);
                }
            }
        });
        light.beams.push_back(std::move(beam));
        progress.report((s + 1) / jobs);
    }

    light.skyOnSurface.assign(topo.size(), glm::vec3(0.0f));
    light.snowRays.assign(topo.size(), 0);
    const SkyRays rays(settings.skySamples);
    light.skyUnderSnow.assign(topo.faces.size(), glm::vec3(0.0f));
    const bool bounce = !scene.occluders->empty();
    const double limit = columnLimit(reducedExtinctionPerDensity(medium.optics()));
    const std::uint64_t seed = settings.seed ^ 0x5C1Eull;
    parallelChunks(topo.size(), progress, [&](const auto &range) {
        Medium::ColumnMarcher marcher(medium);
        for (std::size_t i = range.begin(); i != range.end(); ++i)
            if (topo.patches[i].isSurface())
                light.skyOnSurface[i] = skyIrradianceAt(scene, outside(i), topo.patches[i].normal, rays, bounce,
                                                        Crossing::Uncollided, seed, i, marcher, &light.snowRays[i]);
    });
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
