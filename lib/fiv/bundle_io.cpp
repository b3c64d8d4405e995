// The visibility and FIV bundles: layers of domain "grid" on object 0, the occluder mesh (docs/bundle.md).
#include "fiv.h"

#include "core.h"
#include "runtime.h"

#include <cmath>
#include <limits>
#include <type_traits>

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

template <typename T>
T param(const json& params, const char* key, const std::string& path, const std::string& layer) {
    if (!params.contains(key)) throw Error(path, layer, std::string("params.") + key + " is missing");
    const json& value = params.at(key);
    const std::string place = layer + ", params." + key;
    if constexpr (std::is_same_v<T, bool>) {
        if (!value.is_boolean()) throw Error(path, place, "is " + std::string(value.type_name()) + ", not a boolean");
        return value.get<bool>();
    } else if constexpr (std::is_same_v<T, std::string>) {
        if (!value.is_string()) throw Error(path, place, "is " + std::string(value.type_name()) + ", not a string");
        return value.get<std::string>();
    } else if constexpr (std::is_integral_v<T>) {
        // Range-checked before the cast: 2^32 + 3 must not become 3.
        if (!value.is_number_integer()) throw Error(path, place, "is " + std::string(value.type_name()) + ", not an integer");
        bool fits = value.is_number_unsigned() ? value.get<uint64_t>() <= uint64_t(std::numeric_limits<T>::max())
                                               : value.get<int64_t>() >= int64_t(std::numeric_limits<T>::min()) &&
                                                     (value.get<int64_t>() < 0 ||
                                                      uint64_t(value.get<int64_t>()) <= uint64_t(std::numeric_limits<T>::max()));
        if (!fits) throw Error(path, place, "is out of range");
        return value.get<T>();
    } else {
        if (!value.is_number()) throw Error(path, place, "is " + std::string(value.type_name()) + ", not a number");
        double x = value.get<double>();
        if (!std::isfinite(x) || std::abs(x) > kFivMaxCoordinate)
            throw Error(path, place, "is not a finite number within +-" + std::to_string(int64_t(kFivMaxCoordinate)));
        return T(x);
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
    const Layer* header = findLayer(bundle, "fiv_mask_offsets");
    if (!header) throw Error(path, "fiv_mask_offsets", "layer is missing (not a visibility bundle from `prt fiv`)");
    const json& p = header->params;
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
    checkWork(vis.grid, vis.cube, vis.supersample, path, kExitInput);
    if (!p.contains("centre") || !p.at("centre").is_array() || p.at("centre").size() != 3)
        throw Error(path, name + ", params.centre", "is not an array of 3 numbers");
    for (size_t c = 0; c < 3; ++c) {
        json one = {{"centre", p.at("centre")[c]}};
        vis.sphere.centre[c] = param<double>(one, "centre", path, name);
    }
    vis.sphere.radius = param<double>(p, "radius", path, name);
    if (!(vis.sphere.radius > 0.0)) throw Error(path, name, "params.radius must be positive");
    vis.rowBegin = param<size_t>(p, "row_begin", path, name);
    vis.rowEnd = param<size_t>(p, "row_end", path, name);
    if (!p.contains("shard") || !p.at("shard").is_array() || p.at("shard").size() != 2)
        throw Error(path, name + ", params.shard", "is not [I, N]");
    json shard = {{"index", p.at("shard")[0]}, {"count", p.at("shard")[1]}};
    vis.shardIndex = param<int>(shard, "index", path, name + ", params.shard");
    vis.shardCount = param<int>(shard, "count", path, name + ", params.shard");
    vis.rays = param<uint64_t>(p, "rays", path, name);
    vis.naiveRays = param<uint64_t>(p, "naive_rays", path, name);
    vis.closed = param<bool>(p, "closed", path, name);
    size_t samples = vis.grid.sampleCount();
    if (vis.rowBegin > vis.rowEnd || vis.rowEnd > samples)
        throw Error(path, name, "rows " + std::to_string(vis.rowBegin) + ".." + std::to_string(vis.rowEnd) +
                                    " lie outside the grid's " + std::to_string(samples) + " samples");
    uint64_t rows = vis.rowEnd - vis.rowBegin;
    // The one FIV layer check (runtime.h fivLayer): type, count and shape, so no layer is read as another storage.
    const Layer& offsets = fivLayer(bundle, "fiv_mask_offsets", 0, "fiv_mask_offsets", FivStorage::Uint32, {rows + 1}, path);
    const Layer& bits = fivLayer(bundle, "fiv_mask_bits", 0, "fiv_mask_bits", FivStorage::Uint8, {}, path);
    const Layer& valid = fivLayer(bundle, "fiv_mask_valid", 0, "fiv_valid", FivStorage::Uint8, {rows}, path);
    for (uint32_t v : valid.integers)
        if (v > 1) throw Error(path, "fiv_mask_valid", "holds a value other than 0 and 1");
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

    if (!options.selfIrradiance.empty()) { // optional: readers without it ignore the layer
        Layer self;
        self.name = "fiv_self";
        self.domain = "vertex";
        self.semantic = "self_shadowed_irradiance_rgb";
        self.shape = {options.selfIrradiance.size() / 3, 3};
        self.componentType = options.half ? "float16" : "float32";
        self.data = options.selfIrradiance;
        self.params = {{"env", options.envHash},
                       {"layout", "[vertex][channel]: irradiance with the mesh itself as the only occluder"}};
        bundle.layers.push_back(std::move(self));
    }
    if (options.sourceGrid) { // optional: readers without it see the rest of the map only (docs/fiv.md)
        const SourceGrid& sg = *options.sourceGrid;
        json sourceParams = gridParams(sg.grid, sg.sphere);
        sourceParams["sharpen"] = sg.sharpen;
        sourceParams["source_power"] = sg.power;
        sourceParams["source_fiv"] = json::array();
        for (int c = 0; c < 3; ++c)
            sourceParams["source_fiv"].push_back({sg.fiv[size_t(3 * c)], sg.fiv[size_t(3 * c + 1)], sg.fiv[size_t(3 * c + 2)]});
        sourceParams["source_texels"] = sg.texels;
        sourceParams["source_rays"] = sg.sourceRays;
        sourceParams["inside_rays"] = sg.insideRays;
        sourceParams["env"] = options.envHash;
        sourceParams["layout"] = "[row]: hidden fraction f of the sources' luminance power; the runtime subtracts "
                                 "clamp(0.5 + sharpen (f - 0.5), 0, 1) max(0, N . source_fiv[channel])";
        Layer fraction;
        fraction.name = "fiv_source_grid";
        fraction.domain = "grid";
        fraction.semantic = "fiv_source_hidden_fraction";
        fraction.shape = {sg.fraction.size()};
        fraction.componentType = options.half ? "float16" : "float32";
        fraction.data = sg.fraction;
        fraction.params = std::move(sourceParams);
        bundle.layers.push_back(std::move(fraction));
        bundle.layers.push_back(integerLayer("fiv_source_valid", "fiv_valid", "uint8",
                                             std::vector<uint32_t>(sg.valid.begin(), sg.valid.end()),
                                             {{"grid", "fiv_source_grid"},
                                              {"resolution", {sg.grid.shells, sg.grid.polar, sg.grid.azimuth}},
                                              {"meaning", "1 usable, 0 receiver inside the occluder"}}));
        bundle.layers[0].params["sources"] = "fiv_source_grid"; // the grid holds the rest of the map
    }
    return bundle;
}

} // namespace prt::fiv
