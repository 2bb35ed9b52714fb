#include "firn/io/spray_files.h"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <type_traits>

#include "firn/io/atomic_file.h"
#include "firn/io/vdb_io.h"
#include "firn/util/error.h"

namespace firn {

namespace {

constexpr char kMagic[8] = {'F', 'I', 'R', 'N', 'S', 'P', 'R', 'Y'};
constexpr std::uint32_t kFormat = 1;

// One particle as stored: every field packed, in order (no padding).
constexpr std::size_t kParticleBytes = 6 * 8 + 8 + 4 + 1 + 1 + kMaxBallsPerLump * (3 * 4 + 4);

template <class T>
void put(std::ostream &out, const T &value) {
    static_assert(std::is_trivially_copyable_v<T>);
    out.write(reinterpret_cast<const char *>(&value), sizeof(T));
}

template <class T>
T take(std::istream &in) {
    T value;
    in.read(reinterpret_cast<char *>(&value), sizeof(T));
    return value;
}

// A 64-bit digest of the inputs (mix64 chained over 64-bit words): a state file made by other inputs is not
// resumed.
class Fingerprint {
  public:
    void add(std::uint64_t word) { digest_ = mix64(digest_ ^ word); }
    void add(double x) {
        std::uint64_t bits;
        std::memcpy(&bits, &x, sizeof bits);
        add(bits);
    }
    void add(const glm::dvec3 &v) { add(v.x), add(v.y), add(v.z); }
    void addBytes(const char *data, std::size_t size) {
        addWords(data, size);
        add(std::uint64_t(size));
    }
    // A file's bytes, read a chunk at a time.
    void addFile(const std::string &path) {
        std::ifstream file(path, std::ios::binary);
        if (!file) throw ReadError("cannot read " + path);
        std::vector<char> chunk(1 << 20);  // a multiple of 8 bytes: words do not straddle chunks
        std::uint64_t size = 0;
        while (file.read(chunk.data(), std::streamsize(chunk.size())) || file.gcount() > 0) {
            addWords(chunk.data(), std::size_t(file.gcount()));
            size += std::uint64_t(file.gcount());
        }
        if (file.bad()) throw ReadError("cannot read " + path);
        add(size);
    }
    std::uint64_t digest() const { return digest_; }

