// Bake Scattering: optics, lights, the bake itself, and the reference tools the tests and benchmarks use.
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "firn/io/vdb_io.h"
#include "firn/transport/bake.h"
#include "firn/transport/half_space.h"
#include "firn/transport/joint_medium.h"
#include "firn/transport/monte_carlo.h"
#include "firn/transport/nishita_sky.h"
#include "firn/transport/slab.h"
#include "firn/transport/source_lobe.h"
#include "firn/util/error.h"
#include "firn/util/random.h"
#include "firn/util/sampling.h"
#include "mesh_arrays.h"

namespace py = pybind11;

namespace firncore {

namespace {


RgbTuple rgbFrom(const py::handle &values, const char *what) {
    const py::sequence rgb = itemsOf(values, 3, what, "(r, g, b)");
    RgbTuple out;
    for (std::size_t c = 0; c < 3; ++c) {
        out[c] = PyFloat_AsDouble(py::object(rgb[c]).ptr());
        if (out[c] == -1.0 && PyErr_Occurred()) {
            PyErr_Clear();
            throw firn::InvalidArgument(std::string(what) + " must be three numbers");
        }
    }
    return out;
}

firn::BakeQuality parseQuality(const std::string &name) {
    if (name == "DRAFT") return firn::BakeQuality::Draft;
    if (name == "FINAL") return firn::BakeQuality::Final;
    if (name == "REFERENCE") return firn::BakeQuality::Reference;
    throw firn::InvalidArgument("quality must be 'DRAFT', 'FINAL' or 'REFERENCE', not '" + name + "'");
}

// (vertices (N, 3) m, triangles (M, 3), albedo (r, g, b)) per object, merged with one albedo per triangle.
// Occluders as copied out of Python (with the GIL); their ray-tracing structure is built without it.
struct OccluderArrays {
    std::vector<firn::TriangleMesh> meshes;
    std::vector<firn::Rgb> albedo;  // per triangle
};

OccluderArrays occludersFrom(const py::list &objects) {
    OccluderArrays out;
    for (const py::handle &object : objects) {
        const py::sequence item = itemsOf(object, 3, "an occluder", "(vertices, triangles, albedo)");
        out.meshes.push_back(meshFromArrays(item[0], item[1], "occluder"));
        out.albedo.insert(out.albedo.end(), out.meshes.back().triangleCount(), rgb(rgbFrom(item[2], "occluder albedo")));
    }
    return out;
}

openvdb::FloatGrid::Ptr densityGrid(const openvdb::GridPtrVec &grids, const std::string &path) {
    for (const auto &grid : grids)
        if (grid->getName() == "density")
            if (auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(grid)) return density;
    throw firn::InvalidArgument(path + " has no float grid named 'density'");
}

// Heavy (reads the grids' scene, builds the occluders' BVH): call it inside longCall.
firn::Scene sceneFrom(const openvdb::GridPtrVec &grids, const std::string &path, const firn::VolumeOptics &optics,
                      const std::vector<firn::SunLight> &suns, const std::vector<firn::Lamp> &lamps,
                      const std::optional<firn::Sky> &sky, OccluderArrays occluders) {
    firn::Scene scene;
    scene.medium = std::make_shared<firn::Medium>(densityGrid(grids, path), optics);
    scene.suns = suns;
    scene.lamps = lamps;
    if (sky) scene.sky = *sky;
    if (!occluders.meshes.empty())
        scene.occluders =
            std::make_shared<firn::Occluders>(firn::merge(occluders.meshes), std::move(occluders.albedo));
    firn::validate(scene);
    return scene;
}

std::vector<firn::Ray> raysFrom(const DoubleArray &origins, const DoubleArray &directions) {
    if (origins.ndim() != 2 || origins.shape(1) != 3 || directions.ndim() != 2 || directions.shape(1) != 3 ||
        origins.shape(0) != directions.shape(0))
        throw firn::InvalidArgument("origins and directions must be (N, 3) arrays of the same length");
    std::vector<firn::Ray> rays(origins.shape(0));
    for (py::ssize_t i = 0; i < origins.shape(0); ++i) {
        const glm::dvec3 d(directions.at(i, 0), directions.at(i, 1), directions.at(i, 2));
        const double length = glm::length(d);
        if (!(length > 0.0) || !std::isfinite(length)) throw firn::InvalidArgument("ray directions must be non-zero");
        const glm::dvec3 o(origins.at(i, 0), origins.at(i, 1), origins.at(i, 2));
        if (!std::isfinite(o.x + o.y + o.z)) throw firn::InvalidArgument("ray origins must be finite");
        rays[i] = {o, d / length};
    }
    return rays;
}

void bindLights(py::module_ &m) {
    py::class_<firn::SunLight>(m, "SunLight", R"doc(
A distant disc light (Blender's Sun): direction towards the sun (world, normalized here), irradiance in
W/m^2 per RGB channel on a plane facing it, angular_diameter in radians.)doc")
        .def(py::init([](const RgbTuple &direction, const RgbTuple &irradiance, double angularDiameter) {
                 const glm::dvec3 d(direction[0], direction[1], direction[2]);
                 const double length = glm::length(d);
                 if (!(length > 0.0) || !std::isfinite(length)) throw firn::InvalidArgument("sun direction must be non-zero");
                 firn::SunLight sun{d / length, rgb(irradiance), angularDiameter};
                 firn::validate(sun);
                 return sun;
             }),
             py::arg("direction"), py::arg("irradiance"), py::arg("angular_diameter") = 0.0)
        .def_property_readonly("direction", [](const firn::SunLight &s) { return tuple(s.direction); })
        .def_property_readonly("irradiance", [](const firn::SunLight &s) { return tuple(s.irradiance); })
        .def_readonly("angular_diameter", &firn::SunLight::angularDiameter);

    py::class_<firn::Lamp>(m, "Lamp", R"doc(
A lamp at a finite distance (cpp/firn/transport/lamps.h). shape: 'POINT', 'SPOT' (spheres of `radius` m,
emission = intensity W/sr per RGB channel; Blender: Power / (4 pi) x Color), 'RECTANGLE' or 'ELLIPSE'
(one-sided, `size` = (x, y) m, emission = radiance W/m^2/sr; Blender: Power / (4 area) x Color).
position (m), axis: where a spot or area lamp shines (Blender: the lamp's -Z), tangent: an area's x
direction (both normalized here, tangent made perpendicular to axis); spot_angle (rad, full) and
spot_blend (0..1) as Blender's Spot Size and Blend.)doc")
        .def(py::init([](const std::string &shape, const RgbTuple &position, const RgbTuple &emission,
                         const RgbTuple &axis, const RgbTuple &tangent, double radius, double spotAngle,
                         double spotBlend, const std::array<double, 2> &size) {
                 firn::Lamp lamp;
                 if (shape == "POINT") lamp.shape = firn::Lamp::Shape::Point;
                 else if (shape == "SPOT") lamp.shape = firn::Lamp::Shape::Spot;
                 else if (shape == "RECTANGLE") lamp.shape = firn::Lamp::Shape::Rectangle;
                 else if (shape == "ELLIPSE") lamp.shape = firn::Lamp::Shape::Ellipse;
                 else throw firn::InvalidArgument("lamp shape must be 'POINT', 'SPOT', 'RECTANGLE' or 'ELLIPSE', not '" + shape + "'");
                 const glm::dvec3 a(axis[0], axis[1], axis[2]), t(tangent[0], tangent[1], tangent[2]);
                 const glm::dvec3 across = t - glm::dot(t, a) / std::max(glm::dot(a, a), 1e-300) * a;
                 if (!(glm::length(a) > 0.0) || !(glm::length(across) > 0.0))
                     throw firn::InvalidArgument("lamp axis and tangent must be non-zero and not parallel");
                 lamp.position = {position[0], position[1], position[2]};
                 lamp.axis = glm::normalize(a), lamp.tangent = glm::normalize(across);
                 lamp.emission = rgb(emission);
                 lamp.radius = radius, lamp.spotAngle = spotAngle, lamp.spotBlend = spotBlend;
                 lamp.sizeX = size[0], lamp.sizeY = size[1];
                 firn::validate(lamp);
                 return lamp;
             }),
             py::arg("shape"), py::arg("position"), py::arg("emission"), py::arg("axis") = RgbTuple{0.0, 0.0, -1.0},
             py::arg("tangent") = RgbTuple{1.0, 0.0, 0.0}, py::arg("radius") = 0.0, py::arg("spot_angle") = firn::kPi,
             py::arg("spot_blend") = 0.0, py::arg("size") = std::array<double, 2>{1.0, 1.0})
        .def_property_readonly("position", [](const firn::Lamp &l) { return tuple(l.position); })
        .def_property_readonly("emission", [](const firn::Lamp &l) { return tuple(l.emission); })
        .def(
            "irradiance",
            [](const firn::Lamp &l, const RgbTuple &point, const RgbTuple &normal, int samples, std::uint64_t seed) -> RgbTuple {
                if (samples < 1 || samples > 10000000) throw firn::InvalidArgument("samples must be between 1 and 1e7");
                const glm::dvec3 n = glm::normalize(glm::dvec3(normal[0], normal[1], normal[2]));
                firn::Rng rng(seed, 0);
                firn::Rgb sum(0.0);
                for (int s = 0; s < samples; ++s) {
                    const firn::LampSample sample = firn::sampleLamp(l, {point[0], point[1], point[2]}, rng.uniform(), rng.uniform());
                    sum += sample.irradiance * std::max(0.0, glm::dot(n, sample.direction));
                }
                return tuple(sum / double(samples));
            },
            py::arg("point"), py::arg("normal"), py::arg("samples") = 1, py::arg("seed") = 0,
            "Irradiance (W/m^2) onto a surface at `point` facing `normal`, nothing in between (mean of `samples`).");

    py::class_<firn::Sky>(m, "Sky", R"doc(
The world's light. radiance: W/m^2/sr per RGB channel, uniform, or scaling `map`, an equirectangular
(H, W, 3 or 4) float array in Blender's convention: rows from the bottom (nadir) up to the top (zenith),
as Image.pixels; u = 0.5 looks along +X, u = 0.25 along +Y (Environment Texture, default mapping).)doc")
        .def(py::init([](const RgbTuple &radiance, const std::optional<FloatArray> &map) {
                 firn::Sky sky{rgb(radiance), nullptr};
                 if (map) {
                     if (map->ndim() != 3 || (map->shape(2) != 3 && map->shape(2) != 4))
                         throw firn::InvalidArgument("sky map must be an (H, W, 3) or (H, W, 4) array");
                     const int height = int(map->shape(0)), width = int(map->shape(1)), stride = int(map->shape(2));
                     std::vector<firn::Rgb> pixels(std::size_t(width) * height);
                     const float *data = map->data();
                     for (std::size_t i = 0; i < pixels.size(); ++i)
                         pixels[i] = firn::Rgb(data[i * stride], data[i * stride + 1], data[i * stride + 2]);
                     sky.map = std::make_shared<firn::EnvironmentMap>(width, height, std::move(pixels));
                 }
                 firn::validate(sky);
                 return sky;
             }),
             py::arg("radiance") = RgbTuple{1.0, 1.0, 1.0}, py::arg("map") = py::none())
        .def_property_readonly("radiance", [](const firn::Sky &s) { return tuple(s.radiance); })
        .def(
            "radiance_from",
            [](const firn::Sky &s, const RgbTuple &d) -> RgbTuple {
                return tuple(s.radianceFrom(glm::normalize(glm::dvec3(d[0], d[1], d[2]))));
            },
            py::arg("direction"), "Radiance arriving from a world direction (W/m^2/sr).");
}

// A direction from Python, made unit; InvalidArgument when it has no length.
glm::dvec3 unitDirection(const RgbTuple &d) {
    const glm::dvec3 v(d[0], d[1], d[2]);
    const double length = glm::length(v);
    if (!(length > 0.0) || !std::isfinite(length)) throw firn::InvalidArgument("direction must be finite and non-zero");
    return v / length;
}

// Blender's Nishita Sky Texture, computed by the core (no Cycles render on Blender's main thread).
void bindNishitaSky(py::module_ &m) {
    using S = firn::NishitaSky;
    py::class_<S>(m, "NishitaSky", R"doc(
Blender's Sky Texture (Nishita) behind a Background node of `strength`, its settings as the node names them
(angles in rad, altitude in m): the sky of Nishita et al. 1993 as Cycles 3.4 renders it, in W/m^2/sr.)doc")
        .def(py::init([](const py::kwargs &kwargs) { return settingsFromKwargs<S>(kwargs, "NishitaSky"); }))
        .def_readwrite("sun_elevation", &S::sunElevation, "rad above the horizon")
        .def_readwrite("sun_rotation", &S::sunRotation, "rad about +Z; 0 puts the sun towards +Y, turning to +X")
        .def_readwrite("sun_size", &S::sunSize, "rad, the disc's angular diameter")
        .def_readwrite("sun_intensity", &S::sunIntensity, "scales the disc only")
        .def_readwrite("sun_disc", &S::sunDisc)
        .def_readwrite("altitude", &S::altitude, "m above sea level")
        .def_readwrite("air_density", &S::airDensity)
        .def_readwrite("dust_density", &S::dustDensity)
        .def_readwrite("ozone_density", &S::ozoneDensity)
        .def_readwrite("strength", &S::strength, "the Background node's Strength")
        .def_property_readonly("sun_direction", [](const S &s) { return tuple(firn::sunDirection(s)); })
        .def(
            "radiance",
            [](const S &s, const RgbTuple &d) {
                firn::validate(s);
                return tuple(firn::skyRadiance(s, unitDirection(d)));
            },
            py::arg("direction"), "Radiance of the sky without its sun disc from a world direction (W/m^2/sr).")
        .def(
            "sun_disc_radiance",
            [](const S &s, const RgbTuple &d) {
                firn::validate(s);
                return tuple(firn::sunDiscRadiance(s, unitDirection(d)));
            },
            py::arg("direction"), "Radiance of the sun disc from a world direction (W/m^2/sr), 0 off the disc.")
        .def(
            "sun",
            [](const S &s) {
                firn::validate(s);
                return firn::nishitaSun(s);
            },
            "The sun disc as a SunLight (irradiance integrated over the disc above the horizon), or None.")
        .def(
            "map",
            [](const S &s, const std::optional<DoubleArray> &rotation, int width, int height, int samples) {
                glm::dmat3 toWorld(1.0);
                if (rotation) {
                    if (rotation->ndim() != 2 || rotation->shape(0) != 3 || rotation->shape(1) != 3)
                        throw firn::InvalidArgument("rotation must be a 3 x 3 array");
                    for (int row = 0; row < 3; ++row)
                        for (int column = 0; column < 3; ++column) toWorld[column][row] = rotation->at(row, column);
                }
                const std::vector<firn::Rgb> map =
                    longCall([&] { return firn::nishitaSkyMap(s, toWorld, width, height, samples); });
                py::array_t<float> pixels({py::ssize_t(height), py::ssize_t(width), py::ssize_t(3)});
                auto out = pixels.mutable_unchecked<3>();
                for (int row = 0; row < height; ++row)
                    for (int column = 0; column < width; ++column)
                        for (int c = 0; c < 3; ++c)
                            out(row, column, c) = float(map[std::size_t(row) * width + column][c]);
                return pixels;
            },
            py::arg("rotation") = py::none(), py::arg("width") = 128, py::arg("height") = 64, py::arg("samples") = 2,
            R"doc(The sky without its disc as an equirectangular (height, width, 3) float32 map in Sky's convention
(rows bottom to top) for a frame whose directions `rotation` (3 x 3) turns into world directions; each pixel
the mean of samples x samples directions over it. Runs in parallel without the GIL.)doc");
}

firn::BakeSettings bakeSettings(const std::string &quality, std::uint64_t seed, int skySamples, int sunSamples,
                               int referenceSamples, int sourceScale, bool lightTracing = true) {
    firn::BakeSettings settings;
    settings.quality = parseQuality(quality);
    settings.seed = seed;
    settings.skySamples = skySamples;
    settings.sunSamples = sunSamples;
    settings.referenceSamples = referenceSamples;
    settings.sourceScale = sourceScale;
    settings.lightTracing = lightTracing;
    return settings;
}

// Writes `output`: the grids of `path` with `density` in its density's place and `baked` in place of any earlier
// bake's grids, its scatter grid too (the car's surface grid is read only now: 14 bytes per voxel). A cancel of
// `progress` (may be null) while the grids are compressed leaves `output` as it was.
void writeBaked(const std::string &path, const openvdb::GridBase::Ptr &density, const firn::BakedGrids &baked,
                const std::string &output, const firn::Progress *progress) {
    openvdb::GridPtrVec grids;
    for (const std::string &name : firn::gridNames(path))
        if (name == "density") grids.push_back(density);
        else if (!firn::BakedGrids::isBaked(name))
            grids.push_back(firn::readGrid(path, name));
    for (const auto &grid : baked.grids()) grids.push_back(grid);
    if (progress) progress->throwIfCancelled();  // the other grids' read
    firn::writeGrids(output, grids, progress);
}

// The 'density' grid of one of a joint bake's files (read alone). Throws InvalidArgument when it has none.
openvdb::FloatGrid::Ptr jointDensity(const std::string &path) {
    const openvdb::GridBase::Ptr grid = firn::readGrid(path, "density");
    return densityGrid(grid ? openvdb::GridPtrVec{grid} : openvdb::GridPtrVec{}, path);
}

py::dict phasesDict(const firn::BakeStats::Phases &phases) {
    py::dict d;
    d["topology"] = phases.topology, d["light"] = phases.light, d["trace"] = phases.trace;
    d["solve"] = phases.solve, d["gather"] = phases.gather, d["grids"] = phases.grids;
    return d;
}

py::dict statsDict(const firn::BakeStats &stats) {
    py::dict d;
    d["unknowns"] = stats.unknowns;
    d["surface_voxels"] = stats.surfaceVoxels;
    d["sky_traced_voxels"] = stats.skyTracedVoxels;
    d["traced_voxels"] = stats.tracedVoxels;
    d["scatter_voxels"] = stats.scatterVoxels;
    d["traced_paths"] = stats.tracedPaths;
    d["traced_faces"] = stats.tracedFaces;
    d["face_paths"] = stats.facePaths;
    d["light_traced_voxels"] = stats.lightTracedVoxels;
    d["photons"] = stats.photons;
    d["light_tracing_bytes"] = stats.lightTracingBytes;
    d["air_faces"] = stats.airFaces;
    d["occluder_faces"] = stats.occluderFaces;
    d["iterations"] = stats.iterations;
    d["beam_iterations"] = stats.beamIterations;
    d["relative_residual"] = stats.relativeResidual;
    d["passes"] = stats.passes;
    d["source_scale"] = stats.sourceScale;
    d["seconds"] = phasesDict(stats.seconds);
    d["cpu_seconds"] = phasesDict(stats.cpuSeconds);
    return d;
}

}  // namespace

void bindTransport(py::module_ &m) {
    bindLights(m);
    bindNishitaSky(m);
    {
        py::tuple names(firn::BakedGrids::kCount);
        for (std::size_t k = 0; k < firn::BakedGrids::kCount; ++k) names[k] = firn::BakedGrids::kNames[k];
        m.attr("BAKED_GRID_NAMES") = names;
        m.attr("SCATTER_GRID_NAME") = firn::BakedGrids::kScatterName;  // written only where the renderer scatters
        m.attr("SCATTER_SCALE") = firn::BakedGrids::kScatterScale;      // its voxels per axis, in density voxels
    }
    m.attr("LOBE_MAX_ANISOTROPY") = firn::kMaxLobeAnisotropy;  // the baked lobe's largest k (source_lobe.h)

    m.def(
        "bake",
        [](const std::string &path, const firn::VolumeOptics &optics, const std::vector<firn::SunLight> &suns,
           const std::optional<firn::Sky> &sky, const py::list &occluders, const std::string &quality,
           std::uint64_t seed, std::shared_ptr<firn::Progress> progress, int skySamples, int sunSamples,
           int referenceSamples, const std::optional<std::string> &outputPath, const std::vector<firn::Lamp> &lamps,
           int sourceScale, bool lightTracing) {
            const firn::BakeSettings settings =
                bakeSettings(quality, seed, skySamples, sunSamples, referenceSamples, sourceScale, lightTracing);
            OccluderArrays blockers = occludersFrom(occluders);
            firn::BakeStats stats;
            longCall([&] {
                // The bake holds the density alone: the file's other grids are read when it is written back (the
                // car's surface grid: 14 bytes per voxel), and an earlier bake's grids are replaced, never read.
                const openvdb::GridBase::Ptr density = firn::readGrid(path, "density");
                const firn::Scene scene = sceneFrom(density ? openvdb::GridPtrVec{density} : openvdb::GridPtrVec{}, path,
                                                    optics, suns, lamps, sky, std::move(blockers));
                const firn::BakedGrids baked = firn::bakeScattering(scene, settings, progress.get(), &stats);
                writeBaked(path, density, baked, outputPath.value_or(path), progress.get());
            });
            return statsDict(stats);
        },
        py::arg("vdb_path"), py::arg("optics"), py::arg("suns") = std::vector<firn::SunLight>{},
        py::arg("sky") = py::none(), py::arg("occluders") = py::list(), py::arg("quality") = "FINAL",
        py::arg("seed") = 0, py::arg("progress") = nullptr, py::arg("sky_samples") = 0, py::arg("sun_samples") = 0,
        py::arg("reference_samples") = 0, py::arg("output_path") = py::none(),
        py::arg("lamps") = std::vector<firn::Lamp>{}, py::arg("source_scale") = 0, py::arg("light_tracing") = true,
        R"doc(
Bakes the light scattered inside the snow of `vdb_path` (its 'density' grid, kg/m^3), lit by `suns`, `lamps`
(firncore.Lamp) and `sky`, and writes the file
back, atomically, with the baked grids BAKED_GRID_NAMES added, and SCATTER_GRID_NAME where the renderer scatters
in traced thin snow (docs/vdb-contract.md; an earlier bake's are replaced or removed), or, given `output_path`,
writes that file instead and leaves `vdb_path` as it was. occluders: list of
(vertices (N, 3) float32 m, triangles (M, 3) uint32, albedo (r, g, b)). quality: 'DRAFT', 'FINAL' or
'REFERENCE' (Monte Carlo surface, slow). sky_samples (rays per surface voxel, at most 64), sun_samples
(points on a sun's disc or a lamp) and reference_samples (paths per direction, REFERENCE) override the quality's
defaults when non-zero. source_scale: the baked grids' voxel size in density voxels (1: as fine as the
density; 2: an eighth of the memory Cycles needs for them; 0: the finest within 512 MB of Cycles' memory).
light_tracing: False leaves the voxels too costly to gather per voxel to the diffusion, and light traces none
(docs/bake.md Method 3; for measuring the diffusion). Releases the GIL; raises firncore.Cancelled if `progress` is
cancelled, ValueError for bad input, firncore.ReadError (an OSError) when `vdb_path` is missing or damaged,
firncore.WriteError (an OSError) when the result cannot be written. Returns the solve's statistics.)doc");

    m.def(
        "bake_joint",
        [](const std::vector<std::string> &paths, const std::vector<std::optional<std::string>> &outputPaths,
           const firn::VolumeOptics &optics, const std::vector<firn::SunLight> &suns,
           const std::optional<firn::Sky> &sky, const py::list &occluders, const std::string &quality,
           std::uint64_t seed, std::shared_ptr<firn::Progress> progress, const std::vector<firn::Lamp> &lamps,
           int sourceScale, bool lightTracing) {
            if (paths.empty() || outputPaths.size() != paths.size())
                throw firn::InvalidArgument("bake_joint: one output path (or None) per VDB path, and at least one");
            const firn::BakeSettings settings = bakeSettings(quality, seed, 0, 0, 0, sourceScale, lightTracing);
            OccluderArrays blockers = occludersFrom(occluders);
            firn::BakeStats stats;
            longCall([&] {
                std::vector<openvdb::FloatGrid::Ptr> densities;
                for (const std::string &path : paths) densities.push_back(jointDensity(path));
                const openvdb::FloatGrid::Ptr joint =
                    firn::unionDensity(std::vector<openvdb::FloatGrid::ConstPtr>(densities.begin(), densities.end()));
                const firn::Scene scene =
                    sceneFrom({joint}, paths.front(), optics, suns, lamps, sky, std::move(blockers));
                const firn::BakedGrids baked = firn::bakeScattering(scene, settings, progress.get(), &stats);
                // Not cancelled once written: a cancel between two files would leave one new beside one old.
                for (std::size_t i = 0; i < paths.size(); ++i)
                    if (outputPaths[i])
                        writeBaked(paths[i], densities[i], firn::bakedGridsOf(baked, *densities[i]), *outputPaths[i],
                                   nullptr);
            });
            return statsDict(stats);
        },
        py::arg("vdb_paths"), py::arg("output_paths"), py::arg("optics"),
        py::arg("suns") = std::vector<firn::SunLight>{}, py::arg("sky") = py::none(), py::arg("occluders") = py::list(),
        py::arg("quality") = "FINAL", py::arg("seed") = 0, py::arg("progress") = nullptr,
        py::arg("lamps") = std::vector<firn::Lamp>{}, py::arg("source_scale") = 0, py::arg("light_tracing") = true,
        R"doc(
Bakes several snow objects lit as one medium (transport/joint_medium.h: a spray's lumps and the tracked snow
they fly over shade and light each other): the 'density' grids of `vdb_paths` summed on the first one's voxels
are baked as `bake` does, then each output_paths[i] that is not None gets the grids of vdb_paths[i] with the
union's baked grids on its own voxels (docs/vdb-contract.md: each object renders its own density times the
shared source, and the objects add up to the union). A file may hold an empty density (a frame without lumps).
Every file written atomically, none before the bake is done. Arguments (light_tracing too), errors and statistics
as `bake`'s.)doc");

    m.def(
        "write_empty_light",
        [](const std::string &path, const std::string &outputPath, const firn::VolumeOptics &optics,
           const std::string &quality, std::uint64_t seed) {
            const firn::BakeSettings settings = bakeSettings(quality, seed, 0, 0, 0, 0);
            longCall([&] {
                const openvdb::FloatGrid::Ptr density = jointDensity(path);
                writeBaked(path, density, firn::emptyBakedGrids(*density, optics, settings), outputPath, nullptr);
            });
        },
        py::arg("vdb_path"), py::arg("output_path"), py::arg("optics"), py::arg("quality") = "FINAL",
        py::arg("seed") = 0, R"doc(
Writes the grids of `vdb_path`, whose 'density' is empty (a spray's frame without lumps), with the six source
grids of BAKED_GRID_NAMES empty, to `output_path` (atomically), without a bake: `bake` refuses an empty density,
and bake_joint would bake the snow beside it only for this. The grids carry a bake's metadata (quality, seed,
optics). ValueError when the density is missing or has an active voxel.)doc");

    m.def(
        "union_density",
        [](const std::vector<std::string> &paths, const std::string &outputPath) {
            longCall([&] {
                std::vector<openvdb::FloatGrid::ConstPtr> densities;
                for (const std::string &path : paths) densities.push_back(jointDensity(path));
                firn::writeGrids(outputPath, {firn::unionDensity(densities)});
            });
        },
        py::arg("vdb_paths"), py::arg("output_path"), R"doc(
Writes the medium `bake_joint` bakes: the 'density' grids of `vdb_paths` summed on the first one's voxels, as
the only grid of `output_path` (atomically). For references: monte_carlo_radiance of that file is what the
objects baked together should render.)doc");

    m.def(
        "render_baked",
        [](const std::string &path, const firn::VolumeOptics &optics, const DoubleArray &origins,
           const DoubleArray &directions, const py::list &occluders) {
            OccluderArrays blockers = occludersFrom(occluders);
            const std::vector<firn::Ray> rays = raysFrom(origins, directions);
            std::vector<firn::Rgb> radiance(rays.size());
            longCall([&] {
                const openvdb::GridPtrVec grids = firn::readGrids(path);
                const firn::Scene scene = sceneFrom(grids, path, optics, {}, {}, std::nullopt, std::move(blockers));
                const firn::BakedGrids baked = firn::BakedGrids::find(grids);
                for (std::size_t i = 0; i < rays.size(); ++i) radiance[i] = firn::renderBaked(scene, baked, rays[i]);
            });
            return rgbRows(radiance);
        },
        py::arg("vdb_path"), py::arg("optics"), py::arg("origins"), py::arg("directions"),
        py::arg("occluders") = py::list(), R"doc(
What Cycles draws for the baked snow of `vdb_path` along camera rays (N, 3 origins and directions, m):
the emission-absorption integral of the contract's material, up to the first occluder. (N, 3) W/m^2/sr.)doc");

    m.def(
        "scatter_voxels",
        [](const std::string &path, const firn::VolumeOptics &optics, const py::list &occluders, double thinDepth,
           bool tracedOnly) {
            OccluderArrays blockers = occludersFrom(occluders);
            const std::vector<openvdb::Coord> voxels = longCall([&] {
                const openvdb::GridPtrVec grids = firn::readGrids(path);
                const firn::Scene scene = sceneFrom(grids, path, optics, {}, {}, std::nullopt, std::move(blockers));
                std::vector<openvdb::Coord> on;
                const openvdb::BoolTree::Ptr mask = firn::scatterMask(scene, thinDepth, tracedOnly);
                for (auto it = mask->cbeginValueOn(); it; ++it) on.push_back(it.getCoord());
                return on;
            });
            py::array_t<std::int32_t> out({py::ssize_t(voxels.size()), py::ssize_t(3)});
            auto rows = out.mutable_unchecked<2>();
            for (std::size_t n = 0; n < voxels.size(); ++n)
                for (int a = 0; a < 3; ++a) rows(n, a) = voxels[n][a];
            return out;
        },
        py::arg("vdb_path"), py::arg("optics"), py::arg("occluders") = py::list(), py::arg("thin_depth") = 2.0,
        py::arg("traced_only") = true, R"doc(
The density's voxels (N, 3 index coordinates) whose density render_scattering_where_thin lets the renderer
scatter: with the defaults, those whose density the bake's SCATTER_GRID_NAME grid holds, coarsened to SCATTER_SCALE
times the voxel (docs/vdb-contract.md); a bench helper.)doc");

    m.def(
        "render_scattering_where_thin",
        [](const std::string &path, const firn::VolumeOptics &optics, const DoubleArray &origins,
           const DoubleArray &directions, const std::vector<firn::SunLight> &suns, const std::optional<firn::Sky> &sky,
           const py::list &occluders, int samples, std::uint64_t seed, double thinDepth, int bounces,
           bool tracedOnly, int scatterScale) {
            if (samples < 1 || samples > 1000000) throw firn::InvalidArgument("samples must be between 1 and 1e6");
            OccluderArrays blockers = occludersFrom(occluders);
            const std::vector<firn::Ray> rays = raysFrom(origins, directions);
            const std::vector<firn::RadianceEstimate> estimates = longCall([&] {
                const openvdb::GridPtrVec grids = firn::readGrids(path);
                const firn::MonteCarloReference reference(sceneFrom(grids, path, optics, suns, {}, sky, std::move(blockers)));
                return firn::renderScatteringWhereThin(reference, firn::BakedGrids::find(grids), rays, samples, seed,
                                                       thinDepth, bounces, tracedOnly, scatterScale);
            });
            std::vector<firn::Rgb> mean, error;
            for (const auto &e : estimates) mean.push_back(e.mean), error.push_back(e.standardError);
            return py::make_tuple(rgbRows(mean), rgbRows(error));
        },
        py::arg("vdb_path"), py::arg("optics"), py::arg("origins"), py::arg("directions"),
        py::arg("suns") = std::vector<firn::SunLight>{}, py::arg("sky") = py::none(), py::arg("occluders") = py::list(),
        py::arg("samples") = 64, py::arg("seed") = 0, py::arg("thin_depth") = 2.0,
        py::arg("bounces") = 1 << 30, py::arg("traced_only") = false,
        py::arg("scatter_scale") = firn::BakedGrids::kScatterScale, R"doc(
A baked file rendered as a renderer that scatters in the thin snow would (benchmarks.md, thin-ring): path traced
in the voxels of optical depth sigma_t h under `thin_depth` (the density it scatters, as the bake writes
SCATTER_GRID_NAME), the baked emission elsewhere; `bounces`: the renderer's volume bounces (0: the lights' single
scattering only); `traced_only`: only in the voxels the bake traces (not the fringes of diffused snow);
`scatter_scale`: the scattered density read trilinearly from voxels that many times the density's (SCATTER_SCALE;
1: the density's own).
Returns (mean, standard error), each (N, 3) W/m^2/sr, as monte_carlo_radiance.)doc");

    m.def(
        "monte_carlo_radiance",
        [](const std::string &path, const firn::VolumeOptics &optics, const DoubleArray &origins,
           const DoubleArray &directions, const std::vector<firn::SunLight> &suns, const std::optional<firn::Sky> &sky,
           const py::list &occluders, int samples, std::uint64_t seed, std::shared_ptr<firn::Progress> progress,
           const std::vector<firn::Lamp> &lamps) {
            if (samples < 1 || samples > 1000000) throw firn::InvalidArgument("samples must be between 1 and 1e6");
            OccluderArrays blockers = occludersFrom(occluders);
            const std::vector<firn::Ray> rays = raysFrom(origins, directions);
            const std::vector<firn::RadianceEstimate> estimates = longCall([&] {
                const openvdb::GridPtrVec grids = firn::readGrids(path);
                const firn::MonteCarloReference reference(sceneFrom(grids, path, optics, suns, lamps, sky, std::move(blockers)));
                return reference.estimate(rays, samples, seed, progress.get());
            });
            std::vector<firn::Rgb> mean, error;
            for (const auto &e : estimates) mean.push_back(e.mean), error.push_back(e.standardError);
            return py::make_tuple(rgbRows(mean), rgbRows(error));
        },
        py::arg("vdb_path"), py::arg("optics"), py::arg("origins"), py::arg("directions"),
        py::arg("suns") = std::vector<firn::SunLight>{}, py::arg("sky") = py::none(), py::arg("occluders") = py::list(),
        py::arg("samples") = 64, py::arg("seed") = 0, py::arg("progress") = nullptr,
        py::arg("lamps") = std::vector<firn::Lamp>{}, R"doc(
Brute-force volumetric path tracing of the same scene: the radiance the snow scatters along each camera
ray (what the baked emission stands for). Returns (mean, standard error), each (N, 3) W/m^2/sr.)doc");

    m.def(
        "write_slab_vdb",
        [](const std::string &path, double voxelSize, int width, int layers, float density) {
            longCall([&] { firn::writeGrids(path, {firn::makeSlabDensity(voxelSize, width, layers, density)}); });
        },
        py::arg("path"), py::arg("voxel_size"), py::arg("width"), py::arg("layers"), py::arg("density"), R"doc(
Writes a test VDB: a box of uniform density (kg/m^3), width x width voxels around the z axis and `layers`
deep, whose top surface (half-column point of the density ramp) is the plane z = 0.)doc");

    m.def(
        "slab_monte_carlo",
        [](double omega, double g, double tau, double mu0, long photons, std::uint64_t seed) {
            if (photons < 1 || photons > 100000000) throw firn::InvalidArgument("photons must be between 1 and 1e8");
            if (!(omega >= 0.0 && omega <= 1.0) || !(g > -1.0 && g < 1.0) || !(tau > 0.0) || !(mu0 <= 1.0))
                throw firn::InvalidArgument("slab: omega in [0, 1], g in (-1, 1), tau > 0, mu0 <= 1");
            const firn::SlabResponse r = longCall([&] { return firn::slabMonteCarlo(omega, g, tau, mu0, photons, seed); });
            py::dict d;
            d["reflectance"] = r.reflectance, d["transmittance"] = r.transmittance;
            d["reflectance_error"] = r.reflectanceError, d["transmittance_error"] = r.transmittanceError;
            return d;
        },
        py::arg("omega"), py::arg("g"), py::arg("tau"), py::arg("mu0"), py::arg("photons"), py::arg("seed") = 0,
        R"doc(
Photon Monte Carlo of a plane-parallel slab (optical thickness tau, float('inf') for a half-space), lit by
a beam at cos(zenith) mu0 (a uniform sky if mu0 <= 0): reflectance and transmittance with standard errors.)doc");
    m.def("art_plane_albedo", &firn::artPlaneAlbedo, py::arg("omega"), py::arg("g"), py::arg("mu0"),
          "Kokhanovsky & Zege (2004) plane albedo of a semi-infinite medium, exp(-y u(mu0)).");
    m.def("art_spherical_albedo", &firn::artSphericalAlbedo, py::arg("omega"), py::arg("g"),
          "Kokhanovsky & Zege (2004) spherical albedo of a semi-infinite medium, exp(-y).");
}

}  // namespace firncore
