// Snow thrown by moving objects from Python (issue 14): the settings, the whole simulation of a frame sequence with
// its files, and the particles a state file holds.
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "firn/io/spray_files.h"
#include "firn/util/error.h"
#include "mesh_arrays.h"

namespace py = pybind11;

namespace firncore {

namespace {

using S = firn::SpraySettings;

// A setting of one of SpraySettings' parts (emission, lumps, flight, tracks) as a flat attribute.
template <class Part, class T>
void partField(py::class_<S> &c, const char *name, Part S::*part, T Part::*field, const char *doc) {
    c.def_property(
        name, [part, field](const S &s) { return s.*part.*field; },
        [part, field](S &s, const T &value) { (s.*part).*field = value; }, doc);
}

void bindSettings(py::module_ &m) {
    py::class_<S> c(m, "SpraySettings", R"doc(
Settings of a spray simulation (docs/spray.md). Lengths in m, times in s, densities in kg/m^3, angles in rad.
SpraySettings(**kwargs) sets any of the attributes.)doc");
    c.def(py::init([](const py::kwargs &kwargs) { return settingsFromKwargs<S>(kwargs, "SpraySettings"); }));
    partField(c, "rate", &S::emission, &firn::EmissionSettings::rate,
              "lumps thrown per m^2 of emitter per m it travels through the snow (1/m^3)");
    partField(c, "spread_angle", &S::emission, &firn::EmissionSettings::spreadAngle,
              "rad, half-angle of the cone around straight up that lumps are thrown in");
    partField(c, "throw_speed", &S::emission, &firn::EmissionSettings::throwSpeed,
              "speed of the throw as a fraction of the emitter's local speed");
    partField(c, "cell_size", &S::emission, &firn::EmissionSettings::cellSize,
              "m, the cells an emitter is sampled on");
    partField(c, "lump_radius", &S::lumps, &firn::LumpSettings::radius, "m, mean radius of a new lump");
    partField(c, "lump_radius_variation", &S::lumps, &firn::LumpSettings::radiusVariation,
              "0..1, radius x (1 + variation (2u - 1))");
    partField(c, "lump_density", &S::lumps, &firn::LumpSettings::density, "kg/m^3 of a lump");
    partField(c, "balls_per_lump", &S::lumps, &firn::LumpSettings::ballsPerLump, "metaballs per new lump (1..8)");
    partField(c, "break_rate", &S::lumps, &firn::LumpSettings::breakRate,
              "1/s, chance per second that a flying lump splits in two");
    partField(c, "break_speed", &S::lumps, &firn::LumpSettings::breakSpeed,
              "m/s, relative speed of the two halves of a split");
    c.def_property(
        "down", [](const S &s) { return RgbTuple{s.flight.down.x, s.flight.down.y, s.flight.down.z}; },
        [](S &s, const RgbTuple &d) { s.flight.down = {d[0], d[1], d[2]}; }, "unit vector, the way gravity pulls");
    partField(c, "gravity", &S::flight, &firn::FlightSettings::gravity, "m/s^2");
    partField(c, "air_density", &S::flight, &firn::FlightSettings::airDensity, "kg/m^3");
    partField(c, "drag_coefficient", &S::flight, &firn::FlightSettings::dragCoefficient,
              "C_d of a lump (0.47: a sphere)");
    partField(c, "track_thickness", &S::tracks, &firn::TrackSettings::thickness,
              "m, how far an emitter's box reaches under its rectangle");
    partField(c, "compaction_depth", &S::tracks, &firn::TrackSettings::compactionDepth,
              "m, the layer under a track that takes the snow pushed out of it");
    partField(c, "max_density", &S::tracks, &firn::TrackSettings::maxDensity,
              "kg/m^3 the compacted layer never exceeds");
    c.def_readwrite("substeps", &S::substeps, "sub-steps per frame")
        .def_readwrite("deposit", &S::deposit, "lumps that come to rest stay where they lie (False: they vanish)")
        .def_readwrite("cut_tracks", &S::cutTracks, "emitters cut tracks in the snow")
        .def_readwrite("voxel_size", &S::voxelSize, "m of the spray's grids; 0: the snow's")
        .def_readwrite("max_particles", &S::maxParticles,
                       "particle budget, counted as the metaballs the lumps could split into")
        .def_readwrite("max_voxels", &S::maxVoxels, "voxel budget of the spray's grids and of one frame's track")
        .def_readwrite("seed", &S::seed)
        .def("validate", &S::validate, "Raises ValueError naming the first setting out of range.");
}

// (F, 3, 3) per emitter: at each frame its centre, half side u and half side v (m).
std::vector<firn::Emitter> emittersFrom(const py::handle &emitters) {
    if (!py::isinstance<py::sequence>(emitters) || py::isinstance<py::str>(emitters))
        throw firn::InvalidArgument("emitters must be a sequence of (frames, 3, 3) arrays");
    std::vector<firn::Emitter> out;
    for (const py::handle item : emitters) {
        const DoubleArray a = py::cast<DoubleArray>(item);
        if (a.ndim() != 3 || a.shape(1) != 3 || a.shape(2) != 3)
            throw firn::InvalidArgument("emitter " + std::to_string(out.size()) +
                                        " must be a (frames, 3, 3) array: centre, half side u, half side v per frame");
        firn::Emitter e;
        for (py::ssize_t f = 0; f < a.shape(0); ++f) {
            const auto row = [&](int r) { return glm::dvec3(a.at(f, r, 0), a.at(f, r, 1), a.at(f, r, 2)); };
            e.frames.push_back({row(0), row(1), row(2)});
        }
        out.push_back(std::move(e));
    }
    return out;
}

// One row per lump, of shape `row` (empty: a scalar per lump); fill(lump, out) writes a lump's row.
template <class T, class Fill>
py::array_t<T> perLump(const firn::SprayParticles &lumps, std::vector<py::ssize_t> row, Fill fill) {
    py::ssize_t width = 1;
    for (py::ssize_t n : row) width *= n;
    row.insert(row.begin(), py::ssize_t(lumps.size()));
    py::array_t<T> out(row);
    T *data = out.mutable_data();
    for (std::size_t i = 0; i < lumps.size(); ++i) fill(lumps[i], data + i * width);
    return out;
}

void bindParticles(py::module_ &m) {
    using P = firn::SavedSprayState;
    m.attr("SPRAY_FLYING") = int(firn::ParticleState::Flying);
    m.attr("SPRAY_ON_SNOW") = int(firn::ParticleState::OnSnow);
    m.attr("SPRAY_ON_OBJECT") = int(firn::ParticleState::OnObject);
    m.attr("SPRAY_MAX_BALLS_PER_LUMP") = firn::kMaxBallsPerLump;
    py::class_<P>(m, "SprayParticles", R"doc(
The lumps of a spray simulation after one frame, as its state file holds them (read_spray_state). Arrays are
copies: positions, velocities (N, 3) float64 (m, m/s); radii (N,) float32 (m, of the sphere of the lump's volume);
ids (N,) uint64; states (N,) uint8 (SPRAY_FLYING, SPRAY_ON_SNOW, SPRAY_ON_OBJECT); ball_counts (N,) uint8;
ball_offsets (N, 8, 3) float32 (m from the position) and ball_radii (N, 8) float32 (m, field radius), of which the
first ball_counts[i] are used.)doc")
        .def("__len__", [](const P &p) { return p.particles.size(); })
        .def_property_readonly("frame_index", [](const P &p) { return p.frame; }, "index of the frame in the sequence")
        .def_property_readonly("next_id", [](const P &p) { return p.nextId; })
        .def_property_readonly("snow_frame", [](const P &p) { return p.snowFrame; },
                               "Blender frame of the snow file in force (None: the input snow)")
        .def_property_readonly("positions", [](const P &p) {
            return perLump<double>(p.particles, {3}, [](const firn::SprayParticle &q, double *o) {
                for (int k = 0; k < 3; ++k) o[k] = q.position[k];
            });
        })
        .def_property_readonly("velocities", [](const P &p) {
            return perLump<double>(p.particles, {3}, [](const firn::SprayParticle &q, double *o) {
                for (int k = 0; k < 3; ++k) o[k] = q.velocity[k];
            });
        })
        .def_property_readonly("radii", [](const P &p) {
            return perLump<float>(p.particles, {}, [](const firn::SprayParticle &q, float *o) { *o = q.radius; });
        })
        .def_property_readonly("ids", [](const P &p) {
            return perLump<std::uint64_t>(p.particles, {}, [](const firn::SprayParticle &q, std::uint64_t *o) { *o = q.id; });
        })
        .def_property_readonly("states", [](const P &p) {
            return perLump<std::uint8_t>(p.particles, {},
                                         [](const firn::SprayParticle &q, std::uint8_t *o) { *o = std::uint8_t(q.state); });
        })
        .def_property_readonly("ball_counts", [](const P &p) {
            return perLump<std::uint8_t>(p.particles, {},
                                         [](const firn::SprayParticle &q, std::uint8_t *o) { *o = q.ballCount; });
        })
        .def_property_readonly("ball_offsets", [](const P &p) {
            return perLump<float>(p.particles, {firn::kMaxBallsPerLump, 3}, [](const firn::SprayParticle &q, float *o) {
                for (int b = 0; b < firn::kMaxBallsPerLump; ++b)
                    for (int k = 0; k < 3; ++k) o[3 * b + k] = q.ballOffset[b][k];
            });
        })
        .def_property_readonly("ball_radii", [](const P &p) {
            return perLump<float>(p.particles, {firn::kMaxBallsPerLump}, [](const firn::SprayParticle &q, float *o) {
                for (int b = 0; b < firn::kMaxBallsPerLump; ++b) o[b] = q.ballRadius[b];
            });
        });
}

}  // namespace

void bindSpray(py::module_ &m) {
    bindSettings(m);
    bindParticles(m);

    m.def(
        "simulate_spray",
        [](const std::string &snowPath, const py::object &emitters, const std::string &directory, double fps,
           int firstFrame, const S &settings, const py::object &objects, std::shared_ptr<firn::Progress> progress) {
            firn::SprayJob job;
            job.snowPath = snowPath, job.emitters = emittersFrom(emitters), job.directory = directory;
            job.fps = fps, job.firstFrame = firstFrame, job.settings = settings;
            job.objects = optionalMesh(objects, "objects");
            const firn::SprayRun run = longCall([&] { return firn::runSpraySequence(job, progress.get()); });
            py::dict out;
            out["resumed_after"] = run.resumedAfter;
            out["frames_written"] = run.framesWritten;
            out["snow_frames"] = run.snowFrames;
            out["thrown"] = run.last.thrown, out["flying"] = run.last.flying, out["resting"] = run.last.resting;
            out["carved_voxels"] = run.last.tracks.carvedVoxels;
            out["removed_mass"] = run.last.tracks.removedMass;
            out["compacted_mass"] = run.last.tracks.compactedMass;
            py::dict seconds;
            seconds["simulate"] = run.simulateSeconds, seconds["rasterize"] = run.rasterizeSeconds,
            seconds["write"] = run.writeSeconds;
            out["seconds"] = seconds;
            return out;
        },
        py::arg("snow_path"), py::arg("emitters"), py::arg("directory"), py::arg("fps") = 24.0,
        py::arg("first_frame") = 1, py::arg("settings") = S{}, py::arg("objects") = py::none(),
        py::arg("progress") = nullptr, R"doc(
Snow thrown by moving objects, and their tracks (docs/spray.md). `snow_path`: a VDB with the snow's `density` and
`surface` grids (a snow layer's file). `emitters`: a sequence of (F, 3, 3) arrays, one per emitter: at each of F
frames (first_frame, first_frame + 1, ...) its rectangle's centre, half side u and half side v (world m);
between frames each point moves linearly. `objects`: None or (vertices, triangles) that lumps land on.
Writes, for each frame, in `directory`: spray_####.vdb (the lumps' density and surface), snow_####.vdb (the snow
with its tracks, only at frames where they changed it) and spray_####.state (the state, written last: the frame's
completion marker). A run of the same inputs resumes after the last complete frame. Returns a dict: resumed_after
(frame or None), frames_written, snow_frames (every frame of the sequence with a snow file), thrown, flying, resting
and carved_voxels, removed_mass, compacted_mass (kg) of the last frame simulated, seconds (simulate, rasterize,
write). Releases the GIL; raises ValueError for bad input, firncore.BudgetError over a budget, OSError
(firncore.ReadError, firncore.WriteError) for files, firncore.Cancelled when `progress` is cancelled.)doc");

    m.def(
        "spray_frame_paths",
        [](const std::string &directory, int frame) {
            const firn::SprayFramePaths p = firn::sprayFramePaths(directory, frame);
            return py::make_tuple(p.spray, p.snow, p.state);
        },
        py::arg("directory"), py::arg("frame"), "The (spray VDB, snow VDB, state) paths of a frame.");

    m.def(
        "read_spray_state", [](const std::string &path) { return longCall([&] { return firn::readSprayState(path); }); },
        py::arg("path"), "The SprayParticles of a state file; raises firncore.ReadError for a damaged one.");

    m.def(
        "spray_terminal_speed",
        [](double radius, const S &settings) {
            return firn::terminalSpeed(radius, settings.lumps.density, settings.flight);
        },
        py::arg("radius"), py::arg("settings") = S{},
        "m/s at which drag balances gravity for a lump of `radius` (m): sqrt(2 m g / (rho_air C_d A)).");
}

}  // namespace firncore