  private:
    void addWords(const char *data, std::size_t size) {
        for (std::size_t i = 0; i < size; i += 8) {
            std::uint64_t word = 0;
            std::memcpy(&word, data + i, std::min<std::size_t>(8, size - i));
            add(word);
        }
    }
    std::uint64_t digest_ = 0x46697261u;
};

// fingerprints[k]: the digest of the inputs the state after frame index k depends on: the settings, objects, fps,
// first frame, the snow file's bytes and the emitters' rectangles up to frame k (a longer sequence of the same
// beginning resumes).
std::vector<std::uint64_t> fingerprintsOf(const SprayJob &job, std::size_t frameCount) {
    Fingerprint f;
    const SpraySettings &s = job.settings;
    for (double x : {s.emission.rate, s.emission.spreadAngle, s.emission.throwSpeed, s.emission.cellSize,
                     s.lumps.radius, s.lumps.radiusVariation, s.lumps.density, double(s.lumps.ballsPerLump),
                     s.lumps.breakRate, s.lumps.breakSpeed, s.flight.gravity, s.flight.airDensity,
                     s.flight.dragCoefficient, s.tracks.thickness, s.tracks.compactionDepth, s.tracks.maxDensity,
                     double(s.substeps), double(s.deposit), double(s.cutTracks), s.voxelSize, s.maxParticles,
                     s.maxVoxels, job.fps, double(job.firstFrame), double(job.emitters.size())})
        f.add(x);
    f.add(s.flight.down);
    f.add(s.seed);
    f.addBytes(reinterpret_cast<const char *>(job.objects.positions.data()),
               job.objects.positions.size() * sizeof(glm::vec3));
    f.addBytes(reinterpret_cast<const char *>(job.objects.triangles.data()),
               job.objects.triangles.size() * sizeof(glm::uvec3));
    f.addFile(job.snowPath);
    std::vector<std::uint64_t> digests;
    for (std::size_t k = 0; k < frameCount; ++k) {
        for (const Emitter &e : job.emitters) {
            const EmitterRectangle &r = e.frames[k];
            f.add(r.centre), f.add(r.halfU), f.add(r.halfV);
        }
        digests.push_back(f.digest());
    }
    return digests;
}

void putParticle(std::ostream &out, const SprayParticle &p) {
    for (const glm::dvec3 &v : {p.position, p.velocity}) put(out, v.x), put(out, v.y), put(out, v.z);
    put(out, p.id), put(out, p.radius), put(out, std::uint8_t(p.state)), put(out, p.ballCount);
    for (int b = 0; b < kMaxBallsPerLump; ++b) {
        put(out, p.ballOffset[b].x), put(out, p.ballOffset[b].y), put(out, p.ballOffset[b].z);
        put(out, p.ballRadius[b]);
    }
}

SprayParticle takeParticle(std::istream &in) {
    SprayParticle p;
    for (glm::dvec3 *v : {&p.position, &p.velocity}) v->x = take<double>(in), v->y = take<double>(in), v->z = take<double>(in);
    p.id = take<std::uint64_t>(in);
    p.radius = take<float>(in);
    const auto state = take<std::uint8_t>(in);
    p.ballCount = take<std::uint8_t>(in);
    if (state > std::uint8_t(ParticleState::OnObject) || p.ballCount < 1 || p.ballCount > kMaxBallsPerLump)
        throw std::runtime_error("a particle's state or ball count is out of range");
    p.state = ParticleState(state);
    for (int b = 0; b < kMaxBallsPerLump; ++b) {
        p.ballOffset[b].x = take<float>(in), p.ballOffset[b].y = take<float>(in), p.ballOffset[b].z = take<float>(in);
        p.ballRadius[b] = take<float>(in);
    }
    return p;
}

SnowGrids readSnow(const std::string &path) {
    const openvdb::GridPtrVec grids = readGrids(path);
    SnowGrids snow;
    for (const openvdb::GridBase::Ptr &grid : grids) {
        if (grid->getName() == "density") snow.density = openvdb::gridPtrCast<openvdb::FloatGrid>(grid);
        if (grid->getName() == "surface") snow.surface = openvdb::gridPtrCast<openvdb::FloatGrid>(grid);
    }
    if (!snow.density || !snow.surface) throw InvalidArgument(path + " has no float 'density' and 'surface' grids");
    return snow;
}

// The last frame of the sequence whose files are complete and were made by the same inputs, with its state.
std::optional<SavedSprayState> lastCompleteFrame(const SprayJob &job, const std::vector<std::uint64_t> &fingerprints) {
    for (std::size_t k = fingerprints.size(); k-- > 0;) {
        const SprayFramePaths paths = sprayFramePaths(job.directory, job.firstFrame + int(k));
        if (!std::filesystem::exists(paths.state) || !std::filesystem::exists(paths.spray)) continue;
        try {
            const SavedSprayState header = readSprayState(paths.state, StateRead::Header);
            if (header.fingerprint == fingerprints[k] && header.frame == k) return readSprayState(paths.state);
        } catch (const ReadError &) {
            // a damaged marker: that frame is not complete
        }
    }
    return std::nullopt;
}

double secondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

SprayFramePaths sprayFramePaths(const std::string &directory, int frame) {
    char number[32];
    std::snprintf(number, sizeof number, "%04d", frame);
    const std::filesystem::path dir(directory);
    const std::string n(number);
    return {(dir / ("spray_" + n + ".vdb")).string(), (dir / ("snow_" + n + ".vdb")).string(),
            (dir / ("spray_" + n + ".state")).string()};
}

void writeSprayState(const std::string &path, const SavedSprayState &s) {
    writeFileAtomically(path, [&](std::ostream &out) {
        out.write(kMagic, sizeof kMagic);
        put(out, kFormat);
        put(out, s.fingerprint), put(out, std::uint64_t(s.frame)), put(out, s.nextId);
        put(out, std::uint8_t(s.snowFrame.has_value())), put(out, std::int32_t(s.snowFrame.value_or(0)));
        put(out, std::uint64_t(s.particles.size()));
        for (const SprayParticle &p : s.particles) putParticle(out, p);
    });
}

SavedSprayState readSprayState(const std::string &path, StateRead what) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw ReadError("cannot read " + path);
    in.exceptions(std::ios_base::failbit | std::ios_base::badbit);
    try {
        in.seekg(0, std::ios::end);
        const auto size = std::uint64_t(in.tellg());
        in.seekg(0);
        char magic[sizeof kMagic];
        in.read(magic, sizeof magic);
        if (std::memcmp(magic, kMagic, sizeof kMagic) != 0 || take<std::uint32_t>(in) != kFormat)
            throw std::runtime_error("not a Firn spray state (format " + std::to_string(kFormat) + ")");
        SavedSprayState s;
        s.fingerprint = take<std::uint64_t>(in);
        s.frame = std::size_t(take<std::uint64_t>(in));
        s.nextId = take<std::uint64_t>(in);
        const bool hasSnow = take<std::uint8_t>(in) != 0;
        const auto snowFrame = take<std::int32_t>(in);
        if (hasSnow) s.snowFrame = snowFrame;
        const auto count = take<std::uint64_t>(in);
        const std::uint64_t header = std::uint64_t(in.tellg());
        if (count > (size - header) / kParticleBytes || header + count * kParticleBytes != size)
            throw std::runtime_error("its length does not match its " + std::to_string(count) +
                                     " particles (truncated?)");
        if (what == StateRead::Header) return s;
        s.particles.resize(count);
        for (SprayParticle &p : s.particles) p = takeParticle(in);
        return s;
    } catch (const std::exception &e) {  // std::ios_base::failure: cut short
        throw ReadError("cannot read " + path + ": " + e.what());
    }
}

SprayRun runSpraySequence(const SprayJob &job, Progress *progress) {
    job.settings.validate();
    SprayScene scene;
    scene.emitters = job.emitters;
    scene.fps = job.fps;
    scene.validate();
    if (job.directory.empty()) throw InvalidArgument("spray needs a folder for its files");
    const std::size_t frameCount = scene.frameCount();
    const std::vector<std::uint64_t> fingerprints = fingerprintsOf(job, frameCount);
    if (!job.objects.empty()) scene.objects = std::make_shared<RayCaster>(job.objects);

    SprayRun run;
    SprayState state;
    std::optional<int> snowFrame;
    if (std::optional<SavedSprayState> saved = lastCompleteFrame(job, fingerprints)) {
        run.resumedAfter = job.firstFrame + int(saved->frame);
        snowFrame = saved->snowFrame;
        state.snow = readSnow(snowFrame ? sprayFramePaths(job.directory, *snowFrame).snow : job.snowPath);
        state.frame = saved->frame, state.nextId = saved->nextId, state.particles = std::move(saved->particles);
    } else {
        state = initialSprayState(readSnow(job.snowPath));
    }
    const auto writeFrame = [&](bool snowChanged) {
        const int frame = job.firstFrame + int(state.frame);
        const SprayFramePaths paths = sprayFramePaths(job.directory, frame);
        auto start = std::chrono::steady_clock::now();
        const SnowGrids spray = spraySnapshot(state, job.settings, SubProgress(nullptr, 0.0, 1.0));
        run.rasterizeSeconds += secondsSince(start);
        start = std::chrono::steady_clock::now();
        writeGrids(paths.spray, {spray.density, spray.surface});
        if (snowChanged) {
            writeGrids(paths.snow, {state.snow.density, state.snow.surface});
            snowFrame = frame;
        } else {
            std::error_code error;  // an earlier job's file: the snow here is that of snowFrame
            if (std::filesystem::remove(paths.snow, error), error)
                throw WriteError("cannot remove " + paths.snow + ": " + error.message());
        }
        writeSprayState(paths.state, {fingerprints[state.frame], state.frame, state.nextId, snowFrame, state.particles});
        run.writeSeconds += secondsSince(start);
        run.framesWritten.push_back(frame);
    };
    if (!run.resumedAfter) writeFrame(false);
    while (state.frame + 1 < frameCount) {
        const double done = double(state.frame) / double(frameCount - 1);
        const auto start = std::chrono::steady_clock::now();
        run.last = simulateSprayFrame(state, scene, job.settings,
                                      SubProgress(progress, done, done + 0.8 / double(frameCount - 1)));
        run.simulateSeconds += secondsSince(start);
        writeFrame(run.last.tracks.carvedVoxels > 0);
        if (progress) {
            progress->report(double(state.frame) / double(frameCount - 1));
            progress->throwIfCancelled();
        }
    }
    for (std::size_t k = 0; k < frameCount; ++k)
        if (std::filesystem::exists(sprayFramePaths(job.directory, job.firstFrame + int(k)).snow))
            run.snowFrames.push_back(job.firstFrame + int(k));
    return run;
}

}  // namespace firn
