// Reading Firn's VDB files from Python without pyopenvdb (which Blender's Python may lack), and taking grids out.
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <openvdb/tools/Count.h>
#include <openvdb/tools/Interpolation.h>

#include "bindings.h"
#include "firn/io/vdb_io.h"
#include "firn/util/error.h"
#include "mesh_arrays.h"

namespace py = pybind11;

namespace firncore {

namespace {

openvdb::FloatGrid::Ptr floatGrid(const std::string &path, const std::string &name) {
    for (const auto &grid : firn::readGrids(path))
        if (grid->getName() == name) {
            if (auto typed = openvdb::gridPtrCast<openvdb::FloatGrid>(grid)) return typed;
            throw firn::InvalidArgument("grid '" + name + "' in " + path + " is not a float grid");
        }
    throw firn::InvalidArgument(path + " has no grid named '" + name + "'");
}

openvdb::Vec3fGrid::Ptr colorGrid(const std::string &path, const std::string &name) {
    const openvdb::GridBase::Ptr grid = firn::readGrid(path, name);
    if (!grid) throw firn::InvalidArgument(path + " has no grid named '" + name + "'");
    if (auto typed = openvdb::gridPtrCast<openvdb::Vec3fGrid>(grid)) return typed;
    throw firn::InvalidArgument("grid '" + name + "' in " + path + " is not an RGB (Vec3f) grid");
}

// OpenVDB's coordinates are 32-bit: a point beyond them (1e30 m) cannot be looked up, and holds no snow.
bool withinIndexRange(const openvdb::GridBase &grid, const openvdb::Vec3d &world) {
    const openvdb::Vec3d ijk = grid.worldToIndex(world);
    const double limit = double(std::numeric_limits<std::int32_t>::max() / 2);
    return std::abs(ijk.x()) < limit && std::abs(ijk.y()) < limit && std::abs(ijk.z()) < limit;
}

}  // namespace

void bindIo(py::module_ &m) {
    m.def(
        "grid_names",
        [](const std::string &path) { return longCall([&] { return firn::gridNames(path); }); },
        py::arg("path"),
        "Names of the grids in a VDB file, from its header and grid descriptors (no voxel is read), whose lengths "
        "and offsets are checked against the file's size: a truncated file raises firncore.ReadError (an OSError). "
        "Cheap; a file damaged inside its voxels is found by verify_file or the read that uses it.");
    m.def(
        "verify_file",
        [](const std::string &path) {
            longCall([&] { firn::readGrids(path); });
        },
        py::arg("path"),
        "Reads every grid of the VDB file at `path`, as a bake does. Raises firncore.ReadError (an OSError) if it is "
        "missing or damaged (truncated, corrupted), also inside its voxels, which grid_names does not read.");
    m.def(
        "remove_grids",
        [](const std::string &path, const std::vector<std::string> &names) {
            return longCall([&] { return firn::removeGrids(path, names); });
        },
        py::arg("path"), py::arg("names"),
        "Rewrites the VDB file at `path` without the named grids (atomically: temporary file, then rename); the "
        "other grids and the file's metadata stay as they were. Returns the names it removed (none: the file is "
        "untouched). Raises OSError for file trouble, ValueError if no grid would remain.");
    m.def(
        "sample_grid",
        [](const std::string &path, const std::string &name, const FloatArray &points) {
            if (points.ndim() != 2 || points.shape(1) != 3) throw firn::InvalidArgument("points must be (N, 3)");
            const openvdb::FloatGrid::Ptr grid = longCall([&] { return floatGrid(path, name); });
            py::array_t<float> values(points.shape(0));
            auto out = values.mutable_unchecked<1>();
            const auto in = points.unchecked<2>();
            const openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(*grid);
            for (py::ssize_t i = 0; i < points.shape(0); ++i) {
                const openvdb::Vec3d p(in(i, 0), in(i, 1), in(i, 2));
                if (!std::isfinite(p.x() + p.y() + p.z()))
                    throw firn::InvalidArgument("point " + std::to_string(i) + " is not finite");
                out(i) = withinIndexRange(*grid, p) ? sampler.wsSample(p) : grid->background();
            }
            return values;
        },
        py::arg("path"), py::arg("name"), py::arg("points"),
        "Trilinear samples of a float grid at world-space points (m), in the grid's own units.");
    m.def(
        "sample_color_grid",
        [](const std::string &path, const std::string &name, const FloatArray &points) {
            if (points.ndim() != 2 || points.shape(1) != 3) throw firn::InvalidArgument("points must be (N, 3)");
            const openvdb::Vec3fGrid::Ptr grid = longCall([&] { return colorGrid(path, name); });
            py::array_t<float> values({points.shape(0), py::ssize_t(3)});
            auto out = values.mutable_unchecked<2>();
            const auto in = points.unchecked<2>();
            const openvdb::tools::GridSampler<openvdb::Vec3fGrid, openvdb::tools::BoxSampler> sampler(*grid);
            for (py::ssize_t i = 0; i < points.shape(0); ++i) {
                const openvdb::Vec3d p(in(i, 0), in(i, 1), in(i, 2));
                if (!std::isfinite(p.x() + p.y() + p.z()))
                    throw firn::InvalidArgument("point " + std::to_string(i) + " is not finite");
                const openvdb::Vec3f v = withinIndexRange(*grid, p) ? sampler.wsSample(p) : grid->background();
                for (int k = 0; k < 3; ++k) out(i, k) = v[k];
            }
            return values;
        },
        py::arg("path"), py::arg("name"), py::arg("points"),
        "Trilinear samples of an RGB (Vec3f) grid, such as the baked firn_source, at world-space points (m): (N, 3).");
    m.def(
        "grid_statistics",
        [](const std::string &path, const std::string &name) {
            openvdb::FloatGrid::Ptr grid;
            const openvdb::math::MinMax<float> range = longCall([&] {
                grid = floatGrid(path, name);
                return openvdb::tools::minMax(grid->tree());
            });
            py::dict out;
            out["active_voxels"] = grid->activeVoxelCount();
            out["min"] = range.min(), out["max"] = range.max();
            out["voxel_size"] = grid->voxelSize()[0];
            const openvdb::Coord box = grid->evalActiveVoxelDim();  // what a dense copy of the grid holds
            out["box_voxels"] = py::make_tuple(box.x(), box.y(), box.z());
            return out;
        },
        py::arg("path"), py::arg("name"),
        "Active voxel count, min and max value, voxel size (m) and box_voxels (the active voxels' bounding box in "
        "voxels: what Cycles copies densely) of a float grid.");
}

}  // namespace firncore
