// Add Snow Layer from Python: settings, generation, regeneration from kept metaballs, the surface mesh.
#include <optional>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <tbb/task_group.h>

#include "bindings.h"
#include "firn/io/vdb_io.h"
#include "firn/snow/snow_bands.h"
#include "firn/snow/snow_brush.h"
#include "firn/snow/snow_layer.h"
#include "firn/snow/surface_mesh.h"
#include "firn/util/error.h"
#include "mesh_arrays.h"

namespace py = pybind11;

namespace firncore {

namespace {

template <typename T>
py::array_t<T> rows(std::size_t n, std::size_t columns) {
    const auto count = static_cast<py::ssize_t>(n), width = static_cast<py::ssize_t>(columns);
    return columns == 1 ? py::array_t<T>({count}) : py::array_t<T>({count, width});
}

py::dict metaballsToArrays(const std::vector<firn::Metaball> &balls) {
    const std::size_t n = balls.size();
    auto centres = rows<float>(n, 3), normals = rows<float>(n, 3);
    auto radii = rows<float>(n, 1), bases = rows<float>(n, 1), depths = rows<float>(n, 1);
    auto c = centres.mutable_unchecked<2>(), nm = normals.mutable_unchecked<2>();
    auto r = radii.mutable_unchecked<1>(), b = bases.mutable_unchecked<1>(), d = depths.mutable_unchecked<1>();
    for (std::size_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) c(i, k) = balls[i].centre[k], nm(i, k) = balls[i].normal[k];
        r(i) = balls[i].radius, b(i) = balls[i].base, d(i) = balls[i].depth;
    }
    py::dict out;
    out["centres"] = centres, out["radii"] = radii, out["normals"] = normals, out["bases"] = bases,
    out["depths"] = depths;
    return out;
}

std::vector<firn::Metaball> metaballsFromArrays(const py::dict &arrays) {
    const auto get = [&](const char *key) {
        if (!arrays.contains(key)) throw firn::InvalidArgument(std::string("metaballs need the array '") + key + "'");
        return floatArray(arrays[key], std::string("metaball array '") + key + "'");
    };
    const FloatArray centres = get("centres"), normals = get("normals"), radii = get("radii"), bases = get("bases"),
                     depths = get("depths");
    const py::ssize_t n = radii.size();
    if (centres.size() != 3 * n || normals.size() != 3 * n || bases.size() != n || depths.size() != n)
        throw firn::InvalidArgument("metaball arrays disagree in length");
    std::vector<firn::Metaball> balls(n);
    for (py::ssize_t i = 0; i < n; ++i) {
        const float *c = centres.data() + 3 * i, *nm = normals.data() + 3 * i;
        balls[i] = {{c[0], c[1], c[2]}, radii.data()[i], {nm[0], nm[1], nm[2]}, bases.data()[i], depths.data()[i]};
        if (!(balls[i].radius > 0.0f) || !std::isfinite(c[0] + c[1] + c[2]))
            throw firn::InvalidArgument("metaball " + std::to_string(i) + " has a bad centre or radius");
    }
    return balls;
}

// What Python gets back: statistics and the kept metaballs. Grids go to the VDB file.
py::dict describe(const firn::SnowLayer &layer) {
    py::dict out;
    out["metaballs"] = metaballsToArrays(layer.metaballs);
    out["site_count"] = layer.siteCount;
    out["voxel_size"] = layer.voxelSize;
    out["active_voxels"] = layer.grids.density->activeVoxelCount();
    out["mean_density"] = firn::meanInteriorDensity(layer.grids);
    const openvdb::CoordBBox box = layer.grids.density->evalActiveVoxelBoundingBox();
    const openvdb::Vec3d lo = layer.grids.density->indexToWorld(box.min());
    const openvdb::Vec3d hi = layer.grids.density->indexToWorld(box.max());
    out["bounds"] = py::make_tuple(py::make_tuple(lo.x(), lo.y(), lo.z()), py::make_tuple(hi.x(), hi.y(), hi.z()));
    return out;
}

std::shared_ptr<firn::Progress> orNew(std::shared_ptr<firn::Progress> progress) {
    return progress ? progress : std::make_shared<firn::Progress>();
}

void bindSettings(py::module_ &m) {
    using S = firn::SnowLayerSettings;
    py::class_<S>(m, "SnowLayerSettings", "Settings of Add Snow Layer. Lengths in m, angles in rad, densities in kg/m^3.")
        .def(py::init([](const py::kwargs &kwargs) { return settingsFromKwargs<S>(kwargs, "SnowLayerSettings"); }))
        .def_readwrite("depth", &S::depth, "m of snow on open level ground")
        .def_readwrite("max_slope", &S::maxSlope, "rad from horizontal; steeper surfaces stay bare")
        .def_readwrite("spacing", &S::spacing, "m between landing sites: small is smooth, large is uneven")
        .def_readwrite("randomness", &S::randomness, "0..1 jitter of depth and ball radius")
        .def_readwrite("smoothness", &S::smoothness, "0..1 overlap of the metaballs")
        .def_property(
            "direction", [](const S &s) { return py::make_tuple(s.direction.x, s.direction.y, s.direction.z); },
            [](S &s, const std::array<float, 3> &d) { s.direction = {d[0], d[1], d[2]}; },
            "the way snow falls (x, y, z); tilt it for wind")
        .def_readwrite("spread", &S::spread, "rad, half-angle of the cone snow falls from")
        .def_readwrite("exposure_rays", &S::exposureRays, "rays per landing site for sheltering")
        .def_readwrite("density_top", &S::densityTop, "kg/m^3 at the snow surface")
        .def_readwrite("density_bottom", &S::densityBottom, "kg/m^3 approached at depth")
        .def_readwrite("compaction", &S::compaction, "0..1: how fast density rises with depth")
        .def_readwrite("voxel_size", &S::voxelSize, "m; 0 picks it from depth and spacing")
        .def_readwrite("max_voxels", &S::maxVoxels, "voxel budget checked before allocating")
        .def_readwrite("seed", &S::seed)
        .def("validate", &S::validate, "Raises ValueError naming the first setting out of range.")
        .def_property_readonly("effective_voxel_size", &S::effectiveVoxelSize, "m, the voxel size that will be used");
}

void bindCamera(py::module_ &m) {
    using C = firn::CameraFootprint;
    const auto vec = [](const glm::dvec3 &v) { return py::make_tuple(v.x, v.y, v.z); };
    py::class_<C>(m, "CameraFootprint",
                  "The camera that sizes the voxels of snow with levels of detail. Lengths in m, angles in rad.")
        .def(py::init([](const py::kwargs &kwargs) { return settingsFromKwargs<C>(kwargs, "CameraFootprint"); }))
        .def_property(
            "position", [vec](const C &c) { return vec(c.position); },
            [](C &c, const std::array<double, 3> &p) { c.position = {p[0], p[1], p[2]}; }, "m, world space")
        .def_property(
            "forward", [vec](const C &c) { return vec(c.forward); },
            [](C &c, const std::array<double, 3> &d) { c.forward = {d[0], d[1], d[2]}; }, "unit view direction")
        .def_readwrite("pixel_angle", &C::pixelAngle, "rad per pixel: field of view over pixels across")
        .def_readwrite("view_half_angle", &C::viewHalfAngle,
                       "rad, a cone around forward holding the whole view (pi or more: all around)")
        .def("validate", &C::validate, "Raises ValueError naming the first field out of range.");
    m.def(
        "lod_voxel_size",
        [](double distance, const C &camera, double fineVoxel, int bands) {
            return firn::lodVoxelSize(firn::lodLevel(distance, camera, fineVoxel, bands), fineVoxel);
        },
        py::arg("distance"), py::arg("camera"), py::arg("fine_voxel"), py::arg("bands") = 16,
        "Voxel size (m) of snow `distance` m from the camera: fine_voxel x 2^k within a pixel's footprint.");
}

// `pattern` with "{level}" replaced by the band's level: one VDB file per band.
std::string bandPath(const std::string &pattern, int level) {
    const std::string key = "{level}";
    const std::size_t at = pattern.find(key);
    if (at == std::string::npos) throw firn::InvalidArgument("band path pattern needs '{level}': " + pattern);
    return pattern.substr(0, at) + std::to_string(level) + pattern.substr(at + key.size());
}

firn::BrushMode brushMode(const std::string &mode) {
    if (mode == "ADD") return firn::BrushMode::Add;
    if (mode == "ERASE") return firn::BrushMode::Erase;
    if (mode == "SMOOTH") return firn::BrushMode::Smooth;
    throw firn::InvalidArgument("brush mode must be 'ADD', 'ERASE' or 'SMOOTH' (got '" + mode + "')");
}

py::dict stats(const firn::DabStats &s) {
    py::dict out;
    out["added"] = s.added, out["removed"] = s.removed, out["changed"] = s.changed, out["leaves"] = s.leaves;
    return out;
}

openvdb::FloatGrid::Ptr snowGrid(const std::string &path, const char *name) {
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(firn::readGrid(path, name));
    if (!grid) throw firn::InvalidArgument(path + " has no float '" + name + "' grid");
    return grid;
}

void bindCanvas(py::module_ &m) {
    using firn::SnowCanvas;
    py::class_<SnowCanvas>(m, "SnowCanvas", R"doc(A snow layer edited by brush dabs (docs/architecture.md, Snow brush).
SnowCanvas(metaballs, settings, path, vertices, triangles, occluders=None): the layer's metaballs (as
generate_snow_layer returns them) and settings, the VDB file `path` they were rasterized into, its targets and
occluders (world m, as for generate_snow_layer). Each dab rasterizes again only the leaves it changes.)doc")
        .def(py::init([](const py::dict &metaballs, const firn::SnowLayerSettings &settings, const std::string &path,
                         const py::object &vertices, const py::object &triangles, const py::object &occluders) {
                 std::vector<firn::Metaball> balls = metaballsFromArrays(metaballs);
                 const firn::TriangleMesh targets = meshFromArrays(vertices, triangles, "targets");
                 const firn::TriangleMesh blockers = optionalMesh(occluders, "occluders");
                 return longCall([&] {
                     firn::SnowGrids grids{snowGrid(path, "density"), snowGrid(path, "surface")};
                     return std::make_unique<SnowCanvas>(std::move(balls), std::move(grids), settings, targets,
                                                         blockers);
                 });
             }),
             py::arg("metaballs"), py::arg("settings"), py::arg("path"), py::arg("vertices"), py::arg("triangles"),
             py::arg("occluders") = py::none())
        .def(
            "stroke",
            [](SnowCanvas &canvas, const py::object &locations, const py::object &pressures, const std::string &mode,
               double radius, double strength) {
                const FloatArray at = floatArray(locations, "stroke locations");
                const FloatArray p = floatArray(pressures, "stroke pressures");
                if (at.size() != 3 * p.size()) throw firn::InvalidArgument("stroke: one pressure per (x, y, z) location");
                firn::Dab dab;
                dab.mode = brushMode(mode), dab.radius = radius, dab.strength = strength;
                const firn::DabStats total = longCall([&] {
                    firn::DabStats sum;
                    for (py::ssize_t i = 0; i < p.size(); ++i) {
                        dab.centre = {at.data()[3 * i], at.data()[3 * i + 1], at.data()[3 * i + 2]};
                        dab.pressure = p.data()[i];
                        const firn::DabStats one = canvas.apply(dab);
                        sum.added += one.added, sum.removed += one.removed, sum.changed += one.changed,
                            sum.leaves += one.leaves;
                    }
                    return sum;
                });
                return stats(total);
            },
            py::arg("locations"), py::arg("pressures"), py::arg("mode"), py::arg("radius"), py::arg("strength"),
            R"doc(Dabs at `locations` ((N, 3) world m) with `pressures` ((N,) 0..1); `mode` 'ADD', 'ERASE' or 'SMOOTH',
`radius` m, `strength` m of depth per dab. Returns a dict of balls added, removed, changed and leaves rasterized
again (summed). Releases the GIL; ValueError for bad input.)doc")
        .def("metaballs", [](const SnowCanvas &c) { return metaballsToArrays(c.metaballs()); },
             "The live metaballs, as generate_snow_layer returns them.")
        .def(
            "write",
            [](const SnowCanvas &c, const std::string &path) {
                longCall([&] { firn::writeGrids(path, {c.grids().density, c.grids().surface}); });
            },
            py::arg("path"), "Writes the density and surface grids to the VDB file at `path` (atomically).")
        .def_property_readonly("active_voxels", [](const SnowCanvas &c) { return c.grids().density->activeVoxelCount(); })
        .def_property_readonly("leaf_count", [](const SnowCanvas &c) { return c.grids().surface->tree().leafCount(); },
                               "8^3 leaves of the surface grid")
        .def_property_readonly("mean_density", [](const SnowCanvas &c) { return firn::meanInteriorDensity(c.grids()); },
                               "kg/m^3 of the voxels wholly inside the snow");
}

