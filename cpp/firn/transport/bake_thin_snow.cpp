#include "firn/transport/bake_thin_snow.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace firn::bake {

namespace {

// The single-scattering albedo of the least absorbing channel.
double leastAbsorbedAlbedo(const VolumeOptics &optics) {
    return std::max({optics.albedo.x, optics.albedo.y, optics.albedo.z});
}

// The faces of unknown i on the axes along which it has air (no snow, no occluder) on both faces: bit f for face f
// (-x, +x, -y, +y, -z, +z).
unsigned twoSidedFaces(const SnowTopology &topo, std::size_t i) {
    unsigned open = 0;
    for (int a = 0; a < 3; ++a)
        if (topo.isAirFace(i, 2 * a) && topo.isAirFace(i, 2 * a + 1)) open |= 3u << (2 * a);
    return open;
}

// Voxels optically thinner than kTracedOpticalDepth (partly filled voxels of thrown snow, thin flakes, a
// small object's thin fringe) are too thin for a voxel diffusion and take the exact fluence and flux from
// Monte Carlo instead (bench/bake_suite.py: mean errors fell by 1-7 points on balls and lumps, and rose on a
// ball under one transport mean free path at g 0.85; voxels thicker than this were better left to the
// diffusion and its surface radiance, for a voxel's mean fluence is not what a camera sees of its first
// optical depth). Not next to transport-thick snow
// (sigma_tr h >= kThickReducedDepth in the least absorbing channel): that is the fringe of a thick surface,
// whose light the diffusion carries, and paths into such snow would scatter thousands of times.
// Small pieces of snow (at most kSmallPieceVoxels voxels connected through faces, edges or corners: thrown
// lumps, a cloud of them) are traced whole, however thick: a diffusion over a few voxels has no inside, and its
// surfaces' escape function is a half-space's (bench/bake_suite.py: spray_lumps 19.7 -> 11.9 %, spray_dense,
// lumps of up to 20 optical depths per voxel, 34.8 -> 27.0 %; the balls of 5 cm on 1 cm voxels, 500+ voxels,
// stay with the diffusion: ball_forward traced whole was 19.7 % against 17.1 %). Connected through faces only,
// 167 voxels of bits beside the car sample's snow counted as pieces and took 12 s to trace, and the lumps
// of spray_lumps, touching at edges, made pieces of over 125 voxels. Not a small layer of dense snow (a voxel
// too thick or absorbing for a traced layer, no inside or wide in transport mean free paths, every voxel with snow
// or an occluder on one side of each axis): a dusting of 16 x 16 x 1 voxels of sigma_t h 15 on the ground read
// 41.2 % per block, bias -42.3 % traced, 11.1 %, +1.6 % diffused, 10 x 10 x 3 of it 23.4 -> 8.6 %
// (bench/snow_on_ground_bench.py --one-voxel; floating one-voxel layers, diffused, +15 to +59 %).
// Larger pieces that are thin in transport mean free paths (more than kSmallPieceVoxels voxels, but at most
// kMaxTracedPieceReducedVolume summed over them in (sigma_tr h)^3: a ball of transport radius 2.5) have no
// diffusion inside either: ball_forward (5 cm, voxels of optical depth 4, g 0.9, sigma_tr h 0.4: 33 of it, 672
// voxels; the suite's next piece, ball_rgb, 660) read 22.7 % on the rays through its fringe alone and +/-20 %
// inside across the sun with the diffusion. Traced whole they are light traced (light_tracing.h: paths shared by
// the voxels): gathered per voxel, the backward tail of g 0.9 snow's source is too noisy to fit (1024 paths per
// voxel 13.1 %, bias -9.5 %; 8192 paths 8.6 %, -4.6 %, at 29 processor s), light traced 7.2 %, bias -2.3 % at
// 5.4 processor s (docs/bake.md, Accuracy), within a quarter of the budget (kWholePieceTracedSteps) 7.8 %, -2.7 %
// at 1.4 (a tenth: 8.7 %, -4.2 %); Draft a quarter of that (Preset::lightTracingShare; its seeds 0-1 9.4, 9.8 % at
// 0.35-0.41 processor s against 8.0, 7.5 % at 1.4-1.5). Where light tracing is not used (lamps, over that budget)
// they are diffused as before. Layers have no inside either: a piece none of whose voxels lies kMaxTracedPieceDepth
// transport mean free paths deep (axisDepth: to the air along an axis; a slab up to 5 thick) is traced whole too,
// however wide, where all its voxels are optically thinner than kTracedLayerOpticalDepth and absorb less than
// kTracedLayerAbsorptionDepth each (sigma_a h in the most absorbing channel). Measured on 24 x 24 slabs of 3 voxels
// (bench/bake_suite.py's slab_thin and its views, 4096-path references; docs/benchmarks.md, thin-slab), diffused ->
// traced whole: slab_thin (sigma_t h 2, omega 0.99, g 0.6) 8.0 -> 6.2 %, worst -34 -> +17 %, bias -2.7 -> +0.9 %;
// 4, 5, 6, 8 voxels of it 6.0, 5.2, 6.0, 4.0 -> 5.4, 4.6, 5.1, 4.3 % (half-thicknesses 1.6, 2.0, 2.4, 3.2); omega
// 0.9999 8.9 -> 6.3 %, 0.98 7.7 -> 6.2 %, but 0.95 6.9 -> 6.8 % and 0.9 6.8 -> 8.2 % (bias -8 %: in absorbing snow a
// voxel's mean source is not what a camera sees of its first optical depth); sigma_t h 2.5 mixed (g 0.6: 6.8 -> 8.1
// %, g 0.7: 8.5 -> 7.2 %), 3 and more worse (g 0.6: 6.3 -> 10.4 %; real snow, 10 at g 0.85: 9.0 -> 16.4 %). Along
// the axes, a tilted layer reads up to sqrt(3) deeper and stays with the diffusion sooner.
constexpr double kTracedOpticalDepth = 1.5, kThickReducedDepth = 2.0;
constexpr int kSmallPieceVoxels = 343;  // 7^3
// A small piece larger than this in (sigma_tr h)^3 summed has an inside after all (spray_dense's largest lump 672,
// a 10 x 10 x 3 layer of sigma_t h 15 27,500: traced -20 %; no case between them measured).
constexpr double kMaxTracedSmallPieceReducedVolume = 4096.0;
constexpr double kMaxTracedPieceReducedVolume = 64.0, kMaxTracedPieceDepth = 2.5, kTracedLayerOpticalDepth = 2.25,
                 kTracedLayerAbsorptionDepth = 0.1;
// A voxel under this optical depth (sigma_t h) is air to the tracing: it changes no light by more than that share. A
// layer of next to no density (float rounding of an antialiased fill, 2.3e-15 of the snow's) over snow that is not
// thick per voxel was traced as thin snow, and the renderer scattered in it: a flat top's mixed render +27 %
// (docs/benchmarks.md, lead-93 6.).
constexpr double kNegligibleOpticalDepth = 1e-6;
// kg/m^3: the density of kNegligibleOpticalDepth per voxel; at or under it a voxel holds no snow to trace, nor diffused
// snow beside a traced voxel (scatteredVoxels).
float negligibleDensity(const Medium &medium) {
    return float(kNegligibleOpticalDepth / (medium.optics().extinctionPerDensity * medium.voxelSize()));
}
// What a piece of connected snow is (26-neighbours of more than negligible density), as marked in thinVoxels' `done`.
// kTracedLayer: a transport-thin piece past both sizes, traced whole for having no inside (a layer).
enum PieceKind : std::int32_t {
    kUnvisited = 0,
    kSmallPiece = 1,
    kLargePiece = 2,
    kTransportThinPiece = 3,
    kTracedLayer = 4
};

// How deep `c` lies in its snow: the least reduced optical depth (sigma_tr h = reducedPerDensity * density per
// voxel) from its centre to the air along the six axis directions, `enough` at most. The six walks go in step
// and stop at the least so far: a voxel of a wide thin layer costs its way to the layer's face, not across it.
double axisDepth(Medium::Accessor &density, const openvdb::Coord &c, double reducedPerDensity, double enough) {
    std::array<double, 6> depth;
    depth.fill(0.5 * reducedPerDensity * density.getValue(c));
    double least = enough;
    for (int s = 1;; ++s) {
        bool walking = false;
        for (int a = 0; a < 6; ++a) {
            if (!(depth[a] < least)) continue;
            openvdb::Coord n = c;
            n[a / 2] += a % 2 ? s : -s;
            const float d = density.getValue(n);
            if (d > 0.0f) depth[a] += reducedPerDensity * d, walking = true;
            else least = depth[a];  // the air
        }
        if (!walking) return least;
    }
}

// Whether `piece` is shaped as a layer: wide along two directions against its thickness (its second widest extent
// over kLayerAspect times its thinnest), the extents along the principal axes of its voxels' centres weighted by
// density (a box n voxels long has variance (n^2 - 1) / 12 along it, so n = sqrt(12 var + 1), tilted or not). A
// dusting 16 x 16 x 1 or 10 x 10 x 3 is one; spray_dense's lumps of 2 x 2 x 2 and 1 x 2 x 2 voxels are not.
constexpr double kLayerAspect = 2.0;
bool layerShaped(Medium::Accessor &density, const std::vector<openvdb::Coord> &piece) {
    double weight = 0.0;
    openvdb::Vec3d first(0.0);
    openvdb::Mat3d second = openvdb::Mat3d::zero();
    for (const openvdb::Coord &c : piece) {
        const double w = density.getValue(c);
        const openvdb::Vec3d x = c.asVec3d();
        weight += w, first += w * x, second += w * openvdb::math::outerProduct(x, x);
    }
    const openvdb::Vec3d mean = first / weight;
    const openvdb::Mat3d covariance = second * (1.0 / weight) - openvdb::math::outerProduct(mean, mean);
    openvdb::Mat3d axes;
    openvdb::Vec3d variance;
    openvdb::math::diagonalizeSymmetricMatrix(covariance, axes, variance);
    std::array<double, 3> extent;
    for (int a = 0; a < 3; ++a) extent[a] = std::sqrt(12.0 * std::max(0.0, variance[a]) + 1.0);
    std::sort(extent.begin(), extent.end());
    return extent[1] > kLayerAspect * extent[0];
}

// Whether the unknown at `c` has air (no snow, no occluder) on both faces along some axis; `index`: the caller's,
// of topo.index.
bool twoSided(const SnowTopology &topo, openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index,
              const openvdb::Coord &c) {
    const std::int32_t i = index.getValue(c);
    return i >= 0 && twoSidedFaces(topo, std::size_t(i)) != 0;
}

// The kind of the piece around `seed` (sigma_tr h = reducedPerDensity * density); marks what it visits in `done`.
// Voxels of density `layerBelow` or more make no traced layer; those of `air` or less are none of it. A fill that
// meets a large piece's voxel stops, and so does one past both sizes that is no traced layer: each voxel is visited a
// bounded number of times, however large the snow.
PieceKind pieceAround(Medium::Accessor &density, openvdb::tree::ValueAccessor<openvdb::Int32Tree> &done,
                      const openvdb::Coord &seed, double reducedPerDensity, float layerBelow, float air,
                      const SnowTopology &topo, openvdb::tree::ValueAccessor<const openvdb::Int32Tree> &index) {
    const auto reducedVolume = [&](const openvdb::Coord &c) {
        return std::pow(reducedPerDensity * density.getValue(c), 3.0);
    };
    std::vector<openvdb::Coord> piece{seed}, stack{seed};
    std::size_t shallow = 0;  // piece[0, shallow) lie less than kMaxTracedPieceDepth deep (checked past both sizes)
    const auto hasInside = [&] {
        const double D = kMaxTracedPieceDepth;
        while (shallow < piece.size())
            if (axisDepth(density, piece[shallow++], reducedPerDensity, D) >= D) return true;
        return false;
    };
    done.setValue(seed, kSmallPiece);  // visited by this fill
    double reduced = reducedVolume(seed);
    bool notLayer = !(density.getValue(seed) < layerBelow), large = false;  // a voxel too thick for a traced layer
    while (!stack.empty() && !large) {
        const openvdb::Coord c = stack.back();
        stack.pop_back();
        for (int i = 0; i < 27 && !large; ++i) {
            const openvdb::Coord n = c + blockOffset(i);
            if (i == 13 || !(density.getValue(n) > air)) continue;
            const std::int32_t mark = done.getValue(n);
            if (mark == kLargePiece) large = true;
            else if (mark == kUnvisited) {
                done.setValue(n, kSmallPiece), piece.push_back(n), stack.push_back(n);
                reduced += reducedVolume(n);
                notLayer = notLayer || !(density.getValue(n) < layerBelow);
                large = int(piece.size()) > kSmallPieceVoxels && reduced > kMaxTracedPieceReducedVolume &&
                        (notLayer || hasInside());
            }
        }
    }
    // A small piece shaped as a layer with no inside (or wide in transport mean free paths) whose voxels are not all
    // thin enough for a traced layer is a layer of dense snow (a dusting): a camera sees its voxels' first optical
    // depth, not their mean, and the diffusion's surface patches hold it, unless a voxel is open to air on two
    // opposite faces (its density gradient cancels there: no side for its patch to face). A lump as thick as it is
    // wide is no layer: spray_dense's of 2 x 2 x 2 voxels (sigma_t h 6-17) diffused read +103 % seen from the sun's
    // side, -66 % against it (docs/benchmarks.md, spray-budget).
    const auto oneSided = [&] {
        return std::none_of(piece.begin(), piece.end(),
                            [&](const openvdb::Coord &c) { return twoSided(topo, index, c); });
    };
    const bool small = !large && int(piece.size()) <= kSmallPieceVoxels;
    const bool wide = reduced > kMaxTracedSmallPieceReducedVolume;
    const bool denseLayer = small && notLayer && (wide || (!hasInside() && layerShaped(density, piece))) && oneSided();
    const bool layer = reduced > kMaxTracedPieceReducedVolume;
    const PieceKind kind = large || denseLayer ? kLargePiece
                           : small             ? kSmallPiece
                           : layer             ? kTracedLayer
                                               : kTransportThinPiece;
    if (kind != kSmallPiece)
        for (const openvdb::Coord &c : piece) done.setValue(c, kind);
    return kind;
}

}  // namespace

