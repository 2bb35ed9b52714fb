// Seeded random-input driver for the core's entry points that take user data (issue 11): the mesh, Add
// Snow Layer and its rebuild from kept metaballs, VDB files (corrupted, truncated), the density grid into
// the transport Medium and the bake (with suns, and with lamps), the optics parameters, and the thrown-snow
// simulation (emitters, objects, settings). Every input must give a valid result or one
// of the clear exceptions (InvalidArgument, BudgetExceeded, IoError); anything else, a sanitizer report or
// an iteration running past the watchdog fails the run. Same seed, same inputs: a failure replays with
// `firn_fuzz --first SEED --count 1` (or `--only TARGET --first SEED --count 1`: a seed's input depends on the seed
// alone, its target on the seed modulo the number of targets, which grows as targets are added).
//
//   firn_fuzz [--first N] [--count M] [--seconds S] [--dir D] [--memory-mb MB] [--skip TARGET]... [--only TARGET]
//             [--verbose]
//
// Inputs stay tiny (few triangles, voxel budgets of thousands) so an iteration takes milliseconds.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <functional>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include <sys/resource.h>

#include <openvdb/openvdb.h>

#include "firn/geometry/mesh.h"
#include "firn/io/spray_files.h"
#include "firn/io/vdb_io.h"
#include "firn/optics/snow_optics.h"
#include "firn/snow/snow_layer.h"
#include "firn/spray/sequence.h"
#include "firn/transport/bake.h"
#include "firn/util/error.h"
#include "firn/util/openvdb_library.h"
#include "firn/util/random.h"
#include "firn/util/threads.h"
#include "../cpp/spray/slab_snow.h"

namespace firn::fuzz {

namespace {

// ---------------------------------------------------------------------------------------------------------
// Random values that like the edges: NaN, infinities, zero, negatives, huge and tiny magnitudes.

class Input {
  public:
    explicit Input(std::uint64_t seed) : rng_(seed, 0xF022) {}

    double uniform() { return rng_.uniform(); }
    bool chance(double p) { return rng_.uniform() < p; }
    int integer(int lo, int hi) { return lo + int(rng_.nextBits() % std::uint64_t(hi - lo + 1)); }
    double range(double lo, double hi) { return lo + (hi - lo) * rng_.uniform(); }

    // Mostly in [lo, hi]; sometimes a value no setting should accept.
    double setting(double lo, double hi, double pBad = 0.1) { return chance(pBad) ? awkward() : range(lo, hi); }

    double awkward() {
        static const double kValues[] = {std::numeric_limits<double>::quiet_NaN(),
                                         std::numeric_limits<double>::infinity(),
                                         -std::numeric_limits<double>::infinity(),
                                         0.0, -0.0, -1.0, 1e-300, 1e-30, 1e-7, 1e7, 1e30, 1e300, -1e30,
                                         std::numeric_limits<double>::max(), std::numeric_limits<double>::denorm_min()};
        return kValues[rng_.nextBits() % (sizeof(kValues) / sizeof(kValues[0]))];
    }

    float coordinate(double scale) {
        if (chance(0.03)) return float(awkward());
        return float(range(-scale, scale));
    }