// A vertex group mask from Python: None, or one 0..1 per target vertex.
std::vector<float> optionalWeights(const py::object &weights) {
    if (weights.is_none()) return {};
    const FloatArray w = floatArray(weights, "weights");
    return std::vector<float>(w.data(), w.data() + w.size());
}

// (vertices (N, 3) float32, triangles (M, 3) uint32) of a surface mesh, for Python.
py::tuple meshArrays(const firn::SurfaceMesh &mesh) {
    auto vertices = rows<float>(mesh.vertices.size(), 3);
    auto faces = rows<unsigned>(mesh.triangles.size(), 3);
    auto v = vertices.mutable_unchecked<2>();
    auto f = faces.mutable_unchecked<2>();
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
        for (int k = 0; k < 3; ++k) v(i, k) = mesh.vertices[i][k];
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
        for (int k = 0; k < 3; ++k) f(i, k) = mesh.triangles[i][k];
    return py::make_tuple(vertices, faces);
}

// The proxy's meshing from Python: None, or a dict of snow_surface_mesh's settings (adaptivity, max_triangles,
// isovalue), each optional.
std::optional<firn::SurfaceMeshSettings> optionalMeshSettings(const py::object &settings) {
    if (settings.is_none()) return std::nullopt;
    const py::dict d = settings.cast<py::dict>();
    for (const auto &item : d) {
        const auto key = item.first.cast<std::string>();
        if (key != "adaptivity" && key != "max_triangles" && key != "isovalue")
            throw firn::InvalidArgument("proxy_mesh: unknown setting '" + key + "'");
    }
    firn::SurfaceMeshSettings s;
    if (d.contains("adaptivity")) s.adaptivity = d["adaptivity"].cast<double>();
    if (d.contains("max_triangles")) s.maxTriangles = d["max_triangles"].cast<std::size_t>();
    if (d.contains("isovalue")) s.isovalue = d["isovalue"].cast<double>();
    return s;
}