std::vector<openvdb::Coord> TracedSnow::voxels() const {
    std::vector<openvdb::Coord> out = thin;
    out.insert(out.end(), wholePieces.begin(), wholePieces.end());
    return out;
}

// A diffused body's traced fringe, scattered by the renderer, takes the body's baked light as a path tracer does and
// reads too bright where the snow absorbs (docs/bake.md, Limits; docs/benchmarks.md, lead-88): a 5 cm ball of omega
// 0.9, g 0.6 on 1 cm voxels of sigma_t h 3 read 14.5 % per block, bias +10.2 %, where its traced values drawn as
// emission read 8.0 %, -0.7 % (sigma_t h 2: 13.4 % against 9.2 %; omega 0.95: 8.5 %, +4.9 % against 7.2 %), while in
// snow that scatters it is worth 2 points (ball_issue, omega 0.98: 8.5 -> 6.5 %; ball_rgb, 0.999 in its least
// absorbing channel: 8.4 -> 5.9 %). Scattered where 1 - omega is under this in the least absorbing channel.
constexpr double kFringeScatterAbsorption = 0.03;

std::vector<openvdb::Coord> scatteredVoxels(const Medium &medium, const TracedSnow &snow) {
    std::vector<openvdb::Coord> out = snow.voxels();
    if (1.0 - leastAbsorbedAlbedo(medium.optics()) < kFringeScatterAbsorption) return out;
    openvdb::BoolTree traced(false);
    for (const openvdb::Coord &c : out) traced.setValueOn(c);
    openvdb::tree::ValueAccessor<const openvdb::BoolTree> isTraced(traced);
    Medium::Accessor density = medium.accessor();
    const float air = negligibleDensity(medium);
    const auto besideDiffused = [&](const openvdb::Coord &c) {
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz)
                    if (const openvdb::Coord n = c.offsetBy(dx, dy, dz);
                        density.getValue(n) > air && !isTraced.isValueOn(n))
                        return true;
        return false;
    };
    // Whole pieces are traced whole: only thin voxels lie beside diffused snow.
    const auto thinEnd = out.begin() + std::ptrdiff_t(snow.thin.size());
    out.erase(std::remove_if(out.begin(), thinEnd, besideDiffused), thinEnd);
    return out;
}