  private:
    Rng rng_;
};

using Check = std::function<void()>;

// ---------------------------------------------------------------------------------------------------------
// Meshes

struct RawMesh {
    std::vector<float> positions;
    std::vector<unsigned> indices;
    std::size_t vertexCount() const { return positions.size() / 3; }
    std::size_t triangleCount() const { return indices.size() / 3; }
};

// A triangle soup: random points (scale m), random indices, some out of range or repeated.
RawMesh randomSoup(Input &in, int maxTriangles, double scale, bool corrupt) {
    RawMesh m;
    const int vertices = in.integer(0, 3 * maxTriangles);
    const int triangles = in.integer(0, maxTriangles);
    for (int i = 0; i < 3 * vertices; ++i) m.positions.push_back(corrupt ? in.coordinate(scale) : float(in.range(-scale, scale)));
    for (int i = 0; i < 3 * triangles; ++i) {
        unsigned index = vertices > 0 ? unsigned(in.integer(0, vertices - 1)) : 0u;
        if (corrupt && in.chance(0.02)) index = in.chance(0.5) ? unsigned(vertices) : 0xFFFFFFFFu;  // -1 as uint32
        m.indices.push_back(index);
    }
    return m;
}

// An upward-facing ground square with a few random triangles above it: snow lands on the square.
RawMesh groundWithClutter(Input &in) {
    const float s = float(in.range(0.05, 0.6));
    RawMesh m{{-s, -s, 0, s, -s, 0, s, s, 0, -s, s, 0}, {0, 1, 2, 0, 2, 3}};
    const RawMesh clutter = randomSoup(in, 3, s, false);
    const unsigned offset = unsigned(m.vertexCount());
    m.positions.insert(m.positions.end(), clutter.positions.begin(), clutter.positions.end());
    for (unsigned i : clutter.indices) m.indices.push_back(i + offset);
    return m;
}

TriangleMesh build(const RawMesh &m) {
    return makeTriangleMesh(m.positions.data(), m.vertexCount(), m.indices.data(), m.triangleCount());
}

void requireValid(const TriangleMesh &mesh, const char *what) {
    for (const glm::uvec3 &t : mesh.triangles)
        for (int k = 0; k < 3; ++k)
            if (t[k] >= mesh.positions.size()) throw std::logic_error(std::string(what) + ": index out of range");
    for (const glm::vec3 &p : mesh.positions)
        if (!std::isfinite(p.x + p.y + p.z)) throw std::logic_error(std::string(what) + ": non-finite vertex");
}

void fuzzMesh(Input &in) {
    const RawMesh raw = randomSoup(in, 12, in.chance(0.2) ? 1e30 : 10.0, true);
    requireValid(build(raw), "makeTriangleMesh");
}

// ---------------------------------------------------------------------------------------------------------
// Add Snow Layer, and its rebuild from kept metaballs

SnowLayerSettings randomSettings(Input &in) {
    SnowLayerSettings s;
    s.depth = in.setting(0.02, 0.3);
    s.spacing = in.setting(0.03, 0.3);
    s.maxSlope = in.setting(0.1, 1.6);
    s.randomness = in.setting(0.0, 1.0);
    s.smoothness = in.setting(0.0, 1.0);
    s.direction = in.chance(0.9) ? glm::vec3{float(in.range(-0.5, 0.5)), float(in.range(-0.5, 0.5)), -1.0f}
                                 : glm::vec3{float(in.awkward()), float(in.awkward()), float(in.awkward())};
    s.spread = in.setting(0.0, 1.0);
    s.exposureRays = in.chance(0.95) ? in.integer(1, 4) : in.integer(-5, 5000);
    s.densityTop = in.setting(50.0, 400.0);
    s.densityBottom = in.setting(100.0, 917.0);
    s.compaction = in.setting(0.0, 1.0);
    s.voxelSize = in.chance(0.7) ? 0.0 : in.setting(0.001, 0.1);
    s.maxVoxels = in.chance(0.95) ? in.range(1.0, 2e5) : in.awkward();
    s.seed = in.integer(0, 1000);
    return s;
}

void requireValid(const SnowGrids &grids) {
    if (!grids.density || !grids.surface) throw std::logic_error("snow layer without grids");
    for (auto it = grids.density->cbeginValueOn(); it; ++it)
        if (!(*it >= 0.0f && *it <= 917.0f)) throw std::logic_error("density outside [0, 917] kg/m^3");
    for (auto it = grids.surface->cbeginValueOn(); it; ++it)
        if (!std::isfinite(*it)) throw std::logic_error("non-finite level set");
}

// The metaballs a user kept and edited in Blender: moved, scaled, some nonsense.
void editMetaballs(Input &in, std::vector<Metaball> &balls) {
    if (in.chance(0.2)) balls.clear();
    for (Metaball &b : balls) {
        if (!in.chance(0.1)) continue;
        switch (in.integer(0, 4)) {
        case 0: b.centre[in.integer(0, 2)] = float(in.awkward()); break;
        case 1: b.radius = float(in.awkward()); break;
        case 2: b.normal = glm::vec3{float(in.awkward()), 0.0f, float(in.awkward())}; break;
        case 3: b.base = float(in.awkward()); break;
        default: b.depth = float(in.awkward()); break;
        }
    }
}

void fuzzSnowLayer(Input &in) {
    const RawMesh targets = in.chance(0.8) ? groundWithClutter(in) : randomSoup(in, 4, 0.5, true);
    const RawMesh occluders = in.chance(0.5) ? randomSoup(in, 3, 0.5, false) : RawMesh{};
    const SnowLayerSettings s = randomSettings(in);
    SnowLayer layer = generateSnowLayer(build(targets), build(occluders), s, nullptr);
    requireValid(layer.grids);
    editMetaballs(in, layer.metaballs);
    SnowLayerSettings rebuild = s;
    if (in.chance(0.3)) rebuild.voxelSize = in.setting(0.001, s.depth);
    rebuild.validate();
    requireValid(rasterizeSnow(layer.metaballs, rebuild.raster(), SubProgress(nullptr, 0.0, 1.0)));
}

// Metaballs straight from a user's arrays, no snow layer behind them.
void fuzzMetaballs(Input &in) {
    std::vector<Metaball> balls(in.integer(0, 6));
    for (Metaball &b : balls) {
        b.centre = glm::vec3{in.coordinate(1.0), in.coordinate(1.0), in.coordinate(1.0)};
        b.radius = float(in.setting(0.01, 0.2));
        b.normal = glm::vec3(0.0f, 0.0f, 1.0f);
        b.base = float(in.setting(-0.1, 0.1));
        b.depth = float(in.setting(0.0, 0.3));
    }
    editMetaballs(in, balls);
    RasterSettings r;
    r.voxelSize = in.chance(0.9) ? in.range(0.005, 0.05) : in.awkward();
    r.maxVoxels = in.chance(0.9) ? in.range(1.0, 2e5) : in.awkward();
    r.compaction = {120.0, 350.0, 0.5, 0.1};
    requireValid(rasterizeSnow(balls, r, SubProgress(nullptr, 0.0, 1.0)));
}

// ---------------------------------------------------------------------------------------------------------
// Density grids: the transport Medium and the bake

openvdb::FloatGrid::Ptr randomDensity(Input &in) {
    auto grid = openvdb::FloatGrid::create(in.chance(0.95) ? 0.0f : float(in.awkward()));
    grid->setName("density");
    const double h = in.chance(0.9) ? in.range(0.005, 0.05) : std::abs(in.awkward());
    try {
        grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
    } catch (const openvdb::ArithmeticError &) {  // OpenVDB itself makes no such grid: keep h = 1 m
    }
    const int n = in.integer(1, 5), layers = in.integer(1, 5);
    auto acc = grid->getAccessor();
    for (int x = 0; x < n; ++x)
        for (int y = 0; y < n; ++y)
            for (int z = 0; z < layers; ++z) acc.setValue({x, y, -z}, in.chance(0.97) ? float(in.range(0, 600)) : float(in.awkward()));
    if (in.chance(0.05)) acc.setValue({in.integer(-100000, 100000), in.integer(-100000, 100000), 0}, 300.0f);  // far apart
    if (in.chance(0.05)) grid->tree().addTile(1, openvdb::Coord(64, 0, 0), 300.0f, true);
    if (in.chance(0.03)) grid->tree().clear();
    return grid;
}

VolumeOptics randomOptics(Input &in) {
    return {in.setting(0.5, 10.0), Rgb{in.setting(0.9, 1.0), in.setting(0.9, 1.0), in.setting(0.9, 1.0)},
            in.setting(0.0, 0.9)};
}

SunLight randomSun(Input &in) {
    SunLight sun;
    // The sun's direction is a unit vector from the add-on: a random one normalized, now and then nonsense.
    sun.direction = in.chance(0.9) ? glm::normalize(glm::dvec3{in.range(-1, 1), in.range(-1, 1), in.range(0.1, 1)})
                                   : glm::dvec3{in.awkward(), 0.0, in.awkward()};
    sun.irradiance = Rgb(float(in.setting(0.0, 5.0)));
    sun.angularDiameter = in.setting(0.0, 0.1);
    return sun;
}

// A lamp of any shape, now and then with a field no lamp has.
Lamp randomLamp(Input &in) {
    constexpr double kBad = 0.02;  // per field
    Lamp lamp;
    lamp.shape = Lamp::Shape(in.integer(0, 3));
    lamp.position = {in.setting(-0.3, 0.3, kBad), in.setting(-0.3, 0.3, kBad), in.setting(-0.05, 1.0, kBad)};
    const glm::dvec3 axis{in.range(-0.5, 0.5), in.range(-0.5, 0.5), -1.0};
    lamp.axis = glm::normalize(axis);
    lamp.tangent = glm::normalize(glm::cross(lamp.axis, glm::dvec3{0.0, 1.0, 0.0}));
    if (in.chance(kBad)) lamp.axis = axis;  // not a unit vector
    if (in.chance(kBad)) lamp.tangent = glm::dvec3{in.awkward(), in.awkward(), 0.0};
    lamp.emission = Rgb(in.setting(0.0, 50.0, kBad), in.setting(0.0, 50.0, kBad), in.setting(0.0, 50.0, kBad));
    lamp.radius = in.setting(0.0, 0.1, kBad);
    lamp.spotAngle = in.setting(0.1, 3.14159, kBad);
    lamp.spotBlend = in.setting(0.0, 1.0, kBad);
    lamp.sizeX = in.setting(0.001, 1.0, kBad);
    lamp.sizeY = in.setting(0.001, 1.0, kBad);
    return lamp;
}

void requireFinite(const BakedGrids &baked) {
    for (const auto &grid : baked.source)
        for (auto it = grid->cbeginValueOn(); it; ++it)
            if (!std::isfinite(it->x() + it->y() + it->z())) throw std::logic_error("non-finite baked source");
}

void fuzzBake(Input &in) {
    Scene scene;
    const openvdb::FloatGrid::Ptr density = randomDensity(in);  // first the grid, then the optics: seeded order
    const VolumeOptics optics = randomOptics(in);
    scene.medium = std::make_shared<Medium>(density, optics);
    for (int i = in.integer(0, 2); i > 0; --i) scene.suns.push_back(randomSun(in));
    scene.sky.radiance = Rgb(float(in.setting(0.0, 1.0)));
    if (in.chance(0.3)) {
        const RawMesh ground = groundWithClutter(in);
        TriangleMesh mesh = build(ground);
        std::vector<Rgb> albedo(mesh.triangleCount(), Rgb(float(in.setting(0.0, 1.0))));
        scene.occluders = std::make_shared<Occluders>(std::move(mesh), std::move(albedo));
    }
    BakeSettings settings;
    settings.quality = in.chance(0.95) ? BakeQuality::Draft : BakeQuality::Reference;
    settings.seed = in.integer(0, 100);
    settings.skySamples = in.chance(0.9) ? in.integer(1, 4) : in.integer(-10, 100);
    settings.sunSamples = in.chance(0.9) ? in.integer(1, 2) : in.integer(-10, 100);
    settings.tolerance = in.chance(0.9) ? 1e-3 : in.awkward();
    settings.referenceSamples = in.integer(1, 4);
    requireFinite(bakeScattering(scene, settings));
}

// A block of snow n x n x layers voxels (1 cm) of 100-600 kg/m^3, one voxel in 500 awkward: thick snow, whose bake is
// quick (thin snow is traced, seconds a seed in the short run: the bake target has it).
openvdb::FloatGrid::Ptr snowBlock(Input &in) {
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    grid->setTransform(openvdb::math::Transform::createLinearTransform(0.01));
    const int n = in.integer(1, 6), layers = in.integer(1, 6);
    auto acc = grid->getAccessor();
    for (int x = 0; x < n; ++x)
        for (int y = 0; y < n; ++y)
            for (int z = 0; z < layers; ++z)
                acc.setValue({x, y, -z}, float(in.chance(0.998) ? in.range(100.0, 600.0) : in.awkward()));
    return grid;
}

// Lamps of every shape over the snow (and beside it, inside it, at awkward places), with or without occluders.
void fuzzLamps(Input &in) {
    constexpr double kBad = 0.02;
    Scene scene;
    const openvdb::FloatGrid::Ptr density = snowBlock(in);
    const VolumeOptics optics{in.setting(0.5, 10.0, kBad), Rgb{in.setting(0.9, 1.0, kBad), in.setting(0.9, 1.0, kBad),
                                                               in.setting(0.9, 1.0, kBad)},
                              in.setting(0.0, 0.9, kBad)};
    scene.medium = std::make_shared<Medium>(density, optics);
    for (int i = in.integer(1, 3); i > 0; --i) scene.lamps.push_back(randomLamp(in));
    if (in.chance(0.3)) scene.suns.push_back(randomSun(in));
    scene.sky.radiance = Rgb(in.chance(0.5) ? 0.0 : in.setting(0.0, 1.0, kBad));
    if (in.chance(0.3)) {
        TriangleMesh mesh = build(groundWithClutter(in));
        std::vector<Rgb> albedo(mesh.triangleCount(), Rgb(in.setting(0.0, 1.0, kBad)));
        scene.occluders = std::make_shared<Occluders>(std::move(mesh), std::move(albedo));
    }
    BakeSettings settings;
    settings.quality = BakeQuality::Draft;
    settings.seed = in.integer(0, 100);
    settings.sunSamples = in.chance(0.95) ? in.integer(1, 4) : in.integer(-10, 100);
    requireFinite(bakeScattering(scene, settings));
}

// ---------------------------------------------------------------------------------------------------------
// VDB files, corrupted

void fuzzVdbFile(Input &in, const std::filesystem::path &dir) {
    const std::filesystem::path path = dir / "fuzz.vdb";
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    for (int i = in.integer(1, 40); i > 0; --i) grid->tree().setValue({in.integer(0, 20), in.integer(0, 20), in.integer(0, 20)}, 1.0f);
    writeGrids(path.string(), {grid});
    std::string bytes;
    {
        std::ifstream file(path, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(file), {});
    }
    if (in.chance(0.4)) bytes.resize(std::size_t(in.uniform() * double(bytes.size())));  // truncated
    for (int flips = in.integer(0, 8); flips > 0 && !bytes.empty(); --flips)
        bytes[std::size_t(in.uniform() * double(bytes.size()))] = char(in.integer(0, 255));
    {
        std::ofstream file(path, std::ios::binary | std::ios::trunc);
        file.write(bytes.data(), std::streamsize(bytes.size()));
    }
    gridNames(path.string());  // the cheap header check the add-on runs on load, then the full read
    for (const auto &read : readGrids(path.string()))
        if (!read) throw std::logic_error("readGrids returned a null grid");
}

// ---------------------------------------------------------------------------------------------------------
// Optics parameters

void fuzzOptics(Input &in) {
    SnowParameters p;
    p.grainRadius = in.setting(20e-6, 2e-3);
    p.density = in.setting(50.0, 917.0);
    p.blackCarbon = in.setting(0.0, 1e-6);
    p.dust = in.setting(0.0, 1e-4);
    p.liquidWater = in.setting(0.0, 0.1);
    p.B = in.setting(1.0, 2.0);
    p.g = in.setting(0.7, 0.9);
    const VolumeOptics o = snowOptics(p);
    const double wavelength = in.setting(390e-9, 800e-9);
    const double coAlbedoValue = coAlbedo(p, wavelength);
    bool sane = o.extinctionPerDensity > 0.0 && std::isfinite(o.extinctionPerDensity) && std::abs(o.g) < 1.0 &&
                coAlbedoValue >= 0.0 && coAlbedoValue <= 1.0;
    for (int c = 0; c < 3; ++c) sane = sane && o.albedo[c] >= 0.0f && o.albedo[c] <= 1.0f;
    if (!sane) throw std::logic_error("snowOptics returned coefficients outside their ranges");
}

// ---------------------------------------------------------------------------------------------------------
// Thrown snow: emitters moving through a small slab, objects the lumps land on, the settings of the panel

// A slab of snow [-s, s]^2 x [-d, 0] (m) on voxels of h (m), with a snow layer's grids (the spray tests' slab).
SnowGrids slab(double s, double d, double h, float density) {
    return test::slabSnow(openvdb::Vec3d(-s, -s, -d), openvdb::Vec3d(s, s, 0.0), h, density);
}

EmitterRectangle randomRectangle(Input &in, const glm::dvec3 &centre) {
    EmitterRectangle r;
    r.centre = centre;
    r.halfU = {in.setting(0.02, 0.3, 0.01), 0.0, 0.0};
    r.halfV = {0.0, in.setting(0.01, 0.1, 0.01), in.chance(0.98) ? in.range(-0.05, 0.05) : in.awkward()};
    return r;
}

// An emitter gliding at a random depth through the snow, or jumping about; now and then a corner nowhere.
Emitter randomEmitter(Input &in, std::size_t frames) {
    Emitter e;
    const glm::dvec3 start{in.range(-0.3, 0.3), in.range(-0.3, 0.3), in.range(-0.08, 0.05)};
    const glm::dvec3 step{in.setting(-0.2, 0.2, 0.01), in.setting(-0.2, 0.2, 0.01), in.setting(-0.02, 0.02, 0.01)};  // m/frame
    for (std::size_t f = 0; f < frames; ++f) e.frames.push_back(randomRectangle(in, start + double(f) * step));
    if (in.chance(0.05)) e.frames[std::size_t(in.integer(0, int(frames) - 1))].centre.x = in.awkward();
    return e;
}

SpraySettings randomSpraySettings(Input &in) {
    constexpr double kBad = 0.01;  // per setting: about one run in five has one no panel allows
    SpraySettings s;
    s.emission.rate = in.setting(100.0, 20000.0, kBad);
    s.emission.spreadAngle = in.setting(0.0, 1.5, kBad);
    s.emission.throwSpeed = in.setting(0.0, 2.0, kBad);
    s.emission.cellSize = in.setting(0.01, 0.05, kBad);
    s.lumps.radius = in.setting(0.004, 0.03, kBad);
    s.lumps.radiusVariation = in.setting(0.0, 1.0, kBad);
    s.lumps.density = in.setting(100.0, 500.0, kBad);
    s.lumps.ballsPerLump = in.chance(0.9) ? in.integer(1, 8) : in.integer(-3, 100);
    s.lumps.breakRate = in.setting(0.0, 5.0, kBad);
    s.lumps.breakSpeed = in.setting(0.0, 2.0, kBad);
    s.flight.down = in.chance(0.9) ? glm::dvec3{0.0, 0.0, -1.0} : glm::dvec3{in.awkward(), 0.0, in.awkward()};
    s.flight.gravity = in.setting(0.0, 20.0, kBad);
    s.flight.airDensity = in.setting(0.0, 2.0, kBad);
    s.flight.dragCoefficient = in.setting(0.0, 1.0, kBad);
    s.tracks.thickness = in.setting(0.0, 0.05, kBad);
    s.tracks.compactionDepth = in.setting(0.0, 0.1, kBad);
    s.tracks.maxDensity = in.setting(300.0, 917.0, kBad);
    s.substeps = in.chance(0.9) ? in.integer(1, 8) : in.integer(-5, 5000);
    s.deposit = in.chance(0.5);
    s.cutTracks = in.chance(0.7);
    s.voxelSize = in.chance(0.7) ? 0.0 : in.setting(0.005, 0.05, kBad);
    s.maxParticles = in.chance(0.95) ? in.range(1.0, 2e4) : in.awkward();
    s.maxVoxels = in.chance(0.95) ? in.range(1.0, 2e5) : in.awkward();
    s.seed = std::uint64_t(in.integer(0, 1000));
    return s;
}

void requireValid(const SprayParticles &particles) {
    for (const SprayParticle &p : particles)
        if (!std::isfinite(p.position.x + p.position.y + p.position.z + p.velocity.x + p.velocity.y + p.velocity.z) ||
            !(p.radius > 0.0f) || p.ballCount == 0 || p.ballCount > kMaxBallsPerLump)
            throw std::logic_error("a lump with a non-finite place or speed, or no balls");
}

// A whole sequence as the add-on hands it over (runSpraySequence: the snow's file in, each frame's files out), then
// the same job again, which finds every frame complete and leaves the files as they were.
void fuzzSpray(Input &in, const std::filesystem::path &dir) {
    const double h = in.chance(0.9) ? in.range(0.01, 0.03) : 0.02;
    const SnowGrids snow = slab(in.range(0.2, 0.5), in.range(0.05, 0.2), h, float(in.range(100, 400)));
    SprayJob job;
    job.snowPath = (dir / "snow.vdb").string();
    writeGrids(job.snowPath, {snow.density, snow.surface});
    job.fps = in.chance(0.9) ? in.range(12.0, 60.0) : in.awkward();
    const std::size_t frames = std::size_t(in.integer(2, 4));
    for (int i = in.integer(1, 2); i > 0; --i) job.emitters.push_back(randomEmitter(in, frames));
    if (in.chance(0.3)) job.objects = build(groundWithClutter(in));
    job.firstFrame = in.integer(-5, 100);
    job.settings = randomSpraySettings(in);
    job.directory = (dir / "spray").string();
    std::filesystem::remove_all(job.directory);
    const SprayRun run = runSpraySequence(job, nullptr);
    if (run.framesWritten.size() != frames) throw std::logic_error("a spray sequence left frames unwritten");
    const SprayFramePaths last = sprayFramePaths(job.directory, job.firstFrame + int(frames) - 1);
    requireValid(readSprayState(last.state).particles);
    SnowGrids spray;
    for (const openvdb::GridBase::Ptr &grid : readGrids(last.spray))
        (grid->getName() == "density" ? spray.density : spray.surface) = openvdb::gridPtrCast<openvdb::FloatGrid>(grid);
    requireValid(spray);
    if (!runSpraySequence(job, nullptr).framesWritten.empty()) throw std::logic_error("a complete sequence ran again");
}

// ---------------------------------------------------------------------------------------------------------
// The driver

struct Target {
    const char *name;
    std::function<void(Input &)> run;
};

std::atomic<std::int64_t> gIterationStart{0};  // ms since epoch; 0 between iterations
std::atomic<std::uint64_t> gSeed{0};
constexpr std::int64_t kHangMs = 60'000;  // far beyond any tiny input, sanitizers included

std::int64_t nowMs() {
    return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

void watchdog() {
    for (;;) {
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
        const std::int64_t start = gIterationStart.load();
        if (start != 0 && nowMs() - start > kHangMs) {
            std::fprintf(stderr, "HANG: seed %llu ran over %lld s\n", (unsigned long long)gSeed.load(),
                         (long long)(kHangMs / 1000));
            std::abort();
        }
    }
}

int run(int argc, char **argv) {
    std::uint64_t first = 0, count = 1000;
    double seconds = 0.0;
    bool verbose = false;
    std::vector<std::string> skipped;  // target names whose seeds are passed over
    std::string only;                  // a target every seed runs, in place of the seed's own
    rlim_t memoryMb = 2048;  // 0: no limit (under ASan, use ASAN_OPTIONS=max_allocation_size_mb instead)
    std::filesystem::path dir = std::filesystem::temp_directory_path() / ("firn_fuzz_" + std::to_string(::getpid()));
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        const auto next = [&]() -> std::string {
            if (i + 1 >= argc) throw InvalidArgument(arg + " needs a value");
            return argv[++i];
        };
        if (arg == "--first") first = std::stoull(next());
        else if (arg == "--count") count = std::stoull(next());
        else if (arg == "--seconds") seconds = std::stod(next());
        else if (arg == "--dir") dir = next();
        else if (arg == "--memory-mb") memoryMb = std::stoull(next());
        else if (arg == "--skip") skipped.push_back(next());
        else if (arg == "--only") only = next();
        else if (arg == "--verbose") verbose = true;
        else throw InvalidArgument("unknown argument " + arg);
    }
    if (verbose) std::setvbuf(stdout, nullptr, _IOLBF, 0);  // the last line names the last seed before a sanitizer stops
    // OpenVDB's reader trusts the lengths in a file: a corrupted one asks for gigabytes (docs/reliability.md).
    // Capped, the allocation fails and readGrids reports it as IoError instead of taking the machine's memory.
    const rlimit memory{memoryMb << 20, memoryMb << 20};
    if (memoryMb > 0) setrlimit(RLIMIT_DATA, &memory);
    initializeOpenVdb();
    setThreadCount(2);
    std::filesystem::create_directories(dir);
    const std::vector<Target> targets = {
        {"mesh", fuzzMesh},
        {"snow_layer", fuzzSnowLayer},
        {"metaballs", fuzzMetaballs},
        {"bake", fuzzBake},
        {"vdb_file", [&](Input &in) { fuzzVdbFile(in, dir); }},
        {"optics", fuzzOptics},
        {"lamps", fuzzLamps},
        {"spray", [&](Input &in) { fuzzSpray(in, dir); }},
    };
    const auto named = std::find_if(targets.begin(), targets.end(), [&](const Target &t) { return t.name == only; });
    if (!only.empty() && named == targets.end()) throw InvalidArgument("no target named " + only);
    std::thread(watchdog).detach();
    const std::int64_t begin = nowMs();
    std::uint64_t done = 0, refused = 0;
    for (std::uint64_t seed = first; seed < first + count; ++seed) {
        if (seconds > 0.0 && double(nowMs() - begin) > 1000.0 * seconds) break;
        const Target &target = only.empty() ? targets[seed % targets.size()] : *named;
        if (std::find(skipped.begin(), skipped.end(), target.name) != skipped.end()) continue;
        Input in(seed);
        gSeed = seed;
        gIterationStart = nowMs();
        try {
            target.run(in);
            if (verbose) std::printf("seed %llu %s: ok\n", (unsigned long long)seed, target.name);
        } catch (const InvalidArgument &e) {
            ++refused;
            if (verbose) std::printf("seed %llu %s: InvalidArgument: %s\n", (unsigned long long)seed, target.name, e.what());
        } catch (const BudgetExceeded &e) {
            ++refused;
            if (verbose) std::printf("seed %llu %s: BudgetExceeded: %s\n", (unsigned long long)seed, target.name, e.what());
        } catch (const IoError &e) {
            ++refused;
            if (verbose) std::printf("seed %llu %s: IoError: %s\n", (unsigned long long)seed, target.name, e.what());
        } catch (const std::exception &e) {
            std::fprintf(stderr, "FAIL: seed %llu (%s): unclear exception: %s\n", (unsigned long long)seed, target.name,
                         e.what());
            return 1;
        }
        gIterationStart = 0;
        ++done;
    }
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
    std::printf("firn_fuzz: %llu inputs from seed %llu in %.1f s, %llu refused with a clear exception, no failure\n",
                (unsigned long long)done, (unsigned long long)first, double(nowMs() - begin) / 1000.0,
                (unsigned long long)refused);
    return 0;
}

}  // namespace

}  // namespace firn::fuzz

int main(int argc, char **argv) { return firn::fuzz::run(argc, argv); }