// Writes the grids to `path` while meshing their surface from memory (when `settings` asks for it): the write
// is serial (OpenVDB compresses leaf by leaf), the meshing parallel, so the two share the cores, and the mesh
// needs no read of the file back.
std::optional<firn::SurfaceMesh> writeMeshing(const std::string &path, const firn::SnowGrids &grids,
                                              const std::optional<firn::SurfaceMeshSettings> &settings,
                                              firn::Progress *progress) {
    if (!settings) {
        firn::writeGrids(path, {grids.density, grids.surface});
        return std::nullopt;
    }
    tbb::task_group writing;
    writing.run([&] { firn::writeGrids(path, {grids.density, grids.surface}); });
    std::optional<firn::SurfaceMesh> mesh;
    try {
        mesh = firn::meshSurface(*grids.surface, *settings, firn::SubProgress(progress, 1.0, 1.0));
    } catch (...) {
        writing.wait();  // the write reads the grids: it ends before they go
        throw;
    }
    writing.wait();  // rethrows the write's error
    return mesh;
}

}  // namespace

void bindSnow(py::module_ &m) {
    bindSettings(m);
    bindCanvas(m);
    bindCamera(m);
    m.def(
        "generate_snow_layer",
        [](const py::object &vertices, const py::object &triangles, const py::object &occluders,
           const firn::SnowLayerSettings &settings, const std::string &path, std::shared_ptr<firn::Progress> progress,
           const py::object &weights, const py::object &proxyMesh) {
            const firn::TriangleMesh targets = meshFromArrays(vertices, triangles, "targets");
            const std::vector<float> depthWeights = optionalWeights(weights);
            const firn::TriangleMesh blockers = optionalMesh(occluders, "occluders");
            const std::optional<firn::SurfaceMeshSettings> meshing = optionalMeshSettings(proxyMesh);
            progress = orNew(progress);
            std::optional<firn::SurfaceMesh> proxy;
            const firn::SnowLayer layer = longCall([&] {
                firn::SnowLayer made = firn::generateSnowLayer(targets, blockers, settings, progress.get(), depthWeights);
                proxy = writeMeshing(path, made.grids, meshing, progress.get());
                return made;
            });
            py::dict out = describe(layer);
            out["dropped_triangles"] = targets.droppedDegenerate + blockers.droppedDegenerate;
            out["open_surfaces_turned"] = layer.openSurfaces.surfaces;
            if (proxy) out["proxy"] = meshArrays(*proxy);
            return out;
        },
        py::arg("vertices"), py::arg("triangles"), py::arg("occluders") = py::none(), py::arg("settings"),
        py::arg("path"), py::arg("progress") = nullptr, py::arg("weights") = py::none(),
        py::arg("proxy_mesh") = py::none(),
        R"doc(Puts snow on the target triangles (world space, m) and writes its `density` and `surface` grids to the
VDB file at `path` (atomically). `occluders` is None or (vertices, triangles) of everything else that shelters
the targets. `weights` is None or one 0..1 per target vertex scaling the depth (a vertex group mask). `proxy_mesh`
is None or a dict of snow_surface_mesh's settings (adaptivity, max_triangles, isovalue): the surface is then
meshed from memory while the file is written, as snow_surface_mesh would mesh the file. Returns a dict:
metaballs (arrays centres, radii, normals, bases, depths), site_count, voxel_size, active_voxels, mean_density
(kg/m^3), bounds, dropped_triangles, open_surfaces_turned (open target surfaces whose downward normals were
ignored: snow lies on their upper side), and with proxy_mesh, proxy: (vertices, triangles) as
snow_surface_mesh returns them. Releases the GIL; raises ValueError for bad
input, firncore.BudgetError over the voxel budget, firncore.Cancelled when `progress` is cancelled.)doc");

    m.def(
        "generate_snow_bands",
        [](const py::object &vertices, const py::object &triangles, const py::object &occluders,
           const firn::SnowLayerSettings &settings, const firn::CameraFootprint &camera, const std::string &pattern,
           std::shared_ptr<firn::Progress> progress, const py::object &weights) {
            bandPath(pattern, 0);  // a bad pattern before any work
            const firn::TriangleMesh targets = meshFromArrays(vertices, triangles, "targets");
            const std::vector<float> depthWeights = optionalWeights(weights);
            const firn::TriangleMesh blockers = optionalMesh(occluders, "occluders");
            progress = orNew(progress);
            const firn::SnowBands snow = longCall([&] {
                firn::SnowBands made =
                    firn::generateSnowBands(targets, blockers, settings, camera, progress.get(), depthWeights);
                for (const firn::SnowBand &b : made.bands)
                    firn::writeGrids(bandPath(pattern, b.band.level), {b.grids.density, b.grids.surface});
                return made;
            });
            py::list bands;
            for (const firn::SnowBand &b : snow.bands) {
                firn::SnowLayer layer;  // describe() reads the grids and voxel size; the balls are shared, below
                layer.grids = b.grids, layer.voxelSize = b.band.voxelSize, layer.siteCount = b.siteCount;
                py::dict band = describe(layer);
                band.attr("pop")("metaballs");
                band["level"] = b.band.level, band["path"] = bandPath(pattern, b.band.level);
                band["near_distance"] = b.band.nearDistance, band["far_distance"] = b.band.farDistance;
                band["spacing"] = b.band.spacing;
                bands.append(band);
            }
            py::dict out;
            out["bands"] = bands;
            out["metaballs"] = metaballsToArrays(snow.metaballs);
            out["out_of_view"] = snow.outOfView;
            out["dropped_triangles"] = targets.droppedDegenerate + blockers.droppedDegenerate;
            out["open_surfaces_turned"] = snow.openSurfaces.surfaces;
            return out;
        },
        py::arg("vertices"), py::arg("triangles"), py::arg("occluders") = py::none(), py::arg("settings"),
        py::arg("camera"), py::arg("path_pattern"), py::arg("progress") = nullptr, py::arg("weights") = py::none(),
        R"doc(Add Snow Layer with levels of detail by distance to `camera` (a CameraFootprint): as generate_snow_layer,
but one VDB file per band of distances, `path_pattern` with '{level}' replaced by the band's level (0: the
finest, settings.effective_voxel_size; each level doubles the voxel and the spacing). Returns a dict: bands (a
list, finest first, of dicts: level, path, voxel_size, spacing, near_distance, far_distance (m from the camera),
site_count, active_voxels, mean_density, bounds), metaballs (all bands'), out_of_view (target pieces left out),
dropped_triangles, open_surfaces_turned. Errors as generate_snow_layer.)doc");

    m.def(
        "rasterize_metaballs",
        [](const py::dict &metaballs, const firn::SnowLayerSettings &settings, const std::string &path,
           std::shared_ptr<firn::Progress> progress, const py::object &proxyMesh) {
            settings.validate();
            firn::SnowLayer layer;
            layer.metaballs = metaballsFromArrays(metaballs);
            if (layer.metaballs.empty()) throw firn::InvalidArgument("no metaballs to rasterize");
            layer.voxelSize = settings.effectiveVoxelSize();
            layer.siteCount = 0;
            const std::optional<firn::SurfaceMeshSettings> meshing = optionalMeshSettings(proxyMesh);
            progress = orNew(progress);
            std::optional<firn::SurfaceMesh> proxy;
            longCall([&] {
                layer.grids = firn::rasterizeSnow(layer.metaballs, settings.raster(),
                                                  firn::SubProgress(progress.get(), 0.0, 1.0));
                proxy = writeMeshing(path, layer.grids, meshing, progress.get());
            });
            py::dict out = describe(layer);
            if (proxy) out["proxy"] = meshArrays(*proxy);
            return out;
        },
        py::arg("metaballs"), py::arg("settings"), py::arg("path"), py::arg("progress") = nullptr,
        py::arg("proxy_mesh") = py::none(),
        "Rebuilds the grids from (possibly edited) metaballs, as returned by generate_snow_layer, into `path`; "
        "proxy_mesh as for generate_snow_layer.");

    m.def(
        "snow_surface_mesh",
        [](const std::string &path, double adaptivity, std::size_t maxTriangles, double isovalue,
           std::shared_ptr<firn::Progress> progress) {
            const firn::SurfaceMeshSettings settings{adaptivity, maxTriangles, isovalue};
            progress = orNew(progress);
            const firn::SurfaceMesh mesh = longCall([&] {
                // The surface grid alone: a snow file's density is several times larger.
                const auto surface = openvdb::gridPtrCast<openvdb::FloatGrid>(firn::readGrid(path, "surface"));
                if (!surface) throw firn::InvalidArgument(path + " has no float 'surface' grid");
                return firn::meshSurface(*surface, settings, firn::SubProgress(progress.get(), 0.0, 1.0));
            });
            return meshArrays(mesh);
        },
        py::arg("path"), py::arg("adaptivity") = 0.0, py::arg("max_triangles") = 0, py::arg("isovalue") = 0.0,
        py::arg("progress") = nullptr,
        R"doc(The snow surface (where the `surface` level set in the VDB at `path` crosses `isovalue` m: 0 is the surface) as (vertices (N, 3)
float32, world m; triangles (M, 3) uint32, counter-clockwise seen from outside). `adaptivity` (0..1) merges flat
regions; `max_triangles` (0: no budget, else at least 100) is met with more adaptivity, then coarser voxels
(the viewport proxy). Releases the GIL; raises ValueError for bad settings or a file without a surface grid,
OSError for an unreadable file, firncore.Cancelled when `progress` is cancelled.)doc");
}

}  // namespace firncore
