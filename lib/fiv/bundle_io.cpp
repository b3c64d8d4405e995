// The visibility and FIV bundles: layers of domain "grid" on object 0, the occluder mesh (docs/bundle.md).
#include "fiv.h"

#include "core.h"

#include <algorithm>

namespace prt::fiv {

namespace {

using nlohmann::json;

Layer integerLayer(const std::string& name, const std::string& semantic, const char* type,
                   std::vector<uint32_t> values, json params, const char* domain = "grid") {
    Layer layer;
    layer.name = name;
    layer.domain = domain;
    layer.semantic = semantic;
    layer.componentType = type;
    layer.shape = {values.size()};
    layer.integers = std::move(values);
    layer.params = std::move(params);
    return layer;
}

const Layer& requireLayer(const Bundle& bundle, const std::string& name, const std::string& path) {
    const Layer* layer = findLayer(bundle, name);
    if (!layer) throw Error(path, name, "layer is missing (not a bundle from `prt fiv`)");
    return *layer;
}

template <typename T>
T param(const json& params, const char* key, const std::string& path, const std::string& layer) {
    if (!params.contains(key)) throw Error(path, layer, std::string("params.") + key + " is missing");
    try {
        return params.at(key).get<T>();
    } catch (const json::exception&) {
        throw Error(path, layer, std::string("params.") + key + " has the wrong type");
    }
}

} // namespace

Bundle visibilityBundle(const TriMesh& occluder, const Visibility& vis, const json& inputs) {
    json params = gridParams(vis.grid, vis.sphere);
    params["cube"] = vis.cube;
    params["supersample"] = vis.supersample;
    params["bits_per_texel"] = vis.bitsPerTexel;
    params["row_begin"] = vis.rowBegin;
    params["row_end"] = vis.rowEnd;
    params["shard"] = {vis.shardIndex, vis.shardCount};
    params["rays"] = vis.rays;
    params["naive_rays"] = vis.naiveRays;
    params["closed"] = vis.closed;
    params["boundary_edges"] = vis.boundaryEdges;
    params["candidates"] = "texels whose cone reaches the bounding sphere, ascending; all when rho <= 1";
    Bundle bundle;
    bundle.mesh = occluder;
    bundle.meshName = "occluder";
    bundle.meshRole = "occluder";
    bundle.producer = {{"tool", "prt"}, {"stage", "fiv"}};
    bundle.inputs = inputs;
    bundle.convention = conventionRecord();
    // Rows row_begin .. row_end - 1 of the grid (all of it unless sharded): ragged bytes per row.
    bundle.layers.push_back(integerLayer("fiv_mask_offsets", "fiv_mask_offsets", "uint32",
                                         std::vector<uint32_t>(vis.offsets.begin(), vis.offsets.end()), params,
                                         "grid_offsets"));
    bundle.layers.push_back(integerLayer("fiv_mask_bits", "fiv_mask_bits", "uint8",
                                         std::vector<uint32_t>(vis.bits.begin(), vis.bits.end()),
                                         {{"offsets", "fiv_mask_offsets"}}, "grid_ragged"));
    bundle.layers.push_back(integerLayer("fiv_mask_valid", "fiv_valid", "uint8",
                                         std::vector<uint32_t>(vis.valid.begin(), vis.valid.end()),
                                         {{"row_begin", vis.rowBegin}, {"row_end", vis.rowEnd}}));
    return bundle;
}

Visibility readVisibility(const Bundle& bundle, const std::string& path) {
    const Layer& offsets = requireLayer(bundle, "fiv_mask_offsets", path);
    const Layer& bits = requireLayer(bundle, "fiv_mask_bits", path);
    const Layer& valid = requireLayer(bundle, "fiv_mask_valid", path);
    const json& p = offsets.params;
    const std::string name = "fiv_mask_offsets";
    Visibility vis;
    vis.grid.azimuth = param<int>(p, "azimuth", path, name);
    vis.grid.polar = param<int>(p, "polar", path, name);
    vis.grid.shells = param<int>(p, "shells", path, name);
    vis.grid.shellMin = param<double>(p, "shell_min", path, name);
    vis.grid.shellMax = param<double>(p, "shell_max", path, name);
    vis.grid.spacing = param<std::string>(p, "shell_spacing", path, name);
    checkGrid(vis.grid, path, kExitInput);
    vis.cube = param<int>(p, "cube", path, name);
    vis.supersample = param<int>(p, "supersample", path, name);
    if (vis.cube < 1 || vis.cube > kMaxCube || vis.supersample < 1 || vis.supersample > kMaxSupersample)
        throw Error(path, name, "cube or supersample out of range");
    vis.bitsPerTexel = bitsPerTexel(vis.supersample);
    if (param<int>(p, "bits_per_texel", path, name) != vis.bitsPerTexel)
        throw Error(path, name, "bits_per_texel disagrees with supersample");
    auto centre = param<std::vector<double>>(p, "centre", path, name);
    if (centre.size() != 3) throw Error(path, name, "params.centre is not 3 numbers");
    std::copy(centre.begin(), centre.end(), vis.sphere.centre.begin());
    vis.sphere.radius = param<double>(p, "radius", path, name);
    if (!(vis.sphere.radius > 0.0)) throw Error(path, name, "params.radius must be positive");
    vis.rowBegin = param<size_t>(p, "row_begin", path, name);
    vis.rowEnd = param<size_t>(p, "row_end", path, name);
    auto shard = param<std::vector<int>>(p, "shard", path, name);
    if (shard.size() != 2) throw Error(path, name, "params.shard is not [I, N]");
    vis.shardIndex = shard[0];
    vis.shardCount = shard[1];
    vis.rays = param<uint64_t>(p, "rays", path, name);
    vis.naiveRays = param<uint64_t>(p, "naive_rays", path, name);
    vis.closed = param<bool>(p, "closed", path, name);
    size_t samples = vis.grid.sampleCount();
    if (vis.rowBegin > vis.rowEnd || vis.rowEnd > samples)
        throw Error(path, name, "rows " + std::to_string(vis.rowBegin) + ".." + std::to_string(vis.rowEnd) +
                                    " lie outside the grid's " + std::to_string(samples) + " samples");
    size_t rows = vis.rowEnd - vis.rowBegin;
    if (offsets.integers.size() != rows + 1)
        throw Error(path, name, "holds " + std::to_string(offsets.integers.size()) + " offsets, the grid header needs " +
                                    std::to_string(rows + 1));
    if (valid.integers.size() != rows)
        throw Error(path, "fiv_mask_valid", "holds " + std::to_string(valid.integers.size()) +
                                                " rows, the grid header needs " + std::to_string(rows));
    if (offsets.integers.front() != 0 || offsets.integers.back() != bits.integers.size() ||
        !std::is_sorted(offsets.integers.begin(), offsets.integers.end()))
        throw Error(path, name, "offsets do not run from 0 to the size of fiv_mask_bits in order");
    vis.offsets.assign(offsets.integers.begin(), offsets.integers.end());
    vis.bits.assign(bits.integers.begin(), bits.integers.end());
    vis.valid.assign(valid.integers.begin(), valid.integers.end());
    return vis;
}

Bundle fivBundle(const TriMesh& occluder, const FivGrid& grid, const std::vector<float>& difmap,
                 const std::array<double, 9>& fivEnv, const FivBundleOptions& options, const json& inputs) {
    json params = gridParams(grid.grid, grid.sphere);
    params["cube"] = grid.cube;
    params["supersample"] = grid.supersample;
    params["env"] = options.envHash;
    params["layout"] = "[row][channel r,g,b][x,y,z]";
    Bundle bundle;
    bundle.mesh = occluder;
    bundle.meshName = "occluder";
    bundle.meshRole = "occluder";
    bundle.producer = {{"tool", "prt"}, {"stage", "fiv"}};
    bundle.inputs = inputs;
    bundle.convention = conventionRecord();
    size_t samples = grid.grid.sampleCount();

    Layer fiv;
    fiv.name = "fiv";
    fiv.domain = "grid";
    fiv.semantic = "fiv_occluded_rgb";
    fiv.shape = {samples, 3, 3};
    fiv.componentType = options.half ? "float16" : "float32";
    fiv.data = grid.fiv;
    fiv.params = params;
    bundle.layers.push_back(std::move(fiv));

    Layer power;
    power.name = "fiv_power";
    power.domain = "grid";
    power.semantic = "occluded_power_rgb";
    power.shape = {samples, 3};
    power.componentType = options.half ? "float16" : "float32";
    power.data = grid.power;
    power.params = {{"grid", "fiv"}, {"resolution", {grid.grid.shells, grid.grid.polar, grid.grid.azimuth}},
                    {"layout", "[row][channel]: sum of L dw over the occluded texels"}};
    bundle.layers.push_back(std::move(power));

    bundle.layers.push_back(integerLayer("fiv_valid", "fiv_valid", "uint8",
                                         std::vector<uint32_t>(grid.valid.begin(), grid.valid.end()),
                                         {{"grid", "fiv"}, {"resolution", {grid.grid.shells, grid.grid.polar, grid.grid.azimuth}},
                                          {"meaning", "1 usable, 0 receiver inside the occluder"}}));

    Layer cube;
    cube.name = "difmap";
    cube.domain = "grid";
    cube.semantic = "irradiance_cube_rgb";
    cube.shape = {difmap.size() / 3, 3};
    cube.data = difmap;
    cube.params = {{"size", options.difmapSize},
                   {"resolution", {6, options.difmapSize, options.difmapSize}},
                   {"axes", {"face", "row", "column"}},
                   {"layout", "cube strip texels face * size^2 + row * size + column, faces +X -X +Y -Y +Z -Z"},
                   {"env", options.envHash}};
    bundle.layers.push_back(std::move(cube));

    Layer env;
    env.name = "fiv_env";
    env.domain = "grid";
    env.semantic = "fiv_environment_rgb";
    env.shape = {1, 3, 3};
    env.data.resize(9);
    for (int e = 0; e < 9; ++e) env.data[size_t(e)] = float(fivEnv[size_t(e)]);
    env.params = {{"env", options.envHash}, {"resolution", {1}}, {"axes", {"single"}}, {"layout", "[1][channel][x,y,z]"}};
    bundle.layers.push_back(std::move(env));
    return bundle;
}

} // namespace prt::fiv
