#include "firn/incident_light.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "firn/random.h"
#include "firn/sampling.h"

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
glm::vec3 skyIrradianceAt(const Scene &scene, const glm::dvec3 &p, const glm::dvec3 &n, int samples, bool bounce,
                          Crossing crossing, std::uint64_t seed, std::uint64_t stream, Medium::ColumnMarcher &marcher,
                          float *snowCover = nullptr) {
    const glm::dvec3 reduced = extinction(scene.medium->optics(), crossing);
    const double limit = columnLimit(reduced);
    const int strata = std::max(1, int(std::lround(std::sqrt(double(samples)))));
    Rng rng(seed, stream);
    const double thinnest = std::min({reduced.x, reduced.y, reduced.z});
    glm::dvec3 sum(0.0);
    double covered = 0.0;
    for (int i = 0; i < strata; ++i)
        for (int j = 0; j < strata; ++j) {
            const glm::dvec3 w = sampleCosineHemisphere(n, (i + rng.uniform()) / strata, (j + rng.uniform()) / strata);
            const auto hit = scene.occluders->caster().intersect(glm::vec3(p), glm::vec3(w), 1e-5f);
            const double column = marcher.column(p, w, hit ? double(hit->distance) : std::numeric_limits<double>::infinity(), limit);
            covered += 1.0 - std::exp(-thinnest * column);
            if (column >= limit) continue;
            glm::dvec3 radiance;
            if (!hit) {
                radiance = scene.sky.radianceFrom(w);
            } else if (bounce) {
                const glm::dvec3 normal(hit->normal);
                radiance = reflectedByOccluder(scene, p + double(hit->distance) * w,
                                               glm::dot(normal, w) < 0.0 ? normal : -normal,
                                               scene.occluders->albedo(hit->triangle), rng, marcher);
            } else {
                continue;
            }
            sum += kPi * radiance * glm::exp(-reduced * column);
        }
    if (snowCover) *snowCover = float(covered / double(strata * strata));
    return glm::vec3(sum / double(strata * strata));
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
        parallelChunks(topo.size(), progress, [&](const auto &range) {
            Medium::ColumnMarcher marcher(medium);
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                beam.atVoxel[i] = sunBeamAt(scene, sun, medium.voxelCentre(topo.coord[i]), settings.sunSamples, seed,
                                            2 * i, marcher);
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
    light.snowCover.assign(topo.size(), 0.0f);
    light.skyUnderSnow.assign(topo.faces.size(), glm::vec3(0.0f));
    const bool bounce = !scene.occluders->empty();
    const double limit = columnLimit(reducedExtinctionPerDensity(medium.optics()));
    const std::uint64_t seed = settings.seed ^ 0x5C1Eull;
    parallelChunks(topo.size(), progress, [&](const auto &range) {
        Medium::ColumnMarcher marcher(medium);
        for (std::size_t i = range.begin(); i != range.end(); ++i)
            if (topo.patches[i].isSurface())
                light.skyOnSurface[i] = skyIrradianceAt(scene, outside(i), topo.patches[i].normal, settings.skySamples,
                                                        bounce, Crossing::Uncollided, seed, i, marcher,
                                                        &light.snowCover[i]);
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
            light.skyUnderSnow[f] = skyIrradianceAt(scene, ground, up, settings.skySamples, false, Crossing::Beam, seed,
                                                    topo.size() + f, marcher);
        }
    });
    return light;
}

}  // namespace firn
