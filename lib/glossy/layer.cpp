// The bundle layer of the fitted lobes ("glossy_lobes") and its params.
#include "glossy.h"

#include "core.h"

namespace prt::glossy {

Layer lobeLayer(const GlossyLobes& lobes, const GlossyOptions& options, size_t vertexCount, int shardIndex,
                int shardCount) {
    Layer layer;
    layer.name = "glossy_lobes";
    bool whole = lobes.vertexBegin == 0 && lobes.vertexEnd == vertexCount;
    if (!whole && shardCount <= 1)
        throw Error("", "glossy_lobes", "rows [" + std::to_string(lobes.vertexBegin) + ", " +
                                            std::to_string(lobes.vertexEnd) + ") are not every vertex, but no shard",
                    kExitFailure);
    layer.semantic = "sg_lobes";
    if (options.lobeType != "float16" && options.lobeType != "float32")
        throw Error("", "--lobe-type", "must be float16 or float32", kExitUsage);
    layer.componentType = options.lobeType;
    layer.shape = {uint64_t(lobes.vertexEnd - lobes.vertexBegin), uint64_t(kViewCount), uint64_t(lobes.lobes),
                   uint64_t(kLobeParams)};
    layer.data = lobes.values;
    nlohmann::json directions = nlohmann::json::array();
    for (const auto& d : viewSet().directions) directions.push_back({d[0], d[1], d[2]});
    layer.params["views"] = directions;
    nlohmann::json triangles = nlohmann::json::array();
    for (const auto& t : viewSet().triangles) triangles.push_back({t[0], t[1], t[2]});
    layer.params["view_triangles"] = triangles;
    layer.params["view_set"] = "geodesic-icosahedron-frequency-3";
    layer.params["lobes"] = lobes.lobes;
    layer.params["record"] = "a, mu_x, mu_y, mu_z, lambda: a exp(lambda (mu . w - 1)), radiance per steradian";
    layer.params["brdf"] = {{"model", "phong"}, {"exponent", options.phong.exponent}, {"ks", options.phong.ks}};
    layer.params["grid"] = {{"kind", "cube"}, {"resolution", options.gridResolution}};
    layer.params["solver"] = options.solver == Solver::OpenCl ? "pocl" : "ceres";
    layer.params["weights"] = {{"beta", options.weights.beta}, {"gamma", options.weights.gamma},
                               {"delta", options.weights.delta}};
    layer.params["lambda_bounds"] = {options.bounds.lambdaMin, options.bounds.lambdaMax};
    if (options.warmStart) layer.params["warm_start"] = true; // absent when off, so other bundles keep their bytes
    if (options.nested) layer.params["nested"] = {{"held_out", "cube grid turned 0.5 rad about (1, 2, 3)"},
                                                     {"resolution", heldOutResolution(options)}};
    // The keep criterion, only where it is not the default per-view L2 gate (so those bundles keep their bytes).
    if (options.nested && options.nestedMargin > 0) layer.params["nested"]["margin"] = options.nestedMargin;
    if (options.nested && options.nestedPerVertex) layer.params["nested"]["per_vertex"] = true;
    if (options.nested && options.nestedMaxNorm) layer.params["nested"]["score"] = "largest held-out residual";
    if (options.nested && !options.nestedLighting.empty())
        layer.params["nested"]["score"] = "relit held-out error under " +
                                          std::to_string(options.nestedLighting.size() / heldOutGrid(heldOutResolution(options)).count()) +
                                          " training lightings";
    if (options.fromBelow) // absent when off, so other bundles keep their bytes
        layer.params["from_below"] = {{"fit", "lobe k fitted alone on the kernel minus lobes < k"},
                                      {"overshoot", options.fromBelowOvershoot},
                                      {"lambda_max", fromBelowSharpnessMax(options)}};
    if (!options.indirectTransfer.empty()) // absent when off, so bundles without it keep their bytes
        layer.params["indirect"] = {{"bounce", "one diffuse bounce off the mesh (shadowed SH transfer at the hit)"},
                                    {"order", options.indirectOrder}, {"samples", options.indirectSamples}};
    markVertexShard(layer, lobes.vertexBegin, lobes.vertexEnd, vertexCount, shardIndex, shardCount);
    return layer;
}

} // namespace prt::glossy