TracedSnow thinVoxels(const Medium &medium, const SnowTopology &topo) {
    const VolumeOptics &optics = medium.optics();
    const double h = medium.voxelSize(), k = optics.extinctionPerDensity;
    const double leastReduced = 1.0 - leastAbsorbedAlbedo(optics) * optics.g;
    const float thinBelow = float(kTracedOpticalDepth / (k * h)),
                thickFrom = float(kThickReducedDepth / (leastReduced * k * h));
    const double mostAbsorbed = 1.0 - std::min({optics.albedo.x, optics.albedo.y, optics.albedo.z});
    const float layerBelow =
        float(std::min(kTracedLayerOpticalDepth, kTracedLayerAbsorptionDepth / mostAbsorbed) / (k * h));
    const float air = negligibleDensity(medium);
    TracedSnow out;
    Medium::Accessor density = medium.accessor();
    openvdb::Int32Tree pieces(kUnvisited);
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> done(pieces);
    openvdb::tree::ValueAccessor<const openvdb::Int32Tree> index(*topo.index);
    std::vector<bool> wholeInLayer;  // per voxel of out.wholePieces
    for (auto it = medium.density().cbeginValueOn(); it; ++it) {
        if (!(*it > air)) continue;
        std::int32_t mark = done.getValue(it.getCoord());
        if (mark == kUnvisited)
            mark = pieceAround(density, done, it.getCoord(), leastReduced * k * h, layerBelow, air, topo, index);
        if (mark == kSmallPiece) {
            out.thin.push_back(it.getCoord());
            continue;
        }
        bool nearThick = !(*it < thinBelow);
        for (int dx = -1; dx <= 1 && !nearThick; ++dx)
            for (int dy = -1; dy <= 1 && !nearThick; ++dy)
                for (int dz = -1; dz <= 1 && !nearThick; ++dz)
                    nearThick = density.getValue(it.getCoord().offsetBy(dx, dy, dz)) >= thickFrom;
        if (!nearThick) out.thin.push_back(it.getCoord());
        else if (mark == kTransportThinPiece || mark == kTracedLayer) {
            out.wholePieces.push_back(it.getCoord());
            wholeInLayer.push_back(mark == kTracedLayer);
        }
    }
    out.inLayer.assign(out.thin.size(), false);
    out.inLayer.insert(out.inLayer.end(), wholeInLayer.begin(), wholeInLayer.end());
    return out;
}

}  // namespace firn::bake
